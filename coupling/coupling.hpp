// A coupled run in preCICE's words (participants, meshes, data, time windows): the FE participant
// (fem::Solver; its mesh the bodies' boundary nodes) and a DEM participant (its mesh the disks).
// A time window is one step of the DEM participant, of about `window` seconds (by default its
// stable step, a tenth of the contact time of its lightest disk); the FE participant takes its
// own, shorter steps within it. This is r-RESPA multiple time stepping (Tuckerman, Berne &
// Martyna 1992; DemParticipant::endWindow): the disks' own forces (disk-disk and wall contacts)
// are the slow forces, the FE bodies' forces on them the fast ones.
//   - At the window's start the disks' state is read (Particle-State: x(n), v(n) and their own
//     forces f(n)) and they take the slow half kick over the planned length P:
//     v_h = v(n) + P/2 f(n)/m.
//   - Every FE step the disks are where both forces have taken them, x(n) + t v_h + dx: dx and dv
//     are integrated by velocity Verlet on the FE steps from the FE-DEM contact forces
//     (disk_contact.hpp), the same forces whose reactions go to the FE nodes in that step. Forces
//     and reactions act over the same FE steps: momentum is kept to round-off.
//   - The FE step nearest to P ends the window: the DEM participant takes (dx, dv)
//   (Particle-Motion)
//     and its own step of the window's length D.
// Only the disks that can come within reach of an FE body during the window are moved step by
// step (the near disks): chosen at the window's start, and again whenever the FE bodies leave the
// region that choice allowed for; the others move on their slow path alone, exactly.
// A window of one FE step (`window` shorter than the FE step) is the plain velocity-Verlet
// coupling of both solvers step by step.
// Equations: docs/models.md §9.5.
#pragma once

#include "dem.hpp"
#include "disk_contact.hpp"
#include "exchange.hpp"
#include "solver.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>

namespace mesopen::coupling {

class FeDemCoupling : public fem::ForceProvider {
public:
  // window: the DEM participant's step [s]; 0: its stable step.
  FeDemCoupling(const fem::Model &model, DemParticipant &dem, DiskContactSettings settings,
                double window = 0.0);
  // One FE step within the window; ends the window if due.
  void addForces(fem::Model &model, double time, double dt) override;
  double stepStiffness() const override { return contact_.stepStiffness(); }
  void boundaryChanged(const fem::Model &model, const std::vector<std::uint32_t> &) override;
  // With the FE bodies shared among processes, each computes the FE-DEM contact of its own disks
  // (LIGGGHTS's decomposition) with the FE bodies that reach them: their owners send their
  // boundary nodes to the processes whose near disks their boxes meet, and the reactions go back
  // to the nodes' owners: messages between those processes alone, which every process knows from
  // the cells every process's disks reach and its moving bodies cover (one all-gather).
  void shareWork(const parallel::Communicator &processes, const std::vector<int> &owner) override;
  // One figure: the number of bodies at rest this process's reactions loaded in the step (each
  // woke at its owner, with the reactions); with any, every process's are all-gathered and every
  // process wakes them all.
  void stepFigures(const fem::Model &model, double drift,
                   std::vector<double> &figures) const override;
  void stepReduced(fem::Model &model, const double *largest) override;
  // Multiple time stepping: the FE-DEM contact is computed at the base step, so a body (or part) a
  // disk may reach before its next step steps at level 0. It may take level l only while the gap
  // between its box and every near disk exceeds 2^(l+1) dt v, v the fastest closing speed (the
  // fastest FE boundary node's speed plus the fastest near disk's, its spin included): a disk
  // cannot touch it within twice its window. Disks are looked for up to the largest disk's radius
  // from the box (`level_search`); one farther is taken as that far.
  // With the FE bodies shared, a body's gap is the least of the processes' own (a process whose
  // disk lies within the search of a moving body's box has the body: its marks reach that far at
  // levels), gathered in capLevels with the disks near a body in parts, whose owner caps its
  // parts; the closing speed's two maxima ride in the step's reduction (stepFigures).
  bool takesLevels() const override { return true; }
  void bodiesInParts(const std::vector<std::uint32_t> &bodies) override { in_parts_ = bodies; }
  void capLevels(const fem::Model &model, const std::vector<std::uint8_t> &reach,
                 std::vector<std::uint8_t> &cap) override;
  void capParts(const std::vector<std::uint8_t> &own, std::uint32_t body,
                const std::vector<double> &boxes, std::vector<std::uint8_t> &cap) const override;
  // Other processes' FE boundary nodes received, over the run.
  std::size_t haloNodes() const { return halo_nodes_; }
  const DiskContact &contact() const { return contact_; }
  const DemParticipant &dem() const { return dem_; }
  // The disks now, within the window: positions, velocities and spins at the FE step's end.
  Particles disks() const;
  std::uint64_t windows() const { return window_; } // ended
  double window() const { return planned_; }
  double seconds() const { return seconds_; } // in the coupling: the FE-DEM contact, the DEM steps
  const ExchangeLedger &exchanges() const { return exchanges_; }
  // A time window under way (between them the coupling's state is its State's).
  bool windowOpen() const { return open_; }

