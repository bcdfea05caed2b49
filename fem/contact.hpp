// Frictional contact between bodies and with the rigid walls of the box (thesis section 3;
// MODELS.md "Contact"). Every step, at x(n+1):
//   - broad phase: the bodies' bounding boxes in a uniform grid give the pairs of bodies whose boxes
//     overlap (at least one of them moving);
//   - narrow phase, node to segment both ways: a boundary node of one body inside the other is
//     pushed out through the closest boundary segment (depth d, outward normal n), and the reaction
//     goes to the segment's two nodes by the linear weights of the contact point;
//   - normal force: a penalty tied to the nodal masses and the step, with damping on approach,
//       f_n = max(0, m_eff / dt (kappa d / dt + 2 zeta sqrt(kappa) v_approach)),
//       m_eff = m_node m_seg / (m_node + m_seg)
//     kappa = 1, zeta = 1/2 would be f_n = m_eff (d + v_approach dt) / dt^2, the force that closes
//     in one step the penetration two free nodes would reach at the next step (a kinematic
//     constraint). Two nodes that meet are pushed apart by both passes, which doubles the
//     stiffness: a head-on impact stays stable up to kappa = 0.5 and breaks its mirror symmetry
//     from 0.7 (tests/verification/contact.cpp); the default is 0.5;
//   - Coulomb friction against the relative tangential velocity v_t:
//       f_t = min(mu f_n, m_eff |v_t| / dt)
//     (sliding at mu f_n; the second term is the force that stops the slip in one step: sticking).
// Forces go into the nodes by Nodes::addExternal (with their frictional part),
// so that the solver accounts their work as contact and friction energy. Bodies that are loaded
// are woken; pairs of bodies that both rest are not searched.
// Each pair keeps the lists of its boundary nodes and segments near the overlap of the two boxes,
// taken with a margin and refreshed only when the two bodies may have moved by a quarter of that
// margin (a bound on the displacement of every boundary node, summed step by step): a step then
// looks at a handful of nodes and segments per pair, and finds exactly what a search of the whole
// boundaries would.
#pragma once

#include "solver.hpp"

#include <cstdint>
#include <limits>
#include <unordered_map>
#include <vector>

namespace mesopen::fem {

struct ContactSettings {
  // Coulomb coefficient per pair of materials (Model::materials indices), n x n row-major; a
  // single value applies to every pair.
  std::vector<double> friction{0.3};
  double wall_friction = 0.3;
  double stiffness = 0.5; // kappa: penalty k = kappa m_eff / dt^2
  double damping = 0.5;   // zeta: fraction of the contact spring's critical damping
  // Rigid walls, each a half-plane the nodes stay on the inside of (NaN: no wall).
  double wall_left = std::numeric_limits<double>::quiet_NaN();   // x >= wall_left
  double wall_right = std::numeric_limits<double>::quiet_NaN();  // x <= wall_right
  double wall_bottom = std::numeric_limits<double>::quiet_NaN(); // y >= wall_bottom
};

struct ContactStatistics {
  std::size_t pairs = 0, contacts = 0;   // this step: body pairs searched, nodes in contact
  double depth = 0.0;                    // this step: deepest penetration / element size
  double max_depth = 0.0;                // the same, over the run
  std::size_t deep = 0;                  // over the run: node-steps deeper than half an element
  std::size_t refreshed = 0;             // over the run: pair lists (re)built
  double seconds = 0.0;                  // wall time spent in contact, over the run
};

class Contact final : public ForceProvider {
public:
  Contact(const Model &model, ContactSettings settings);
  void addForces(Model &model, double time, double dt) override;
  const ContactStatistics &statistics() const { return stats_; }

  // One contact force: on `node`, and minus it on the segment's nodes by weights 1 - w2, w2 (no
  // segment for a wall).
  struct Hit {
    std::uint32_t node, s1, s2;
    double w2, fx, fy, friction_x, friction_y, depth; // depth / element size
  };

private:
  struct Box {
    double x0, y0, x1, y1;
  };
  struct Segment {
    double ax, ay, tx, ty, length, nx, ny; // start, unit tangent, length, outward normal
  };
  // What a pair of bodies (a, b), a < b, looks at: a's boundary nodes (indices into nodes_), b's
  // segments, b's nodes, a's segments (indices into the segment lists), near the boxes' overlap.
  struct PairList {
    double travel_a = -std::numeric_limits<double>::infinity(), travel_b = 0.0; // the bodies' travel_ when it was built
    double margin = 0.0;
    std::size_t used = 0;                        // the last step that used it
    std::uint32_t end[3] = {};                   // ends of the first three parts of `items`
    std::vector<std::uint32_t> items;
  };
  // Bodies in a uniform grid of cells (cell lists), for the broad phase.
  struct Grid {
    double x0 = 0, y0 = 0, cell = 0;
    std::size_t nx = 0, ny = 0;
    std::vector<std::uint32_t> start, bodies;
    std::size_t ix(double x) const;
    std::size_t iy(double y) const;
    void build(const std::vector<Box> &boxes, const std::vector<std::uint32_t> &which, double cell);
  };

  void measure(const Model &model, std::size_t body);
  void findPairs(const Model &model);
  void refresh(std::size_t a, std::size_t b, PairList &list) const;
  void touch(const Model &model, std::size_t A, std::size_t B, const std::uint32_t *nodes,
             const std::uint32_t *nodes_end, const std::uint32_t *segments,
             const std::uint32_t *segments_end, double dt, std::vector<Hit> &hits,
             std::vector<Segment> &near, std::vector<std::uint32_t> &near_index) const;
  bool inside(const Nodes &nodes, std::size_t B, double px, double py) const;
  void walls(const Model &model, double dt, std::vector<Hit> &hits) const;
  void hit(const Model &model, std::uint32_t node, std::uint32_t s1, std::uint32_t s2, double w2,
           double nx, double ny, double depth, double h, double mu, double dt,
           std::vector<Hit> &hits) const;

  ContactSettings s_;
  std::size_t n_materials_;
  std::vector<std::size_t> node_begin_, segment_begin_; // per body, into nodes_ and segments_
  std::vector<std::uint32_t> nodes_;                    // boundary nodes, body by body
  std::vector<double> node_x_, node_y_;                 // their positions, this step
  std::vector<std::uint32_t> segments_;                 // boundary edges (node pairs, ccw)
  std::vector<std::uint32_t> segment_ends_;             // the same as indices into nodes_
  std::vector<double> size_;                            // per body: longest boundary edge [m]
  std::vector<Box> boxes_;                              // per body, this step
  std::vector<double> travel_; // per body: sum over steps of its boundary nodes' largest move
  std::vector<std::uint32_t> moving_;                   // bodies not at rest, this step
  double cell_ = 0.0;
  Grid rest_grid_, moving_grid_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs_;
  std::unordered_map<std::uint64_t, PairList> lists_;  // per pair of bodies seen lately
  std::vector<PairList *> pair_lists_;                  // of pairs_, this step
  std::size_t step_ = 0;
  std::vector<std::vector<Hit>> thread_hits_;
  ContactStatistics stats_;
};

} // namespace mesopen::fem
