// Grain and void sites (thesis section 4.2.1): counts from areas, initial placement
// (regular or clustered, section 4.2.5) and the Gaussian overlap minimisation (Eq. 4.1).
// Equations: docs/models.md §10.1, §10.2.
#pragma once

#include "random.hpp"
#include "target.hpp"

#include <functional>
#include <vector>

namespace mesopen {

struct PlacementReport {
  std::vector<double> energy; // overlap energy before each iteration (Eq. 4.1 summed)
  int iterations = 0;
  bool converged = false;
};

// Number of grains N = A(1 - phi) / (pi dbar^2 / 4) (thesis 4.2.1).
std::size_t grainCount(const TargetSpec &spec);

// Grain diameters: uniform in [d_min, d_max] by stratified quantiles in random order, so that
// the assigned sizes have exactly the requested mean and spread.
std::vector<double> grainDiameters(const TargetSpec &spec, Random &random);

// Sites with their radii at their initial random positions (thesis 4.2.1, 4.2.5). Void sites
// have diameter void_ratio * dbar; their number sets the porosity:
// V = void_scale * (A - sum A_grain) / A_void (the generator then tunes the void cells' size).
Sites initialSites(const TargetSpec &spec, double void_scale);

// Steepest descent of the Gaussian overlap (Eq. 4.1) with cell lists: each site moves along its
// conflict vector, the sum of G_ij e_ij over the sites it overlaps (and over its mirror images in
// the walls), with moves normalised by the largest and scaled by step_scale * dbar (thesis
// 4.2.1). The conflict vector is minus the gradient of sum_pairs int_d^R G(s) ds, so this is a
// true descent. When the energy rises the step shrinks by step_decay (1 keeps the thesis's fixed
// step). It stops at a local minimum (the step below 1 % of its start, or the energy changing by
// less than 1e-4 of itself over 20 iterations) or after max_iterations.
// `progress`, when given, is called after each iteration with (iteration, max_iterations,
// energy / initial energy).
PlacementReport relaxSites(Sites &sites, const TargetSpec &spec,
                           const std::function<void(int, int, double)> &progress = {});

// max_iterations, or when it is 0: 50 for regular placement (its sites start spread out) and
// 500 for clustered (random start), the counts after which the grain-size spread stops
// improving (baseline target: std 9.96 / 9.94 / 10.03 um after 50 / 100 / 200 iterations; the
// 60 um clustered target: 4.0 / 2.9 / 2.0 / 1.75 um after 100 / 200 / 400 / 500).
int maxIterations(const TargetSpec &spec);

// Overlap energy of the sites (sum over overlapping pairs and wall images of Eq. 4.1).
double overlapEnergy(const Sites &sites, const TargetSpec &spec);

} // namespace mesopen
