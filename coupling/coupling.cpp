#include "coupling.hpp"

#include <chrono>

namespace mesopen::coupling {

FeDemCoupling::FeDemCoupling(const fem::Model &model, DemParticipant &dem,
                             DiskContactSettings settings)
    : dem_(dem), contact_(model, std::move(settings)),
      data_{{"Particle-State", "DEM-Particles", "DEM", "FE"},
            {"Particle-Force", "DEM-Particles", "FE", "DEM"},
            {"Reaction-Force", "FE-Boundary", "FE", "FE"}} {}

void FeDemCoupling::addForces(fem::Model &model, double time, double dt) {
  const auto start = std::chrono::steady_clock::now();
  ++window_;
  reactions_.clear();
  dem_.advance(dt, [&](const Particles &particles, ParticleForces &forces) {
    data_[0].window = window_; // read: positions at n+1, velocities at n+1/2
    contact_.addForces(model, particles, forces, reactions_, dt);
    data_[1].window = window_; // written
  });
  dem_.gatherReactions(reactions_);
  DiskContact::apply(model, reactions_);
  data_[2].window = window_;
  seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (const Data &d : data_)
    if (d.window != window_)
      throw fem::RunFailure("coupling: " + d.name + " on " + d.mesh + " (" + d.writer + " to " +
                            d.reader + ") was not exchanged in time window " +
                            std::to_string(window_) + " ending at t = " + std::to_string(time) +
                            " s");
}

} // namespace mesopen::coupling
