#include "measures.hpp"

#include "polygon.hpp"

#include <algorithm>
#include <cmath>

namespace mesopen {

GrainFigures grainFigures(const Polygons &grains) {
  const std::size_t n = grains.size();
  GrainFigures f;
  f.area.resize(n);
  f.diameter.resize(n);
  f.centroid_x.resize(n);
  f.centroid_y.resize(n);
  for (std::size_t g = 0; g < n; ++g) {
    const double *x = grains.x.data() + grains.offset[g];
    const double *y = grains.y.data() + grains.offset[g];
    const std::size_t corners = grains.corners(g);
    f.area[g] = std::abs(signedArea(x, y, corners));
    f.diameter[g] = equivalentDiameter(f.area[g]);
    const Point c = centroid(x, y, corners);
    f.centroid_x[g] = c.x;
    f.centroid_y[g] = c.y;
  }
  return f;
}

DiameterRatios cellOverSiteDiameter(const Target &target) {
  const std::vector<double> d = grainFigures(target.grains).diameter;
  std::vector<double> ratio;
  for (std::size_t g = 0; g < d.size() && g < target.grain_site.size(); ++g)
    ratio.push_back(d[g] / (2.0 * target.sites.r[target.grain_site[g]]));
  DiameterRatios q;
  if (ratio.empty())
    return q;
  std::sort(ratio.begin(), ratio.end());
  auto quantile = [&](double p) { return ratio[static_cast<std::size_t>(p * (ratio.size() - 1))]; };
  q.min = ratio.front(), q.p01 = quantile(0.01), q.median = quantile(0.5);
  q.p99 = quantile(0.99), q.max = ratio.back();
  return q;
}

TargetMeasures measureTarget(const Polygons &grains, const TargetSpec &spec) {
  TargetMeasures m;
  const std::size_t n = grains.size();
  m.grains = n;
  const GrainFigures figures = grainFigures(grains);
  const std::vector<double> &d = figures.diameter;
  double area = 0.0;
  for (double a : figures.area)
    area += a;
  m.porosity = (spec.area() - area) / spec.area();
  if (n > 0) {
    double sum = 0.0;
    for (double v : d)
      sum += v;
    m.mean_diameter = sum / n;
    double var = 0.0;
    for (double v : d)
      var += (v - m.mean_diameter) * (v - m.mean_diameter);
    m.std_diameter = n > 1 ? std::sqrt(var / (n - 1)) : 0.0;
    m.min_diameter = *std::min_element(d.begin(), d.end());
    m.max_diameter = *std::max_element(d.begin(), d.end());
  }

  // Local porosity over windows: every grain's area is split among the windows it overlaps.
  m.window = 4.0 * spec.meanDiameter();
  const int nx = std::max(1, static_cast<int>(spec.width / m.window));
  const int ny = std::max(1, static_cast<int>(spec.height / m.window));
  const double wx = spec.width / nx, wy = spec.height / ny;
  std::vector<double> solid(static_cast<std::size_t>(nx) * ny, 0.0);
  for (std::size_t g = 0; g < n; ++g) {
    const double *x = grains.x.data() + grains.offset[g], *y = grains.y.data() + grains.offset[g];
    const std::size_t k = grains.corners(g);
    const auto [x0, x1] = std::minmax_element(x, x + k);
    const auto [y0, y1] = std::minmax_element(y, y + k);
    const int i0 = std::clamp(static_cast<int>(*x0 / wx), 0, nx - 1),
              i1 = std::clamp(static_cast<int>(*x1 / wx), 0, nx - 1);
    const int j0 = std::clamp(static_cast<int>(*y0 / wy), 0, ny - 1),
              j1 = std::clamp(static_cast<int>(*y1 / wy), 0, ny - 1);
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i)
        solid[static_cast<std::size_t>(j) * nx + i] +=
            clippedArea(x, y, k, i * wx, j * wy, (i + 1) * wx, (j + 1) * wy);
  }
  double mean = 0.0, var = 0.0;
  for (double s : solid)
    mean += 1.0 - s / (wx * wy);
  mean /= solid.size();
  for (double s : solid)
    var += std::pow(1.0 - s / (wx * wy) - mean, 2);
  m.local_porosity_std = solid.size() > 1 ? std::sqrt(var / (solid.size() - 1)) : 0.0;

  // Histogram with 1 um bins over the range of diameters.
  const double bin = 1e-6;
  if (n > 0) {
    const double lo = std::floor(m.min_diameter / bin) * bin;
    const int bins = std::max(1, static_cast<int>(std::ceil((m.max_diameter - lo) / bin + 1e-9)));
    m.histogram_counts.assign(bins, 0);
    for (int b = 0; b <= bins; ++b)
      m.histogram_edges.push_back(lo + b * bin);
    for (double v : d)
      ++m.histogram_counts[std::clamp(static_cast<int>((v - lo) / bin), 0, bins - 1)];
  }
  return m;
}

} // namespace mesopen
