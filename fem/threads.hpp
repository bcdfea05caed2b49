// Work split among OpenMP threads in contiguous runs, so that a thread keeps the same items (and
// their data in its core's cache) from one pass to the next.
#pragma once

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <memory>
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

// Work items in lists, one list a thread: each thread takes the items of its own list from the
// front, then those the others have not taken yet, so that every item is taken once, mostly by
// the thread it was listed for (its data in that core's cache), and a thread that runs out early
// (less work, or a slower core) helps the others instead of waiting. Items must not depend on
// which thread takes them.
class WorkLists {
public:
  static constexpr std::size_t none = static_cast<std::size_t>(-1);
  // `lists` empty lists, none of their items taken
  void reset(std::size_t lists) {
    if (lists != lists_.size())
      next_ = std::make_unique<Cursor[]>(lists);
    lists_.resize(lists);
    for (std::size_t t = 0; t < lists; ++t)
      lists_[t].clear(), next_[t].value.store(0, std::memory_order_relaxed);
  }
  std::size_t size() const { return lists_.size(); }
  std::vector<std::size_t> &list(std::size_t t) { return lists_[t]; }
  // The next item not taken of list t, or `none`.
  std::size_t take(std::size_t t) {
    const std::vector<std::size_t> &list = lists_[t];
    if (next_[t].value.load(std::memory_order_relaxed) >= list.size())
      return none;
    const std::size_t i = next_[t].value.fetch_add(1, std::memory_order_relaxed);
    return i < list.size() ? list[i] : none;
  }
  // The next item for thread `me`: of its own list, else of the others' (the next list after its
  // own first), or `none` when every item has been taken.
  std::size_t next(std::size_t me) {
    const std::size_t n = lists_.size();
    for (std::size_t k = 0; k < n; ++k)
      if (const std::size_t item = take((me + k) % n); item != none)
        return item;
    return none;
  }

private:
  struct alignas(64) Cursor { // (a cache line each: the threads' cursors do not share one)
    std::atomic<std::size_t> value{0};
  };
  std::vector<std::vector<std::size_t>> lists_;
  std::unique_ptr<Cursor[]> next_;
};

} // namespace mesopen::fem
