#include "analyze.hpp"

#include "h5file.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace mesopen {

RunSeries readRunSeries(const std::string &path) {
  const H5File h5 = H5File::open(path);
  RunSeries s;
  // A series: one dimension, and some finite value in it.
  auto column = [&](const std::string &name) {
    if (!h5.exists(name))
      throw std::runtime_error(path + ": no " + name + " (not a run.h5 of mesopen run?)");
    if (h5.shape(name).size() != 1)
      throw std::runtime_error(path + ": " + name + " has " +
                               std::to_string(h5.shape(name).size()) +
                               " dimensions; allowed: 1 (a series)");
    std::vector<double> v = h5.read<double>(name);
    if (!v.empty() && std::none_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); }))
      throw std::runtime_error(path + ": " + name + " holds no finite value");
    return v;
  };
  s.time = column("/series/time");
  s.depth = column("/series/projectile/depth");
  s.com_x = column("/series/projectile/com_x");
  s.vx = column("/series/projectile/vx");
  s.rotational_momentum = column("/series/projectile/rotational_momentum");
  s.lateral_force = column("/series/projectile/lateral_force");
  s.tilt = column("/series/projectile/tilt");
  // Read when present (files of every version have them; hand-made ones may not).
  if (h5.exists("/series/projectile/vy"))
    s.vy = column("/series/projectile/vy");
  if (h5.exists("/series/projectile/axial_force"))
    s.axial_force = column("/series/projectile/axial_force");
  for (const char *term : {"kinetic", "internal", "plastic", "viscous", "friction", "contact",
                           "eroded", "mass_scaling", "external", "balance_error"})
    if (h5.exists(std::string("/series/energy/") + term))
      s.energy.emplace_back(term, column(std::string("/series/energy/") + term));
  for (const auto *v :
       {&s.depth, &s.com_x, &s.vx, &s.rotational_momentum, &s.lateral_force, &s.tilt})
    if (v->size() != s.time.size())
      throw std::runtime_error(path + ": the series have different lengths");
  for (const auto *v : {&s.vy, &s.axial_force})
    if (!v->empty() && v->size() != s.time.size())
      throw std::runtime_error(path + ": the series have different lengths");
  for (const auto &[term, v] : s.energy)
    if (v.size() != s.time.size())
      throw std::runtime_error(path + ": the series have different lengths");
  if (s.time.size() < 2)
    throw std::runtime_error(path + ": fewer than two samples in /series");
  // The scene's projectile.length (what run.end_depth counts in) when the file has it; else, the
  // projectile (body 0) standing on its tip at the start, its initial extent along y.
  if (h5.hasAttribute("/", "projectile_length")) {
    s.length = h5.readAttribute<double>("/", "projectile_length");
  } else {
    const auto y = column("/mesh/y");
    const auto body = h5.read<std::uint32_t>("/mesh/node_body");
    double lo = HUGE_VAL, hi = -HUGE_VAL;
    for (std::size_t a = 0; a < y.size() && a < body.size(); ++a)
      if (body[a] == 0)
        lo = std::min(lo, y[a]), hi = std::max(hi, y[a]);
    if (!(hi > lo))
      throw std::runtime_error(path + ": no projectile (body 0) in /mesh");
    s.length = hi - lo;
  }
  if (!(s.length > 0.0) || !std::isfinite(s.length))
    throw std::runtime_error(path + ": the projectile's length is " +
                             (std::ostringstream() << s.length).str() +
                             " m; allowed: a positive length [m]");
  if (h5.hasAttribute("/series/projectile", "mass"))
    s.mass = h5.readAttribute<double>("/series/projectile", "mass");
  if (h5.hasAttribute("/", "velocity"))
    s.velocity = h5.readAttribute<double>("/", "velocity");
  return s;
}

std::vector<double> cumulativeImpulse(const std::vector<double> &time,
                                      const std::vector<double> &force) {
  std::vector<double> impulse(time.size(), 0.0);
  for (std::size_t i = 1; i < time.size(); ++i)
    impulse[i] = impulse[i - 1] + 0.5 * (force[i - 1] + force[i]) * (time[i] - time[i - 1]);
  return impulse;
}

namespace {

// Least-squares a + b u + c u^2 (u in [-1, 1] over the record) removed from y in place.
void removeQuadratic(std::vector<double> &y) {
  const std::size_t n = y.size();
  double a[3][4] = {};
  for (std::size_t k = 0; k < n; ++k) {
    const double u = n > 1 ? 2.0 * k / (n - 1) - 1.0 : 0.0;
    const double p[3] = {1.0, u, u * u};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j)
        a[i][j] += p[i] * p[j];
      a[i][3] += p[i] * y[k];
    }
  }
  // Gaussian elimination of the 3 x 3 normal equations (positive definite: no pivoting needed).
  for (int i = 0; i < 3; ++i)
    for (int r = i + 1; r < 3; ++r) {
      const double f = a[r][i] / a[i][i];
      for (int j = i; j < 4; ++j)
        a[r][j] -= f * a[i][j];
    }
  double c[3];
  for (int i = 2; i >= 0; --i) {
    c[i] = a[i][3];
    for (int j = i + 1; j < 3; ++j)
      c[i] -= a[i][j] * c[j];
    c[i] /= a[i][i];
  }
  for (std::size_t k = 0; k < n; ++k) {
    const double u = n > 1 ? 2.0 * k / (n - 1) - 1.0 : 0.0;
    y[k] -= c[0] + c[1] * u + c[2] * u * u;
  }
}

} // namespace

