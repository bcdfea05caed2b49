// What `mesopen run` writes: the series and frames of run.h5, the VTK frames with their ParaView
// collection (vtk/run.pvd). Layout of run.h5 (SI units, per metre of depth):
//   attributes of /: format = "mesopen-run", version, program (its version), status
//                    ("completed", "failed" or "interrupted"), representation, scene (the scene
//                    composed, as scene.toml), seed, velocity, spin, end_time,
//                    projectile_length (projectile.length); obliquity, yaw, offset when not 0
//   /materials/{projectile, grains}                            attributes preset or type, and
//                                                              every parameter (resolved)
//   /series/{time, step, dt}                                   one value per sample
//   /series/projectile/{com_x, com_y, vx, vy, rotational_momentum, lateral_force, axial_force,
//                       tilt, depth}                           attributes unit, meaning
//   /series/projectile                                         attribute mass [kg/m]
//   /series/energy/{kinetic, internal, plastic, viscous, friction, contact, external, eroded,
//                   balance_error}
//   /mesh/{x, y (initial node positions), triangles (n x 3, uint32), element_body, node_body}
//                                                              attribute body_names
//   /frames/NNNNNN/{x, y, vx, vy (nodes); sxx, syy, sxy, szz (total stress sigma = S - p I),
//                   pressure, effective_stress, plastic_strain, eroded (uint8, 1: removed)
//                   (elements)}, attributes time, step; each dataset attribute unit
//   /frames/NNNNNN/disks/{x, y, radius, vx, vy, omega}        with disks; attribute unit
// Strings are UTF-8 (variable length). The VTK frames name their arrays as run.h5 does (the
// velocity as one vector of vx, vy, 0).
// Eroded elements are empty cells in the VTK frames; nodes that erosion left without elements
// are not the projectile's in its series.
// Body 0 is the projectile, body b >= 1 the grain b - 1 of the target.
#pragma once

#include "coupling.hpp"
#include "h5file.hpp"
#include "model.hpp"
#include "solver.hpp"

#include <string>
#include <vector>

namespace mesopen {

// The projectile's figures of instability (thesis section 3.4) and the energies, sampled in memory
// and written at the end (H5File writes whole datasets).
class Series {
public:
  explicit Series(const fem::Model &model); // body 0 is the projectile, at its initial state
  void sample(const fem::Model &model, const fem::Solver &solver);
  void write(H5File &h5) const;
  std::size_t size() const { return time_.size(); }
  // The last sample of "projectile/NAME" or "energy/NAME"; NaN before the first.
  double last(const std::string &name) const;
  // The projectile's depth now: its initial lowest point minus its current lowest point [m].
  // (every process calls it)
  double depth(const fem::Model &model, const fem::Solver &solver) const;

  struct Column {
    std::string name, unit, meaning;
    std::vector<double> values;
  };

private:
  friend class Checkpoints;     // keeps and restores the samples so far (checkpoint.hpp)
  std::vector<double> x0_, y0_; // projectile nodes relative to the initial centre of mass [m]
  double mass_ = 0.0;           // the projectile's mass [kg/m]
  double lowest0_ = 0.0;        // initial lowest point of the projectile [m]
  std::vector<double> time_, dt_;
  std::vector<std::uint64_t> step_;
  std::vector<Column> columns_;
};

// Fields every `interval` of simulated time, written into run.h5 as they are taken and as VTK
// files when a directory is given.
class Frames {
public:
  // interval 0: no frames. vtk_dir empty: no VTK files. Writes /mesh at once. h5 null: the frames
  // are taken but nothing is written (an MPI rank other than 0: it takes part in gathering the
  // disks).
  Frames(H5File *h5, const fem::Model &model, double interval, std::string vtk_dir);
  // A frame when the solver's time has reached the next multiple of the interval, or when `force`.
  void offer(const fem::Model &model, const fem::Solver &solver, bool force = false);
  // The DEM participant's disks go into every frame too: /frames/NNNNNN/disks/{x, y, radius, vx,
  // vy, omega} and vtk/disks_NNNNNN.vtu (points with radius, velocity and spin, as the second part
  // of each time in run.pvd; tools/paraview/show.py draws them as circles of their radius). Under
  // MPI every rank takes the frames (the disks are gathered to rank 0, which writes them). The
  // disks are where they are at the frame's time, within the coupling's window.
  void addDisks(const coupling::FeDemCoupling *coupled) { coupled_ = coupled; }
  // vtk/run.pvd listing the VTK frames written so far (nothing without VTK frames).
  void writeCollection() const;
  std::size_t size() const { return times_.size(); }
  bool vtk() const { return !vtk_dir_.empty() && !times_.empty(); }
  // The wall seconds taking the frames took in this process.
  double seconds() const { return seconds_; }

private:
  friend class Checkpoints; // keeps and restores the frames' times (checkpoint.hpp)
  void take(const fem::Model &model, const fem::Solver &solver);

  H5File *h5_;
  double interval_, next_ = 0.0;
  std::string vtk_dir_;
  std::vector<double> times_;
  const coupling::FeDemCoupling *coupled_ = nullptr;
  double seconds_ = 0.0;
};

} // namespace mesopen
