// Points with a radius (sites, disks) in the cell grid of every neighbour search, copied into cell
// order so that a search reads memory front to back.
#pragma once

#include "cell_grid.hpp"

#include <cstdint>

namespace mesopen {

struct GridPoint {
  double x, y, r;
  std::uint32_t index;
};
using PointGrid = CellGrid<GridPoint>;

// Cells of edges at least `cell` over [0, width] x [0, height].
inline PointGrid pointGrid(double width, double height, double cell) {
  PointGrid grid;
  grid.tile(width, height, cell);
  return grid;
}

// The points [first, last) of x, y, r into the grid's cells.
inline void binPoints(PointGrid &grid, const double *x, const double *y, const double *r,
                      std::uint32_t first, std::uint32_t last) {
  grid.fillPoints(
      last - first, [&](std::size_t k) { return x[first + k]; },
      [&](std::size_t k) { return y[first + k]; },
      [&](std::size_t k) {
        const std::uint32_t i = first + static_cast<std::uint32_t>(k);
        return GridPoint{x[i], y[i], r[i], i};
      });
}

} // namespace mesopen
