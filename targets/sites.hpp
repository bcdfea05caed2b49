// Grain and void sites (thesis section 4.2.1): counts from areas, initial placement
// (regular or clustered, section 4.2.5) and the Gaussian overlap minimisation (Eq. 4.1).
#pragma once

#include "random.hpp"
#include "target.hpp"

#include <vector>

namespace mesopen {

struct PlacementReport {
  std::vector<double> energy;   // overlap energy before each iteration (Eq. 4.1 summed)
  int iterations = 0;
  bool converged = false;
};

// Number of grains N = A(1 - phi) / (pi dbar^2 / 4) (thesis 4.2.1; MODELS.md).
std::size_t grainCount(const TargetSpec &spec);

// Grain diameters: uniform in [d_min, d_max] by stratified quantiles in random order, so that
// the assigned sizes have exactly the requested mean and spread.
std::vector<double> grainDiameters(const TargetSpec &spec, Random &random);

// Sites with their radii at their initial random positions. Void sites have diameter
// void_ratio * dbar; their number fills the area the grain disks leave: V = (A - sum A_grain) / A_void.
Sites initialSites(const TargetSpec &spec);

// Steepest descent on the summed Gaussian overlap (Eq. 4.1) with cell lists: each site moves
// along the sum of G_ij * e_ij over the sites it overlaps (and its mirror images in the walls),
// moves normalised by the largest and scaled by step_scale * dbar. When the energy rises the
// step shrinks by `step_decay` (1 keeps the thesis's fixed step); the descent stops at a local
// minimum: the step below 1 % of its start, or a relative energy change under 1e-4 over 20
// iterations, or max_iterations.
PlacementReport relaxSites(Sites &sites, const TargetSpec &spec, double step_decay = 0.7);

// Overlap energy of the sites (sum over overlapping pairs and wall images of Eq. 4.1).
double overlapEnergy(const Sites &sites, const TargetSpec &spec);

} // namespace mesopen
