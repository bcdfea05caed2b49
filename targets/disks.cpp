#include "disks.hpp"

#include "measures.hpp"
#include "point_grid.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace mesopen {

namespace {

// The point of polygon g's boundary closest to (px, py), and whether (px, py) lies inside it.
struct Nearest {
  double x, y, distance;
  bool inside;
};
Nearest nearestOnPolygon(const Polygons &polygons, std::size_t g, double px, double py) {
  Nearest best{px, py, INFINITY, false};
  const std::size_t first = polygons.offset[g], n = polygons.corners(g);
  for (std::size_t k = 0; k < n; ++k) {
    const double ax = polygons.x[first + k], ay = polygons.y[first + k];
    const double bx = polygons.x[first + (k + 1) % n], by = polygons.y[first + (k + 1) % n];
    const double dx = bx - ax, dy = by - ay, l2 = dx * dx + dy * dy;
    const double t = l2 > 0.0 ? std::clamp(((px - ax) * dx + (py - ay) * dy) / l2, 0.0, 1.0) : 0.0;
    const double cx = ax + t * dx, cy = ay + t * dy, d = std::hypot(cx - px, cy - py);
    if (d < best.distance)
      best.x = cx, best.y = cy, best.distance = d;
    if ((ay > py) != (by > py) && px < ax + (py - ay) * dx / dy) // crossing number
      best.inside = !best.inside;
  }
  return best;
}

// Jacobi sweeps that push overlapping disks apart (each of a pair by 0.8 of the overlap along the
// line of centres: over-relaxed, since a disk's neighbours push it back; the baseline's 6,198
// disks need 186 sweeps so, 634 at 0.5), out of the walls (x = 0, x = width, y = 0 and, while
// relaxing, the box's top y = height, so that the target keeps its box and bulk density) and out of
// the obstacles (meshed grains, other FE bodies: the whole overlap), all from the positions before
// the sweep, so that the result does not depend on the order. Until the largest overlap is below
// 1e-6 of the mean radius, or `sweeps` sweeps. Meshed grains are found through `grain_grid` (their
// centroids).
void relaxApart(std::vector<double> &x, std::vector<double> &y, const std::vector<double> &r,
                const std::vector<char> &is_disk, double width, double height,
                const Polygons &grains, const PointGrid &grain_grid, double grain_reach,
                const Polygons &bodies, int sweeps) {
  const std::size_t n = x.size();
  double r_max = 0.0, r_mean = 0.0, disks = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    if (is_disk[i])
      r_max = std::max(r_max, r[i]), r_mean += r[i], disks += 1.0;
  if (disks == 0.0)
    return;
  r_mean /= disks;
  std::vector<double> dx(n), dy(n), box; // the bodies' bounding boxes
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const auto first = bodies.offset[b], last = bodies.offset[b + 1];
    const auto [x0, x1] = std::minmax_element(bodies.x.begin() + first, bodies.x.begin() + last);
    const auto [y0, y1] = std::minmax_element(bodies.y.begin() + first, bodies.y.begin() + last);
    box.insert(box.end(), {*x0, *x1, *y0, *y1});
  }
  constexpr double push = 0.8;
  const bool any_meshed = std::find(is_disk.begin(), is_disk.end(), 0) != is_disk.end();
  PointGrid grid = pointGrid(width, height, 2.0 * r_max);
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    binPoints(grid, x.data(), y.data(), r.data(), 0, static_cast<std::uint32_t>(n));
    double worst = 0.0;
#pragma omp parallel for reduction(max : worst) schedule(static)
    for (long k = 0; k < static_cast<long>(n); ++k) {
      const auto i = static_cast<std::size_t>(k);
      dx[i] = dy[i] = 0.0;
      if (!is_disk[i])
        continue;
      grid.forNear(x[i], y[i], 2.0 * r_max, [&](const GridPoint &o) {
        if (o.index == i || !is_disk[o.index])
          return;
        const double ex = x[i] - o.x, ey = y[i] - o.y, d = std::hypot(ex, ey);
        const double overlap = r[i] + o.r - d;
        if (overlap <= 0.0)
          return;
        worst = std::max(worst, overlap);
        // coincident centres: apart along x, the lower index to the left
        const double ux = d > 0.0 ? ex / d : (i < o.index ? -1.0 : 1.0),
                     uy = d > 0.0 ? ey / d : 0.0;
        dx[i] += push * overlap * ux, dy[i] += push * overlap * uy;
      });
      const double walls[4] = {r[i] - x[i], x[i] + r[i] - width, r[i] - y[i], y[i] + r[i] - height};
      dx[i] += std::max(walls[0], 0.0) - std::max(walls[1], 0.0);
      dy[i] += std::max(walls[2], 0.0) - std::max(walls[3], 0.0);
      for (double w : walls)
        worst = std::max(worst, w);
      auto pushOut = [&](const Polygons &polygons, std::size_t g) {
        const Nearest c = nearestOnPolygon(polygons, g, x[i], y[i]);
        if (!c.inside && c.distance >= r[i])
          return;
        const double overlap = c.inside ? r[i] + c.distance : r[i] - c.distance;
        worst = std::max(worst, overlap);
        if (c.distance == 0.0)
          return; // on the boundary: the shrinking afterwards takes it
        const double sign = c.inside ? -1.0 : 1.0; // from the nearest point out through the centre
        dx[i] += sign * overlap * (x[i] - c.x) / c.distance;
        dy[i] += sign * overlap * (y[i] - c.y) / c.distance;
      };
      if (any_meshed)
        grain_grid.forNear(x[i], y[i], grain_reach + r[i], [&](const GridPoint &o) {
          if (!is_disk[o.index])
            pushOut(grains, o.index);
        });
      for (std::size_t b = 0; b < bodies.size(); ++b)
        if (x[i] + r[i] > box[4 * b] && x[i] - r[i] < box[4 * b + 1] &&
            y[i] + r[i] > box[4 * b + 2] && y[i] - r[i] < box[4 * b + 3])
          pushOut(bodies, b);
    }
    if (worst < 1e-6 * r_mean)
      break;
    for (std::size_t i = 0; i < n; ++i)
      x[i] += dx[i], y[i] += dy[i];
  }
}

} // namespace

