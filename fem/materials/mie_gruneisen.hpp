// Mie-Grueneisen equation of state (thesis Eq. 3.5-3.7):
//   p = (K mu + K1 mu^2 + K2 mu^3)(1 - Gamma mu / 2) + Gamma rho0 e,   mu = rho / rho0 - 1,
// with e the specific internal energy (rho0 e = E / V0 for an element of energy E and initial
// volume V0), and the pressure cut-off p >= -K_c (K_c = 0: no tensile mean stress).
// In tension (mu < 0) only the linear term K mu is used, as is usual for this form.
// Equations: docs/models.md §3.5.
#pragma once

#include <algorithm>

namespace mesopen::fem {

struct MieGruneisen {
  double K, K1, K2, gamma, cutoff;

  // P-bar = K mu + K1 mu^2 + K2 mu^3 (mu >= 0), K mu (mu < 0): the cold part.
  double cold(double mu) const { return mu > 0.0 ? ((K2 * mu + K1) * mu + K) * mu : K * mu; }
  // p(n+1) = a + b E(n+1) at this volume: a = P-bar (1 - Gamma mu / 2), b = Gamma / V0.
  double energyFree(double mu, double cold_p) const { return cold_p * (1.0 - 0.5 * gamma * mu); }
  // Isentropic bulk modulus rho dp/drho, bounded below by K (for the sound speed), plus the
  // thermal part Gamma p.
  double bulkModulus(double mu, double p) const {
    const double m = std::max(mu, 0.0);
    return std::max(K, (1.0 + m) * ((3.0 * K2 * m + 2.0 * K1) * m + K)) + gamma * std::max(p, 0.0);
  }
  // The tangent bulk modulus: bulkModulus, or 0 where the pressure is held at the cut-off p_min,
  // the equation of state's pressure at the new volume and energy, p_eos, being below it: there
  // the pressure does not follow the volume.
  double tangentBulk(double mu, double p, double p_eos, double p_min) const {
    return p_eos < p_min ? 0.0 : bulkModulus(mu, p);
  }
};

} // namespace mesopen::fem
