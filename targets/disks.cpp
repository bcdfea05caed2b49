#include "disks.hpp"

#include "cell_grid.hpp"
#include "measures.hpp"

#include <algorithm>
#include <cmath>

namespace mesopen {

namespace {

// Distance from (px, py) to the boundary of grain g (its centre lies outside the grain).
double distanceToPolygon(const Polygons &grains, std::size_t g, double px, double py) {
  double best = INFINITY;
  const std::size_t first = grains.offset[g], n = grains.corners(g);
  for (std::size_t k = 0; k < n; ++k) {
    const double ax = grains.x[first + k], ay = grains.y[first + k];
    const double dx = grains.x[first + (k + 1) % n] - ax, dy = grains.y[first + (k + 1) % n] - ay;
    const double l2 = dx * dx + dy * dy;
    const double t = l2 > 0.0 ? std::clamp(((px - ax) * dx + (py - ay) * dy) / l2, 0.0, 1.0) : 0.0;
    best = std::min(best, std::hypot(ax + t * dx - px, ay + t * dy - py));
  }
  return best;
}

} // namespace

Disks grainDisks(const Polygons &grains, double density, const std::vector<char> &meshed) {
  const GrainFigures f = grainFigures(grains);
  const std::size_t n = grains.size();
  auto isDisk = [&](std::size_t g) { return meshed.empty() || !meshed[g]; };
  std::vector<double> equal(n), radius(n);
  double r_max = 0.0, width = 0.0, height = 0.0;
  for (std::size_t g = 0; g < n; ++g) {
    equal[g] = radius[g] = 0.5 * f.diameter[g];
    r_max = std::max(r_max, equal[g]);
    width = std::max(width, f.centroid_x[g]), height = std::max(height, f.centroid_y[g]);
  }
  // Neighbours within three of the largest equal-area radii: two disks farther apart than two
  // cannot overlap, and an elongated polygon reaches at most about 1.5 of its own from its centroid.
  const double reach = 3.0 * r_max;
  CellGrid grid(std::max(width, 1e-12), std::max(height, 1e-12), reach);
  grid.fill(f.centroid_x.data(), f.centroid_y.data(), equal.data(), 0, static_cast<std::uint32_t>(n));
  for (std::size_t g = 0; g < n; ++g) {
    if (!isDisk(g))
      continue;
    const double x = f.centroid_x[g], y = f.centroid_y[g];
    grid.forNear(x, y, reach, [&](const CellGrid::Item &o) {
      if (o.index == g)
        return;
      if (isDisk(o.index))
        radius[g] = std::min(radius[g], std::hypot(o.x - x, o.y - y) * equal[g] / (equal[g] + o.r));
      else
        radius[g] = std::min(radius[g], distanceToPolygon(grains, o.index, x, y));
    });
  }
  Disks disks;
  for (std::size_t g = 0; g < n; ++g) {
    if (!isDisk(g))
      continue;
    disks.grain.push_back(static_cast<std::uint32_t>(g));
    disks.x.push_back(f.centroid_x[g]), disks.y.push_back(f.centroid_y[g]);
    disks.radius.push_back(radius[g]);
    disks.density.push_back(density * f.area[g] / (M_PI * radius[g] * radius[g]));
  }
  return disks;
}

} // namespace mesopen
