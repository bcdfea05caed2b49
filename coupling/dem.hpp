// The DEM participant of a coupled run, in preCICE's words: a solver of disks whose mesh is its
// particles, which reads the force data the FE participant writes on them once per time window.
// Disks in 2D plane strain, 1 m thick like the FE model: mass rho pi r^2 [kg/m], moment of inertia
// m r^2 / 2 [kg m^2/m], forces [N/m], torques [N m/m].
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace mesopen::coupling {

// The disks, struct of arrays. Within a window's exchange: positions at its end, velocities and
// spins at its middle (the velocity-Verlet half step both solvers take); after it, both at its end.
struct Particles {
  std::vector<double> x, y, vx, vy, omega; // [m], [m/s], [rad/s]
  std::vector<double> radius, mass;        // [m], [kg/m]
  std::size_t size() const { return x.size(); }
  double inertia(std::size_t i) const { return 0.5 * mass[i] * radius[i] * radius[i]; }
  // Kinetic energy, translation and rotation [J/m].
  double kineticEnergy() const {
    double e = 0.0;
    for (std::size_t i = 0; i < size(); ++i)
      e += 0.5 * mass[i] * (vx[i] * vx[i] + vy[i] * vy[i]) + 0.5 * inertia(i) * omega[i] * omega[i];
    return e;
  }
};

// A step that takes ten steps over the contact time pi sqrt(m / k_n) of the lightest disk (mass
// m) against a wall, the stiffest of its contacts; infinite without a contact stiffness.
inline double contactStep(double lightest_mass, double kn) {
  return kn > 0.0 && lightest_mass > 0.0 ? 0.1 * M_PI * std::sqrt(lightest_mass / kn) : INFINITY;
}

// Forces and torques on the disks [N/m, N m/m], written by the FE participant.
struct ParticleForces {
  std::vector<double> fx, fy, torque;
  void reset(std::size_t n) { fx.assign(n, 0.0), fy.assign(n, 0.0), torque.assign(n, 0.0); }
};

// A reaction of the disks on an FE node [N/m], with its frictional part.
struct Reaction {
  std::uint32_t node, body;
  double fx, fy, friction_x, friction_y;
};

// A DEM solver as a participant. advance() takes one time window of length dt as velocity
// Verlet: v(n+1/2) = v(n) + dt/2 f(n)/m, x(n+1) = x(n) + dt v(n+1/2); then its own forces at x(n+1)
// and `exchange`, which reads the particles there (positions at n+1, velocities at n+1/2) and
// writes the forces the FE bodies exert on them; then v(n+1) = v(n+1/2) + dt/2 f(n+1)/m. The FE
// solver takes the same steps in the same order, so that both read each other at x(n+1).
class DemParticipant {
public:
  using Exchange = std::function<void(const Particles &, ParticleForces &)>;
  virtual ~DemParticipant() = default;
  virtual const Particles &particles() const = 0;
  // The largest stable time step of its own contacts [s] (contactStep; over MPI ranks, every rank
  // calls it).
  virtual double stableStep() const = 0;
  virtual void advance(double dt, const Exchange &exchange) = 0;
  // Over MPI ranks each holding part of the disks, the reactions of every rank's disks, in rank
  // order, so that every rank loads its copy of the FE nodes alike (one rank: as they are).
  virtual void gatherReactions(std::vector<Reaction> &) const {}
  // Every rank's disks on rank 0 (every rank calls it), in the order of their ids; elsewhere empty.
  virtual void gatherParticles(Particles &all) const { all = particles(); }
};

} // namespace mesopen::coupling
