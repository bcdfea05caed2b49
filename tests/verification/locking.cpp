// Volumetric locking: a flat rigid punch pressed into an elastic-perfectly-plastic block in plane
// strain (Nagtegaal, Parks & Rice 1974). Prandtl's limit load, exact for a rigid-plastic
// half-space, is P = (2 + pi) k a with k = Y / sqrt(3) (von Mises in plane strain) and a the
// punch width. Plain constant-strain triangles with one diagonal per cell lock: the load climbs
// far past the limit. With the averaged nodal volume the load levels off near the limit.
// Y / E = 1 / 1000 so that the limit is reached at small indentation (geometry nearly unchanged).
#include "meshes.hpp"
#include "solver.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace mesopen;
using test::TestMesh;

namespace {

constexpr double a = 1e-3, Y = 0.2e9;

// Punch load [N/m] against indentation depth [m] for a block 8a x 4a (rollers on the sides and
// the bottom) with `per_punch` elements under the punch; quasi-static: punch speed 2 m/s (the
// same loads within 0.5 % at 0.5 m/s), sampled every 0.1 % of a.
std::vector<std::pair<double, double>> punch(bool anti_locking, double depth, int per_punch) {
  TestMesh mesh;
  const double W = 8 * a, H = 4 * a, v = 2.0;
  mesh.addRectangle(0, 0, W, H, 8 * per_punch, 4 * per_punch);
  fem::Model model = mesh.model(test::oneMaterial("von-mises", {{"k1", 0},
                                                                {"k2", 0},
                                                                {"gruneisen", 0},
                                                                {"yield_stress", Y},
                                                                {"hardening_modulus", 0},
                                                                {"pressure_cutoff", 1e12}}));
  const auto under = test::nodesWhere(model, [&](double x, double y) {
    return y > H - 1e-9 && std::abs(x - 0.5 * W) <= 0.5 * a + 1e-9;
  });
  model.constraints.push_back({"punch", under, false, true, 0.0, -v});
  model.constraints.push_back({"bottom",
                               test::nodesWhere(model, [](double, double y) { return y < 1e-9; }),
                               false, true, 0, 0});
  model.constraints.push_back(
      {"sides", test::nodesWhere(model, [&](double x, double) { return x < 1e-9 || x > W - 1e-9; }),
       true, false, 0, 0});
  fem::Solver solver(model, {.anti_locking = anti_locking});
  std::vector<std::pair<double, double>> curve;
  double next = 0.0;
  while (v * solver.time() < depth) {
    solver.step();
    if (v * solver.time() >= next) {
      double load = 0.0; // the block's resistance at the punch nodes
      for (std::uint32_t n : under)
        load += model.nodes.fy[n];
      curve.emplace_back(v * solver.time(), load);
      next += 0.001 * a;
    }
  }
  return curve;
}

} // namespace

// Prandtl's load is the rigid-plastic limit; the elastic-plastic elements approach it from above
// as the mesh is refined, the excess coming from the singular punch corners (measured, load at
// 4 % of a: 1.19 with 8 elements under the punch, 1.125 with 16). Requirements: the
// averaged-volume load levels off (it rises by less than 5 % of the limit over the second half
// of the indentation) and lies within 20 % of the limit on the coarse mesh and closer on the
// finer one; the plain elements lock: more than 40 % above the limit and still rising by more
// than 10 % of it.
TEST(Locking, PunchLimitLoad) {
  const double limit = (2.0 + M_PI) * Y / std::sqrt(3.0) * a;
  const double depth = 0.04 * a;
  const auto good = punch(true, depth, 8);
  const auto plain = punch(false, depth, 8);
  const auto fine = punch(true, depth, 16);
  auto at = [&](const std::vector<std::pair<double, double>> &curve, double d) {
    for (const auto &[x, load] : curve)
      if (x >= d)
        return load / limit;
    return curve.back().second / limit;
  };
  for (double d = 0.0; d <= depth + 1e-12; d += 0.005 * a)
    std::printf("depth/a %.3f  P/P_Prandtl: averaged volume %.3f (finer mesh %.3f), plain %.3f\n",
                d / a, at(good, d), at(fine, d), at(plain, d));
  EXPECT_LT(at(good, depth) - at(good, depth / 2), 0.05);
  EXPECT_NEAR(at(good, depth), 1.0, 0.20);
  EXPECT_LT(std::abs(at(fine, depth) - 1.0), std::abs(at(good, depth) - 1.0));
  EXPECT_GT(at(plain, depth), 1.40);
  EXPECT_GT(at(plain, depth) - at(plain, depth / 2), 0.10);
}
