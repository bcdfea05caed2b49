#include "polygon.hpp"

#include <algorithm>

namespace mesopen {

double signedArea(const double *x, const double *y, std::size_t n) {
  double twice = 0.0;
  for (std::size_t i = 0, j = n - 1; i < n; j = i++)
    twice += x[j] * y[i] - x[i] * y[j];
  return 0.5 * twice;
}

Point centroid(const double *x, const double *y, std::size_t n) {
  // Shift to the first vertex so that the sums do not cancel for small, distant polygons.
  double a = 0.0, cx = 0.0, cy = 0.0;
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const double xj = x[j] - x[0], yj = y[j] - y[0], xi = x[i] - x[0], yi = y[i] - y[0];
    const double c = xj * yi - xi * yj;
    a += c;
    cx += (xj + xi) * c;
    cy += (yj + yi) * c;
  }
  if (a == 0.0)
    return {x[0], y[0]};
  return {x[0] + cx / (3.0 * a), y[0] + cy / (3.0 * a)};
}

bool isConvex(const double *x, const double *y, std::size_t n, double tolerance) {
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t p = (i + n - 1) % n, q = (i + 1) % n;
    const double ax = x[i] - x[p], ay = y[i] - y[p], bx = x[q] - x[i], by = y[q] - y[i];
    const double scale = std::hypot(ax, ay) * std::hypot(bx, by);
    if (cross(ax, ay, bx, by) < -tolerance * scale)
      return false;
  }
  return true;
}

double clippedArea(const double *x, const double *y, std::size_t n, double x0, double y0, double x1,
                   double y1) {
  std::vector<Point> poly(n), next;
  for (std::size_t i = 0; i < n; ++i)
    poly[i] = {x[i], y[i]};
  // Clip against the four half-planes in turn: keep points with side(p) >= 0.
  auto clip = [&](auto side) {
    next.clear();
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const Point a = poly[i], b = poly[(i + 1) % poly.size()];
      const double sa = side(a), sb = side(b);
      if (sa >= 0)
        next.push_back(a);
      if ((sa >= 0) != (sb >= 0)) {
        const double t = sa / (sa - sb);
        next.push_back({a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)});
      }
    }
    poly.swap(next);
  };
  clip([&](Point p) { return p.x - x0; });
  clip([&](Point p) { return x1 - p.x; });
  clip([&](Point p) { return p.y - y0; });
  clip([&](Point p) { return y1 - p.y; });
  if (poly.size() < 3)
    return 0.0;
  std::vector<double> px(poly.size()), py(poly.size());
  for (std::size_t i = 0; i < poly.size(); ++i)
    px[i] = poly[i].x, py[i] = poly[i].y;
  return std::abs(signedArea(px.data(), py.data(), px.size()));
}

} // namespace mesopen
