#include "fake_dem.hpp"

#include <algorithm>
#include <stdexcept>

namespace mesopen::coupling {

FakeDem::FakeDem(Particles particles, FakeDemSettings settings)
    : p_(std::move(particles)), s_(settings) {
  const std::size_t n = p_.size();
  for (auto *v : {&p_.y, &p_.vx, &p_.vy, &p_.omega, &p_.radius, &p_.mass})
    if (v->size() != n)
      throw std::invalid_argument("FakeDem: particle arrays of different lengths");
  if (!(s_.restitution > 0.0 && s_.restitution <= 1.0))
    throw std::invalid_argument("FakeDem: restitution outside (0, 1]");
  // The disks start apart: the first half step takes gravity alone.
  f_.reset(n);
  for (std::size_t i = 0; i < n; ++i)
    f_.fy[i] = -p_.mass[i] * s_.gravity;
}

double FakeDem::stableStep() const {
  const auto lightest = std::min_element(p_.mass.begin(), p_.mass.end());
  return contactStep(lightest == p_.mass.end() ? 0.0 : *lightest, s_.stiffness);
}

// The contact of disk i with disk j (j = size(): a wall), n the unit normal from j to i, depth the
// overlap: spring-dashpot normal force, Coulomb friction at the contact point (spins included),
// capped at the force that stops the slip in one step (tangential effective mass: a disk's point
// takes 1/m + r^2/I = 3/m per unit force).
void FakeDem::contactForce(std::size_t i, std::size_t j, double nx, double ny, double depth,
                           double dt) {
  const bool wall = j == p_.size();
  const double ri = p_.radius[i], mi = p_.mass[i];
  double vx = p_.vx[i] + p_.omega[i] * ri * ny, vy = p_.vy[i] - p_.omega[i] * ri * nx;
  double m_eff = mi, m_t = mi / 3.0;
  if (!wall) {
    const double rj = p_.radius[j], mj = p_.mass[j];
    vx -= p_.vx[j] - p_.omega[j] * rj * ny, vy -= p_.vy[j] + p_.omega[j] * rj * nx;
    m_eff = mi * mj / (mi + mj), m_t = 1.0 / (3.0 / mi + 3.0 / mj);
  }
  const double vn = vx * nx + vy * ny; // > 0: separating
  const double log_e = std::log(s_.restitution);
  const double gamma =
      2.0 * std::sqrt(s_.stiffness * m_eff) * -log_e / std::sqrt(log_e * log_e + M_PI * M_PI);
  const double fn = std::max(0.0, s_.stiffness * depth - gamma * vn);
  const double tx = vx - vn * nx, ty = vy - vn * ny, slip = std::sqrt(tx * tx + ty * ty);
  const double ft = slip > 0.0 ? std::min(s_.friction * fn, m_t * slip / dt) / slip : 0.0;
  const double fx = fn * nx - ft * tx, fy = fn * ny - ft * ty;
  f_.fx[i] += fx, f_.fy[i] += fy, f_.torque[i] -= ri * (nx * fy - ny * fx);
  if (!wall)
    f_.fx[j] -= fx, f_.fy[j] -= fy, f_.torque[j] -= p_.radius[j] * (nx * fy - ny * fx);
}

void FakeDem::ownForces(double dt) {
  const std::size_t n = p_.size();
  f_.reset(n);
  for (std::size_t i = 0; i < n; ++i)
    f_.fy[i] = -p_.mass[i] * s_.gravity;
  if (!(s_.stiffness > 0.0))
    return;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = p_.x[i], y = p_.y[i], r = p_.radius[i];
    for (std::size_t j = i + 1; j < n; ++j) {
      const double dx = x - p_.x[j], dy = y - p_.y[j], reach = r + p_.radius[j];
      const double d2 = dx * dx + dy * dy;
      if (d2 >= reach * reach || d2 == 0.0)
        continue;
      const double d = std::sqrt(d2);
      contactForce(i, j, dx / d, dy / d, reach - d, dt);
    }
    if (!std::isnan(s_.wall_left) && x - r < s_.wall_left)
      contactForce(i, n, 1.0, 0.0, s_.wall_left - (x - r), dt);
    if (!std::isnan(s_.wall_right) && x + r > s_.wall_right)
      contactForce(i, n, -1.0, 0.0, x + r - s_.wall_right, dt);
    if (!std::isnan(s_.wall_bottom) && y - r < s_.wall_bottom)
      contactForce(i, n, 0.0, 1.0, s_.wall_bottom - (y - r), dt);
  }
}

void FakeDem::advance(double dt, const Exchange &exchange) {
  const std::size_t n = p_.size();
  // v(n+1/2) = v(n) + dt/2 f(n)/m, x(n+1) = x(n) + dt v(n+1/2)
  for (std::size_t i = 0; i < n; ++i) {
    p_.vx[i] += 0.5 * dt * f_.fx[i] / p_.mass[i], p_.vy[i] += 0.5 * dt * f_.fy[i] / p_.mass[i];
    p_.omega[i] += 0.5 * dt * f_.torque[i] / p_.inertia(i);
    p_.x[i] += dt * p_.vx[i], p_.y[i] += dt * p_.vy[i];
  }
  ownForces(dt);
  external_.reset(n);
  exchange(p_, external_);
  // f(n+1) = own + external; v(n+1) = v(n+1/2) + dt/2 f(n+1)/m
  for (std::size_t i = 0; i < n; ++i) {
    f_.fx[i] += external_.fx[i], f_.fy[i] += external_.fy[i], f_.torque[i] += external_.torque[i];
    p_.vx[i] += 0.5 * dt * f_.fx[i] / p_.mass[i], p_.vy[i] += 0.5 * dt * f_.fy[i] / p_.mass[i];
    p_.omega[i] += 0.5 * dt * f_.torque[i] / p_.inertia(i);
  }
}

} // namespace mesopen::coupling
