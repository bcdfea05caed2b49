// A run's model and solvers, assembled from its scene: the target generated, the projectile placed
// on it, the grains meshed or made LIGGGHTS's disks (run.representation), one model of the
// projectile and the meshed grains, the solver with the contact and the coupling to the disks.
#pragma once

#include "contact.hpp"
#include "coupling.hpp"
#include "liggghts_dem.hpp"
#include "model.hpp"
#include "mpi_communicator.hpp"
#include "partitioner.hpp"
#include "projectile.hpp"
#include "scene.hpp"
#include "solver.hpp"
#include "target.hpp"

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace mesopen {

// The scene's projectile placed on the target's grains (on the box's surface without a target),
// turned by run.yaw + run.obliquity about its tip and moved by run.offset.
PlacedProjectile runProjectile(const Scene &scene, const Target *target);

// The projectile's initial velocity: run.velocity along (sin, -cos) of run.obliquity [m/s].
std::array<double, 2> runVelocity(const RunSpec &run);

// Which grains are meshed (1) and which are disks (0): every one meshed (fe), none (dem), or those
// whose centroids lie within the band around the projectile's path (hybrid).
std::vector<char> meshedGrains(const Scene &scene, const Target &target, const PlacedProjectile &p);

// One model of the projectile (body 0, "projectile") and the grains marked in `meshed`
// ("grain-<g>", g the grain's number in the target; none without a target), with the scene's
// materials, the projectile's initial velocity (runVelocity) and spin, and the fixed box edges.
fem::Model buildRunModel(const Scene &scene, const Target *target, const PlacedProjectile &p,
                         const std::vector<char> &meshed);

// Everything a run steps: the model, its solver, the contact between the FE bodies and, when some
// grains are disks, LIGGGHTS and the coupling to it. It stays where it is made (the solver holds
// the model).
class RunAssembly {
public:
  // The target generated, the model built, dem.data written into `dir` (rank 0) and LIGGGHTS
  // started there (liggghts.log) when there are disks, `liggghts_script` its input script. A
  // signal to stop is looked for between these phases (stopIfAsked). Throws Interrupted,
  // InputError (dem.step longer than the disks' stable step) or what the phases throw.
  // `liggghts_restart`: LIGGGHTS starts from this restart file instead (a run continued from
  // its checkpoint, run/checkpoint.hpp).
  RunAssembly(const Scene &scene, const std::string &dir, const std::string &liggghts_script,
              const parallel::World &world, const std::string &liggghts_restart = "");
  RunAssembly(const RunAssembly &) = delete;
  RunAssembly &operator=(const RunAssembly &) = delete;

  fem::Model model;
  // The ranks the solver shares its element work with (serial for one process).
  std::unique_ptr<parallel::Communicator> processes;
  // Which rank owns which body (Zoltan's RCB with several processes, none needed with one).
  std::unique_ptr<parallel::Partitioner> partitioner;
  std::unique_ptr<coupling::LiggghtsDem> dem;       // null: no disks
  std::unique_ptr<coupling::FeDemCoupling> coupled; // null: no disks
  std::unique_ptr<fem::Solver> solver;
  std::unique_ptr<fem::Contact> contact; // null: contact.enabled = false
};

} // namespace mesopen
