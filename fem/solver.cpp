#include "solver.hpp"
#include "element_step.hpp"
#include "levels.hpp"
#include "materials/hyperelastic.hpp"
#include "threads.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#ifdef __AVX__
#include <immintrin.h>
#endif

namespace mesopen::fem {

namespace {

// The balance error of a run's energies (Energy).
double balanceError(const Energy &e) {
  const double total = e.kinetic + e.internal + e.friction + e.contact + e.eroded + e.mass_scaling;
  const double scale = std::max({std::abs(total), std::abs(e.initial), std::abs(e.external)});
  return scale > 0.0 ? (total - e.initial - e.external) / scale : 0.0;
}

// The energies each process holds a share of (Solver::energy), in the order they are sent.
constexpr double Energy::*energy_shares[] = {
    &Energy::kinetic, &Energy::internal, &Energy::plastic, &Energy::viscous,     &Energy::friction,
    &Energy::contact, &Energy::external, &Energy::eroded,  &Energy::mass_scaling};

std::vector<double> sharesOf(const Energy &e) {
  std::vector<double> shares;
  for (auto share : energy_shares)
    shares.push_back(e.*share);
  return shares;
}

constexpr std::size_t max_chunk = 256;        // elements per material batch (scratch on the stack)
constexpr std::size_t node_block = 4096;      // nodes per block of the node loops
constexpr std::size_t level_node_block = 512; // the same with levels (shared by node count)
constexpr std::size_t unit_target = 4096;     // elements per work unit of the element pass
constexpr double refine_margin = 1.05;        // refine the steps below this times the last shortest

// Whether an element of a material that erodes (erosion strain `erosion`, infinite when it does
// not) has failed: at its erosion strain, or crushed to a fifth of its area (a grain corner driven
// into it, a few steps before it would invert).
constexpr double crushed_area = 0.2;
bool hasFailed(double plastic_strain, double area, double area0, double erosion) {
  return plastic_strain >= erosion || (erosion < HUGE_VAL && area < crushed_area * area0);
}

// Appends the range `piece` to `ranges` in pieces of at most `limit`, first filling up the last
// range (if it is at index `first` or later, ends where `piece` begins and `joinable` says so).
template <class R, class Joinable>
void appendInPieces(std::vector<R> &ranges, std::size_t first, R piece, std::size_t limit,
                    Joinable joinable) {
  const std::size_t end = piece.end;
  while (piece.begin < end) {
    R *last = ranges.size() > first ? &ranges.back() : nullptr;
    if (last && last->end == piece.begin && last->end - last->begin < limit && joinable(*last)) {
      last->end += std::min(limit - (last->end - last->begin), end - piece.begin);
      piece.begin = last->end;
    } else {
      piece.end = piece.begin + std::min(limit, end - piece.begin);
      ranges.push_back(piece);
      piece.begin = piece.end;
    }
  }
}

// Node values of a batch's elements are read by the two helpers below rather than inside the
// vectorized loops: GCC turns indexed loads there into 8-lane gathers, which cost about 2 cycles
// per value on the AMD EPYC this was measured on, several times a scalar load.

// The states (x, y, vx, vy) of node k of each element of a batch, transposed into four arrays
// (with AVX: four elements at a time, one 32-byte load per node and a 4 x 4 transpose).
// `state` holds the nodes from number `base` on.
template <class NodeState>
void gatherNodeStates(const NodeState *state, std::size_t base, const std::uint32_t *conn, int k,
                      std::size_t n, double *x, double *y, double *vx, double *vy) {
  std::size_t i = 0;
#ifdef __AVX__
  for (; i + 4 <= n; i += 4) {
    const __m256d r0 = _mm256_load_pd(&state[conn[3 * i + k] - base].x);
    const __m256d r1 = _mm256_load_pd(&state[conn[3 * i + 3 + k] - base].x);
    const __m256d r2 = _mm256_load_pd(&state[conn[3 * i + 6 + k] - base].x);
    const __m256d r3 = _mm256_load_pd(&state[conn[3 * i + 9 + k] - base].x);
    const __m256d t0 = _mm256_unpacklo_pd(r0, r1), t1 = _mm256_unpackhi_pd(r0, r1);
    const __m256d t2 = _mm256_unpacklo_pd(r2, r3), t3 = _mm256_unpackhi_pd(r2, r3);
    _mm256_store_pd(x + i, _mm256_permute2f128_pd(t0, t2, 0x20));
    _mm256_store_pd(vx + i, _mm256_permute2f128_pd(t0, t2, 0x31));
    _mm256_store_pd(y + i, _mm256_permute2f128_pd(t1, t3, 0x20));
    _mm256_store_pd(vy + i, _mm256_permute2f128_pd(t1, t3, 0x31));
  }
#endif
  for (; i < n; ++i) {
    const NodeState &s = state[conn[3 * i + k] - base];
    x[i] = s.x, y[i] = s.y, vx[i] = s.vx, vy[i] = s.vy;
  }
}

// The mean of a nodal value over the three nodes of each element of a batch (with AVX: scalar
// loads, four elements at a time); `value` holds the nodes from number `base` on.
void elementMean(const double *value, std::size_t base, const std::uint32_t *conn, std::size_t n,
                 double *mean) {
  auto sum = [&](std::size_t i) {
    return value[conn[3 * i] - base] + value[conn[3 * i + 1] - base] +
           value[conn[3 * i + 2] - base];
  };
  std::size_t i = 0;
#ifdef __AVX__
  for (; i + 4 <= n; i += 4)
    _mm256_store_pd(mean + i,
                    _mm256_mul_pd(_mm256_setr_pd(sum(i), sum(i + 1), sum(i + 2), sum(i + 3)),
                                  _mm256_set1_pd(1.0 / 3.0)));
#endif
  for (; i < n; ++i)
    mean[i] = sum(i) * (1.0 / 3.0);
}
} // namespace

Solver::Solver(Model &model, SolverSettings settings, const parallel::Communicator &processes,
               const parallel::Partitioner &partitioner)
    : m_(model), s_(settings), comm_(processes), partitioner_(partitioner) {
  s_.chunk = std::clamp<std::size_t>(s_.chunk, 1, max_chunk);
  // The partitioner's ids are 32-bit: body numbers are (Elements::body, active_bodies_).
  if (m_.bodies.size() > std::numeric_limits<std::uint32_t>::max())
    throw std::length_error("a model of " + std::to_string(m_.bodies.size()) +
                            " bodies: at most 2^32 - 1 can be numbered");
  // Until the first partition (balanceLoad), body b is rank b mod size's: the partitioner's
  // starting distribution.
  owner_.resize(m_.bodies.size());
  for (std::size_t b = 0; b < owner_.size(); ++b)
    owner_[b] = static_cast<int>(b % comm_.size());
  rank_elements_.assign(comm_.size(), 0);
  rank_nodes_.assign(comm_.size(), 0);
  level_.assign(m_.bodies.size(), 0);
  if (levels())
    startLevels();
  rank_element_steps_.assign(comm_.size(), 0.0);
  rank_node_steps_.assign(comm_.size(), 0.0);
  const Nodes &nd = m_.nodes;
  inv_mass_.resize(nd.size());
  for (std::size_t a = 0; a < nd.size(); ++a)
    inv_mass_[a] = nd.mass[a] > 0.0 ? 1.0 / nd.mass[a] : 0.0;
  // A body moves if any of its nodes moves, is driven, or any of its elements is stressed.
  for (std::size_t a = 0; a < nd.size(); ++a)
    if (nd.vx[a] != 0.0 || nd.vy[a] != 0.0)
      m_.wake(nd.body[a]);
  for (const auto &c : m_.constraints)
    if ((c.constrain_x && c.vx != 0.0) || (c.constrain_y && c.vy != 0.0))
      for (std::uint32_t a : c.nodes)
        m_.wake(nd.body[a]);
  if (s_.gravity_x != 0.0 || s_.gravity_y != 0.0) // gravity loads every body
    for (std::size_t b = 0; b < m_.bodies.size(); ++b)
      m_.wake(b);
  const Elements &el = m_.elements;
  for (std::size_t e = 0; e < el.size(); ++e)
    if (el.sxx[e] != 0.0 || el.syy[e] != 0.0 || el.sxy[e] != 0.0 || el.pressure[e] != 0.0 ||
        el.energy[e] != 0.0)
      m_.wake(el.body[e]);
  m_.nodes.clearExternal();
  updateActivity();
  step_elements_ = active_elements_;
  failed_.assign(el.size(), 0);
  storeReferenceShapes();
  internalForces(0.0);
  erode_below_ = s_.erode_step_ratio * shortest_step_;
  scale_below_ = s_.mass_scaling_step_ratio * shortest_step_;
  dt_ = std::min(next_dt_, s_.max_dt);
  for (const Range &r : node_ranges_) // (this process's nodes; the processes' sums added)
    for (std::size_t a = r.begin; a < r.end; ++a)
      addKinetic(a, 0.5 * nd.mass[a] * (nd.vx[a] * nd.vx[a] + nd.vy[a] * nd.vy[a]));
  if (levels()) {
    bodySums(0, units_.size());
    shareBodySteps(s_.max_level);
    std::fill(m_.window.begin(), m_.window.end(), dt_);
  }
  accountEnergy();
  const std::vector<double> start = comm_.sumInOrder({energy_.kinetic, energy_.internal});
  energy_.initial = start[0] + start[1];
  energy_.balance_error = 0.0;
}

void Solver::storeReferenceShapes() {
  const Elements &el = m_.elements;
  const double *X = m_.nodes.x0.data(), *Y = m_.nodes.y0.data();
  for (const Body &body : m_.bodies) {
    if (!m_.materials[body.material]->usesDeformationGradient())
      continue;
    for (auto &inverse : reference_inverse_)
      inverse.resize(el.size(), 0.0);
    for (std::size_t e = body.element_begin; e < body.element_end; ++e) {
      const std::uint32_t a = el.node[3 * e], b = el.node[3 * e + 1], c = el.node[3 * e + 2];
      const double exx = X[b] - X[a], exy = X[c] - X[a], eyx = Y[b] - Y[a], eyy = Y[c] - Y[a];
      const double inv = 1.0 / (exx * eyy - exy * eyx);
      reference_inverse_[0][e] = eyy * inv, reference_inverse_[1][e] = -exy * inv;
      reference_inverse_[2][e] = -eyx * inv, reference_inverse_[3][e] = exx * inv;
    }
  }
}

void Solver::addForceProvider(ForceProvider *provider) {
  if (levels() && !provider->takesLevels())
    throw std::invalid_argument("multiple time stepping (max_level " +
                                std::to_string(s_.max_level) +
                                ") with a force provider that steps every body every step (DEM "
                                "coupling): allowed with FE-FE contact alone");
  providers_.push_back(provider);
  provider->shareWork(comm_, owner_);
  if (levels())
    provider->bodiesInParts(parted_bodies_);
  const double scale = std::sqrt(std::max(0.0, 1.0 - 0.25 * provider->stepStiffness()));
  if (scale < step_scale_) { // the step already taken from the elements, scaled
    next_dt_ *= scale / step_scale_;
    dt_ = std::min(next_dt_, s_.max_dt);
    step_scale_ = scale;
  }
}

// The steps that end a run at endAt's time: the last end_steps stable steps or less are made equal.
constexpr double end_steps = 20.0;

void wakeEverywhere(Model &model, const parallel::Communicator &processes,
                    std::vector<std::int64_t> &woken, std::size_t most) {
  if (most > 0) {
    woken.resize(most, -1); // (-1: none)
    const std::vector<std::int64_t> all = processes.allGather(
        std::move(woken), std::vector<std::int64_t>(static_cast<std::size_t>(processes.size()),
                                                    static_cast<std::int64_t>(most)));
    for (const std::int64_t b : all)
      if (b >= 0)
        model.wake(static_cast<std::size_t>(b));
  }
  woken.clear();
}

// The step to take from the stable one: within end_steps stable steps of endAt's time, the rest in
// equal steps (past it: stable steps); `last` whether it ends at that time.
double Solver::stepToTake(bool &last) const {
  const double stable = dt_, remaining = end_at_ - time_;
  const double steps_left = remaining > 0.0 && remaining < end_steps * stable
                                ? std::ceil(remaining / stable * (1.0 - 1e-12))
                                : 0.0;
  last = steps_left == 1.0;
  return steps_left > 0.0 ? remaining / steps_left : stable;
}

// The time loop's step: each line one stage of the central-difference scheme.
void Solver::step() {
  if (levels())
    return stepLevels();
  const double stable = dt_;
  bool last = false;
  const double dt = stepToTake(last);
  kick_work_ = provider_work_ = friction_work_ = 0.0;
  if (comm_.size() > 1 && s_.rebalance_every > 0 && steps_ > 0 && steps_ % s_.rebalance_every == 0)
    rebalance_due_ = true;
  kickAndDrift(dt); // v(n+1/2) = v(n) + dt/2 f(n) / m, the imposed velocities;
                    // x(n+1) = x(n) + dt v(n+1/2)
  m_.nodes.clearExternal();
  for (auto *provider : providers_) // external forces at x(n+1): contact, coupling
    provider->addForces(m_, time_ + dt, dt);
  // Bodies the providers woke take part. With several processes a body the contact woke is known
  // to move at its owner now, at the others after the step's reduction (forces): the load is
  // balanced at the end of the step, when every process knows the same bodies to move.
  const bool shared = comm_.size() > 1;
  updateActivity(!shared);
  forces(dt, true); // stresses at n+1, f(n+1), the next stable step, and unit by unit
                    // v(n+1) = v(n+1/2) + dt/2 f(n+1) / m, the imposed velocities at n+1
  step_elements_ = active_elements_;
  for (std::size_t r = 0; r < rank_elements_.size(); ++r) {
    rank_element_steps_[r] += static_cast<double>(rank_elements_[r]);
    rank_node_steps_[r] += static_cast<double>(rank_nodes_[r]);
  }
  scaleMasses(0.5 * dt); // mass for the elements whose step fell below scale_below_
  time_ = last ? end_at_ : time_ + dt;
  ++steps_;
  if (steps_ == 1)
    first_dt_ = stable;
  nextStep(stable, s_.dt_rise_interval);
  accountEnergy();
  // A state no longer finite (a material driven where its law has no value) would run on as NaN
  // and be reported as completed: it ends the run here (every process: the step's figures said
  // whether any process's energies are), naming where it began.
  if (not_finite_)
    throw RunFailure(notFinite());
  erode(); // elements that failed in this step leave the model
  if (shared)
    updateActivity(true);
}

// The step to come from the one just taken (`stable`, before the end's equal steps) and the
// elements' next_dt_. The step falls at once to what the elements allow; it rises only every
// `rise_interval` steps, to the shortest step allowed over them: a step that followed the elements'
// fastest oscillation up and down would pump energy into it (a leapfrog of varying step is not
// symplectic). A step below min_dt_ratio of the first ends the run.
void Solver::nextStep(double stable, std::size_t rise_interval) {
  shortest_allowed_ = std::min(shortest_allowed_, next_dt_);
  if (next_dt_ < stable)
    dt_ = std::min(next_dt_, s_.max_dt);
  else if (steps_ % rise_interval == 0)
    dt_ = std::min({shortest_allowed_, s_.max_dt, s_.max_dt_growth * stable});
  if (steps_ % rise_interval == 0)
    shortest_allowed_ = std::numeric_limits<double>::infinity();
  if (next_dt_ < s_.min_dt_ratio * first_dt_) {
    std::ostringstream msg;
    msg << "the stable step fell to " << next_dt_ << " s, below " << s_.min_dt_ratio
        << " of the first (" << first_dt_ << " s), at t = " << time_ << " s, step " << steps_
        << "; the thinnest element: " << thinnestElement();
    throw RunFailure(msg.str());
  }
}

std::string Solver::notFinite() const {
  const Elements &el = m_.elements;
  std::ostringstream msg;
  for (const Chunk &c : chunks_)
    for (std::size_t e = c.begin; e < c.end; ++e)
      if (!std::isfinite(el.sxx[e] + el.syy[e] + el.sxy[e] + el.pressure[e] + el.energy[e])) {
        const Body &body = m_.bodies[el.body[e]];
        msg << "the stress of element " << e << " of body " << body.name << " (material "
            << m_.materials[body.material]->type() << ") is not a number (S_xx " << el.sxx[e]
            << ", S_yy " << el.syy[e] << ", S_xy " << el.sxy[e] << ", pressure " << el.pressure[e]
            << " Pa, energy " << el.energy[e] << " J/m) at t = " << time_ << " s, step " << steps_
            << ": its material's parameters give a state their law cannot compute";
        return msg.str();
      }
  msg << "the nodes' velocities are not numbers at t = " << time_ << " s, step " << steps_;
  return msg.str();
}

// Work ranges over the bodies that move: element chunks of one material, node blocks. With levels,
// level by level (each level's units and blocks together), a unit holding consecutive bodies.
void Solver::updateActivity(bool may_partition) {
  // (a change a call without may_partition saw is checked at the next call with it)
  if (at_rest_seen_ == m_.at_rest && !(may_partition && (rebalance_due_ || load_check_due_)) &&
      laid_levels_ == level_ && laid_part_levels_ == part_level_)
    return;
  at_rest_seen_ = m_.at_rest;
  laid_levels_ = level_;
  laid_part_levels_ = part_level_;
  balanceLoad(may_partition && std::exchange(rebalance_due_, false), may_partition);
  load_check_due_ = !may_partition;
  chunks_.clear();
  units_.clear();
  unit_nodes_.clear();
  node_ranges_.clear();
  countActive();
  const bool by_body = levels();
  const int n_levels = s_.max_level + 1;
  level_units_.assign(n_levels + 1, 0);
  level_blocks_.assign(n_levels + 1, 0);
  for (int l = 0; l < n_levels; ++l) {
    const std::size_t first_unit = units_.size(), first_block = node_ranges_.size();
    std::size_t unit_elements = 0;
    for (std::uint32_t b : active_bodies_) {
      if (level_[b] != l)
        continue;
      const Body &body = m_.bodies[b];
      // A process moves the nodes and computes the elements of the bodies it owns.
      if (!owns(b))
        continue;
      // (with levels, in smaller blocks: the due levels' blocks are shared among the threads by
      // node count, and a level 0 of a few thousand nodes is then shared evenly)
      appendInPieces(node_ranges_, first_block, Range{body.node_begin, body.node_end},
                     by_body ? level_node_block : node_block, [](const Range &) { return true; });
      const Material *material = m_.materials[body.material].get();
      const bool averaged = s_.anti_locking && material->plastic();
      // A work unit holds whole bodies (no node is shared between units, so each unit adds its
      // elements' forces into the nodes without races, in element order).
      // (with levels, a unit holds consecutive bodies: its nodes stay together)
      // (a body in parts is a unit of its own)
      const bool in_parts = by_body && part_begin_[b] < part_begin_[b + 1];
      const bool new_unit = units_.size() == first_unit || unit_elements >= unit_target ||
                            (by_body && units_.back().node_hi != body.node_begin) || in_parts ||
                            units_.back().in_parts;
      if (new_unit) {
        units_.push_back({chunks_.size(), chunks_.size(), unit_nodes_.size(), unit_nodes_.size(),
                          body.node_begin, body.node_end, false, in_parts});
        unit_elements = 0;
      }
      Unit &unit = units_.back();
      // The body's elements (part by part for a body in parts) in runs without eroded ones.
      auto addElements = [&](std::size_t begin, std::size_t stop, std::uint8_t level,
                             std::uint32_t part, std::size_t first_chunk) {
        for (std::size_t e = begin; e < stop;) {
          std::size_t end = stop;
          if (body.eroded > 0) {
            while (e < end && m_.elements.eroded[e])
              ++e;
            end = e;
            while (end < stop && !m_.elements.eroded[end])
              ++end;
          }
          appendInPieces(chunks_, first_chunk, Chunk{{e, end}, material, averaged, level, part},
                         s_.chunk, [&](const Chunk &c) {
                           return c.material == material && c.averaged_volume == averaged;
                         });
          unit_elements += end - e;
          e = end;
        }
      };
      if (in_parts)
        for (std::size_t p = part_begin_[b]; p < part_begin_[b + 1]; ++p)
          addElements(parts_[p].element_begin, parts_[p].element_end, part_level_[p],
                      static_cast<std::uint32_t>(p), chunks_.size());
      else
        addElements(body.element_begin, body.element_end, static_cast<std::uint8_t>(l),
                    Chunk::no_part, unit.chunk_begin);
      appendInPieces(unit_nodes_, unit.nodes_begin, Range{body.node_begin, body.node_end},
                     std::numeric_limits<std::size_t>::max(), [](const Range &) { return true; });
      unit.chunk_end = chunks_.size();
      unit.nodes_end = unit_nodes_.size();
      unit.node_lo = std::min(unit.node_lo, body.node_begin);
      unit.node_hi = std::max(unit.node_hi, body.node_end);
      unit.averaged_volume = unit.averaged_volume || averaged;
    }
    level_units_[l + 1] = units_.size();
    level_blocks_[l + 1] = node_ranges_.size();
  }
  sums_.resize(chunks_.size());
  shareAmongThreads();
}

namespace {

// max / mean - 1 of the ranks' loads (0 without load).
double imbalance(const std::vector<double> &loads) {
  double total = 0.0, most = 0.0;
  for (double l : loads)
    total += l, most = std::max(most, l);
  return total > 0.0 ? most * static_cast<double>(loads.size()) / total - 1.0 : 0.0;
}

std::vector<double> asDoubles(const std::vector<std::size_t> &counts) {
  return std::vector<double>(counts.begin(), counts.end());
}

} // namespace

// With several processes, a new partition when the load (each rank's active elements: the bodies
// it owns that move; with levels each element weighted by its updates per base step, 2^-level, a
// body in parts by its parts' levels, which every process knows: chooseLevels) is out of balance.
// The loads change only when the bodies that move, their elements or their levels change, which
// is when updateActivity calls this: the check is one pass over the bodies and no message, and
// every process, holding the same model, takes the same decision. Out of balance is measured
// against the best a partition of whole bodies can do: the most loaded rank's load over the
// larger of the mean and the heaviest body's, less 1 (with no body heavier than the mean, the
// imbalance max / mean - 1). The bodies are partitioned at the first load, when `forced`, and when
// that measure passes rebalance_above_; never when not `may_partition` (a run continued with its
// partition).
void Solver::balanceLoad(bool forced, bool may_partition) {
  const std::size_t ranks = static_cast<std::size_t>(comm_.size());
  // (one process owns every body: nothing to share)
  if (ranks == 1 || !may_partition)
    return;
  std::vector<double> load(m_.bodies.size(), 0.0);
  double total = 0.0, heaviest = 0.0;
  for (std::size_t b = 0; b < load.size(); ++b) {
    if (!m_.at_rest[b])
      load[b] = levelLoad(b);
    total += load[b];
    heaviest = std::max(heaviest, load[b]);
  }
  if (total == 0.0) // (nothing moves: nothing to share)
    return;
  auto rankLoads = [&] {
    std::vector<double> loads(ranks, 0.0);
    for (std::size_t b = 0; b < load.size(); ++b)
      loads[static_cast<std::size_t>(owner_[b])] += load[b];
    return loads;
  };
  std::vector<double> rank_loads = rankLoads();
  const double best = std::max(total / static_cast<double>(ranks), heaviest);
  auto excess = [&] {
    return *std::max_element(rank_loads.begin(), rank_loads.end()) / best - 1.0;
  };
  // A partition that could not reach rebalance_imbalance (a body heavier than a rank's share in
  // the middle of the others: no straight cut balances it) is made again only once the load is
  // that much worse than it achieved, or the total load has changed by that fraction since.
  const double out_of_balance = excess(), tol = s_.rebalance_imbalance;
  const bool worth_trying =
      out_of_balance > last_achieved_ + tol || std::abs(total - last_total_) > tol * last_total_;
  if (partitioned_ && !forced && !(out_of_balance > tol && worth_trying))
    return;
  const double before = imbalance(rank_loads);
  repartition(load);
  rank_loads = rankLoads();
  last_achieved_ = excess();
  last_total_ = total;
  if (partitioned_) {
    ++partition_.rebalances;
    partition_.forced += forced;
  }
  partitioned_ = true;
  partition_.last_before = before;
  partition_.last_after = imbalance(rank_loads);
}

// Every body to the rank the partitioner gives it: each process passes the bodies it owns, with
// their nodes' centroid and their load (balanceLoad), and all learn every body's new owner.
// Every process holds every body, but only a body's owner keeps its elements' state (stress,
// energy, plastic strain...) and its nodes' motion current: the moving bodies that change owner
// take theirs to their new owner.
void Solver::repartition(const std::vector<double> &load) {
  Nodes &nd = m_.nodes;
  parallel::PartitionItems mine;
  for (std::size_t b = 0; b < m_.bodies.size(); ++b) {
    if (!owns(b))
      continue;
    const Body &body = m_.bodies[b];
    double x = 0.0, y = 0.0;
    for (std::size_t a = body.node_begin; a < body.node_end; ++a)
      x += nd.x[a], y += nd.y[a];
    const double nodes =
        static_cast<double>(std::max<std::size_t>(body.node_end - body.node_begin, 1));
    mine.id.push_back(static_cast<std::uint32_t>(b));
    mine.x.push_back(x / nodes);
    mine.y.push_back(y / nodes);
    mine.weight.push_back(load[b]);
  }
  const std::vector<int> to = partitioner_.partition(mine);
  std::vector<std::int64_t> moves;
  moves.reserve(2 * to.size());
  for (std::size_t k = 0; k < to.size(); ++k)
    moves.insert(moves.end(), {mine.id[k], to[k]});
  const std::vector<std::int64_t> all = comm_.allGather(std::move(moves));
  if (all.size() != 2 * owner_.size())
    throw std::logic_error("the partition gave " + std::to_string(all.size() / 2) + " owners for " +
                           std::to_string(owner_.size()) + " bodies");
  std::vector<int> owner = owner_;
  for (std::size_t k = 0; k < all.size(); k += 2) {
    const auto b = static_cast<std::size_t>(all[k]);
    const auto rank = static_cast<int>(all[k + 1]);
    if (b >= owner.size() || rank < 0 || rank >= comm_.size())
      throw std::logic_error("the partition gave body " + std::to_string(b) + " of " +
                             std::to_string(owner.size()) + " to rank " + std::to_string(rank) +
                             " of " + std::to_string(comm_.size()));
    owner[b] = rank;
  }
  // The bodies that change owner and move carry their state to their new owner alone (a body at
  // rest is the same on every process): its elements' state, its nodes' x(n+1), v(n+1), f(n+1)
  // and external forces (the next step's half-kick and the work it does), at the end of a step;
  // with levels what only the owner keeps of them (packLevels).
  std::vector<std::uint32_t> moving;
  for (std::size_t b = 0; b < owner.size(); ++b)
    if (owner[b] != owner_[b]) {
      ++partition_.migrated_bodies;
      if (!m_.at_rest[b])
        moving.push_back(static_cast<std::uint32_t>(b));
    }
  const auto fields = elementState();
  parallel::moveValues(
      comm_, moving.size(), [&](std::size_t k) { return owner_[moving[k]]; },
      [&](std::size_t k) { return owner[moving[k]]; },
      [&](std::size_t k) {
        const Body &body = m_.bodies[moving[k]];
        return fields.size() * (body.element_end - body.element_begin) +
               10 * (body.node_end - body.node_begin) + levelValues(moving[k]);
      },
      [&](std::size_t k, double *out) {
        const Body &body = m_.bodies[moving[k]];
        for (std::size_t e = body.element_begin; e < body.element_end; ++e)
          for (auto *f : fields)
            *out++ = (*f)[e];
        for (std::size_t a = body.node_begin; a < body.node_end; ++a) {
          const Nodes::External &x = nd.external[a];
          *out++ = nd.x[a], *out++ = nd.y[a], *out++ = nd.vx[a], *out++ = nd.vy[a];
          *out++ = nd.fx[a], *out++ = nd.fy[a];
          *out++ = x.fx, *out++ = x.fy, *out++ = x.friction_x, *out++ = x.friction_y;
        }
        packLevels(moving[k], out);
      },
      [&](std::size_t k, const double *in) {
        const Body &body = m_.bodies[moving[k]];
        for (std::size_t e = body.element_begin; e < body.element_end; ++e)
          for (auto *f : fields)
            (*f)[e] = *in++;
        for (std::size_t a = body.node_begin; a < body.node_end; ++a, in += 10) {
          nd.x[a] = in[0], nd.y[a] = in[1];
          nd.vx[a] = in[2], nd.vy[a] = in[3];
          nd.fx[a] = in[4], nd.fy[a] = in[5];
          nd.external[a] = {in[6], in[7], in[8], in[9]};
          if (!nd.is_loaded[a] && (in[6] != 0.0 || in[7] != 0.0 || in[8] != 0.0 || in[9] != 0.0))
            nd.is_loaded[a] = 1, nd.loaded.push_back(static_cast<std::uint32_t>(a));
        }
        unpackLevels(moving[k], in);
      });
  for (ForceProvider *provider : providers_)
    provider->bodiesMoving(m_, moving, owner);
  owner_ = std::move(owner);
}

PartitionReport Solver::partition() const {
  PartitionReport report = partition_;
  report.bodies.assign(rank_elements_.size(), 0);
  for (int rank : owner_)
    ++report.bodies[static_cast<std::size_t>(rank)];
  report.active_elements = rank_elements_;
  report.active_nodes = rank_nodes_;
  report.element_steps = rank_element_steps_;
  report.node_steps = rank_node_steps_;
  report.imbalance = imbalance(asDoubles(rank_elements_));
  report.run_imbalance = imbalance(rank_element_steps_);
  return report;
}

// Each thread takes a contiguous run of units with about its share of the elements, and the node
// blocks beside them: the nodes it kicks and moves are those whose elements it computes, so that
// a node is not written on one core and read on the other at each pass (with the units taken as
// they came and the blocks in halves, run 6 to 0.4 length took 3 % longer on two threads).
void Solver::shareAmongThreads() {
  const auto threads = static_cast<std::size_t>(omp_get_max_threads());
  std::vector<std::size_t> elements(units_.size(), 0);
  for (std::size_t u = 0; u < units_.size(); ++u)
    for (std::size_t c = units_[u].chunk_begin; c < units_[u].chunk_end; ++c)
      elements[u] += chunks_[c].end - chunks_[c].begin;
  thread_units_ = contiguousShares(elements, threads);
  // A block goes with the units that hold its first node.
  thread_blocks_.assign(threads + 1, node_ranges_.size());
  thread_blocks_[0] = 0;
  for (std::size_t t = 1, i = 0; t < threads; ++t) {
    const std::size_t first_node = thread_units_[t] < units_.size()
                                       ? units_[thread_units_[t]].node_lo
                                       : std::numeric_limits<std::size_t>::max();
    while (i < node_ranges_.size() && node_ranges_[i].begin < first_node)
      ++i;
    thread_blocks_[t] = i;
  }
  if (levels())
    shareLevelsAmongThreads(threads, elements);
}

// The bodies that move (active_bodies_), their elements and each rank's nodes and elements.
void Solver::countActive() {
  active_elements_ = 0;
  active_bodies_.clear();
  std::fill(rank_nodes_.begin(), rank_nodes_.end(), 0);
  std::fill(rank_elements_.begin(), rank_elements_.end(), 0);
  for (std::size_t b = 0; b < m_.bodies.size(); ++b) {
    const Body &body = m_.bodies[b];
    if (m_.at_rest[b])
      continue;
    const std::size_t elements = body.element_end - body.element_begin - body.eroded;
    active_bodies_.push_back(static_cast<std::uint32_t>(b));
    rank_nodes_[static_cast<std::size_t>(owner(b))] += body.node_end - body.node_begin;
    rank_elements_[static_cast<std::size_t>(owner(b))] += elements;
    active_elements_ += elements;
  }
}

// A half-kick of node a from velocity (vx, vy) under the force (fx, fy). The work of the external
// forces over it, force . mean velocity, is summed over the loaded nodes alone (the kick's own
// arithmetic), gravity's over every node when there is gravity (both still to be multiplied by
// half_dt). After the second half, the kinetic energy of the leapfrog,
// 1/2 m v(n-1/2) . v(n+1/2) = 1/2 m (|v(n)|^2 - |dv|^2) with dv this half-kick: central differences
// conserve it exactly for a linear elastic system (1/2 m |v(n)|^2 carries an O((omega dt)^2)
// oscillation of the fastest modes).
void Solver::halfKick(std::size_t a, double half_dt, double fx, double fy, bool second_half,
                      double &vx, double &vy, KickSums &sums) const {
  const Nodes &nd = m_.nodes;
  const double dvx = half_dt * fx * inv_mass_[a], dvy = half_dt * fy * inv_mass_[a];
  const double mean_vx = vx + 0.5 * dvx, mean_vy = vy + 0.5 * dvy;
  if (nd.is_loaded[a]) {
    const Nodes::External &e = nd.external[a];
    sums.provider += e.fx * mean_vx + e.fy * mean_vy;
    sums.friction += e.friction_x * mean_vx + e.friction_y * mean_vy;
  }
  if (s_.gravity_x != 0.0 || s_.gravity_y != 0.0)
    sums.gravity += nd.mass[a] * (s_.gravity_x * mean_vx + s_.gravity_y * mean_vy);
  vx += dvx, vy += dvy;
  if (second_half)
    sums.kinetic += 0.5 * nd.mass[a] * (vx * vx + vy * vy - dvx * dvx - dvy * dvy);
}

// Sums of the half-kicks of blocks or units, in their order (the same for any thread count).
void Solver::addKickSums(const std::vector<KickSums> &sums, double half_dt) {
  for (const KickSums &k : sums) {
    kick_work_ += half_dt * k.gravity;
    provider_work_ += half_dt * k.provider;
    friction_work_ += half_dt * k.friction;
    energy_.kinetic += k.kinetic;
  }
}

// The first half-kick and the drift of this process's active nodes in one pass; the imposed
// velocities, and the positions of their nodes, corrected after.
void Solver::kickAndDrift(double dt) {
  Nodes &nd = m_.nodes;
  const double half_dt = 0.5 * dt;
  const long blocks = static_cast<long>(node_ranges_.size());
  kick_sums_.assign(blocks, KickSums{});
#pragma omp parallel if (blocks > 1)
  for (auto [i, end] = threadShare(thread_blocks_); i < end; ++i) {
    KickSums sums; // in registers: the node arrays' stores could alias kick_sums_
    for (std::size_t a = node_ranges_[i].begin; a < node_ranges_[i].end; ++a) {
      double vx = nd.vx[a], vy = nd.vy[a];
      halfKick(a, half_dt, nd.fx[a], nd.fy[a], false, vx, vy, sums);
      nd.vx[a] = vx, nd.vy[a] = vy;
      nd.x[a] += dt * vx;
      nd.y[a] += dt * vy;
    }
    kick_sums_[i] = sums;
  }
  addKickSums(kick_sums_, half_dt);
  applyConstraints(half_dt, false);
}

// Imposed velocities at this process's nodes; the reactions' work, impulse . mean velocity, is
// external work. The kick took the work of the other external forces, and the kinetic energy, at
// the velocity before the constraint: corrected, into the sums, or with `late` into it (per
// imposed velocity: the kick's work, the providers', the frictional part, gravity's, the kinetic
// energy's change) to be added after the kick's sums (forces). (Stored first, then added: added
// here, their products could be fused into the sums, whose last bits would then depend on how the
// compiler contracts them.)
void Solver::applyConstraints(double half_dt, bool second_half, std::vector<double> *late) {
  Nodes &nd = m_.nodes;
  // After the first half the node has drifted with v: by 2 half_dt (target - v) more with the
  // target.
  auto impose = [&](std::uint32_t a, double &v, double &position, double target, double f,
                    double f_ext, double f_friction, double gravity) {
    const double before = v - half_dt * f * inv_mass_[a];
    const double shift = 0.5 * half_dt * (target - v); // mean velocity change x half_dt
    const double change[5] = {
        nd.mass[a] * (target - v) * 0.5 * (before + target), f_ext * shift, f_friction * shift,
        nd.mass[a] * gravity * shift,
        second_half ? 0.5 * nd.mass[a] *
                          (target * target - square(target - before) - v * v + square(v - before))
                    : 0.0};
    if (late)
      late->insert(late->end(), std::begin(change), std::end(change));
    else {
      kick_work_ += change[0], provider_work_ += change[1], friction_work_ += change[2];
      kick_work_ += change[3];
      if (second_half)
        addKinetic(a, change[4]);
    }
    if (!second_half)
      position += 2.0 * half_dt * (target - v);
    v = target;
  };
  for (const auto &c : m_.constraints)
    for (std::uint32_t a : c.nodes) {
      if (m_.at_rest[nd.body[a]] || !owns(nd.body[a]))
        continue;
      if (c.constrain_x)
        impose(a, nd.vx[a], nd.x[a], c.vx, nd.fx[a], nd.external[a].fx, nd.external[a].friction_x,
               s_.gravity_x);
      if (c.constrain_y)
        impose(a, nd.vy[a], nd.y[a], c.vy, nd.fy[a], nd.external[a].fy, nd.external[a].friction_y,
               s_.gravity_y);
    }
}

void Solver::internalForces(double dt) { forces(dt, false); }

// Gravity and the elements' forces of a unit at its nodes' current state, into this thread's
// copies of its nodes (numbered from unit.node_lo), over a step dt.
void Solver::unitPass(const Unit &unit, double dt, UnitScratch &scratch) {
  const Nodes &nd = m_.nodes;
  const double gx = s_.gravity_x, gy = s_.gravity_y;
  const bool gravity = gx != 0.0 || gy != 0.0;
  const std::size_t base = unit.node_lo;
  std::vector<NodeState> &state = scratch.state;
  std::vector<NodeForce> &force = scratch.force;
  state.resize(unit.node_hi - base);
  force.resize(state.size());
  scratch.jacobian.resize(unit.averaged_volume ? state.size() : 0);
  for (std::size_t r = unit.nodes_begin; r < unit.nodes_end; ++r)
    for (std::size_t a = unit_nodes_[r].begin; a < unit_nodes_[r].end; ++a) {
      state[a - base] = {nd.x[a], nd.y[a], nd.vx[a], nd.vy[a]};
      force[a - base] = gravity ? NodeForce{nd.mass[a] * gx, nd.mass[a] * gy} : NodeForce{0.0, 0.0};
    }
  const UnitNodes nodes{state.data(), force.data(), scratch.jacobian.data(), base};
  if (unit.averaged_volume)
    nodalVolumes(unit, nodes);
  for (std::size_t i = unit.chunk_begin; i < unit.chunk_end; ++i)
    elementPass(chunks_[i], dt, nodes, sums_[i]);
}

// Unit by unit (whole bodies, so that a unit's nodes and elements stay in cache between the
// nodal volumes, the element pass and the kick): gravity first, the elements add theirs, the
// external forces at the loaded nodes; with `kick`, the second half-kick of the unit's nodes.
void Solver::forces(double dt, bool kick) {
  Nodes &nd = m_.nodes;
  const long units = static_cast<long>(units_.size());
  kick_sums_.assign(kick ? units : 0, KickSums{});
  if (measure_body_steps_)
    element_step_.assign(m_.elements.size(), HUGE_VAL);
  thread_scratch_.resize(static_cast<std::size_t>(omp_get_max_threads()));
#pragma omp parallel if (units > 1)
  {
    UnitScratch &scratch = threadScratch();
    for (auto [u, end] = threadShare(thread_units_); u < end; ++u) {
      const Unit &unit = units_[u];
      const std::size_t base = unit.node_lo;
      unitPass(unit, dt, scratch);
      const std::vector<NodeState> &state = scratch.state;
      const std::vector<NodeForce> &force = scratch.force;
      KickSums sums; // in registers: the node arrays' stores could alias kick_sums_
      for (std::size_t r = unit.nodes_begin; r < unit.nodes_end; ++r)
        for (std::size_t a = unit_nodes_[r].begin; a < unit_nodes_[r].end; ++a) {
          double fx = force[a - base].x, fy = force[a - base].y;
          if (nd.is_loaded[a])
            fx += nd.external[a].fx, fy += nd.external[a].fy;
          nd.fx[a] = fx, nd.fy[a] = fy;
          if (kick) {
            double vx = state[a - base].vx, vy = state[a - base].vy;
            halfKick(a, 0.5 * dt, fx, fy, true, vx, vy, sums);
            nd.vx[a] = vx, nd.vy[a] = vy;
          }
        }
      if (kick)
        kick_sums_[u] = sums;
    }
  }
  // This process's sums: its elements' energies (chunk order), its units' kick sums (unit order)
  // and the second half's constraints at its nodes (applyConstraints); the processes' shares of
  // the energies are summed only when asked (sumEnergy). The step's figures every process needs
  // in its one reduction (reduceStep).
  const long n = static_cast<long>(chunks_.size());
  double dt_min = std::numeric_limits<double>::infinity();
  std::int64_t inverted = -1;
  for (long i = 0; i < n && inverted < 0; ++i) {
    inverted = sums_[i].inverted;
    dt_min = std::min(dt_min, sums_[i].dt_min);
  }
  double internal = 0.0, plastic = 0.0, viscous = 0.0;
  std::size_t failing = 0, scaling = 0; // this process's elements that failed, that ask for mass
  for (std::size_t i = 0; i < chunks_.size(); ++i) {
    internal += sums_[i].internal;
    plastic += sums_[i].plastic;
    viscous += sums_[i].viscous;
    if (sums_[i].eroding)
      for (std::size_t e = chunks_[i].begin; e < chunks_[i].end; ++e)
        failing += failed_[e] != 0;
    scaling += sums_[i].scaled.size();
  }
  step_sums_ = {internal, plastic, viscous};
  if (kick) {
    std::vector<double> late;
    applyConstraints(0.5 * dt, true, &late);
    energy_.kinetic = 0.0;
    addKickSums(kick_sums_, 0.5 * dt);
    for (std::size_t k = 0; k < late.size(); k += 5) {
      kick_work_ += late[k], provider_work_ += late[k + 1];
      friction_work_ += late[k + 2], kick_work_ += late[k + 3];
      energy_.kinetic += late[k + 4];
    }
  }
  kick_sums_.clear();
  dt_min = reduceStep(dt_min, inverted, failing, scaling,
                      std::isfinite(energy_.kinetic) && std::isfinite(internal), kick, time_ + dt);
  next_dt_ = s_.safety * step_scale_ * dt_min;
  shortest_step_ = dt_min;
  if (measure_body_steps_)
    bodyStepsFromElements();
}

// The step's one reduction (every process calls it; the largest of each value over the
// processes): this process's shortest element step `dt_min` (returned: every process's shortest),
// its first inverted element (-1: none), its elements that failed and that ask for mass (erode and
// scaleMasses gather theirs only when some process has some, as many from each), whether its
// energies are finite; at a step (`kick`) also the providers' figures for the next step (with the
// work shared) and the time loop's values. An inverted element ends the run (`time`: the step's
// end), named by the lowest number whoever computed it (its area from the process that did,
// gathered only then).
double Solver::reduceStep(double dt_min, std::int64_t inverted, std::size_t failing,
                          std::size_t scaling, bool finite, bool kick, double time) {
  std::vector<double> figures = {
      -dt_min, inverted >= 0 ? -static_cast<double>(inverted) : -HUGE_VAL,
      static_cast<double>(failing), static_cast<double>(scaling), finite ? 0.0 : 1.0};
  const bool provider_figures = kick && comm_.size() > 1;
  std::vector<std::size_t> provider_first; // where each provider's figures begin
  if (provider_figures) {
    const double drift = nextDriftBound();
    for (const ForceProvider *provider : providers_) {
      provider_first.push_back(figures.size());
      provider->stepFigures(m_, drift, figures);
    }
  }
  const std::size_t first_agreed = figures.size();
  if (kick) {
    figures.insert(figures.end(), agree_next_.begin(), agree_next_.end());
    agree_next_.clear();
  }
  const std::vector<double> all = comm_.max(std::move(figures));
  most_failing_ = static_cast<std::size_t>(all[2]),
  most_scaling_ = static_cast<std::size_t>(all[3]);
  not_finite_ = all[4] != 0.0;
  if (provider_figures) { // (the bodies woken at other processes move here too from now on)
    for (std::size_t k = 0; k < providers_.size(); ++k)
      providers_[k]->stepReduced(m_, all.data() + provider_first[k]);
    countActive();
  }
  if (kick)
    agreed_.assign(all.begin() + static_cast<long>(first_agreed), all.end());
  if (all[1] > -HUGE_VAL) {
    const auto e = static_cast<std::size_t>(-all[1]);
    const double area =
        comm_.max({inverted == static_cast<std::int64_t>(e) ? m_.elements.area[e] : -HUGE_VAL})[0];
    const Body &body = m_.bodies[m_.elements.body[e]];
    std::ostringstream msg;
    msg << "element " << e << " of body " << body.name << " (material "
        << m_.materials[body.material]->type() << ") is inverted: area " << area
        << " m^2, initially " << m_.elements.area0[e] << " m^2, at t = " << time << " s, step "
        << steps_ + 1;
    throw RunFailure(msg.str());
  }
  return -all[0];
}

// How far any node this process moves can go in the next step's drift, dt' |v + dt'/2 f / m| at
// most (each component bounded by its magnitudes), from the state after this step's second
// half-kick: the next step dt' is at most max_dt_growth times this one (nextStep; the end's equal
// steps are shorter); mass scaling, which comes before it, only adds mass (slower nodes, smaller
// kicks); a node whose velocity is imposed moves by dt' times it (its v now). With levels see
// nextDriftBoundLevels.
double Solver::nextDriftBound() const {
  if (levels())
    return nextDriftBoundLevels();
  const Nodes &nd = m_.nodes;
  const double dt = std::max(1.0, s_.max_dt_growth) * dt_, half_dt = 0.5 * dt;
  const long blocks = static_cast<long>(node_ranges_.size());
  double most = 0.0;
#pragma omp parallel for schedule(static) reduction(max : most) if (blocks > 1)
  for (long i = 0; i < blocks; ++i)
    for (std::size_t a = node_ranges_[i].begin; a < node_ranges_[i].end; ++a) {
      const double ux = std::abs(nd.vx[a]) + half_dt * std::abs(nd.fx[a]) * inv_mass_[a];
      const double uy = std::abs(nd.vy[a]) + half_dt * std::abs(nd.fy[a]) * inv_mass_[a];
      most = std::max(most, ux * ux + uy * uy);
    }
  return dt * std::sqrt(most);
}

// Each active body's own step from the elements' exact steps of the pass (every process's, from
// their owners), with the factors of the solver's step: safety and the providers' scaling.
void Solver::bodyStepsFromElements() {
  measure_body_steps_ = false;
  shareOwned<1>(active_bodies_, &Body::element_begin, &Body::element_end, {&element_step_});
  body_step_.assign(m_.bodies.size(), HUGE_VAL);
  for (std::uint32_t b : active_bodies_) {
    const Body &body = m_.bodies[b];
    double shortest = HUGE_VAL;
    for (std::size_t e = body.element_begin; e < body.element_end; ++e)
      shortest = std::min(shortest, element_step_[e]);
    body_step_[b] = s_.safety * step_scale_ * shortest;
  }
  body_steps_at_ = steps_ + 1;
}

// The element state a process keeps of its own elements and the others read: what output and
// erosion need of them.
std::array<std::vector<double> *, 8> Solver::elementState() const {
  Elements &el = m_.elements;
  return {&el.area,           &el.sxx,      &el.syy, &el.sxy, &el.pressure, &el.energy,
          &el.plastic_strain, &el.viscosity};
}

// `fields` over the range [begin, end) (nodes or elements) of each of `bodies` (in body order),
// copied from the body's owner to every process (or `to_first` to the first only): each sends its
// own bodies' values in body order, and knows where the others' lie (every process knows every
// body's owner).
template <std::size_t N>
void Solver::shareOwned(const std::vector<std::uint32_t> &bodies, std::size_t Body::*begin,
                        std::size_t Body::*end, const std::array<std::vector<double> *, N> &fields,
                        bool to_first) const {
  if (comm_.size() == 1) // (this process holds every value)
    return;
  const std::vector<std::vector<std::uint32_t>> of = byOwner(bodies);
  const std::vector<std::uint32_t> &mine = of[static_cast<std::size_t>(comm_.rank())];
  std::size_t count = 0;
  for (std::uint32_t b : mine)
    count += N * (m_.bodies[b].*end - m_.bodies[b].*begin);
  auto pack = [&](double *out) {
    for (std::uint32_t b : mine)
      for (std::size_t i = m_.bodies[b].*begin; i < m_.bodies[b].*end; ++i)
        for (auto *f : fields)
          *out++ = (*f)[i];
  };
  // process r's values; returns where the next process's begin
  auto unpack = [&](int r, const double *values) {
    for (std::uint32_t b : of[static_cast<std::size_t>(r)])
      for (std::size_t i = m_.bodies[b].*begin; i < m_.bodies[b].*end; ++i)
        for (auto *f : fields)
          (*f)[i] = *values++;
    return values;
  };
  if (to_first)
    comm_.collect(count, pack, unpack);
  else
    comm_.share(count, pack, [&](const double *all) {
      for (int r = 0; r < comm_.size(); ++r)
        all = unpack(r, all);
    });
}

void Solver::collectFrame() const {
  Nodes &nd = m_.nodes;
  shareOwned(active_bodies_, &Body::element_begin, &Body::element_end, elementState(), true);
  shareOwned<4>(active_bodies_, &Body::node_begin, &Body::node_end, {&nd.x, &nd.y, &nd.vx, &nd.vy},
                true);
}

void Solver::collectCheckpoint() {
  Nodes &nd = m_.nodes;
  collectFrame();
  shareOwned<2>(active_bodies_, &Body::node_begin, &Body::node_end, {&nd.fx, &nd.fy}, true);
  collectExternal(active_bodies_);
  if (levels())
    collectLevels();
  if (comm_.size() > 1) { // every process's share, kept for the checkpoint, and their sum
    checkpoint_shares_ = comm_.allGather(
        sharesOf(energy_), std::vector<std::int64_t>(static_cast<std::size_t>(comm_.size()),
                                                     std::ssize(energy_shares)));
    sumShares(checkpoint_shares_);
  }
}

// The external forces at the nodes of `bodies`, complete at their owners only (the providers'
// forces of this step), copied from them to the first process; a node they load is listed as
// loaded there.
void Solver::collectExternal(const std::vector<std::uint32_t> &bodies) {
  if (comm_.size() == 1) // (this process holds every value)
    return;
  Nodes &nd = m_.nodes;
  const std::vector<std::vector<std::uint32_t>> of = byOwner(bodies);
  const std::vector<std::uint32_t> &mine = of[static_cast<std::size_t>(comm_.rank())];
  std::size_t count = 0;
  for (std::uint32_t b : mine)
    count += 4 * (m_.bodies[b].node_end - m_.bodies[b].node_begin);
  auto pack = [&](double *out) {
    for (std::uint32_t b : mine)
      for (std::size_t a = m_.bodies[b].node_begin; a < m_.bodies[b].node_end; ++a) {
        const Nodes::External &e = nd.external[a];
        *out++ = e.fx, *out++ = e.fy, *out++ = e.friction_x, *out++ = e.friction_y;
      }
  };
  auto unpack = [&](int r, const double *values) {
    for (std::uint32_t b : of[static_cast<std::size_t>(r)])
      for (std::size_t a = m_.bodies[b].node_begin; a < m_.bodies[b].node_end; ++a, values += 4) {
        nd.external[a] = {values[0], values[1], values[2], values[3]};
        if (!nd.is_loaded[a] &&
            (values[0] != 0.0 || values[1] != 0.0 || values[2] != 0.0 || values[3] != 0.0))
          nd.is_loaded[a] = 1, nd.loaded.push_back(static_cast<std::uint32_t>(a));
      }
  };
  comm_.collect(count, pack, unpack);
}

// Each process's bodies among `bodies`, in their order.
std::vector<std::vector<std::uint32_t>>
Solver::byOwner(const std::vector<std::uint32_t> &bodies) const {
  std::vector<std::vector<std::uint32_t>> of(static_cast<std::size_t>(comm_.size()));
  for (std::uint32_t b : bodies)
    of[static_cast<std::size_t>(owner(b))].push_back(b);
  return of;
}

// The active element with the shortest altitude, and what it has become: for the message of a
// collapsed step.
std::string Solver::thinnestElement() const {
  const Nodes &nd = m_.nodes;
  const Elements &el = m_.elements;
  std::size_t thinnest = 0;
  double altitude = HUGE_VAL, longest = 0.0;
  for (const Chunk &c : chunks_)
    for (std::size_t e = c.begin; e < c.end; ++e) {
      const std::uint32_t *v = &el.node[3 * e];
      double edge = 0.0;
      for (int k = 0; k < 3; ++k)
        edge = std::max(
            edge, std::hypot(nd.x[v[(k + 1) % 3]] - nd.x[v[k]], nd.y[v[(k + 1) % 3]] - nd.y[v[k]]));
      if (2.0 * el.area[e] / edge < altitude)
        thinnest = e, altitude = 2.0 * el.area[e] / edge, longest = edge;
    }
  const Body &body = m_.bodies[el.body[thinnest]];
  std::ostringstream msg;
  msg << "element " << thinnest << " of body " << body.name << " (material "
      << m_.materials[body.material]->type() << "), altitude " << altitude << " m, longest edge "
      << longest << " m, area " << el.area[thinnest] / el.area0[thinnest]
      << " of the initial, plastic strain " << el.plastic_strain[thinnest] << ", pressure "
      << el.pressure[thinnest] << " Pa";
  return msg.str();
}

// Averaged nodal volume (Bonet & Burton 1998): J at a node is the area of its elements over their
// initial area (a third of each); an element takes the mean J of its three nodes for its
// pressure, which removes the volumetric locking of constant-strain triangles in plastic flow.
void Solver::nodalVolumes(const Unit &unit, const UnitNodes &nodes) {
  const double *area0 = m_.nodes.area0.data();
  const std::uint32_t *conn = m_.elements.node.data();
  const NodeState *state = nodes.state;
  double *jacobian = nodes.jacobian;
  const std::size_t base = nodes.base;
  for (std::size_t r = unit.nodes_begin; r < unit.nodes_end; ++r)
    for (std::size_t a = unit_nodes_[r].begin; a < unit_nodes_[r].end; ++a)
      jacobian[a - base] = 0.0;
  for (std::size_t i = unit.chunk_begin; i < unit.chunk_end; ++i) {
    if (!chunks_[i].averaged_volume)
      continue;
    for (std::size_t e = chunks_[i].begin; e < chunks_[i].end; ++e) {
      const std::size_t a = conn[3 * e] - base, b = conn[3 * e + 1] - base,
                        c = conn[3 * e + 2] - base;
      const NodeState &sa = state[a], &sb = state[b], &sc = state[c];
      const double third =
          (1.0 / 6.0) * ((sb.x - sa.x) * (sc.y - sa.y) - (sc.x - sa.x) * (sb.y - sa.y));
      jacobian[a] += third, jacobian[b] += third, jacobian[c] += third;
    }
  }
  for (std::size_t r = unit.nodes_begin; r < unit.nodes_end; ++r)
    for (std::size_t a = unit_nodes_[r].begin; a < unit_nodes_[r].end; ++a)
      jacobian[a - base] = area0[a] > 0.0 ? jacobian[a - base] / area0[a] : 1.0; // 0: detached
}

// Kinematics, material update, artificial viscosity and nodal forces of one batch of elements.
void Solver::elementPass(const Chunk &chunk, double dt, const UnitNodes &nodes, ChunkSums &sums) {
  alignas(64) double dxx[max_chunk], dyy[max_chunk], dxy[max_chunk], spin[max_chunk];
  alignas(64) double jac[max_chunk], dvol[max_chunk], vmid[max_chunk], len[max_chunk],
      cs[max_chunk];
  alignas(64) double gx[3][max_chunk], gy[3][max_chunk]; // 2A dN_k/dx, 2A dN_k/dy at n+1
  Elements &el = m_.elements;
  const std::size_t n = chunk.end - chunk.begin, e0 = chunk.begin;
  const std::uint32_t *conn = el.node.data() + 3 * e0;
  const double *area0 = el.area0.data() + e0;
  double *area = el.area.data() + e0;
  const bool averaged = chunk.averaged_volume;
  const double hdt = 0.5 * dt;
  double min_area = HUGE_VAL;

  // Kinematics: D and w on the mid-step configuration x(n+1/2) = x(n+1) - dt/2 v(n+1/2) (a rigid
  // rotation then gives D = 0 exactly); the area, the shape function gradients and the element's
  // shortest altitude at n+1.
  alignas(64) double x[3][max_chunk], y[3][max_chunk], vx[3][max_chunk], vy[3][max_chunk];
  for (int k = 0; k < 3; ++k)
    gatherNodeStates(nodes.state, nodes.base, conn, k, n, x[k], y[k], vx[k], vy[k]);
#pragma omp simd reduction(min : min_area)
  for (std::size_t i = 0; i < n; ++i) {
    const double xa = x[0][i], xb = x[1][i], xc = x[2][i], ya = y[0][i], yb = y[1][i], yc = y[2][i];
    const double vxa = vx[0][i], vxb = vx[1][i], vxc = vx[2][i];
    const double vya = vy[0][i], vyb = vy[1][i], vyc = vy[2][i];
    const double area_new = 0.5 * ((xb - xa) * (yc - ya) - (xc - xa) * (yb - ya));
    const double mxa = xa - hdt * vxa, mxb = xb - hdt * vxb, mxc = xc - hdt * vxc;
    const double mya = ya - hdt * vya, myb = yb - hdt * vyb, myc = yc - hdt * vyc;
    const double two_am = (mxb - mxa) * (myc - mya) - (mxc - mxa) * (myb - mya);
    const double inv = 1.0 / two_am;
    const double bxa = (myb - myc) * inv, bxb = (myc - mya) * inv, bxc = (mya - myb) * inv;
    const double bya = (mxc - mxb) * inv, byb = (mxa - mxc) * inv, byc = (mxb - mxa) * inv;
    const double lxx = vxa * bxa + vxb * bxb + vxc * bxc, lyy = vya * bya + vyb * byb + vyc * byc;
    const double lxy = vxa * bya + vxb * byb + vxc * byc, lyx = vya * bxa + vyb * bxb + vyc * bxc;
    dxx[i] = lxx, dyy[i] = lyy, dxy[i] = 0.5 * (lxy + lyx), spin[i] = 0.5 * (lyx - lxy);
    dvol[i] = area_new - area[i];
    vmid[i] = 0.5 * two_am;
    area[i] = area_new;
    gx[0][i] = yb - yc, gx[1][i] = yc - ya, gx[2][i] = ya - yb;
    gy[0][i] = xc - xb, gy[1][i] = xa - xc, gy[2][i] = xb - xa;
    const double lab = (xb - xa) * (xb - xa) + (yb - ya) * (yb - ya);
    const double lbc = (xc - xb) * (xc - xb) + (yc - yb) * (yc - yb);
    const double lca = (xa - xc) * (xa - xc) + (ya - yc) * (ya - yc);
    len[i] = 2.0 * area_new / std::sqrt(std::max(lab, std::max(lbc, lca)));
    min_area = std::min(min_area, std::min(area_new, two_am));
  }
  sums.inverted = -1;
  sums.eroding = false;
  sums.scaled.clear();
  if (!(min_area > 0.0)) {
    for (std::size_t i = 0; i < n; ++i)
      if (!(area[i] > 0.0 && vmid[i] > 0.0))
        sums.inverted = static_cast<long>(e0 + i);
    if (sums.inverted < 0)
      sums.inverted = static_cast<long>(e0);
    sums.dt_min = HUGE_VAL;
    return;
  }
  // J = V / V0, or the mean of the three nodal J (averaged nodal volume, see nodalVolumes).
  if (averaged) {
    elementMean(nodes.jacobian, nodes.base, conn, n, jac);
  } else {
#pragma omp simd
    for (std::size_t i = 0; i < n; ++i)
      jac[i] = area[i] / area0[i];
  }

  // Stress update by the body's material.
  // Materials without strength take their deviator from the deformation gradient F = dx/dX, at
  // n + 1 and at n (x(n) = x(n+1) - dt v(n+1/2)), on the constant-strain triangle's initial shape.
  alignas(64) double f_new[4][max_chunk], f_old[4][max_chunk];
  alignas(64) double r_new[max_chunk], r_old[max_chunk]; // J^(-1/3)
  const bool total_form = chunk.material->usesDeformationGradient();
  if (total_form) {
    alignas(64) double j_new[max_chunk], j_old[max_chunk];
    const double *ixx = reference_inverse_[0].data() + e0, *ixy = reference_inverse_[1].data() + e0;
    const double *iyx = reference_inverse_[2].data() + e0, *iyy = reference_inverse_[3].data() + e0;
#pragma omp simd
    for (std::size_t i = 0; i < n; ++i) {
      // F = [x_b - x_a, x_c - x_a] [X_b - X_a, X_c - X_a]^-1, at n+1 and at n.
      double exx = x[1][i] - x[0][i], exy = x[2][i] - x[0][i];
      double eyx = y[1][i] - y[0][i], eyy = y[2][i] - y[0][i];
      f_new[0][i] = exx * ixx[i] + exy * iyx[i], f_new[1][i] = exx * ixy[i] + exy * iyy[i];
      f_new[2][i] = eyx * ixx[i] + eyy * iyx[i], f_new[3][i] = eyx * ixy[i] + eyy * iyy[i];
      j_new[i] = f_new[0][i] * f_new[3][i] - f_new[1][i] * f_new[2][i];
      exx -= dt * (vx[1][i] - vx[0][i]), exy -= dt * (vx[2][i] - vx[0][i]);
      eyx -= dt * (vy[1][i] - vy[0][i]), eyy -= dt * (vy[2][i] - vy[0][i]);
      f_old[0][i] = exx * ixx[i] + exy * iyx[i], f_old[1][i] = exx * ixy[i] + exy * iyy[i];
      f_old[2][i] = eyx * ixx[i] + eyy * iyx[i], f_old[3][i] = eyx * ixy[i] + eyy * iyy[i];
      j_old[i] = f_old[0][i] * f_old[3][i] - f_old[1][i] * f_old[2][i];
    }
    inverseCubeRoots(j_new, r_new, n);
    inverseCubeRoots(j_old, r_old, n);
  }
  StrainBatch in{n, dt, dxx, dyy, dxy, spin, jac, dvol, vmid, el.area0.data() + e0};
  if (total_form) {
    in.f = {f_new[0], f_new[1], f_new[2], f_new[3]};
    in.f_old = {f_old[0], f_old[1], f_old[2], f_old[3]};
    in.inverse_cube_root_j = r_new, in.inverse_cube_root_j_old = r_old;
  }
  StressState state{el.sxx.data() + e0,      el.syy.data() + e0,    el.sxy.data() + e0,
                    el.pressure.data() + e0, el.energy.data() + e0, el.plastic_strain.data() + e0};
  alignas(64) double shear_share[max_chunk];
  MaterialOutput out{cs, shear_share};
  chunk.material->update(in, state, out);
  // Elements that failed (hasFailed, or a step below erode_below_) leave the model after this step
  // (erode): their step does not count.
  const double erosion =
      chunk.material->erosionStrain() > 0.0 ? chunk.material->erosionStrain() : HUGE_VAL;
  const double *plastic_strain = state.plastic_strain;
  long failing = 0;

  // Artificial viscosity (Wilkins 1980), compression only:
  //   q = rho L (C_Q L tr(D)^2 + C_L c |tr(D)|),  tr(D) < 0,  L the shortest altitude;
  // nodal forces f_a = -A B_a^T sigma on the configuration at n+1; the stable step
  //   dt_e = L_s / (Q + sqrt(Q^2 + c^2)),  Q = C_L c + C_Q L_s |tr(D)|,  L_s = 2/3 L.
  // L / c exceeds the critical step 2 / omega_max of a lumped-mass triangle by up to a factor 1.5
  // (equilateral, G -> 0 or K >> G; 1.26 for steel); 2/3 L makes dt_e a bound for every shape
  // and material, so that `safety` is a true margin (tests/unit/fem.cpp checks it).
  const double cl = s_.viscosity_linear, cq = s_.viscosity_quadratic;
  double internal = 0.0, viscous = 0.0, dt_min = HUGE_VAL;
  alignas(64) double fx[3][max_chunk], fy[3][max_chunk], step[max_chunk];
  alignas(64) std::uint8_t fail[max_chunk];
  const double erode_below = erode_below_;
  const double rho0 = chunk.material->density();
  const double *sxx_ = el.sxx.data() + e0, *syy_ = el.syy.data() + e0, *sxy_ = el.sxy.data() + e0;
  const double *pressure = el.pressure.data() + e0;
  double *energy = el.energy.data() + e0, *viscosity = el.viscosity.data() + e0;
  // (the shortest step after the loop: GCC 12 with AVX-512 vectors gave this loop's min
  // reduction a longer step than its elements' shortest, docs/decisions.md)
#pragma omp simd reduction(+ : internal, viscous, failing)
  for (std::size_t i = 0; i < n; ++i) {
    const double comp = std::max(-(dxx[i] + dyy[i]), 0.0);
    const double rho = rho0 * area0[i] / area[i];
    const double q = rho * len[i] * comp * (cq * len[i] * comp + cl * cs[i]);
    const double q_work = -0.5 * (viscosity[i] + q) * dvol[i]; // trapezoid, as the stress
    viscosity[i] = q;
    energy[i] += q_work;
    viscous += q_work;
    internal += energy[i];
    const double pq = pressure[i] + q;
    const double sxx = sxx_[i] - pq, syy = syy_[i] - pq, sxy = sxy_[i];
    for (int k = 0; k < 3; ++k) {
      fx[k][i] = -0.5 * (sxx * gx[k][i] + sxy * gy[k][i]);
      fy[k][i] = -0.5 * (sxy * gx[k][i] + syy * gy[k][i]);
    }
    const double ls = (2.0 / 3.0) * len[i], Q = cl * cs[i] + cq * ls * comp;
    const double stable = ls / (Q + std::sqrt(Q * Q + cs[i] * cs[i]));
    const bool collapsed = stable < erode_below;
    const bool fails = hasFailed(plastic_strain[i], area[i], area0[i], erosion) || collapsed;
    fail[i] = fails ? 1 + collapsed : 0;
    failing += fails;
    step[i] = fails ? HUGE_VAL : stable;
  }
  for (std::size_t i = 0; i < n; ++i)
    dt_min = std::min(dt_min, step[i]);
  sums.eroding = failing > 0;
  if (failing > 0)
    for (std::size_t i = 0; i < n; ++i)
      failed_[e0 + i] = fail[i];
  // measureBodySteps: the steps before the refinement below, to tell which it left as they were.
  alignas(64) double unrefined[max_chunk];
  const bool measuring = measure_body_steps_;
  if (measuring)
    std::copy(step, step + n, unrefined);
  // The elements whose step is near the shortest of the last pass (refine_below) take the exact
  // element bound for their material's state: L_s / c times criticalStepGain, the damping factor
  // unchanged.
  const double refine_below = refine_margin * shortest_step_;
  // With levels, the gain on its step each element is known to have (below): 1 for those refined
  // here, which have it already.
  alignas(64) double known_gain[max_chunk];
  if (levels())
    std::fill(known_gain, known_gain + n, 0.0);
  // (in vector lanes, criticalStepGains: in a uniform mesh every element may be near)
  if (dt_min < refine_below) {
    alignas(64) std::uint32_t near[max_chunk];
    alignas(64) double gain[max_chunk];
    std::size_t count = 0;
    for (std::size_t i = 0; i < n; ++i) {
      near[count] = static_cast<std::uint32_t>(i);
      count += step[i] < refine_below;
    }
    criticalStepGains(near, count, gx, gy, area, len, shear_share, gain);
    for (std::size_t j = 0; j < count; ++j)
      step[near[j]] *= gain[j], known_gain[near[j]] = 1.0;
    dt_min = HUGE_VAL;
    for (std::size_t i = 0; i < n; ++i)
      dt_min = std::min(dt_min, step[i]);
  }
  // For the others: the exact gain (criticalStepGain) where the step may set its body's (its least
  // gain over shapes, leastStepGain, brings it below the body's last shortest with a margin for
  // this step's change), the least over shapes elsewhere (a lower bound: the body's step never
  // comes out too long).
  if (levels()) {
    alignas(64) double least[max_chunk], exact[max_chunk];
    alignas(64) std::uint32_t pick[max_chunk]; // the elements that take the exact gain
#pragma omp simd
    for (std::size_t i = 0; i < n; ++i)
      least[i] = leastStepGain(shear_share[i]);
    // (an element of a body in parts: its part's step)
    const double part_step = chunk.part != Chunk::no_part ? part_step_min_[chunk.part] : 0.0;
    const std::uint32_t *body = el.body.data() + e0;
    std::size_t picked = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const bool refined = known_gain[i] == 1.0;
      const double reference = chunk.part != Chunk::no_part ? part_step : body_step_min_[body[i]];
      pick[picked] = static_cast<std::uint32_t>(i);
      picked += !refined && step[i] * least[i] < refine_margin * reference;
      known_gain[i] = refined ? 1.0 : least[i];
    }
    criticalStepGains(pick, picked, gx, gy, area, len, shear_share, exact);
    for (std::size_t j = 0; j < picked; ++j)
      known_gain[pick[j]] = exact[j];
  }
  // Selective mass scaling: an element whose step is below scale_below_ needs the mass
  //   m_e ((scale_below_ / dt_e)^2 - 1)
  // added on its nodes, a third on each: the lumped element's frequencies scale as 1 / sqrt(mass),
  // so its step becomes scale_below_ (scaleMasses adds it after the pass).
  if (dt_min < scale_below_) {
    dt_min = HUGE_VAL;
    for (std::size_t i = 0; i < n; ++i) {
      if (step[i] < scale_below_) {
        const auto e = static_cast<std::uint32_t>(e0 + i);
        const double mass = rho0 * area0[i], needed = mass * (square(scale_below_ / step[i]) - 1.0);
        const auto it = added_mass_.find(e);
        const double added = it == added_mass_.end() ? 0.0 : it->second;
        if (needed > added)
          sums.scaled.emplace_back(e, needed), step[i] = scale_below_;
        else
          step[i] *= std::sqrt(1.0 + added / mass);
      }
      dt_min = std::min(dt_min, step[i]);
    }
  }
  // measureBodySteps: every element's step as the refinement and the mass scaling above make it,
  // the exact bound (criticalStepGain) also for those the refinement left.
  if (measuring) {
    double *exact = element_step_.data() + e0;
    for (std::size_t i = 0; i < n; ++i) {
      exact[i] = step[i];
      if (step[i] == unrefined[i] && step[i] < HUGE_VAL) {
        const double g_x[3] = {gx[0][i], gx[1][i], gx[2][i]},
                     g_y[3] = {gy[0][i], gy[1][i], gy[2][i]};
        exact[i] *= criticalStepGain(g_x, g_y, area[i], (2.0 / 3.0) * len[i], shear_share[i]);
      }
    }
  }
  // With levels, each element's step for its body's (bodySums), the known gain on the cheap bound
  // taken (mass scaling lowers all of an element's frequencies alike: the gain holds).
  if (levels())
    for (std::size_t i = 0; i < n; ++i)
      level_step_[e0 + i] = step[i] * known_gain[i];
  // Into the unit's nodes, in element order.
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      NodeForce &f = nodes.force[conn[3 * i + k] - nodes.base];
      f.x += fx[k][i], f.y += fy[k][i];
    }
  sums.internal = internal;
  sums.plastic = out.plastic_work;
  sums.viscous = viscous;
  sums.dt_min = dt_min;
}

