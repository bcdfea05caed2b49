#include "contact_boundaries.hpp"

#include <algorithm>
#include <cmath>

namespace mesopen::fem {

namespace {
double sq(double x) { return x * x; }
} // namespace

ContactBoundaries::ContactBoundaries(const Model &model) {
  const std::size_t n_bodies = model.bodies.size();
  for (const Body &body : model.bodies)
    material.push_back(static_cast<std::uint16_t>(body.material));
  // Each body's element size: its longest boundary edge now.
  for (const Body &body : model.bodies) {
    double longest = 0.0;
    for (std::size_t k = 0; k + 1 < body.boundary.size(); k += 2) {
      const std::uint32_t a = body.boundary[k], b = body.boundary[k + 1];
      longest = std::max(longest, std::sqrt(sq(model.nodes.x[b] - model.nodes.x[a]) +
                                            sq(model.nodes.y[b] - model.nodes.y[a])));
    }
    size.push_back(longest);
  }
  boxes.resize(n_bodies);
  travel.assign(n_bodies, 0.0);
  take(model);
}

// Nodes that erosion left without elements are not among the boundary nodes: held by contact
// springs alone, a free node squeezed between several grains is stiffer than the step allows (as
// in explicit codes' usual practice, eroded nodes leave the contact; they keep their mass and
// momentum).
void ContactBoundaries::take(const Model &model) {
  const Nodes &nd = model.nodes;
  node_begin.assign(1, 0), segment_begin.assign(1, 0);
  nodes.clear(), segment_ends.clear();
  for (const Body &body : model.bodies) {
    std::vector<std::uint32_t> own(body.boundary.begin(), body.boundary.end());
    std::sort(own.begin(), own.end());
    own.erase(std::unique(own.begin(), own.end()), own.end());
    for (std::uint32_t p : body.boundary)
      segment_ends.push_back(static_cast<std::uint32_t>(
          nodes.size() + (std::lower_bound(own.begin(), own.end(), p) - own.begin())));
    nodes.insert(nodes.end(), own.begin(), own.end());
    node_begin.push_back(nodes.size());
    segment_begin.push_back(segment_ends.size() / 2);
  }
  points.resize(nodes.size());
  for (std::size_t k = 0; k < nodes.size(); ++k)
    points[k] = {nd.x[nodes[k]], nd.y[nodes[k]]};
  // A vertex is the start of one segment and the end of one, unless the boundary touches itself
  // there (erosion can leave two elements joined at a corner alone).
  std::vector<std::uint32_t> starts(nodes.size(), 0);
  for (std::size_t k = 0; k < segment_ends.size(); k += 2)
    ++starts[segment_ends[k]];
  pinched.resize(nodes.size());
  for (std::size_t k = 0; k < nodes.size(); ++k)
    pinched[k] = starts[k] != 1;
  // (the points are where the nodes are: no travel)
  for (std::size_t b = 0; b < model.bodies.size(); ++b)
    measure(model, b);
}

void ContactBoundaries::measure(const Model &model, std::size_t b) {
  const Nodes &nd = model.nodes;
  Box box{HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  double moved2 = 0.0;
  for (std::size_t k = node_begin[b]; k < node_begin[b + 1]; ++k) {
    const std::uint32_t a = nodes[k];
    const double x = nd.x[a], y = nd.y[a];
    moved2 = std::max(moved2, sq(x - points[k].x) + sq(y - points[k].y));
    points[k] = {x, y};
    box.x0 = std::min(box.x0, x), box.x1 = std::max(box.x1, x);
    box.y0 = std::min(box.y0, y), box.y1 = std::max(box.y1, y);
  }
  boxes[b] = box;
  travel[b] += std::sqrt(moved2);
}

} // namespace mesopen::fem
