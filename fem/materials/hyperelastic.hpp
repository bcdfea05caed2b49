// The deviator of the purely elastic materials ("elastic", "quartz" without strength), in total
// form: a compressible neo-Hookean solid (e.g. Bonet & Wood, Nonlinear Continuum Mechanics for FE
// Analysis, 2008, section 6.4.3), in plane strain (F_zz = 1), with the stored energy per initial
// volume
//   W = G(J) / 2 (tr b* - 3),   b* = J^(-2/3) F F^T,   J = det F,
// and the Cauchy stress it derives, sigma = (1/J) dW/dF F^T:
//   S = G(J) / J dev(b*),   and with a shear modulus that follows the volume, the mean stress
//   G'(J) / 2 (tr b* - 3), a pressure p_G = -G'(J) / 2 (tr b* - 3).
// For small strains S = 2 G dev(eps), Hooke's law. A stress that derives from a stored energy makes
// the element's nodal forces the gradient of A0 W: the leapfrog then keeps the energy bounded,
// while the rate form dS = 2 G dev(D) dt, integrated along the path, creates energy when the
// elements ring near their stable step or when G changes along a closed path (tests/verification/
// energy.cpp). Materials with strength keep the rate form, where yield bounds the deviator, and so
// does "von-mises" without plasticity (steel-elastic): its vectorized rate form costs a third of
// the total form's in run 6, where the projectile is a third of the element work, and the
// artificial viscosity damps the modes it would pump.
#pragma once

#include <cmath>

namespace mesopen::fem {

struct DeformationGradient {
  double xx, xy, yx, yy; // F = dx/dX (F_zz = 1)
  double det() const { return xx * yy - xy * yx; }
};

// What the stress and the energy need of F: J, J^(-2/3) (by one cube root, the costly part) and
// tr b* = J^(-2/3) (F_xx^2 + F_xy^2 + F_yx^2 + F_yy^2 + 1).
struct Isochoric {
  double J, j23, trace;
  explicit Isochoric(const DeformationGradient &F) : J(F.det()) {
    const double c = std::cbrt(J);
    j23 = 1.0 / (c * c);
    trace = (F.xx * F.xx + F.xy * F.xy + F.yx * F.yx + F.yy * F.yy + 1.0) * j23;
  }
  // The incremental shear modulus about the state: G tr(b*) / (3 J) (G / J under volume change).
  double shearModulus(double G) const { return G * trace / (3.0 * J); }
};

// S = G / J dev(b*) (S_zz = -S_xx - S_yy).
inline void neoHookeanDeviator(const DeformationGradient &F, const Isochoric &iso, double G,
                               double &sxx, double &syy, double &sxy) {
  const double f = G * iso.j23 / iso.J;
  const double bxx = F.xx * F.xx + F.xy * F.xy, byy = F.yx * F.yx + F.yy * F.yy;
  const double third = (bxx + byy + 1.0) / 3.0;
  sxx = f * (bxx - third);
  syy = f * (byy - third);
  sxy = f * (F.xx * F.yx + F.xy * F.yy);
}

} // namespace mesopen::fem
