// Material-point tests of the strength models against closed-form answers: radial return with
// linear hardening in uniaxial strain, and the quartz overstress relaxation.
#include "material.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace mesopen;

namespace {

// One element driven through a prescribed rate of deformation: J follows tr(D) exactly.
struct MaterialPoint {
  std::unique_ptr<fem::Material> material;
  double sxx = 0, syy = 0, sxy = 0, p = 0, energy = 0, eps_p = 0, c = 0, g = 0, J = 1, V0 = 1e-10;
  double plastic_work = 0;

  explicit MaterialPoint(std::unique_ptr<fem::Material> m) : material(std::move(m)) {}
  void step(double dxx, double dyy, double dxy, double dt) {
    const double J_new = J * std::exp((dxx + dyy) * dt);
    const double dv = V0 * (J_new - J), vmid = 0.5 * V0 * (J + J_new), spin = 0.0;
    const fem::StrainBatch in{1, dt, &dxx, &dyy, &dxy, &spin, &J_new, &dv, &vmid, &V0};
    fem::StressState s{&sxx, &syy, &sxy, &p, &energy, &eps_p};
    fem::MaterialOutput out{&c, &g};
    material->update(in, s, out);
    plastic_work += out.plastic_work;
    J = J_new;
  }
};

} // namespace

// Uniaxial strain (D = diag(0, eps_rate, 0)) with von Mises and linear hardening. The deviatoric
// strain is proportional to n = (-1, 2, -1) / sqrt(6) with magnitude e = sqrt(2/3) |eps|; then
//   |S| = 2 G e                                  (elastic, 2 G e <= sqrt(2/3) Y0),
//   |S| = sqrt(2/3) (Y0 + M sqrt(2/3) e_p),  e_p = (2 G e - sqrt(2/3) Y0) / (2 G + 2 M / 3),
// and sigma_yy = -p + S_yy with p = K (1/J - 1) (Gamma = K1 = K2 = 0). Radial return with linear
// hardening is exact for proportional loading at any step size, so the tolerance is round-off:
// 1e-9 of the stress.
TEST(RadialReturn, UniaxialStrainCurve) {
  const double K = 160e9, G = 80e9, Y0 = 1.2e9, M = 5e9;
  MaterialPoint point(fem::makeMaterial("von-mises", {{"bulk_modulus", K},
                                                      {"shear_modulus", G},
                                                      {"k1", 0},
                                                      {"k2", 0},
                                                      {"gruneisen", 0},
                                                      {"yield_stress", Y0},
                                                      {"hardening_modulus", M},
                                                      {"pressure_cutoff", 1e12}}));
  const double rate = -1e5, dt = 2e-9; // compression, 2e-4 strain per step
  double eps = 0.0, max_plastic = 0.0;
  for (int n = 1; n <= 250; ++n) {
    point.step(0.0, rate, 0.0, dt);
    eps += rate * dt;
    const double e = std::sqrt(2.0 / 3.0) * std::abs(eps);
    const double ep = std::max(0.0, (2 * G * e - std::sqrt(2.0 / 3.0) * Y0) / (2 * G + 2 * M / 3));
    const double norm = 2 * G * (e - ep);
    const double s_yy = -norm * 2 / std::sqrt(6.0); // compression: S_yy < 0
    const double sigma_exact = -K * (1 / point.J - 1) + s_yy;
    const double sigma = point.syy - point.p;
    ASSERT_NEAR(sigma, sigma_exact, 1e-9 * std::abs(sigma_exact)) << "step " << n;
    ASSERT_NEAR(point.sxx, -0.5 * point.syy, 1e-9 * std::abs(s_yy)); // S_xx = S_zz = -S_yy / 2
    ASSERT_NEAR(point.eps_p, std::sqrt(2.0 / 3.0) * ep, 1e-12);
    max_plastic = point.eps_p;
  }
  EXPECT_GT(max_plastic, 0.01); // well into the plastic range (yield at ~0.7 % strain)
  EXPECT_GT(point.plastic_work, 0.0);
}

// Overstress relaxation (thesis Eq. 3.12): after a jump above the equilibrium surface, held at
// constant strain, the excess |S| - |Se| decays as (1 - dt/T_R)^n, the explicit form of
// exp(-t/T_R). With dt = T_R / 100 the two differ by less than 0.2 % of the initial excess after
// one T_R; tolerance 0.5 %.
TEST(Overstress, RelaxesToTheEquilibriumSurface) {
  const double T = 3.5e-9, dt = T / 100, B = 2.353e9;
  MaterialPoint point(fem::makeMaterial("quartz", {{"gruneisen", 0}}));
  const double se = std::sqrt(2.0 / 3.0) * B; // p = 0 in pure shear: Y = B
  point.step(0.0, 0.0, 0.05 / dt, dt);        // a shear strain jump of 0.05: trial |S| ~ 9 GPa
  const double trial = 2.0 * 46.92e9 * 0.05 * std::sqrt(2.0);
  ASSERT_NEAR(point.p, 0.0, 1.0);
  for (int n = 1; n <= 300; ++n) {
    const double norm = std::sqrt(2 * point.sxx * point.sxx + 2 * point.sxy * point.sxy);
    const double excess = (norm - se) / (trial - se);
    ASSERT_NEAR(excess, std::exp(-n * dt / T), 0.005) << "step " << n;
    point.step(0.0, 0.0, 0.0, dt);
  }
}

// The equilibrium yield is bilinear, Y(p) = min(B + M p, Y1): held long enough under a pressure
// where B + M p > Y1, the deviator relaxes onto sqrt(2/3) Y1 (to round-off).
TEST(Overstress, EquilibriumYieldIsCapped) {
  const double Y1 = 4.4e9, T = 3.5e-9;
  MaterialPoint point(fem::makeMaterial("quartz", {{"gruneisen", 0}}));
  point.step(0.0, -0.15 / T, 0.0, T); // 15 % confined compression: p ~ 9 GPa, B + M p > Y1
  ASSERT_GT(2.353e9 + 0.667 * point.p, Y1);
  for (int n = 0; n < 200; ++n)
    point.step(0.0, 0.0, 0.0, T / 4);
  const double szz = -point.sxx - point.syy;
  const double norm = std::sqrt(point.sxx * point.sxx + point.syy * point.syy + szz * szz);
  EXPECT_NEAR(norm, std::sqrt(2.0 / 3.0) * Y1, 1e-6 * Y1);
}
