// Contact between the FE bodies' boundaries and DEM disks, with the law of FE-FE contact
// (fem/contact_law.hpp): a penalty tied to the masses and the step, damping on approach, Coulomb
// friction capped at the force that stops the slip in one step.
//   A disk of centre c, radius r against a body: q the closest point of the body's boundary to c,
//   on segment (s1, s2) at weight w of s2; n the unit normal from the body to the disk; overlap
//   d = r - |c - q| (or r + |c - q| with the centre inside the body).
//   f_n = max(0, m_eff / dt (kappa d / dt + 2 zeta sqrt(kappa) v_approach)),
//     m_eff the reduced mass of the disk and the segment point ((1 - w) m_s1 + w m_s2);
//     kappa twice the FE-FE kappa, as for the rigid walls: one pass finds the contact (with the
//     default 0.5, the constraint that closes the overlap in one step);
//   f_t = min(mu f_n, m_t |v_t| / dt) against the slip at the contact point (the disk's spin
//     included), m_t the reduced mass with the disk's tangential 1/m + r^2/I = 3/m.
// The force goes to the disk (and its torque about the centre), the reaction to s1 and s2 by
// weights 1 - w, w: the two sum to zero up to round-off. A closest point at a vertex takes the
// side of the vertex's pseudo-normal, as FE-FE contact does. A depth that no step's approach can
// make (erosion laying a boundary bare over a disk) is allowed for and let go over 200 steps, as in
// FE-FE contact (fem/contact.hpp).
// Equations: docs/models.md §9.4.
#pragma once

#include "cell_grid.hpp"
#include "dem.hpp"
#include "model.hpp"

#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

