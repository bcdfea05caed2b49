// A coupled run in preCICE's words (participants, meshes, data, time windows): the FE participant
// (fem::Solver; its mesh the bodies' boundary nodes) and a DEM participant (its mesh the disks).
// A time window is one FE step: the FE solver kicks and drifts to x(n+1), then, as one of its force
// providers, this coupling lets the DEM participant advance over the same window; at x(n+1) the
// DEM participant's particle state is read, the FE-DEM contact forces are written onto the disks
// and their reactions onto the FE nodes (disk_contact.hpp); both solvers then finish the step
// with the forces at n+1. Every declared exchange is checked to have happened once per window.
#pragma once

#include "dem.hpp"
#include "disk_contact.hpp"
#include "solver.hpp"

#include <cstdint>
#include <string>

namespace mesopen::coupling {

// One exchanged quantity (preCICE's data on a mesh), written by one participant and read by the
// other, with the last window it was exchanged in.
struct Data {
  std::string name, mesh, writer, reader;
  std::uint64_t window = 0;
};

class FeDemCoupling : public fem::ForceProvider {
public:
  FeDemCoupling(const fem::Model &model, DemParticipant &dem, DiskContactSettings settings);
  // One time window: the DEM participant's step with the exchange at x(n+1). Throws
  // fem::RunFailure if a declared exchange did not happen.
  void addForces(fem::Model &model, double time, double dt) override;
  double stepStiffness() const override { return contact_.stepStiffness(); }
  void boundaryChanged(const fem::Model &model, const std::vector<std::uint32_t> &) override {
    contact_.boundaryChanged(model);
  }
  const DiskContact &contact() const { return contact_; }
  const DemParticipant &dem() const { return dem_; }
  std::uint64_t windows() const { return window_; }
  double seconds() const { return seconds_; } // in the windows: the DEM step and the exchange
  const std::vector<Data> &data() const { return data_; }

private:
  DemParticipant &dem_;
  DiskContact contact_;
  std::uint64_t window_ = 0;
  double seconds_ = 0.0;
  std::vector<Data> data_; // the particles' state, the forces on them, the reactions on FE nodes
  std::vector<Reaction> reactions_;
};

} // namespace mesopen::coupling
