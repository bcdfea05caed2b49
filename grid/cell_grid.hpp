// A uniform grid of cells (cell lists) for every neighbour search: the target generator's sites
// and disks, the FE contact's bodies (broad phase), the FE-DEM contact's disks and boundary
// segments. Items are put in the cells of a rectangle each (a point in one cell, a box in the
// cells it meets) by a counting sort, so that a cell's items lie side by side, in the order
// given, and the cells row by row. A search looks at the cells a rectangle meets, row by row.
// Coordinates beyond the grid go to its edge cells.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace mesopen {

// A rectangle of cells, columns i0..i1 and rows j0..j1 (inclusive).
struct CellRange {
  std::size_t i0, j0, i1, j1;
};

template <class Item = std::uint32_t> class CellGrid {
public:
  CellGrid() = default;

  // Square cells of edge `cell` from (x0, y0) over width x height; the edge doubled while the grid
  // would have more than max_cells cells (something flung far away must not make it huge).
  void cover(double x0, double y0, double width, double height, double cell,
             std::size_t max_cells = std::size_t{1} << 22) {
    for (;; cell *= 2.0) {
      nx_ = static_cast<std::size_t>(width / cell) + 1;
      ny_ = static_cast<std::size_t>(height / cell) + 1;
      if (nx_ * ny_ <= max_cells)
        break;
    }
    x0_ = x0, y0_ = y0, inverse_x_ = inverse_y_ = 1.0 / cell;
  }
  // Cells of edges at least `cell` that tile [0, width] x [0, height] exactly.
  void tile(double width, double height, double cell) {
    nx_ = static_cast<std::size_t>(std::max(1, static_cast<int>(width / cell)));
    ny_ = static_cast<std::size_t>(std::max(1, static_cast<int>(height / cell)));
    x0_ = y0_ = 0.0;
    inverse_x_ = static_cast<double>(nx_) / width, inverse_y_ = static_cast<double>(ny_) / height;
  }

  std::size_t columns() const { return nx_; }
  std::size_t rows() const { return ny_; }
  std::size_t size() const { return nx_ * ny_; }
  std::size_t column(double x) const { return index((x - x0_) * inverse_x_, nx_); }
  std::size_t row(double y) const { return index((y - y0_) * inverse_y_, ny_); }
  std::size_t cellOf(double x, double y) const { return row(y) * nx_ + column(x); }
  // The cells the rectangle [xa, xb] x [ya, yb] meets.
  CellRange cells(double xa, double ya, double xb, double yb) const {
    return {column(xa), row(ya), column(xb), row(yb)};
  }

  // Items 0..n-1 into the cells of cellsOf(k) (a CellRange), as item(k).
  template <class CellsOf, class MakeItem>
  void fill(std::size_t n, CellsOf cellsOf, MakeItem item) {
    start_.assign(size() + 1, 0);
    for (std::size_t k = 0; k < n; ++k)
      forCells(cellsOf(k), [&](std::size_t c) { ++start_[c + 1]; });
    for (std::size_t c = 0; c < size(); ++c)
      start_[c + 1] += start_[c];
    items_.resize(start_.back());
    fill_.assign(start_.begin(), start_.end() - 1);
    for (std::size_t k = 0; k < n; ++k)
      forCells(cellsOf(k), [&](std::size_t c) { items_[fill_[c]++] = item(k); });
  }
  // Points 0..n-1 at (x(k), y(k)), one cell each, as item(k).
  template <class X, class Y, class MakeItem>
  void fillPoints(std::size_t n, X x, Y y, MakeItem item) {
    fill(
        n,
        [&](std::size_t k) {
          const std::size_t i = column(x(k)), j = row(y(k));
          return CellRange{i, j, i, j};
        },
        item);
  }

  // The items of cell c (row * columns() + column).
  std::span<const Item> cell(std::size_t c) const {
    return {items_.data() + start_[c], items_.data() + start_[c + 1]};
  }
  // f(item) for the items of the cells `r`, row by row (an item in several cells comes as often).
  template <class F> void forEach(const CellRange &r, F &&f) const {
    for (std::size_t j = r.j0; j <= r.j1; ++j) {
      const Item *it = items_.data() + start_[j * nx_ + r.i0];
      const Item *end = items_.data() + start_[j * nx_ + r.i1 + 1];
      for (; it != end; ++it)
        f(*it);
    }
  }
  // f(item) for the items of the cells the square [x - reach, x + reach]^2 meets.
  template <class F> void forNear(double x, double y, double reach, F &&f) const {
    forEach(cells(x - reach, y - reach, x + reach, y + reach), f);
  }
  // All items, cell by cell.
  const std::vector<Item> &items() const { return items_; }

private:
  // floor(u) within 0..n-1
  static std::size_t index(double u, std::size_t n) {
    if (!(u >= 1.0))
      return 0;
    return u >= static_cast<double>(n - 1) ? n - 1 : static_cast<std::size_t>(u);
  }
  template <class F> void forCells(const CellRange &r, F &&f) const {
    for (std::size_t j = r.j0; j <= r.j1; ++j)
      for (std::size_t i = r.i0; i <= r.i1; ++i)
        f(j * nx_ + i);
  }

  double x0_ = 0.0, y0_ = 0.0, inverse_x_ = 1.0, inverse_y_ = 1.0;
  std::size_t nx_ = 0, ny_ = 0;
  std::vector<std::uint32_t> start_, fill_;
  std::vector<Item> items_;
};

} // namespace mesopen
