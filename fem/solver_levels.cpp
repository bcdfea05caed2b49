// Multiple time stepping by body (SolverSettings::max_level > 0; docs/solver.md, "Multiple time
// stepping"). Each body b steps at its level e_b: every 2^e_b base steps, a whole central-
// difference step over its window tau = the time since its last step,
//   v += tau'/2 f/m + J/(2m),  x += tau' v,  f = internal(x, v) + f_ext,  v += tau/2 f/m + J/(2m),
// its nodes standing still in between. A pair of bodies is computed only at steps where both
// step; its penalty and friction take the pair's window tau_p (the coarser body's) and it gives
// each body the impulse J = tau_p f as a force over the body's own window (Model::window), half in
// this step's second half-kick and half in the next first half-kick: the impulse (r-RESPA,
// Tuckerman et al. 1992; asynchronous variational integrators, Lew et al. 2003) form of the
// contact across levels. A body's level is the longest power of two of base steps within its own
// stable step, at most level_gap levels coarser than the own level of any body it may meet (the
// contact's Verlet pairs, found before the bodies touch), chosen at its own steps (aligned: a
// level l begins at a step number that is a multiple of 2^l). Bodies with imposed velocities stay
// at level 0. A large body (the projectile) steps in parts, each at its own level at or above its
// body's (partsPass).
#include "levels.hpp"
#include "solver.hpp"
#include "threads.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numeric>
#include <sstream>

