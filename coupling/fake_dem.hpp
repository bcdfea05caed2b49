// A small DEM solver without LIGGGHTS, so that the coupling is tested on any machine: disks with
// the linear spring-dashpot normal law of LIGGGHTS's hooke/stiffness model (f_n = k_n d - gamma_n
// v_n, gamma_n for a restitution e: 2 sqrt(k_n m_eff) |ln e| / sqrt(ln^2 e + pi^2)), Coulomb
// friction capped at the force that stops the slip in one step, gravity and straight walls. Every
// pair of disks is tested each step: meant for the tens of disks of a test.
#pragma once

#include "dem.hpp"

#include <cmath>

namespace mesopen::coupling {

struct FakeDemSettings {
  double stiffness = 0.0;   // k_n [N/m per m]; 0: no disk-disk or wall contact
  double restitution = 0.5; // e of a normal impact
  double friction = 0.0;    // mu
  double gravity = 0.0;     // downward [m/s^2]
  double wall_left = NAN, wall_right = NAN, wall_bottom = NAN; // x, x, y [m]; NaN: none
};

class FakeDem : public DemParticipant {
public:
  FakeDem(Particles particles, FakeDemSettings settings);
  const Particles &particles() const override { return p_; }
  double stableStep() const override;
  double largestRadius() const override;
  void advance(double dt, const Exchange &exchange) override;
  void endWindow(double length, double planned, const WindowMotion &motion) override;

private:
  void ownForces(double dt);
  void kick(std::size_t i, double dt);
  void drift(double dt); // with the half kick before
  void contactForce(std::size_t i, std::size_t j, double nx, double ny, double depth, double dt);
  Particles p_;
  FakeDemSettings s_;
  ParticleForces external_;
};

} // namespace mesopen::coupling
