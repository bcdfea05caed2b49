// The generator's pieces against what they must guarantee: counts and sizes from the formulas,
// a placement that lowers the overlap energy, grains that are convex, inside the box and do not
// overlap, meshes that cover their grains exactly, results independent of the thread count.
#include "generator.hpp"
#include "mesh.hpp"
#include "polygon.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <numeric>

using namespace mesopen;

namespace {

TargetSpec smallSpec(Tessellation t, Placement p) {
  TargetSpec s;
  s.width = s.height = 1.2e-3;
  s.diameter_min = 45e-6, s.diameter_max = 75e-6;
  s.tessellation = t;
  s.placement = p;
  s.mesh = MeshKind::none;
  return s;
}

// Two convex polygons overlap when no edge of either separates them (separating axis theorem);
// returns the depth of the shallowest separating test (negative: a gap).
double overlapDepth(const Polygons &p, std::size_t a, std::size_t b) {
  double depth = HUGE_VAL;
  for (auto [u, v] : {std::pair{a, b}, std::pair{b, a}}) {
    const double *ux = p.x.data() + p.offset[u], *uy = p.y.data() + p.offset[u];
    const double *vx = p.x.data() + p.offset[v], *vy = p.y.data() + p.offset[v];
    const std::size_t n = p.corners(u), m = p.corners(v);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t j = (i + 1) % n;
      const double ex = ux[j] - ux[i], ey = uy[j] - uy[i], len = std::hypot(ex, ey);
      double deepest = -HUGE_VAL; // how far v reaches to the inside of u's edge
      for (std::size_t k = 0; k < m; ++k)
        deepest = std::max(deepest, cross(ex, ey, vx[k] - ux[i], vy[k] - uy[i]) / len);
      depth = std::min(depth, deepest);
    }
  }
  return depth;
}

void expectValidGrains(const Polygons &grains, const TargetSpec &spec) {
  const double tol = 1e-9 * spec.meanDiameter();
  for (std::size_t g = 0; g < grains.size(); ++g) {
    const double *x = grains.x.data() + grains.offset[g], *y = grains.y.data() + grains.offset[g];
    const std::size_t n = grains.corners(g);
    ASSERT_GE(n, 3u);
    EXPECT_GT(signedArea(x, y, n), 0.0) << "grain " << g << " is not counter-clockwise";
    EXPECT_TRUE(isConvex(x, y, n, max_dent_turn + 1e-9))
        << "grain " << g << " is not convex (up to the allowed dent)";
    for (std::size_t i = 0; i < n; ++i)
      EXPECT_TRUE(x[i] >= 0 && x[i] <= spec.width && y[i] >= 0 && y[i] <= spec.height);
  }
  // No two grains overlap by more than round-off (neighbours share edges exactly).
  std::vector<std::size_t> order(grains.size());
  std::iota(order.begin(), order.end(), 0);
  std::vector<double> lo(grains.size());
  for (std::size_t g = 0; g < grains.size(); ++g)
    lo[g] = *std::min_element(grains.x.data() + grains.offset[g],
                              grains.x.data() + grains.offset[g + 1]);
  std::sort(order.begin(), order.end(), [&](auto a, auto b) { return lo[a] < lo[b]; });
  std::size_t pairs = 0;
  for (std::size_t i = 0; i < order.size(); ++i)
    for (std::size_t j = i + 1;
         j < order.size() && lo[order[j]] < lo[order[i]] + spec.diameter_max * 2; ++j) {
      EXPECT_LT(overlapDepth(grains, order[i], order[j]), tol) << order[i] << " " << order[j];
      ++pairs;
    }
  EXPECT_GT(pairs, grains.size());
}

} // namespace

TEST(Sites, GrainCountFromAreas) {
  TargetSpec s;
  s.width = s.height = 5e-3;
  s.diameter_min = s.diameter_max = 60e-6;
  s.porosity = 0.3;
  EXPECT_EQ(grainCount(s), 6189u); // thesis 4.2.1: 5 x 5 mm, 60 um, 30 % gives 6189 grains
}

TEST(Sites, StratifiedDiametersHaveTheExactMeanAndSpread) {
  TargetSpec s = smallSpec(Tessellation::power, Placement::regular);
  Random r(3);
  const std::vector<double> d = grainDiameters(s, r);
  const double mean = std::accumulate(d.begin(), d.end(), 0.0) / d.size();
  double var = 0;
  for (double v : d)
    var += (v - mean) * (v - mean);
  // Quantiles of the uniform distribution: mean exact, variance (b-a)^2/12 (1 - 1/n^2).
  EXPECT_NEAR(mean, 60e-6, 1e-15);
  const double n = d.size();
  EXPECT_NEAR(std::sqrt(var / n), 30e-6 / std::sqrt(12.0) * std::sqrt(1 - 1 / (n * n)), 1e-15);
}