namespace mesopen::fem {

void Solver::startLevels() {
  if (s_.max_level > 7)
    throw std::invalid_argument("max_level " + std::to_string(s_.max_level) +
                                ": at most 7 levels above the base step");
  if (s_.level_gap < 0 || s_.level_gap > 7)
    throw std::invalid_argument("level_gap " + std::to_string(s_.level_gap) +
                                ": allowed 0 <= level_gap <= 7");
  const std::size_t n = m_.bodies.size();
  m_.due.assign(n, 1);
  m_.window.assign(n, 0.0);
  m_.level.assign(n, 0);
  m_.own_step.assign(n, 0.0);
  own_level_.assign(n, static_cast<std::uint8_t>(s_.max_level));
  body_step_min_.assign(n, HUGE_VAL);
  body_kinetic_.assign(n, 0.0);
  body_internal_.assign(n, 0.0);
  level_start_.assign(static_cast<std::size_t>(s_.max_level) + 1, 0.0);
  level_step_.assign(m_.elements.size(), HUGE_VAL);
  startParts();
}

// The levels' state for a checkpoint (State::Levels), and back.
Solver::State::Levels Solver::levelsState() const {
  State::Levels st;
  st.level = level_, st.own_level = own_level_, st.due = m_.due, st.model_level = m_.level;
  st.step_min = body_step_min_, st.kinetic = body_kinetic_, st.internal = body_internal_;
  st.window = m_.window, st.own_step = m_.own_step, st.level_start = level_start_;
  st.element_step = level_step_;
  st.part_level = part_level_, st.part_own_level = part_own_level_;
  st.part_step_min = part_step_min_, st.part_weight = part_weight_;
  for (const NodeForce &f : part_force_)
    st.part_force.insert(st.part_force.end(), {f.x, f.y});
  for (std::size_t i = 0; i < parted_bodies_.size(); ++i)
    for (int l = 1; l <= s_.max_level; ++l)
      for (const auto *start :
           {&window_x_[i][static_cast<std::size_t>(l)], &window_y_[i][static_cast<std::size_t>(l)]})
        st.window_start.insert(st.window_start.end(), start->begin(), start->end());
  // (with several processes, every process's as collectLevels summed them)
  st.element_steps = comm_.size() > 1 ? checkpoint_element_steps_ : element_steps_;
  st.single_rate_element_steps = single_rate_element_steps_;
  return st;
}

void Solver::restoreLevels(const State::Levels &st) {
  const std::size_t n = m_.bodies.size(), parts = parts_.size();
  std::size_t window_values = 0;
  for (std::uint32_t b : parted_bodies_)
    window_values += 2 * static_cast<std::size_t>(s_.max_level) *
                     (m_.bodies[b].node_end - m_.bodies[b].node_begin);
  auto levelsBelow = [&](const std::vector<std::uint8_t> &v) {
    return std::all_of(v.begin(), v.end(), [&](std::uint8_t l) { return l <= s_.max_level; });
  };
  const bool sized = st.level.size() == n && st.own_level.size() == n && st.due.size() == n &&
                     st.model_level.size() == n && st.step_min.size() == n &&
                     st.kinetic.size() == n && st.internal.size() == n && st.window.size() == n &&
                     st.own_step.size() == n && st.level_start.size() == level_start_.size() &&
                     st.element_step.size() == m_.elements.size() &&
                     st.part_level.size() == parts && st.part_own_level.size() == parts &&
                     st.part_step_min.size() == parts && st.part_weight.size() == parts &&
                     st.part_force.size() == 2 * part_force_.size() &&
                     st.window_start.size() == window_values;
  if (!sized || !levelsBelow(st.level) || !levelsBelow(st.own_level) ||
      !levelsBelow(st.model_level) || !levelsBelow(st.part_level) ||
      !levelsBelow(st.part_own_level))
    throw std::invalid_argument("levels' state not of this model with max_level " +
                                std::to_string(s_.max_level));
  level_ = st.level, own_level_ = st.own_level, m_.due = st.due, m_.level = st.model_level;
  body_step_min_ = st.step_min, body_kinetic_ = st.kinetic, body_internal_ = st.internal;
  m_.window = st.window, m_.own_step = st.own_step, level_start_ = st.level_start;
  level_step_ = st.element_step;
  part_level_ = st.part_level, part_own_level_ = st.part_own_level;
  part_step_min_ = st.part_step_min, part_weight_ = st.part_weight;
  for (std::size_t j = 0; j < part_force_.size(); ++j)
    part_force_[j] = {st.part_force[2 * j], st.part_force[2 * j + 1]};
  const double *start = st.window_start.data();
  for (std::size_t i = 0; i < parted_bodies_.size(); ++i)
    for (int l = 1; l <= s_.max_level; ++l)
      for (auto *to : {&window_x_[i][static_cast<std::size_t>(l)],
                       &window_y_[i][static_cast<std::size_t>(l)]}) {
        std::copy(start, start + to->size(), to->begin());
        start += to->size();
      }
  // (with several processes, the updates so far are the first process's: their sum counts them)
  element_steps_ = comm_.rank() == 0 ? st.element_steps : 0.0;
  single_rate_element_steps_ = st.single_rate_element_steps;
}

// With several processes, what only a body's owner keeps of its levels, which goes with it to a
// new owner (Solver::repartition): its elements' steps of their last pass, its kinetic and
// internal energy at its last update; of a body in parts each part's level, own level, shortest
// step and weight, its force at its nodes, and the body's nodes' window starts. (Its level, own
// level and shortest step every process knows.)
std::size_t Solver::levelValues(std::uint32_t b) const {
  if (!levels())
    return 0;
  const Body &body = m_.bodies[b];
  std::size_t count = body.element_end - body.element_begin + 2;
  if (part_begin_[b] < part_begin_[b + 1])
    count += 4 * (part_begin_[b + 1] - part_begin_[b]) +
             2 * (part_node_begin_[part_begin_[b + 1]] - part_node_begin_[part_begin_[b]]) +
             2 * static_cast<std::size_t>(s_.max_level) * (body.node_end - body.node_begin);
  return count;
}

void Solver::packLevels(std::uint32_t b, double *&out) const {
  if (!levels())
    return;
  const Body &body = m_.bodies[b];
  out = std::copy(level_step_.begin() + static_cast<long>(body.element_begin),
                  level_step_.begin() + static_cast<long>(body.element_end), out);
  *out++ = body_kinetic_[b], *out++ = body_internal_[b];
  if (part_begin_[b] == part_begin_[b + 1])
    return;
  for (std::size_t p = part_begin_[b]; p < part_begin_[b + 1]; ++p)
    *out++ = part_level_[p], *out++ = part_own_level_[p], *out++ = part_step_min_[p],
    *out++ = part_weight_[p];
  for (std::size_t j = part_node_begin_[part_begin_[b]]; j < part_node_begin_[part_begin_[b + 1]];
       ++j)
    *out++ = part_force_[j].x, *out++ = part_force_[j].y;
  const std::size_t i = partedIndex(b);
  for (int l = 1; l <= s_.max_level; ++l)
    for (const auto *start :
         {&window_x_[i][static_cast<std::size_t>(l)], &window_y_[i][static_cast<std::size_t>(l)]})
      out = std::copy(start->begin(), start->end(), out);
}

void Solver::unpackLevels(std::uint32_t b, const double *&in) {
  if (!levels())
    return;
  const Body &body = m_.bodies[b];
  std::copy(in, in + (body.element_end - body.element_begin),
            level_step_.begin() + static_cast<long>(body.element_begin));
  in += body.element_end - body.element_begin;
  body_kinetic_[b] = *in++, body_internal_[b] = *in++;
  if (part_begin_[b] == part_begin_[b + 1])
    return;
  for (std::size_t p = part_begin_[b]; p < part_begin_[b + 1]; ++p, in += 4) {
    part_level_[p] = static_cast<std::uint8_t>(in[0]);
    part_own_level_[p] = static_cast<std::uint8_t>(in[1]);
    part_step_min_[p] = in[2], part_weight_[p] = in[3];
  }
  for (std::size_t j = part_node_begin_[part_begin_[b]]; j < part_node_begin_[part_begin_[b + 1]];
       ++j, in += 2)
    part_force_[j] = {in[0], in[1]};
  const std::size_t i = partedIndex(b);
  for (int l = 1; l <= s_.max_level; ++l)
    for (auto *to :
         {&window_x_[i][static_cast<std::size_t>(l)], &window_y_[i][static_cast<std::size_t>(l)]}) {
      std::copy(in, in + to->size(), to->begin());
      in += to->size();
    }
}

// The place of body b (a body in parts) among parted_bodies_.
std::size_t Solver::partedIndex(std::uint32_t b) const {
  return static_cast<std::size_t>(std::find(parted_bodies_.begin(), parted_bodies_.end(), b) -
                                  parted_bodies_.begin());
}

// A moving body's load for the partition: its active elements, with levels each weighted by its
// updates per base step, 2^-level (a body in parts by its parts' levels, which every process
// knows: chooseLevels).
double Solver::levelLoad(std::size_t b) const {
  const Body &body = m_.bodies[b];
  if (!levels() || part_begin_[b] == part_begin_[b + 1])
    return std::ldexp(static_cast<double>(body.element_end - body.element_begin - body.eroded),
                      levels() ? -level_[b] : 0);
  double load = 0.0;
  for (std::size_t p = part_begin_[b]; p < part_begin_[b + 1]; ++p) {
    std::size_t active = 0;
    for (std::size_t e = parts_[p].element_begin; e < parts_[p].element_end; ++e)
      active += m_.elements.eroded[e] ? 0 : 1;
    load += std::ldexp(static_cast<double>(active), -part_level_[p]);
  }
  return load;
}

// With several processes, for a checkpoint: what only the owners keep of the active bodies' levels
// (packLevels) to the first process, which writes it, and the element updates every process
// computed, summed (levelsState).
void Solver::collectLevels() {
  if (comm_.size() == 1)
    return;
  const std::vector<std::vector<std::uint32_t>> of = byOwner(active_bodies_);
  std::size_t count = 0;
  for (std::uint32_t b : of[static_cast<std::size_t>(comm_.rank())])
    count += levelValues(b);
  comm_.collect(
      count,
      [&](double *out) {
        for (std::uint32_t b : of[static_cast<std::size_t>(comm_.rank())])
          packLevels(b, out);
      },
      [&](int r, const double *in) {
        for (std::uint32_t b : of[static_cast<std::size_t>(r)])
          unpackLevels(b, in);
      });
  checkpoint_element_steps_ = comm_.sumInOrder({element_steps_})[0];
}

// The bodies of at least parts_from elements step in parts of part_elements consecutive elements
// (the projectile: its elements are ordered from the tip, so that a part is a slab across it).
void Solver::startParts() {
  constexpr std::size_t parts_from = 2048;
  const std::size_t n = m_.bodies.size();
  part_begin_.assign(n + 1, 0);
  for (std::size_t b = 0; b < n; ++b) {
    part_begin_[b] = parts_.size();
    const Body &body = m_.bodies[b];
    if (body.element_end - body.element_begin < parts_from)
      continue;
    parted_bodies_.push_back(static_cast<std::uint32_t>(b));
    for (std::size_t e = body.element_begin; e < body.element_end; e += part_elements)
      parts_.push_back({e, std::min(e + part_elements, body.element_end)});
    const std::size_t nodes = body.node_end - body.node_begin;
    window_x_.emplace_back(static_cast<std::size_t>(s_.max_level) + 1, std::vector<double>(nodes));
    window_y_.emplace_back(static_cast<std::size_t>(s_.max_level) + 1, std::vector<double>(nodes));
    for (int l = 1; l <= s_.max_level; ++l) { // every window starts at the first positions
      std::copy(m_.nodes.x.begin() + static_cast<long>(body.node_begin),
                m_.nodes.x.begin() + static_cast<long>(body.node_end), window_x_.back()[l].begin());
      std::copy(m_.nodes.y.begin() + static_cast<long>(body.node_begin),
                m_.nodes.y.begin() + static_cast<long>(body.node_end), window_y_.back()[l].begin());
    }
  }
  part_begin_[n] = parts_.size();
  // each part's nodes (sorted), and room for its force at them
  part_node_begin_.assign(1, 0);
  for (const Part &part : parts_) {
    const auto first = m_.elements.node.begin() + 3 * static_cast<long>(part.element_begin);
    std::vector<std::uint32_t> nodes(
        first, first + 3 * static_cast<long>(part.element_end - part.element_begin));
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    part_nodes_.insert(part_nodes_.end(), nodes.begin(), nodes.end());
    part_node_begin_.push_back(part_nodes_.size());
  }
  part_force_.assign(part_nodes_.size(), NodeForce{0.0, 0.0});
  part_weight_.assign(parts_.size(), 1.0);
  part_level_.assign(parts_.size(), 0);
  part_own_level_.assign(parts_.size(), static_cast<std::uint8_t>(s_.max_level));
  part_step_min_.assign(parts_.size(), HUGE_VAL);
  part_box_.assign(4 * parts_.size(), HUGE_VAL);
}

// A body in parts (one unit): its due parts in order, each from its nodes' velocities over its
// window (at the body's own level e the nodes' velocities; at a coarser level l their mean
// velocity, (x - x at the window's start) / tau_l), its force on its nodes kept. The second
// half-kick takes half of each part's impulse over the body's window,
//   f = sum over the due parts p of (tau_l(p) / tau_e) f_p,
// the first half-kick of the body's next step the rest (chooseLevels). Each level's window start
// is kept.
void Solver::partsPass(const Unit &unit, int top, const double *tau, UnitScratch &scratch) {
  const Nodes &nd = m_.nodes;
  const std::uint32_t b = nd.body[unit.node_lo];
  const int e = level_[b];
  const std::size_t base = unit.node_lo, n = unit.node_hi - base;
  const std::size_t i_body = partedIndex(b);
  std::vector<NodeState> &state = scratch.state;
  std::vector<NodeForce> &force = scratch.force, &part_force = scratch.part_force;
  state.resize(n);
  force.resize(n);
  part_force.resize(n);
  scratch.jacobian.resize(unit.averaged_volume ? n : 0);
  const double gx = s_.gravity_x, gy = s_.gravity_y;
  for (std::size_t a = base; a < unit.node_hi; ++a)
    force[a - base] = {nd.mass[a] * gx, nd.mass[a] * gy};
  // the positions of the due parts' nodes (below), of every node for the nodal volumes
  if (unit.averaged_volume) {
    for (std::size_t a = base; a < unit.node_hi; ++a)
      state[a - base] = {nd.x[a], nd.y[a], nd.vx[a], nd.vy[a]};
    nodalVolumes(unit, {state.data(), force.data(), scratch.jacobian.data(), base});
  }
  const UnitNodes nodes{state.data(), part_force.data(), scratch.jacobian.data(), base};
  std::size_t i = unit.chunk_begin;
  for (std::size_t p = part_begin_[b]; p < part_begin_[b + 1]; ++p) {
    const int l = part_level_[p];
    if (l > top) {
      for (; i < unit.chunk_end && chunks_[i].part == p; ++i) // not due: no sums this step
        sums_[i] = ChunkSums{0.0, 0.0, 0.0, HUGE_VAL, -1, false, {}};
      continue;
    }
    const std::uint32_t *part_node = part_nodes_.data() + part_node_begin_[p];
    const std::size_t count = part_node_begin_[p + 1] - part_node_begin_[p];
    const std::vector<double> &x0 = window_x_[i_body][static_cast<std::size_t>(l)],
                              &y0 = window_y_[i_body][static_cast<std::size_t>(l)];
    const double inv_tau = 1.0 / tau[l];
    for (std::size_t j = 0; j < count; ++j) {
      const std::uint32_t a = part_node[j];
      const std::size_t k = a - base;
      state[k].x = nd.x[a], state[k].y = nd.y[a];
      if (l == e)
        state[k].vx = nd.vx[a], state[k].vy = nd.vy[a];
      else
        state[k].vx = (state[k].x - x0[k]) * inv_tau, state[k].vy = (state[k].y - y0[k]) * inv_tau;
      part_force[k] = {0.0, 0.0};
    }
    for (; i < unit.chunk_end && chunks_[i].part == p; ++i)
      elementPass(chunks_[i], tau[l], nodes, sums_[i]);
    // the part's box and shortest element step (for choosePartLevels), while they are at hand
    double x_lo = HUGE_VAL, y_lo = HUGE_VAL, x_hi = -HUGE_VAL, y_hi = -HUGE_VAL, step = HUGE_VAL;
    for (std::size_t element = parts_[p].element_begin; element < parts_[p].element_end;
         ++element) {
      if (m_.elements.eroded[element])
        continue;
      step = std::min(step, level_step_[element]);
      for (int k = 0; k < 3; ++k) {
        const NodeState &node =
            state[m_.elements.node[3 * element + static_cast<std::size_t>(k)] - base];
        x_lo = std::min(x_lo, node.x), x_hi = std::max(x_hi, node.x);
        y_lo = std::min(y_lo, node.y), y_hi = std::max(y_hi, node.y);
      }
    }
    double *box = &part_box_[4 * p];
    box[0] = x_lo, box[1] = y_lo, box[2] = x_hi, box[3] = y_hi;
    part_step_min_[p] = step;
    const double ratio = tau[l] / tau[e];
    NodeForce *kept = part_force_.data() + part_node_begin_[p];
    for (std::size_t j = 0; j < count; ++j) {
      const std::size_t k = part_node[j] - base;
      force[k].x += ratio * part_force[k].x, force[k].y += ratio * part_force[k].y;
      kept[j] = part_force[k];
    }
  }
  for (int l = 1; l <= top; ++l) {
    std::copy_n(nd.x.begin() + static_cast<long>(base), n,
                window_x_[i_body][static_cast<std::size_t>(l)].begin());
    std::copy_n(nd.y.begin() + static_cast<long>(base), n,
                window_y_[i_body][static_cast<std::size_t>(l)].begin());
  }
}

// The levels of the parts of body `body` (which stepped) that stepped: each part's own level from
// its elements' shortest step, no coarser than the own level of a body it may meet (its box within
// the provider's reach), nor than the step number allows.
void Solver::choosePartLevels(std::uint32_t body, int top, std::uint8_t limit) {
  const std::size_t p0 = part_begin_[body], p1 = part_begin_[body + 1];
  // (the parts that did not step keep their level: an empty box; those that did have their box
  // and shortest step from their pass, partsPass)
  std::vector<double> boxes(4 * (p1 - p0), HUGE_VAL);
  for (std::size_t p = p0; p < p1; ++p) {
    if (part_level_[p] > top)
      continue;
    std::copy_n(&part_box_[4 * p], 4, &boxes[4 * (p - p0)]);
    part_own_level_[p] =
        static_cast<std::uint8_t>(ownLevel(s_.safety * step_scale_ * part_step_min_[p], dt_,
                                           part_own_level_[p], s_.max_level, part_level_up_margin));
  }
  std::vector<std::uint8_t> cap(p1 - p0, static_cast<std::uint8_t>(s_.max_level));
  for (auto *provider : providers_)
    provider->capParts(own_level_, body, boxes, cap);
  for (std::size_t p = p0; p < p1; ++p)
    if (part_level_[p] <= top)
      part_level_[p] = std::min({part_own_level_[p], cap[p - p0], limit});
}

// The share of element e's force in the nodes' force for their next first half-kick: 1, or in a
// body in parts its part's weight (chooseLevels).
double Solver::nextForceWeight(std::size_t element) const {
  if (part_begin_.empty())
    return 1.0;
  const std::uint32_t b = m_.elements.body[element];
  if (part_begin_[b] == part_begin_[b + 1])
    return 1.0;
  return part_weight_[part_begin_[b] + (element - m_.bodies[b].element_begin) / part_elements];
}

void Solver::addKinetic(std::size_t node, double change) {
  energy_.kinetic += change;
  if (levels())
    body_kinetic_[m_.nodes.body[node]] += change;
}

// The internal energy and shortest element step of the bodies of units [unit_begin, unit_end)
// from their elements after the last pass (their energy, their steps in level_step_).
void Solver::bodySums(std::size_t unit_begin, std::size_t unit_end) {
  const Elements &el = m_.elements;
  std::size_t b = static_cast<std::size_t>(-1);
  double internal = 0.0, step = HUGE_VAL;
  for (std::size_t u = unit_begin; u < unit_end; ++u)
    for (std::size_t c = units_[u].chunk_begin; c < units_[u].chunk_end; ++c)
      for (std::size_t e = chunks_[c].begin; e < chunks_[c].end; ++e) {
        if (el.body[e] != b) {
          if (b != static_cast<std::size_t>(-1))
            body_internal_[b] = internal, body_step_min_[b] = step;
          b = el.body[e], internal = 0.0, step = HUGE_VAL;
        }
        internal += el.energy[e];
        step = std::min(step, level_step_[e]);
      }
  if (b != static_cast<std::size_t>(-1))
    body_internal_[b] = internal, body_step_min_[b] = step;
}

std::vector<std::size_t> Solver::elementsByLevel() const {
  std::vector<std::size_t> count(static_cast<std::size_t>(s_.max_level) + 1, 0);
  for (std::uint32_t b : active_bodies_) {
    const Body &body = m_.bodies[b];
    if (!owns(b))
      continue;
    if (part_begin_.empty() || part_begin_[b] == part_begin_[b + 1]) {
      count[level_[b]] += body.element_end - body.element_begin - body.eroded;
      continue;
    }
    for (std::size_t p = part_begin_[b]; p < part_begin_[b + 1]; ++p)
      for (std::size_t e = parts_[p].element_begin; e < parts_[p].element_end; ++e)
        count[part_level_[p]] += m_.elements.eroded[e] ? 0 : 1;
  }
  return count;
}

// A half-kick as halfKick, the external force taken over half_external (half the window it was
// computed for: its impulse's half), the elements' force and gravity over half_dt; the work sums in
// joules (not to be multiplied by the half step).
void Solver::halfKickLevels(std::size_t a, double half_dt, double half_external, double fx,
                            double fy, bool second_half, double &vx, double &vy,
                            KickSums &sums) const {
  const Nodes &nd = m_.nodes;
  double dvx = half_dt * fx * inv_mass_[a], dvy = half_dt * fy * inv_mass_[a];
  const bool loaded = nd.is_loaded[a];
  if (loaded && half_external != half_dt) {
    const Nodes::External &e = nd.external[a];
    dvx += (half_external - half_dt) * e.fx * inv_mass_[a];
    dvy += (half_external - half_dt) * e.fy * inv_mass_[a];
  }
  const double mean_vx = vx + 0.5 * dvx, mean_vy = vy + 0.5 * dvy;
  if (loaded) {
    const Nodes::External &e = nd.external[a];
    sums.provider += half_external * (e.fx * mean_vx + e.fy * mean_vy);
    sums.friction += half_external * (e.friction_x * mean_vx + e.friction_y * mean_vy);
  }
  if (s_.gravity_x != 0.0 || s_.gravity_y != 0.0)
    sums.gravity += half_dt * nd.mass[a] * (s_.gravity_x * mean_vx + s_.gravity_y * mean_vy);
  vx += dvx, vy += dvy;
  if (second_half)
    sums.kinetic += 0.5 * nd.mass[a] * (vx * vx + vy * vy - dvx * dvx - dvy * dvy);
}

// The time loop's step with levels: the bodies due at this step (level at most `top`) step over
// their windows tau[level], the pairs of two due bodies load them, the others stand still. With
// several processes, as step(): each moves and computes its own bodies, the step's one reduction
// (forcesLevels) tells every process the bodies the others' forces woke, and the levels are chosen
// alike on every process (chooseLevels).
void Solver::stepLevels() {
  const double stable = dt_;
  bool last = false;
  const double dt = stepToTake(last);
  const std::size_t k = steps_ + 1;
  const int top = std::min(s_.max_level, std::countr_zero(k));
  const double time_new = last ? end_at_ : time_ + dt;
  step_end_ = time_new;
  double tau[8];
  for (int l = 0; l <= top; ++l)
    tau[l] = time_new - level_start_[static_cast<std::size_t>(l)];
  kick_work_ = provider_work_ = friction_work_ = 0.0;
  const bool shared = comm_.size() > 1;
  if (shared && s_.rebalance_every > 0 && steps_ > 0 && steps_ % s_.rebalance_every == 0)
    rebalance_due_ = true;
  // the work laid out for the levels chosen at the last step, before their bodies move (every
  // process knows the same bodies to move: the load is balanced here)
  updateActivity();
  kickAndDriftLevels(top, tau); // v += tau'/2 f / m + J / 2m; x += tau' v (due bodies)
  Nodes &nd = m_.nodes;
  const double longest_step = std::ldexp(dt, s_.max_level); // a body's own step at most
  for (std::size_t b = 0; b < m_.bodies.size(); ++b) {
    const bool due = m_.at_rest[b] || level_[b] <= top;
    m_.due[b] = due;
    if (due)
      m_.window[b] = tau[level_[b]], m_.level[b] = level_[b],
      m_.own_step[b] = std::min(longest_step, s_.safety * step_scale_ * body_step_min_[b]);
  }
  { // the due bodies' external forces cleared; the others keep theirs for their next half-kick
    std::size_t kept = 0;
    for (std::uint32_t a : nd.loaded)
      if (m_.due[nd.body[a]])
        nd.external[a] = {}, nd.is_loaded[a] = 0;
      else
        nd.loaded[kept++] = a;
    nd.loaded.resize(kept);
  }
  for (auto *provider : providers_) // pairs of due bodies: contact at x(n+1)
    provider->addForces(m_, time_new, dt);
  // bodies the providers woke take part (at level 0); with several processes known to move at
  // their owner now, at the others after the step's reduction (forcesLevels)
  updateActivity(!shared);
  forcesLevels(top, tau, dt);
  single_rate_element_steps_ += static_cast<double>(active_elements_);
  step_elements_ = active_elements_;
  for (std::size_t r = 0; r < rank_elements_.size(); ++r) {
    rank_element_steps_[r] += static_cast<double>(rank_elements_[r]);
    rank_node_steps_[r] += static_cast<double>(rank_nodes_[r]);
  }
  scaleMasses(0.5 * dt);
  time_ = time_new;
  ++steps_;
  if (steps_ == 1)
    first_dt_ = stable;
  // The step falls at once; it rises only at whole cycles (every body due) every rise interval.
  const std::size_t cycle = std::size_t{1} << s_.max_level;
  const std::size_t rise = (s_.dt_rise_interval + cycle - 1) / cycle * cycle;
  nextStep(stable, rise);
  for (int l = 0; l <= top; ++l)
    level_start_[static_cast<std::size_t>(l)] = time_;
  chooseLevels(top);
  accountEnergy();
  if (not_finite_ ||
      (!shared && (!std::isfinite(energy_.kinetic) || !std::isfinite(energy_.internal))))
    throw RunFailure(notFinite());
  erode();
  // (with several processes the load is checked here, as step() does, so that a checkpoint after
  // the step finds it checked: Solver::restore)
  if (shared)
    updateActivity(true);
}

// With levels, each level's units split among the threads in contiguous runs, the same runs at
// every step the level is due, so that a unit's element and node data stay in one core's cache
// from one update to the next (docs/solver.md, "Threads at levels"). A body in parts goes to one
// thread (the k-th such body to thread k mod threads), and its parts at level l count in that
// thread's share of level l: the runs of each level are cut so that every thread has about the
// same elements at the level, with the parts (no thread less than none), and so at every step. A
// node block goes with the unit that holds its first node. Each thread takes its due units and
// blocks in the order of their nodes, not level by level: at a step where every level is due it
// then reads the node and element arrays once from start to end, as at a single rate. `elements`:
// each unit's elements.
void Solver::shareLevelsAmongThreads(std::size_t threads,
                                     const std::vector<std::size_t> &elements) {
  const auto n_levels = static_cast<std::size_t>(s_.max_level) + 1;
  unit_thread_.assign(units_.size(), 0);
  block_thread_.assign(node_ranges_.size(), 0);
  unit_level_.assign(units_.size(), 0);
  block_level_.assign(node_ranges_.size(), 0);
  for (std::size_t l = 0; l < n_levels; ++l) {
    std::fill(unit_level_.begin() + static_cast<long>(level_units_[l]),
              unit_level_.begin() + static_cast<long>(level_units_[l + 1]), l);
    std::fill(block_level_.begin() + static_cast<long>(level_blocks_[l]),
              block_level_.begin() + static_cast<long>(level_blocks_[l + 1]), l);
  }
  auto byNode = [](std::vector<std::size_t> &order, std::size_t n, auto first_node) {
    order.resize(n);
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(),
              [&](std::size_t i, std::size_t j) { return first_node(i) < first_node(j); });
  };
  byNode(unit_order_, units_.size(), [&](std::size_t u) { return units_[u].node_lo; });
  byNode(block_order_, node_ranges_.size(), [&](std::size_t i) { return node_ranges_[i].begin; });
  std::vector<std::vector<double>> parted(n_levels, std::vector<double>(threads, 0.0));
  for (std::size_t u = 0, k = 0; u < units_.size(); ++u)
    if (units_[u].in_parts) {
      const std::size_t t = k++ % threads;
      unit_thread_[u] = static_cast<std::uint16_t>(t);
      for (std::size_t c = units_[u].chunk_begin; c < units_[u].chunk_end; ++c)
        parted[chunks_[c].level][t] += static_cast<double>(chunks_[c].end - chunks_[c].begin);
    }
  for (std::size_t l = 0; l < n_levels; ++l) {
    std::vector<std::size_t> units, weights;
    double all = 0.0;
    for (std::size_t u = level_units_[l]; u < level_units_[l + 1]; ++u)
      if (!units_[u].in_parts) {
        units.push_back(u), weights.push_back(elements[u]);
        all += static_cast<double>(elements[u]);
      }
    for (double p : parted[l])
      all += p;
    std::vector<double> targets(threads);
    for (std::size_t t = 0; t < threads; ++t)
      targets[t] = std::max(0.0, all / static_cast<double>(threads) - parted[l][t]);
    const std::vector<std::size_t> bounds = contiguousShares(weights, targets);
    for (std::size_t t = 0; t < threads; ++t)
      for (std::size_t i = bounds[t]; i < bounds[t + 1]; ++i)
        unit_thread_[units[i]] = static_cast<std::uint16_t>(t);
    // (a level's units and blocks both follow its bodies in order, their nodes contiguous)
    std::size_t u = level_units_[l];
    for (std::size_t i = level_blocks_[l]; i < level_blocks_[l + 1]; ++i) {
      while (u + 1 < level_units_[l + 1] && units_[u].node_hi <= node_ranges_[i].begin)
        ++u;
      if (u < level_units_[l + 1])
        block_thread_[i] = unit_thread_[u];
    }
  }
}

