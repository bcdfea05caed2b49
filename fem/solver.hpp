// The explicit time integration (thesis section 3): central difference in its velocity form,
//   v(n+1/2) = v(n) + dt/2 f(n)/m,   x(n+1) = x(n) + dt v(n+1/2),
//   f(n+1) = internal(x(n+1), v(n+1/2)) + external,   v(n+1) = v(n+1/2) + dt/2 f(n+1)/m,
// with a stable step recomputed every step from each element's size and current sound speed,
// Wilkins artificial viscosity in compression, and the energy of every kind accounted.
#pragma once

#include "communicator.hpp"
#include "model.hpp"
#include "partitioner.hpp"
#include "threads.hpp"

#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace mesopen::fem {

// The defaults are also a scene's ([run] in run/scene.hpp takes them from here).
struct SolverSettings {
  double safety = 0.9;              // dt = safety * the smallest element's stable step
  double viscosity_linear = 0.5;    // C_L (thesis Table 3.1)
  double viscosity_quadratic = 4.0; // C_Q (thesis Table 3.1)
  // Averaged nodal volume in bodies with plastic flow (against volumetric locking); off by
  // default: under a penetrator it lets crushed elements collapse (docs/solver.md).
  bool anti_locking = false;
  double max_dt = std::numeric_limits<double>::infinity();
  // The step may grow by at most this factor at a rise (it falls at once; dt_rise_interval). A
  // penalty tied to the step (contact, k ~ m / dt^2) otherwise changes its stiffness tenfold
  // between steps when a crushed element makes the stable step oscillate, and puts energy in.
  double max_dt_growth = 1.1;
  std::size_t dt_rise_interval = 50; // the step rises at most once in so many steps (Solver::step)
  // A stable step below this fraction of the first ends the run (RunFailure naming the thinnest
  // element): an element drawn into a sliver would otherwise stall it (0: never).
  double min_dt_ratio = 1e-3;
  // An element whose stable step falls below this fraction of the shortest element step at the
  // start is eroded (a collapsed element, a sliver a grain corner drew out: the time-step erosion
  // of explicit codes, e.g. LS-DYNA's DTMIN with ERODE); 0: never. The thesis runs that finish
  // without it go no lower than 0.038 (docs/solver.md).
  double erode_step_ratio = 0.01;
  // Selective mass scaling (LS-DYNA's DT2MS < 0): an element whose stable step falls below this
  // fraction of the shortest element step at the start gets mass on its nodes, enough to bring its
  // step back to that fraction; the mass is not taken back, and the nodes keep their momentum
  // (the kinetic energy this takes is booked, Energy::mass_scaling). 0: never.
  double mass_scaling_step_ratio = 0.0;
  double gravity_x = 0.0, gravity_y = 0.0; // body force per unit mass [m/s^2]
  // With the element work shared by several processes: the bodies are partitioned anew when the
  // load imbalance (the most loaded process's active elements over the least the partition could
  // give, see Solver::balanceLoad) passes this fraction, and also before every rebalance_every-th
  // step when that is not 0 (to exercise a change of owners in tests).
  double rebalance_imbalance = 0.1;
  std::size_t rebalance_every = 0;
  std::size_t chunk = 256; // elements per material batch
  // Multiple time stepping by body (docs/solver.md, "Multiple time stepping"): the largest level.
  // A body at level l steps every 2^l base steps (the base step is the shortest body's), within
  // its own stable step and at most level_gap levels coarser than the bodies it may meet; 0: every
  // body every step.
  int max_level = 0;
  // With levels: a body steps at most this many levels coarser than the own level of a body it may
  // meet (0: no coarser). A pair of bodies on different levels is computed at the coarser body's
  // steps, its penalty softer by the square of the windows' ratio: most of the grains beside a
  // grain with one thin element step at the coarser level, but contacts go deeper
  // (docs/solver.md, "The level gap").
  int level_gap = 1;
};

// Energies per metre of depth [J/m]. Internal includes the plastic and viscous work done.
// Friction is the energy the frictional forces took out (minus their work), contact the energy the
// normal contact forces took out (held in the penalty springs or dissipated by their damping);
// external is the work of the imposed velocities and of gravity; eroded the internal energy the
// eroded elements took with them; mass_scaling the kinetic energy that mass added at constant
// momentum took (mass_scaling_step_ratio). The balance error is
//   (kinetic + internal + friction + contact + eroded + mass_scaling - external - initial)
//     / max(|total|, initial, |external|)
// (0 when nothing moves).
struct Energy {
  double kinetic = 0, internal = 0, plastic = 0, viscous = 0, friction = 0, contact = 0,
         external = 0, eroded = 0, mass_scaling = 0;
  double initial = 0, balance_error = 0;
};

