// The DEM participant of a coupled run, in preCICE's words: a solver of disks whose mesh is its
// particles, which reads the force data the FE participant writes on them once per time window.
// Disks in 2D plane strain, 1 m thick like the FE model: mass rho pi r^2 [kg/m], moment of inertia
// m r^2 / 2 [kg m^2/m], forces [N/m], torques [N m/m].
// Equations: docs/models.md §9.3.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace mesopen::coupling {

// The disks, struct of arrays. Within a window's exchange: positions at its end, velocities and
// spins at its middle (the velocity-Verlet half step both solvers take); after it, both at its end,
// with the participant's own forces there (disk-disk and wall contacts, gravity; not the FE
// bodies').
struct Particles {
  std::vector<double> x, y, vx, vy, omega; // [m], [m/s], [rad/s]
  std::vector<double> radius, mass;        // [m], [kg/m]
  std::vector<double> fx, fy, torque;      // own forces [N/m], torques [N m/m]
  std::vector<std::int64_t> id;            // each disk's number, whatever its place in the arrays
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

// The disks' motion over a time window under the FE bodies' forces, beyond the motion their own
// forces give them (multiple time stepping, see DemParticipant::endWindow), in the order of
// Particles: displacement [m], velocity [m/s], spin [rad/s]. Only the disks in `moved` (the ones
// the FE bodies could reach) have any; the others are zero there.
struct WindowMotion {
  std::vector<double> dx, dy, dvx, dvy, domega;
  std::vector<std::uint32_t> moved; // indices into Particles
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

// A force and torque on the disk numbered `id` [N/m, N m/m].
struct DiskForce {
  std::int64_t id;
  double fx, fy, torque;
};

// A DEM solver as a participant. advance() takes one time window of length dt as velocity
// Verlet: v(n+1/2) = v(n) + dt/2 f(n)/m, x(n+1) = x(n) + dt v(n+1/2); then its own forces at x(n+1)
// and `exchange`, which reads the particles there (positions at n+1, velocities at n+1/2) and
// writes the forces the FE bodies exert on them; then v(n+1) = v(n+1/2) + dt/2 f(n+1)/m.
// endWindow() ends a window of many FE steps (r-RESPA multiple time stepping, Tuckerman, Berne &
// Martyna 1992, J. Chem. Phys. 97, 1990): over the window the disks moved as
//   x(t) = x(n) + t v_h + dx(t),  v_h = v(n) + P/2 f(n)/m,
// the slow kick of their own forces f(n) over the planned length P, then their own forces frozen
// and the FE bodies' forces (fast) integrated on the FE steps into dx and dv. endWindow(D, P, m),
// D the window's actual length, makes x(n+1) = x(n) + D v_h + dx for the moved disks (where the FE
// bodies saw them), computes its own forces there and ends with
//   v(n+1) = v(n) + D/2 f(n)/m + dv + D/2 f(n+1)/m
// (and the spins alike): one step of its own of length D whose forces are computed once, its own
// forces' impulses those of velocity Verlet with the step D whatever P was. The disks not moved
// take that step alone, x(n+1) = x(n) + D (v(n) + D/2 f(n)/m): their path with P was only used to
// tell that no FE body reaches them (the two differ by D |P - D| / 2 f/m, P - D a fraction of an FE
// step).
class DemParticipant {
public:
  using Exchange = std::function<void(const Particles &, ParticleForces &)>;
  virtual ~DemParticipant() = default;
  virtual const Particles &particles() const = 0;
  // The largest stable time step of its own contacts [s] (contactStep; over MPI ranks, every rank
  // calls it).
  virtual double stableStep() const = 0;
  // The largest disk's radius over all ranks [m] (every rank calls it).
  virtual double largestRadius() const = 0;
  virtual void advance(double dt, const Exchange &exchange) = 0;
  virtual void endWindow(double length, double planned, const WindowMotion &motion) = 0;
  // A number that changes whenever the particles' order or number in particles() may have changed
  // (LIGGGHTS sorts and exchanges atoms when it rebuilds its neighbour lists); what is kept per
  // place (the disks' places by id) is taken anew then.
  virtual std::uint64_t layout() const { return 0; }
  // Over MPI ranks each holding part of the disks, the forces on disks named by their ids, every
  // rank's in rank order (one rank: as they are).
  virtual void gatherDiskForces(std::vector<DiskForce> &) const {}
  // Every rank's disks on rank 0 (every rank calls it), in the order of their ids; elsewhere empty.
  // `local`: this rank's disks as they are to be gathered (its particles, or their state within a
  // window), in the order of particles().
  virtual void gatherParticles(const Particles &local, Particles &all) const { all = local; }
  void gatherParticles(Particles &all) const { gatherParticles(particles(), all); }
};

} // namespace mesopen::coupling
