#include "sites.hpp"

#include "point_grid.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace mesopen {

std::size_t grainCount(const TargetSpec &spec) {
  const double d = spec.meanDiameter();
  return static_cast<std::size_t>(
      std::llround(spec.area() * (1.0 - spec.porosity) / (M_PI * d * d / 4.0)));
}

std::vector<double> grainDiameters(const TargetSpec &spec, Random &random) {
  const std::size_t n = grainCount(spec);
  std::vector<double> d(n);
  for (std::size_t i = 0; i < n; ++i)
    d[i] = spec.diameter_min + (spec.diameter_max - spec.diameter_min) * (i + 0.5) / n;
  random.shuffle(d);
  return d;
}

namespace {

// Renumber grains and voids separately in the row-by-row order of a grid: neighbours in
// space become neighbours in memory.
void sortSpatially(Sites &s, double width, double height, double cell) {
  PointGrid grid = pointGrid(width, height, cell);
  std::vector<std::uint32_t> order;
  order.reserve(s.size());
  binPoints(grid, s.x.data(), s.y.data(), s.r.data(), 0, static_cast<std::uint32_t>(s.grains));
  for (const auto &item : grid.items())
    order.push_back(item.index);
  binPoints(grid, s.x.data(), s.y.data(), s.r.data(), static_cast<std::uint32_t>(s.grains),
            static_cast<std::uint32_t>(s.size()));
  for (const auto &item : grid.items())
    order.push_back(item.index);
  auto permute = [&](std::vector<double> &v) {
    std::vector<double> w(v.size());
    for (std::size_t i = 0; i < order.size(); ++i)
      w[i] = v[order[i]];
    v.swap(w);
  };
  permute(s.x);
  permute(s.y);
  permute(s.r);
}

} // namespace

Sites initialSites(const TargetSpec &spec, double void_scale) {
  // Grains and voids draw from streams of their own: the grains are the same whatever V is.
  Random random(spec.seed), void_random(spec.seed ^ 0x9E3779B97F4A7C15ull);
  const std::vector<double> diameters = grainDiameters(spec, random);
  const std::size_t n = diameters.size();
  double grain_area = 0.0;
  for (double d : diameters)
    grain_area += M_PI * d * d / 4.0;
  const double void_d = spec.void_ratio * spec.meanDiameter();
  const double free_area = std::max(0.0, spec.area() - grain_area);
  const std::size_t v = static_cast<std::size_t>(
      std::llround(void_scale * free_area / (M_PI * void_d * void_d / 4.0)));

  Sites s;
  s.grains = n;
  s.x.resize(n + v);
  s.y.resize(n + v);
  s.r.resize(n + v);
  for (std::size_t i = 0; i < n; ++i)
    s.r[i] = 0.5 * diameters[i];
  for (std::size_t i = n; i < n + v; ++i)
    s.r[i] = 0.5 * void_d;

  const double w = spec.width, h = spec.height;
  std::size_t placed_grains = 0, placed_voids = 0;
  if (spec.placement == Placement::regular) {
    // Thesis 4.2.5: about N sub-boxes, one grain site and V/N void sites in each; the rest at
    // random. The grid has nx * ny >= N boxes of the box's aspect; N of them, drawn at random,
    // get a grain, so that no grain is left to chance in long, thin boxes.
    const int nx = std::max(1, static_cast<int>(std::lround(std::sqrt(n * w / h))));
    const int ny = std::max(1, static_cast<int>(std::ceil(static_cast<double>(n) / nx)));
    const std::size_t boxes = static_cast<std::size_t>(nx) * ny;
    std::vector<std::uint8_t> has_grain(boxes, 0);
    std::fill(has_grain.begin(), has_grain.begin() + std::min(n, boxes), 1);
    random.shuffle(has_grain);
    const std::size_t per_box = v / boxes;
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const double x0 = w * i / nx, x1 = w * (i + 1) / nx, y0 = h * j / ny, y1 = h * (j + 1) / ny;
        if (has_grain[static_cast<std::size_t>(j) * nx + i]) {
          s.x[placed_grains] = random.uniform(x0, x1);
          s.y[placed_grains++] = random.uniform(y0, y1);
        }
        for (std::size_t k = 0; k < per_box; ++k, ++placed_voids) {
          s.x[n + placed_voids] = void_random.uniform(x0, x1);
          s.y[n + placed_voids] = void_random.uniform(y0, y1);
        }
      }
  }
  for (; placed_grains < n; ++placed_grains) {
    s.x[placed_grains] = random.uniform(0.0, w);
    s.y[placed_grains] = random.uniform(0.0, h);
  }
  for (; placed_voids < v; ++placed_voids) {
    s.x[n + placed_voids] = void_random.uniform(0.0, w);
    s.y[n + placed_voids] = void_random.uniform(0.0, h);
  }
  sortSpatially(s, w, h, spec.diameter_max);
  return s;
}