// `values` padded with -1 to `count`, as every process gives to an all-gather of equal parts
// (equalParts); with one process as they are.
std::vector<double> Solver::padTo(std::vector<double> values, std::size_t count) const {
  if (comm_.size() == 1)
    return values;
  if (values.size() > count)
    throw std::logic_error("padTo: " + std::to_string(values.size()) + " values, more than the " +
                           std::to_string(count) + " the step's reduction said");
  values.resize(count, -1.0);
  return values;
}

std::vector<std::int64_t> Solver::equalParts(std::size_t count) const {
  return std::vector<std::int64_t>(static_cast<std::size_t>(comm_.size()),
                                   static_cast<std::int64_t>(count));
}

// The elements that failed in this step's pass (flagged in failed_ by elementPass) are removed
// (erodeElements): their internal energy is booked as eroded, the element chunks are laid out
// anew and the providers take the new boundaries. Their forces leave f(n+1), which the next
// half-kick uses; the step to come was taken without them (elementPass).
void Solver::erode() {
  if (most_failing_ == 0) // no element of any process failed in this step's pass
    return;
  std::vector<std::uint32_t> failed;
  std::vector<std::uint8_t> kind;
  for (std::size_t i = 0; i < chunks_.size(); ++i)
    if (sums_[i].eroding)
      for (std::size_t e = chunks_[i].begin; e < chunks_[i].end; ++e)
        if (failed_[e]) {
          kind.push_back(failed_[e]);
          failed_[e] = 0, failed.push_back(static_cast<std::uint32_t>(e));
        }
  Elements &el = m_.elements;
  { // every process's failed elements, with their state, in element order: per element its
    // number and kind (exact as doubles), then its state, in one all-gather of as many values
    // from each process (the most any has, from the step's reduction; -1: none)
    const auto state = elementState();
    const std::size_t values = 2 + state.size();
    std::vector<double> mine;
    for (std::size_t j = 0; j < failed.size(); ++j) {
      mine.insert(mine.end(), {static_cast<double>(failed[j]), static_cast<double>(kind[j])});
      for (auto *f : state)
        mine.push_back((*f)[failed[j]]);
    }
    const std::vector<double> all = comm_.allGather(padTo(std::move(mine), most_failing_ * values),
                                                    equalParts(most_failing_ * values));
    std::vector<std::pair<std::uint32_t, std::uint8_t>> every;
    for (std::size_t k = 0; k < all.size(); k += values) {
      if (all[k] < 0.0)
        continue;
      const auto e = static_cast<std::uint32_t>(all[k]);
      every.emplace_back(e, static_cast<std::uint8_t>(all[k + 1]));
      for (std::size_t f = 0; f < state.size(); ++f)
        (*state[f])[e] = all[k + 2 + f];
    }
    std::sort(every.begin(), every.end());
    failed.clear(), kind.clear();
    for (auto [e, k] : every)
      failed.push_back(e), kind.push_back(k);
  }
  for (std::uint8_t k : kind)
    collapsed_elements_ += k == 2;
  if (failed.empty())
    return;
  // Their forces leave f(n+1) with them: f_k = -A B_k^T sigma, as in elementPass (in a body in
  // parts, as its part's force came into f(n+1): nextForceWeight).
  Nodes &nd = m_.nodes;
  for (std::uint32_t e : failed) {
    const std::uint32_t *v = &el.node[3 * e];
    const double pq = el.pressure[e] + el.viscosity[e], w = nextForceWeight(e);
    const double sxx = w * (el.sxx[e] - pq), syy = w * (el.syy[e] - pq), sxy = w * el.sxy[e];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t b = v[(k + 1) % 3], c = v[(k + 2) % 3];
      const double gx = nd.y[b] - nd.y[c], gy = nd.x[c] - nd.x[b];
      nd.fx[v[k]] += 0.5 * (sxx * gx + sxy * gy);
      nd.fy[v[k]] += 0.5 * (sxy * gx + syy * gy);
    }
  }
  if (levels()) // their energy leaves their body's sum (until its next update sums it anew)
    for (std::uint32_t e : failed)
      if (!el.eroded[e])
        body_internal_[el.body[e]] -= el.energy[e];
  // (every process erodes every failed element: the energy they take is the first process's share)
  const double taken = erodeElements(m_, failed);
  const double energy = comm_.rank() == 0 ? taken : 0.0;
  energy_.eroded += energy;
  eroded_elements_ += failed.size();
  energy_.internal -= energy; // this step's pass summed theirs
  at_rest_seen_.clear();      // the chunks are laid out anew
  std::vector<std::uint32_t> bodies;
  for (std::uint32_t e : failed)
    bodies.push_back(el.body[e]);
  std::sort(bodies.begin(), bodies.end());
  bodies.erase(std::unique(bodies.begin(), bodies.end()), bodies.end());
  // (the providers measure the new boundaries against their neighbours: the positions of every
  // node of those bodies, which may now lie on a boundary, from their owners)
  shareOwned<2>(bodies, &Body::node_begin, &Body::node_end, {&nd.x, &nd.y});
  for (auto *provider : providers_)
    provider->boundaryChanged(m_, bodies);
}

