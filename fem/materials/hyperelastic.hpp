// The deviator of the purely elastic materials ("elastic", "quartz" without strength, "von-mises"
// without plasticity), in total form: a compressible neo-Hookean solid (e.g. Bonet & Wood,
// Nonlinear Continuum Mechanics for FE Analysis, 2008, section 6.4.3), in plane strain (F_zz = 1),
// with the stored energy per initial volume
//   W = G(J) / 2 (tr b* - 3),   b* = J^(-2/3) F F^T,   J = det F,
// and the Cauchy stress it derives, sigma = (1/J) dW/dF F^T:
//   S = G(J) / J dev(b*),   and with a shear modulus that follows the volume, the mean stress
//   G'(J) / 2 (tr b* - 3), a pressure p_G = -G'(J) / 2 (tr b* - 3).
// For small strains S = 2 G dev(eps), Hooke's law. A stress that derives from a stored energy makes
// the element's nodal forces the gradient of A0 W: the leapfrog then keeps the energy bounded,
// while the rate form dS = 2 G dev(D) dt, integrated along the path, creates energy when the
// elements ring near their stable step or when G changes along a closed path (tests/verification/
// energy.cpp). Materials with strength keep the rate form, where yield bounds the deviator.
// Equations: docs/models.md §3.6.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace mesopen::fem {

// F = dx/dX (xx, xy, yx, yy; F_zz = 1) enters as four scalars: a batch loop over elements then
// vectorizes (a struct local in an `omp simd` loop does not).
inline double determinant(double fxx, double fxy, double fyx, double fyy) {
  return fxx * fyy - fxy * fyx;
}

// r = J^(-1/3), the factor that makes F isochoric (det(r F) = 1 with F_zz = 1), for a batch,
// without a library call so that the loop vectorizes: Newton's iteration on r^-3 = J,
//   r <- r (4 - J r^3) / 3,
// from r = 1 - d / 3 + 2 d^2 / 9 (the series of (1 + d)^(-1/3), d = J - 1); five iterations reach
// rounding (relative error below 1e-15) for 0.35 <= J <= 2; elements outside take std::cbrt.
inline void inverseCubeRoots(const double *J, double *r, std::size_t n) {
  constexpr double J_low = 0.35, J_high = 2.0;
  double lowest = J_low, highest = J_high;
#pragma omp simd reduction(min : lowest) reduction(max : highest)
  for (std::size_t i = 0; i < n; ++i) {
    const double j = J[i], d = j - 1.0;
    double x = 1.0 + d * (2.0 / 9.0 * d - 1.0 / 3.0);
    for (int k = 0; k < 5; ++k)
      x *= (4.0 - j * x * x * x) * (1.0 / 3.0);
    r[i] = x;
    lowest = std::min(lowest, j), highest = std::max(highest, j);
  }
  if (!(lowest >= J_low && highest <= J_high))
    for (std::size_t i = 0; i < n; ++i)
      if (!(J[i] >= J_low && J[i] <= J_high))
        r[i] = 1.0 / std::cbrt(J[i]);
}

// tr b* = J^(-2/3) (F_xx^2 + F_xy^2 + F_yx^2 + F_yy^2 + 1), with r = J^(-1/3) (inverseCubeRoots).
inline double isochoricTrace(double fxx, double fxy, double fyx, double fyy, double r) {
  return (fxx * fxx + fxy * fxy + fyx * fyx + fyy * fyy + 1.0) * (r * r);
}

// The incremental shear modulus about the state: G tr(b*) / (3 J) (G / J under volume change).
inline double incrementalShearModulus(double G, double trace, double J) {
  return G * trace / (3.0 * J);
}

// S = G / J dev(b*) (S_zz = -S_xx - S_yy), with r = J^(-1/3).
inline void neoHookeanDeviator(double fxx, double fxy, double fyx, double fyy, double J, double r,
                               double G, double &sxx, double &syy, double &sxy) {
  const double f = G * (r * r) / J;
  const double bxx = fxx * fxx + fxy * fxy, byy = fyx * fyx + fyy * fyy;
  const double third = (bxx + byy + 1.0) / 3.0;
  sxx = f * (bxx - third);
  syy = f * (byy - third);
  sxy = f * (fxx * fyx + fxy * fyy);
}

} // namespace mesopen::fem
