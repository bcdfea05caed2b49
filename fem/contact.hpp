// Frictional contact between bodies and with the rigid walls of the box (thesis section 3).
// Every step, at x(n+1), on the bodies' boundaries (contact_boundaries.hpp), in three pieces:
//   - broad phase (contact_broad.hpp, BodyPairs): the bodies' bounding boxes in a cell grid
//     (grid/cell_grid.hpp) give the pairs of bodies whose boxes overlap (at least one of them
//     moving);
//   - narrow phase (contact_narrow.hpp), node to segment both ways: a boundary node of one body
//     inside the other is pushed out through the closest boundary segment (depth d, outward normal
//     n), and the reaction goes to the segment's two nodes by the linear weights of the contact
//     point;
//   - the law (contact_law.hpp, shared with FE-DEM contact): a normal force, a penalty tied to
//     the nodal masses and the step, with damping on approach,
//       f_n = max(0, m_eff / dt (kappa d / dt + 2 zeta sqrt(kappa) v_approach)),
//       m_eff = m_node m_seg / (m_node + m_seg)
//     kappa = 1, zeta = 1/2 would be f_n = m_eff (d + v_approach dt) / dt^2, the force that closes
//     in one step the penetration two free nodes would reach at the next step (a kinematic
//     constraint). Two nodes that meet are pushed apart by both passes, which doubles the
//     stiffness and the damping: a head-on impact stays stable up to kappa = 0.5 and breaks its
//     mirror symmetry from 0.7 (tests/verification/contact.cpp); the default is 0.5. The damping
//     acts on v(n+1/2), one half step behind, and central differences with such a damper (c in
//     units of m / dt) are stable only while (omega dt)^2 + 2 c <= 4. With the doubled contact
//     (kappa_n = 2 kappa = 1, c_n = 4 zeta sqrt(kappa)) beside the stiffest element the step
//     allows ((omega_e dt)^2 = 4 * 0.9^2 (1 - kappa_n / 4), see ForceProvider::stepStiffness),
//     that holds up to zeta = 0.1, the default. Beyond it meeting corners chatter with a period of
//     two steps and the elements' energy no longer follows the work done on them: at zeta = 0.5 a
//     pair of grains meeting corner to corner at 100 m/s closed its energy balance within 0.18 of
//     the impact's energy, at 0.1 within 1e-4 (tests/verification/grain_pair.cpp). A rigid wall is
//     found by one pass only and takes 2 kappa (1: the stiffness of the one-step constraint);
//   - a depth no step's approach can make (deeper than the node's depth the step before plus twice
//     its approach, -2 v_n dt, or 0.005 of an element: a boundary folded over it, a closest segment
//     changed in a dented body) is not pushed out at once, at depth / dt: the excess is allowed for
//     and let go over 200 steps, as the overlaps erosion lays bare (see hit and
//     contact_allowances.hpp);
//   - Coulomb friction against the relative tangential velocity v_t:
//       f_t = min(mu f_n, m_eff |v_t| / dt)
//     (sliding at mu f_n; the second term is the force that stops the slip in one step: sticking).
// Forces go into the nodes by Nodes::addExternal (with their frictional part),
// so that the solver accounts their work as contact and friction energy. Bodies that are loaded
// are woken; pairs of bodies that both rest are not searched.
// The pairs of bodies are kept from step to step (a Verlet list of bodies, BodyPairs): found with
// the boxes widened by a margin, and found anew only when some body may have moved by half of it;
// a body that wakes in between adds its pairs with bodies at rest. Each pair keeps the lists of its
// boundary nodes and segments near the overlap of the two boxes, taken with a margin of its own
// and refreshed when the two bodies may have moved by a quarter of that (a bound on the
// displacement of every boundary node, summed step by step), not when the pairs are searched anew
// (the projectile's pace sets that, and most pairs move far more slowly): a step looks at a handful
// of nodes and segments per pair, in one stream of memory per run of pairs, and finds exactly what
// a search of the whole boundaries would. Of those nodes, one found outside the other body by a gap
// g stays outside while the two bodies move by less than g together: such clear nodes are looked at
// again only then, the others (hot: in contact, touching) every step; a side of a pair with no hot
// node and no clear node due is skipped.
// Equations: docs/models.md §8.
#pragma once

#include "contact_allowances.hpp"
#include "contact_boundaries.hpp"
#include "contact_broad.hpp"
#include "contact_law.hpp"
#include "contact_narrow.hpp"
#include "solver.hpp"

#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace mesopen::fem {

