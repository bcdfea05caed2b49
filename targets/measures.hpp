// Validation measures of a target (thesis section 4.2.4) and a measure of clustering.
#pragma once

#include "target.hpp"

#include <vector>

namespace mesopen {

struct TargetMeasures {
  std::size_t grains = 0;
  double porosity = 0.0;          // (A_T - A_G) / A_T, Eq. 4.5
  double mean_diameter = 0.0;     // of D = sqrt(4A/pi) [m]
  double std_diameter = 0.0;      // sample standard deviation of D [m]
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

// Area, equivalent diameter D = sqrt(4A/pi) and centroid of every grain polygon.
struct GrainFigures {
  std::vector<double> area, diameter, centroid_x, centroid_y;
};
GrainFigures grainFigures(const Polygons &grains);

} // namespace mesopen
