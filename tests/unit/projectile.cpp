// The projectile's geometry (thesis sections 3.2, 4.3): tangent-ogive
// profile, tip facets, outline polygon against the closed-form area and centroid, the mesh, and
// the placement on a target.
#include "projectile.hpp"
#include "polygon.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <vector>

using namespace mesopen;

namespace {

constexpr double eps = std::numeric_limits<double>::epsilon();
constexpr double degree = M_PI / 180.0;

struct Outline {
  std::vector<double> x, y;
  std::size_t size() const { return x.size(); }
};

Outline outline(const ProjectileShape &s, double edge) {
  Outline o;
  projectileOutline(s, edge, o.x, o.y);
  return o;
}

double area(const Outline &o) { return signedArea(o.x.data(), o.y.data(), o.size()); }

// Arc length of one ogive arc, facet end to shoulder: rho times the angle it subtends,
// asin((L_n - s_f) / rho).
double arcLength(const ProjectileShape &s) {
  return s.ogive_radius * std::asin((s.nose_length - s.facet_end) / s.ogive_radius);
}

// Area the inscribed outline misses: a circular segment of chord c under an arc piece l <= h
// has area rho^2 (dphi - sin dphi)/2 <= l^3 / (12 rho) <= h^2 l / (12 rho); summed over both
// arcs, 0 < A_exact - A_poly <= S h^2 / (6 rho) with S one arc's length.
double areaErrorBound(const ProjectileShape &s, double h) {
  return arcLength(s) * h * h / (6.0 * s.ogive_radius);
}

// Smallest Euclidean distance between two polygons' boundaries (vertex to segment, both ways).
double pointSegment(double px, double py, double ax, double ay, double bx, double by) {
  const double dx = bx - ax, dy = by - ay;
  const double t = std::clamp(((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy), 0.0, 1.0);
  return std::hypot(px - ax - t * dx, py - ay - t * dy);
}

double distance(const std::vector<double> &ax, const std::vector<double> &ay,
                const std::vector<double> &bx, const std::vector<double> &by) {
  double d = std::numeric_limits<double>::infinity();
  for (int pass = 0; pass < 2; ++pass) {
    const auto &px = pass ? bx : ax, &py = pass ? by : ay;
    const auto &qx = pass ? ax : bx, &qy = pass ? ay : by;
    for (std::size_t i = 0; i < px.size(); ++i)
      for (std::size_t j = 0; j < qx.size(); ++j) {
        const std::size_t k = (j + 1) % qx.size();
        d = std::min(d, pointSegment(px[i], py[i], qx[j], qy[j], qx[k], qy[k]));
      }
  }
  return d;
}

// Separating-axis measure of two convex CCW polygons: the largest, over the edges of both, of
// the smallest outward distance of the other polygon's vertices. >= 0: no overlap; < 0: the
// polygons overlap by at least that much along every edge normal.
double separation(const std::vector<double> &ax, const std::vector<double> &ay,
                  const std::vector<double> &bx, const std::vector<double> &by) {
  double best = -std::numeric_limits<double>::infinity();
  for (int pass = 0; pass < 2; ++pass) {
    const auto &px = pass ? bx : ax, &py = pass ? by : ay;
    const auto &qx = pass ? ax : bx, &qy = pass ? ay : by;
    for (std::size_t i = 0; i < px.size(); ++i) {
      const std::size_t k = (i + 1) % px.size();
      const double ex = px[k] - px[i], ey = py[k] - py[i], len = std::hypot(ex, ey);
      double least = std::numeric_limits<double>::infinity();
      for (std::size_t j = 0; j < qx.size(); ++j) // outward normal of a CCW edge: (ey, -ex)
        least = std::min(least, ((qx[j] - px[i]) * ey - (qy[j] - py[i]) * ex) / len);
      best = std::max(best, least);
    }
  }
  return best;
}

TargetSpec box() {
  TargetSpec t;
  t.width = 7.076e-3;
  t.height = 3.538e-3;
  return t;
}

} // namespace

TEST(ProjectileShape, NoseLengthOfBaseline) {
  const ProjectileShape s = projectileShape(ProjectileSpec{});
  const double d = 1.7e-3 / 3.85;
  // Same formula, different evaluation order: a few units of round-off.
  EXPECT_NEAR(s.diameter, d, 4 * eps * d);
  EXPECT_NEAR(s.ogive_radius, 3.5 * d, 4 * eps * d);
  EXPECT_NEAR(s.nose_length, d * std::sqrt(3.25), 4 * eps * d);
  // The thesis quotes L_n ~ 0.796 mm, d ~ 0.4416 mm to the last printed digit.
  EXPECT_NEAR(s.nose_length, 0.796e-3, 0.5e-6);
  EXPECT_NEAR(s.diameter, 0.4416e-3, 0.05e-6);
}

TEST(ProjectileShape, SharpOgiveStartsOnTheAxis) {
  const ProjectileShape s = projectileShape(ProjectileSpec{});
  // y(0) = sqrt(rho^2 - L_n^2) + d/2 - rho = 3d + d/2 - 7d/2: round-off of terms of size rho.
  EXPECT_NEAR(s.halfWidth(0.0), 0.0, 4 * eps * s.ogive_radius);
}

TEST(ProjectileShape, ShoulderIsTangent) {
  const ProjectileShape s = projectileShape(ProjectileSpec{});
  const double L_n = s.nose_length, half = 0.5 * s.diameter;
  // Continuity at L_n: the nose formula gives rho + d/2 - rho there; round-off of size rho.
  EXPECT_NEAR(s.halfWidth(std::nextafter(L_n, 0.0)), half, 4 * eps * s.ogive_radius);
  EXPECT_EQ(s.halfWidth(L_n), half);
  EXPECT_EQ(s.halfWidth(0.5 * (L_n + s.length)), half);
  // Tangency: near the shoulder y = d/2 - delta^2/(2 rho) + O(delta^4), so the secant slope
  // over [L_n - delta, L_n] is delta/(2 rho) -> 0. 1 %: the O(delta^2/rho^2) terms are < 1e-4
  // relative and the round-off (~eps rho / delta^2 ~ 1e-5 relative at 1e-7 m) is smaller.
  for (double delta : {1e-5, 1e-6, 1e-7}) {
    const double slope = (s.halfWidth(L_n) - s.halfWidth(L_n - delta)) / delta;
    EXPECT_GT(slope, 0.0);
    EXPECT_NEAR(slope, delta / (2.0 * s.ogive_radius), 0.01 * delta / (2.0 * s.ogive_radius));
  }
}

TEST(ProjectileShape, FacetsCutTheTip) {
  const ProjectileSpec spec;
  const ProjectileShape s = projectileShape(spec);
  const double theta = spec.tip_half_angle * degree, ell = spec.tip_facet_length;
  // y(s_f) = ell sin(theta): s_f comes from inverting y, so y(s_f) carries the round-off of
  // Eq. 3.2 (terms of size rho ~ 1.5 mm, ulp ~ 2e-19 m), far below 1e-12 ell.
  EXPECT_NEAR(s.halfWidth(s.facet_end), ell * std::sin(theta), 1e-12 * ell);
  EXPECT_NEAR(s.facet_end - s.tip_cut, ell * std::cos(theta), 1e-12 * ell);
  EXPECT_GT(s.tip_cut, 0.0);
  EXPECT_LT(s.facet_end, s.nose_length);

  const double h = 10e-6;
  const Outline o = outline(s, h);
  ASSERT_EQ(o.x[0], 0.0);
  ASSERT_EQ(o.y[0], s.tip_cut);
  // The facet end is an outline point; the points between it and the apex lie on the facet.
  std::size_t f = 0;
  for (std::size_t i = 1; i < o.size() / 2; ++i)
    if (o.y[i] == s.facet_end)
      f = i;
  ASSERT_GT(f, 0u);
  // Evenly split into pieces <= h (with qualityMesh's 1e-9 slack in the count).
  EXPECT_EQ(f, static_cast<std::size_t>(std::ceil(ell / h - 1e-9)));
  const double fx = o.x[f], fy = o.y[f] - o.y[0];
  // Length and angle from the outline's points: coordinate round-off ~1e-18 m, << 1e-12 ell.
  EXPECT_NEAR(std::hypot(fx, fy), ell, 1e-12 * ell);
  EXPECT_NEAR(std::atan2(fx, fy), theta, 1e-12);
  for (std::size_t i = 1; i < f; ++i) // distance from the facet line, round-off of ~1e-4 m
    EXPECT_NEAR((o.x[i] * fy - (o.y[i] - o.y[0]) * fx) / ell, 0.0, 1e-12 * ell);
  // Same on the mirrored facet.
  const std::size_t g = o.size() - f;
  EXPECT_EQ(o.x[g], -fx);
  EXPECT_EQ(o.y[g], o.y[f]);
}

TEST(ProjectileShape, RejectsFacetsThatDoNotCut) {
  ProjectileSpec spec;
  spec.tip_half_angle = 25.0; // sharper than the ogive's own ~31 deg tip
  EXPECT_THROW(projectileShape(spec), std::invalid_argument);
  spec.tip_half_angle = 95.0; // a concave tip
  EXPECT_THROW(projectileShape(spec), std::invalid_argument);
  spec = ProjectileSpec{};
  spec.tip_facet_length = 1e-3; // the facet would end past the shoulder
  EXPECT_THROW(projectileShape(spec), std::invalid_argument);
  spec = ProjectileSpec{};
  spec.crh = 0.5; // a hemispherical nose, already flat at the tip: an empty range, said so (it
                  // printed "(90, 90]")
  try {
    projectileShape(spec);
    ADD_FAILURE() << "a facet on a hemispherical nose was accepted";
  } catch (const std::invalid_argument &e) {
    EXPECT_NE(std::string(e.what()).find("already flat"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find("(90, 90]"), std::string::npos) << e.what();
  }
  spec = ProjectileSpec{};
  spec.crh = 0.4; // no tangent ogive
  EXPECT_THROW(projectileShape(spec), std::invalid_argument);
  spec = ProjectileSpec{};
  spec.length_over_diameter = 0.5; // the nose is longer than the projectile
  EXPECT_THROW(projectileShape(spec), std::invalid_argument);
  spec = ProjectileSpec{};
  spec.tip_facet_length = 0.0; // a sharp tip
  const ProjectileShape s = projectileShape(spec);
  EXPECT_EQ(s.tip_cut, 0.0);
  EXPECT_EQ(s.facet_end, 0.0);
}

class ProjectileOutlineFacets : public testing::TestWithParam<double> {};

TEST_P(ProjectileOutlineFacets, CounterClockwiseSymmetricAndFine) {
  ProjectileSpec spec;
  spec.tip_facet_length = GetParam();
  const ProjectileShape s = projectileShape(spec);
  const double h = 10e-6;
  const Outline o = outline(s, h);
  const std::size_t n = o.size();
  EXPECT_GT(area(o), 0.0);
  EXPECT_TRUE(isConvex(o.x.data(), o.y.data(), n));
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t j = (i + 1) % n;
    const double len = std::hypot(o.x[j] - o.x[i], o.y[j] - o.y[i]);
    EXPECT_GT(len, 0.0) << "duplicate point " << i;
    EXPECT_LE(len, h * (1 + 1e-9)) << "edge " << i; // qualityMesh's own splitting slack
    // Exact mirror: point i and point n - i.
    const std::size_t m = (n - i) % n;
    EXPECT_EQ(o.x[m], -o.x[i]);
    EXPECT_EQ(o.y[m], o.y[i]);
  }
  // Ogive points lie on their circle, centre (d/2 - rho, L_n): round-off of sin/cos at rho.
  const double cx = 0.5 * s.diameter - s.ogive_radius;
  int on_arc = 0;
  for (std::size_t i = 0; i <= n / 2; ++i) // the right side
    if (o.y[i] >= s.facet_end && o.y[i] <= s.nose_length) {
      EXPECT_NEAR(std::hypot(o.x[i] - cx, o.y[i] - s.nose_length), s.ogive_radius,
                  8 * eps * s.ogive_radius);
      ++on_arc;
    }
  EXPECT_EQ(on_arc, static_cast<int>(std::ceil(arcLength(s) / h - 1e-9)) + 1);
  // Extent: apex at the blunted tip, base at L, width d.
  EXPECT_EQ(*std::min_element(o.y.begin(), o.y.end()), s.tip_cut);
  EXPECT_EQ(*std::max_element(o.y.begin(), o.y.end()), s.length);
  EXPECT_EQ(*std::max_element(o.x.begin(), o.x.end()), 0.5 * s.diameter);
}

// The baseline facets, and a sharp tip.
INSTANTIATE_TEST_SUITE_P(Tips, ProjectileOutlineFacets, testing::Values(40e-6, 0.0));

TEST(ProjectileOutline, AreaConvergesQuadratically) {
  const ProjectileShape s = projectileShape(ProjectileSpec{});
  const double exact = exactArea(s);
  // Round-off of the shoelace sum over ~400 points of size ~1e-3 m: << 1e-14 of the area.
  const double roundoff = 1e-14 * exact;
  double previous = 0.0;
  for (double h : {20e-6, 10e-6}) {
    const double err = exact - area(outline(s, h));
    const double bound = areaErrorBound(s, h);
    std::printf("h = %g m: A_exact = %.12e m^2, A_exact - A_poly = %.4e m^2 (%.3e relative), "
                "bound %.4e\n",
                h, exact, err, err / exact, bound);
    EXPECT_GT(err, 0.0); // the outline is inscribed
    EXPECT_LE(err, bound + roundoff);
    // Halving h doubles the arc pieces (up to the ceil in their count, 1 in ~40 here): the
    // error, ~1/pieces^2, drops by 4 within about 2 x 2.5 %; allow 10 %.
    if (previous > 0.0) {
      std::printf("error ratio %.4f\n", previous / err);
      EXPECT_NEAR(previous / err, 4.0, 0.4);
    }
    previous = err;
  }
  // Fine outline: the closed form agrees to the O(h^2) bound, ~1e-8 relative at 1 um.
  const double h = 1e-6;
  EXPECT_NEAR(area(outline(s, h)), exact, areaErrorBound(s, h) + roundoff);
}

// x - sin x by its series, free of cancellation for the small angles of the arc pieces.
double xMinusSin(double x) {
  const double x2 = x * x;
  return x * x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0)));
}