struct ContactSettings {
  // Coulomb coefficient per pair of materials (Model::materials indices), n x n row-major; a
  // single value applies to every pair.
  std::vector<double> friction{0.3};
  double wall_friction = 0.3;
  double stiffness = 0.5; // kappa: penalty k = kappa m_eff / dt^2 (2 kappa at the walls)
  double damping = 0.1;   // zeta: fraction of the contact spring's critical damping (see above)
  // Rigid walls, each a half-plane the nodes stay on the inside of (NaN: no wall).
  double wall_left = std::numeric_limits<double>::quiet_NaN();   // x >= wall_left
  double wall_right = std::numeric_limits<double>::quiet_NaN();  // x <= wall_right
  double wall_bottom = std::numeric_limits<double>::quiet_NaN(); // y >= wall_bottom
  // With the work shared among processes: a body of at least this many boundary nodes goes to a
  // halo partner in part (Contact::exchangeHalo; 0: every body whole). The run is the same.
  std::int64_t halo_in_part_from = 128;
};

struct ContactStatistics {
  std::size_t pairs = 0, contacts = 0; // this step: body pairs searched, nodes in contact
  double depth = 0.0;                  // this step: deepest penetration / element size
  double max_depth = 0.0;              // the same, over the run
  std::size_t deep = 0;                // over the run: node-steps deeper than half an element
  std::size_t refreshed = 0;           // over the run: pair lists (re)built
  std::size_t searches = 0;            // over the run: searches for pairs of bodies
  std::size_t pair_steps = 0;          // over the run: body pairs searched, summed over the steps
  std::size_t sides = 0, skipped = 0;  // over the run: sides of overlapping pairs, skipped as clear
  std::size_t partial = 0;             // over the run: sides whose hot nodes alone were looked at
  std::size_t sudden = 0;              // over the run: contacts found deeper than a step's approach
  std::size_t beneath_folds = 0; // over the run: contacts beneath a fold of a boundary (touch)
  std::size_t halo_nodes = 0;    // over the run: other processes' boundary nodes received (halo)
  double seconds = 0.0;          // wall time spent in contact, over the run
};

class Contact final : public ForceProvider {
public:
  Contact(const Model &model, ContactSettings settings);
  void addForces(Model &model, double time, double dt) override;
  // A node meeting a node is pushed by both passes, a node at a wall by one with twice the
  // stiffness: kappa_n = 2 kappa either way.
  double stepStiffness() const override { return 2.0 * s_.stiffness; }
  void boundaryChanged(const Model &model, const std::vector<std::uint32_t> &bodies) override;
  // Levels: a pair is computed at steps where both bodies are due, over the coarser body's window;
  // a body may meet the bodies of its pairs (boxes within the search margin).
  bool takesLevels() const override { return true; }
  void capLevels(const Model &model, const std::vector<std::uint8_t> &reach,
                 std::vector<std::uint8_t> &cap) override;
  // A part may meet the bodies of its body's pairs whose boxes, widened by the search margin (by
  // which the pairs were found), overlap its box.
  void capParts(const std::vector<std::uint8_t> &own, std::uint32_t body,
                const std::vector<double> &boxes, std::vector<std::uint8_t> &cap) const override;
  // This process's statistics (with the work shared, of the pairs and sides it computed); of all
  // processes together (every process calls it: counts summed, depths the largest).
  const ContactStatistics &statistics() const { return stats_; }
  ContactStatistics statisticsOfAll() const;
  // The work shared by several processes: each computes the sides of the pairs (a body's nodes
  // against the other's segments) of the bodies it owns, and sends the reactions on other
  // processes' nodes to their owners, with the bodies it woke to all.
  void shareWork(const parallel::Communicator &processes, const std::vector<int> &owner) override;
  void bodiesMoving(const Model &model, const std::vector<std::uint32_t> &bodies,
                    const std::vector<int> &new_owner) override;
  // Two figures: the farthest this process's moving bodies may have travelled since the last
  // search for pairs at the next step (after a drift of at most `drift`): when the largest over
  // the processes cannot call for a search, the next step asks no process whether to search; and
  // the number of bodies at rest this process's contacts loaded in the step (each woke at its
  // owner, with the loads): with any, every process's are all-gathered, and every process wakes
  // them all.
  void stepFigures(const Model &model, double drift, std::vector<double> &figures) const override;
  void stepReduced(Model &model, const double *largest) override;
  // The last step's contacts between bodies (the walls' left out; with the work shared, this
  // process's), in pair order: a boundary node
  // of `node_body` pushed out of `segment_body` through the segment between two of its nodes
  // (model node indices).
  struct BodyContact {
    std::uint32_t node_body, node, segment_body, segment_node[2];
  };
  std::vector<BodyContact> lastContacts() const;
  // The last step's pairs of bodies whose boxes overlap (those the narrow phase looked at; with the
  // work shared, those of this process's bodies: the others' boxes are current at their owners).
  std::vector<std::pair<std::uint32_t, std::uint32_t>> overlappingPairs() const;

private:
  using Box = narrow::Box;
  using Point = narrow::Point;
  using Near = narrow::Near;
  using Pair = BodyPairs::Pair;

