// The grains as DEM disks: one disk per grain at the polygon's centroid with the grain's mass.
// Disks of the grains' equal area, sqrt(A / pi), would overlap their neighbours (in the baseline
// target 6,483 pairs, a quarter of a radius on average, up to 0.85): a DEM target built from them
// would burst at the first step. So a disk's radius is the equal-area radius, or less where it
// would overlap: two disks share the distance between their centres in proportion to their
// equal-area radii, and a disk keeps out of the meshed grains' polygons. Its density is then
// rho A / (pi r^2), which keeps its mass per metre rho A (baseline: radii 0.86 of the equal-area
// ones on average, none below 0.70; the disks cover 52 % of the box).
#pragma once

#include "target.hpp"

#include <cstdint>
#include <vector>

namespace mesopen {

struct Disks {
  std::vector<std::uint32_t> grain; // the grain each disk stands for
  std::vector<double> x, y, radius, density;
  std::size_t size() const { return grain.size(); }
};

// The disks of the grains not marked in `meshed` (empty: every grain a disk), in grain order.
Disks grainDisks(const Polygons &grains, double density, const std::vector<char> &meshed = {});

} // namespace mesopen