TEST(ProjectileOutline, ClosedFormsEqualPolygonPlusSegments) {
  // The inscribed outline misses exactly the circular segments under its ogive chords: with
  // dphi = 2 asin(c / 2 rho), each has area rho^2 (dphi - sin dphi)/2 and its centroid at
  // 4 rho sin^3(dphi/2) / (3 (dphi - sin dphi)) from the arc's centre along the bisector.
  // Adding them back must give exactArea and exactCentroidY to round-off, which checks the
  // closed forms far below the O(h^2) outline error.
  for (double ell : {40e-6, 0.0}) {
    ProjectileSpec spec;
    spec.tip_facet_length = ell;
    const ProjectileShape s = projectileShape(spec);
    const double rho = s.ogive_radius, cx = 0.5 * s.diameter - rho, h = 20e-6;
    const Outline o = outline(s, h);
    double seg_area = 0.0, seg_moment = 0.0;
    for (std::size_t i = 0; i + 1 < o.size() / 2; ++i) {
      if (o.x[i + 1] <= 0.0 || o.y[i] < s.facet_end || o.y[i + 1] > s.nose_length)
        continue; // not an ogive chord of the right side
      const double c = std::hypot(o.x[i + 1] - o.x[i], o.y[i + 1] - o.y[i]);
      const double dphi = 2.0 * std::asin(c / (2.0 * rho));
      const double a = 0.5 * rho * rho * xMinusSin(dphi);
      const double r = 4.0 * rho * std::pow(std::sin(0.5 * dphi), 3) / (3.0 * xMinusSin(dphi));
      const double mid = 0.5 * (std::atan2(o.y[i] - s.nose_length, o.x[i] - cx) +
                                std::atan2(o.y[i + 1] - s.nose_length, o.x[i + 1] - cx));
      seg_area += 2.0 * a; // both sides
      seg_moment += 2.0 * a * (s.nose_length + r * std::sin(mid));
    }
    const double a_poly = area(o);
    const Point c = centroid(o.x.data(), o.y.data(), o.size());
    const double a_exact = exactArea(s);
    std::printf("facet %g m: (A_poly + segments) / A_exact - 1 = %.3e, centroid difference "
                "%.3e m\n",
                ell, (a_poly + seg_area) / a_exact - 1.0,
                (c.y * a_poly + seg_moment) / a_exact - exactCentroidY(s));
    // Round-off: the shoelace sum over ~200 products of size ~1e-6 m^2 carries ~1e-14 of the
    // area; the segment sums are 5e-5 of the area with ~1e-9 relative error of their own.
    EXPECT_NEAR(a_poly + seg_area, a_exact, 1e-12 * a_exact);
    EXPECT_NEAR((c.y * a_poly + seg_moment) / a_exact, exactCentroidY(s), 1e-12 * s.length);
  }
}

