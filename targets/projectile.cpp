#include "projectile.hpp"

#include "polygon.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace mesopen {

namespace {

constexpr double degree = M_PI / 180.0;

// A number for an error message, %g (std::to_string prints micrometres as 0.000040).
std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

// Angle of the facet end on the right ogive arc, seen from the arc's centre (d/2 - rho, L_n):
// the arc runs from phi_f < 0 at the facet end to 0 at the shoulder.
double facetEndAngle(const ProjectileShape &s) {
  const double c = 0.5 * s.diameter - s.halfWidth(s.facet_end); // d/2 - y_f
  return -std::atan2(s.nose_length - s.facet_end, s.ogive_radius - c);
}

// Height of the segment (x0, y0)-(x1, y1) at abscissa x, or NaN when x is outside it or the
// segment is vertical (its end points are then covered as vertices).
double segmentY(double x0, double y0, double x1, double y1, double x) {
  if (x0 == x1 || x < std::min(x0, x1) || x > std::max(x0, x1))
    return std::numeric_limits<double>::quiet_NaN();
  const double t = (x - x0) / (x1 - x0);
  return y0 + t * (y1 - y0);
}

} // namespace

// Eq. 3.2: y(s) = sqrt(rho^2 - (s - L_n)^2) + d/2 - rho on the nose, d/2 on the
// shank, 0 outside the body.
double ProjectileShape::halfWidth(double s) const {
  if (s < 0.0 || s > length)
    return 0.0;
  if (s >= nose_length)
    return 0.5 * diameter;
  const double u = s - nose_length;
  return std::sqrt((ogive_radius - u) * (ogive_radius + u)) + 0.5 * diameter - ogive_radius;
}

ProjectileShape projectileShape(const ProjectileSpec &spec) {
  if (!(spec.length > 0.0) || !(spec.length_over_diameter > 0.0))
    throw std::invalid_argument("projectile: length and length_over_diameter must be positive");
  // rho >= d/2, or the two arcs would not meet on the axis (psi = 1/2: a hemisphere).
  if (!(spec.crh >= 0.5))
    throw std::invalid_argument("projectile: a tangent ogive needs crh >= 1/2 (got " +
                                num(spec.crh) + ")");
  ProjectileShape s{};
  s.length = spec.length;
  s.diameter = spec.length / spec.length_over_diameter;    // d = L / (l/d)
  s.ogive_radius = spec.crh * s.diameter;                  // rho = psi d
  s.nose_length = s.diameter * std::sqrt(spec.crh - 0.25); // L_n = d sqrt(psi - 1/4)
  if (s.nose_length > s.length)
    throw std::invalid_argument("projectile: the ogive nose (" + num(s.nose_length) +
                                " m) is longer than the projectile (" + num(s.length) + " m)");

  const double ell = spec.tip_facet_length;
  if (!(ell >= 0.0))
    throw std::invalid_argument("projectile: tip_facet_length must be >= 0");
  s.tip_cut = s.facet_end = 0.0;
  if (ell == 0.0)
    return s;

  // The facets cut the tip only if they are blunter than the ogive's own tip, whose half-angle
  // is atan(y'(0)) = atan(L_n / (rho - d/2)), and not beyond a flat face (theta <= 90 deg).
  const double ogive_tip = std::atan2(s.nose_length, s.ogive_radius - 0.5 * s.diameter) / degree;
  const double theta = spec.tip_half_angle;
  if (!(ogive_tip < 90.0)) // a hemispherical nose (crh 1/2): no range of angles left
    throw std::invalid_argument("projectile: tip_facet_length " + num(ell) +
                                " m: the ogive's tip (crh " + num(spec.crh) +
                                ") is already flat, 90 deg, and no facet can blunt it; allowed: "
                                "tip_facet_length = 0, or crh > 0.5");
  if (!(theta > ogive_tip && theta <= 90.0))
    throw std::invalid_argument("projectile: tip_half_angle " + num(theta) + " deg must lie in (" +
                                num(ogive_tip) + ", 90], above the ogive's own tip half-angle");
  // Facet end: y(s_f) = ell sin(theta). With c = d/2 - y_f, inverting Eq. 3.2 gives
  // L_n - s_f = sqrt(rho^2 - (rho - c)^2) = sqrt(c (2 rho - c)), exact and monotone in y_f.
  const double y_f = ell * std::sin(theta * degree);
  const double c = 0.5 * s.diameter - y_f;
  if (c < 0.0)
    throw std::invalid_argument("projectile: tip facets of " + num(ell) +
                                " m reach past the shoulder (facet half-width " + num(y_f) +
                                " m > d/2)");
  s.facet_end = s.nose_length - std::sqrt(c * (2.0 * s.ogive_radius - c));
  // s_t = s_f - ell cos(theta) > 0 follows from theta above the ogive's tip angle (y concave).
  s.tip_cut = s.facet_end - ell * std::cos(theta * degree);
  return s;
}