Disks grainDisks(const Polygons &grains, double density, const DiskBounds &bounds) {
  const GrainFigures f = grainFigures(grains);
  const std::size_t n = grains.size();
  std::vector<char> is_disk(n, 1);
  for (std::size_t g = 0; g < bounds.meshed.size() && g < n; ++g)
    is_disk[g] = !bounds.meshed[g];
  std::vector<double> equal(n), radius(n);
  double r_max = 0.0, width = 0.0, height = 0.0;
  for (std::size_t g = 0; g < n; ++g) {
    equal[g] = radius[g] = 0.5 * f.diameter[g];
    r_max = std::max(r_max, equal[g]);
    width = std::max(width, f.centroid_x[g]), height = std::max(height, f.centroid_y[g]);
  }
  // Neighbours within three of the largest equal-area radii: two disks farther apart than two
  // cannot overlap, and an elongated polygon reaches at most about 1.5 of its own from its
  // centroid.
  const double reach = 3.0 * r_max;
  PointGrid grid = pointGrid(std::max(width, 1e-12), std::max(height, 1e-12), reach);
  binPoints(grid, f.centroid_x.data(), f.centroid_y.data(), equal.data(), 0,
            static_cast<std::uint32_t>(n));
  std::vector<double> x = f.centroid_x, y = f.centroid_y;
  if (bounds.size == DiskSize::equal_area && bounds.width > 0.0 && bounds.height > 0.0) {
    relaxApart(x, y, equal, is_disk, bounds.width, bounds.height, grains, grid, reach,
               bounds.bodies, bounds.sweeps);
  }
  // What relaxing left (or, without it, every overlap) is taken off the radii.
  PointGrid placed = pointGrid(std::max(width, 1e-12), std::max(height, 1e-12), reach);
  binPoints(placed, x.data(), y.data(), equal.data(), 0, static_cast<std::uint32_t>(n));
  for (std::size_t g = 0; g < n; ++g) {
    if (!is_disk[g])
      continue;
    placed.forNear(x[g], y[g], reach, [&](const GridPoint &o) {
      if (o.index != g && is_disk[o.index])
        radius[g] =
            std::min(radius[g], std::hypot(o.x - x[g], o.y - y[g]) * equal[g] / (equal[g] + o.r));
    });
    grid.forNear(x[g], y[g], reach, [&](const GridPoint &o) {
      if (!is_disk[o.index]) {
        const Nearest c = nearestOnPolygon(grains, o.index, x[g], y[g]);
        radius[g] = std::min(radius[g], c.inside ? 0.0 : c.distance);
      }
    });
    if (bounds.width > 0.0) // inside the walls: touching at most
      radius[g] = std::min({radius[g], x[g], bounds.width - x[g], y[g]});
    for (std::size_t b = 0; b < bounds.bodies.size(); ++b) {
      const Nearest c = nearestOnPolygon(bounds.bodies, b, x[g], y[g]);
      radius[g] = std::min(radius[g], c.inside ? 0.0 : c.distance);
    }
  }
  Disks disks;
  for (std::size_t g = 0; g < n; ++g) {
    if (!is_disk[g])
      continue;
    if (!(radius[g] > 0.0))
      throw std::runtime_error("grain " + std::to_string(g) +
                               " has no room for a disk (its centre "
                               "lies on or inside an FE body or a wall)");
    disks.grain.push_back(static_cast<std::uint32_t>(g));
    disks.x.push_back(x[g]), disks.y.push_back(y[g]);
    disks.radius.push_back(radius[g]);
    disks.density.push_back(density * f.area[g] / (M_PI * radius[g] * radius[g]));
  }
  return disks;
}

Disks targetDisks(const Target &target, DiskSize size, const std::vector<char> &meshed,
                  const PlacedProjectile *projectile) {
  DiskBounds bounds;
  bounds.width = target.spec.width, bounds.height = target.spec.height, bounds.meshed = meshed;
  bounds.size = size;
  if (projectile)
    bounds.bodies.add(projectile->outline_x, projectile->outline_y);
  return grainDisks(target.grains, target.spec.density, bounds);
}

} // namespace mesopen
