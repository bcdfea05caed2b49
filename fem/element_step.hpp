// The critical step of a constant-strain triangle with lumped masses against its cheap bound
// L_s / c: the element pass takes it for the elements near the shortest step, and with levels for
// those that may set their body's step (docs/models.md, §4.2; docs/solver.md).
#pragma once

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace mesopen::fem {

// x^2 (the element pass takes it too)
inline double square(double x) { return x * x; }

// The largest root y of y^3 - 3y = 2c, c in [-1, 1]: y = 2 cos(acos(c) / 3), in [1, 2] (the
// trigonometric solution of a cubic with three real roots). Without acos and cos, a third of the
// time: y is analytic in s = sqrt((1 + c) / 2), and a polynomial of degree 6 in s is within 9e-7
// of it (least squares, Chebyshev basis); Newton steps from there end above the root (the cubic is
// convex for y > 0) and close on it quadratically. Where two roots nearly meet (c near -1) Newton
// is slow, and the trigonometric form is taken.
// (always inlined and without a branch, so that SIMD lanes can take it: `newton` is false where
// the trigonometric form is needed, and y is then to be replaced)
[[gnu::always_inline]] inline double largestCubicRootByNewton(double c, bool &newton) {
  const double s = std::sqrt(std::max(0.5 * (1.0 + c), 0.0));
  double y =
      1.00000087 +
      s * (1.15465022 +
           s * (-0.22151017 +
                s * (0.102632071 + s * (-0.0523143943 + s * (0.0206477273 + s * -0.00410657997)))));
  // three Newton steps; the root is y after the first step below 1e-9 (what is left is then
  // about step^2 / (y - 1))
  auto newtonStep = [c](double y) { return (y * (y * y - 3.0) - 2.0 * c) / (3.0 * (y * y - 1.0)); };
  const double step0 = newtonStep(y), y1 = y - step0;
  const double step1 = newtonStep(y1), y2 = y1 - step1;
  const double step2 = newtonStep(y2), y3 = y2 - step2;
  newton = std::min(std::min(std::abs(step0), std::abs(step1)), std::abs(step2)) < 1e-9;
  return std::abs(step0) < 1e-9 ? y1 : std::abs(step1) < 1e-9 ? y2 : y3;
}

inline double largestCubicRoot(double c) {
  bool newton = false;
  const double y = largestCubicRootByNewton(c, newton);
  return newton ? y : 2.0 * std::cos(std::acos(c) / 3.0);
}

// The largest eigenvalue of S Dhat(g) for a constant-strain triangle: S = B B^T from the shape
// function gradients (gx, gy over 2A, engineering shear), Dhat(g) = C / M the plane-strain
// elasticity over the longitudinal modulus M = K + 4G/3, g = G / M in [0, 3/4]:
//   S = [P 0 R; 0 Q R; R R P+Q],  Dhat = [1 1-2g 0; 1-2g 1 0; 0 0 g] = L L^T,
//   L = [1 0 0; 1-2g s 0; 0 0 sqrt g],  s = 2 sqrt(g (1 - g)),
// S Dhat is similar to the symmetric T = L^T S L, whose eigenvalues are q + p y with y the roots of
// y^3 - 3y = 2 det (the trigonometric solution of the cubic; p = 0 when T = q I). g = 0 is the
// rank-one limit u u^T, u = (1, 1, 0): P + Q. (inlined without a branch, as above)
struct ShapeCubic {
  double q, p, det;
};
[[gnu::always_inline]] inline ShapeCubic shapeCubic(double P, double Q, double R, double g) {
  const double d = 1.0 - 2.0 * g, s = 2.0 * std::sqrt(g * (1.0 - g)), r = std::sqrt(g);
  const double t00 = P + d * d * Q, t01 = s * d * Q, t02 = r * (1.0 + d) * R;
  const double t11 = s * s * Q, t12 = s * r * R, t22 = g * (P + Q);
  const double off = t01 * t01 + t02 * t02 + t12 * t12, q = (t00 + t11 + t22) / 3.0;
  const double p2 = square(t00 - q) + square(t11 - q) + square(t22 - q) + 2.0 * off;
  // (p2 >= 0, a sum of squares; where p = 0 every b is 0)
  const double p = std::sqrt(std::max(p2, 0.0) / 6.0), over = std::max(p, DBL_MIN);
  const double b00 = (t00 - q) / over, b11 = (t11 - q) / over, b22 = (t22 - q) / over,
               b01 = t01 / over, b02 = t02 / over, b12 = t12 / over;
  const double det = 0.5 * (b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) +
                            b02 * (b01 * b12 - b11 * b02));
  return {q, p, std::min(std::max(det, -1.0), 1.0)};
}

