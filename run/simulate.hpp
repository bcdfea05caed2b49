// A run of a scene from its set-up to its files: the target and the projectile as finite-element
// bodies (some grains LIGGGHTS's disks), integrated in time; run.h5 (series and frames),
// vtk/run.pvd, summary.json, scene.toml (the scene composed: every key at its value) and
// mesopen.log in the output directory.
#pragma once

#include "command_log.hpp"
#include "liggghts_dem.hpp"
#include "output.hpp"
#include "scene.hpp"
#include "time_loop.hpp"

#include <cstddef>
#include <string>

namespace mesopen {

// What `mesopen run` needs of a scene beyond its keys' ranges (target.mesh with the grains, the
// representation, the projectile, dem.skin); `where` names the scene in messages. Throws
// InputError.
void checkRunnable(const Scene &scene, const std::string &where);

// How a run ended, and its figures for the closing message.
struct RunReport {
  LoopResult loop;
  std::size_t steps = 0, elements = 0, bodies = 0;
  double time = 0.0, wall = 0.0, balance_error = 0.0;
  bool vtk = false; // vtk/run.pvd written
};

// Where a run writes and what it shows.
struct RunPlace {
  std::string dir;             // the output directory, taken (takeRunDirectory) by rank 0
  std::string liggghts_script; // liggghts-inputs/dem.in
  bool progress = false;       // the progress line on stderr (rank 0)
  Clock::time_point start;     // the command's start, for the wall time
  CommandLog *log = nullptr;   // DIR/mesopen.log (rank 0)
};

// The scene run on every rank of `world` (rank 0 writes the files). SIGINT and SIGTERM are caught
// from the set-up to the end of the time loop: during the set-up (target, meshes, model, LIGGGHTS)
// they end it with Interrupted at the next phase, during the loop after its step (with a
// checkpoint when they are on), the files written as for a failure. Whatever the loop's end, the
// files hold everything computed and are whole. `resume`: the run goes on from the last
// checkpoint in place.dir (scene: checkpointScene's; run/checkpoint.hpp). Throws Interrupted,
// InputError (found once LIGGGHTS has started, or a checkpoint not of this run) or what the
// set-up or the files throw.
RunReport simulate(const Scene &scene, const RunPlace &place, const parallel::World &world,
                   bool resume = false);

} // namespace mesopen