// The mass the element pass asked for (mass_scaling_step_ratio), added at v(n+1) to each element's
// three nodes, a third each. The nodes keep their momentum, v' = v m / m' (a velocity imposed by a
// constraint is kept); the change of the leapfrog kinetic energy 1/2 m (|v|^2 - |dv|^2), dv the
// half-kick dt/2 f / m, is booked as mass_scaling.
void Solver::scaleMasses(double half_dt) {
  if (!(scale_below_ > 0.0) || most_scaling_ == 0) // off, or no element asked (every process knows)
    return;
  std::vector<std::pair<std::uint32_t, double>> scaled;
  for (std::size_t i = 0; i < chunks_.size(); ++i)
    scaled.insert(scaled.end(), sums_[i].scaled.begin(), sums_[i].scaled.end());
  { // every process's, in element order: number (exact as a double) and mass, in one all-gather
    // of as many from each process (the most any has, from the step's reduction; -1: none)
    std::vector<double> mine;
    for (auto [e, mass] : scaled)
      mine.insert(mine.end(), {static_cast<double>(e), mass});
    const std::vector<double> all =
        comm_.allGather(padTo(std::move(mine), 2 * most_scaling_), equalParts(2 * most_scaling_));
    scaled.clear();
    for (std::size_t k = 0; k < all.size(); k += 2)
      if (all[k] >= 0.0)
        scaled.emplace_back(static_cast<std::uint32_t>(all[k]), all[k + 1]);
    std::sort(scaled.begin(), scaled.end());
  }
  if (scaled.empty())
    return;
  Nodes &nd = m_.nodes;
  if (constrained_.size() != nd.size()) {
    constrained_.assign(nd.size(), 0);
    for (const auto &c : m_.constraints)
      for (std::uint32_t a : c.nodes)
        constrained_[a] |= (c.constrain_x ? 1 : 0) | (c.constrain_y ? 2 : 0);
  }
  // (with levels, over half the window of the node's body)
  auto kinetic = [&](std::size_t a) {
    const double h = levels() ? 0.5 * m_.window[nd.body[a]] : half_dt;
    const double dvx = h * nd.fx[a] / nd.mass[a], dvy = h * nd.fy[a] / nd.mass[a];
    return 0.5 * nd.mass[a] * (nd.vx[a] * nd.vx[a] + nd.vy[a] * nd.vy[a] - dvx * dvx - dvy * dvy);
  };
  // The kinetic energy a node's change takes is measured by its owner (its velocity and force are
  // current there), into its share of the energies, in the elements' order.
  for (std::size_t i = 0; i < scaled.size(); ++i) {
    const auto [e, needed] = scaled[i];
    double &added = added_mass_[e];
    const double share = (needed - added) / 3.0;
    added = needed;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = m_.elements.node[3 * e + k];
      const bool own = owns(nd.body[a]);
      const double before = own ? kinetic(a) : 0.0, ratio = nd.mass[a] / (nd.mass[a] + share);
      nd.mass[a] += share;
      inv_mass_[a] = 1.0 / nd.mass[a];
      if (!(constrained_[a] & 1))
        nd.vx[a] *= ratio;
      if (!(constrained_[a] & 2))
        nd.vy[a] *= ratio;
      if (own) {
        const double change = kinetic(a) - before;
        addKinetic(a, change);
        energy_.mass_scaling -= change;
      }
    }
  }
}

