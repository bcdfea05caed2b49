// Wave propagation against exact answers: the elastic P-wave speed in uniaxial strain, and the
// plateau of a steady shock against the Rankine-Hugoniot jump conditions with the
// Mie-Grueneisen equation of state.
#include "meshes.hpp"
#include "solver.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace mesopen;
using test::TestMesh;

namespace {

// A strip of width w and length len along y, laterally confined (v_x = 0 everywhere: uniaxial
// strain), driven at its bottom by a piston moving up at `piston` m/s.
struct Strip {
  fem::Model model;
  std::vector<std::uint32_t> bottom;
  Strip(std::unique_ptr<fem::Material> material, double w, double len, int nx, int ny,
        double piston) {
    TestMesh mesh;
    mesh.addRectangle(0, 0, w, len, nx, ny);
    std::vector<std::unique_ptr<fem::Material>> m;
    m.push_back(std::move(material));
    model = mesh.model(std::move(m));
    std::vector<std::uint32_t> all(model.nodes.size());
    for (std::uint32_t a = 0; a < all.size(); ++a)
      all[a] = a;
    model.constraints.push_back({"confined", all, true, false, 0.0, 0.0});
    bottom = test::nodesWhere(model, [](double, double y) { return y < 1e-12; });
    model.constraints.push_back({"piston", bottom, false, true, 0.0, piston});
  }
  // Mean v_y of the nodes in the row at height y.
  double rowVelocity(double y) const {
    double sum = 0.0;
    int n = 0;
    for (std::size_t a = 0; a < model.nodes.size(); ++a)
      if (std::abs(model.nodes.y0[a] - y) < 1e-9)
        sum += model.nodes.vy[a], ++n;
    return sum / n;
  }
};

} // namespace

// P-wave: c = sqrt((K + 4G/3) / rho) (uniaxial strain). The half-amplitude point of the front is
// timed at two stations 2 mm apart; tolerance 0.2 %: the numerical front is smeared over a few
// elements, but the smear grows slowly and cancels in the difference of the two arrivals
// (measured: 0.005 %).
TEST(ElasticWave, PWaveSpeed) {
  const double K = 163.9e9, G = 77.5e9, rho = 7823.0, v0 = 1.0;
  Strip strip(
      fem::makeMaterial("elastic", {{"density", rho}, {"bulk_modulus", K}, {"shear_modulus", G}}),
      0.1e-3, 4e-3, 2, 160, v0);
  fem::Solver solver(strip.model, {});
  const double y1 = 1e-3, y2 = 3e-3;
  double t1 = -1, t2 = -1;
  while (t2 < 0 && solver.time() < 2e-6) {
    const double before = solver.time();
    const double u1 = strip.rowVelocity(y1), u2 = strip.rowVelocity(y2);
    solver.step();
    // Linear interpolation of the crossing of v0 / 2 within the step.
    auto crossing = [&](double u_old, double u_new) {
      return before + (solver.time() - before) * (0.5 * v0 - u_old) / (u_new - u_old);
    };
    if (t1 < 0 && strip.rowVelocity(y1) >= 0.5 * v0)
      t1 = crossing(u1, strip.rowVelocity(y1));
    if (t2 < 0 && strip.rowVelocity(y2) >= 0.5 * v0)
      t2 = crossing(u2, strip.rowVelocity(y2));
  }
  ASSERT_GT(t1, 0);
  ASSERT_GT(t2, 0);
  const double exact = std::sqrt((K + 4.0 / 3.0 * G) / rho);
  const double measured = (y2 - y1) / (t2 - t1);
  EXPECT_NEAR(measured / exact, 1.0, 0.002) << "measured " << measured << " m/s, exact " << exact;
}

// Steady shock driven by a piston at u_p into quartz without strength (G = 0): behind the shock,
// rho0 U_s = rho (U_s - u_p), p = rho0 U_s u_p, e = u_p^2 / 2, and p must lie on the EOS:
//   p = P(mu) (1 - Gamma mu / 2) + Gamma rho0 e.
// The exact plateau comes from solving the three for mu. Tolerance 0.5 % on the pressure averaged
// over the shocked region away from piston and front (the artificial viscosity smears the front
// over a few elements and rings a little behind it, but does not change the jump; measured
// 0.003 %).
TEST(Shock, PlateauMatchesHugoniot) {
  const double rho0 = 2648.5, K = 43.19e9, K1 = 156.2e9, K2 = 48.6e9, gamma = 0.675, up = 500.0;
  Strip strip(fem::makeMaterial("quartz", {{"strength", 0}, {"g0", 0}, {"g1", 0}, {"g2", 0}}),
              0.05e-3, 3e-3, 1, 300, up);
  // Exact: f(mu) = EOS(mu, e) - rho0 U_s u_p = 0 with U_s = u_p (1 + mu) / mu, by bisection.
  auto residual = [&](double mu) {
    const double cold = ((K2 * mu + K1) * mu + K) * mu;
    const double us = up * (1 + mu) / mu;
    return cold * (1 - 0.5 * gamma * mu) + gamma * rho0 * 0.5 * up * up - rho0 * us * up;
  };
  double lo = 1e-4, hi = 1.0;
  for (int i = 0; i < 200; ++i)
    (residual(0.5 * (lo + hi)) > 0 ? hi : lo) = 0.5 * (lo + hi);
  const double mu = 0.5 * (lo + hi), us = up * (1 + mu) / mu, p_exact = rho0 * us * up;

  fem::Solver solver(strip.model, {});
  const double t_end = 2.5e-3 / us; // the shock has crossed 2.5 mm of the 3 mm strip
  while (solver.time() < t_end)
    solver.step();
  // Elements between 0.5 mm above the piston and 0.4 mm below the front (initial positions).
  double sum = 0.0;
  int n = 0;
  const auto &el = strip.model.elements;
  for (std::size_t e = 0; e < el.size(); ++e) {
    const std::uint32_t a = el.node[3 * e];
    const double y0 = strip.model.nodes.y0[a];
    if (y0 > 0.5e-3 && y0 < us * solver.time() - 0.4e-3)
      sum += el.pressure[e] + el.viscosity[e], ++n;
  }
  ASSERT_GT(n, 100);
  const double p_mean = sum / n;
  EXPECT_NEAR(p_mean / p_exact, 1.0, 0.005) << "plateau " << p_mean << " Pa, Hugoniot " << p_exact
                                            << " Pa (mu " << mu << ", U_s " << us << " m/s)";
}
