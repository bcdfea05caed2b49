// Depths FE-FE contact (fem/contact.hpp) does not push against at once: the overlaps erosion lays
// bare (a node already inside another body when the elements that held it out left) and the
// contacts found deeper than a step's approach can make (a boundary folded over a node, a closest
// segment changed in a dented body). Such a node's depth then is allowed for (not pushed against)
// and let go over release_steps steps (contact_law.hpp), so that the overlap opens at a bounded
// speed instead of in one step.
// Equations: docs/models.md §8.5.
#pragma once

#include "contact_law.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace mesopen::fem {

class ContactAllowances {
public:
  explicit ContactAllowances(std::size_t n_nodes) : n_nodes_(n_nodes) {}

  // Model node `node`'s depth up to `depth` [m] is allowed for, and let go over release_steps
  // steps (a deeper allowance than the node has replaces it).
  void allow(std::uint32_t node, double depth) {
    if (allowance_.empty())
      allowance_.assign(n_nodes_, 0.0);
    if (depth <= allowance_[node])
      return;
    if (allowance_[node] == 0.0)
      allowed_.push_back({node, 0.0});
    allowance_[node] = depth;
    for (Allowed &a : allowed_)
      if (a.node == node)
        a.rate = depth / release_steps;
  }
  // A step's share of every allowance is let go.
  void release() {
    std::erase_if(allowed_, [&](const Allowed &a) {
      allowance_[a.node] = std::max(0.0, allowance_[a.node] - a.rate);
      return allowance_[a.node] == 0.0;
    });
  }
  // Model node `node`'s allowance and release per step set as they are (0: none), as another
  // process kept them.
  void set(std::uint32_t node, double allowance, double rate) {
    if (allowance > 0.0 && allowance_.empty())
      allowance_.assign(n_nodes_, 0.0);
    if (allowance_.empty())
      return;
    if (allowance_[node] > 0.0)
      std::erase_if(allowed_, [&](const Allowed &a) { return a.node == node; });
    allowance_[node] = allowance;
    if (allowance > 0.0)
      allowed_.push_back({node, rate});
  }
  // The release per step of model node `node`'s allowance (0: none).
  double rate(std::uint32_t node) const {
    for (const Allowed &a : allowed_)
      if (a.node == node)
        return a.rate;
    return 0.0;
  }
  // The depth allowed for at model node `node` [m] (0 most steps, without a look-up).
  double of(std::uint32_t node) const { return allowed_.empty() ? 0.0 : allowance_[node]; }

  // The nodes with an allowance, in order, with their release per step (a checkpoint); restore
  // takes them back with their allowances.
  struct Allowed {
    std::uint32_t node;
    double rate; // [m per step]
  };
  const std::vector<Allowed> &allowed() const { return allowed_; }
  void restore(const std::vector<Allowed> &allowed, const std::vector<double> &allowances) {
    allowance_.clear(), allowed_ = allowed;
    if (!allowed_.empty())
      allowance_.assign(n_nodes_, 0.0);
    for (std::size_t k = 0; k < allowed_.size(); ++k)
      allowance_[allowed_[k].node] = allowances[k];
  }

private:
  std::size_t n_nodes_;
  std::vector<double> allowance_; // per model node, once some node is allowed for
  std::vector<Allowed> allowed_;  // the nodes with an allowance
};

} // namespace mesopen::fem
