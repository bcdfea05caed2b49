// The head-on collision of two disks under the linear spring-dashpot law of liggghts-inputs/dem.in
// (LIGGGHTS `model hooke/stiffness`, `absolute_damping on`, `limitForce on`), per metre of
// thickness:
//   f = max(0, kn d - gn v_n)   [N/m]
// d the overlap [m], v_n the normal relative velocity (negative on approach) [m/s], kn [N/m per m],
// gn [N s/m per m]. For a pair of effective mass m_eff = m1 m2 / (m1 + m2) [kg/m] meeting at v,
// while f > 0: m_eff d'' = -kn d - gn d', so d(t) = v / w e^(-b t) sin(w t), with
//   b = gn / (2 m_eff),   w = sqrt(kn / m_eff - b^2)   (underdamped, b < sqrt(kn / m_eff)).
// f = m_eff v e^(-b t) ((w^2 - b^2) / w sin(w t) + 2 b cos(w t)) falls to zero at
// w t = pi - 2 atan(b / w), where d' = -v e^(-b t): with limitForce the force then stays zero (the
// dashpot may not pull) and the disks leave at that speed. Contact time and restitution:
//   t_c = (pi - 2 atan(b / w)) / w,   e = exp(-b t_c).
// Without the limit the dashpot pulls until d = 0: t_c = pi / w, e = exp(-b pi / w) (the textbook
// law, e.g. Schaefer, Dippel & Wolf, J. Phys. I France 6 (1996) 5). With the limit e >= exp(-2)
// (b / w -> infinity) in the underdamped range. Both are independent of the impact speed.
// Equations: docs/models.md §9.2.
#pragma once

#include <cmath>
#include <stdexcept>

namespace mesopen::coupling {

struct SpringDashpot {
  double kn, gn; // [N/m per m], [N s/m per m]
};

struct PairCollision {
  double contact_time, restitution; // [s], [-]
};

// Contact time and restitution of a pair of effective mass m_eff [kg/m] under `law`, with the force
// limited to f >= 0 (`limited`, as dem.in has it) or not.
inline PairCollision pairCollision(const SpringDashpot &law, double m_eff, bool limited = true) {
  const double b = law.gn / (2.0 * m_eff), w2 = law.kn / m_eff - b * b;
  if (!(w2 > 0.0))
    throw std::invalid_argument("pairCollision: the spring-dashpot is not underdamped");
  const double w = std::sqrt(w2);
  const double t = limited ? (M_PI - 2.0 * std::atan(b / w)) / w : M_PI / w;
  return {t, std::exp(-b * t)};
}

// The law that gives a pair of effective mass m_eff [kg/m] the contact time t_c [s] and the
// restitution e: b = -ln(e) / t_c; then w t_c = theta, the root in (0, pi] of
// theta + 2 atan(b t_c / theta) = pi (limited; pi itself when not); kn = m_eff (w^2 + b^2),
// gn = 2 m_eff b. Limited, a root exists only for e > exp(-2) (std::invalid_argument otherwise).
inline SpringDashpot springDashpotFor(double t_c, double e, double m_eff, bool limited = true) {
  if (!(t_c > 0.0) || !(e > 0.0) || !(e <= 1.0))
    throw std::invalid_argument("springDashpotFor: needs t_c > 0 and 0 < e <= 1");
  const double a = -std::log(e), b = a / t_c;
  double theta = M_PI;
  if (limited && a > 0.0) {
    if (!(a < 2.0))
      throw std::invalid_argument("springDashpotFor: a limited spring-dashpot cannot give e <= "
                                  "exp(-2)");
    // g(theta) = theta + 2 atan(a / theta) - pi is convex, g(0+) = 0, g'(0+) = 1 - 2 / a < 0 and
    // g(pi) > 0: negative on (0, root), positive after it. Bisection.
    double lo = 1e-12, hi = M_PI;
    for (int k = 0; k < 200; ++k) {
      const double mid = 0.5 * (lo + hi);
      (mid + 2.0 * std::atan(a / mid) - M_PI < 0.0 ? lo : hi) = mid;
    }
    theta = 0.5 * (lo + hi);
  }
  const double w = theta / t_c;
  return {m_eff * (w * w + b * b), 2.0 * m_eff * b};
}

// The DEM contact law of quartz grains for runs (liggghts-inputs/dem.in's kn, gn, kt, gt),
// calibrated against head-on collisions of pairs of meshed grains of the baseline's mean size
// (tests/verification/grain_pair.cpp, docs/coupling.md "Calibration of the DEM contact law").
// kn: in 2D a spring per metre of thickness is a modulus [Pa]; the same kn makes the contact time
// grow with the disk size as an elastic contact's does. gn: absolute, so that the restitution is
// the calibrated one at the calibration size only (it rises for larger disks, falls for smaller).
// kt, gt: not calibrated (head-on collisions have no tangential motion). Chosen so that the
// tangential spring and dashpot of a pair of disks have the normal ones' frequency and damping
// ratio. The tangential effective mass of two equal disks with their spin (I = m r^2 / 2) is
//   1 / m_t = 2 / m + 2 r^2 / I = 6 / m,   m_t = m_eff / 3,
// hence kt = kn / 3, gt = gn / 3 (the 2D analogue of kt = 2/7 kn for spheres).
struct GrainContactLaw {
  double diameter, density; // of the calibration pair's disks [m], [kg/m^3]
  double kn, gn, kt, gt;    // [N/m per m], [N s/m per m]
  double mass() const { return density * M_PI * 0.25 * diameter * diameter; } // [kg/m]
};
inline constexpr GrainContactLaw quartz_grains{.diameter = 60e-6,
                                               .density = 2648.5,
                                               .kn = 3.35e10,
                                               .gn = 27.2,
                                               .kt = 3.35e10 / 3.0,
                                               .gt = 27.2 / 3.0};

} // namespace mesopen::coupling