void projectileOutline(const ProjectileShape &shape, double edge, std::vector<double> &x,
                       std::vector<double> &y) {
  if (!(edge > 0.0))
    throw std::invalid_argument("projectile: outline edge must be positive");
  const double half = 0.5 * shape.diameter, rho = shape.ogive_radius;
  const double s_t = shape.tip_cut, s_f = shape.facet_end;
  const double y_f = shape.halfWidth(s_f);

  // Right side (x >= 0), from the apex (excluded) up to the base corner (d/2, L).
  std::vector<double> rx, ry;
  // Facet: the straight line (0, s_t) -> (y_f, s_f), split evenly; none for a sharp tip
  // (s_f = 0, where y(0) is zero only to round-off).
  const int nf = s_f > 0.0 ? edgePieces(std::hypot(y_f, s_f - s_t), edge) : 0;
  for (int k = 1; k < nf; ++k) {
    const double t = static_cast<double>(k) / nf;
    rx.push_back(t * y_f);
    ry.push_back(s_t + t * (s_f - s_t));
  }
  if (nf > 0) {
    rx.push_back(y_f);
    ry.push_back(s_f);
  }
  // Ogive arc about (d/2 - rho, L_n), equal angles phi_f (1 - k/q); each arc piece rho dphi is
  // at most `edge`, so each chord is too. x = d/2 - rho (1 - cos phi) = d/2 - 2 rho sin^2(phi/2).
  const double phi_f = facetEndAngle(shape);
  const int na = edgePieces(-phi_f * rho, edge);
  for (int k = 1; k < na; ++k) {
    const double phi = phi_f * (1.0 - static_cast<double>(k) / na);
    const double h = std::sin(0.5 * phi);
    rx.push_back(half - 2.0 * rho * h * h);
    ry.push_back(shape.nose_length + rho * std::sin(phi));
  }
  if (na > 0) {
    rx.push_back(half);
    ry.push_back(shape.nose_length);
  }
  // Shank: x = d/2 from L_n to L.
  const double shank = shape.length - shape.nose_length;
  const int ns = edgePieces(shank, edge);
  for (int k = 1; k < ns; ++k) {
    rx.push_back(half);
    ry.push_back(shape.nose_length + shank * k / ns);
  }
  if (ns > 0) {
    rx.push_back(half);
    ry.push_back(shape.length);
  }

  // Apex, right side, base, mirrored left side: point i and point N - i are exact mirrors.
  const std::size_t m = rx.size();
  const int nb = edgePieces(shape.diameter, edge);
  x.assign(1, 0.0);
  y.assign(1, s_t);
  x.insert(x.end(), rx.begin(), rx.end());
  y.insert(y.end(), ry.begin(), ry.end());
  for (int k = 1; k < nb; ++k) {
    x.push_back(half * (nb - 2 * k) / nb); // x_{nb-k} = -x_k exactly
    y.push_back(shape.length);
  }
  for (std::size_t i = m; i-- > 0;) {
    x.push_back(-rx[i]);
    y.push_back(ry[i]);
  }
}

// Area of the blunted profile (the geometry above): facet triangle y_f (s_f - s_t), the nose
// 2 int_{s_f}^{L_n} y ds with u = s - L_n and F(u) = (u sqrt(rho^2-u^2) + rho^2 asin(u/rho))/2
// the antiderivative of sqrt(rho^2-u^2), and the shank rectangle d (L - L_n).
double exactArea(const ProjectileShape &s) {
  const double rho = s.ogive_radius, y_f = s.halfWidth(s.facet_end);
  const double u_f = s.facet_end - s.nose_length; // <= 0
  const double a = std::sqrt((rho - u_f) * (rho + u_f));
  const double F_f = 0.5 * (u_f * a + rho * rho * std::asin(u_f / rho)); // F(0) = 0
  const double nose = 2.0 * (-F_f + (0.5 * s.diameter - rho) * (-u_f));
  return y_f * (s.facet_end - s.tip_cut) + nose + s.diameter * (s.length - s.nose_length);
}

