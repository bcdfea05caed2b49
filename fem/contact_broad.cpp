// The broad phase of FE-FE contact (contact_broad.hpp).
#include "contact_broad.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <span>
#include <tuple>

namespace mesopen::fem {

namespace {
constexpr double search_margin = 1.0; // pairs of bodies: margin / the median element size
} // namespace

BodyPairs::BodyPairs(const Model &model, const ContactBoundaries &boundaries, std::size_t runs) {
  const std::size_t n_bodies = model.bodies.size();
  const std::vector<Box> &boxes = boundaries.boxes;
  travel_searched_.assign(n_bodies, 0.0);
  listed_.assign(n_bodies, 0);
  // Grid cells about twice the typical body: a grain sits in at most four cells.
  std::vector<double> extents;
  for (std::size_t b = 0; b < n_bodies; ++b)
    if (boundaries.hasNodes(b))
      extents.push_back(std::max(boxes[b].x1 - boxes[b].x0, boxes[b].y1 - boxes[b].y0));
  if (!extents.empty()) {
    std::nth_element(extents.begin(), extents.begin() + extents.size() / 2, extents.end());
    cell_ = 2.0 * extents[extents.size() / 2];
  }
  std::vector<double> sizes;
  for (double h : boundaries.size)
    if (h > 0.0)
      sizes.push_back(h);
  if (!sizes.empty()) {
    std::nth_element(sizes.begin(), sizes.begin() + sizes.size() / 2, sizes.end());
    search_margin_ = search_margin * sizes[sizes.size() / 2];
  }
  // The bodies at rest now, in a grid that stays: a body at rest does not move.
  std::vector<std::uint32_t> resting;
  for (std::size_t b = 0; b < n_bodies; ++b)
    if (model.at_rest[b] && boundaries.hasNodes(b))
      resting.push_back(static_cast<std::uint32_t>(b));
  gridBodies(rest_grid_, boxes, resting);
  arenas_.resize(runs);
}

bool BodyPairs::search(const Model &model, const ContactBoundaries &boundaries, bool anew) {
  if (anew)
    findPairs(boundaries);
  else
    addPairsOfWoken(model, boundaries.boxes);
  return anew;
}

// Cell lists of the bodies `which` over the rectangle their boxes cover (counting sort: cell by
// cell, bodies in the given order).
void BodyPairs::gridBodies(CellGrid<> &grid, const std::vector<Box> &boxes,
                           const std::vector<std::uint32_t> &which) const {
  grid = {};
  if (which.empty() || !(cell_ > 0.0))
    return;
  double xa = HUGE_VAL, ya = HUGE_VAL, xb = -HUGE_VAL, yb = -HUGE_VAL;
  for (std::uint32_t b : which) {
    xa = std::min(xa, boxes[b].x0), xb = std::max(xb, boxes[b].x1);
    ya = std::min(ya, boxes[b].y0), yb = std::max(yb, boxes[b].y1);
  }
  grid.cover(xa, ya, xb - xa, yb - ya, cell_);
  grid.fill(
      which.size(),
      [&](std::size_t k) {
        const Box &box = boxes[which[k]];
        return grid.cells(box.x0, box.y0, box.x1, box.y1);
      },
      [&](std::size_t k) { return which[k]; });
}

// The pairs of bodies whose boxes come closer than the search margin, at least one
// of them moving, in the order of their numbers; each pair found once, in the cell that holds
// the lower-left corner of the overlap. Moving bodies meet each other in a grid of their boxes
// widened by half the margin, built here; the bodies at rest in the grid built at the start.
// The runs of pairs are shared evenly among the threads. A pair found before keeps its lists (they
// hold what they must while its two bodies move less than their margin, whatever the search), the
// others' are taken when first needed; after a change of the boundaries all are taken anew.
void BodyPairs::findPairs(const ContactBoundaries &boundaries) {
  const std::vector<Box> &boxes = boundaries.boxes;
  std::vector<Pair> before;
  std::vector<std::vector<std::uint32_t>> arenas_before(arenas_.size());
  std::vector<std::uint32_t> run_before; // per pair before: its run
  if (!run_pairs_.empty()) {
    before.swap(pairs_);
    for (std::size_t r = 0; r < arenas_.size(); ++r) {
      arenas_before[r].swap(arenas_[r]);
      run_before.insert(run_before.end(), run_pairs_[r + 1] - run_pairs_[r],
                        static_cast<std::uint32_t>(r));
    }
  }
  pairs_.clear();
  std::vector<Box> wide(boxes.size());
  for (std::uint32_t b : moving_) {
    wide[b] = boxes[b].widened(0.5 * search_margin_);
    travel_searched_[b] = boundaries.travel[b];
    listed_[b] = 1;
  }
  auto add = [&](std::uint32_t a, std::uint32_t b) { pairs_.emplace_back(a, b); };
  gridBodies(moving_grid_, wide, moving_);
  const CellGrid<> &g = moving_grid_;
  for (std::size_t c = 0; c < g.size(); ++c) {
    const std::span<const std::uint32_t> in = g.cell(c);
    for (std::size_t i = 0; i < in.size(); ++i)
      for (std::size_t j = i + 1; j < in.size(); ++j) {
        const Box &A = wide[in[i]], &B = wide[in[j]];
        if (A.overlaps(B) && g.cellOf(std::max(A.x0, B.x0), std::max(A.y0, B.y0)) == c)
          add(in[i], in[j]);
      }
  }
  for (std::uint32_t a : moving_)
    restNeighbours(
        boxes, a, search_margin_, [&](std::uint32_t b) { return !listed_[b]; }, add);
  auto earlier = [](const Pair &p, const Pair &q) {
    return std::tie(p.a, p.b) < std::tie(q.a, q.b);
  };
  std::sort(pairs_.begin(), pairs_.end(), earlier);
  const std::size_t runs = arenas_.size();
  run_pairs_.resize(runs + 1);
  for (std::size_t r = 0; r <= runs; ++r)
    run_pairs_[r] = pairs_.size() * r / runs;
  for (auto &arena : arenas_)
    arena.clear();
  // The pairs before in the order of the new ones (those the bodies that woke added come last),
  // matched; each listed one's lists and hot nodes into its new run's arena.
  std::vector<std::uint32_t> order(before.size());
  for (std::uint32_t j = 0; j < order.size(); ++j)
    order[j] = j;
  std::sort(order.begin(), order.end(),
            [&](std::uint32_t i, std::uint32_t j) { return earlier(before[i], before[j]); });
  auto old = order.begin();
  for (std::size_t r = 0; r < runs; ++r)
    for (std::size_t i = run_pairs_[r]; i < run_pairs_[r + 1]; ++i) {
      Pair &pair = pairs_[i];
      while (old != order.end() && earlier(before[*old], pair))
        ++old;
      if (old == order.end() || before[*old].a != pair.a || before[*old].b != pair.b ||
          before[*old].capacity == 0)
        continue;
      const Pair &kept = before[*old];
      const std::vector<std::uint32_t> &from = arenas_before[run_before[*old]];
      std::vector<std::uint32_t> &arena = arenas_[r];
      pair = kept;
      pair.begin = static_cast<std::uint32_t>(arena.size());
      arena.insert(arena.end(), from.begin() + kept.begin,
                   from.begin() + kept.begin + kept.capacity);
    }
}

// The pairs of the bodies that woke since the last step with the bodies at rest (or woken now):
// they were not searched while both rested. Added to the last run of pairs.
void BodyPairs::addPairsOfWoken(const Model &model, const std::vector<Box> &boxes) {
  woken_.clear();
  for (std::uint32_t b : moving_)
    if (!listed_[b])
      woken_.push_back(b);
  if (woken_.empty())
    return;
  for (std::uint32_t a : woken_)
    restNeighbours(
        boxes, a, search_margin_,
        [&](std::uint32_t b) { return !listed_[b] && (model.at_rest[b] || a < b); },
        [&](std::uint32_t a, std::uint32_t b) { pairs_.emplace_back(a, b); });
  for (std::uint32_t a : woken_)
    listed_[a] = 1;
  run_pairs_.back() = pairs_.size();
}

// The bodies of the grid of bodies at rest whose boxes come closer to body a's than `margin` and
// that `wanted` accepts, each once: add(a, b).
template <class Wanted, class Add>
void BodyPairs::restNeighbours(const std::vector<Box> &boxes, std::uint32_t a, double margin,
                               Wanted wanted, Add add) const {
  const CellGrid<> &r = rest_grid_;
  if (r.size() == 0)
    return;
  const Box A = boxes[a].widened(margin);
  const CellRange cells = r.cells(A.x0, A.y0, A.x1, A.y1);
  for (std::size_t j = cells.j0; j <= cells.j1; ++j)
    for (std::size_t i = cells.i0; i <= cells.i1; ++i)
      for (const std::uint32_t b : r.cell(j * r.columns() + i)) {
        const Box &B = boxes[b];
        if (b != a && A.overlaps(B) &&
            r.cellOf(std::max(A.x0, B.x0), std::max(A.y0, B.y0)) == j * r.columns() + i &&
            wanted(b))
          add(a, b);
      }
}

void BodyPairs::restore(const std::vector<std::uint32_t> &pairs, bool search_due,
                        const std::vector<double> &travel_searched,
                        const std::vector<char> &listed) {
  travel_searched_ = travel_searched, listed_ = listed;
  pairs_.clear();
  for (std::size_t k = 0; k + 1 < pairs.size(); k += 2)
    pairs_.emplace_back(pairs[k], pairs[k + 1]);
  for (auto &arena : arenas_)
    arena.clear();
  run_pairs_.clear();
  if (!search_due) { // the runs split anew (the hits come in pair order whatever the split)
    const std::size_t runs = arenas_.size();
    run_pairs_.resize(runs + 1);
    for (std::size_t r = 0; r <= runs; ++r)
      run_pairs_[r] = pairs_.size() * r / runs;
  }
}

} // namespace mesopen::fem