// The first half-kick and the drift of the due bodies' nodes (levels 0 to top, each over its
// window), in one pass over their blocks, each listed for its thread (shareLevelsAmongThreads) and
// taken by another if that one is still busy.
void Solver::kickAndDriftLevels(int top, const double *tau) {
  Nodes &nd = m_.nodes;
  const std::size_t blocks = level_blocks_[static_cast<std::size_t>(top) + 1];
  kick_sums_.assign(blocks, KickSums{});
  const auto threads = static_cast<std::size_t>(omp_get_max_threads());
  block_lists_.reset(threads);
  for (std::size_t i : block_order_)
    if (static_cast<int>(block_level_[i]) <= top)
      block_lists_.list(block_thread_[i] % threads).push_back(i);
#pragma omp parallel if (blocks > 1)
  {
    const auto me = static_cast<std::size_t>(omp_get_thread_num());
    for (std::size_t i; (i = block_lists_.next(me)) != WorkLists::none;) {
      const double t = tau[block_level_[i]], half = 0.5 * t;
      KickSums sums;
      for (std::size_t a = node_ranges_[i].begin; a < node_ranges_[i].end; ++a) {
        double vx = nd.vx[a], vy = nd.vy[a];
        const double half_external = nd.is_loaded[a] ? 0.5 * m_.window[nd.body[a]] : half;
        halfKickLevels(a, half, half_external, nd.fx[a], nd.fy[a], false, vx, vy, sums);
        nd.vx[a] = vx, nd.vy[a] = vy;
        nd.x[a] += t * vx;
        nd.y[a] += t * vy;
      }
      kick_sums_[i] = sums;
    }
  }
  addKickSums(kick_sums_, 1.0);
  applyConstraints(0.5 * tau[0], false);
}

