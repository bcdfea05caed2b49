#include "contact.hpp"
#include "threads.hpp"

#include <omp.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <numeric>
#include <span>
#include <stdexcept>
#include <tuple>
#include <utility>

namespace mesopen::fem {

namespace {
using narrow::no_node;
constexpr double touching = 1e-6; // penetration (this fraction of an element) taken as touching
constexpr double deep = 0.5;      // penetration beyond this fraction of an element counts as deep
constexpr double check_depth = 0.05; // penetration from which a contact is checked by crossings
constexpr double list_margin = 0.5;  // a pair's lists: margin / the smaller body's element size
constexpr std::size_t runs_per_thread = 4; // runs of pairs: each thread its own, then the others'
constexpr std::size_t owner_blocks = 16;   // blocks of bodies, each adding its nodes' forces
constexpr std::size_t prefetch_ahead = 8;  // contacts and loads ahead whose nodes are fetched
// With the work shared: a body in part goes to a partner with its segments within this many of its
// element sizes (and each overlap's diagonal) of the overlaps (exchangeHalo).
constexpr double halo_reach = 2.0;
constexpr double kept_softer = 2.0; // with levels: a contact's kept penalty step, at most this
                                    // times a beginning contact's (hit)

double sq(double x) { return x * x; }

// With levels, the level of the pair of bodies A and B (B no_node: a wall): the coarser body's, at
// whose steps it is computed; 0 without.
std::uint8_t pairLevel(const Model &model, std::uint32_t A, std::uint32_t B) {
  if (model.level.empty())
    return 0;
  return B == no_node ? model.level[A] : std::max(model.level[A], model.level[B]);
}

// The settings with one friction coefficient per pair of materials.
ContactSettings frictionPerPair(ContactSettings s, std::size_t n_materials) {
  if (s.friction.size() == 1)
    s.friction.assign(n_materials * n_materials, s.friction[0]);
  if (s.friction.size() != n_materials * n_materials)
    throw std::invalid_argument("contact: friction needs one value or one per pair of materials");
  return s;
}
} // namespace

Contact::Contact(const Model &model, ContactSettings settings)
    : s_(frictionPerPair(std::move(settings), model.materials.size())),
      n_materials_(model.materials.size()), boundaries_(model),
      pairs_(model, boundaries_, runs_per_thread * static_cast<std::size_t>(omp_get_max_threads())),
      allowances_(model.nodes.size()) {
  for (int wall = 0; wall < 2; ++wall) // kappa doubled at a wall (see hit)
    damping_[wall] = dampingCoefficient(s_.damping, wall ? 2.0 * s_.stiffness : s_.stiffness);
  run_hits_.resize(pairs_.runs());
  for (Hits &hits : run_hits_)
    hits.loads.resize(owner_blocks);
  scratch_.resize(static_cast<std::size_t>(omp_get_max_threads()));
  const std::size_t n_bodies = model.bodies.size();
  for (std::size_t b = 0; b < n_bodies; ++b)
    block_.push_back(static_cast<std::uint8_t>(b * owner_blocks / n_bodies));
  block_loaded_.resize(owner_blocks);
  block_pushed_.resize(owner_blocks);
  pushed_.assign(model.nodes.size(), 0.0);
}

// Erosion changed the boundaries of `bodies`: the lists, which hold indices into the boundaries,
// are all taken anew at the next step with a new search for pairs. The overlaps the new
// boundaries have with their neighbours are allowed for (allowOverlaps).
void Contact::boundaryChanged(const Model &model, const std::vector<std::uint32_t> &bodies) {
  const std::vector<std::uint32_t> before = boundaries_.nodes;
  const std::vector<std::size_t> before_begin = boundaries_.node_begin;
  // (a body of another process here in part keeps its box and its points as they came, NaN where
  // none came; one that eroded came whole, its nodes' positions shared)
  std::vector<Box> window_boxes;
  for (const HaloWindow &w : windows_)
    window_boxes.push_back(boundaries_.boxes[w.body]);
  boundaries_.take(model);
  std::vector<HaloWindow> windows;
  for (std::size_t i = 0; i < windows_.size(); ++i) {
    HaloWindow &w = windows_[i];
    window_of_[w.body] = -1;
    if (std::binary_search(bodies.begin(), bodies.end(), w.body))
      continue;
    ContactBoundaries &bd = boundaries_;
    const std::size_t first = bd.node_begin[w.body];
    bd.boxes[w.body] = window_boxes[i];
    for (std::size_t k = first; k < bd.node_begin[w.body + 1]; ++k)
      bd.points[k] = {std::nan(""), std::nan("")};
    for (std::uint32_t k : w.received)
      bd.points[first + k] = {model.nodes.x[bd.nodes[first + k]],
                              model.nodes.y[bd.nodes[first + k]]};
    window_of_[w.body] = static_cast<std::int32_t>(windows.size());
    windows.push_back(std::move(w));
  }
  windows_ = std::move(windows);
  for (std::uint32_t C : bodies)
    allowOverlaps(C, std::vector<std::uint32_t>(before.begin() + before_begin[C],
                                                before.begin() + before_begin[C + 1]));
  pairs_.forget();
}

// The overlaps of body C's new boundary with the bodies of its pairs: their nodes inside C, and
// C's newly bare nodes (not in `before`, its boundary nodes before) inside them, deeper than a
// contact gets in a step (check_depth of an element): each such node's depth is allowed for.
void Contact::allowOverlaps(std::size_t C, const std::vector<std::uint32_t> &before) {
  const ContactBoundaries &bd = boundaries_;
  const std::vector<Point> &points = bd.points;
  Scratch scratch;
  for (const Pair &pair : pairs_.pairs()) {
    if (pair.a != C && pair.b != C)
      continue;
    const std::size_t B = pair.a == C ? pair.b : pair.a;
    const Box region = bd.boxes[C].overlap(bd.boxes[B]);
    for (std::size_t k = bd.node_begin[B]; k < bd.node_begin[B + 1]; ++k)
      if (region.contains(points[k].x, points[k].y))
        if (const double d = penetration(C, points[k].x, points[k].y, scratch);
            d > check_depth * bd.size[C])
          allowances_.allow(bd.nodes[k], d);
    for (std::size_t k = bd.node_begin[C]; k < bd.node_begin[C + 1]; ++k)
      if (region.contains(points[k].x, points[k].y) &&
          !std::binary_search(before.begin(), before.end(), bd.nodes[k]))
        if (const double d = penetration(B, points[k].x, points[k].y, scratch);
            d > check_depth * bd.size[B])
          allowances_.allow(bd.nodes[k], d);
  }
}

// How deep (px, py) lies inside body B: its distance to B's boundary, 0 outside.
double Contact::penetration(std::size_t B, double px, double py, Scratch &scratch) const {
  if (!insideOf(B, px, py))
    return 0.0;
  // every segment of B lies in its box
  nearSegments(B, boundaries_.ends(B), boundaries_.endsEnd(B), boundaries_.boxes[B], scratch.near);
  return std::sqrt(narrow::closest(scratch.near, px, py, nullptr).distance);
}

// A step: the allowances let go by a step's share, the pairs of bodies (broad phase), the contacts
// of each pair and their forces (narrow phase), the walls' contacts, the forces into the nodes.
void Contact::addForces(Model &model, double time, double dt) {
  const auto start = std::chrono::steady_clock::now();
  time_ = time;
  if (!model.due.empty()) { // a pushed depth per level of pair (pushed_)
    if (model.level.size() != model.bodies.size())
      throw std::invalid_argument(
          "contact with levels: Model::level has " + std::to_string(model.level.size()) +
          " entries, not one per body (" + std::to_string(model.bodies.size()) + ")");
    std::size_t levels = 1;
    for (std::uint8_t l : model.level)
      levels = std::max<std::size_t>(levels, l + 1u);
    if (levels > pushed_levels_ || level_pushed_.empty()) { // (the levels so far kept)
      const std::size_t before = level_pushed_.empty() ? 0 : pushed_levels_;
      std::vector<LevelPushed> kept = std::move(level_pushed_);
      pushed_levels_ = std::max(levels, pushed_levels_);
      level_pushed_.assign(pushed_levels_ * model.nodes.size(), LevelPushed{});
      for (std::size_t a = 0; before > 0 && a < model.nodes.size(); ++a)
        std::copy_n(&kept[a * before], before, &levelPushed(a, 0));
    }
  }
  allowances_.release();
  // (with the work shared, each process measures its own bodies, and the pairs' other bodies come
  // from their owners: shareBoxes, exchangeHalo)
  auto own = [&](std::size_t b) { return mine(b); };
  pairs_.measure(model, boundaries_, own);
  double farthest = pairs_.farthest(boundaries_, own);
  // (with the work shared, the largest over the processes decides; none is asked when the pairs
  // are to be found anew anyway, or the last step's reduction bounds it below what needs a search)
  const double bound = std::exchange(travel_bound_, HUGE_VAL);
  if (shared() && !pairs_.searchNeeded(0.0) && pairs_.searchNeeded(bound))
    farthest = processes_->max({farthest})[0];
  const bool anew = pairs_.searchNeeded(farthest);
  if (shared())
    shareBoxes(model, anew);
  if (pairs_.search(model, boundaries_, anew))
    ++stats_.searches;
  if (shared())
    exchangeHalo(model);
  narrowPhase(model, dt);
  walls(model, dt, run_hits_.back());
  addHits(model);
  stats_.max_depth = std::max(stats_.max_depth, stats_.depth);
  stats_.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Each moving body of this process has travelled by at most its body's drift more at the next
// step's measure (ContactBoundaries::measure adds its farthest node's move), and the bodies that
// woke in this step move from there: the farthest of them since the last search, plus the drift
// with room for the rounding of the positions and the sums.
void Contact::stepFigures(const Model &model, double drift, std::vector<double> &figures) const {
  const std::vector<double> &searched = pairs_.travelSearched();
  double most = 0.0;
  for (std::size_t b = 0; b < model.bodies.size(); ++b)
    if (!model.at_rest[b] && mine(b) && boundaries_.hasNodes(b))
      most = std::max(most, boundaries_.travel[b] - searched[b]);
  figures.insert(figures.end(), {most + 1.001 * drift + 1e-9 * pairs_.searchMargin(),
                                 static_cast<double>(woken_.size())});
}

void Contact::stepReduced(Model &model, const double *largest) {
  travel_bound_ = largest[0];
  wakeEverywhere(model, *processes_, woken_, static_cast<std::size_t>(largest[1]));
}

// The narrow phase over the runs of pairs, each with its lists and its hits: taken run by run, the
// hits come in pair order whatever the number of threads. Each thread takes its own consecutive
// runs, then those the others have not taken yet: a run's lists stay in one core's cache from step
// to step, unless that core falls behind.
void Contact::narrowPhase(const Model &model, double dt) {
  const ContactBoundaries &bd = boundaries_;
  const long runs = static_cast<long>(pairs_.runs());
  const bool levels = !model.due.empty();
  std::size_t refreshed = 0, overlapping = 0, skipped = 0, partial = 0;
  const auto threads = static_cast<std::size_t>(omp_get_max_threads());
  run_lists_.reset(threads);
  for (long r = 0; r < runs; ++r)
    run_lists_.list(static_cast<std::size_t>(r) * threads / static_cast<std::size_t>(runs))
        .push_back(static_cast<std::size_t>(r));
#pragma omp parallel if (pairs_.size() > 64) reduction(+ : refreshed, overlapping, skipped, partial)
  {
    Scratch &scratch = scratch_[omp_get_thread_num()];
    const auto me = static_cast<std::size_t>(omp_get_thread_num());
    for (std::size_t r; (r = run_lists_.next(me)) != WorkLists::none;) {
      std::vector<std::uint32_t> &arena = pairs_.arena(r);
      const std::span<Pair> run = pairs_.run(r);
      Hits &hits = run_hits_[r];
      hits.clear();
      for (std::size_t i = 0; i < run.size(); ++i) {
        if (i + prefetch_ahead < run.size())
          prefetchPair(run[i + prefetch_ahead], arena);
        Pair &pair = run[i];
        if (levels && !(model.due[pair.a] && model.due[pair.b]))
          continue;
        if (!mine(pair.a) && !mine(pair.b)) // another process's pair
          continue;
        if (!bd.boxes[pair.a].overlaps(bd.boxes[pair.b]))
          continue;
        ++overlapping;
        // Each boundary node has moved by at most its body's travel since the lists were
        // taken; the overlap by as much as either body; a segment's box by its body's.
        if (2.0 * ((bd.travel[pair.a] - pair.travel_a) + (bd.travel[pair.b] - pair.travel_b)) >
            pair.margin)
          refresh(pair, arena, scratch), ++refreshed;
        // A side is looked at if some of its nodes are hot, or the clear ones may have come
        // into contact (see touch).
        const double travel = bd.travel[pair.a] + bd.travel[pair.b];
        const std::uint32_t *items = arena.data() + pair.begin;
        const std::uint32_t part[5] = {0, pair.end[0], pair.end[1], pair.end[2], pair.end[3]};
        std::uint32_t *hot = arena.data() + pair.begin + pair.end[3];
        const std::uint64_t place = static_cast<std::uint64_t>(&pair - pairs_.pairs().data());
        for (int side = 0; side < 2; ++side) {
          if (!mine(side ? pair.b : pair.a)) // the side of the other process's body
            continue;
          const bool all = !(travel < pair.until[side]);
          if (!all && pair.hot[side] == 0) {
            ++skipped;
            continue;
          }
          partial += !all;
          const std::size_t before = hits.found.size();
          touch(model, side ? pair.b : pair.a, side ? pair.a : pair.b, items + part[2 * side],
                items + part[2 * side + 1], items + part[2 * side + 1], items + part[2 * side + 2],
                travel, pair.until[side], hot + (side ? pair.end[0] : 0), pair.hot[side], hits,
                scratch);
          for (std::size_t j = before; j < hits.found.size(); ++j)
            hits.found[j].order = place << 32 | static_cast<std::uint64_t>(side) << 31 |
                                  static_cast<std::uint64_t>(j - before) << 2;
        }
      }
      // The forces after the search: their nodes' masses and velocities, scattered in memory, are
      // then fetched a few contacts ahead.
      const std::size_t n_found = hits.found.size();
      for (std::size_t i = 0; i < n_found; ++i) {
        if (i + prefetch_ahead < n_found)
          prefetchHit(model, hits.found[i + prefetch_ahead]);
        hit(model, hits.found[i], dt, hits);
      }
    }
  }
  stats_.refreshed += refreshed;
  stats_.sides += 2 * overlapping, stats_.skipped += skipped, stats_.partial += partial;
  stats_.pairs = overlapping;
  stats_.pair_steps += overlapping;
}

std::vector<Contact::BodyContact> Contact::lastContacts() const {
  const ContactBoundaries &bd = boundaries_;
  std::vector<BodyContact> contacts;
  for (const Hits &hits : run_hits_)
    for (const Found &f : hits.found)
      if (f.k1 != no_node)
        contacts.push_back({f.A, bd.nodes[f.k], f.B, {bd.nodes[f.k1], bd.nodes[f.k2]}});
  return contacts;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> Contact::overlappingPairs() const {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> overlapping;
  for (const Pair &pair : pairs_.pairs())
    if ((mine(pair.a) || mine(pair.b)) &&
        boundaries_.boxes[pair.a].overlaps(boundaries_.boxes[pair.b]))
      overlapping.emplace_back(pair.a, pair.b);
  return overlapping;
}

void Contact::Hits::clear() {
  found.clear();
  sudden.clear();
  for (auto &block : loads)
    block.clear();
  count = deep = beneath_folds = 0;
  depth = 0.0;
}

// The contact forces into the nodes, every body loaded woken. Each block of bodies (fixed,
// whatever the number of threads) is one thread's: it adds the forces on its nodes, run by run in
// the order of the contacts, and lists its newly loaded nodes, so that every node sums its forces
// in the same order, and the loaded nodes come block by block, for any number of threads. A
// thread takes a contiguous run of blocks with about its share of the loads: as the solver's
// threads take contiguous runs of bodies, the forces are mostly added on the core that reads them
// next, and the loads, gathered under the tip, are shared evenly.
void Contact::addHits(Model &model) {
  Nodes &nd = model.nodes;
  const std::size_t blocks = block_loaded_.size();
  std::size_t n_loads = 0, contacts = 0, deep_steps = 0;
  double deepest = 0.0;
  std::vector<std::size_t> block_loads(blocks, 0);
  for (const Hits &hits : run_hits_) {
    for (std::size_t k = 0; k < blocks; ++k)
      block_loads[k] += hits.loads[k].size(), n_loads += hits.loads[k].size();
    contacts += hits.count, deep_steps += hits.deep, deepest = std::max(deepest, hits.depth);
  }
  if (shared())
    sendLoads(model);
  const std::vector<std::size_t> bounds =
      contiguousShares(block_loads, static_cast<std::size_t>(omp_get_max_threads()));
#pragma omp parallel if (n_loads > 1024)
  {
    for (auto [k, last] = threadShare(bounds); k < last; ++k)
      addBlock(model, k);
  }
  for (auto &loaded : block_loaded_) {
    nd.loaded.insert(nd.loaded.end(), loaded.begin(), loaded.end());
    loaded.clear();
  }
  // The sudden depths are allowed for, run by run.
  for (const Hits &hits : run_hits_) {
    for (auto [p, excess] : hits.sudden)
      allowances_.allow(p, excess);
    stats_.sudden += hits.sudden.size(), stats_.beneath_folds += hits.beneath_folds;
  }
  stats_.contacts = contacts;
  stats_.depth = deepest;
  stats_.deep += deep_steps;
}

// The loads of block k into the nodes (see addHits).
void Contact::addBlock(Model &model, std::size_t k) {
  Nodes &nd = model.nodes;
  std::uint32_t woken = no_node;
  // the depths the block's nodes are pushed at, for the next step's hits
  // (with levels, a depth carries the time it was pushed at instead: see hit)
  const bool levels = !model.due.empty();
  if (!levels) {
    for (std::uint32_t p : block_pushed_[k])
      pushed_[p] = 0.0;
    block_pushed_[k].clear();
  }
  // With the work shared, this process's loads on its own nodes and those the others sent, merged
  // in the order of their contacts.
  static const std::vector<Load> none;
  const std::vector<Load> &received = block_received_.empty() ? none : block_received_[k];
  std::size_t next = 0;
  auto add = [&](const Load &l) {
    if (levels) {
      if (l.depth > 0.0) { // the softest penalty of the node's contacts of this level and step
        LevelPushed &at = levelPushed(l.node, l.level);
        const bool first = at.time != time_;
        at.penalty = first ? l.penalty_step : std::max(at.penalty, l.penalty_step);
        if (first || l.depth > at.depth)
          at.depth = l.depth, at.time = time_;
      }
    } else if (l.depth > 0.0 && l.depth > pushed_[l.node]) { // (a reaction is pushed at 0)
      if (pushed_[l.node] == 0.0)
        block_pushed_[k].push_back(l.node);
      pushed_[l.node] = l.depth;
    }
    nd.addExternal(l.node, l.fx, l.fy, l.friction_x, l.friction_y, block_loaded_[k]);
    if (l.body != woken) // the loads of a body come together
      model.wake(l.body), woken = l.body;
  };
  for (const Hits &hits : run_hits_)
    for (std::size_t i = 0, n = hits.loads[k].size(); i < n; ++i) {
      const Load &l = hits.loads[k][i];
      if (i + prefetch_ahead < n)
        prefetchLoad(nd, hits.loads[k][i + prefetch_ahead]);
      if (!mine(l.body)) // sent to its owner (sendLoads)
        continue;
      for (; next < received.size() && received[next].order < l.order; ++next)
        add(received[next]);
      add(l);
    }
  for (; next < received.size(); ++next)
    add(received[next]);
}

// With the work shared: the loads on other processes' nodes go to their owners, the processes
// whose bodies share an overlapping pair with this one's (partners_, exchangeHalo; no other can
// have a contact with its nodes), as a message to each of them; the loads this process receives
// wait in block_received_, by block of bodies, in the order of their contacts. A message: per
// load its order, node, fx, fy and frictional part (the doubles' bits). A body at rest that is
// loaded wakes at its owner (addBlock), at the others after the step's reduction (stepReduced).
void Contact::sendLoads(Model &model) {
  const int me = processes_->rank();
  const auto ranks = static_cast<std::size_t>(processes_->size());
  woken_.clear();
  for (const Hits &hits : run_hits_)
    for (const auto &loads : hits.loads)
      for (const Load &l : loads)
        if (model.at_rest[l.body] && (woken_.empty() || woken_.back() != l.body))
          woken_.push_back(l.body);
  std::sort(woken_.begin(), woken_.end());
  woken_.erase(std::unique(woken_.begin(), woken_.end()), woken_.end());
  std::vector<std::vector<std::int64_t>> to(ranks);
  for (const Hits &hits : run_hits_)
    for (const auto &loads : hits.loads)
      for (const Load &l : loads)
        if (const int r = (*owner_)[l.body]; r != me)
          to[static_cast<std::size_t>(r)].insert(
              to[static_cast<std::size_t>(r)].end(),
              {static_cast<std::int64_t>(l.order), l.node, std::bit_cast<std::int64_t>(l.fx),
               std::bit_cast<std::int64_t>(l.fy), std::bit_cast<std::int64_t>(l.friction_x),
               std::bit_cast<std::int64_t>(l.friction_y)});
  const std::vector<std::vector<std::int64_t>> from =
      processes_->exchangeWith(std::move(to), partners_);
  for (auto &loads : block_received_)
    loads.clear();
  for (std::size_t r = 0; r < ranks; ++r) {
    if (static_cast<int>(r) == me)
      continue;
    const std::vector<std::int64_t> &message = from[r];
    for (std::size_t i = 0; i + 6 <= message.size(); i += 6) {
      const auto node = static_cast<std::uint32_t>(message[i + 1]);
      const std::uint32_t body = model.nodes.body[node];
      block_received_[block_[body]].push_back(
          {node, body, std::bit_cast<double>(message[i + 2]), std::bit_cast<double>(message[i + 3]),
           std::bit_cast<double>(message[i + 4]), std::bit_cast<double>(message[i + 5]), 0.0,
           static_cast<std::uint64_t>(message[i])});
    }
  }
  for (auto &loads : block_received_)
    std::sort(loads.begin(), loads.end(),
              [](const Load &a, const Load &b) { return a.order < b.order; });
}

// With the work shared: the moving bodies' boxes and travel from their owners, who measured them,
// where they are needed, so that every process finds the same pairs in the same order as one
// would. At a search (`anew`) every process needs every moving body's: an all-gather. Between
// searches the pairs stay, and a process needs those of the other processes' bodies its pairs hold,
// and those of the bodies that woke since the last step (every process finds their pairs with the
// bodies at rest: to all).
void Contact::shareBoxes(const Model &model, bool anew) {
  ContactBoundaries &bd = boundaries_;
  constexpr std::size_t values = ContactBoundaries::box_values;
  const auto ranks = static_cast<std::size_t>(processes_->size());
  auto owner = [&](std::uint32_t b) { return (*owner_)[b]; };
  if (anew) { // (every process knows every moving body's owner: how many values each gives)
    std::vector<double> mine_boxes;
    std::vector<std::int64_t> sizes(ranks, 0);
    for (std::uint32_t b : pairs_.moving()) {
      sizes[static_cast<std::size_t>(owner(b))] += values;
      if (mine(b))
        for (double v : bd.boxAndTravel(b))
          mine_boxes.push_back(v);
    }
    const std::vector<double> all = processes_->allGather(std::move(mine_boxes), sizes);
    std::vector<const double *> from(ranks); // where each process's values are next
    for (std::size_t r = 0, at = 0; r < ranks; at += static_cast<std::size_t>(sizes[r++]))
      from[r] = all.data() + at;
    for (std::uint32_t b : pairs_.moving()) {
      const double *&in = from[static_cast<std::size_t>(owner(b))];
      bd.setBoxAndTravel(b, in);
      in += values;
    }
    return;
  }
  const int me = processes_->rank();
  BodiesTo sends, receives;
  auto share = [&](std::uint32_t b, int with) { // b's box to process `with`, if b moves
    if (model.at_rest[b] || owner(b) == with)
      return;
    if (mine(b))
      sends.emplace_back(with, b);
    else if (with == me)
      receives.emplace_back(owner(b), b);
  };
  for (const Pair &pair : pairs_.pairs())
    share(pair.a, owner(pair.b)), share(pair.b, owner(pair.a));
  const std::vector<char> &listed = pairs_.listed();
  for (std::uint32_t b : pairs_.moving())
    if (!listed[b])
      for (std::size_t r = 0; r < ranks; ++r)
        share(b, static_cast<int>(r));
  sendBodies(
      std::move(sends), std::move(receives), [](std::uint32_t) { return values; },
      [&](std::uint32_t b, std::int64_t *out) {
        for (double v : bd.boxAndTravel(b))
          *out++ = std::bit_cast<std::int64_t>(v);
      },
      [&](std::uint32_t b, const std::int64_t *in) {
        double box[values];
        for (std::size_t k = 0; k < values; ++k)
          box[k] = std::bit_cast<double>(in[k]);
        bd.setBoxAndTravel(b, box);
      });
}

// With the work shared: the pairs whose boxes overlap and whose bodies two processes own are
// computed by both (each its own body's side); each sends the other its body's boundary nodes,
// position and velocity (Model::nodes and the boundary's points). A body of at least
// ContactSettings::halo_in_part_from boundary nodes (the projectile) goes in part when that is less
// than 3/4 of them:
// the ends of its segments that meet the window, the box around the overlaps of its pairs with the
// partner's bodies widened by halo_reach of its element size, with the window and whether its
// lower-left corner lies inside the body (the owner's crossing count). There the others' points
// are NaN until the next exchange (no near segment), and insideOf counts the crossings from that
// corner: a node in the window is inside by the corner's answer and the parity of the segments
// between them, all of which meet the window. A contact's node, its closest segment and the
// segments the lists hold lie within the window, unless a node is deeper than about the reach;
// a node found clear is clear at most until it could reach the window's edge (touch).
void Contact::exchangeHalo(Model &model) {
  ContactBoundaries &bd = boundaries_;
  Nodes &nd = model.nodes;
  const int me = processes_->rank();
  const auto ranks = static_cast<std::size_t>(processes_->size());
  // per (partner, own body): the box around the overlaps with the partner's bodies; and the
  // partners' bodies that come, (partner, body) in order as they come
  std::vector<std::pair<std::pair<int, std::uint32_t>, Box>> sends;
  BodiesTo receives;
  partners_.clear();
  const bool levels = !model.due.empty();
  for (const Pair &pair : pairs_.pairs()) {
    const int owner_a = (*owner_)[pair.a], owner_b = (*owner_)[pair.b];
    if (owner_a == owner_b || (owner_a != me && owner_b != me) ||
        !bd.boxes[pair.a].overlaps(bd.boxes[pair.b]))
      continue;
    // (with levels, the pairs due at this step alone: no other is computed, narrowPhase)
    if (levels && !(model.due[pair.a] && model.due[pair.b]))
      continue;
    const int partner = owner_a == me ? owner_b : owner_a;
    sends.push_back(
        {{partner, owner_a == me ? pair.a : pair.b}, bd.boxes[pair.a].overlap(bd.boxes[pair.b])});
    receives.emplace_back(partner, owner_a == me ? pair.b : pair.a);
    partners_.push_back(partner);
  }
  std::sort(partners_.begin(), partners_.end());
  partners_.erase(std::unique(partners_.begin(), partners_.end()), partners_.end());
  std::sort(sends.begin(), sends.end(),
            [](const auto &p, const auto &q) { return p.first < q.first; });
  std::sort(receives.begin(), receives.end());
  receives.erase(std::unique(receives.begin(), receives.end()), receives.end());
  for (const HaloWindow &w : windows_)
    window_of_[w.body] = -1;
  windows_.clear();
  // A body's message: its nodes' values (4 each); one that may go in part first says
  // how many come, -1 for all, and if not all the window (4 values), the corner's side (1) and
  // before each node's values its position in the body's boundary nodes.
  auto may_part = [&](std::size_t n) {
    return s_.halo_in_part_from > 0 && n >= static_cast<std::size_t>(s_.halo_in_part_from);
  };
  std::vector<std::vector<std::int64_t>> to(ranks);
  std::vector<std::uint32_t> sent; // positions in the body's boundary nodes
  for (std::size_t i = 0; i < sends.size();) {
    const auto [partner, b] = sends[i].first;
    // (each overlap widened by its diagonal: a pair's lists can hold a segment as far from a node
    // in the overlap as the node's clearance, which is at most about that)
    auto reach = [&](const Box &o) {
      return o.widened(std::hypot(o.x1 - o.x0, o.y1 - o.y0) + halo_reach * bd.size[b]);
    };
    Box window = reach(sends[i].second);
    for (++i; i < sends.size() && sends[i].first == sends[i - 1].first; ++i) {
      const Box o = reach(sends[i].second);
      window = {std::min(window.x0, o.x0), std::min(window.y0, o.y0), std::max(window.x1, o.x1),
                std::max(window.y1, o.y1)};
    }
    std::vector<std::int64_t> &message = to[static_cast<std::size_t>(partner)];
    const std::size_t first = bd.node_begin[b], n = bd.node_begin[b + 1] - first;
    auto put = [&](std::size_t k) {
      const std::uint32_t node = bd.nodes[k];
      for (double v : {nd.x[node], nd.y[node], nd.vx[node], nd.vy[node]})
        message.push_back(std::bit_cast<std::int64_t>(v));
    };
    sent.clear();
    if (may_part(n)) {
      for (const std::uint32_t *e = bd.ends(b); e != bd.endsEnd(b); e += 2) {
        const Point &p = bd.points[e[0]], &q = bd.points[e[1]];
        if (window.meets(p.x, p.y, q.x, q.y))
          sent.insert(sent.end(), {static_cast<std::uint32_t>(e[0] - first),
                                   static_cast<std::uint32_t>(e[1] - first)});
      }
      std::sort(sent.begin(), sent.end());
      sent.erase(std::unique(sent.begin(), sent.end()), sent.end());
    }
    const bool whole = !may_part(n) || 4 * sent.size() >= 3 * n;
    if (may_part(n))
      message.push_back(whole ? -1 : static_cast<std::int64_t>(sent.size()));
    if (whole) {
      for (std::size_t k = first; k < first + n; ++k)
        put(k);
      continue;
    }
    for (double v : {window.x0, window.y0, window.x1, window.y1})
      message.push_back(std::bit_cast<std::int64_t>(v));
    message.push_back(bd.inside(b, window.x0, window.y0) ? 1 : 0);
    for (std::uint32_t k : sent) {
      message.push_back(k);
      put(first + k);
    }
  }
  const std::vector<std::vector<std::int64_t>> from =
      processes_->exchangeWith(std::move(to), partners_);
  auto take = [&](std::size_t k, const std::int64_t *in) {
    const std::uint32_t node = bd.nodes[k];
    nd.x[node] = std::bit_cast<double>(in[0]), nd.y[node] = std::bit_cast<double>(in[1]);
    nd.vx[node] = std::bit_cast<double>(in[2]), nd.vy[node] = std::bit_cast<double>(in[3]);
  };
  std::vector<std::size_t> at(ranks, 0); // where each partner's message is read next
  for (auto [partner, b] : receives) {
    const std::vector<std::int64_t> &message = from[static_cast<std::size_t>(partner)];
    std::size_t &i = at[static_cast<std::size_t>(partner)];
    const std::size_t first = bd.node_begin[b], n = bd.node_begin[b + 1] - first;
    const std::int64_t m = may_part(n) ? message[i++] : -1;
    if (m < 0) {
      for (std::size_t k = first; k < first + n; ++k, i += 4)
        take(k, &message[i]);
      bd.place(model, b);
      stats_.halo_nodes += n;
      continue;
    }
    HaloWindow w{b,
                 {std::bit_cast<double>(message[i]), std::bit_cast<double>(message[i + 1]),
                  std::bit_cast<double>(message[i + 2]), std::bit_cast<double>(message[i + 3])},
                 message[i + 4] != 0,
                 {}};
    i += 5;
    for (std::size_t k = first; k < first + n; ++k)
      bd.points[k] = {std::nan(""), std::nan("")};
    for (std::int64_t j = 0; j < m; ++j, i += 5) {
      const std::size_t k = first + static_cast<std::size_t>(message[i]);
      take(k, &message[i + 1]);
      bd.points[k] = {nd.x[bd.nodes[k]], nd.y[bd.nodes[k]]};
      w.received.push_back(static_cast<std::uint32_t>(k - first));
    }
    stats_.halo_nodes += static_cast<std::size_t>(m);
    window_of_[b] = static_cast<std::int32_t>(windows_.size());
    windows_.push_back(std::move(w));
  }
}

// Whether (px, py) lies inside body B: the crossing count, or for a body here in part (its window
// holds the point) the parity of the crossings between the window's lower-left corner and the
// point and the corner's answer (exchangeHalo).
bool Contact::insideOf(std::size_t B, double px, double py) const {
  const ContactBoundaries &bd = boundaries_;
  if (window_of_.empty() || window_of_[B] < 0)
    return bd.inside(B, px, py);
  const HaloWindow &w = windows_[static_cast<std::size_t>(window_of_[B])];
  const double cx = w.box.x0, cy = w.box.y0;
  auto side = [](double ax, double ay, double bx, double by, double x, double y) {
    return (bx - ax) * (y - ay) - (by - ay) * (x - ax) > 0.0;
  };
  bool in = w.corner_inside;
  for (const std::uint32_t *e = bd.ends(B); e != bd.endsEnd(B); e += 2) {
    const Point &a = bd.points[e[0]], &b = bd.points[e[1]];
    if (std::isnan(a.x) || std::isnan(b.x))
      continue;
    if (side(cx, cy, px, py, a.x, a.y) != side(cx, cy, px, py, b.x, b.y) &&
        side(a.x, a.y, b.x, b.y, cx, cy) != side(a.x, a.y, b.x, b.y, px, py))
      in = !in;
  }
  return in;
}

// The distance from (px, py) to the edge of the window body B came in here (exchangeHalo;
// infinite for a body here whole): its segments beyond lie at least as far.
double Contact::windowClearance(std::size_t B, double px, double py) const {
  if (window_of_.empty() || window_of_[B] < 0)
    return HUGE_VAL;
  return windows_[static_cast<std::size_t>(window_of_[B])].box.edgeDistance(px, py);
}

// With the work shared: `count(b)` values of each body of `sends` (its process, the body), packed
// by `pack(b, out)`, go to that process, and those of `receives` come from theirs, unpacked by
// `unpack(b, in)`. Both sides know the lists (the pairs, the boxes and the owners): messages alone,
// body after body in (process, body) order.
template <class Count, class Pack, class Unpack>
void Contact::sendBodies(BodiesTo sends, BodiesTo receives, Count count, Pack pack,
                         Unpack unpack) const {
  for (auto *list : {&sends, &receives}) {
    std::sort(list->begin(), list->end());
    list->erase(std::unique(list->begin(), list->end()), list->end());
  }
  const auto ranks = static_cast<std::size_t>(processes_->size());
  std::vector<std::int64_t> sizes(ranks, 0);
  for (auto [r, b] : receives)
    sizes[static_cast<std::size_t>(r)] += static_cast<std::int64_t>(count(b));
  std::vector<std::vector<std::int64_t>> to(ranks);
  for (auto [r, b] : sends) {
    std::vector<std::int64_t> &message = to[static_cast<std::size_t>(r)];
    const std::size_t at = message.size();
    message.resize(at + count(b));
    pack(b, message.data() + at);
  }
  const std::vector<std::vector<std::int64_t>> from = processes_->exchange(std::move(to), sizes);
  std::vector<std::size_t> at(ranks, 0);
  for (auto [r, b] : receives) {
    const auto q = static_cast<std::size_t>(r);
    unpack(b, from[q].data() + at[q]);
    at[q] += count(b);
  }
}

void Contact::shareWork(const parallel::Communicator &processes, const std::vector<int> &owner) {
  processes_ = &processes, owner_ = &owner;
  block_received_.assign(owner_blocks, {});
  window_of_.assign(owner.size(), -1);
  windows_.clear();
}

// Bodies about to change owner: their box and travel, and the depths their nodes were pushed at and
// their allowances, kept by their owner only, go to their new owner, who places their boundaries
// where their old owner measured them this step (their nodes came with them: Solver::repartition);
// every side of every pair is looked at whole at the next step (its clear nodes were measured by
// the process that computed it). With levels a node's depth is kept per level of pair, with the
// time it was pushed at and its contact's penalty step.
void Contact::bodiesMoving(const Model &model, const std::vector<std::uint32_t> &bodies,
                           const std::vector<int> &new_owner) {
  if (!shared())
    return;
  const bool levels = !level_pushed_.empty();
  const std::size_t depths = levels ? pushed_levels_ : 1;
  // per node: allowance, release per step, the pushed depths (with levels, each with its time
  // and penalty step)
  const std::size_t values = 2 + (levels ? 3 : 1) * depths;
  constexpr std::size_t body_values = ContactBoundaries::box_values; // per body: box, travel
  ContactBoundaries &bd = boundaries_;
  parallel::moveValues(
      *processes_, bodies.size(), [&](std::size_t k) { return (*owner_)[bodies[k]]; },
      [&](std::size_t k) { return new_owner[bodies[k]]; },
      [&](std::size_t k) {
        return body_values +
               values * (model.bodies[bodies[k]].node_end - model.bodies[bodies[k]].node_begin);
      },
      [&](std::size_t k, double *out) {
        const Body &body = model.bodies[bodies[k]];
        for (double v : bd.boxAndTravel(bodies[k]))
          *out++ = v;
        for (std::size_t a = body.node_begin; a < body.node_end; ++a) {
          const auto p = static_cast<std::uint32_t>(a);
          const double allowance = allowances_.of(p);
          *out++ = allowance, *out++ = allowance > 0.0 ? allowances_.rate(p) : 0.0;
          if (!levels)
            *out++ = pushed_[a];
          for (std::size_t l = 0; levels && l < depths; ++l) {
            const LevelPushed &at = levelPushed(a, l);
            *out++ = at.depth, *out++ = at.time, *out++ = at.penalty;
          }
        }
      },
      [&](std::size_t k, const double *in) {
        const std::uint32_t b = bodies[k];
        bd.setBoxAndTravel(b, in);
        in += body_values;
        for (std::size_t a = model.bodies[b].node_begin; a < model.bodies[b].node_end; ++a) {
          const auto p = static_cast<std::uint32_t>(a);
          if (in[0] > 0.0 || allowances_.of(p) > 0.0)
            allowances_.set(p, in[0], in[1]);
          in += 2;
          if (!levels) {
            if (in[0] != 0.0 && pushed_[a] == 0.0)
              block_pushed_[block_[b]].push_back(p);
            pushed_[a] = *in++;
            continue;
          }
          for (std::size_t l = 0; l < depths; ++l, in += 3)
            levelPushed(a, l) = {in[0], in[1], in[2]};
        }
        bd.place(model, b);
      });
  for (std::size_t r = 0; r < pairs_.runs(); ++r)
    for (Pair &pair : pairs_.run(r))
      pair.until[0] = pair.until[1] = 0.0, pair.hot[0] = pair.hot[1] = 0;
}

ContactStatistics Contact::statisticsOfAll() const {
  if (!shared())
    return stats_;
  const ContactStatistics &s = stats_;
  const std::vector<std::int64_t> counts = processes_->allGather(std::vector<std::int64_t>{
      static_cast<std::int64_t>(s.pairs), static_cast<std::int64_t>(s.contacts),
      static_cast<std::int64_t>(s.deep), static_cast<std::int64_t>(s.refreshed),
      static_cast<std::int64_t>(s.searches), static_cast<std::int64_t>(s.pair_steps),
      static_cast<std::int64_t>(s.sides), static_cast<std::int64_t>(s.skipped),
      static_cast<std::int64_t>(s.partial), static_cast<std::int64_t>(s.sudden),
      static_cast<std::int64_t>(s.beneath_folds)});
  const std::vector<double> depths =
      processes_->allGather(std::vector<double>{s.depth, s.max_depth, s.seconds});
  ContactStatistics all;
  for (std::size_t at = 0; at < counts.size(); at += 11) {
    all.pairs += counts[at], all.contacts += counts[at + 1], all.deep += counts[at + 2];
    all.refreshed += counts[at + 3];
    all.searches = std::max(all.searches, static_cast<std::size_t>(counts[at + 4]));
    all.pair_steps += counts[at + 5], all.sides += counts[at + 6], all.skipped += counts[at + 7];
    all.partial += counts[at + 8], all.sudden += counts[at + 9];
    all.beneath_folds += counts[at + 10];
  }
  for (std::size_t at = 0; at < depths.size(); at += 3) {
    all.depth = std::max(all.depth, depths[at]);
    all.max_depth = std::max(all.max_depth, depths[at + 1]);
    all.seconds = std::max(all.seconds, depths[at + 2]);
  }
  return all;
}

// A pair's lists, taken in the overlap of the two boxes widened by the margin: the nodes of each
// body that are inside the other or closer to its boundary than the margin, and the segments that
// may be the closest to one of them until the lists are taken again. In place in the arena if they
// fit, else at its end with room to grow.
void Contact::refresh(Pair &pair, std::vector<std::uint32_t> &arena, Scratch &scratch) const {
  const ContactBoundaries &bd = boundaries_;
  const std::size_t a = pair.a, b = pair.b;
  const double margin = list_margin * std::min(bd.size[a], bd.size[b]);
  const Box region = bd.boxes[a].overlap(bd.boxes[b]).widened(margin);
  std::vector<std::uint32_t> &items = scratch.items;
  items.clear();
  pair.end[0] = listNear(a, b, region, margin, scratch);
  pair.end[1] = static_cast<std::uint32_t>(items.size());
  pair.end[2] = listNear(b, a, region, margin, scratch);
  pair.end[3] = static_cast<std::uint32_t>(items.size());
  // after the lists, room for the hot nodes of each side
  const std::size_t room = items.size() + pair.end[0] + (pair.end[2] - pair.end[1]);
  if (room > pair.capacity) {
    pair.begin = static_cast<std::uint32_t>(arena.size());
    pair.capacity = static_cast<std::uint32_t>(room + room / 2 + 8);
    arena.resize(arena.size() + pair.capacity);
  }
  std::copy(items.begin(), items.end(), arena.begin() + pair.begin);
  pair.travel_a = bd.travel[a], pair.travel_b = bd.travel[b], pair.margin = margin;
  pair.until[0] = pair.until[1] = 0.0, pair.hot[0] = pair.hot[1] = 0; // all to be looked at
}

// Appends to scratch.items body A's nodes in the rectangle that are behind their closest segment
// of body B or nearer to it than `margin`, then (as node pairs) B's segments that are nearer to
// one of them than its closest segment plus `margin` (for a node about as deep as the margin,
// sought among all of B's segments). While the two bodies move by less than margin / 2 together,
// these hold every node that can come into contact and its closest segment.
// Returns the end of the nodes.
std::uint32_t Contact::listNear(std::size_t A, std::size_t B, const Box &region, double margin,
                                Scratch &scratch) const {
  const ContactBoundaries &bd = boundaries_;
  const Box wide = nearSegments(B, bd.ends(B), bd.endsEnd(B), region, scratch.near);
  const Near &near = scratch.near;
  std::vector<std::uint32_t> &items = scratch.items;
  std::vector<double> &distance = scratch.distance;
  std::vector<std::uint64_t> &beyond = scratch.beyond; // segments beyond `wide` (ends as one key)
  distance.resize(near.size);
  scratch.keep.assign(near.size, 0);
  beyond.clear();
  for (std::size_t k = bd.node_begin[A]; k < bd.node_begin[A + 1] && near.count > 0; ++k) {
    const double px = bd.points[k].x, py = bd.points[k].y;
    if (!region.contains(px, py))
      continue;
    const narrow::Closest c = narrow::closest(near, px, py, distance.data());
    double clearance = std::sqrt(c.distance);
    if (clearance >= margin && c.g >= 0.0)
      continue;
    items.push_back(static_cast<std::uint32_t>(k));
    // A node behind B's boundary whose segments within its clearance plus the margin may reach
    // beyond the edge of `wide` (a node about as deep as the margin): those are sought among all
    // of B's segments (a segment beyond lies at least wide.edgeDistance from the node).
    if (c.g < 0.0 && clearance + margin > wide.edgeDistance(px, py)) {
      const Near &around = scratch.node_near;
      const double r = clearance + margin;
      nearSegments(B, bd.ends(B), bd.endsEnd(B), Box{px - r, py - r, px + r, py + r},
                   scratch.node_near);
      clearance = std::sqrt(narrow::closest(around, px, py, nullptr).distance);
      for (std::size_t i = 0; i < around.size; ++i) {
        if (!around.in(i))
          continue;
        // (the test of narrow::nearSegments on the same points: a segment is in `near` or here)
        const Point &a = bd.points[around.ends[2 * i]], &b = bd.points[around.ends[2 * i + 1]];
        if (!wide.meets(a.x, a.y, b.x, b.y) &&
            around[i].foot(px, py).distance < sq(clearance + margin))
          beyond.push_back(std::uint64_t{around.ends[2 * i]} << 32 | around.ends[2 * i + 1]);
      }
    }
    const double reach = sq(clearance + margin);
    for (std::size_t i = 0; i < near.size; ++i)
      scratch.keep[i] |= distance[i] < reach;
  }
  const auto nodes_end = static_cast<std::uint32_t>(items.size());
  for (std::size_t i = 0; i < near.size; ++i)
    if (scratch.keep[i])
      items.push_back(near.ends[2 * i]), items.push_back(near.ends[2 * i + 1]);
  std::sort(beyond.begin(), beyond.end());
  beyond.erase(std::unique(beyond.begin(), beyond.end()), beyond.end());
  for (const std::uint64_t ends : beyond)
    items.push_back(static_cast<std::uint32_t>(ends >> 32)),
        items.push_back(static_cast<std::uint32_t>(ends));
  return nodes_end;
}

// (see narrow::nearSegments; the reach: see touch)
MESOPEN_INLINE Contact::Box Contact::nearSegments(std::size_t body, const std::uint32_t *ends,
                                                  const std::uint32_t *ends_end, const Box &region,
                                                  Near &near) const {
  const Box wide = region.widened(check_depth * boundaries_.size[body]);
  narrow::nearSegments(boundaries_.points.data(), ends, ends_end, wide, near);
  return wide;
}

// The boundary nodes of body A that are inside body B, among A's `nodes` and B's `segments` (from
// the pair's list), into `hits`. A node inside B is in the overlap of the two boxes; the segment
// that decides is the closest to it.
// A node found outside B, at least a distance g from it, stays outside while the two bodies
// travel together by less than g (a node and a point of B's boundary move by at most their
// body's travel): it is clear until the pair's travel `travel` now plus g. g is,
// for a node outside the overlap, its distance to B's box; for one in it, its distance to the
// closest near segment, or to the edge of the region the near segments cover if that is less.
// The other nodes (in contact, touching, or by a vertex whose other segment is not near) are hot:
// they are looked at every step. So all nodes are looked at when `travel` reaches `until` (the
// least travel up to which every node last found clear stays clear), else the `n_hot` nodes in
// `hot` (positions in `nodes`) alone; both are updated.
MESOPEN_INLINE void Contact::touch(const Model &model, std::size_t A, std::size_t B,
                                   const std::uint32_t *nodes, const std::uint32_t *nodes_end,
                                   const std::uint32_t *ends, const std::uint32_t *ends_end,
                                   double travel, double &until, std::uint32_t *hot,
                                   std::uint32_t &n_hot, Hits &hits, Scratch &scratch) const {
  const ContactBoundaries &bd = boundaries_;
  // A node inside B is in the overlap of the two boxes: the listed nodes there, if any, are
  // checked against the segments within `reach` of the overlap (a node behind one of them by less
  // than `reach` finds its closest segment among them; a node farther from them than from the
  // edge of the region they cover seeks it among all the listed segments; deeper contacts are
  // confirmed by the crossing count).
  const Box &box = bd.boxes[B];
  const Box region = bd.boxes[A].overlap(box);
  std::vector<std::uint32_t> &candidates = scratch.candidates; // positions in `nodes`
  candidates.clear();
  const bool all = !(travel < until);
  double clear = all ? HUGE_VAL : until;
  auto look = [&](std::uint32_t i) {
    const Point &p = bd.points[nodes[i]];
    if (region.contains(p.x, p.y))
      candidates.push_back(i);
    else // outside B's box: at least as far from B as the largest of the coordinate gaps
      clear = std::min(clear, travel + std::max(std::max(box.x0 - p.x, p.x - box.x1),
                                                std::max(box.y0 - p.y, p.y - box.y1)));
  };
  if (all)
    for (std::uint32_t i = 0; i < static_cast<std::uint32_t>(nodes_end - nodes); ++i)
      look(i);
  else
    for (std::uint32_t j = 0; j < n_hot; ++j)
      look(hot[j]);
  n_hot = 0;
  until = clear;
  if (candidates.empty())
    return;
  const double h = bd.size[B];
  const Box wide = nearSegments(B, ends, ends_end, region, scratch.near);
  const Near &near = scratch.near;
  if (near.count == 0) {
    std::copy(candidates.begin(), candidates.end(), hot);
    n_hot = static_cast<std::uint32_t>(candidates.size());
    return;
  }
  const double mu = s_.friction[bd.material[A] * n_materials_ + bd.material[B]];
  for (const std::uint32_t i : candidates) {
    const std::uint32_t k = nodes[i];
    const double px = bd.points[k].x, py = bd.points[k].y;
    // The near segments cover `wide`: a segment left out lies at least `edge` from the node.
    double edge = wide.edgeDistance(px, py);
    // The closest point of B's boundary among `near`: on a segment's inside (the node is in
    // contact when behind it) or a vertex (when behind its vertex normal; see atVertex).
    // w2: the weight of the segment's end, set if the node meets a vertex, else along / length.
    const Near *searched = &near;
    narrow::Closest c;
    double depth = 0.0, nx = 0.0, ny = 0.0, w2 = -1.0;
    using narrow::At;
    auto locate = [&]() {
      c = narrow::closest(*searched, px, py, nullptr);
      if (c.segment == no_node)
        return At::unknown;
      depth = 0.0, w2 = -1.0;
      const At at = narrow::atInside(*searched, c)
                        ? At::segment
                        : narrow::atVertex(*searched, bd.points.data(), bd.pinched.data(), c, px,
                                           py, depth, nx, ny, w2);
      if (at == At::segment)
        depth = -c.g, nx = searched->nx[c.segment], ny = searched->ny[c.segment];
      return at;
    };
    At at = locate();
    // Farther from the closest near segment than from the edge of `wide` (a node deeper than the
    // reach at the edge of the overlap, or clear by more; or beyond a segment's end whose other
    // segment at that vertex is left out): B's closest segment may be one left out, beyond the
    // edge, and the node's depth, or its side of B, other than measured (an eroding tip, a dented
    // grain). Sought again among all the pair's listed segments within that distance of the node.
    if (c.segment != no_node && !(c.distance < edge * edge)) {
      const double d = std::sqrt(c.distance);
      nearSegments(B, ends, ends_end, Box{px - d, py - d, px + d, py + d}, scratch.node_near);
      searched = &scratch.node_near, edge = d;
      at = locate();
    }
    if (at == At::unknown) { // none near, or beyond a segment's end, the other segment not near
      hot[n_hot++] = i;
      continue;
    }
    // Outside B, the node is as far from it as from the closest point found, or from the edge
    // of the region the near segments cover (the segments beyond lie beyond it).
    auto outside = [&] {
      until = std::min(
          until, travel + std::min({std::sqrt(c.distance), edge, windowClearance(B, px, py)}));
    };
    const Near &found = *searched;
    bool counted_inside = false; // inside B by the crossing count, already counted
    if (depth < 0.0) {           // in front of the closest segment or vertex
      // Just in front of it (clear of it: a node on B's boundary has no sure side by the
      // crossing count), yet behind another segment about as close and inside B by the crossing
      // count: B's boundary is folded over itself there (a flap of an eroding tip pressed into
      // the body beneath, which has no contact with itself), the closest segment the fold's. The
      // node is in contact with the closest segment it lies behind, beneath the fold; taken for
      // the closest, the fold would let it sink into B unseen.
      const bool near_fold = touching * h < -depth && -depth < check_depth * h;
      const narrow::Closest beneath =
          near_fold ? narrow::closestBehind(found, px, py, -depth + check_depth * h)
                    : narrow::Closest{};
      if (beneath.segment == no_node || !(counted_inside = insideOf(B, px, py))) {
        outside();
        continue;
      }
      c = beneath, depth = -c.g, w2 = -1.0;
      nx = found.nx[c.segment], ny = found.ny[c.segment];
      ++hits.beneath_folds;
    }
    if (depth <= touching * h ||
        (depth > check_depth * h && !counted_inside && !insideOf(B, px, py))) {
      // touching only; or deeper than a few percent of an element, where a dented grain can put
      // a node outside it behind one of its segments: the crossing count decides
      if (depth > check_depth * h)
        outside();
      else
        hot[n_hot++] = i;
      continue;
    }
    hot[n_hot++] = i;
    if (const double allowed = allowances_.of(bd.nodes[k]);
        allowed > 0.0 && (depth -= allowed) <= touching * h)
      continue; // a depth allowed for (erosion's overlap, a sudden depth), still opening
    hits.found.push_back({static_cast<std::uint32_t>(A), k, static_cast<std::uint32_t>(B),
                          found.ends[2 * c.segment], found.ends[2 * c.segment + 1],
                          w2 < 0.0 ? c.along / found.length[c.segment] : w2, nx, ny, depth, h, mu,
                          0});
  }
}

// The rigid walls: a boundary node of a moving body beyond a wall is pushed back along its normal.
void Contact::walls(const Model &model, double dt, Hits &hits) const {
  const ContactBoundaries &bd = boundaries_;
  const bool left = !std::isnan(s_.wall_left), right = !std::isnan(s_.wall_right),
             bottom = !std::isnan(s_.wall_bottom);
  if (!left && !right && !bottom)
    return;
  // (after every pair's contacts, in the order of the bodies and their nodes)
  std::uint64_t order = static_cast<std::uint64_t>(pairs_.size()) << 32;
  for (std::uint32_t b : pairs_.moving()) {
    if ((!model.due.empty() && !model.due[b]) || !mine(b))
      continue;
    const Box &box = bd.boxes[b];
    if (!(left && box.x0 < s_.wall_left) && !(right && box.x1 > s_.wall_right) &&
        !(bottom && box.y0 < s_.wall_bottom))
      continue;
    const double h = bd.size[b];
    for (std::size_t k = bd.node_begin[b]; k < bd.node_begin[b + 1]; ++k) {
      const double x = bd.points[k].x, y = bd.points[k].y;
      for (auto [on, depth, nx, ny] : {std::tuple{left, s_.wall_left - x, 1.0, 0.0},
                                       {right, x - s_.wall_right, -1.0, 0.0},
                                       {bottom, s_.wall_bottom - y, 0.0, 1.0}})
        if (on && depth > touching * h)
          if (on && depth > touching * h) {
            hit(model,
                {b, static_cast<std::uint32_t>(k), no_node, no_node, no_node, 0.0, nx, ny, depth, h,
                 s_.wall_friction, order},
                dt, hits);
            order += 4;
          }
    }
  }
}

// Prefetching (a fast path: without it the results are the same). The lists of a pair ahead, its
// second body's box (scattered in memory).
void Contact::prefetchPair(const Pair &pair, const std::vector<std::uint32_t> &arena) const {
  __builtin_prefetch(&boundaries_.boxes[pair.b]);
  __builtin_prefetch(arena.data() + pair.begin);
  __builtin_prefetch(arena.data() + pair.begin + pair.end[3]);
}

// The nodal sums a load ahead adds to.
void Contact::prefetchLoad(const Nodes &nd, const Load &load) {
  __builtin_prefetch(&nd.external[load.node], 1);
  __builtin_prefetch(&nd.is_loaded[load.node], 1);
}

// The nodal data a contact's force reads (scattered: one line per node and array), fetched ahead.
void Contact::prefetchHit(const Model &model, const Found &f) const {
  const ContactBoundaries &bd = boundaries_;
  const Nodes &nd = model.nodes;
  for (std::uint32_t k : {f.k, f.k1, f.k2}) {
    if (k == no_node)
      break;
    const std::uint32_t p = bd.nodes[k];
    __builtin_prefetch(&nd.mass[p]), __builtin_prefetch(&nd.vx[p]), __builtin_prefetch(&nd.vy[p]);
  }
  if (!model.due.empty()) { // the node's pushed depths, all levels (hit)
    const LevelPushed *at = &levelPushed(bd.nodes[f.k], 0);
    __builtin_prefetch(at), __builtin_prefetch(at + pushed_levels_ - 1);
  } else
    __builtin_prefetch(&pushed_[bd.nodes[f.k]]);
}

// The force of a contact (the first `touching` h of the depth is free), relative velocities at
// mid-step; the reaction goes to the segment's nodes by weights 1 - w2, w2.
MESOPEN_INLINE void Contact::hit(const Model &model, const Found &f, double dt, Hits &hits) const {
  const ContactBoundaries &bd = boundaries_;
  const auto [A, k, B, k1, k2, w2, nx, ny, found_depth, h, mu, order] = f;
  // With levels, over the pair's window (the coarser body's), each side's impulse as a force over
  // its own body's window. The penalty of a contact that begins from half the finer body's own
  // stable step (Model::own_step), at least the window: tied to the window alone, a pair across
  // levels kicks the finer body every few of its steps with a penalty near the window's limit,
  // which puts energy in (r-RESPA's resonances). A contact the node was in at its pairs' last step
  // within the window keeps its penalty step, softened to the window if that grew, and stiffened
  // only to kept_softer times a beginning contact's (after a fall of the base step, when a body
  // at rest wakes): stiffened under load at depth d the penalty k puts (k' - k) d^2 / 2 in, and a
  // penalty that follows the bodies' steps (shorter as they are pressed, longer when let go)
  // stiffens under load and softens after, a ratchet.
  const bool levels = !model.window.empty();
  double penalty_dt = dt;
  if (levels) {
    dt = k1 == no_node ? model.window[A] : std::max(model.window[A], model.window[B]);
    penalty_dt =
        0.5 * (k1 == no_node ? model.own_step[A] : std::min(model.own_step[A], model.own_step[B]));
  }
  double depth = found_depth;
  const Nodes &nd = model.nodes;
  const double w1 = 1.0 - w2;
  const std::uint32_t p = bd.nodes[k];
  double m_eff = nd.mass[p], vx = nd.vx[p], vy = nd.vy[p];
  if (k1 != no_node) {
    const std::uint32_t s1 = bd.nodes[k1], s2 = bd.nodes[k2];
    const double m_seg = w1 * nd.mass[s1] + w2 * nd.mass[s2];
    m_eff = reducedMass(m_eff, m_seg);
    vx -= w1 * nd.vx[s1] + w2 * nd.vx[s2];
    vy -= w1 * nd.vy[s1] + w2 * nd.vy[s2];
  }
  const double vn = normalVelocity(vx, vy, nx, ny); // > 0: separating
  // Found deeper than its approach reaches from the depth its node was pushed at the step before
  // (approachReach), the node was not reached by approach: B's boundary folded over it, or a new
  // closest segment took over in a dented body. Pushed out at once it would leave at depth / dt;
  // the excess is allowed for instead and let go over release_steps steps, as erosion's overlaps.
  // (with levels, the deepest the node was pushed at by the pairs of each level at their last
  // step within the pair's window: its own last step's depth, whichever pairs were computed since)
  const std::uint8_t level = pairLevel(model, A, B);
  // (and the softest penalty it was pushed with then: its contact's, kept)
  double pushed = levels ? 0.0 : pushed_[p], kept = 0.0;
  for (std::size_t l = 0; levels && l < pushed_levels_; ++l)
    if (const LevelPushed &at = levelPushed(p, l); at.time >= time_ - dt * (1.0 + 1e-9))
      pushed = std::max(pushed, at.depth), kept = std::max(kept, at.penalty);
  if (levels)
    penalty_dt = std::max(dt, kept > 0.0 ? std::min(kept, kept_softer * penalty_dt) : penalty_dt);
  const double reach = approachReach(pushed, h, vn, dt);
  if (depth > reach)
    hits.sudden.emplace_back(p, depth - reach), depth = reach;
  // Two nodes that meet are pushed apart by both passes, a wall contact by one: the walls take
  // twice the stiffness (kappa 1 by default, the one-step constraint).
  const bool wall = k1 == no_node;
  const double kappa = wall ? 2.0 * s_.stiffness : s_.stiffness, c = damping_[wall];
  // (the first `touching` h of the depth is free)
  const ContactForce f_c = contactForce(m_eff, m_eff, depth - touching * h, vx, vy, vn, nx, ny,
                                        kappa, c, mu, penalty_dt);
  const double fx = f_c.fx, fy = f_c.fy, friction_x = -f_c.ft * f_c.tx,
               friction_y = -f_c.ft * f_c.ty;
  const double scale_a = levels ? dt / model.window[A] : 1.0;
  hits.loads[block_[A]].push_back({p, A, scale_a * fx, scale_a * fy, scale_a * friction_x,
                                   scale_a * friction_y, depth, order, level, penalty_dt});
  if (k1 != no_node) {
    std::vector<Load> &loads = hits.loads[block_[B]];
    const double scale_b = levels ? dt / model.window[B] : 1.0;
    for (auto [s, w, at] : {std::tuple{k1, w1, 1u}, {k2, w2, 2u}}) {
      const double ws = w * scale_b;
      loads.push_back({bd.nodes[s], B, -ws * fx, -ws * fy, -ws * friction_x, -ws * friction_y, 0.0,
                       order + at});
    }
  }
  ++hits.count;
  hits.depth = std::max(hits.depth, found_depth / h);
  hits.deep += found_depth / h > deep;
}

void Contact::capLevels(const Model &, const std::vector<std::uint8_t> &reach,
                        std::vector<std::uint8_t> &cap) {
  for (const Pair &pair : pairs_.pairs()) {
    cap[pair.a] = std::min(cap[pair.a], reach[pair.b]);
    cap[pair.b] = std::min(cap[pair.b], reach[pair.a]);
  }
}

void Contact::capParts(const std::vector<std::uint8_t> &own, std::uint32_t body,
                       const std::vector<double> &boxes, std::vector<std::uint8_t> &cap) const {
  for (const Pair &pair : pairs_.pairs()) {
    if (pair.a != body && pair.b != body)
      continue;
    const std::uint32_t other = pair.a == body ? pair.b : pair.a;
    const Box reach = boundaries_.boxes[other].widened(pairs_.searchMargin());
    for (std::size_t p = 0; p < cap.size(); ++p)
      if (reach.overlaps({boxes[4 * p], boxes[4 * p + 1], boxes[4 * p + 2], boxes[4 * p + 3]}))
        cap[p] = std::min(cap[p], own[other]);
  }
}

Contact::State Contact::state(const Model &model) const {
  State st;
  for (const BodyPairs::Pair &p : pairs_.pairs())
    st.pairs.insert(st.pairs.end(), {p.a, p.b});
  st.search_due = pairs_.searchDue();
  st.travel = boundaries_.travel, st.travel_searched = pairs_.travelSearched();
  st.listed.assign(pairs_.listed().begin(), pairs_.listed().end());
  for (const Box &b : boundaries_.boxes)
    st.boxes.insert(st.boxes.end(), {b.x0, b.y0, b.x1, b.y1});
  for (const Point &p : boundaries_.points)
    st.points.insert(st.points.end(), {p.x, p.y});
  if (shared()) { // the moving bodies' boxes, travel and points from their owners, who measured
                  // them: per body its number, box, travel and its boundary nodes' points
    std::vector<double> measured;
    for (std::uint32_t b : pairs_.moving())
      if (mine(b)) {
        measured.push_back(static_cast<double>(b));
        for (double v : boundaries_.boxAndTravel(b))
          measured.push_back(v);
        for (std::size_t k = boundaries_.node_begin[b]; k < boundaries_.node_begin[b + 1]; ++k)
          measured.insert(measured.end(), {boundaries_.points[k].x, boundaries_.points[k].y});
      }
    const std::vector<double> all = processes_->allGather(std::move(measured));
    for (std::size_t i = 0; i < all.size();) {
      const auto b = static_cast<std::size_t>(all[i]);
      std::copy(&all[i + 1], &all[i + 5], &st.boxes[4 * b]);
      st.travel[b] = all[i + 5];
      i += 6;
      for (std::size_t k = boundaries_.node_begin[b]; k < boundaries_.node_begin[b + 1];
           ++k, i += 2)
        st.points[2 * k] = all[i], st.points[2 * k + 1] = all[i + 1];
    }
  }
  // (with the work shared, each node's from its owner: every process's, in rank order)
  const std::vector<std::uint32_t> &body = model.nodes.body;
  std::vector<std::int64_t> allowed, pushed;
  std::vector<double> allowance, pushed_depth;
  for (const ContactAllowances::Allowed &a : allowances_.allowed())
    if (mine(body[a.node]))
      allowed.push_back(a.node),
          allowance.insert(allowance.end(), {allowances_.of(a.node), a.rate});
  for (const auto &nodes : block_pushed_)
    for (std::uint32_t p : nodes)
      if (mine(body[p]) && pushed_[p] != 0.0)
        pushed.push_back(p), pushed_depth.push_back(pushed_[p]);
  if (shared()) {
    allowed = processes_->allGather(std::move(allowed));
    allowance = processes_->allGather(std::move(allowance));
    pushed = processes_->allGather(std::move(pushed));
    pushed_depth = processes_->allGather(std::move(pushed_depth));
  }
  for (std::size_t k = 0; k < allowed.size(); ++k)
    st.allowed.push_back(static_cast<std::uint32_t>(allowed[k])),
        st.allowance.push_back(allowance[2 * k]), st.rate.push_back(allowance[2 * k + 1]);
  st.pushed.assign(pushed.begin(), pushed.end());
  st.pushed_depth = pushed_depth;
  if (!level_pushed_.empty()) { // with levels, in the order of their places l n + node
    st.pushed_levels = pushed_levels_;
    const std::size_t n_nodes = model.nodes.size();
    std::vector<std::int64_t> places;
    std::vector<double> values; // depth, time, penalty step
    for (std::size_t l = 0; l < pushed_levels_; ++l)
      for (std::size_t a = 0; a < n_nodes; ++a)
        if (const LevelPushed &at = levelPushed(a, l); at.time != -HUGE_VAL && mine(body[a]))
          places.push_back(static_cast<std::int64_t>(l * n_nodes + a)),
              values.insert(values.end(), {at.depth, at.time, at.penalty});
    if (shared()) {
      places = processes_->allGather(std::move(places));
      values = processes_->allGather(std::move(values));
    }
    std::vector<std::size_t> order(places.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(),
              [&](std::size_t i, std::size_t j) { return places[i] < places[j]; });
    for (std::size_t i : order) {
      st.level_pushed.push_back(static_cast<std::uint64_t>(places[i]));
      st.level_pushed_depth.push_back(values[3 * i]);
      st.level_pushed_time.push_back(values[3 * i + 1]);
      st.level_pushed_penalty.push_back(values[3 * i + 2]);
    }
  }
  st.statistics = statisticsOfAll();
  return st;
}

void Contact::restore(const Model &model, const State &st) {
  boundaries_.take(model);
  travel_bound_ = HUGE_VAL;
  const std::size_t n_bodies = model.bodies.size();
  if (st.travel.size() != n_bodies || st.travel_searched.size() != n_bodies ||
      st.listed.size() != n_bodies || st.boxes.size() != 4 * n_bodies ||
      st.points.size() != 2 * boundaries_.points.size() || st.pairs.size() % 2 != 0 ||
      st.allowance.size() != st.allowed.size() || st.rate.size() != st.allowed.size() ||
      st.pushed_depth.size() != st.pushed.size() ||
      st.level_pushed_depth.size() != st.level_pushed.size() ||
      st.level_pushed_time.size() != st.level_pushed.size() ||
      st.level_pushed_penalty.size() != st.level_pushed.size() ||
      st.pushed_levels > 8) // (levels 0 to 7: SolverSettings::max_level <= 7)
    throw std::invalid_argument("contact state: sizes not of this model");
  for (const auto *nodes : {&st.allowed, &st.pushed})
    for (std::uint32_t p : *nodes)
      if (p >= model.nodes.size())
        throw std::invalid_argument("contact state: a node not of this model");
  for (std::uint32_t b : st.pairs)
    if (b >= n_bodies)
      throw std::invalid_argument("contact state: a body not of this model");
  boundaries_.travel = st.travel;
  for (std::size_t b = 0; b < n_bodies; ++b)
    boundaries_.boxes[b] = {st.boxes[4 * b], st.boxes[4 * b + 1], st.boxes[4 * b + 2],
                            st.boxes[4 * b + 3]};
  for (std::size_t k = 0; k < boundaries_.points.size(); ++k)
    boundaries_.points[k] = {st.points[2 * k], st.points[2 * k + 1]};
  pairs_.restore(st.pairs, st.search_due, st.travel_searched,
                 std::vector<char>(st.listed.begin(), st.listed.end()));
  std::vector<ContactAllowances::Allowed> allowed;
  for (std::size_t k = 0; k < st.allowed.size(); ++k)
    allowed.push_back({st.allowed[k], st.rate[k]});
  allowances_.restore(allowed, st.allowance);
  // one depth per node, or with levels one per level of pair and node
  const std::size_t n_nodes = model.nodes.size();
  pushed_levels_ = std::max<std::size_t>(st.pushed_levels, 1);
  pushed_.assign(n_nodes, 0.0);
  level_pushed_.clear();
  if (st.pushed_levels > 0) {
    level_pushed_.assign(pushed_levels_ * n_nodes, LevelPushed{});
    for (std::size_t k = 0; k < st.level_pushed.size(); ++k) {
      const std::uint64_t at = st.level_pushed[k]; // its place l n + node
      if (at >= level_pushed_.size())
        throw std::invalid_argument("contact state: a pushed depth not of this model");
      levelPushed(at % n_nodes, at / n_nodes) = {st.level_pushed_depth[k], st.level_pushed_time[k],
                                                 st.level_pushed_penalty[k]};
    }
  }
  for (auto &nodes : block_pushed_)
    nodes.clear();
  for (std::size_t k = 0; k < st.pushed.size(); ++k) {
    const std::uint32_t p = st.pushed[k];
    pushed_[p] = st.pushed_depth[k];
    block_pushed_[block_[model.nodes.body[p]]].push_back(p);
  }
  // (with the work shared, the counts go on from the first process's: statisticsOfAll sums them)
  stats_ = !shared() || processes_->rank() == 0 ? st.statistics : ContactStatistics{};
}

} // namespace mesopen::fem
