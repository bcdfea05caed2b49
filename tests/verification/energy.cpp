// Energy accounting: with the artificial viscosity off, an elastic body vibrating freely keeps
// kinetic + internal energy constant; with imposed velocities the external work closes the
// balance.
#include "meshes.hpp"
#include "solver.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace mesopen;
using test::TestMesh;

// Free vibration of an irregularly meshed steel block started with a non-rigid velocity field.
// Central differences conserve a shadow energy; the balance error stays O(dt^2) and bounded.
// Requirement (issue 3): |balance error| <= 0.1 % over many vibration periods.
TEST(Energy, ElasticVibrationConservesEnergy) {
  TestMesh mesh;
  mesh.addRectangle(0, 0, 1e-3, 0.5e-3, 16, 8, 0.3, 5);
  fem::Model model = mesh.model(test::oneMaterial("steel-elastic"));
  for (std::size_t a = 0; a < model.nodes.size(); ++a) {
    const double x = model.nodes.x[a] / 1e-3, y = model.nodes.y[a] / 0.5e-3;
    model.nodes.vx[a] = 20.0 * std::sin(M_PI * y) * (x - 0.5);
    model.nodes.vy[a] = 30.0 * std::cos(M_PI * x) * y;
  }
  fem::Solver solver(model, {.viscosity_linear = 0.0, .viscosity_quadratic = 0.0});
  const double e0 = solver.energy().kinetic;
  double worst = 0.0, most_internal = 0.0;
  while (solver.time() < 2e-6) { // ~10 periods of the lowest modes
    solver.step();
    worst = std::max(worst, std::abs(solver.energy().balance_error));
    most_internal = std::max(most_internal, solver.energy().internal);
  }
  EXPECT_GT(most_internal, 0.3 * e0); // energy really goes back and forth
  EXPECT_LT(worst, 1e-3) << "after " << solver.steps() << " steps";
}

// Work done by a piston on a confined elastic column: kinetic + internal = external work.
TEST(Energy, ExternalWorkOfImposedVelocity) {
  TestMesh mesh;
  mesh.addRectangle(0, 0, 0.1e-3, 2e-3, 2, 40, 0.0);
  fem::Model model = mesh.model(test::oneMaterial("steel-elastic"));
  std::vector<std::uint32_t> all(model.nodes.size());
  for (std::uint32_t a = 0; a < all.size(); ++a)
    all[a] = a;
  model.constraints.push_back({"confined", all, true, false, 0.0, 0.0});
  model.constraints.push_back(
      {"piston", test::nodesWhere(model, [](double, double y) { return y < 1e-12; }), false, true, 0.0, 5.0});
  fem::Solver solver(model, {.viscosity_linear = 0.0, .viscosity_quadratic = 0.0});
  double worst = 0.0;
  while (solver.time() < 0.5e-6) {
    solver.step();
    worst = std::max(worst, std::abs(solver.energy().balance_error));
  }
  EXPECT_GT(solver.energy().external, 0.0);
  EXPECT_LT(worst, 1e-3);
}