TEST(ProjectileOutline, SharpTipArea) {
  ProjectileSpec spec;
  spec.tip_facet_length = 0.0;
  const ProjectileShape s = projectileShape(spec);
  const Outline o = outline(s, 10e-6);
  EXPECT_EQ(o.x[0], 0.0);
  EXPECT_EQ(o.y[0], 0.0);
  const double h = 2e-6;
  const double err = exactArea(s) - area(outline(s, h));
  EXPECT_GT(err, 0.0);                                         // inscribed
  EXPECT_LE(err, areaErrorBound(s, h) + 1e-14 * exactArea(s)); // bound as above
  // The facets remove 2 int_0^{s_f} y ds - y_f (s_f - s_t): positive (the facets lie inside
  // the ogive) and, since y <= y_f below s_f, at most y_f (s_f + s_t).
  const ProjectileShape b = projectileShape(ProjectileSpec{});
  const double cut = exactArea(s) - exactArea(b);
  EXPECT_GT(cut, 0.0);
  EXPECT_LT(cut, b.halfWidth(b.facet_end) * (b.facet_end + b.tip_cut));
}

TEST(ProjectileOutline, CentroidMatchesClosedForm) {
  const ProjectileShape s = projectileShape(ProjectileSpec{});
  const double exact = exactCentroidY(s);
  for (double h : {20e-6, 10e-6}) {
    const Outline o = outline(s, h);
    const Point c = centroid(o.x.data(), o.y.data(), o.size());
    const double err = exact - c.y;
    std::printf("h = %g m: C_exact = %.12e m, C_exact - C_poly = %.4e m\n", h, exact, err);
    // Moving the missing segments' area dA from points within L of the centroid moves it by
    // at most dA L / A; plus round-off (~1e-14 of L).
    EXPECT_LE(std::abs(err), areaErrorBound(s, h) * s.length / exactArea(s) + 1e-14 * s.length);
    // The mirror image cancels in x up to round-off of the shoelace sum.
    EXPECT_NEAR(c.x, 0.0, 1e-12 * s.diameter);
  }
  // The centroid lies above mid-length (the nose is thinner than the shank) and below the
  // shank rectangle's centre (L_n + L)/2 (the nose's own centroid is below L_n).
  EXPECT_GT(exact, 0.5 * s.length);
  EXPECT_LT(exact, 0.5 * (s.nose_length + s.length));
}

