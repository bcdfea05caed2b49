// Work split among OpenMP threads in contiguous runs, so that a thread keeps the same items (and
// their data in its core's cache) from one pass to the next.
#pragma once

#include <omp.h>

#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

namespace mesopen::fem {

// Bounds of contiguous runs of items, one run per entry of `targets`, run t taking about
// targets[t] / (sum of targets) of the sum of `weights`: run t is [bounds[t], bounds[t + 1]). An
// item goes to the run whose share holds its middle (all to the first run without weight or
// targets).
inline std::vector<std::size_t> contiguousShares(const std::vector<std::size_t> &weights,
                                                 const std::vector<double> &targets) {
  double total = 0.0, target_sum = 0.0;
  for (std::size_t w : weights)
    total += static_cast<double>(w);
  for (double t : targets)
    target_sum += t;
  const std::size_t parts = targets.size();
  std::vector<std::size_t> bounds(parts + 1, weights.size());
  bounds[0] = 0;
  if (!(total > 0.0 && target_sum > 0.0))
    return bounds;
  double before = 0.0, end_of_run = targets[0] / target_sum * total;
  for (std::size_t i = 0, t = 0; i < weights.size(); before += static_cast<double>(weights[i++])) {
    const double middle = before + 0.5 * static_cast<double>(weights[i]);
    while (t + 1 < parts && middle >= end_of_run) {
      bounds[++t] = i;
      end_of_run += targets[t] / target_sum * total;
    }
  }
  return bounds;
}

// The same with `parts` runs of about equal sums.
inline std::vector<std::size_t> contiguousShares(const std::vector<std::size_t> &weights,
                                                 std::size_t parts) {
  return contiguousShares(weights, std::vector<double>(parts, 1.0));
}

// This thread's run [begin, end) of work split at `bounds` (one bound more than threads); a team
// of another size splits the whole evenly.
inline std::pair<std::size_t, std::size_t> threadShare(const std::vector<std::size_t> &bounds) {
  const auto t = static_cast<std::size_t>(omp_get_thread_num());
  const auto n = static_cast<std::size_t>(omp_get_num_threads());
  if (bounds.size() == n + 1)
    return {bounds[t], bounds[t + 1]};
  const std::size_t all = bounds.back() - bounds.front();
  return {bounds.front() + t * all / n, bounds.front() + (t + 1) * all / n};
}

} // namespace mesopen::fem
