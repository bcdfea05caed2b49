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
  if (p_.id.empty())
    for (std::size_t i = 0; i < n; ++i)
      p_.id.push_back(static_cast<std::int64_t>(i + 1));
  // The disks start apart: the first half step takes gravity alone.
  p_.fx.assign(n, 0.0), p_.fy.assign(n, 0.0), p_.torque.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    p_.fy[i] = -p_.mass[i] * s_.gravity;
}

double FakeDem::largestRadius() const {
  double largest = 0.0;
  for (double r : p_.radius)
    largest = std::max(largest, r);
  return largest;
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
  p_.fx[i] += fx, p_.fy[i] += fy, p_.torque[i] -= ri * (nx * fy - ny * fx);
  if (!wall)
    p_.fx[j] -= fx, p_.fy[j] -= fy, p_.torque[j] -= p_.radius[j] * (nx * fy - ny * fx);
}

void FakeDem::ownForces(double dt) {
  const std::size_t n = p_.size();
  p_.fx.assign(n, 0.0), p_.fy.assign(n, 0.0), p_.torque.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    p_.fy[i] = -p_.mass[i] * s_.gravity;
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
  drift(dt);
  ownForces(dt);
  external_.reset(n);
  exchange(p_, external_);
  // f(n+1) = own + external; v(n+1) = v(n+1/2) + dt/2 f(n+1)/m
  for (std::size_t i = 0; i < n; ++i) {
    p_.fx[i] += external_.fx[i], p_.fy[i] += external_.fy[i], p_.torque[i] += external_.torque[i];
    kick(i, dt);
  }
}

// The window's motion put into the state at its start, so that the step of length D that follows
// (half kick with f(n), drift, own forces, half kick) ends as DemParticipant::endWindow says.
void FakeDem::endWindow(double length, double planned, const WindowMotion &m) {
  const double shift = 0.5 * length * (planned - length);
  for (const std::uint32_t i : m.moved) {
    p_.vx[i] += m.dvx[i], p_.vy[i] += m.dvy[i], p_.omega[i] += m.domega[i];
    p_.x[i] += m.dx[i] - length * m.dvx[i] + shift * p_.fx[i] / p_.mass[i];
    p_.y[i] += m.dy[i] - length * m.dvy[i] + shift * p_.fy[i] / p_.mass[i];
  }
  drift(length);
  ownForces(length);
  for (std::size_t i = 0; i < p_.size(); ++i)
    kick(i, length);
}

// v += dt/2 f/m (and the spin); then, in drift, x += dt v.
void FakeDem::kick(std::size_t i, double dt) {
  p_.vx[i] += 0.5 * dt * p_.fx[i] / p_.mass[i], p_.vy[i] += 0.5 * dt * p_.fy[i] / p_.mass[i];
  p_.omega[i] += 0.5 * dt * p_.torque[i] / p_.inertia(i);
}
void FakeDem::drift(double dt) {
  for (std::size_t i = 0; i < p_.size(); ++i) {
    kick(i, dt);
    p_.x[i] += dt * p_.vx[i], p_.y[i] += dt * p_.vy[i];
  }
}

} // namespace mesopen::coupling
