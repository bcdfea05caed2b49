// "elastic": a solid with constant moduli and no strength limit: the compressible neo-Hookean
// deviator (hyperelastic.hpp) and the pressure p = -K ln J (thesis Eq. 3.3's bulk law in rate form,
// p' = -K tr(D), integrated exactly), whose stored energy per initial volume is
// U = K (J ln J - J + 1). The internal energy takes the change of A0 (W + U) exactly. No pressure
// cut-off.
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
    for (std::size_t i = 0; i < in.n; ++i) {
      const DeformationGradient F{in.f[0][i], in.f[1][i], in.f[2][i], in.f[3][i]};
      const DeformationGradient F_old{in.f_old[0][i], in.f_old[1][i], in.f_old[2][i],
                                      in.f_old[3][i]};
      const Isochoric now(F), before(F_old);
      neoHookeanDeviator(F, now, G_, s.sxx[i], s.syy[i], s.sxy[i]);
      s.energy[i] += in.volume0[i] * (storedEnergy(now) - storedEnergy(before));
      s.pressure[i] = -K_ * std::log(now.J);
      const double shear = now.shearModulus(G_);
      out.sound_speed[i] = std::sqrt((K_ + 4.0 / 3.0 * shear) * now.J / rho0_); // rho = rho0 / J
      out.shear_share[i] = shear / (K_ + 4.0 / 3.0 * shear);
    }
  }

private:
  // W + U per initial volume.
  double storedEnergy(const Isochoric &iso) const {
    const double J = iso.J;
    return 0.5 * G_ * (iso.trace - 3.0) + K_ * (J * std::log(J) - J + 1.0);
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