// Something that adds external nodal forces at x(n+1) before the second half-kick (contact,
// coupling) by Nodes::addExternal, with their frictional part. It must wake every body it loads.
// `dt` is the step being taken.
class ForceProvider {
public:
  virtual ~ForceProvider() = default;
  virtual void addForces(Model &model, double time, double dt) = 0;
  // The largest stiffness it adds at a node, as a multiple kappa_n of m / dt^2 (a penalty tied to
  // the step). Central differences are stable while omega dt <= 2; with the provider's spring at a
  // node, (omega_e dt)^2 + kappa_n <= 4, so the solver scales the elements' step by
  // sqrt(1 - kappa_n / 4).
  virtual double stepStiffness() const { return 0.0; }
  // The boundaries of `bodies` changed (elements eroded): what was built from them is taken anew.
  virtual void boundaryChanged(const Model &, const std::vector<std::uint32_t> & /*bodies*/) {}
  // With several processes (Solver): `owner` (kept up to date by the solver) gives each body's
  // process. A moving body's nodes are current at its owner only: a provider computes for this
  // process's bodies, exchanges the other processes' nodes it needs itself, and sends its forces
  // on their nodes to their owners (Nodes::external is complete at a node's owner only); before
  // moving bodies change owner (bodiesMoving, every process, `owner` not yet changed, `new_owner`
  // the owners to come; their nodes' positions already at their new owner) what only their owner
  // keeps goes with them.
  virtual void shareWork(const parallel::Communicator & /*processes*/,
                         const std::vector<int> & /*owner*/) {}
  virtual void bodiesMoving(const Model &, const std::vector<std::uint32_t> & /*bodies*/,
                            const std::vector<int> & /*new_owner*/) {}
  // With the work shared, the provider's values in the step's one reduction (Solver::forces, after
  // the second half-kick), appended to `figures` (as many on every process), given `drift`, a
  // bound on how far any node this process moves can go in the next step's drift; the largest of
  // each over the processes comes back in stepReduced (every process calls it, in provider order:
  // it may make collective calls), so that the provider need not ask the others itself.
  virtual void stepFigures(const Model &, double /*drift*/,
                           std::vector<double> & /*figures*/) const {}
  virtual void stepReduced(Model &, const double * /*largest*/) {}
  // Multiple time stepping: whether it honours Model::due and Model::window, and, from each
  // body's `reach` (its own level plus the level gap: the coarsest level a body it may meet may
  // take), the least reach of the bodies each body may meet through it (`cap`, lowered only), so
  // that bodies step together, or a level gap apart at most, before they touch.
  // Every process calls capLevels, in provider order, after the step's reduction: it may make
  // collective calls. `bodiesInParts` names the bodies stepped in parts (once, when the provider
  // is added).
  virtual bool takesLevels() const { return false; }
  virtual void bodiesInParts(const std::vector<std::uint32_t> & /*bodies*/) {}
  virtual void capLevels(const Model &, const std::vector<std::uint8_t> & /*reach*/,
                         std::vector<std::uint8_t> & /*cap*/) {}
  // The same for the parts of body `body` (boxes x0, y0, x1, y1 each): the finest own level of the
  // bodies each part may meet (`cap`, one per part, lowered only).
  virtual void capParts(const std::vector<std::uint8_t> & /*own*/, std::uint32_t /*body*/,
                        const std::vector<double> & /*boxes*/,
                        std::vector<std::uint8_t> & /*cap*/) const {}
};

// With the work shared, a provider's forces wake a body at rest at its owner, who receives them,
// and at every other process after the step's reduction (ForceProvider::stepReduced): there each
// process's `woken` (the bodies at rest its forces loaded, sorted and unique; `most`, the most any
// process has, from the reduction) is all-gathered, as many from each, and every process wakes
// them all. `woken` is left empty.
void wakeEverywhere(Model &model, const parallel::Communicator &processes,
                    std::vector<std::int64_t> &woken, std::size_t most);

