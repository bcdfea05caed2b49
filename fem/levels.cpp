#include "levels.hpp"

#include <algorithm>
#include <cmath>

namespace mesopen::fem {

int stepLevel(double body_step, double base_step, int max_level) {
  if (!(body_step < HUGE_VAL))
    return max_level;
  // the largest l with 2^l base_step <= body_step (doubling is exact: no rounding of a quotient,
  // and no logarithm for each of the bodies that step)
  int level = 0;
  for (double reach = 2.0 * base_step; level < max_level && body_step >= reach; reach *= 2.0)
    ++level;
  return level;
}

int ownLevel(double body_step, double base_step, int now, int max_level, double up_margin) {
  const int level = stepLevel(body_step, base_step, max_level);
  if (level <= now)
    return level;
  return std::max(now, stepLevel(body_step / up_margin, base_step, max_level));
}

LevelCensus::LevelCensus(const Model &model, int max_level) : max_level_(max_level) {
  const Elements &el = model.elements;
  const std::size_t n_nodes = model.nodes.size();
  node_element_begin_.assign(n_nodes + 1, 0);
  for (std::uint32_t a : el.node)
    ++node_element_begin_[a + 1];
  for (std::size_t a = 0; a < n_nodes; ++a)
    node_element_begin_[a + 1] += node_element_begin_[a];
  node_elements_.resize(el.node.size());
  std::vector<std::uint32_t> next(node_element_begin_.begin(), node_element_begin_.end() - 1);
  for (std::size_t e = 0; e < el.size(); ++e)
    for (int k = 0; k < 3; ++k)
      node_elements_[next[el.node[3 * e + k]]++] = static_cast<std::uint32_t>(e);
  node_level_.assign(n_nodes, -1);
  element_level_.assign(el.size(), -1);
}

LevelCensus::Column &LevelCensus::column(const std::string &name, const std::string &unit,
                                         const std::string &meaning) {
  for (Column &c : columns_)
    if (c.name == name)
      return c;
  columns_.push_back({name, unit, meaning, std::vector<double>(samples_, 0.0)});
  return columns_.back();
}

double LevelCensus::total(const std::string &name) const {
  for (const Column &c : columns_)
    if (c.name == name) {
      double sum = 0.0;
      for (double v : c.values)
        sum += v;
      return sum;
    }
  return 0.0;
}

void LevelCensus::sample(const Model &model, double time, std::size_t step,
                         const std::vector<double> &body_steps, double base_step,
                         const std::vector<std::pair<std::uint32_t, std::uint32_t>> &pairs,
                         const std::vector<Contact::BodyContact> &contacts) {
  const std::size_t n_bodies = model.bodies.size();
  auto active = [&](std::size_t b) {
    const Body &body = model.bodies[b];
    return body_steps[b] < HUGE_VAL ? body.element_end - body.element_begin - body.eroded
                                    : std::size_t{0};
  };
  auto moving_nodes = [&](std::size_t b) {
    const Body &body = model.bodies[b];
    return body_steps[b] < HUGE_VAL ? body.node_end - body.node_begin : std::size_t{0};
  };
  std::size_t active_elements = 0;
  for (std::size_t b = 0; b < n_bodies; ++b)
    active_elements += active(b);
  column("time", "s", "the time at the end of the step sampled").values.push_back(time);
  column("step", "", "the step sampled").values.push_back(static_cast<double>(step));
  column("base_dt", "s", "the step the solver takes next: the base step h0 of level 0")
      .values.push_back(base_step);
  column("active_elements", "", "elements of the bodies that move (the single-rate work)")
      .values.push_back(static_cast<double>(active_elements));
  column("pairs", "", "pairs of bodies whose boxes overlap (the narrow phase's single-rate work)")
      .values.push_back(static_cast<double>(pairs.size()));
  column("contacts", "", "node-to-segment contacts between bodies")
      .values.push_back(static_cast<double>(contacts.size()));
  std::size_t active_nodes = 0;
  for (std::size_t b = 0; b < n_bodies; ++b)
    active_nodes += moving_nodes(b);
  column("active_nodes", "", "nodes of the bodies that move (the single-rate node work)")
      .values.push_back(static_cast<double>(active_nodes));
  { // the elements on a node in contact (the pushed node, the segment's two), whatever the levels
    const Elements &el = model.elements;
    auto mark = [&](std::uint32_t a) {
      for (std::uint32_t i = node_element_begin_[a]; i < node_element_begin_[a + 1]; ++i) {
        const std::uint32_t e = node_elements_[i];
        if (!el.eroded[e] && element_level_[e] < 0)
          marked_elements_.push_back(e), element_level_[e] = 0;
      }
    };
    for (const Contact::BodyContact &c : contacts)
      mark(c.node), mark(c.segment_node[0]), mark(c.segment_node[1]);
    column("contact_node_elements", "",
           "elements on a node in contact between bodies (a ring at every contact)")
        .values.push_back(static_cast<double>(marked_elements_.size()));
    for (std::uint32_t e : marked_elements_)
      element_level_[e] = -1;
    marked_elements_.clear();
  }

  std::vector<int> level(n_bodies);
  for (int L = 1; L <= max_level_; ++L) {
    std::string p("L"); // the columns of largest level L: "L<L>/..."
    p += std::to_string(L);
    p += '/';
    for (std::size_t b = 0; b < n_bodies; ++b)
      level[b] = stepLevel(body_steps[b], base_step, L);
    // The bodies' elements by level, and their work per base step, sum of 2^-l.
    std::vector<double> by_level(L + 1, 0.0);
    double element_work = 0.0;
    for (std::size_t b = 0; b < n_bodies; ++b) {
      const auto n = static_cast<double>(active(b));
      by_level[level[b]] += n;
      element_work += n * std::ldexp(1.0, -level[b]);
    }
    // A pair at the finer level; a contact across levels promotes the coarser body's nodes in it
    // (the segment's two nodes or the pushed node) to the finer level, and their elements.
    std::vector<double> pair_count((L + 1) * (L + 1), 0.0);
    double pair_work = 0.0;
    for (auto [a, b] : pairs) {
      const int fine = std::min(level[a], level[b]), coarse = std::max(level[a], level[b]);
      pair_count[fine * (L + 1) + coarse] += 1.0;
      pair_work += std::ldexp(1.0, -fine);
    }
    auto promote = [&](std::uint32_t node, int to) {
      if (node_level_[node] < 0)
        marked_nodes_.push_back(node), node_level_[node] = static_cast<std::int8_t>(to);
      node_level_[node] = static_cast<std::int8_t>(std::min<int>(node_level_[node], to));
    };
    for (const Contact::BodyContact &c : contacts) {
      const int la = level[c.node_body], lb = level[c.segment_body];
      if (la > lb)
        promote(c.node, lb);
      else if (lb > la)
        promote(c.segment_node[0], la), promote(c.segment_node[1], la);
    }
    const Elements &el = model.elements;
    for (std::uint32_t a : marked_nodes_)
      for (std::uint32_t i = node_element_begin_[a]; i < node_element_begin_[a + 1]; ++i) {
        const std::uint32_t e = node_elements_[i];
        if (el.eroded[e])
          continue;
        if (element_level_[e] < 0)
          marked_elements_.push_back(e), element_level_[e] = node_level_[a];
        element_level_[e] = std::min(element_level_[e], node_level_[a]);
      }
    std::vector<double> promoted(L + 1, 0.0);
    for (std::uint32_t e : marked_elements_) {
      const int from = level[el.body[e]], to = element_level_[e];
      promoted[to] += 1.0;
      element_work += std::ldexp(1.0, -to) - std::ldexp(1.0, -from);
      element_level_[e] = -1;
    }
    for (std::uint32_t a : marked_nodes_)
      node_level_[a] = -1;
    const auto ring = static_cast<double>(marked_elements_.size());
    marked_nodes_.clear(), marked_elements_.clear();

    for (int l = 0; l <= L; ++l)
      column(p + "elements_level_" + std::to_string(l), "",
             std::string("active elements of the bodies at level ") + std::to_string(l))
          .values.push_back(by_level[l]);
    for (int l = 0; l < L; ++l)
      column(p + "ring_elements_to_level_" + std::to_string(l), "",
             std::string("elements of coarser bodies promoted to level ") + std::to_string(l) +
                 " by a contact with a body at that level")
          .values.push_back(promoted[l]);
    column(p + "ring_elements", "", "elements promoted by contacts across levels")
        .values.push_back(ring);
    for (int l = 0; l <= L; ++l)
      for (int m = l; m <= L; ++m)
        column(p + "pairs_" + std::to_string(l) + "_" + std::to_string(m), "",
               std::string("overlapping pairs of bodies at levels ") + std::to_string(l) + " and " +
                   std::to_string(m))
            .values.push_back(pair_count[l * (L + 1) + m]);
    column(p + "element_work", "",
           "element updates per base step: sum over active elements of 2^-level, rings promoted")
        .values.push_back(element_work);
    column(p + "pair_work", "", "pair updates per base step: sum over pairs of 2^-(finer level)")
        .values.push_back(pair_work);
    // Levels by whole body instead of rings: a body takes the finest own level of its partners
    // (one hop), its elements and nodes alike; the partners the bodies in contact with it, or those
    // whose boxes overlap its own (promoted before they touch).
    auto wholeBody = [&](const std::string &name, const std::string &partners,
                         const auto &each_partnership) {
      std::vector<int> whole(level);
      each_partnership([&](std::uint32_t a, std::uint32_t b) {
        whole[a] = std::min(whole[a], level[b]);
        whole[b] = std::min(whole[b], level[a]);
      });
      double elements = 0.0, nodes = 0.0;
      for (std::size_t b = 0; b < n_bodies; ++b) {
        elements += static_cast<double>(active(b)) * std::ldexp(1.0, -whole[b]);
        nodes += static_cast<double>(moving_nodes(b)) * std::ldexp(1.0, -whole[b]);
      }
      column(p + name + "_element_work", "",
             "element updates per base step with levels by whole body, a body at the finest level "
             "of " +
                 partners + ": sum over active elements of 2^-level")
          .values.push_back(elements);
      column(p + name + "_node_work", "",
             "node moves per base step with levels by whole body (" + partners +
                 "), each node at its body's level")
          .values.push_back(nodes);
    };
    wholeBody("whole_body", "the bodies in contact with it", [&](const auto &partners) {
      for (const Contact::BodyContact &c : contacts)
        partners(c.node_body, c.segment_body);
    });
    wholeBody("pair_promoted", "the bodies whose boxes overlap its own", [&](const auto &partners) {
      for (auto [a, b] : pairs)
        partners(a, b);
    });
    column(p + "projectile_level", "", "the level of body 0, the projectile")
        .values.push_back(n_bodies > 0 ? level[0] : 0.0);
  }
  ++samples_;
}

} // namespace mesopen::fem
