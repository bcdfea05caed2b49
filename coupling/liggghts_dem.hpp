// The DEM participant run by LIGGGHTS 3.8 through its library interface (library.h): the input
// script liggghts-inputs/dem.in with its variables, one step of LIGGGHTS's integrator per time
// window. A window of many FE steps (endWindow) writes the disks' motion under the FE bodies'
// forces into the atoms' positions, velocities and spins before the step; a window of one step
// (advance) puts the forces in by `fix external pf/callback` inside the step, after the drift
// (writing the forces between runs instead gives half the impulse), and their torques in the same
// callback. The only file, with its .cpp, that includes LIGGGHTS headers.
#pragma once

#include "dem.hpp"
#include "mpi_communicator.hpp"

#include <mpi.h>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace mesopen::coupling {

class LiggghtsDem : public DemParticipant {
public:
  // `variables` as the script's -var name value pairs; every value a finite number or an existing
  // file, checked here (std::invalid_argument) before anything reaches LIGGGHTS, which exits the
  // process on a bad command. LIGGGHTS writes its log to `log` ("none": nowhere), after what the
  // file holds if `append_log` (a run continued).
  LiggghtsDem(const std::string &script, std::vector<std::pair<std::string, std::string>> variables,
              const std::string &log, MPI_Comm comm, bool append_log = false);
  ~LiggghtsDem() override;
  LiggghtsDem(const LiggghtsDem &) = delete;
  LiggghtsDem &operator=(const LiggghtsDem &) = delete;
  const Particles &particles() const override { return p_; }
  double stableStep() const override;
  double largestRadius() const override;
  void advance(double dt, const Exchange &exchange) override;
  void endWindow(double length, double planned, const WindowMotion &motion) override;
  std::uint64_t layout() const override { return layout_; }
  void gatherDiskForces(std::vector<DiskForce> &forces) const override;
  using DemParticipant::gatherParticles;
  void gatherParticles(const Particles &local, Particles &all) const override;
  // The LIGGGHTS instance, for library.h calls (benchmarks).
  void *handle() const { return lmp_; }

  // Between two windows: LIGGGHTS's restart file `path` (written by rank 0, every rank calling
  // it; a temporary name, for the caller to rename when whole), and every rank's disks' own forces
  // and torques by id (a restart file does not hold them). LIGGGHTS's set-up, which must follow a
  // restart file, is made here as it is after read_restart (the run continued from it): with the
  // script's `lists = 1`, its lists are those the last step built, and the forces it computes
  // again (in another order of summation, without the contacts' history update) are put back as
  // they were, so that the run goes on as without the restart file.
  std::vector<DiskForce> writeRestart(const std::string &path);
  // The disks' own forces and torques put back for this rank's disks (by id), after LIGGGHTS's
  // set-up computed them again (writeRestart's, or this one's of a restart file).
  void restoreForces(const std::vector<DiskForce> &forces);
  // Time in the windows [s]: all of it, and the part spent in the exchange (the state read, the
  // FE-DEM contact, the forces put in, the state read at the window's end).
  double windowSeconds() const { return window_seconds_; }
  double exchangeSeconds() const { return exchange_seconds_; }

private:
  static void callback(void *self, std::int64_t step, int n, int *id, double **x, double **f);
  void read(); // the particles' state from LIGGGHTS's arrays into p_
  void setStep(double dt);
  void step(const Exchange *exchange);
  void *lmp_ = nullptr;
  // mesopen's own gathers and reductions go through a duplicate of the processes' communicator:
  // they never meet LIGGGHTS's messages
  parallel::MpiCommunicator own_;
  MPI_Comm comm_;
  Particles p_;
  ParticleForces forces_;
  const Exchange *exchange_ = nullptr; // set during a window
  std::int64_t exchange_step_ = 0;     // LIGGGHTS's step number of the window's step
  double dt_ = 0.0, kn_ = 0.0;
  double window_seconds_ = 0.0, exchange_seconds_ = 0.0;
  std::int64_t listed_at_ = -1; // LIGGGHTS's step of the neighbour lists p_'s order was read at
  std::uint64_t layout_ = 0;
};

} // namespace mesopen::coupling