// A run that cannot go on (an inverted element, a step collapsed by a sliver); the message says
// which element and when.
class RunFailure : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

// How the element work is shared by the processes (Solver::partition): per rank, the bodies it
// owns, their active elements and their nodes (the active nodes it owns) now, and over this
// process's steps (not those before a checkpoint) the element-steps it computed and the
// node-steps of the nodes it owned; the imbalance
// max / mean - 1 of the active elements now and of the element-steps over the run; the partitions
// made after the first (`rebalances`, of which `forced` by rebalance_every), the bodies that
// changed owner at them, and the imbalance just before and just after the last.
struct PartitionReport {
  std::vector<std::size_t> bodies, active_elements, active_nodes;
  std::vector<double> element_steps, node_steps;
  double imbalance = 0.0, run_imbalance = 0.0;
  std::size_t rebalances = 0, forced = 0, migrated_bodies = 0;
  double last_before = 0.0, last_after = 0.0;
};

class Solver {
public:
  // `processes` share the work: each computes the elements of the bodies it owns and moves their
  // nodes; every process holds the whole model.
  // With more than one process `partitioner` says who owns which body, from the bodies' centroids
  // weighted by their active elements, at the start and whenever the load is out of balance
  // (balanceLoad); a moving body that changes owner brings its elements' state and its nodes'
  // positions, velocities and external forces to its new owner. A moving body's nodes are current
  // at its owner (the force providers exchange what they need of them); the failed elements'
  // states go to all; the stable step is the least over the processes (the step's one
  // reduction); each keeps its share of the energies (energy()). Both outlive the solver.
  Solver(Model &model, SolverSettings settings,
         const parallel::Communicator &processes = parallel::serial(),
         const parallel::Partitioner &partitioner = parallel::serialPartitioner());

  // One time step: half-kick, drift, internal and external forces, half-kick.
  void step();

  double time() const { return time_; }
  std::size_t steps() const { return steps_; }
  // The processes that share the run (one: the serial communicator).
  const parallel::Communicator &processes() const { return comm_; }
  // Values of the time loop's (a stop signal, an output failure, a checkpoint due) that go into
  // the next step's one reduction, so that the processes agree on them without a reduction of
  // their own (as many on every process); after that step, agreedInLastStep() holds the largest
  // of each that any process gave (none until given).
  void agreeInNextStep(std::vector<double> values) { agree_next_ = std::move(values); }
  const std::vector<double> &agreedInLastStep() const { return agreed_; }
  double dt() const { return dt_; } // the stable step, which step() takes short of the end
  // The steps end exactly at `time`: within 20 stable steps of it the rest is taken in equal steps,
  // so that the step changes once and by a twentieth at most, unless the whole run is shorter than
  // a step (a sudden short step makes a penalty tied to the step, k ~ m / dt^2, three times
  // stiffer, and shifts the kinetic energy the leapfrog reports, 1.7e-3 of the impact's in
  // Energy.MultiBodyImpactWithoutViscosityClosesItsBalance).
  void endAt(double time) { end_at_ = time; }
  // The run's energies. With one process, as of the last step. With several, each process holds
  // its share (its elements' and its nodes'; what every process knows, the first process), and
  // sumEnergy, which every process calls, adds the shares in rank order: energy() is the last sum.
  const Energy &energy() const { return comm_.size() > 1 ? summed_ : energy_; }
  const Energy &sumEnergy() const;
  void addForceProvider(ForceProvider *provider);
  // Elements updated in the last step (bodies at rest and eroded elements are skipped).
  std::size_t activeElements() const { return step_elements_; }
  // Over the run (this process's steps): the element updates computed (this process's, of its
  // own bodies), and those a single-rate run would have computed (the active elements of every
  // step, of every process); equal without levels on one process.
  double elementSteps() const { return element_steps_; }
  double singleRateElementSteps() const { return single_rate_element_steps_; }
  // With levels: the active elements of this process's bodies at each level now (a body in parts
  // by its parts' levels); the bodies stepped in parts and their parts.
  std::vector<std::size_t> elementsByLevel() const;
  std::size_t bodiesInParts() const { return parted_bodies_.size(); }
  std::size_t parts() const { return parts_.size(); }
  std::size_t erodedElements() const { return eroded_elements_; } // over the run
  // Of those, the ones eroded for a collapsed step (erode_step_ratio).
  std::size_t collapsedElements() const { return collapsed_elements_; }
  // Mass scaling (mass_scaling_step_ratio) over the run: the elements that took mass, and the mass
  // added [kg/m] to all bodies, or to one.
  static constexpr std::size_t all_bodies = static_cast<std::size_t>(-1);
  std::size_t massScaledElements() const { return added_mass_.size(); }
  double addedMass(std::size_t body = all_bodies) const;
  // How the element work is shared now and was over the run (every process knows every owner).
  PartitionReport partition() const;
  // The process that computes `body`'s elements and owns its nodes' external forces.
  int owner(std::size_t body) const { return owner_[body]; }