  // What the windows to come depend on beyond the model's and the disks' states, between two
  // windows (a run's checkpoint, run/checkpoint.hpp).
  struct State {
    std::uint64_t windows = 0;
    std::vector<DiskForce> carried; // the last forces of the window before, by disk id
    double seconds = 0.0;
    DiskContact::State contact;
  };
  // Throws std::logic_error within a window.
  State state() const;
  // Continues from `state` once the model's state was restored, the disks' being the
  // participant's.
  void restore(const fem::Model &model, const State &state);

private:
  // Disk i's velocity and spin after the slow half kick of its own forces over the window:
  // v_h = v(n) + P/2 f(n)/m.
  std::array<double, 3> slow(const Particles &p, std::size_t i) const {
    const double half = 0.5 * length_;
    return {p.vx[i] + half * p.fx[i] / p.mass[i], p.vy[i] + half * p.fy[i] / p.mass[i],
            p.omega[i] + half * p.torque[i] / p.inertia(i)};
  }
  void startWindow(double dt);
  void choose(const fem::Model &model, const DiskContact::Region &now, double dt);
  void endWindow();
  bool shared() const { return processes_ != nullptr && processes_->size() > 1; }
  // The cells of the FE-DEM halo's marks (exchangeBoundaries) over a region, none if it is not
  // set or has no area: nx x ny cells, in blocks of 4 x 4 (bx x by); per process `words` words
  // of cell bits, then `block_words` of block bits.
  struct MarkGrid {
    static constexpr int cells = 4096, words = cells / 64;
    DiskContact::Region r;
    bool bodies_there;
    int nx, ny, bx, by, block_words, each;
    double cw, ch;
    MarkGrid(const DiskContact::Region &region, bool set);
    int column(double x) const {
      return static_cast<int>(std::clamp(std::floor((x - r.x0) / cw), 0.0, nx - 1.0));
    }
    int row(double y) const {
      return static_cast<int>(std::clamp(std::floor((y - r.y0) / ch), 0.0, ny - 1.0));
    }
    static void set(std::int64_t *m, int c) { m[c / 64] |= std::int64_t{1} << (c % 64); }
  };
  void nearDisksNow();
  std::vector<std::int64_t> shareRegion(const fem::Model &model,
                                        const DiskContact::Region &mine) const;
  std::vector<std::int64_t> markCells(const MarkGrid &grid, const fem::Model &model) const;
  void exchangeBoundaries(fem::Model &model, const MarkGrid &grid,
                          const std::vector<std::int64_t> &all);
  void applyReactions(fem::Model &model);

  DemParticipant &dem_;
  DiskContact contact_;
  double planned_;           // the window asked for
  double length_ = 0.0;      // this one's planned length P: whole FE steps
  bool open_ = false;        // a window under way
  double elapsed_ = 0.0;     // its time so far
  std::uint64_t window_ = 0; // windows ended
  double seconds_ = 0.0;
  double r_max_ = 0.0; // the largest disk, over all ranks
  DiskContact::Region
      allowed_{}; // where the FE bodies may go before the near disks are chosen anew
  // The near disks (motion_.moved: indices into the participant's particles), their motion beyond
  // the slow path and the last FE-DEM forces on them, and their state now for the contact.
  std::vector<char> is_near_, meets_;
  std::vector<std::int64_t> place_; // per disk id: its index, -1 if not this rank's
  std::uint64_t layout_ = 0;        // the participant's layout place_ was taken at
  bool listed_ = false;
  WindowMotion motion_;            // per disk (zero but for the near ones, which it lists)
  ParticleForces fast_;            // per near disk
  Particles now_;                  // per near disk
  std::vector<DiskForce> carried_; // the last forces of the window before, by disk id
  ExchangeLedger exchanges_;       // every datum's exchanges, checked at each window's end
  std::uint64_t window_steps_ = 0; // FE steps in the window under way
  std::vector<Reaction> reactions_;
  // With the FE bodies shared among processes (shareWork): per model body, its owner, and whether
  // its nodes are current here this step (DiskContact::lookAt).
  const parallel::Communicator *processes_ = nullptr;
  const std::vector<int> *owner_ = nullptr;
  std::vector<char> current_;
  // The processes this one exchanges boundaries and reactions with in this step (ascending), and
  // the bodies at rest its reactions loaded (applyReactions, to stepReduced).
  std::vector<int> partners_;
  std::vector<std::int64_t> woken_;
  double fastest_of_all_ = 0.0; // the fastest boundary node over every process's bodies [m/s]
  DiskContact::Region region_of_all_{}; // the region every process's FE bodies cover
  // the region of the next step's marks' cells (the last region widened by twice the largest
  // disk's diameter), and whether there is one (shareRegion)
  DiskContact::Region marks_region_{};
  bool marks_set_ = false;
  std::size_t halo_nodes_ = 0;
  // With levels (Model::due not empty): the near disks now in cells of the largest disk's
  // diameter, this process's fastest FE boundary node and near disk [m/s] (closing_speed_ their
  // sum over every process) and the step [s] they were taken at, and which bodies' boxes are
  // current here (capLevels).
  void measureForLevels(const fem::Model &model, double dt);
  // visit(c, gap) for each of this process's near disks c within level_search of the box
  // [x0, x1] x [y0, y1], `gap` from the box to its surface.
  template <class Visit>
  void forDisksNear(double x0, double y0, double x1, double y1, Visit visit) const;
  // The gap from the box [x0, x1] x [y0, y1] to the nearest of this process's near disks within
  // level_search of it (infinite if none), and to those of `more` (x, y, radius each).
  double gapToDisks(double x0, double y0, double x1, double y1,
                    const std::vector<double> &more = {}) const;
  // The coarsest level up to `top` whose reach 2^(l+1) dt v stays short of `gap`.
  std::uint8_t levelClearOf(double gap, std::uint8_t top) const;
  double levelSearch() const { return r_max_; }
  CellGrid<> level_disks_;
  double closing_speed_ = 0.0, level_dt_ = 0.0, fastest_node_ = 0.0, fastest_disk_ = 0.0;
  std::vector<std::uint32_t> in_parts_;
  std::vector<char> box_current_;                // per contact body (index k)
  std::vector<std::vector<double>> parts_disks_; // per body in parts: other processes' near disks
};

} // namespace mesopen::coupling
