// What a coupled run exchanges, in preCICE's vocabulary (Bungartz et al., Computers & Fluids 141,
// 2016; the preCICE configuration's data, meshes and participants): two participants, FE
// (fem::Solver) and DEM (a DemParticipant); two meshes, FE-Boundary (the FE bodies' boundary nodes)
// and DEM-Particles (the disks); the data below, each a quantity on one mesh written by one
// participant and read by the other; and time windows, one DEM step each (coupling.hpp).
// The ledger records every exchange with its window; at a window's end each datum must have been
// exchanged in it as often as it is declared to be: a coupling that skipped one ends the run.
#pragma once

#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace mesopen::coupling {

enum class Datum : std::uint8_t { particle_state, particle_motion, reaction_force };
constexpr std::size_t data_count = 3;

struct DataDeclaration {
  const char *name, *mesh, *writer, *reader;
  bool every_step; // exchanged every FE step of the window (else once per window)
};

// The data of an FE-DEM window:
//   Particle-State: x(n), v(n) and the disks' own forces f(n), read at the window's start;
//   Reaction-Force: the FE-DEM contact forces' reactions on the FE nodes, every FE step;
//   Particle-Motion: the disks' motion dx, dv over the window, handed to the DEM step at its end.
constexpr std::array<DataDeclaration, data_count> declarations{{
    {"Particle-State", "DEM-Particles", "DEM", "FE", false},
    {"Particle-Motion", "DEM-Particles", "FE", "DEM", false},
    {"Reaction-Force", "FE-Boundary", "FE", "FE", true},
}};

class ExchangeLedger {
public:
  // `datum` exchanged in window `window` (counted from 1).
  void record(Datum datum, std::uint64_t window) {
    Entry &e = entries_[static_cast<std::size_t>(datum)];
    if (e.window != window)
      e.window = window, e.times = 0;
    ++e.times;
  }
  // Throws std::logic_error naming the first datum not exchanged as declared in `window` over
  // `steps` FE steps.
  void checkWindow(std::uint64_t window, std::uint64_t steps) const {
    for (std::size_t d = 0; d < data_count; ++d) {
      const Entry &e = entries_[d];
      const std::uint64_t want = declarations[d].every_step ? steps : 1;
      const std::uint64_t got = e.window == window ? e.times : 0;
      if (got != want)
        throw std::logic_error(std::string("coupling window ") + std::to_string(window) + ": " +
                               declarations[d].name + " on " + declarations[d].mesh + " (" +
                               declarations[d].writer + " to " + declarations[d].reader +
                               ") exchanged " + std::to_string(got) + " times, declared " +
                               std::to_string(want));
    }
  }
  std::uint64_t lastWindow(Datum datum) const {
    return entries_[static_cast<std::size_t>(datum)].window;
  }

private:
  struct Entry {
    std::uint64_t window = 0, times = 0;
  };
  std::array<Entry, data_count> entries_{};
};

} // namespace mesopen::coupling
