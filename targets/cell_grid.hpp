// A uniform grid of buckets over the box for neighbour searches. Points are copied into bucket
// order (counting sort, O(n)), so a search reads memory front to back.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace mesopen {

class CellGrid {
public:
  struct Item {
    double x, y, r;
    std::uint32_t index;
  };

  // Buckets of edge >= `cell` covering [0, width] x [0, height]; points outside go to the
  // nearest edge bucket.
  CellGrid(double width, double height, double cell)
      : nx_(std::max(1, static_cast<int>(width / cell))),
        ny_(std::max(1, static_cast<int>(height / cell))), sx_(nx_ / width), sy_(ny_ / height) {}

  int column(double x) const { return std::clamp(static_cast<int>(std::floor(x * sx_)), 0, nx_ - 1); }
  int row(double y) const { return std::clamp(static_cast<int>(std::floor(y * sy_)), 0, ny_ - 1); }
  std::size_t bucket(double x, double y) const {
    return static_cast<std::size_t>(row(y)) * nx_ + column(x);
  }

  // Sort the points [first, last) of x, y, r into buckets.
  void fill(const double *x, const double *y, const double *r, std::uint32_t first, std::uint32_t last) {
    start_.assign(static_cast<std::size_t>(nx_) * ny_ + 1, 0);
    items_.resize(last - first);
    bucket_of_.resize(last - first);
    for (std::uint32_t i = first; i < last; ++i)
      ++start_[(bucket_of_[i - first] = bucket(x[i], y[i])) + 1];
    for (std::size_t b = 1; b < start_.size(); ++b)
      start_[b] += start_[b - 1];
    fill_.assign(start_.begin(), start_.end() - 1);
    for (std::uint32_t i = first; i < last; ++i)
      items_[fill_[bucket_of_[i - first]]++] = {x[i], y[i], r[i], i};
  }

  // Call f(item) for every point whose bucket meets the square [x - reach, x + reach]^2.
  template <class F> void forNear(double x, double y, double reach, F &&f) const {
    const int c0 = column(x - reach), c1 = column(x + reach);
    const int r0 = row(y - reach), r1 = row(y + reach);
    for (int r = r0; r <= r1; ++r) {
      const std::size_t row_start = static_cast<std::size_t>(r) * nx_;
      const Item *it = items_.data() + start_[row_start + c0], *end = items_.data() + start_[row_start + c1 + 1];
      for (; it != end; ++it)
        f(*it);
    }
  }

  // The points in bucket order (row by row).
  const std::vector<Item> &items() const { return items_; }

private:
  int nx_, ny_;
  double sx_, sy_;
  std::vector<std::uint32_t> start_, fill_;
  std::vector<std::size_t> bucket_of_;
  std::vector<Item> items_;
};

} // namespace mesopen