  // Each active body's own stable step (safety and the providers' scaling applied, as dt()): the
  // smallest over its elements of the exact lumped-triangle bound (criticalStepGain), measured by
  // the element pass of the next step when asked, for multiple time stepping's levels
  // (fem/levels.hpp). Infinity for a body at rest; bodyStepsAt() is the step that measured them
  // (0: never). Asking costs an eigenvalue per element in that pass; not asking, nothing.
  void measureBodySteps() { measure_body_steps_ = true; }
  const std::vector<double> &bodySteps() const { return body_step_; }
  std::size_t bodyStepsAt() const { return body_steps_at_; }

  // The element pass alone, as the time loop calls it: stresses and forces at the current
  // positions with the current velocities over a step dt (for benchmarks).
  void internalForces(double dt);
  // With the work shared, each process computes the elements and moves the nodes of its own
  // bodies; after the drift the positions and velocities of every process's are copied to all
  // (the force providers read them), but the elements' state (stress, pressure, energy, plastic
  // strain, area), the second half-kick's velocities, the forces and the external forces are
  // current at their owners only. For output, from the owners to the first process, which writes
  // them (every process calls them): the active bodies' element state and velocities (a frame),
  // and with their nodes' forces and external forces (a checkpoint).
  // (collectCheckpoint also sums the energies.)
  void collectFrame() const;
  void collectCheckpoint();

  // What the steps to come depend on beyond the model's state and the settings (a run's
  // checkpoint, run/checkpoint.hpp).
  struct State {
    double time = 0, dt = 0, next_dt = 0, shortest_allowed = 0, first_dt = 0, erode_below = 0,
           scale_below = 0, shortest_step = 0;
    std::uint64_t steps = 0, eroded_elements = 0, collapsed_elements = 0;
    Energy energy;
    // mass scaling so far: the elements given mass, in element order, and the mass of each
    std::vector<std::uint32_t> scaled_elements;
    std::vector<double> scaled_mass;
    // with several processes: each one's share of the energies (energy()), in rank order, as
    // collectCheckpoint gathered them (empty with one)
    std::vector<double> energy_shares;
    // with several processes: every body's owner, and the partition's imbalance and total load
    // when it was made (a run continued on as many processes keeps them; empty with one)
    std::vector<int> owner;
    int partition_ranks = 0;
    double partition_achieved = 0, partition_total = 0;
    // With levels (max_level > 0; empty without): per body its level, own level, shortest element
    // step, kinetic and internal energy at its last update, and the model's due, window, level and
    // own_step (Model); per level the start of its window; per element its step in its last pass;
    // per part its level, own level, shortest step and weight, per part node its force (x, y); per
    // body in parts, level 1 to max_level and node the window's start (x, then y); the element
    // updates so far, computed and at a single rate.
    struct Levels {
      std::vector<std::uint8_t> level, own_level, due, model_level;
      std::vector<double> step_min, kinetic, internal, window, own_step, level_start, element_step;
      std::vector<std::uint8_t> part_level, part_own_level;
      std::vector<double> part_step_min, part_weight, part_force, window_start;
      double element_steps = 0, single_rate_element_steps = 0;
    } levels;
  };
  State state() const;
  // Continues from `state` once the model's state was restored (nodes, elements, boundaries,
  // bodies at rest): the work ranges and the nodes' inverse masses are taken anew. Throws
  // std::invalid_argument when its levels are not of this model and these settings.
  void restore(const State &state);

private:
  struct Range {
    std::size_t begin, end;
  };
  struct Chunk : Range {
    const Material *material;
    bool averaged_volume;
    std::uint8_t level = 0; // with levels: its body's, or its part's in a body stepped in parts
    std::uint32_t part = no_part;
    static constexpr std::uint32_t no_part = ~std::uint32_t{0};
  };
  // Whole bodies: their element chunks and node ranges (no node is shared between units).
  struct Unit {
    std::size_t chunk_begin, chunk_end; // in chunks_
    std::size_t nodes_begin, nodes_end; // in unit_nodes_
    std::size_t node_lo, node_hi;       // its nodes lie in [node_lo, node_hi)
    bool averaged_volume;               // some chunk needs the nodal volumes
    bool in_parts = false;              // one body whose parts step at levels of their own
  };
  // A unit's nodes, numbered from its first node `base`: position and velocity side by side (the
  // element pass reads all four at once), the force being assembled, the nodal volume ratio J.
  struct alignas(32) NodeState {
    double x, y, vx, vy;
  };
  struct alignas(16) NodeForce {
    double x, y;
  };
  struct UnitNodes {
    const NodeState *state;
    NodeForce *force;
    double *jacobian;
    std::size_t base;
  };
  // A thread's copies of a unit's nodes (cache-resident) and the forces being assembled on them.
  struct UnitScratch {
    std::vector<NodeState> state;
    std::vector<NodeForce> force, part_force; // (part_force: a body in parts, part by part)
    std::vector<double> jacobian;
  };
  // each thread's, kept from step to step (their memory not given back and touched anew)
  std::vector<UnitScratch> thread_scratch_;
  UnitScratch &threadScratch() {
    return thread_scratch_[static_cast<std::size_t>(omp_get_thread_num())];
  }
  struct ChunkSums {
    double internal, plastic, viscous, dt_min;
    long inverted; // an inverted element, or -1
    bool eroding;  // an element failed (erosion strain, crushed, collapsed step): see erode
    std::vector<std::pair<std::uint32_t, double>> scaled; // elements and the mass they need
  };