// First moment about the sharp tip over the area. Facet triangle: area y_f (s_f - s_t),
// centroid (s_t + 2 s_f)/3. Nose: 2 int (L_n + u)(sqrt(rho^2-u^2) + d/2 - rho) du with
// int u sqrt(rho^2-u^2) du = -(rho^2-u^2)^{3/2}/3. Shank: d (L - L_n) (L + L_n)/2.
double exactCentroidY(const ProjectileShape &s) {
  const double rho = s.ogive_radius, y_f = s.halfWidth(s.facet_end), L_n = s.nose_length;
  const double u_f = s.facet_end - L_n;
  const double a = std::sqrt((rho - u_f) * (rho + u_f));
  const double F_f = 0.5 * (u_f * a + rho * rho * std::asin(u_f / rho));
  // G(0) - G(u_f) = (a^3 - rho^3)/3 with a - rho = -u_f^2 / (a + rho), free of cancellation.
  const double G = -(u_f * u_f / (a + rho)) * (a * a + a * rho + rho * rho) / 3.0;
  const double c0 = 0.5 * s.diameter - rho;
  const double nose = 2.0 * (L_n * -F_f + G + c0 * 0.5 * (L_n * L_n - s.facet_end * s.facet_end));
  const double facet = y_f * (s.facet_end - s.tip_cut) * (s.tip_cut + 2.0 * s.facet_end) / 3.0;
  const double shank = s.diameter * (s.length - L_n) * 0.5 * (s.length + L_n);
  return (facet + nose + shank) / exactArea(s);
}

// The triangles by their centroid's y (then x), from the body frame's y = 0 (the tip, the
// plate's face) on: consecutive elements lie in a slab across the projectile, which the solver's
// levels step as parts of their own.
static void orderFromTheFront(TriangleMesh &mesh) {
  const std::size_t n = mesh.tri.size() / 3;
  std::vector<std::pair<double, double>> centroid(n);
  for (std::size_t t = 0; t < n; ++t) {
    const std::uint32_t *v = &mesh.tri[3 * t];
    centroid[t] = {mesh.y[v[0]] + mesh.y[v[1]] + mesh.y[v[2]],
                   mesh.x[v[0]] + mesh.x[v[1]] + mesh.x[v[2]]};
  }
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return centroid[a] < centroid[b]; });
  std::vector<std::uint32_t> tri(mesh.tri.size());
  for (std::size_t t = 0; t < n; ++t)
    std::copy_n(&mesh.tri[3 * order[t]], 3, &tri[3 * t]);
  mesh.tri = std::move(tri);
}

TriangleMesh projectileMesh(const ProjectileShape &shape, const ProjectileSpec &spec, double edge,
                            std::vector<double> &outline_x, std::vector<double> &outline_y) {
  projectileOutline(shape, edge, outline_x, outline_y);
  TriangleMesh mesh =
      qualityMesh(outline_x.data(), outline_y.data(), outline_x.size(), edge, spec.min_angle);
  orderFromTheFront(mesh);
  return mesh;
}

// A plate W wide and `length` thick in the body frame: its face on y = 0 from x = -W/2 to W/2,
// counter-clockwise, edges no longer than `edge`; and its quality mesh.
static TriangleMesh plateMesh(const ProjectileSpec &spec, double width, double edge,
                              std::vector<double> &x, std::vector<double> &y) {
  const int nw = edgePieces(width, edge), nt = edgePieces(spec.length, edge);
  x.clear(), y.clear();
  for (int k = 0; k < nw; ++k) // face
    x.push_back(width * (static_cast<double>(k) / nw - 0.5)), y.push_back(0.0);
  for (int k = 0; k < nt; ++k) // right side
    x.push_back(0.5 * width), y.push_back(spec.length * k / nt);
  for (int k = 0; k < nw; ++k) // back
    x.push_back(width * (0.5 - static_cast<double>(k) / nw)), y.push_back(spec.length);
  for (int k = 0; k < nt; ++k) // left side
    x.push_back(-0.5 * width), y.push_back(spec.length * (1.0 - static_cast<double>(k) / nt));
  TriangleMesh mesh = qualityMesh(x.data(), y.data(), x.size(), edge, spec.min_angle);
  orderFromTheFront(mesh);
  return mesh;
}

