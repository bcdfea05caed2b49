// "von-mises": Mie-Grueneisen pressure, Jaumann-rate hypoelastic deviator with constant G, and
// von Mises plasticity with linear hardening Y = Y0 + M eps_p (thesis Table 3.2), by radial
// return (Simo & Hughes 1998, Box 3.2): with the trial deviator S*,
//   f = |S*| - sqrt(2/3) Y,  dgamma = f / (2G + 2M/3),  S = S* (1 - 2G dgamma / |S*|),
//   eps_p += sqrt(2/3) dgamma.
// `plastic = false` turns the strength off: the elastic projectile of the thesis; no yield code runs.
#include "../material.hpp"
#include "hypoelastic.hpp"
#include "mie_gruneisen.hpp"

#include <cmath>

namespace mesopen::fem {

namespace {

class VonMises final : public Material {
public:
  explicit VonMises(const Parameters &p)
      : rho0_(p.at("density")), G_(p.at("shear_modulus")),
        eos_{p.at("bulk_modulus"), p.at("k1"), p.at("k2"), p.at("gruneisen"), p.at("pressure_cutoff")},
        Y0_(p.at("yield_stress")), M_(p.at("hardening_modulus")), plastic_(p.at("plastic") != 0.0) {}
  double density() const override { return rho0_; }
  bool plastic() const override { return plastic_; }

  void update(const StrainBatch &in, StressState &s, MaterialOutput &out) const override {
    if (plastic_)
      run<true>(in, s, out);
    else
      run<false>(in, s, out);
  }

private:
  template <bool Plastic> void run(const StrainBatch &in, StressState &s, MaterialOutput &out) const {
    const double dt = in.dt, two_g_dt = 2.0 * G_ * dt, sqrt23 = std::sqrt(2.0 / 3.0);
    const double p_min = -eos_.cutoff;
    // Local array pointers: contiguous vector loads and stores (no per-lane gathers).
    const double *dxx = in.dxx, *dyy = in.dyy, *dxy = in.dxy, *spin = in.spin, *jac = in.jacobian;
    const double *dvol = in.volume_change, *vmid = in.volume_mid, *vol0 = in.volume0;
    double *sxx_ = s.sxx, *syy_ = s.syy, *sxy_ = s.sxy, *pressure = s.pressure, *energy = s.energy;
    double *eps = s.plastic_strain, *cs = out.sound_speed, *shear_share = out.shear_share;
    double plastic_work = 0.0;
#pragma omp simd reduction(+ : plastic_work)
    for (std::size_t i = 0; i < in.n; ++i) {
      const double mu = 1.0 / jac[i] - 1.0;
      // Deviator: rotate, add the elastic trial increment, return to the yield surface.
      double sxx = sxx_[i], syy = syy_[i], sxy = sxy_[i];
      rotateDeviator(sxx, syy, sxy, spin[i] * dt);
      const double power_old = stressPower(sxx, syy, sxy, dxx[i], dyy[i], dxy[i]);
      addDeviatoricIncrement(sxx, syy, sxy, two_g_dt, dxx[i], dyy[i], dxy[i]);
      if constexpr (Plastic) {
        const double norm = deviatorNorm(sxx, syy, sxy);
        const double f = norm - sqrt23 * (Y0_ + M_ * eps[i]);
        if (f > 0.0) {
          const double dgamma = f / (2.0 * G_ + 2.0 / 3.0 * M_);
          const double scale = 1.0 - 2.0 * G_ * dgamma / norm;
          sxx *= scale, syy *= scale, sxy *= scale;
          eps[i] += sqrt23 * dgamma;
          plastic_work += vmid[i] * dgamma * scale * norm; // V S : (S* - S) / 2G
        }
      }
      const double power_new = stressPower(sxx, syy, sxy, dxx[i], dyy[i], dxy[i]);
      sxx_[i] = sxx, syy_[i] = syy, sxy_[i] = sxy;
      // Pressure and energy together (the pressure depends on the new energy).
      const double w_dev = 0.5 * (power_old + power_new) * vmid[i] * dt;
      energyEquation(eos_.energyFree(mu, eos_.cold(mu)), eos_.gamma / vol0[i], p_min, dvol[i], w_dev,
                     energy[i], pressure[i]);
      const double bulk = eos_.bulkModulus(mu, pressure[i]);
      cs[i] = std::sqrt((bulk + 4.0 / 3.0 * G_) * jac[i] / rho0_);
      shear_share[i] = G_ / (bulk + 4.0 / 3.0 * G_);
    }
    out.plastic_work = plastic_work;
  }

  double rho0_, G_;
  MieGruneisen eos_;
  double Y0_, M_;
  bool plastic_;
};

} // namespace

MaterialType vonMisesMaterialType() {
  return {"von-mises",
          "Mie-Grueneisen pressure, hypoelastic deviator, von Mises plasticity with linear "
          "hardening (radial return); defaults: the steel of thesis Table 3.2",
          {{"density", "kg/m^3", "initial density rho0", 1.0, 1e5, 7823.0},
           {"shear_modulus", "Pa", "shear modulus G", 0.0, 1e13, 77.5e9},
           {"bulk_modulus", "Pa", "Mie-Grueneisen K", 1.0, 1e13, 163.9e9},
           {"k1", "Pa", "Mie-Grueneisen K1 (mu^2 term)", 0.0, 1e14, 294.3e9},
           {"k2", "Pa", "Mie-Grueneisen K2 (mu^3 term)", 0.0, 1e15, 500e9},
           {"gruneisen", "", "Grueneisen Gamma", 0.0, 10.0, 1.16},
           {"pressure_cutoff", "Pa", "K_c: the pressure stays >= -K_c", 0.0, 1e12, 0.0},
           {"yield_stress", "Pa", "initial yield stress Y0", 0.0, 1e12, 1.16e9},
           {"hardening_modulus", "Pa", "linear hardening M in Y = Y0 + M eps_p", 0.0, 1e13, 0.12e9},
           {"plastic", "", "plastic flow on; false: elastic, no strength limit", 0.0, 1.0, 1.0, true},
           {"erosion_strain", "", "equivalent plastic strain at which an element is removed (eroded; also when crushed to a fifth of its area); 0: never",
            0.0, 1e3, 0.0}},
          [](const Parameters &p) -> std::unique_ptr<Material> { return std::make_unique<VonMises>(p); }};
}

} // namespace mesopen::fem