  // A contact force on a node (or a segment's node's share of the reaction), with its frictional
  // part; `body` is the node's; the depth the node was pushed at (0 for a reaction); `order`, its
  // contact's (Found::order) plus 0 for the node, 1 and 2 for the segment's nodes.
  struct Load {
    std::uint32_t node, body;
    double fx, fy, friction_x, friction_y, depth;
    std::uint64_t order;
    std::uint8_t level = 0;    // with levels: its pair's (the coarser body's)
    double penalty_step = 0.0; // with levels: the step its penalty was taken from (hit)
  };
  // A contact: boundary node k (index into the boundary nodes) of body A, pushed out along
  // (nx, ny) by `depth` from the segment k1-k2 of body B (at weight w2 from k1) or from a wall
  // (k1 = no_node); h the element size, mu the friction coefficient. `order`: where it comes in
  // a step's contacts (its pair's place in the pairs, the side, its place in the side; the walls'
  // after every pair), the order in which a node's forces add up on whichever process.
  struct Found {
    std::uint32_t A, k, B, k1, k2;
    double w2, nx, ny, depth, h, mu;
    std::uint64_t order;
  };
  // A run's contacts as the narrow phase finds them, then their forces by block of bodies (see
  // addHits) in the order of the contacts, and their number, deepest penetration (over the
  // element size) and how many are deeper than half an element.
  struct Hits {
    std::vector<Found> found;
    std::vector<std::vector<Load>> loads; // per block of bodies
    // the nodes (model indices) found suddenly deep, and by how much (see hit)
    std::vector<std::pair<std::uint32_t, double>> sudden;
    std::size_t count = 0, deep = 0, beneath_folds = 0;
    double depth = 0.0;
    void clear();
  };
  // A thread's working lists: segments near a node set, distances.
  struct Scratch {
    Near near, node_near; // the segments near a pair's overlap; near one node (touch, listNear)
    std::vector<std::uint32_t> items, candidates;
    std::vector<double> distance;
    std::vector<char> keep;
    std::vector<std::uint64_t> beyond;
  };

  // The phases of a step after the broad phase (see addForces).
  void narrowPhase(const Model &model, double dt);
  void walls(const Model &model, double dt, Hits &hits) const;
  void addHits(Model &model);
  void addBlock(Model &model, std::size_t k);
  void sendLoads(Model &model);
  void shareBoxes(const Model &model, bool anew);
  void exchangeHalo(Model &model);
  using BodiesTo = std::vector<std::pair<int, std::uint32_t>>; // (process, body)
  template <class Count, class Pack, class Unpack>
  void sendBodies(BodiesTo sends, BodiesTo receives, Count count, Pack pack, Unpack unpack) const;
  bool shared() const { return processes_ != nullptr && processes_->size() > 1; }
  bool mine(std::size_t body) const { return !shared() || (*owner_)[body] == processes_->rank(); }

  // Narrow phase (on the geometry of contact_narrow.hpp) and forces (the law of contact_law.hpp).
  // The segments of `body` given by their ends that come within its reach (check_depth of an
  // element) of `region`, into `near`; returns the region widened by that reach.
  Box nearSegments(std::size_t body, const std::uint32_t *ends, const std::uint32_t *ends_end,
                   const Box &region, Near &near) const;
  void refresh(Pair &pair, std::vector<std::uint32_t> &arena, Scratch &scratch) const;
  std::uint32_t listNear(std::size_t A, std::size_t B, const Box &region, double margin,
                         Scratch &scratch) const;
  void touch(const Model &model, std::size_t A, std::size_t B, const std::uint32_t *nodes,
             const std::uint32_t *nodes_end, const std::uint32_t *ends,
             const std::uint32_t *ends_end, double travel, double &until, std::uint32_t *hot,
             std::uint32_t &n_hot, Hits &hits, Scratch &scratch) const;
  void hit(const Model &model, const Found &f, double dt, Hits &hits) const;
  double penetration(std::size_t B, double px, double py, Scratch &scratch) const;
  void allowOverlaps(std::size_t C, const std::vector<std::uint32_t> &before);
  // Prefetching ahead in the loops over the pairs, the contacts and the loads.
  void prefetchPair(const Pair &pair, const std::vector<std::uint32_t> &arena) const;
  void prefetchHit(const Model &model, const Found &f) const;
  static void prefetchLoad(const Nodes &nd, const Load &load);