double Solver::addedMass(std::size_t body) const {
  // summed in element order: the same after a run continued from a checkpoint
  std::vector<std::pair<std::uint32_t, double>> added(added_mass_.begin(), added_mass_.end());
  std::sort(added.begin(), added.end());
  double mass = 0.0;
  for (auto [e, m] : added)
    if (body == all_bodies || m_.elements.body[e] == body)
      mass += m;
  return mass;
}

void Solver::accountEnergy() {
  // Element sums of this step's pass (chunk order: the same for any thread count), this
  // process's (forces).
  const double internal = step_sums_[0], plastic = step_sums_[1], viscous = step_sums_[2];
  energy_.internal = internal;
  energy_.plastic += plastic;
  energy_.viscous += viscous;
  energy_.friction -= friction_work_;
  energy_.contact -= provider_work_ - friction_work_;
  energy_.external += kick_work_;
  energy_.balance_error = balanceError(energy_); // (with several processes: sumEnergy's)
}

const Energy &Solver::sumEnergy() const {
  if (comm_.size() == 1)
    return energy_;
  sumShares(comm_.allGather(sharesOf(energy_),
                            std::vector<std::int64_t>(static_cast<std::size_t>(comm_.size()),
                                                      std::ssize(energy_shares))));
  return summed_;
}

