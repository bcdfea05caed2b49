// Multiple time stepping by body: power-of-two levels on a base step h0. A body at level l would
// take steps of 2^l h0, the longest such step within its own stable step (Solver::bodySteps), up
// to a largest level L. A contact pair runs at the finer of its two bodies' levels, and the
// elements of the coarser body that share a node with a node the finer body touches (the ring)
// are promoted to that level. LevelCensus measures what this would give a run, sample by sample:
// the active elements by level, the pairs by their two levels, the rings, and the element and
// pair work against the single-rate run (docs/solver.md, "Multiple time stepping: levels").
#pragma once

#include "contact.hpp"
#include "model.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace mesopen::fem {

// The level of a body whose own stable step is `body_step` on the base step `base_step`:
//   l = min(max_level, floor(log2(body_step / base_step))),
// 0 when the body's step is not twice the base step; max_level for a body at rest (infinite step).
int stepLevel(double body_step, double base_step, int max_level);

// A body's own level rises only when its step holds the higher level with this margin, and falls
// as soon as its step no longer holds its level: its contacts' penalty follows its own level
// (k ~ m / step^2), and a body whose step lies near a level's bound would otherwise switch to
// and fro, each fall stiffening its contacts fourfold at their depth and pushing energy into
// them (run 6 at L = 2: contact energy -61 J/m and balance -1.7e-4 without the margin, -0.06 J/m
// and -1.5e-6 with 1.3, +4.8 J/m at a single rate).
constexpr double body_level_up_margin = 1.3;
// A part of a body in parts sets no penalty (its body's own step does): its level rises with a
// margin against rounding's to and fro alone. With the body's margin the projectile's parts, whose
// steps lie between 4 and 5.2 base steps for most of run 6, stayed at level 1.
constexpr double part_level_up_margin = 1.1;

// A body's (or a part's) own level under multiple time stepping (Solver, max_level), from its
// level `now`: it falls at once to stepLevel, it rises only when the step holds the higher level
// with the margin `up_margin`.
int ownLevel(double body_step, double base_step, int now, int max_level,
             double up_margin = body_level_up_margin);

// The least gain over all triangle shapes of a constant-strain triangle's critical step on its
// cheap bound L_s / c (L_s two thirds of its shortest altitude; the gain criticalStepGain in
// fem/solver.cpp computes for one shape) at shear share g = G / M:
//   1 / sqrt(max(g, 1 - g)) (the equilateral triangle) capped at sqrt(3/2) (the flat right
//   triangle's limit, the least for 1/3 < g < 2/3); 1 outside [0, 3/4].
// For a body's step from the cheap bounds of all its elements without an eigenvalue each: about
// 1.22 for quartz and steel. (inline: the element pass takes it for every element)
inline double leastStepGain(double g) {
  if (!(g >= 0.0 && g <= 0.75))
    return 1.0;
  return std::min(1.0 / std::sqrt(std::max(g, 1.0 - g)), std::sqrt(1.5));
}

class LevelCensus {
public:
  // Censuses for every largest level from 1 to max_level.
  LevelCensus(const Model &model, int max_level);

  // One sample: the bodies' own steps on the base step, and the contact's last step (its pairs of
  // bodies with overlapping boxes, its node-to-segment contacts).
  void sample(const Model &model, double time, std::size_t step,
              const std::vector<double> &body_steps, double base_step,
              const std::vector<std::pair<std::uint32_t, std::uint32_t>> &pairs,
              const std::vector<Contact::BodyContact> &contacts);

  // A quantity per sample, its unit and meaning (run.h5's /levels).
  struct Column {
    std::string name, unit, meaning;
    std::vector<double> values;
  };
  const std::vector<Column> &columns() const { return columns_; }
  std::size_t samples() const { return samples_; }
  int maxLevel() const { return max_level_; }
  // Sum over the samples of column `name`.
  double total(const std::string &name) const;

private:
  Column &column(const std::string &name, const std::string &unit, const std::string &meaning);

  int max_level_;
  std::size_t samples_ = 0;
  std::vector<Column> columns_;
  // Node-to-element adjacency (CSR): the elements of node a are
  // node_elements_[node_element_begin_[a] .. node_element_begin_[a + 1]).
  std::vector<std::uint32_t> node_element_begin_, node_elements_;
  std::vector<std::int8_t> node_level_, element_level_; // promotion of a sample (-1: none)
  std::vector<std::uint32_t> marked_nodes_, marked_elements_;
};

} // namespace mesopen::fem
