// "elastic": hypoelastic solid with constant moduli (thesis Eq. 3.3, 3.8): Jaumann rate of the
// deviator, S' = 2 G D', and the bulk law in rate form, p' = -K tr(D), integrated exactly as
// p = -K ln J. No strength limit, no pressure cut-off.
#include "../material.hpp"
#include "hypoelastic.hpp"

#include <cmath>

namespace mesopen::fem {

namespace {

class Elastic final : public Material {
public:
  explicit Elastic(const Parameters &p)
      : rho0_(p.at("density")), K_(p.at("bulk_modulus")), G_(p.at("shear_modulus")) {}
  double density() const override { return rho0_; }
  bool plastic() const override { return false; }

  void update(const StrainBatch &in, StressState &s, MaterialOutput &out) const override {
    const double dt = in.dt, two_g_dt = 2.0 * G_ * dt, c2 = (K_ + 4.0 / 3.0 * G_) / rho0_;
    const double shear_share = G_ / (K_ + 4.0 / 3.0 * G_);
#pragma omp simd
    for (std::size_t i = 0; i < in.n; ++i) {
      double sxx = s.sxx[i], syy = s.syy[i], sxy = s.sxy[i];
      rotateDeviator(sxx, syy, sxy, in.spin[i] * dt);
      const double power_old = stressPower(sxx, syy, sxy, in.dxx[i], in.dyy[i], in.dxy[i]);
      addDeviatoricIncrement(sxx, syy, sxy, two_g_dt, in.dxx[i], in.dyy[i], in.dxy[i]);
      const double power_new = stressPower(sxx, syy, sxy, in.dxx[i], in.dyy[i], in.dxy[i]);
      s.sxx[i] = sxx, s.syy[i] = syy, s.sxy[i] = sxy;
      const double w_dev = 0.5 * (power_old + power_new) * in.volume_mid[i] * dt;
      energyEquation(-K_ * std::log(in.jacobian[i]), 0.0, -HUGE_VAL, in.volume_change[i], w_dev,
                     s.energy[i], s.pressure[i]);
      out.sound_speed[i] = std::sqrt(c2 * in.jacobian[i]); // rho = rho0 / J
      out.shear_share[i] = shear_share;
    }
  }

private:
  double rho0_, K_, G_;
};

} // namespace

MaterialType elasticMaterialType() {
  return {"elastic",
          "hypoelastic solid: Jaumann rate of the deviator, p = -K ln J; no strength limit",
          {{"density", "kg/m^3", "initial density rho0", 1.0, 1e5, 7823.0},
           {"bulk_modulus", "Pa", "bulk modulus K", 1.0, 1e13, 163.9e9},
           {"shear_modulus", "Pa", "shear modulus G", 0.0, 1e13, 77.5e9}},
          [](const Parameters &p) -> std::unique_ptr<Material> { return std::make_unique<Elastic>(p); }};
}

} // namespace mesopen::fem
