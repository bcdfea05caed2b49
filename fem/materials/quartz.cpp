// "quartz": the thesis's quartz grains (section 3.3.2, Table 3.3).
// Pressure: Mie-Grueneisen. Shear modulus from the cold pressure P-bar = K mu + K1 mu^2 + K2 mu^3
// (Eq. 3.10-3.11): G = G0 + G1 P + G2 P^2 with P = max(P-bar, 0) (the fit is for compression),
// and G >= 0.
// Strength: overstress (viscoplastic) relaxation toward the equilibrium surface (Eq. 3.12):
//   S = S* [1 - (1 - |Se| / |S*|) min(dt / T_R, 1)]   when |S*| > |Se|,
//   |Se| = sqrt(2/3) Y(p),  Y(p) = min(B + M p, Y1)   (bilinear, Y1 its cap).
// With dt >= T_R the update is a radial return. `strength = false`: elastic grains, whose deviator
// is the neo-Hookean one of hyperelastic.hpp with G(J) = G(P-bar(mu)) and the pressure it adds,
// p_G = -G'(J) / 2 (tr b* - 3): a closed path returns the work it took, however G changes on it.
// Equations: docs/models.md §3.3.
#include "../material.hpp"
#include "hyperelastic.hpp"
#include "hypoelastic.hpp"
#include "mie_gruneisen.hpp"

#include <algorithm>
#include <cmath>

namespace mesopen::fem {

namespace {

class Quartz final : public Material {
public:
  explicit Quartz(const Parameters &p)
      : rho0_(p.at("density")), eos_{p.at("bulk_modulus"), p.at("k1"), p.at("k2"),
                                     p.at("gruneisen"), p.at("pressure_cutoff")},
        G0_(p.at("g0")), G1_(p.at("g1")), G2_(p.at("g2")), B_(p.at("cohesion")),
        M_(p.at("friction_slope")), Y1_(p.at("yield_cap")), T_(p.at("relaxation_time")),
        strength_(p.at("strength") != 0.0) {}
  double density() const override { return rho0_; }
  bool plastic() const override { return strength_; }
  bool usesDeformationGradient() const override { return !strength_; }

  void update(const StrainBatch &in, StressState &s, MaterialOutput &out) const override {
    if (strength_)
      strengthUpdate(in, s, out);
    else
      elasticUpdate(in, s, out);
  }

private:
  // G(J) and dG/dJ: G = G0 + G1 P + G2 P^2, P = max(P-bar(mu), 0), mu = 1/J - 1.
  // (inlined without a branch, so that the batch loop of elasticUpdate vectorizes)
  struct Shear {
    double G, dG_dJ, d2G_dJ2;
  };
  [[gnu::always_inline]] Shear shear(double J) const {
    const double mu = 1.0 / J - 1.0, P = std::max(eos_.cold(mu), 0.0);
    const bool loaded = P > 0.0;
    const double P_mu = loaded ? (3.0 * eos_.K2 * mu + 2.0 * eos_.K1) * mu + eos_.K : 0.0;
    const double P_mumu = loaded ? 6.0 * eos_.K2 * mu + 2.0 * eos_.K1 : 0.0;
    const double G = G0_ + (G2_ * P + G1_) * P;
    const double G_P = G1_ + 2.0 * G2_ * P, mu_J = -1.0 / (J * J), mu_JJ = 2.0 / (J * J * J);
    const double dG_dJ = G_P * P_mu * mu_J, d2G_dJ2 = 2.0 * G2_ * P_mu * P_mu * mu_J * mu_J +
                                                      G_P * (P_mumu * mu_J * mu_J + P_mu * mu_JJ);
    const bool held = G <= 0.0; // a fit falling below zero is held there
    return {held ? 0.0 : G, held ? 0.0 : dG_dJ, held ? 0.0 : d2G_dJ2};
  }

