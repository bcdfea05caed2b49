// Pieces every material shares (thesis Eq. 3.3, 3.8): the objective rotation of the deviatoric
// stress, Hooke's law for its increment, the deviatoric work and the energy equation.
// Plane strain: D_zz = 0, S_zz = -S_xx - S_yy.
// Equations: docs/models.md §3.1, §2.3.
#pragma once

#include <cmath>

namespace mesopen::fem {

// Jaumann rate: S <- R S R^T, R the rotation by phi with tan(phi) = w dt (first order in w dt
// like the Jaumann rate, exactly orthogonal: |S| is kept under any spin). The in-plane deviator
// a = (S_xx - S_yy) / 2, b = S_xy turns by 2 phi; S_xx + S_yy is invariant.
inline void rotateDeviator(double &sxx, double &syy, double &sxy, double w_dt) {
  const double t2 = w_dt * w_dt, inv = 1.0 / (1.0 + t2);
  const double c = (1.0 - t2) * inv, s = 2.0 * w_dt * inv; // cos 2phi, sin 2phi
  const double m = 0.5 * (sxx + syy), a = 0.5 * (sxx - syy), b = sxy;
  const double a1 = a * c - b * s;
  sxy = a * s + b * c;
  sxx = m + a1;
  syy = m - a1;
}

// Hooke's law in rate form for the deviator: S += 2 G (D - tr(D) / 3 I) dt.
inline void addDeviatoricIncrement(double &sxx, double &syy, double &sxy, double two_g_dt,
                                   double dxx, double dyy, double dxy) {
  const double third_tr = (dxx + dyy) * (1.0 / 3.0);
  sxx += two_g_dt * (dxx - third_tr);
  syy += two_g_dt * (dyy - third_tr);
  sxy += two_g_dt * dxy;
}

// |S| = sqrt(S_ij S_ij) over the 3D deviator (S_zz = -S_xx - S_yy).
inline double deviatorNorm(double sxx, double syy, double sxy) {
  const double szz = -sxx - syy;
  return std::sqrt(sxx * sxx + syy * syy + szz * szz + 2.0 * sxy * sxy);
}

// S:D with D_zz = 0 (S is traceless, so S:D = S:D').
inline double stressPower(double sxx, double syy, double sxy, double dxx, double dyy, double dxy) {
  return sxx * dxx + syy * dyy + 2.0 * sxy * dxy;
}

// The energy equation E(n+1) = E(n) + W_dev - (p(n) + p(n+1)) / 2 dV with an equation of state
// linear in the energy at the new volume, p(n+1) = a + b E(n+1), solved exactly; then the
// pressure cut-off p >= p_min (the energy follows the cut pressure).
inline void energyEquation(double a, double b, double p_min, double dV, double w_dev, double &E,
                           double &p) {
  const double p_old = p;
  double e_new = (E + w_dev - 0.5 * (p_old + a) * dV) / (1.0 + 0.5 * b * dV);
  double p_new = a + b * e_new;
  if (p_new < p_min) {
    p_new = p_min;
    e_new = E + w_dev - 0.5 * (p_old + p_new) * dV;
  }
  E = e_new;
  p = p_new;
}

} // namespace mesopen::fem