TEST(ProjectileMesh, AreaEqualsOutlineArea) {
  ProjectileSpec spec;
  const ProjectileShape s = projectileShape(spec);
  const double h = 20e-6;
  const Outline o = outline(s, h);
  const TriangleMesh m = qualityMesh(o.x.data(), o.y.data(), o.size(), h, spec.min_angle);
  double sum = 0.0;
  for (std::size_t t = 0; t < m.tri.size(); t += 3) {
    const double x[3] = {m.x[m.tri[t]], m.x[m.tri[t + 1]], m.x[m.tri[t + 2]]};
    const double y[3] = {m.y[m.tri[t]], m.y[m.tri[t + 1]], m.y[m.tri[t + 2]]};
    const double a = signedArea(x, y, 3);
    EXPECT_GT(a, 0.0);
    sum += a;
  }
  std::printf("%zu triangles: sum / A_poly - 1 = %.3e\n", m.tri.size() / 3, sum / area(o) - 1.0);
  // A partition of the same polygon: only summation round-off, ~eps per triangle (~1e-13).
  EXPECT_NEAR(sum, area(o), 1e-12 * area(o));
  // Every outline point is a mesh node (the mesh does not move the boundary).
  for (std::size_t i = 0; i < o.size(); ++i) {
    bool found = false;
    for (std::size_t j = 0; j < m.x.size() && !found; ++j)
      found = m.x[j] == o.x[i] && m.y[j] == o.y[i];
    EXPECT_TRUE(found) << "outline point " << i;
  }
}