  // Without strength: the stored deviatoric energy W = G(J) / 2 (tr b* - 3) per initial volume;
  // the element's pressure is the equation of state's (of the energy less W) plus p_G, its energy
  // takes W's change.
  void elasticUpdate(const StrainBatch &in, StressState &s, MaterialOutput &out) const {
    const double p_min = -eos_.cutoff;
    // Local array pointers: contiguous vector loads and stores (no per-lane gathers).
    const double *f0 = in.f[0], *f1 = in.f[1], *f2 = in.f[2], *f3 = in.f[3];
    const double *g0 = in.f_old[0], *g1 = in.f_old[1], *g2 = in.f_old[2], *g3 = in.f_old[3];
    const double *r = in.inverse_cube_root_j, *r_old = in.inverse_cube_root_j_old;
    const double *jac = in.jacobian, *dvol = in.volume_change, *vol0 = in.volume0;
    double *sxx = s.sxx, *syy = s.syy, *sxy = s.sxy, *pressure = s.pressure, *energy = s.energy;
    double *cs = out.sound_speed, *shear_share = out.shear_share;
#pragma omp simd
    for (std::size_t i = 0; i < in.n; ++i) {
      const double J = determinant(f0[i], f1[i], f2[i], f3[i]);
      const double J_old = determinant(g0[i], g1[i], g2[i], g3[i]);
      const Shear now = shear(J), before = shear(J_old);
      const double trace = isochoricTrace(f0[i], f1[i], f2[i], f3[i], r[i]);
      const double tr = trace - 3.0,
                   tr_old = isochoricTrace(g0[i], g1[i], g2[i], g3[i], r_old[i]) - 3.0;
      const double p_shear = -0.5 * now.dG_dJ * tr, p_shear_old = -0.5 * before.dG_dJ * tr_old;
      neoHookeanDeviator(f0[i], f1[i], f2[i], f3[i], J, r[i], now.G, sxx[i], syy[i], sxy[i]);
      const double w_dev = vol0[i] * 0.5 * (now.G * tr - before.G * tr_old);
      const double mu = 1.0 / jac[i] - 1.0;
      // The stored shear energy is not heat: the thermal term Gamma rho0 e sees E - A0 W.
      const double b = eos_.gamma / vol0[i];
      const double a = eos_.energyFree(mu, eos_.cold(mu)) - b * vol0[i] * 0.5 * now.G * tr;
      double p_eos = pressure[i] - p_shear_old;
      energyEquation(a, b, p_min, dvol[i], w_dev, energy[i], p_eos);
      pressure[i] = p_eos + p_shear;
      const double bulk = eos_.tangentBulk(mu, p_eos, a + b * energy[i], p_min);
      // The stiffness W's dependence on J adds: in volume, -J dp_G/dJ = J G''(J) (tr b* - 3) / 2,
      // and coupling volume and shear, about |G'(J)| |dev b*| (|dev b*|^2 ~ 2 (tr b* - 3)).
      const double coupled = std::max(0.5 * J * now.d2G_dJ2 * tr, 0.0) +
                             std::abs(now.dG_dJ) * std::sqrt(2.0 * std::max(tr, 0.0));
      const double G = incrementalShearModulus(now.G, trace, J),
                   longitudinal = bulk + coupled + 4.0 / 3.0 * G;
      cs[i] = std::sqrt(longitudinal * jac[i] / rho0_);
      shear_share[i] = longitudinal > 0.0 ? G / longitudinal : 0.75;
    }
    out.plastic_work = 0.0;
  }