  ContactSettings s_;      // with a friction coefficient per pair of materials
  double damping_[2] = {}; // the damping coefficient c of hit, between bodies and at a wall
  std::size_t n_materials_;
  ContactBoundaries boundaries_;
  BodyPairs pairs_;
  ContactAllowances allowances_;    // depths not pushed against, let go step by step
  WorkLists run_lists_;             // the runs of pairs listed per thread (narrowPhase)
  std::vector<Hits> run_hits_;      // per run of pairs (the last also the walls')
  std::vector<Scratch> scratch_;    // per thread
  std::vector<std::uint8_t> block_; // per body: its block of bodies
  std::vector<std::vector<std::uint32_t>> block_loaded_; // per block of bodies: nodes it loaded
  std::vector<std::vector<std::uint32_t>> block_pushed_; // per block of bodies: nodes pushed_ holds
  // With the work shared: the processes, every body's owner (the solver's), and per block of
  // bodies the loads other processes sent this step, in order.
  const parallel::Communicator *processes_ = nullptr;
  const std::vector<int> *owner_ = nullptr;
  std::vector<std::vector<Load>> block_received_;
  // The depth each model node was pushed at in the last step (the deepest of its contacts; 0 if
  // none; the nodes where it is not 0 are in block_pushed_).
  std::vector<double> pushed_;
  // With levels instead, one such depth per level of pair: the deepest of the node's contacts in
  // the last step its pairs of that level were computed, and when; a pair takes the deepest within
  // its window (hit), so its own last step's whatever finer pairs pushed the node since. Beside
  // each the step its penalty was taken from (hit: a contact keeps it while it lasts). Node by
  // node, its levels side by side (levelPushed): a contact reads them all, in one or two lines.
  struct LevelPushed {
    double depth = 0.0, time = -HUGE_VAL, penalty = 0.0;
  };
  std::vector<LevelPushed> level_pushed_;
  std::size_t pushed_levels_ = 1;
  LevelPushed &levelPushed(std::size_t node, std::size_t level) {
    return level_pushed_[node * pushed_levels_ + level];
  }
  const LevelPushed &levelPushed(std::size_t node, std::size_t level) const {
    return level_pushed_[node * pushed_levels_ + level];
  }
  double time_ = 0.0;
  // From the last step's reduction: a bound on the largest travel since the last search of the
  // moving bodies at this step (stepFigure); HUGE_VAL: none.
  double travel_bound_ = HUGE_VAL;
  // With the work shared: the processes this one exchanges halo nodes and loads with in this step
  // (ascending), and the bodies at rest its contacts loaded (sendLoads, to stepReduced).
  std::vector<int> partners_;
  std::vector<std::int64_t> woken_;
  // With the work shared: the bodies of other processes here in part in this step (exchangeHalo),
  // each with its window, whether the window's lower-left corner is inside it, and the boundary
  // nodes that came (positions in its boundary nodes); per body its window's place, or -1.
  struct HaloWindow {
    std::uint32_t body;
    Box box;
    bool corner_inside;
    std::vector<std::uint32_t> received;
  };
  std::vector<HaloWindow> windows_;
  std::vector<std::int32_t> window_of_;
  bool insideOf(std::size_t B, double px, double py) const;
  double windowClearance(std::size_t B, double px, double py) const;
  ContactStatistics stats_;

public:
  // What the steps to come depend on beyond the model's state (a run's checkpoint,
  // run/checkpoint.hpp). The pairs' lists are left out: taken anew they hold the same contacts
  // (docs/solver.md); the pairs' order is kept, the order in which a node's forces add up.
  struct State {
    std::vector<std::uint32_t> pairs; // a and b of each pair, in order
    bool search_due = true;           // the pairs are searched anew at the next step
    std::vector<double> travel, travel_searched, boxes; // per body (boxes: x0, y0, x1, y1)
    std::vector<std::uint8_t> listed;                   // per body
    std::vector<double> points;          // per boundary node: x, y where it was last measured
    std::vector<std::uint32_t> allowed;  // the nodes with an allowance, in order
    std::vector<double> allowance, rate; // their allowance [m] and its release per step [m]
    std::vector<std::uint32_t> pushed;   // the nodes pushed in the last step
    std::vector<double> pushed_depth;    // and at what depth [m]
    // with levels, the depths per level of pair instead (pushed_): their levels (0: without
    // levels), and each one ever pushed: its place l n + node, depth [m], time [s], penalty step
    std::uint64_t pushed_levels = 0;
    std::vector<std::uint64_t> level_pushed;
    std::vector<double> level_pushed_depth, level_pushed_time, level_pushed_penalty;
    ContactStatistics statistics;
  };
  // (With the work shared every process calls it: the nodes' pushed depths and allowances come
  // from their owners.)
  State state(const Model &model) const;
  // Continues from `state` once the model's state (its boundaries among it) was restored.
  // Throws std::invalid_argument when `state` is not of this model.
  void restore(const Model &model, const State &state);
};

} // namespace mesopen::fem
