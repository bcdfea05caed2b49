#include "disks.hpp"

#include "cell_grid.hpp"
#include "measures.hpp"

#include <algorithm>
#include <cmath>

namespace mesopen {

namespace {

// Distance from (px, py) to the boundary of polygon g of `polygons` (the point lies outside it).
double distanceToPolygon(const Polygons &polygons, std::size_t g, double px, double py) {
  double best = INFINITY;
  const std::size_t first = polygons.offset[g], n = polygons.corners(g);
  for (std::size_t k = 0; k < n; ++k) {
    const double ax = polygons.x[first + k], ay = polygons.y[first + k];
    const double dx = polygons.x[first + (k + 1) % n] - ax, dy = polygons.y[first + (k + 1) % n] - ay;
    const double l2 = dx * dx + dy * dy;
    const double t = l2 > 0.0 ? std::clamp(((px - ax) * dx + (py - ay) * dy) / l2, 0.0, 1.0) : 0.0;
    best = std::min(best, std::hypot(ax + t * dx - px, ay + t * dy - py));
  }
  return best;
}

} // namespace

Disks grainDisks(const Polygons &grains, double density, const DiskBounds &bounds) {
  const GrainFigures f = grainFigures(grains);
  const std::size_t n = grains.size();
  const std::vector<char> &meshed = bounds.meshed;
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
    if (bounds.width > 0.0) // inside the walls: touching at most
      radius[g] = std::min({radius[g], x, bounds.width - x, y});
    for (std::size_t b = 0; b < bounds.bodies.size(); ++b)
      radius[g] = std::min(radius[g], distanceToPolygon(bounds.bodies, b, x, y));
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

Disks targetDisks(const Target &target, const std::vector<char> &meshed,
                  const PlacedProjectile *projectile) {
  DiskBounds bounds{target.spec.width, meshed, {}};
  if (projectile)
    bounds.bodies.add(projectile->outline_x, projectile->outline_y);
  return grainDisks(target.grains, target.spec.density, bounds);
}

} // namespace mesopen