// The element pass and second half-kick of the due bodies (levels 0 to top, each over its window),
// then the step's sums: each body keeps its internal and kinetic energy and its shortest step from
// its last update, the run's are their sums.
void Solver::forcesLevels(int top, const double *tau, double base_dt) {
  Nodes &nd = m_.nodes;
  const std::size_t units_end = level_units_[static_cast<std::size_t>(top) + 1];
  std::vector<KickSums> unit_sums(units_end);
  // The due levels' units (this process's), each listed for its thread (shareLevelsAmongThreads)
  // and taken by another if that one is still busy; a body in parts on its thread. Their results
  // do not depend on which thread computes them.
  const auto threads = static_cast<std::size_t>(omp_get_max_threads());
  unit_lists_.reset(threads);
  std::vector<std::size_t> parted; // the due bodies in parts' units
  for (std::size_t u : unit_order_)
    if (unit_level_[u] <= top)
      (units_[u].in_parts ? parted : unit_lists_.list(unit_thread_[u] % threads)).push_back(u);
  thread_scratch_.resize(threads);
#pragma omp parallel if (units_end > 1)
  {
    UnitScratch &scratch = threadScratch();
    const auto me = static_cast<std::size_t>(omp_get_thread_num());
    const auto team = static_cast<std::size_t>(omp_get_num_threads());
    auto unitForces = [&](std::size_t u) {
      const Unit &unit = units_[u];
      const double dt = tau[unit_level_[u]];
      const std::size_t base = unit.node_lo;
      if (unit.in_parts)
        partsPass(unit, top, tau, scratch);
      else
        unitPass(unit, dt, scratch);
      bodySums(u, u + 1); // a unit holds whole bodies
      const std::vector<NodeForce> &force = scratch.force;
      KickSums sums; // the kinetic energy body by body into body_kinetic_
      std::uint32_t body = nd.body[unit.node_lo];
      for (std::size_t r = unit.nodes_begin; r < unit.nodes_end; ++r)
        for (std::size_t a = unit_nodes_[r].begin; a < unit_nodes_[r].end; ++a) {
          if (nd.body[a] != body)
            body_kinetic_[body] = std::exchange(sums.kinetic, 0.0), body = nd.body[a];
          double fx = force[a - base].x, fy = force[a - base].y;
          if (nd.is_loaded[a])
            fx += nd.external[a].fx, fy += nd.external[a].fy;
          nd.fx[a] = fx, nd.fy[a] = fy;
          double vx = nd.vx[a], vy = nd.vy[a];
          halfKickLevels(a, 0.5 * dt, 0.5 * dt, fx, fy, true, vx, vy, sums);
          nd.vx[a] = vx, nd.vy[a] = vy;
        }
      body_kinetic_[body] = std::exchange(sums.kinetic, 0.0);
      unit_sums[u] = sums;
    };
    for (std::size_t u : parted) // first: the largest units, not to be taken by another thread
      if (unit_thread_[u] % team == me)
        unitForces(u);
    for (std::size_t u; (u = unit_lists_.next(me)) != WorkLists::none;)
      unitForces(u);
  }
  // This process's sums, in unit order (the same for any thread count), its bodies' energies and
  // shortest steps; the step's one reduction (reduceStep) as in forces. The chunks not due keep
  // their last pass's sums: the elements they found failed or asking for mass then were dealt
  // with then (erode, scaleMasses, which read every chunk's).
  const std::size_t chunks_end = units_end > 0 ? units_[units_end - 1].chunk_end : 0;
  for (std::size_t i = chunks_end; i < chunks_.size(); ++i)
    sums_[i].scaled.clear(), sums_[i].eroding = false;
  double plastic = 0.0, viscous = 0.0;
  std::int64_t inverted = -1;
  std::size_t failing = 0, scaling = 0;
  for (std::size_t i = 0; i < chunks_end; ++i) {
    plastic += sums_[i].plastic;
    viscous += sums_[i].viscous;
    if (sums_[i].eroding)
      for (std::size_t e = chunks_[i].begin; e < chunks_[i].end; ++e)
        failing += failed_[e] != 0;
    scaling += sums_[i].scaled.size();
    if (inverted < 0)
      inverted = sums_[i].inverted;
    if (chunks_[i].level <= top)
      element_steps_ += static_cast<double>(chunks_[i].end - chunks_[i].begin);
  }
  double internal = 0.0, kinetic = 0.0, dt_min = HUGE_VAL;
  for (std::uint32_t b : active_bodies_)
    if (owns(b)) {
      internal += body_internal_[b];
      kinetic += body_kinetic_[b];
      dt_min = std::min(dt_min, body_step_min_[b]);
    }
  step_sums_ = {internal, plastic, viscous};
  energy_.kinetic = kinetic;
  addKickSums(unit_sums, 1.0);
  applyConstraints(0.5 * base_dt, true); // bodies with imposed velocities are at level 0
  dt_min = reduceStep(dt_min, inverted, failing, scaling,
                      std::isfinite(energy_.kinetic) && std::isfinite(internal), true, step_end_);
  next_dt_ = s_.safety * step_scale_ * dt_min;
  shortest_step_ = dt_min;
}

