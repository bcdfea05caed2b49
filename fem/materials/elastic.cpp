// "elastic": a solid with constant moduli and no strength limit: the compressible neo-Hookean
// deviator (hyperelastic.hpp) and the pressure p = -K ln J (thesis Eq. 3.3's bulk law in rate form,
// p' = -K tr(D), integrated exactly), whose stored energy per initial volume is
// U = K (J ln J - J + 1). The internal energy takes the change of A0 (W + U) exactly. No pressure
// cut-off.
// Equations: docs/models.md §3.4.
#include "../material.hpp"
#include "hyperelastic.hpp"

#include <cmath>

namespace mesopen::fem {

namespace {

class Elastic final : public Material {
public:
  explicit Elastic(const Parameters &p)
      : rho0_(p.at("density")), K_(p.at("bulk_modulus")), G_(p.at("shear_modulus")) {}
  double density() const override { return rho0_; }
  bool plastic() const override { return false; }
  bool usesDeformationGradient() const override { return true; }

  void update(const StrainBatch &in, StressState &s, MaterialOutput &out) const override {
    const double *f0 = in.f[0], *f1 = in.f[1], *f2 = in.f[2], *f3 = in.f[3];
    const double *g0 = in.f_old[0], *g1 = in.f_old[1], *g2 = in.f_old[2], *g3 = in.f_old[3];
    const double *r = in.inverse_cube_root_j, *r_old = in.inverse_cube_root_j_old;
    for (std::size_t i = 0; i < in.n; ++i) {
      const double J = determinant(f0[i], f1[i], f2[i], f3[i]);
      const double J_old = determinant(g0[i], g1[i], g2[i], g3[i]);
      const double trace = isochoricTrace(f0[i], f1[i], f2[i], f3[i], r[i]);
      const double trace_old = isochoricTrace(g0[i], g1[i], g2[i], g3[i], r_old[i]);
      neoHookeanDeviator(f0[i], f1[i], f2[i], f3[i], J, r[i], G_, s.sxx[i], s.syy[i], s.sxy[i]);
      s.energy[i] += in.volume0[i] * (storedEnergy(J, trace) - storedEnergy(J_old, trace_old));
      s.pressure[i] = -K_ * std::log(J);
      const double shear = incrementalShearModulus(G_, trace, J);
      out.sound_speed[i] = std::sqrt((K_ + 4.0 / 3.0 * shear) * J / rho0_); // rho = rho0 / J
      out.shear_share[i] = shear / (K_ + 4.0 / 3.0 * shear);
    }
  }

private:
  // W + U per initial volume.
  double storedEnergy(double J, double trace) const {
    return 0.5 * G_ * (trace - 3.0) + K_ * (J * std::log(J) - J + 1.0);
  }

  double rho0_, K_, G_;
};

} // namespace

MaterialType elasticMaterialType() {
  return {"elastic",
          "elastic solid: neo-Hookean deviator, p = -K ln J; no strength limit",
          {{"density", "kg/m^3", "initial density rho0", 1.0, 1e5, 7823.0},
           {"bulk_modulus", "Pa", "bulk modulus K", 1.0, 1e13, 163.9e9},
           {"shear_modulus", "Pa", "shear modulus G", 0.0, 1e13, 77.5e9}},
          [](const Parameters &p) -> std::unique_ptr<Material> {
            return std::make_unique<Elastic>(p);
          }};
}

} // namespace mesopen::fem