// The projectile's triangles come from the tip to the base (centroid y non-decreasing, the body
// frame's tip at y = 0), so that consecutive elements lie in slabs across it (the solver's parts
// under multiple time stepping): 512 consecutive triangles span less than a tenth of its length.
TEST(ProjectileMesh, TrianglesFromTheTip) {
  ProjectileSpec spec;
  const ProjectileShape s = projectileShape(spec);
  std::vector<double> ox, oy;
  const TriangleMesh m = projectileMesh(s, spec, 10e-6, ox, oy);
  const std::size_t n = m.tri.size() / 3;
  ASSERT_GT(n, 2048u);
  auto centroid_y = [&](std::size_t t) {
    return m.y[m.tri[3 * t]] + m.y[m.tri[3 * t + 1]] + m.y[m.tri[3 * t + 2]];
  };
  for (std::size_t t = 1; t < n; ++t)
    ASSERT_LE(centroid_y(t - 1), centroid_y(t)) << "triangle " << t;
  for (std::size_t t = 0; t + 512 <= n; t += 512)
    EXPECT_LT((centroid_y(t + 511) - centroid_y(t)) / 3.0, 0.1 * spec.length) << "from " << t;
}

TEST(PlaceProjectile, RestsOnTheBoxTopWithoutGrains) {
  const ProjectileSpec spec;
  const TargetSpec t = box();
  Polygons grains;
  // A grain beside the projectile's path does not stop it.
  grains.add({0.0, 100e-6, 100e-6, 0.0},
             {t.height - 100e-6, t.height - 100e-6, t.height, t.height});
  for (const Polygons &g : {Polygons{}, grains}) {
    const PlacedProjectile p = placeProjectile(spec, 20e-6, t, g);
    EXPECT_EQ(p.offset_x, 0.5 * t.width);
    // Tip at y = H: one rounding in (H - s_t) + s_t.
    EXPECT_NEAR(*std::min_element(p.outline_y.begin(), p.outline_y.end()), t.height,
                2 * eps * t.height);
    EXPECT_NEAR(*std::min_element(p.mesh.y.begin(), p.mesh.y.end()), t.height, 2 * eps * t.height);
  }
}