// The force for the first half-kick of the next step of body `body` in parts (over its window
// tau_e', its level chosen): gravity and the external forces, as for any body, and of each part
// that stepped (at level l, `stepped_at`, window tau_l) the rest of its impulse tau_l' f_p, tau_l'
// its next window (the asynchronous variational integrator's impulse at an update, Lew et al. 2003;
// its second half-kick took tau_l / 2 f_p), as (2 tau_l' - tau_l) / tau_e' f_p / 2.
void Solver::nextPartForces(std::uint32_t body, int top,
                            const std::vector<std::uint8_t> &stepped_at) {
  Nodes &nd = m_.nodes;
  // (the nodes of no part that stepped have that force already: their second half-kick's)
  const std::size_t p0 = part_begin_[body];
  for (std::size_t p = p0; p < part_begin_[body + 1]; ++p) {
    if (stepped_at[p - p0] > top)
      continue;
    for (std::size_t j = part_node_begin_[p]; j < part_node_begin_[p + 1]; ++j) {
      const std::uint32_t a = part_nodes_[j];
      nd.fx[a] = nd.mass[a] * s_.gravity_x, nd.fy[a] = nd.mass[a] * s_.gravity_y;
      if (nd.is_loaded[a])
        nd.fx[a] += nd.external[a].fx, nd.fy[a] += nd.external[a].fy;
    }
  }
  for (std::size_t p = p0; p < part_begin_[body + 1]; ++p) {
    if (stepped_at[p - p0] > top)
      continue;
    const double weight = std::ldexp(
        std::ldexp(1.0, part_level_[p] + 1) - std::ldexp(1.0, stepped_at[p - p0]), -level_[body]);
    part_weight_[p] = weight;
    for (std::size_t j = part_node_begin_[p]; j < part_node_begin_[p + 1]; ++j) {
      const std::uint32_t a = part_nodes_[j];
      nd.fx[a] += weight * part_force_[j].x, nd.fy[a] += weight * part_force_[j].y;
    }
  }
}