PlacedProjectile placeProjectile(const ProjectileSpec &spec, double default_mesh_size,
                                 const TargetSpec &target, const Polygons &grains,
                                 const ProjectileAttitude &attitude) {
  PlacedProjectile p;
  const double h = spec.mesh_size > 0.0 ? spec.mesh_size : default_mesh_size;
  std::vector<double> bx, by;
  if (spec.shape == ProjectileKind::plate) {
    p.shape = {target.width, 0.0, 0.0, spec.length, 0.0, 0.0};
    p.mesh = plateMesh(spec, target.width, h, bx, by);
  } else {
    p.shape = projectileShape(spec);
    p.mesh = projectileMesh(p.shape, spec, h, bx, by);
  }

  // The axis turned about the (sharp) tip, the body frame's origin: x' = R x.
  if (spec.shape != ProjectileKind::plate && attitude.angle != 0.0) {
    const double c = std::cos(attitude.angle), s = std::sin(attitude.angle);
    auto turn = [&](std::vector<double> &x, std::vector<double> &y) {
      for (std::size_t i = 0; i < x.size(); ++i) {
        const double xi = x[i];
        x[i] = c * xi - s * y[i], y[i] = s * xi + c * y[i];
      }
    };
    turn(bx, by);
    turn(p.mesh.x, p.mesh.y);
  }
  // Start with the lowest point at height H, the tip at x = W/2 + offset; then lower by the
  // smallest vertical gap between the projectile and any grain below it (both convex: the gap's
  // minimum over a common abscissa lies at a vertex of one of them, above or below an edge of the
  // other).
  p.offset_x = 0.5 * target.width + (spec.shape == ProjectileKind::plate ? 0.0 : attitude.offset);
  const bool turned = spec.shape != ProjectileKind::plate && attitude.angle != 0.0;
  const double lowest = turned ? *std::min_element(by.begin(), by.end()) : p.shape.tip_cut;
  const double start_y = target.height - lowest;
  const std::size_t n = bx.size();
  std::vector<double> px(n), py(n);
  for (std::size_t i = 0; i < n; ++i)
    px[i] = bx[i] + p.offset_x, py[i] = by[i] + start_y;
  const double x_lo = *std::min_element(px.begin(), px.end());
  const double x_hi = *std::max_element(px.begin(), px.end());

  double gap = std::numeric_limits<double>::infinity();
  for (std::size_t g = 0; g < grains.size(); ++g) {
    const std::size_t b = grains.offset[g], m = grains.corners(g);
    const double *gx = grains.x.data() + b, *gy = grains.y.data() + b;
    const auto [lo, hi] = std::minmax_element(gx, gx + m);
    if (*hi < x_lo || *lo > x_hi)
      continue;
    // Projectile vertices against grain edges (downward rays).
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < m; ++j) {
        const std::size_t k = (j + 1) % m;
        const double ye = segmentY(gx[j], gy[j], gx[k], gy[k], px[i]);
        if (!std::isnan(ye))
          gap = std::min(gap, py[i] - ye);
      }
    // Grain vertices against projectile edges (upward rays).
    for (std::size_t j = 0; j < m; ++j)
      for (std::size_t i = 0; i < n; ++i) {
        const std::size_t k = (i + 1) % n;
        const double ye = segmentY(px[i], py[i], px[k], py[k], gx[j]);
        if (!std::isnan(ye))
          gap = std::min(gap, ye - gy[j]);
      }
  }
  p.offset_y = std::isfinite(gap) ? start_y - gap : start_y;

  p.outline_x.resize(n);
  p.outline_y.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    p.outline_x[i] = bx[i] + p.offset_x, p.outline_y[i] = by[i] + p.offset_y;
  for (std::size_t i = 0; i < p.mesh.x.size(); ++i)
    p.mesh.x[i] += p.offset_x, p.mesh.y[i] += p.offset_y;
  return p;
}

} // namespace mesopen
