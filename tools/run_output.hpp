// What `mesopen run` writes: the series and frames of run.h5, the VTK frames with their ParaView
// collection (vtk/run.pvd). Layout of run.h5 (SI units, per metre of depth):
//   /series/{time, step, dt}
//   /series/projectile/{com_x, com_y, vx, vy, rotational_momentum, lateral_force, axial_force,
//                       tilt, depth}
//   /series/energy/{kinetic, internal, plastic, viscous, external, balance_error}
//   /mesh/{triangles (n x 3), element_body, node_body}
//   /frames/NNNNNN/{x, y, vx, vy (nodes); sxx, syy, sxy, szz (total stress sigma = S - p I),
//                   pressure, effective_stress, plastic_strain (elements)}, attribute time.
#pragma once

#include "h5file.hpp"
#include "model.hpp"
#include "solver.hpp"

#include <string>
#include <vector>

namespace mesopen {

// The projectile's figures of instability (thesis section 3.4) and the energies, sampled.
class Series {
public:
  explicit Series(const fem::Model &model); // body 0 is the projectile
  void sample(const fem::Model &model, const fem::Solver &solver);
  void write(H5File &h5) const;
  std::size_t size() const { return time_.size(); }
  double last(const std::string &name) const;

private:
  std::vector<double> x0_, y0_; // projectile nodes relative to the initial centre of mass
  double lowest0_ = 0.0;        // initial lowest point of the projectile
  std::vector<double> time_, step_, dt_;
  std::vector<std::pair<std::string, std::vector<double>>> columns_;
  std::vector<double> &column(const std::string &name);
};

// Frames: written into run.h5 as they are taken, and as VTK files when asked.
class Frames {
public:
  Frames(H5File &h5, const fem::Model &model, const std::string &vtk_dir);
  void take(const fem::Model &model, double time);
  // vtk/run.pvd listing the frames written so far.
  void writeCollection() const;
  std::size_t size() const { return times_.size(); }

private:
  H5File &h5_;
  std::string vtk_dir_;
  std::vector<double> times_;
};

} // namespace mesopen