// The levels of the bodies that stepped: each body's own level from its own step on the base step
// to come, at most level_gap levels coarser than the own level of a body it may meet, and no
// coarser than the step number allows. Every process chooses every body's level alike (the own
// steps from the bodies' owners, shareBodySteps; the providers' pairs are every process's), but
// a body in parts, whose parts only its owner knows: its owner's level goes to the others.
void Solver::chooseLevels(int top) {
  const std::size_t n = m_.bodies.size();
  const auto max_level = static_cast<std::uint8_t>(s_.max_level);
  shareBodySteps(top);
  // each body's own level; the coarsest level a body may take beside each body (reach): its own
  // level plus the gap, and beside a body in parts its own level (the projectile's pairs with the
  // grains it meets at one level)
  std::vector<std::uint8_t> &reach = level_reach_, &cap = level_cap_;
  reach.resize(n);
  for (std::size_t b = 0; b < n; ++b) {
    if (m_.at_rest[b])
      own_level_[b] = max_level;
    else if (level_[b] <= top)
      own_level_[b] = static_cast<std::uint8_t>(
          ownLevel(s_.safety * step_scale_ * body_step_min_[b], dt_, own_level_[b], s_.max_level));
    const int gap = part_begin_[b] < part_begin_[b + 1] ? 0 : s_.level_gap;
    reach[b] = static_cast<std::uint8_t>(std::min(own_level_[b] + gap, s_.max_level));
  }
  cap.assign(n, max_level);
  for (auto *provider : providers_)
    provider->capLevels(m_, reach, cap);
  for (const auto &c : m_.constraints) // imposed velocities: level 0, the parts too
    for (std::uint32_t a : c.nodes)
      cap[m_.nodes.body[a]] = 0;
  std::vector<std::uint32_t> parted_stepped; // the bodies in parts that stepped
  for (std::size_t b = 0; b < n; ++b)
    if (!m_.at_rest[b] && level_[b] <= top) {
      if (part_begin_[b] == part_begin_[b + 1]) {
        level_[b] = std::min({own_level_[b], cap[b], static_cast<std::uint8_t>(top)});
        continue;
      }
      parted_stepped.push_back(static_cast<std::uint32_t>(b));
      if (!owns(b))
        continue;
      // a body in parts: at its finest part's level, no coarser than the bodies it may meet
      const std::size_t p0 = part_begin_[b], p1 = part_begin_[b + 1];
      const std::vector<std::uint8_t> stepped_at(part_level_.begin() + static_cast<long>(p0),
                                                 part_level_.begin() + static_cast<long>(p1));
      const bool constrained = std::any_of(
          m_.constraints.begin(), m_.constraints.end(), [&](const VelocityConstraint &c) {
            return std::any_of(c.nodes.begin(), c.nodes.end(),
                               [&](std::uint32_t a) { return m_.nodes.body[a] == b; });
          });
      choosePartLevels(static_cast<std::uint32_t>(b), top,
                       constrained ? std::uint8_t{0} : static_cast<std::uint8_t>(top));
      const auto finest = *std::min_element(part_level_.begin() + static_cast<long>(p0),
                                            part_level_.begin() + static_cast<long>(p1));
      level_[b] = std::min({finest, cap[b], static_cast<std::uint8_t>(top)});
      nextPartForces(static_cast<std::uint32_t>(b), top, stepped_at);
    }
  // their owners' levels and parts' levels (-1: not the owner; the parts' levels weigh the body's
  // load, levelLoad)
  if (comm_.size() > 1 && !parted_stepped.empty()) {
    std::vector<double> chosen;
    for (std::uint32_t b : parted_stepped) {
      chosen.push_back(owns(b) ? static_cast<double>(level_[b]) : -1.0);
      for (std::size_t p = part_begin_[b]; p < part_begin_[b + 1]; ++p)
        chosen.push_back(owns(b) ? static_cast<double>(part_level_[p]) : -1.0);
    }
    chosen = comm_.max(std::move(chosen));
    std::size_t i = 0;
    for (std::uint32_t b : parted_stepped) {
      level_[b] = static_cast<std::uint8_t>(chosen[i++]);
      for (std::size_t p = part_begin_[b]; p < part_begin_[b + 1]; ++p)
        part_level_[p] = static_cast<std::uint8_t>(chosen[i++]);
    }
  }
}