Spectrum dominantPeriod(const std::vector<double> &x, const std::vector<double> &y,
                        std::size_t grid) {
  Spectrum s;
  // The samples with increasing x.
  std::vector<double> xs, ys;
  for (std::size_t i = 0; i < x.size() && i < y.size(); ++i)
    if (std::isfinite(x[i]) && std::isfinite(y[i]) && (xs.empty() || x[i] > xs.back()))
      xs.push_back(x[i]), ys.push_back(y[i]);
  if (xs.size() < 16 || grid < 16)
    return s;
  s.x_begin = xs.front(), s.x_end = xs.back();
  const double record = s.x_end - s.x_begin, dx = record / (grid - 1);
  if (!(dx > 0.0) || !std::isfinite(1.0 / dx))
    return s; // a record too short for its spacing to be a number
  // Linear interpolation onto the uniform grid.
  std::vector<double> u(grid);
  std::size_t j = 0;
  for (std::size_t k = 0; k < grid; ++k) {
    const double xk = s.x_begin + k * dx;
    while (j + 2 < xs.size() && xs[j + 1] < xk)
      ++j;
    const double w = std::clamp((xk - xs[j]) / (xs[j + 1] - xs[j]), 0.0, 1.0);
    u[k] = ys[j] + w * (ys[j + 1] - ys[j]);
  }
  removeQuadratic(u);
  for (std::size_t k = 0; k < grid; ++k) // Hann window
    u[k] *= 0.5 - 0.5 * std::cos(2.0 * M_PI * k / (grid - 1));
  // Power on frequencies from 2 cycles per record to a quarter of the Nyquist frequency, 8 points
  // per 1 / record (zero padding by 8): f = (16 + k) df, k < grid - 16, counted, not summed, so
  // that the loop ends whatever the record's scale.
  const double df = 0.125 / record;
  for (std::size_t k_f = 0; k_f < grid - 16; ++k_f) {
    const double f = static_cast<double>(16 + k_f) * df;
    double re = 0.0, im = 0.0;
    const double step = 2.0 * M_PI * f * dx;
    const double cs = std::cos(step), sn = std::sin(step);
    double c = 1.0, si = 0.0; // exp(-i 2 pi f k dx) by rotation
    for (std::size_t k = 0; k < grid; ++k) {
      re += u[k] * c, im -= u[k] * si;
      const double c2 = c * cs - si * sn;
      si = si * cs + c * sn, c = c2;
    }
    s.frequency.push_back(f), s.power.push_back(re * re + im * im);
  }
  if (s.power.size() < 3)
    return s;
  // The highest local maximum inside the band: a maximum at the band's low edge is what is left
  // of the trend, not an oscillation.
  std::size_t peak = 0;
  for (std::size_t i = 1; i + 1 < s.power.size(); ++i)
    if (s.power[i] > s.power[i - 1] && s.power[i] >= s.power[i + 1] &&
        (peak == 0 || s.power[i] > s.power[peak]))
      peak = i;
  if (peak == 0)
    return s;
  // The vertex of the parabola through the peak and its neighbours.
  const double p0 = s.power[peak - 1], p1 = s.power[peak], p2 = s.power[peak + 1];
  const double f_peak = s.frequency[peak] + 0.5 * (p0 - p2) / (p0 - 2.0 * p1 + p2) * df;
  std::vector<double> sorted = s.power;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double median = sorted[sorted.size() / 2];
  s.period = 1.0 / f_peak;
  s.peak_over_median = median > 0.0 ? s.power[peak] / median : 0.0;
  s.peak_over_largest = s.power[peak] / *std::max_element(s.power.begin(), s.power.end());
  constexpr std::size_t resolution = 8; // grid points per 1 / record
  s.at_band_edge = peak <= resolution || peak + 1 + resolution >= s.power.size();
  return s;
}

Instability instability(const RunSeries &s) {
  Instability m;
  const std::size_t n = s.time.size();
  for (std::size_t i = 0; i < n; ++i) {
    m.scaled_depth.push_back(s.depth[i] / s.length);
    m.lateral_displacement.push_back(s.com_x[i] - s.com_x[0]);
    if (s.mass > 0.0) // radial (lateral) momentum, thesis Fig. 5.24
      m.radial_momentum.push_back(s.mass * s.vx[i]);
  }
  m.lateral_impulse = cumulativeImpulse(s.time, s.lateral_force);
  for (std::size_t i = 0; i < n; ++i) {
    const double elapsed = s.time[i] - s.time[0];
    m.average_lateral_force.push_back(elapsed > 0.0 ? m.lateral_impulse[i] / elapsed : 0.0);
  }
  m.in_depth = dominantPeriod(m.scaled_depth, s.rotational_momentum);
  m.in_time = dominantPeriod(s.time, s.rotational_momentum);
  return m;
}

} // namespace mesopen
