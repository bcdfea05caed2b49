// Every node's position and velocity at the end of a run, to hold a run on several processes
// against the same run on one (the programs under mpirun of tests/support).
#pragma once

#include <cstddef>
#include <cstdio>
#include <tuple>
#include <vector>

namespace mesopen::test {

struct NodeStates {
  std::vector<double> x, y, vx, vy;
};

// For each of x, y, vx and vy that differs in any bit between `many` (the run on `processes`
// processes) and `one`, its first differing node printed; how many of the four differ.
inline int differingNodeStates(int processes, const NodeStates &many, const NodeStates &one) {
  int differing = 0;
  for (auto [name, a, b] : {std::tuple{"x", &many.x, &one.x},
                            {"y", &many.y, &one.y},
                            {"vx", &many.vx, &one.vx},
                            {"vy", &many.vy, &one.vy}})
    for (std::size_t i = 0; i < a->size(); ++i)
      if ((*a)[i] != (*b)[i]) {
        std::printf("%d processes: node %zu's %s is %.17g, on one %.17g\n", processes, i, name,
                    (*a)[i], (*b)[i]);
        ++differing;
        break;
      }
  return differing;
}

} // namespace mesopen::test