namespace mesopen::coupling {

struct DiskContactSettings {
  double stiffness = 0.5;       // kappa of FE-FE contact
  double damping = 0.1;         // zeta of FE-FE contact
  std::vector<double> friction; // mu per FE body
};

struct DiskContactStatistics {
  std::size_t contacts = 0;   // of the last call
  double deepest = 0.0;       // the largest overlap over the FE element size, over the run
  double work_on_disks = 0.0; // the forces' work on the disks [J/m], over the run
  std::size_t sudden = 0;     // over the run: contacts found deeper than a step's approach
  // Over the run, with multiple time stepping: disks found touching an FE body between its steps
  // (FeDemCoupling::capLevels keeps such bodies at level 0; not computed until the body steps).
  std::size_t not_due = 0;
};

class DiskContact {
public:
  DiskContact(const fem::Model &model, DiskContactSettings settings);
  // The contact forces of every disk with every FE body: onto the disks into `forces`, the
  // reactions on the FE nodes appended to `reactions`. Positions at x(n+1), velocities at n+1/2
  // on both sides.
  void addForces(const fem::Model &model, const Particles &disks, ParticleForces &forces,
                 std::vector<Reaction> &reactions, double dt);
  // The FE bodies' boxes now (those of bodies at rest kept) and the rectangle they cover widened by
  // `reach` (no disk centre outside it touches a body when `reach` is its largest radius).
  // addForces measures them itself if this was not called since the nodes moved.
  struct Region {
    double x0, y0, x1, y1;
  };
  Region measure(const fem::Model &model, double reach);
  // The speed of the fastest boundary node of the moving bodies [m/s].
  double fastest(const fem::Model &model) const;
  // With the FE bodies shared among processes: per model body, whether its nodes are current on
  // this process (its own bodies, and those received this step); the bodies at rest are current
  // everywhere (their nodes never moved). measure, fastest and addForces then look at those
  // bodies only. Null (the default): every body is.
  void lookAt(const std::vector<char> *current) { current_ = current; }
  // The region of measure taken over every process (the same disks in the same cells whatever the
  // number of processes), and the boxes and grids of `bodies` measured (received after it).
  void useRegion(const Region &region) { region_ = region; }
  void measureBodies(const fem::Model &model, const std::vector<std::uint32_t> &bodies);
  // The bodies with a boundary (model body numbers), and the box of the k-th of them as measured.
  const std::vector<std::uint32_t> &bodies() const { return fe_bodies_; }
  Region box(std::size_t k) const {
    return {boxes_[k].x0, boxes_[k].y0, boxes_[k].x1, boxes_[k].y1};
  }
  // A body's element size (its longest boundary edge where its boundary last changed) [m].
  double &elementSize(std::size_t body) { return size_[body]; }
  // The depths and allowances held for the disks `here` rejects (another process holds them now),
  // taken out as id and the bits of last, now, allowance and rate, five values each; and such
  // values taken in for the disks `here` accepts.
  std::vector<std::int64_t> takeHeld(const std::function<bool(std::int64_t)> &here);
  void putHeld(const std::vector<std::int64_t> &values,
               const std::function<bool(std::int64_t)> &here);
  // The reactions into the FE nodes (Nodes::addExternal, with their frictional part), their
  // bodies woken.
  static void apply(fem::Model &model, const std::vector<Reaction> &reactions);
  // The reaction node forces lie in model.nodes.external; the boundaries of eroded bodies change.
  void boundaryChanged(const fem::Model &model);
  const DiskContactStatistics &statistics() const { return stats_; }
  double stepStiffness() const { return 2.0 * s_.stiffness; }

private:
  struct Box {
    double x0, y0, x1, y1;
  };
  struct Closest {
    std::uint32_t s1, s2;                      // the segment's nodes
    double w = 0.0;                            // weight of s2
    double distance = 0.0, nx = 0.0, ny = 0.0; // |c - q|, unit normal out of the body
  };
  Closest closest(const fem::Model &model, std::size_t body, double cx, double cy, double reach,
                  const std::vector<std::uint32_t> &near) const;
  // A body's boundary segments in a grid of cells: a disk looks at those in the cells it meets
  // (the projectile has about a thousand). Each segment is in the cells its box widened by
  // `slack` meets: the grid holds while no node of the body moved by `slack` since it was built
  // (measure checks, from the positions then).
  struct EdgeGrid {
    CellGrid<> cells; // per cell: offsets into Body::boundary
    double slack = 0;
    std::vector<double> built_x, built_y; // per segment: its first node when built
    Box box{};                            // the body's box when built
    double cell_size = 0;                 // the disks' size it was built for
    bool valid = false;
    // From the nodes' positions x, y (by node number).
    void build(const std::vector<std::uint32_t> &edges, const double *x, const double *y,
               const Box &box, double cell_size);
  };
  std::vector<EdgeGrid> grids_; // per FE body with many segments
  std::vector<std::uint32_t> near_edges_;
  DiskContactSettings s_;
  std::vector<double> size_;             // per body: longest boundary edge [m]
  std::vector<std::uint32_t> fe_bodies_; // bodies with a boundary
  std::vector<Box> boxes_;               // theirs, this step
  Region region_{};                      // the last measure, with its reach
  double reach_ = 0.0;
  bool measured_ = false;                      // the boxes measured for the next addForces
  const std::vector<char> *current_ = nullptr; // lookAt
  bool looks(const fem::Model &model, std::uint32_t body) const {
    return current_ == nullptr || model.at_rest[body] || (*current_)[body];
  }
  void measureBody(const fem::Model &model, std::size_t k);
  std::vector<std::uint32_t> in_region_; // the disks that may touch a body
  CellGrid<> disk_grid_;                 // those, in cells of the largest disk's size
  DiskContactStatistics stats_;
  // Per disk (by id, or place when the disks have no ids) in contact or with an allowance: the
  // depth it was pushed at in the last step and in this one, a depth allowed for and its release
  // per step [m].
  struct Held {
    double last = 0.0, now = 0.0, allowance = 0.0, rate = 0.0;
  };
  std::unordered_map<std::int64_t, Held> held_;

public:
  // What the steps to come depend on beyond the model's and the disks' states (a run's
  // checkpoint, run/checkpoint.hpp): the bodies' element sizes (taken where the boundaries last
  // changed), the disks' depths and allowances, and the segment grids as they were built (a grid
  // built elsewhere lists a disk's segments in another order, which can pick another of two
  // segments as near).
  struct State {
    std::vector<double> size;                       // per FE body
    std::vector<std::int64_t> held;                 // disks (ids) with a depth or an allowance
    std::vector<double> last, now, allowance, rate; // theirs
    std::vector<std::uint32_t> grid_body;           // the bodies with a valid grid
    std::vector<double> grid_box;                   // per grid: x0, y0, x1, y1, cell size
    std::vector<double> grid_x, grid_y;             // per grid: its built_x, built_y, in order
    DiskContactStatistics statistics;
  };
  State state() const;
  // Continues from `state` once the model's state was restored. Throws std::invalid_argument
  // when `state` is not of this model.
  void restore(const fem::Model &model, const State &state);
};

} // namespace mesopen::coupling