  void updateActivity(bool may_partition = true);
  void countActive();
  void balanceLoad(bool forced, bool may_partition);
  void repartition(const std::vector<double> &load);
  double levelLoad(std::size_t b) const;
  void shareAmongThreads();
  void shareLevelsAmongThreads(std::size_t threads, const std::vector<std::size_t> &elements);
  struct KickSums {
    double gravity = 0.0, kinetic = 0.0, provider = 0.0, friction = 0.0;
  };
  void halfKick(std::size_t a, double half_dt, double fx, double fy, bool second_half, double &vx,
                double &vy, KickSums &sums) const;
  void addKickSums(const std::vector<KickSums> &sums, double half_dt);
  void kickAndDrift(double dt);
  void forces(double dt, bool kick);
  double reduceStep(double dt_min, std::int64_t inverted, std::size_t failing, std::size_t scaling,
                    bool finite, bool kick, double time);
  double nextDriftBound() const;
  double nextDriftBoundLevels() const;
  void nodalVolumes(const Unit &unit, const UnitNodes &nodes);
  void unitPass(const Unit &unit, double dt, UnitScratch &scratch);
  void storeReferenceShapes();
  void elementPass(const Chunk &chunk, double dt, const UnitNodes &nodes, ChunkSums &sums);
  void applyConstraints(double half_dt, bool second_half, std::vector<double> *late = nullptr);
  void erode();
  std::vector<double> padTo(std::vector<double> values, std::size_t count) const;
  std::vector<std::int64_t> equalParts(std::size_t count) const;
  void scaleMasses(double half_dt);
  double stepToTake(bool &last) const;
  void nextStep(double stable, std::size_t rise_interval);
  std::string thinnestElement() const;
  std::string notFinite() const; // where a state that is not finite is (RunFailure's message)
  bool owns(std::size_t body) const { return owner_[body] == comm_.rank(); }
  std::array<std::vector<double> *, 8> elementState() const;
  template <std::size_t N>
  void shareOwned(const std::vector<std::uint32_t> &bodies, std::size_t Body::*begin,
                  std::size_t Body::*end, const std::array<std::vector<double> *, N> &fields,
                  bool to_first = false) const;
  void collectExternal(const std::vector<std::uint32_t> &bodies);
  std::vector<std::vector<std::uint32_t>> byOwner(const std::vector<std::uint32_t> &bodies) const;
  void accountEnergy();
  void sumShares(const std::vector<double> &all) const;
  void bodyStepsFromElements();
  // Multiple time stepping (fem/solver_levels.cpp).
  bool levels() const { return s_.max_level > 0; }
  void stepLevels();
  void kickAndDriftLevels(int top, const double *tau);
  void forcesLevels(int top, const double *tau, double base_dt);
  void halfKickLevels(std::size_t a, double half_dt, double half_external, double fx, double fy,
                      bool second_half, double &vx, double &vy, KickSums &sums) const;
  void chooseLevels(int top);
  void shareBodySteps(int top);
  void collectLevels();
  std::size_t levelValues(std::uint32_t b) const;
  void packLevels(std::uint32_t b, double *&out) const;
  void unpackLevels(std::uint32_t b, const double *&in);
  std::size_t partedIndex(std::uint32_t b) const;
  void startLevels();
  State::Levels levelsState() const;
  void restoreLevels(const State::Levels &st);
  void bodySums(std::size_t unit_begin, std::size_t unit_end);
  void addKinetic(std::size_t node, double change);
  void startParts();
  void partsPass(const Unit &unit, int top, const double *tau, UnitScratch &scratch);
  void choosePartLevels(std::uint32_t body, int top, std::uint8_t limit);
  double nextForceWeight(std::size_t element) const;
  void nextPartForces(std::uint32_t body, int top, const std::vector<std::uint8_t> &stepped_at);

