// A uniform grid of buckets over the box for neighbour searches (counting sort, O(n)).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace mesopen {

class CellGrid {
public:
  // Buckets of edge >= `cell` covering [0, width] x [0, height]; points outside go to the
  // nearest edge bucket.
  CellGrid(double width, double height, double cell)
      : nx_(std::max(1, static_cast<int>(width / cell))),
        ny_(std::max(1, static_cast<int>(height / cell))), sx_(nx_ / width), sy_(ny_ / height) {}

  int nx() const { return nx_; }
  int ny() const { return ny_; }
  int column(double x) const { return std::clamp(static_cast<int>(std::floor(x * sx_)), 0, nx_ - 1); }
  int row(double y) const { return std::clamp(static_cast<int>(std::floor(y * sy_)), 0, ny_ - 1); }
  int bucket(double x, double y) const { return row(y) * nx_ + column(x); }

  // Sort the points [first, last) of x, y into buckets.
  void fill(const double *x, const double *y, std::uint32_t first, std::uint32_t last) {
    start_.assign(static_cast<std::size_t>(nx_) * ny_ + 1, 0);
    items_.resize(last - first);
    for (std::uint32_t i = first; i < last; ++i)
      ++start_[bucket(x[i], y[i]) + 1];
    for (std::size_t b = 1; b < start_.size(); ++b)
      start_[b] += start_[b - 1];
    std::vector<std::uint32_t> fillp(start_.begin(), start_.end() - 1);
    for (std::uint32_t i = first; i < last; ++i)
      items_[fillp[bucket(x[i], y[i])]++] = i;
  }

  // Call f(j) for every point whose bucket meets the square [x - reach, x + reach]^2.
  template <class F> void forNear(double x, double y, double reach, F &&f) const {
    const int c0 = column(x - reach), c1 = column(x + reach);
    const int r0 = row(y - reach), r1 = row(y + reach);
    for (int r = r0; r <= r1; ++r)
      for (std::uint32_t k = start_[r * nx_ + c0]; k < start_[r * nx_ + c1 + 1]; ++k)
        f(items_[k]);
  }

  // The points in bucket order (row by row), for a cache-friendly renumbering.
  const std::vector<std::uint32_t> &ordered() const { return items_; }

private:
  int nx_, ny_;
  double sx_, sy_;
  std::vector<std::uint32_t> start_, items_;
};

} // namespace mesopen