// With several processes: the shortest element step of each body that stepped (active, level at
// most `top`), from its owner (bodySums) to every process, in one all-gather (every process
// knows how many each gives: the bodies it owns that stepped, in body order).
void Solver::shareBodySteps(int top) {
  if (comm_.size() == 1)
    return;
  std::vector<std::vector<std::uint32_t>> stepped(static_cast<std::size_t>(comm_.size()));
  for (std::uint32_t b : active_bodies_)
    if (level_[b] <= top)
      stepped[static_cast<std::size_t>(owner(b))].push_back(b);
  std::vector<std::int64_t> sizes;
  for (const auto &bodies : stepped)
    sizes.push_back(std::ssize(bodies));
  std::vector<double> mine;
  for (std::uint32_t b : stepped[static_cast<std::size_t>(comm_.rank())])
    mine.push_back(body_step_min_[b]);
  const std::vector<double> all = comm_.allGather(std::move(mine), sizes);
  std::size_t i = 0;
  for (const auto &bodies : stepped)
    for (std::uint32_t b : bodies)
      body_step_min_[b] = all[i++];
}

// nextDriftBound with levels, from the state after this step's second half-kick (before the
// levels to come are chosen). A node drifts at the next step over its body's next window, at most
// T = the longest window of a level due then (from that level's window start to this step's end,
// plus dt' <= max_dt_growth dt), after the half-kick
//   v += T/2 (f - f_ext) / m + W/2 f_ext / m     (kickAndDriftLevels),
// W its body's window now (the external force's). A node of a body in parts is kicked instead by
// each part p that stepped with tau_e'/2 w_p f_p, w_p = (2^(l_p+1) - 2^l_last) / 2^e
// (nextPartForces), at most T 2^L f_p whatever the base steps in the body's window: bounded by the
// sum of the parts' |f_p| at it.
double Solver::nextDriftBoundLevels() const {
  const Nodes &nd = m_.nodes;
  const double growth = std::max(1.0, s_.max_dt_growth);
  const int next_top = std::min(s_.max_level, std::countr_zero(steps_ + 2));
  double T = growth * dt_;
  for (int l = 1; l <= next_top; ++l)
    T = std::max(T, step_end_ - level_start_[static_cast<std::size_t>(l)] + growth * dt_);

  // the parts' force magnitudes at the nodes of this process's bodies in parts (by node from the
  // first of its body's)
  std::vector<std::vector<NodeForce>> part_kick(parted_bodies_.size());
  for (std::size_t i = 0; i < parted_bodies_.size(); ++i) {
    const std::uint32_t b = parted_bodies_[i];
    if (!owns(b) || m_.at_rest[b])
      continue;
    const std::size_t first = m_.bodies[b].node_begin;
    part_kick[i].assign(m_.bodies[b].node_end - first, NodeForce{0.0, 0.0});
    for (std::size_t p = part_begin_[b]; p < part_begin_[b + 1]; ++p)
      for (std::size_t j = part_node_begin_[p]; j < part_node_begin_[p + 1]; ++j) {
        NodeForce &k = part_kick[i][part_nodes_[j] - first];
        k.x += std::abs(part_force_[j].x), k.y += std::abs(part_force_[j].y);
      }
  }
  // (a part's kick is tau_e'/2 w_p f_p, w_p = (2^(l+1) - 2^l_last) / 2^e: at most T 2^L f_p)
  const double part_window = std::ldexp(T, s_.max_level);
  const double half = 0.5 * T;
  double most = 0.0;
  for (const Range &r : node_ranges_)
    for (std::size_t a = r.begin; a < r.end; ++a) {
      double kx, ky;
      const std::uint32_t b = nd.body[a];
      if (part_begin_[b] < part_begin_[b + 1]) { // gravity, the external force, the parts
        const NodeForce &k = part_kick[partedIndex(b)][a - m_.bodies[b].node_begin];
        kx = half * nd.mass[a] * std::abs(s_.gravity_x) + part_window * k.x;
        ky = half * nd.mass[a] * std::abs(s_.gravity_y) + part_window * k.y;
      } else
        kx = half * std::abs(nd.fx[a]), ky = half * std::abs(nd.fy[a]);
      if (nd.is_loaded[a]) {
        const double h = half + 0.5 * m_.window[b];
        kx += h * std::abs(nd.external[a].fx), ky += h * std::abs(nd.external[a].fy);
      }
      const double ux = std::abs(nd.vx[a]) + kx * inv_mass_[a];
      const double uy = std::abs(nd.vy[a]) + ky * inv_mass_[a];
      most = std::max(most, ux * ux + uy * uy);
    }
  return T * std::sqrt(most);
}

} // namespace mesopen::fem
