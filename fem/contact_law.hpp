// The contact law of FE-FE contact (fem/contact.hpp) and FE-DEM contact
// (coupling/disk_contact.hpp): a penalty tied to the masses and the step, damping on approach,
// Coulomb friction capped at the force that stops the slip in one step (thesis section 3).
//   f_n = max(0, m_n / dt (kappa d / dt - c v_n)),   c = 2 zeta sqrt(kappa),
//   f_t = min(mu f_n, m_t |v_t| / dt)                 against the tangential velocity v_t,
// d the depth, v_n = v . n the normal relative velocity (> 0 separating), m_n and m_t the reduced
// masses of the two sides in the normal and tangential directions. kappa = 1, zeta = 1/2 is the
// force that closes in one step the penetration two free points would reach at the next step (a
// kinematic constraint); mu f_n is sliding, m_t |v_t| / dt sticking. See fem/contact.hpp for the
// choice of kappa and zeta and the stability of the damping.
//
// A contact may deepen in a step by its approach, twice (-2 v_n dt) for a margin, or by 0.005 of
// an element h, over the depth it was pushed at the step before (approachReach). Found deeper, the
// point was not reached by approach (a boundary folded over it, erosion laid it bare): the excess
// is allowed for and let go over release_steps steps, so that the overlap opens at a bounded
// speed.
//
// Each function keeps the order of its floating-point operations: FE-FE and FE-DEM runs are
// reproduced bit for bit by it.
// Equations: docs/models.md §8.2, §8.3, §8.5.
#pragma once

#include <algorithm>
#include <cmath>

namespace mesopen::fem {

constexpr double release_steps = 200.0;

// The deepest a contact pushed at depth `pushed` the step before can be now, approaching at
// -vn (vn > 0 separating), in a body of element size h.
inline double approachReach(double pushed, double h, double vn, double dt) {
  constexpr double step_margin = 0.005;
  return pushed + std::max(step_margin * h, -2.0 * vn * dt);
}

// The reduced mass of two masses in contact, m1 m2 / (m1 + m2).
inline double reducedMass(double m1, double m2) { return m1 * m2 / (m1 + m2); }

// The damping coefficient c = 2 zeta sqrt(kappa) of the penalty kappa, in units of m / dt.
inline double dampingCoefficient(double zeta, double kappa) {
  return 2.0 * zeta * std::sqrt(kappa);
}

// The normal relative velocity v . n (> 0: separating).
inline double normalVelocity(double vx, double vy, double nx, double ny) {
  return vx * nx + vy * ny;
}

// A contact force on the first side (the reaction on the other is its opposite): in total
// (fx, fy), its normal magnitude fn, the tangential velocity (tx, ty) and the friction per unit
// of it, ft (the friction force is -ft (tx, ty)).
struct ContactForce {
  double fx, fy, fn, tx, ty, ft;
};

// The law above: normal direction (nx, ny) (unit, pointing from the other side to this one),
// relative velocity (vx, vy) of this side to the other with its normal part vn, depth d, penalty
// kappa, damping c, friction coefficient mu, step dt.
inline ContactForce contactForce(double m_n, double m_t, double d, double vx, double vy, double vn,
                                 double nx, double ny, double kappa, double c, double mu,
                                 double dt) {
  const double fn = std::max(0.0, m_n / dt * (kappa * d / dt - c * vn));
  const double tx = vx - vn * nx, ty = vy - vn * ny, slip = std::sqrt(tx * tx + ty * ty);
  const double ft = slip > 0.0 ? std::min(mu * fn, m_t * slip / dt) / slip : 0.0;
  return {fn * nx - ft * tx, fn * ny - ft * ty, fn, tx, ty, ft};
}

} // namespace mesopen::fem