  Model &m_;
  SolverSettings s_;
  const parallel::Communicator &comm_;
  const parallel::Partitioner &partitioner_;
  // Who computes each body's elements: the partitioner's answer (all rank 0 with one process).
  std::vector<int> owner_;
  bool partitioned_ = false;      // owner_ is a partition (it starts as body b on rank b mod size)
  bool rebalance_due_ = false;    // rebalance_every: at the next updateActivity that may partition
  bool load_check_due_ = false;   // the bodies that move changed since the last that may partition
  std::size_t step_elements_ = 0; // the elements the last step updated (activeElements)
  // The last partition's imbalance (as balanceLoad measures it) and total active elements.
  double last_achieved_ = 0.0, last_total_ = 0.0;
  std::vector<std::size_t> rank_elements_; // each rank's active elements, as laid out
  std::vector<std::size_t> rank_nodes_;    // the nodes of each rank's active bodies, as laid out
  std::vector<double> rank_element_steps_, rank_node_steps_; // over the run
  PartitionReport partition_; // the counts and the last rebalance's imbalances
  std::vector<ForceProvider *> providers_;
  std::vector<Chunk> chunks_;
  std::vector<Unit> units_;
  std::vector<Range> unit_nodes_;  // node ranges of the units
  std::vector<Range> node_ranges_; // active nodes, in blocks
  std::vector<ChunkSums> sums_;
  // Each thread's units and node blocks, [bounds[t], bounds[t + 1]): contiguous, of about equal
  // element counts, fixed while the same bodies move (see shareAmongThreads).
  std::vector<std::size_t> thread_units_, thread_blocks_;
  std::vector<KickSums> kick_sums_; // per node block (first half-kick) or unit (second)
  std::vector<double> inv_mass_;
  std::vector<std::uint8_t> at_rest_seen_;   // Model::at_rest when the work ranges were laid out
  std::vector<std::uint32_t> active_bodies_; // every process's, in order
  std::size_t active_elements_ = 0, eroded_elements_ = 0, collapsed_elements_ = 0;
  double time_ = 0.0, dt_ = 0.0, next_dt_ = 0.0;
  double end_at_ = std::numeric_limits<double>::infinity();
  double step_scale_ = 1.0; // sqrt(1 - kappa_n / 4) for the providers' stiffness kappa_n
  double shortest_allowed_ = std::numeric_limits<double>::infinity(); // since the last rise
  double first_dt_ = 0.0;    // the first step (after the providers' scaling)
  double erode_below_ = 0.0; // erode_step_ratio times the shortest element step at the start
  double scale_below_ = 0.0; // mass_scaling_step_ratio times it
  std::unordered_map<std::uint32_t, double> added_mass_; // by element, what mass scaling added
  std::vector<std::uint8_t> constrained_;                // by node: 1 x imposed, 2 y imposed
  // The inverse of each total-form element's initial edge matrix [X_b - X_a, X_c - X_a] (rows x, y;
  // xx, xy, yx, yy): F = [x_b - x_a, x_c - x_a] times it. Empty when no material uses F.
  std::array<std::vector<double>, 4> reference_inverse_;
  std::vector<std::uint8_t>
      failed_; // per element: failed in this step's pass, 2 for a collapsed step
  // The shortest element step of the last element pass, before the safety factor and the
  // providers' scaling (elementPass refines the steps near it)
  double shortest_step_ = std::numeric_limits<double>::infinity();
  std::size_t steps_ = 0;
  // measureBodySteps: asked for the next pass; each element's exact step in it (of the active
  // bodies), its minimum per body, and the step that measured them.
  bool measure_body_steps_ = false;
  std::vector<double> element_step_, body_step_;
  std::size_t body_steps_at_ = 0;
  Energy energy_;                         // this process's share (see energy())
  mutable Energy summed_;                 // with several processes: every process's, as last summed
  std::vector<double> checkpoint_shares_; // every process's share, at the last collectCheckpoint
  // Work of this step: constraints and gravity; providers' forces; their frictional part.
  double kick_work_ = 0.0, provider_work_ = 0.0, friction_work_ = 0.0;
  // This process's last element pass (forces): its internal energy, plastic and viscous work; and
  // from the step's reduction the most elements that failed or asked for mass on a process, and
  // whether any process's energies are no longer finite.
  std::array<double, 3> step_sums_{};
  std::size_t most_failing_ = 0, most_scaling_ = 0; // the most on any process (0: none)
  bool not_finite_ = false;
  std::vector<double> agree_next_, agreed_; // the time loop's values in the step's reduction
  // Multiple time stepping (levels()): per body its level, the level its own step allows, its
  // shortest element step at its last update (before the safety factor), its kinetic and internal
  // energy then; per level l the time at the last step whose number is a multiple of 2^l; the
  // work ranges by level (units [level_units_[l], level_units_[l + 1]), node blocks likewise), the
  // thread and level of each unit and node block, and both in the order of their nodes
  // (shareLevelsAmongThreads); the levels the ranges were laid out for.
  std::vector<std::uint8_t> level_, own_level_, laid_levels_;
  std::vector<std::uint8_t> level_reach_, level_cap_; // chooseLevels' per body, kept
  std::vector<double> body_step_min_, body_kinetic_, body_internal_, level_start_;
  std::vector<double> level_step_; // per element: its step in its last pass
  double step_end_ = 0.0;          // the time at the end of the step being taken
  std::vector<std::size_t> level_units_, level_blocks_;
  std::vector<std::uint16_t> unit_thread_, block_thread_;
  std::vector<std::uint8_t> unit_level_, block_level_;
  std::vector<std::size_t> unit_order_, block_order_;
  // the due units and blocks of a step, listed per thread (forcesLevels, kickAndDriftLevels)
  WorkLists unit_lists_, block_lists_;
  double element_steps_ = 0.0, single_rate_element_steps_ = 0.0;
  double checkpoint_element_steps_ = 0.0; // every process's, at the last collectCheckpoint
  // Bodies stepped in parts (levels(), at least parts_from elements: the projectile): parts of
  // part_elements consecutive elements, each at a level of its own at or above its body's. Per
  // body the first of its parts (parts of b: [part_begin_[b], part_begin_[b + 1])); per part its
  // elements, level, own level, the levels laid out; per body in parts and level l > 0 its nodes'
  // positions at the last step whose number is a multiple of 2^l (window_x_[i][l], i the body's
  // place in parted_bodies_).
  struct Part {
    std::size_t element_begin, element_end;
  };
  std::vector<Part> parts_;
  std::vector<std::size_t> part_begin_;
  std::vector<std::uint8_t> part_level_, part_own_level_, laid_part_levels_;
  std::vector<double> part_step_min_; // its elements' shortest step at its last update
  std::vector<double> part_box_; // its box (x, y low, x, y high) at its last update (partsPass)
  // each part's nodes (sorted), [part_node_begin_[p], part_node_begin_[p + 1]) in part_nodes_, and
  // its force on them at its last update
  std::vector<std::size_t> part_node_begin_;
  std::vector<std::uint32_t> part_nodes_;
  std::vector<NodeForce> part_force_;
  // each part's force in the body's next first half-kick, per unit of its force (chooseLevels)
  std::vector<double> part_weight_;
  static constexpr std::size_t part_elements = 512;
  std::vector<std::uint32_t> parted_bodies_;
  std::vector<std::vector<std::vector<double>>> window_x_, window_y_;
};

} // namespace mesopen::fem