  void strengthUpdate(const StrainBatch &in, StressState &s, MaterialOutput &out) const {
    const double dt = in.dt, sqrt23 = std::sqrt(2.0 / 3.0), p_min = -eos_.cutoff;
    const double relax = std::min(dt / T_, 1.0);
    // Local array pointers: contiguous vector loads and stores (no per-lane gathers).
    const double *dxx = in.dxx, *dyy = in.dyy, *dxy = in.dxy, *spin = in.spin, *jac = in.jacobian;
    const double *dvol = in.volume_change, *vmid = in.volume_mid, *vol0 = in.volume0;
    double *sxx_ = s.sxx, *syy_ = s.syy, *sxy_ = s.sxy, *pressure = s.pressure, *energy = s.energy;
    double *eps = s.plastic_strain, *cs = out.sound_speed, *shear_share = out.shear_share;
    double plastic_work = 0.0;
#pragma omp simd reduction(+ : plastic_work)
    for (std::size_t i = 0; i < in.n; ++i) {
      const double mu = 1.0 / jac[i] - 1.0;
      const double cold = eos_.cold(mu), a = eos_.energyFree(mu, cold), b = eos_.gamma / vol0[i];
      const double P = std::max(cold, 0.0);
      const double G = std::max(G0_ + (G2_ * P + G1_) * P, 0.0); // a fit below zero held there
      double sxx = sxx_[i], syy = syy_[i], sxy = sxy_[i];
      rotateDeviator(sxx, syy, sxy, spin[i] * dt);
      const double power_old = stressPower(sxx, syy, sxy, dxx[i], dyy[i], dxy[i]);
      addDeviatoricIncrement(sxx, syy, sxy, 2.0 * G * dt, dxx[i], dyy[i], dxy[i]);
      // Yield at the new volume with the old energy (the energy follows the new stress).
      const double p_yield = std::max(a + b * energy[i], p_min);
      const double Se = sqrt23 * std::min(B_ + M_ * p_yield, Y1_);
      const double norm = deviatorNorm(sxx, syy, sxy);
      if (norm > Se) {
        const double scale = 1.0 - (1.0 - Se / norm) * relax;
        sxx *= scale, syy *= scale, sxy *= scale;
        // |S* - S| / 2G (without shear stiffness the deviator is the rotated old one: no strain)
        const double dev_plastic = G > 0.0 ? (1.0 - scale) * norm / (2.0 * G) : 0.0;
        eps[i] += sqrt23 * dev_plastic;
        plastic_work += vmid[i] * scale * norm * dev_plastic;
      }
      const double power_new = stressPower(sxx, syy, sxy, dxx[i], dyy[i], dxy[i]);
      sxx_[i] = sxx, syy_[i] = syy, sxy_[i] = sxy;
      const double w_dev = 0.5 * (power_old + power_new) * vmid[i] * dt;
      energyEquation(a, b, p_min, dvol[i], w_dev, energy[i], pressure[i]);
      // The sound speed of the element's tangent stiffness: without bulk stiffness where the
      // pressure is held at the cut-off (a grain element drawn out in tension: in run 6 such a
      // sliver, J = 1.9, set the step from 0.3 us on at 8.7 km/s with K, 6.7 without).
      const double bulk = eos_.tangentBulk(mu, pressure[i], a + b * energy[i], p_min);
      const double longitudinal = bulk + 4.0 / 3.0 * G;
      cs[i] = std::sqrt(longitudinal * jac[i] / rho0_);
      shear_share[i] = longitudinal > 0.0 ? G / longitudinal : 0.75;
    }
    out.plastic_work = plastic_work;
  }

  double rho0_;
  MieGruneisen eos_;
  double G0_, G1_, G2_, B_, M_, Y1_, T_;
  bool strength_;
};

} // namespace

MaterialType quartzMaterialType() {
  return {
      "quartz",
      "Mie-Grueneisen pressure, pressure-dependent shear modulus, overstress strength toward a "
      "bilinear equilibrium yield surface; defaults: the quartz of thesis Table 3.3",
      {{"density", "kg/m^3", "initial density rho0", 1.0, 1e5, 2648.5},
       {"bulk_modulus", "Pa", "Mie-Grueneisen K", 1.0, 1e13, 43.19e9},
       {"k1", "Pa", "Mie-Grueneisen K1 (mu^2 term)", 0.0, 1e14, 156.2e9},
       {"k2", "Pa", "Mie-Grueneisen K2 (mu^3 term)", 0.0, 1e15, 48.6e9},
       {"gruneisen", "", "Grueneisen Gamma", 0.0, 10.0, 0.675},
       {"pressure_cutoff", "Pa", "K_c: the pressure stays >= -K_c", 0.0, 1e12, 0.0},
       {"g0", "Pa", "shear modulus at zero pressure G0", 0.0, 1e13, 46.92e9},
       {"g1", "", "dG/dP, G1", -100.0, 100.0, 1.873},
       {"g2", "1/Pa", "G2, the P^2 term of G", -1e-6, 1e-6, 3.459e-10},
       {"cohesion", "Pa", "B: equilibrium yield at zero pressure", 0.0, 1e12, 2.353e9},
       {"friction_slope", "", "M: slope of the equilibrium yield in p", 0.0, 100.0, 0.667},
       {"yield_cap", "Pa", "Y1: the equilibrium yield's upper bound", 0.0, 1e12, 4.4e9},
       {"relaxation_time", "s", "T_R of the overstress relaxation", 1e-15, 1.0, 3.5e-9},
       {"strength", "", "strength (overstress flow) on; false: elastic grains", 0.0, 1.0, 1.0,
        true}},
      [](const Parameters &p) -> std::unique_ptr<Material> { return std::make_unique<Quartz>(p); }};
}

} // namespace mesopen::fem