TEST(Sites, VoidCountFillsTheAreaLeftByGrains) {
  const TargetSpec s = smallSpec(Tessellation::power, Placement::clustered);
  const Sites sites = initialSites(s, 1.0);
  double grain_area = 0;
  for (std::size_t i = 0; i < sites.grains; ++i)
    grain_area += M_PI * sites.r[i] * sites.r[i];
  const double void_area = M_PI * std::pow(0.25 * 60e-6 / 2, 2);
  EXPECT_NEAR(static_cast<double>(sites.size() - sites.grains), (s.area() - grain_area) / void_area,
              0.5);
}

TEST(Sites, PlacementLowersTheOverlapEnergyAndIsThreadIndependent) {
  TargetSpec s = smallSpec(Tessellation::power, Placement::clustered);
  s.max_iterations = 60;
  Sites a = initialSites(s, 0.6), b = a;
  const double before = overlapEnergy(a, s);
  omp_set_num_threads(1);
  const PlacementReport ra = relaxSites(a, s);
  omp_set_num_threads(2);
  relaxSites(b, s);
  EXPECT_LT(overlapEnergy(a, s), 0.01 * before);
  EXPECT_DOUBLE_EQ(ra.energy.front(), before);
  EXPECT_EQ(a.x, b.x); // bit for bit
  EXPECT_EQ(a.y, b.y);
}

TEST(Tessellation, PowerGrainsAreConvexDisjointAndInTheBox) {
  const TargetSpec s = smallSpec(Tessellation::power, Placement::clustered);
  GeneratorReport r;
  const Target t = generateTarget(s, r);
  EXPECT_EQ(r.tessellation.lost_grains, 0u);
  expectValidGrains(t.grains, s);
  EXPECT_EQ(t.grain_site.size(), t.grains.size());
}

TEST(Tessellation, RelaxedVoronoiGrainsAreConvexDisjointAndInTheBox) {
  const TargetSpec s = smallSpec(Tessellation::voronoi, Placement::clustered);
  GeneratorReport r;
  const Target t = generateTarget(s, r);
  expectValidGrains(t.grains, s);
  // Overlapping sites are combined (thesis 4.2.2); in this small, clustered target (about 350
  // grains, many walls) that costs a few per cent of the grains; the 5 x 5 mm regression stays
  // within 1 %.
  EXPECT_GE(t.grains.size(), 0.95 * grainCount(s));
}

TEST(Tessellation, PorosityControlMeetsTheRequest) {
  // Power cells: the porosity is continuous and increasing in the void factor, and the regula
  // falsi stops within 2e-4 of the request on these very sites.
  for (double porosity : {0.2, 0.3, 0.4}) {
    TargetSpec s = smallSpec(Tessellation::power, Placement::regular);
    s.porosity = porosity;
    GeneratorReport r;
    EXPECT_NEAR(measureTarget(generateTarget(s, r).grains, s).porosity, porosity, 2e-4);
  }
  // Relaxed Voronoi cells are not held to this: the repairs make the porosity jump and inverted
  // cells make it fall again for large factors (docs/targets.md gives the figures).
}

TEST(Measures, PorosityAndDiametersOfKnownSquares) {
  TargetSpec s;
  s.width = s.height = 1e-3;
  Polygons p;
  p.add({0, 1e-4, 1e-4, 0}, {0, 0, 1e-4, 1e-4});
  p.add({5e-4, 7e-4, 7e-4, 5e-4}, {5e-4, 5e-4, 7e-4, 7e-4});
  const TargetMeasures m = measureTarget(p, s);
  EXPECT_NEAR(m.porosity, 1 - (1e-8 + 4e-8) / 1e-6, 1e-12);
  EXPECT_NEAR(m.mean_diameter, 0.5 * (std::sqrt(4e-8 / M_PI) + std::sqrt(16e-8 / M_PI)), 1e-15);
}

