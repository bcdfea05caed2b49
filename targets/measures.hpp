// Validation measures of a target (thesis section 4.2.4) and a measure of clustering.
// Equations: docs/models.md §10.6.
#pragma once

#include "target.hpp"

#include <vector>

namespace mesopen {

struct TargetMeasures {
  std::size_t grains = 0;
  double porosity = 0.0;      // (A_T - A_G) / A_T, Eq. 4.5
  double mean_diameter = 0.0; // of D = sqrt(4A/pi) [m]
  double std_diameter = 0.0;  // sample standard deviation of D [m]
  double min_diameter = 0.0, max_diameter = 0.0;
  // Clustering: the standard deviation of the porosity of square windows of edge
  // `window` (4 mean diameters) tiling the box. Regular targets give a small spread,
  // clustered ones (grain clusters and large pores) a larger one.
  double window = 0.0;
  double local_porosity_std = 0.0;
  std::vector<double> histogram_edges; // grain-size histogram [m], 1 um bins by default
  std::vector<std::size_t> histogram_counts;
};

TargetMeasures measureTarget(const Polygons &grains, const TargetSpec &spec);

// Each grain's equivalent diameter over its site's disk diameter 2 r: how far the tessellation's
// cells stray from the sizes drawn for the sites (a cell's area depends on its neighbours and the
// voids around it), which is why the diameters of the grains span more than [d_min, d_max].
struct DiameterRatios {
  double min = 0.0, p01 = 0.0, median = 0.0, p99 = 0.0, max = 0.0; // quantiles; 0: no grain
};
DiameterRatios cellOverSiteDiameter(const Target &target);

// Area, equivalent diameter D = sqrt(4A/pi) and centroid of every grain polygon.
struct GrainFigures {
  std::vector<double> area, diameter, centroid_x, centroid_y;
};
GrainFigures grainFigures(const Polygons &grains);

} // namespace mesopen