// The run's energies from every process's shares (`all`, in rank order), added in rank order.
void Solver::sumShares(const std::vector<double> &all) const {
  const std::size_t n = std::size(energy_shares);
  Energy sum{.initial = energy_.initial};
  for (std::size_t k = 0; k < all.size(); ++k)
    sum.*energy_shares[k % n] += all[k];
  sum.balance_error = balanceError(sum);
  summed_ = sum;
}

Solver::State Solver::state() const {
  State st;
  st.time = time_, st.dt = dt_, st.next_dt = next_dt_, st.shortest_allowed = shortest_allowed_;
  st.first_dt = first_dt_, st.erode_below = erode_below_, st.scale_below = scale_below_;
  st.shortest_step = shortest_step_;
  st.steps = steps_, st.eroded_elements = eroded_elements_;
  st.collapsed_elements = collapsed_elements_;
  st.energy = energy();
  std::vector<std::pair<std::uint32_t, double>> added(added_mass_.begin(), added_mass_.end());
  std::sort(added.begin(), added.end());
  for (auto [e, mass] : added)
    st.scaled_elements.push_back(e), st.scaled_mass.push_back(mass);
  st.energy_shares = checkpoint_shares_;
  if (levels())
    st.levels = levelsState();
  if (comm_.size() > 1 && partitioned_) {
    st.owner = owner_;
    st.partition_ranks = comm_.size();
    st.partition_achieved = last_achieved_, st.partition_total = last_total_;
  }
  return st;
}

