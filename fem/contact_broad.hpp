// The broad phase of FE-FE contact (fem/contact.hpp): the pairs of bodies whose boxes come within
// the search margin, at least one of them moving, found with the bodies' boxes in cell grids
// (grid/cell_grid.hpp): the bodies at rest in a grid built once, the moving bodies in one built at
// each search. The pairs are kept from step to step (a Verlet list of bodies): found with the
// boxes widened by the margin (one median element size), and found anew only when some body may
// have moved by half of it (its travel, contact_boundaries.hpp); a body that wakes in between adds
// its pairs with bodies at rest. Pairs of two resting bodies are not searched.
// Each pair carries the lists the narrow phase keeps for it (contact.cpp) in the arena of its run;
// a pair found again keeps them.
// Equations: docs/models.md §8.
#pragma once

#include "cell_grid.hpp"
#include "contact_boundaries.hpp"
#include "model.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace mesopen::fem {

class BodyPairs {
public:
  using Box = narrow::Box;
  // A pair of bodies (a, b) whose boxes widened by the margin overlapped, and what the narrow
  // phase looks at: a's boundary nodes (indices into ContactBoundaries::nodes), b's segments (their
  // two nodes, as indices into the boundary nodes), b's nodes, a's segments, near the boxes'
  // overlap; in its run's arena from `begin`.
  struct Pair {
    Pair(std::uint32_t p, std::uint32_t q) : a(std::min(p, q)), b(std::max(p, q)) {}
    std::uint32_t a, b;
    std::uint32_t begin = 0, capacity = 0; // capacity 0: no lists yet
    std::uint32_t end[4] = {};             // ends of the four parts, from `begin`
    double travel_a = -std::numeric_limits<double>::infinity(), travel_b = 0.0; // when listed
    double margin = 0.0;
    // Per side (a's nodes against b, b's against a; see Contact::touch): the travel of the two
    // bodies together up to which its clear nodes need no look, and how many nodes are not clear
    // (hot, listed in the arena after the pair's lists).
    double until[2] = {};
    std::uint32_t hot[2] = {};
  };

  // The cell and the search margin from the bodies' sizes, the grid of the bodies at rest now, and
  // `runs` runs of pairs (none yet).
  BodyPairs(const Model &model, const ContactBoundaries &boundaries, std::size_t runs);
  // This step's moving bodies listed, and those `measured` accepts measured (their boundaries'
  // positions, boxes and travel; with the work shared, the other processes' bodies' come from
  // their owners where needed: Contact::shareBoxes).
  template <class Measured>
  void measure(const Model &model, ContactBoundaries &boundaries, Measured measured) {
    moving_.clear();
    for (std::size_t b = 0; b < model.bodies.size(); ++b)
      if (!model.at_rest[b] && boundaries.hasNodes(b))
        moving_.push_back(static_cast<std::uint32_t>(b));
    const long n_moving = static_cast<long>(moving_.size());
#pragma omp parallel for schedule(static) if (n_moving > 64)
    for (long i = 0; i < n_moving; ++i) // (with levels, the bodies not due stood still)
      if ((model.due.empty() || model.due[moving_[i]]) && measured(moving_[i]))
        boundaries.measure(model, moving_[i]);
  }
  // The largest travel since the last search for pairs of the moving bodies `which` accepts (with
  // the work shared, a process's own: the largest over the processes is the run's).
  template <class Which> double farthest(const ContactBoundaries &boundaries, Which which) const {
    double most = 0.0;
    for (std::uint32_t b : moving_)
      if (which(b))
        most = std::max(most, boundaries.travel[b] - travel_searched_[b]);
    return most;
  }
  // Whether the pairs are to be found anew: a body may have closed half the margin since the last
  // search (`farthest`, the largest travel since), or none was made since forget.
  bool searchNeeded(double farthest) const {
    return run_pairs_.empty() || 2.0 * farthest > search_margin_;
  }
  // The margin by which bodies' boxes are widened to find their pairs.
  double searchMargin() const { return search_margin_; }
  // The pairs: all anew (`anew`, as searchNeeded says), else those of the bodies that woke since
  // the last step added. Returns `anew`.
  bool search(const Model &model, const ContactBoundaries &boundaries, bool anew);
  // The boundaries changed: the lists hold indices into them, so all pairs are found anew, with
  // new lists, at the next update.
  void forget() { run_pairs_.clear(); }

  // The runs of pairs (a few per thread, taken in turn by free threads): run r holds the pairs
  // run(r) (the last also those added since the search) and their lists in arena(r).
  std::size_t runs() const { return arenas_.size(); }
  std::span<Pair> run(std::size_t r) {
    return {pairs_.data() + run_pairs_[r], pairs_.data() + run_pairs_[r + 1]};
  }
  std::vector<std::uint32_t> &arena(std::size_t r) { return arenas_[r]; }
  // Every pair, in run order, and how many.
  const std::vector<Pair> &pairs() const { return pairs_; }
  std::size_t size() const { return pairs_.size(); }
  // The bodies not at rest (with a boundary), this step.
  const std::vector<std::uint32_t> &moving() const { return moving_; }

  // What the next steps depend on (a checkpoint): the pairs' order (the order in which a node's
  // forces add up), whether a search is due, and per body its travel at the last search and
  // whether its pairs are listed. restore takes it back, the pairs' lists to be taken anew at
  // their first look (they then hold the same contacts).
  bool searchDue() const { return run_pairs_.empty(); }
  const std::vector<double> &travelSearched() const { return travel_searched_; }
  const std::vector<char> &listed() const { return listed_; }
  void restore(const std::vector<std::uint32_t> &pairs, bool search_due,
               const std::vector<double> &travel_searched, const std::vector<char> &listed);

private:
  void findPairs(const ContactBoundaries &boundaries);
  void addPairsOfWoken(const Model &model, const std::vector<Box> &boxes);
  // Bodies `which` in the cells their boxes meet, in cells of cell_.
  void gridBodies(CellGrid<> &grid, const std::vector<Box> &boxes,
                  const std::vector<std::uint32_t> &which) const;
  template <class Wanted, class Add>
  void restNeighbours(const std::vector<Box> &boxes, std::uint32_t a, double margin, Wanted wanted,
                      Add add) const;

  std::vector<Pair> pairs_;
  std::vector<std::size_t> run_pairs_; // run r: pairs_[run_pairs_[r], run_pairs_[r + 1])
  std::vector<std::vector<std::uint32_t>> arenas_; // per run: its pairs' lists
  std::vector<double> travel_searched_; // per body: its travel at the last search for pairs
  std::vector<char> listed_;            // per body: its pairs are in pairs_ (it moved then)
  std::vector<std::uint32_t> woken_;    // bodies moving since this step
  std::vector<std::uint32_t> moving_;   // bodies not at rest, this step
  double cell_ = 0.0;                   // the grids' cell: twice the median body
  CellGrid<> rest_grid_, moving_grid_;
  double search_margin_ = 0.0;
};

} // namespace mesopen::fem