// A grain under the tip stops it: touching (distance 0) without overlap, both to 1e-12 m
// (coordinates ~3.5e-3 m carry ~4e-19 m of round-off; 1e-12 m is far above it and far below
// any mesh size).
void expectTouching(const PlacedProjectile &p, const std::vector<double> &gx,
                    const std::vector<double> &gy) {
  EXPECT_LT(distance(p.outline_x, p.outline_y, gx, gy), 1e-12);
  EXPECT_GT(separation(p.outline_x, p.outline_y, gx, gy), -1e-12);
}

TEST(PlaceProjectile, TouchesAGrainUnderTheTip) {
  const ProjectileSpec spec;
  const TargetSpec t = box();
  const double c = 0.5 * t.width, top = 2.0e-3;
  const std::vector<double> gx{c - 50e-6, c + 50e-6, c + 50e-6, c - 50e-6};
  const std::vector<double> gy{top - 100e-6, top - 100e-6, top, top};
  Polygons grains;
  grains.add(gx, gy);
  const PlacedProjectile p = placeProjectile(spec, 10e-6, t, grains);
  expectTouching(p, gx, gy);
  // The flat top meets the apex: the tip sits on y = top.
  EXPECT_NEAR(*std::min_element(p.outline_y.begin(), p.outline_y.end()), top, 1e-12);
  EXPECT_NEAR(p.offset_y, top - p.shape.tip_cut, 1e-12);
  // The mesh moved with the outline.
  EXPECT_NEAR(*std::min_element(p.mesh.y.begin(), p.mesh.y.end()), top, 1e-12);
  EXPECT_NEAR(*std::min_element(p.mesh.x.begin(), p.mesh.x.end()), c - 0.5 * p.shape.diameter,
              1e-12);
}