void Solver::restore(const State &st) {
  time_ = st.time, dt_ = st.dt, next_dt_ = st.next_dt, shortest_allowed_ = st.shortest_allowed;
  first_dt_ = st.first_dt, erode_below_ = st.erode_below, scale_below_ = st.scale_below;
  shortest_step_ = st.shortest_step;
  steps_ = st.steps, eroded_elements_ = st.eroded_elements;
  collapsed_elements_ = st.collapsed_elements;
  // (each process's share as it was, on as many processes; else the run's are the first
  // process's share, the others' none)
  energy_ = summed_ = st.energy;
  const std::size_t n_shares = std::size(energy_shares);
  if (st.energy_shares.size() == n_shares * static_cast<std::size_t>(comm_.size())) {
    for (std::size_t k = 0; k < n_shares; ++k)
      energy_.*energy_shares[k] =
          st.energy_shares[n_shares * static_cast<std::size_t>(comm_.rank()) + k];
  } else if (comm_.rank() != 0)
    energy_ = Energy{.initial = st.energy.initial};
  added_mass_.clear();
  for (std::size_t k = 0; k < st.scaled_elements.size(); ++k)
    added_mass_[st.scaled_elements[k]] = st.scaled_mass[k];
  const Nodes &nd = m_.nodes;
  for (std::size_t a = 0; a < nd.size(); ++a)
    inv_mass_[a] = nd.mass[a] > 0.0 ? 1.0 / nd.mass[a] : 0.0;
  constrained_.clear();
  std::fill(failed_.begin(), failed_.end(), 0);
  // The partition as it was, on as many processes (a checkpoint holds every process's state:
  // any partition could take it up, but the energies' shares would be summed in another order).
  const bool same_partition = st.partition_ranks == comm_.size() &&
                              st.owner.size() == owner_.size() &&
                              std::all_of(st.owner.begin(), st.owner.end(),
                                          [&](int r) { return r >= 0 && r < comm_.size(); });
  if (same_partition) {
    owner_ = st.owner;
    partitioned_ = true;
    last_achieved_ = st.partition_achieved, last_total_ = st.partition_total;
  }
  if (levels())
    restoreLevels(st.levels);
  at_rest_seen_.clear(); // the chunks laid out anew: eroded elements leave them
  updateActivity(!same_partition);
  step_elements_ = active_elements_;
  load_check_due_ = false; // (the step before the checkpoint checked the load)
}

} // namespace mesopen::fem
