// Helpers for coupled FE-DEM tests.
#pragma once

#include "dem.hpp"
#include "model.hpp"

#include <array>

namespace mesopen::test {

// Total linear momentum of the FE nodes and the disks [kg m/s per m].
inline std::array<double, 2> totalMomentum(const fem::Model &model,
                                           const coupling::Particles &disks) {
  std::array<double, 2> p{0.0, 0.0};
  for (std::size_t i = 0; i < disks.size(); ++i)
    p[0] += disks.mass[i] * disks.vx[i], p[1] += disks.mass[i] * disks.vy[i];
  const fem::Nodes &nd = model.nodes;
  for (std::size_t a = 0; a < nd.size(); ++a)
    p[0] += nd.mass[a] * nd.vx[a], p[1] += nd.mass[a] * nd.vy[a];
  return p;
}

} // namespace mesopen::test