// The grains' diameters span more than the sites' [d_min, d_max]: each grain is its site's cell,
// with D / 2r between the ratio's extremes (the quickstart's 42-78 um sites give grains of 35-81
// um, D / 2r of 0.84-1.19 for 98 % of them, median 0.986). Bounds: 1-99 % within 0.8-1.2, the
// median within 2 % of 1 (the porosity control scales the voids, not the grains).
TEST(Measures, CellDiametersFollowTheirSites) {
  TargetSpec s = smallSpec(Tessellation::power, Placement::regular);
  s.diameter_min = 42e-6, s.diameter_max = 78e-6;
  GeneratorReport r;
  const Target t = generateTarget(s, r);
  const TargetMeasures m = measureTarget(t.grains, s);
  const DiameterRatios q = cellOverSiteDiameter(t);
  EXPECT_LE(q.min, q.p01);
  EXPECT_LE(q.p99, q.max);
  EXPECT_GE(m.min_diameter, q.min * s.diameter_min * (1 - 1e-12));
  EXPECT_LE(m.max_diameter, q.max * s.diameter_max * (1 + 1e-12));
  EXPECT_GT(q.p01, 0.8) << q.p01;
  EXPECT_LT(q.p99, 1.2) << q.p99;
  EXPECT_NEAR(q.median, 1.0, 0.02) << q.median;
}

TEST(Measures, ClusteringTellsRegularFromClustered) {
  TargetSpec s = smallSpec(Tessellation::power, Placement::regular);
  s.width = s.height = 2.5e-3;
  GeneratorReport r1, r2;
  const double regular = measureTarget(generateTarget(s, r1).grains, s).local_porosity_std;
  s.placement = Placement::clustered;
  const double clustered = measureTarget(generateTarget(s, r2).grains, s).local_porosity_std;
  // Measured 0.036 against 0.097 on 5 x 5 mm targets: the clustered spread is over twice as large.
  EXPECT_GT(clustered, 1.8 * regular) << regular << " " << clustered;
}

TEST(Mesh, QualityMeshCoversTheGrainAndKeepsItsAngles) {
  const std::vector<double> x{0, 60e-6, 75e-6, 30e-6, -10e-6}, y{0, 0, 40e-6, 70e-6, 35e-6};
  for (double h : {10e-6, 5e-6}) {
    const TriangleMesh m = qualityMesh(x.data(), y.data(), x.size(), h, 20.7);
    double area = 0, smallest = 180;
    for (std::size_t t = 0; t < m.tri.size(); t += 3) {
      const std::uint32_t a = m.tri[t], b = m.tri[t + 1], c = m.tri[t + 2];
      const double px[3] = {m.x[a], m.x[b], m.x[c]}, py[3] = {m.y[a], m.y[b], m.y[c]};
      const double at = signedArea(px, py, 3);
      EXPECT_GT(at, 0.0);
      area += at;
      for (int k = 0; k < 3; ++k) {
        const int i = (k + 1) % 3, j = (k + 2) % 3;
        const double ux = px[i] - px[k], uy = py[i] - py[k], vx = px[j] - px[k], vy = py[j] - py[k];
        smallest = std::min(
            smallest, std::atan2(std::abs(cross(ux, uy, vx, vy)), ux * vx + uy * vy) * 180 / M_PI);
      }
    }
    // The triangles tile the polygon: equal areas to round-off.
    EXPECT_NEAR(area, signedArea(x.data(), y.data(), x.size()), 1e-12 * area);
    // The refinement bound: every angle at least 20.7 degrees, except where the polygon's own
    // corners are sharper (here the smallest corner is 63 degrees).
    EXPECT_GE(smallest, 20.7 - 1e-6);
  }
}

TEST(Mesh, FanMeshHasOneTrianglePerEdge) {
  const std::vector<double> x{0, 1, 1, 0}, y{0, 0, 1, 1};
  const TriangleMesh m = fanMesh(x.data(), y.data(), 4);
  EXPECT_EQ(m.tri.size(), 12u);
  EXPECT_DOUBLE_EQ(m.x.back(), 0.5);
  EXPECT_DOUBLE_EQ(m.y.back(), 0.5);
}

// An edge longer than the polygon (a mesh size of 1000 m on a 1 mm projectile) meshes it coarsely:
// every corner but one was dropped as closer than 1e-6 of the edge, and CGAL crashed (SIGSEGV).
TEST(QualityMesh, EdgeLongerThanThePolygon) {
  const double x[] = {0.0, 1e-3, 1e-3, 0.0}, y[] = {0.0, 0.0, 1e-3, 1e-3};
  for (const double edge : {1e-2, 1.0, 1000.0}) {
    const TriangleMesh m = qualityMesh(x, y, 4, edge, 20.7);
    double area = 0.0;
    for (std::size_t t = 0; t < m.tri.size(); t += 3) {
      const std::uint32_t a = m.tri[t], b = m.tri[t + 1], c = m.tri[t + 2];
      area += 0.5 * ((m.x[b] - m.x[a]) * (m.y[c] - m.y[a]) - (m.x[c] - m.x[a]) * (m.y[b] - m.y[a]));
    }
    EXPECT_NEAR(area, 1e-6, 1e-15) << edge; // the square, to round-off
  }
}
