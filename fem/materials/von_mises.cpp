// "von-mises": Mie-Grueneisen pressure, Jaumann-rate hypoelastic deviator with constant G, and
// von Mises plasticity with linear hardening Y = Y0 + M eps_p (thesis Table 3.2), by radial
// return (Simo & Hughes 1998, Box 3.2): with the trial deviator S*,
//   f = |S*| - sqrt(2/3) Y,  dgamma = f / (2G + 2M/3),  S = S* (1 - 2G dgamma / |S*|),
//   eps_p += sqrt(2/3) dgamma.
// `plastic = false` turns the strength off: the elastic projectile of the thesis, whose deviator is
// then the neo-Hookean one of hyperelastic.hpp with the same G (a total form: the energy it stores
// comes back whole, which the rate form does not guarantee without viscosity).
// Equations: docs/models.md §3.2.
#include "../material.hpp"
#include "hyperelastic.hpp"
#include "hypoelastic.hpp"
#include "mie_gruneisen.hpp"

#include <cmath>

namespace mesopen::fem {

namespace {

class VonMises final : public Material {
public:
  explicit VonMises(const Parameters &p)
      : rho0_(p.at("density")),
        G_(p.at("shear_modulus")), eos_{p.at("bulk_modulus"), p.at("k1"), p.at("k2"),
                                        p.at("gruneisen"), p.at("pressure_cutoff")},
        Y0_(p.at("yield_stress")), M_(p.at("hardening_modulus")), plastic_(p.at("plastic") != 0.0) {
  }
  double density() const override { return rho0_; }
  bool plastic() const override { return plastic_; }
  bool usesDeformationGradient() const override { return !plastic_; }

  void update(const StrainBatch &in, StressState &s, MaterialOutput &out) const override {
    if (plastic_)
      plasticUpdate(in, s, out);
    else
      elasticUpdate(in, s, out);
  }

private:
  // Without plasticity: S from F, W = G / 2 (tr b* - 3) per initial volume; the element's energy
  // takes W's change, and the thermal term Gamma rho0 e of the pressure sees E - A0 W.
  void elasticUpdate(const StrainBatch &in, StressState &s, MaterialOutput &out) const {
    const double p_min = -eos_.cutoff;
    const double *f0 = in.f[0], *f1 = in.f[1], *f2 = in.f[2], *f3 = in.f[3];
    const double *g0 = in.f_old[0], *g1 = in.f_old[1], *g2 = in.f_old[2], *g3 = in.f_old[3];
    const double *r = in.inverse_cube_root_j, *r_old = in.inverse_cube_root_j_old;
    const double *jac = in.jacobian, *dvol = in.volume_change, *vol0 = in.volume0;
    double *sxx = s.sxx, *syy = s.syy, *sxy = s.sxy, *pressure = s.pressure, *energy = s.energy;
    double *cs = out.sound_speed, *shear_share = out.shear_share;
#pragma omp simd
    for (std::size_t i = 0; i < in.n; ++i) {
      const double J = determinant(f0[i], f1[i], f2[i], f3[i]);
      const double trace = isochoricTrace(f0[i], f1[i], f2[i], f3[i], r[i]);
      const double trace_old = isochoricTrace(g0[i], g1[i], g2[i], g3[i], r_old[i]);
      neoHookeanDeviator(f0[i], f1[i], f2[i], f3[i], J, r[i], G_, sxx[i], syy[i], sxy[i]);
      const double W = 0.5 * G_ * (trace - 3.0), W_old = 0.5 * G_ * (trace_old - 3.0);
      const double mu = 1.0 / jac[i] - 1.0, b = eos_.gamma / vol0[i];
      const double a = eos_.energyFree(mu, eos_.cold(mu)) - b * vol0[i] * W;
      energyEquation(a, b, p_min, dvol[i], vol0[i] * (W - W_old), energy[i], pressure[i]);
      const double bulk = eos_.bulkModulus(mu, pressure[i]);
      const double G = incrementalShearModulus(G_, trace, J);
      cs[i] = std::sqrt((bulk + 4.0 / 3.0 * G) * jac[i] / rho0_);
      shear_share[i] = G / (bulk + 4.0 / 3.0 * G);
    }
    out.plastic_work = 0.0;
  }

  void plasticUpdate(const StrainBatch &in, StressState &s, MaterialOutput &out) const {
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
      const double norm = deviatorNorm(sxx, syy, sxy);
      const double f = norm - sqrt23 * (Y0_ + M_ * eps[i]);
      if (f > 0.0) {
        const double dgamma = f / (2.0 * G_ + 2.0 / 3.0 * M_);
        const double scale = 1.0 - 2.0 * G_ * dgamma / norm;
        sxx *= scale, syy *= scale, sxy *= scale;
        eps[i] += sqrt23 * dgamma;
        plastic_work += vmid[i] * dgamma * scale * norm; // V S : (S* - S) / 2G
      }
      const double power_new = stressPower(sxx, syy, sxy, dxx[i], dyy[i], dxy[i]);
      sxx_[i] = sxx, syy_[i] = syy, sxy_[i] = sxy;
      // Pressure and energy together (the pressure depends on the new energy).
      const double w_dev = 0.5 * (power_old + power_new) * vmid[i] * dt;
      energyEquation(eos_.energyFree(mu, eos_.cold(mu)), eos_.gamma / vol0[i], p_min, dvol[i],
                     w_dev, energy[i], pressure[i]);
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
  return {
      "von-mises",
      "Mie-Grueneisen pressure, hypoelastic deviator (neo-Hookean without plasticity), von Mises "
      "plasticity with linear hardening (radial return); defaults: the steel of thesis Table 3.2",
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
       {"erosion_strain", "",
        "equivalent plastic strain at which an element is removed (eroded; also when crushed to a "
        "fifth of its area); 0: never",
        0.0, 1e3, 0.0}},
      [](const Parameters &p) -> std::unique_ptr<Material> {
        return std::make_unique<VonMises>(p);
      }};
}

} // namespace mesopen::fem