namespace {

// Eq. 4.1 with sigma^2 = 1: G = exp(-(1/2) (2 pi d / (r_i + r_j))^2), for d < r_i + r_j.
inline double gaussian(double d2, double reach) {
  return std::exp(-2.0 * M_PI * M_PI * d2 / (reach * reach));
}

struct Conflicts {
  std::vector<double> dx, dy, energy; // composite conflict vector and energy share per site
};

// Conflict vectors of all sites (thesis 4.2.1): the sum over overlapping sites j of G_ij times
// the unit vector from j to i, and the same against each wall through the site's mirror image.
// Each site gathers its own sum, so the pass is parallel and its result independent of threads.
void conflicts(const Sites &s, const TargetSpec &spec, const PointGrid &grains,
               const PointGrid &voids, double r_grain_max, double r_void, Conflicts &c) {
  const std::size_t n = s.size();
  const double *x = s.x.data(), *y = s.y.data(), *r = s.r.data();
  const double w = spec.width, h = spec.height;
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n; ++i) {
    double fx = 0.0, fy = 0.0, e = 0.0;
    const double xi = x[i], yi = y[i], ri = r[i];
    // The site meets itself once, in the grid of its own kind: d = 0, G = 1, no direction;
    // its energy share of 1/2 is taken off below.
    auto pair = [&](const GridPoint &j) {
      const double ex = xi - j.x, ey = yi - j.y, reach = ri + j.r;
      const double d2 = ex * ex + ey * ey;
      if (d2 >= reach * reach)
        return;
      const double g = gaussian(d2, reach);
      e += 0.5 * g; // each pair is seen from both sides
      if (d2 > 0.0) {
        const double inv = 1.0 / std::sqrt(d2);
        fx += g * ex * inv;
        fy += g * ey * inv;
      }
    };
    grains.forNear(xi, yi, ri + r_grain_max, pair);
    voids.forNear(xi, yi, ri + r_void, pair);
    // Walls: the image of the site in a wall at distance delta is 2 delta away, reach 2 r_i.
    auto wall = [&](double delta, double nx, double ny) {
      if (delta >= ri)
        return;
      const double d = 2.0 * std::max(delta, 0.0);
      const double g = gaussian(d * d, 2.0 * ri);
      e += g;
      fx += g * nx;
      fy += g * ny;
    };
    wall(xi, 1.0, 0.0);
    wall(w - xi, -1.0, 0.0);
    wall(yi, 0.0, 1.0);
    wall(h - yi, 0.0, -1.0);
    c.dx[i] = fx;
    c.dy[i] = fy;
    c.energy[i] = e - 0.5;
  }
}

} // namespace

int maxIterations(const TargetSpec &spec) {
  if (spec.max_iterations > 0)
    return spec.max_iterations;
  return spec.placement == Placement::regular ? 50 : 500;
}

PlacementReport relaxSites(Sites &s, const TargetSpec &spec,
                           const std::function<void(int, int, double)> &progress) {
  const std::size_t n = s.size();
  const double r_grain_max = 0.5 * spec.diameter_max;
  const double r_void = 0.5 * spec.void_ratio * spec.meanDiameter();
  PointGrid grains = pointGrid(spec.width, spec.height, r_grain_max);
  PointGrid voids = pointGrid(spec.width, spec.height, 2.0 * r_void);
  Conflicts c{std::vector<double>(n), std::vector<double>(n), std::vector<double>(n)};

  const double step0 = spec.step_scale * spec.meanDiameter();
  double step = step0;
  PlacementReport report;
  for (int it = 0;; ++it) {
    binPoints(grains, s.x.data(), s.y.data(), s.r.data(), 0, static_cast<std::uint32_t>(s.grains));
    binPoints(voids, s.x.data(), s.y.data(), s.r.data(), static_cast<std::uint32_t>(s.grains),
              static_cast<std::uint32_t>(n));
    conflicts(s, spec, grains, voids, r_grain_max, r_void, c);
    // Serial sums keep the result the same for any number of threads.
    double energy = 0.0, largest = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      energy += c.energy[i];
      largest = std::max(largest, c.dx[i] * c.dx[i] + c.dy[i] * c.dy[i]);
    }
    report.energy.push_back(energy);
    const std::size_t k = report.energy.size();
    if (k >= 2 && energy > report.energy[k - 2])
      step *= spec.step_decay;
    const bool flat =
        k > 20 && std::abs(report.energy[k - 21] - energy) < 1e-4 * report.energy[k - 21];
    if (largest == 0.0 || step < 0.01 * step0 || flat) {
      report.converged = true;
      break;
    }
    if (it >= maxIterations(spec))
      break;
    // Normalise by the largest move, scale to the step, move, stay inside the box.
    const double scale = step / std::sqrt(largest);
#pragma omp parallel for schedule(static)
    for (std::size_t i = 0; i < n; ++i) {
      s.x[i] = std::clamp(s.x[i] + scale * c.dx[i], 0.0, spec.width);
      s.y[i] = std::clamp(s.y[i] + scale * c.dy[i], 0.0, spec.height);
    }
    report.iterations = it + 1;
    if (progress)
      progress(it + 1, maxIterations(spec), energy / report.energy.front());
  }
  return report;
}

double overlapEnergy(const Sites &s, const TargetSpec &spec) {
  const double r_grain_max = 0.5 * spec.diameter_max;
  const double r_void = 0.5 * spec.void_ratio * spec.meanDiameter();
  PointGrid grains = pointGrid(spec.width, spec.height, r_grain_max);
  PointGrid voids = pointGrid(spec.width, spec.height, 2.0 * r_void);
  binPoints(grains, s.x.data(), s.y.data(), s.r.data(), 0, static_cast<std::uint32_t>(s.grains));
  binPoints(voids, s.x.data(), s.y.data(), s.r.data(), static_cast<std::uint32_t>(s.grains),
            static_cast<std::uint32_t>(s.size()));
  Conflicts c{std::vector<double>(s.size()), std::vector<double>(s.size()),
              std::vector<double>(s.size())};
  conflicts(s, spec, grains, voids, r_grain_max, r_void, c);
  return std::accumulate(c.energy.begin(), c.energy.end(), 0.0);
}

} // namespace mesopen