TEST(PlaceProjectile, TouchesAGrainCornerUnderTheFlank) {
  // A grain whose corner sits under the ogive, off the axis: grain vertex against projectile
  // edge. A second grain, lower, must not matter.
  const ProjectileSpec spec;
  const TargetSpec t = box();
  const double c = 0.5 * t.width, top = 1.5e-3;
  const std::vector<double> gx{c + 150e-6, c + 400e-6, c + 400e-6, c + 150e-6};
  const std::vector<double> gy{top - 100e-6, top - 100e-6, top, top};
  const std::vector<double> lx{c - 50e-6, c + 50e-6, c + 50e-6, c - 50e-6};
  const std::vector<double> ly{0.5e-3, 0.5e-3, 0.6e-3, 0.6e-3};
  Polygons grains;
  grains.add(lx, ly);
  grains.add(gx, gy);
  const PlacedProjectile p = placeProjectile(spec, 10e-6, t, grains);
  expectTouching(p, gx, gy);
  EXPECT_GT(separation(p.outline_x, p.outline_y, lx, ly), 1e-4);
  // The tip hangs below the corner, by the nose's drop between the axis and x = 150 um.
  EXPECT_LT(*std::min_element(p.outline_y.begin(), p.outline_y.end()), top - 100e-6);
}

TEST(PlaceProjectile, TouchesASlopedGrainTop) {
  // A tilted top edge under the apex: projectile vertex against grain edge interior.
  const ProjectileSpec spec;
  const TargetSpec t = box();
  const double c = 0.5 * t.width;
  const std::vector<double> gx{c - 100e-6, c + 100e-6, c + 100e-6, c - 100e-6};
  const std::vector<double> gy{1.0e-3, 1.0e-3, 1.23e-3, 1.21e-3};
  Polygons grains;
  grains.add(gx, gy);
  const PlacedProjectile p = placeProjectile(spec, 10e-6, t, grains);
  expectTouching(p, gx, gy);
  // Apex on the edge's midpoint height (1.22 mm).
  EXPECT_NEAR(*std::min_element(p.outline_y.begin(), p.outline_y.end()), 1.22e-3, 1e-12);
}

// A yawed projectile (axis turned 10 degrees counter-clockwise from straight down about its tip)
// moved 300 um to the side: it touches the grain below without overlapping it, its axis (from the
// centroid to the sharp tip, the body frame's origin) points along (sin 10, -cos 10), the mesh
// turned and moved with the outline, and its area is the unturned one's.
TEST(PlaceProjectile, YawedAndOffsetTouchesTheGrain) {
  const ProjectileSpec spec;
  const TargetSpec t = box();
  const double c = 0.5 * t.width, top = 1.5e-3, offset = 300e-6, angle = 10.0 * M_PI / 180.0;
  const std::vector<double> gx{c - 600e-6, c + 900e-6, c + 900e-6, c - 600e-6};
  const std::vector<double> gy{top - 100e-6, top - 100e-6, top, top};
  Polygons grains;
  grains.add(gx, gy);
  const PlacedProjectile straight = placeProjectile(spec, 10e-6, t, grains);
  const PlacedProjectile p = placeProjectile(spec, 10e-6, t, grains, {angle, offset});
  expectTouching(p, gx, gy);
  auto centroidAndArea = [](const PlacedProjectile &q) {
    double ax = 0.0, ay = 0.0, area = 0.0;
    const std::size_t n = q.outline_x.size();
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = (i + 1) % n;
      const double cross = q.outline_x[i] * q.outline_y[k] - q.outline_x[k] * q.outline_y[i];
      area += 0.5 * cross;
      ax += (q.outline_x[i] + q.outline_x[k]) * cross,
          ay += (q.outline_y[i] + q.outline_y[k]) * cross;
    }
    return std::array<double, 3>{ax / (6 * area), ay / (6 * area), area};
  };
  const auto centroid = centroidAndArea(p), centroid0 = centroidAndArea(straight);
  EXPECT_NEAR(centroid[2], centroid0[2], 1e-12 * centroid0[2]);
  const double tip_x = p.offset_x, tip_y = p.offset_y;
  const double dx = tip_x - centroid[0], dy = tip_y - centroid[1], len = std::hypot(dx, dy);
  EXPECT_NEAR(dx / len, std::sin(angle), 1e-9);
  EXPECT_NEAR(dy / len, -std::cos(angle), 1e-9);
  EXPECT_NEAR(p.offset_x, c + offset, 1e-15);
  EXPECT_NEAR(*std::min_element(p.mesh.y.begin(), p.mesh.y.end()),
              *std::min_element(p.outline_y.begin(), p.outline_y.end()), 1e-12);
}