inline double shapeStiffness(double P, double Q, double R, double g) {
  const ShapeCubic t = shapeCubic(P, Q, R, g);
  return std::max(t.q + t.p * largestCubicRoot(t.det), g == 0.0 ? P + Q : 0.0);
}

// How much longer than L_s / c the critical step 2 / omega_max of a constant-strain triangle with
// lumped masses is (Flanagan & Belytschko 1981 bound the element's highest frequency; this is its
// exact value): omega_max^2 = 3 c^2 lambda_max(S Dhat(g)), c^2 = M / rho. For the element's own
// shear share g; when that is not known (outside [0, 3/4]), for the worst material: lambda_max is
// convex in g (T is affine in g after a change of basis), so the larger of its values at g = 0 and
// g = 3/4 bounds it. About 1.34 for an equilateral quartz triangle (1.19 steel, 1 at g = 0) and up
// to sqrt(2) for slivers, the elements that set the step.
// (always inlined: the element pass calls it at two places and criticalStepGains for its fallback,
// and its arithmetic is the same at each)
[[gnu::always_inline]] inline double criticalStepGain(const double gx[3], const double gy[3],
                                                      double area, double ls, double g) {
  const double inv = 1.0 / (2.0 * area);
  double P = 0.0, Q = 0.0, R = 0.0;
  for (int k = 0; k < 3; ++k)
    P += square(gx[k] * inv), Q += square(gy[k] * inv), R += gx[k] * gy[k] * inv * inv;
  const double largest =
      g >= 0.0 && g <= 0.75 ? shapeStiffness(P, Q, R, g)
                            : std::max(shapeStiffness(P, Q, R, 0.0), shapeStiffness(P, Q, R, 0.75));
  return (2.0 / ls) / std::sqrt(3.0 * largest);
}

// criticalStepGain for the elements pick[0 .. n) of a batch (the element pass's gx, gy, area,
// shortest altitude len and shear share g), into gain[0 .. n): in SIMD lanes, the elements whose
// shear share is not known or whose root needs the trigonometric form again one at a time.
template <std::size_t N>
inline void criticalStepGains(const std::uint32_t *pick, std::size_t n, const double (&gx)[3][N],
                              const double (&gy)[3][N], const double *area, const double *len,
                              const double *g, double *gain) {
  alignas(64) double P[N], Q[N], R[N], share[N], ls[N];
  for (std::size_t j = 0; j < n; ++j) { // S = B B^T of the picked elements, side by side
    const std::uint32_t i = pick[j];
    const double inv = 1.0 / (2.0 * area[i]);
    P[j] = Q[j] = R[j] = 0.0;
    for (int k = 0; k < 3; ++k)
      P[j] += square(gx[k][i] * inv), Q[j] += square(gy[k][i] * inv),
          R[j] += gx[k][i] * gy[k][i] * inv * inv;
    share[j] = g[i], ls[j] = (2.0 / 3.0) * len[i];
  }
  alignas(64) double again[N]; // 1 where the gain is taken again
#pragma omp simd
  for (std::size_t j = 0; j < n; ++j) {
    const bool known = (share[j] >= 0.0) & (share[j] <= 0.75);
    const double gj = known ? share[j] : 0.0;
    const ShapeCubic t = shapeCubic(P[j], Q[j], R[j], gj);
    bool newton = false;
    const double y = largestCubicRootByNewton(t.det, newton);
    const double largest = std::max(t.q + t.p * y, gj == 0.0 ? P[j] + Q[j] : 0.0);
    gain[j] = (2.0 / ls[j]) / std::sqrt(3.0 * largest);
    again[j] = known && newton ? 0.0 : 1.0;
  }
  for (std::size_t j = 0; j < n; ++j)
    if (again[j] != 0.0) {
      const std::uint32_t i = pick[j];
      const double g_x[3] = {gx[0][i], gx[1][i], gx[2][i]}, g_y[3] = {gy[0][i], gy[1][i], gy[2][i]};
      gain[j] = criticalStepGain(g_x, g_y, area[i], ls[j], g[i]);
    }
}

} // namespace mesopen::fem
