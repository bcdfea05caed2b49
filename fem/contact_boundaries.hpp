// The bodies' boundaries as FE-FE contact (fem/contact.hpp) sees them, body after body in arrays
// of their own: each body's boundary nodes (model node indices) and their positions this step,
// its boundary segments (counter-clockwise, their two ends as indices into the boundary nodes),
// its bounding box, its element size (its longest boundary edge at the start: the contact's reach
// and depths are measured in it, through erosion too) and its travel, a bound on how far any of
// its boundary nodes has moved since the start (the largest move of a step, summed step by step).
// The broad phase (contact_broad.hpp) and the pair lists rely on the travel.
// Equations: docs/models.md §8.
#pragma once

#include "contact_narrow.hpp"
#include "model.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace mesopen::fem {

struct ContactBoundaries {
  using Box = narrow::Box;
  using Point = narrow::Point;

  // The boundaries of the model's bodies now (take), their materials, element sizes, boxes, and
  // no travel yet.
  explicit ContactBoundaries(const Model &model);
  // The boundary nodes and segments from Body::boundary, at their positions now, and the boxes
  // (after erosion changed boundaries: the travel goes on, the element sizes stay).
  void take(const Model &model);
  // Body b's boundary node positions and box now; its travel grows by the largest move of its
  // nodes since the last measure.
  void measure(const Model &model, std::size_t b);
  // Body b's boundary node positions now, its box and travel left as they are (set by the process
  // that measured it).
  void place(const Model &model, std::size_t b) {
    for (std::size_t k = node_begin[b]; k < node_begin[b + 1]; ++k)
      points[k] = {model.nodes.x[nodes[k]], model.nodes.y[nodes[k]]};
  }

  // Body b's box and travel as five values (x0, y0, x1, y1, travel), as they travel between
  // processes; and set from them.
  static constexpr std::size_t box_values = 5;
  std::array<double, box_values> boxAndTravel(std::size_t b) const {
    return {boxes[b].x0, boxes[b].y0, boxes[b].x1, boxes[b].y1, travel[b]};
  }
  void setBoxAndTravel(std::size_t b, const double *values) {
    boxes[b] = {values[0], values[1], values[2], values[3]};
    travel[b] = values[4];
  }

  // Whether body b has a boundary (erosion can leave a body without elements).
  bool hasNodes(std::size_t b) const { return node_begin[b] < node_begin[b + 1]; }
  // Body b's segments: their ends, two by two, from ends(b) up to endsEnd(b).
  const std::uint32_t *ends(std::size_t b) const {
    return segment_ends.data() + 2 * segment_begin[b];
  }
  const std::uint32_t *endsEnd(std::size_t b) const {
    return segment_ends.data() + 2 * segment_begin[b + 1];
  }
  // Whether (px, py) lies inside body B's boundary polygon (the crossing count).
  bool inside(std::size_t B, double px, double py) const {
    return narrow::inside(points.data(), ends(B), endsEnd(B), px, py);
  }

  std::vector<std::uint16_t> material; // per body: its material (Model::materials index)
  // per body, into nodes and segment_ends / 2 (one more: the ends)
  std::vector<std::size_t> node_begin, segment_begin;
  std::vector<std::uint32_t> nodes; // boundary nodes, body by body
  std::vector<Point> points;        // per boundary node (as nodes): its position this step
  // boundary edges (counter-clockwise), their two nodes as indices into nodes
  std::vector<std::uint32_t> segment_ends;
  std::vector<std::uint8_t> pinched; // per boundary node: not the start of exactly one edge
  std::vector<double> size;          // per body: longest boundary edge at the start [m]
  std::vector<Box> boxes;            // per body, this step
  std::vector<double> travel;        // per body: sum over steps of its boundary nodes' largest move
};

} // namespace mesopen::fem
