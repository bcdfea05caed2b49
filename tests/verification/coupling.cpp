// FE-DEM coupling without LIGGGHTS (the fake DEM participant): the exchanged forces balance, a
// disk hitting an FE block conserves momentum, every declared exchange happens each window, and
// with levels a body falls to the base step before a disk touches it.
#include "coupling.hpp"
#include "coupled.hpp"
#include "fake_dem.hpp"
#include "meshes.hpp"
#include "solver.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <omp.h>

using namespace mesopen;
using test::TestMesh;

namespace {

// A disk of quartz (2650 kg/m^3) of radius r at (x, y) with velocity (vx, vy) and spin.
coupling::Particles disks(std::initializer_list<std::array<double, 6>> list) {
  coupling::Particles p;
  for (const auto &[x, y, vx, vy, omega, r] : list) {
    p.x.push_back(x), p.y.push_back(y), p.vx.push_back(vx), p.vy.push_back(vy);
    p.omega.push_back(omega), p.radius.push_back(r), p.mass.push_back(2650.0 * M_PI * r * r);
  }
  return p;
}

// A block of 100 x 50 um of quartz, its lower-left corner at the origin.
fem::Model block() {
  TestMesh mesh;
  mesh.addRectangle(0.0, 0.0, 100e-6, 50e-6, 10, 5, 0.2, 7);
  return mesh.model(test::oneMaterial("quartz"));
}

} // namespace

// Disks pressed into the block's top and sides at several angles, moving and spinning: the forces
// on the disks and the reactions on the nodes sum to zero. Tolerance: round-off of the weights
// (1 - w) + w = 1, relative to the largest force (1e-14).
TEST(Coupling, ExchangedForcesBalance) {
  fem::Model model = block();
  const coupling::Particles p = disks({{30e-6, 58e-6, 1.0, -20.0, 1e5, 10e-6},
                                       {70e-6, 59e-6, -3.0, -5.0, -2e5, 10e-6},
                                       {-4e-6, 20e-6, 30.0, 2.0, 0.0, 6e-6},
                                       {104e-6, 54e-6, -10.0, -10.0, 3e4, 8e-6}, // at a corner
                                       {50e-6, 200e-6, 0.0, 0.0, 0.0, 10e-6}});  // far
  coupling::DiskContact contact(model, {.friction = {0.3}});
  coupling::ParticleForces f;
  f.reset(p.size());
  model.nodes.clearExternal();
  std::vector<coupling::Reaction> reactions;
  contact.addForces(model, p, f, reactions, 1e-9);
  coupling::DiskContact::apply(model, reactions);
  EXPECT_EQ(contact.statistics().contacts, 4u);
  double sx = 0.0, sy = 0.0, largest = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i)
    sx += f.fx[i], sy += f.fy[i], largest = std::max(largest, std::hypot(f.fx[i], f.fy[i]));
  EXPECT_EQ(f.fx[4], 0.0);
  for (const std::uint32_t a : model.nodes.loaded)
    sx += model.nodes.external[a].fx, sy += model.nodes.external[a].fy;
  EXPECT_GT(largest, 0.0);
  EXPECT_LT(std::hypot(sx, sy), 1e-14 * largest);
  // pushed away from the block: up at the top, left on the left side
  EXPECT_GT(f.fy[0], 0.0);
  EXPECT_LT(f.fx[2], 0.0);
  std::printf("forces on 4 disks: largest %.3e N/m, sum with the reactions %.2e N/m\n", largest,
              std::hypot(sx, sy));
}

// A disk hits a free elastic block at 100 m/s, obliquely and spinning, with friction, in windows
// of one FE step and of about ten (multiple time stepping): the total momentum of block and disk
// stays what it was, to round-off (1e-12 of m v: the forces balance at every step, and both
// solvers kick by the same forces over the same steps); the disk bounces back, and the overlap
// stays a small fraction of the block's elements. Without forces of its own (no disk-disk or
// wall contact) a disk's motion is the same in long windows as in windows of one step: to 1e-9 of
// the speed (round-off, summed in another order).
// The ledger of a window's exchanges: a window with each datum exchanged as declared (the state
// and the motion once, the reactions every FE step) passes; one that missed the motion, or that
// took fewer reactions than steps, ends with an error naming the datum.
TEST(Coupling, ExchangeLedgerChecksEveryWindow) {
  using coupling::Datum;
  coupling::ExchangeLedger ledger;
  auto window = [&](std::uint64_t w, bool motion, int reactions) {
    ledger.record(Datum::particle_state, w);
    for (int s = 0; s < reactions; ++s)
      ledger.record(Datum::reaction_force, w);
    if (motion)
      ledger.record(Datum::particle_motion, w);
  };
  window(1, true, 3);
  EXPECT_NO_THROW(ledger.checkWindow(1, 3));
  window(2, false, 3);
  try {
    ledger.checkWindow(2, 3);
    ADD_FAILURE() << "a window without Particle-Motion passed";
  } catch (const std::logic_error &e) {
    EXPECT_NE(std::string(e.what()).find("Particle-Motion"), std::string::npos) << e.what();
  }
  window(3, true, 2);
  EXPECT_THROW(ledger.checkWindow(3, 3), std::logic_error); // a step without its reactions
}

TEST(Coupling, DiskHittingABlockConservesMomentum) {
  auto run = [](double window, std::uint64_t &windows, std::uint64_t &steps) {
    fem::Model model = block();
    fem::setBodyVelocity(model, 0, 0.0, 0.0); // awake: the step is the block's stable step
    coupling::FakeDem dem(disks({{40e-6, 62e-6, 20.0, -100.0, 3e5, 10e-6}}), {});
    coupling::FeDemCoupling coupling(model, dem, {.friction = {0.3}}, window);
    fem::Solver solver(model, {});
    solver.addForceProvider(&coupling);
    auto momentum = [&] { return test::totalMomentum(model, coupling.disks()); };
    const auto p0 = momentum();
    const double e0 = coupling.disks().kineticEnergy();
    const double scale = dem.particles().mass[0] * 100.0;
    double worst = 0.0;
    bool touched = false;
    while (solver.time() < 0.4e-6) {
      solver.step();
      const auto p = momentum();
      worst = std::max({worst, std::abs(p[0] - p0[0]), std::abs(p[1] - p0[1])});
      touched |= coupling.contact().statistics().contacts > 0;
    }
    const coupling::Particles d = coupling.disks();
    // Energy: the contact's damping and friction dissipate, nothing is created.
    const double e1 = d.kineticEnergy() + solver.energy().kinetic + solver.energy().internal;
    std::printf("disk on block, window %.3g s: momentum error %.2e of m v, disk v (%.6f, %.6f) "
                "m/s after (20, -100), energy after / before %.4f, deepest %.4f elements, %llu "
                "windows of %llu steps\n",
                window, worst / scale, d.vx[0], d.vy[0], e1 / e0,
                coupling.contact().statistics().deepest,
                static_cast<unsigned long long>(coupling.windows()),
                static_cast<unsigned long long>(solver.steps()));
    EXPECT_LT(e1, e0);
    EXPECT_GT(e1, 0.1 * e0);
    EXPECT_TRUE(touched);
    EXPECT_GT(d.vy[0], 0.0); // bounced
    EXPECT_LT(worst, 1e-12 * scale);
    EXPECT_LT(coupling.contact().statistics().deepest, 0.1);
    // Every datum exchanged in the last window ended (each window's are checked as it ends).
    for (auto datum : {coupling::Datum::particle_state, coupling::Datum::particle_motion,
                       coupling::Datum::reaction_force})
      EXPECT_GE(coupling.exchanges().lastWindow(datum), coupling.windows());
    windows = coupling.windows(), steps = solver.steps();
    return std::array<double, 3>{d.vx[0], d.vy[0], d.omega[0]};
  };
  std::uint64_t windows = 0, steps = 0;
  const auto each = run(0.0, windows, steps); // without forces of its own: every step a window
  EXPECT_EQ(windows, steps);
  const auto ten = run(15e-9, windows, steps);
  EXPECT_LT(windows, steps / 5);
  for (int k = 0; k < 2; ++k)
    EXPECT_NEAR(ten[k], each[k], 1e-9 * 100.0);
  EXPECT_NEAR(ten[2], each[2], 1e-9 * std::abs(each[2]));
}

// Two disks in line fall on a free block at 50 m/s, the lower one touching the block, the upper
// one a gap above: disk-disk contact (the participant's own, slow force) and FE-DEM contact (fast)
// both act. Windows of the participant's stable step (a tenth of the disk-disk contact time,
// 5 FE steps) against windows of one FE step: momentum kept to round-off in both (walls and
// gravity off), and the disks leave alike, within 1 % of the impact speed (the disk-disk contact
// resolved by ten steps instead of sixty: 0.15 and 0.16 m/s apart, 0.3 %; at twice the window
// 3.1 m/s, at half of it 0.06 m/s).
TEST(Coupling, MultipleTimeSteppingFollowsTheStepByStepRun) {
  auto run = [](bool each_step, std::uint64_t &windows, std::uint64_t &steps) {
    fem::Model model = block();
    fem::setBodyVelocity(model, 0, 0.0, 0.0);
    coupling::FakeDem dem(
        disks({{50e-6, 60.05e-6, 0.0, -50.0, 0.0, 10e-6}, {50e-6, 81e-6, 0.0, -50.0, 0.0, 10e-6}}),
        {.stiffness = 3.35e10, .restitution = 0.9});
    coupling::FeDemCoupling coupling(model, dem, {.friction = {0.3}}, each_step ? 1e-30 : 0.0);
    fem::Solver solver(model, {});
    solver.addForceProvider(&coupling);
    auto momentum = [&] { return test::totalMomentum(model, coupling.disks()); };
    const auto p0 = momentum();
    const double scale = dem.particles().mass[0] * 50.0;
    double worst = 0.0;
    while (solver.time() < 0.3e-6) {
      solver.step();
      const auto p = momentum();
      worst = std::max({worst, std::abs(p[0] - p0[0]), std::abs(p[1] - p0[1])});
    }
    EXPECT_LT(worst, 1e-12 * scale);
    windows = coupling.windows(), steps = solver.steps();
    const coupling::Particles d = coupling.disks();
    std::printf("two disks on a block, %s: momentum error %.2e of m v, disks leave at %.4f and "
                "%.4f m/s, %llu windows of %llu steps (window %.3g s)\n",
                each_step ? "a window each FE step" : "windows of the DEM step", worst / scale,
                d.vy[0], d.vy[1], static_cast<unsigned long long>(windows),
                static_cast<unsigned long long>(steps), coupling.window());
    return std::array<double, 2>{d.vy[0], d.vy[1]};
  };
  std::uint64_t windows = 0, steps = 0;
  const auto each = run(true, windows, steps);
  EXPECT_EQ(windows, steps);
  const auto respa = run(false, windows, steps);
  EXPECT_LT(windows, steps / 3);
  EXPECT_GT(each[1], 0.0); // the upper disk bounced off the lower one
  for (int k = 0; k < 2; ++k)
    EXPECT_NEAR(respa[k], each[k], 0.01 * 50.0) << "disk " << k;
}

// A disk found a third of an element deep in a free block at once, at rest, as when erosion lays a
// boundary bare over it: pushed out in one step it would leave at about kappa d / dt (some 10 km/s
// here); the excess depth is allowed for and let go over 200 steps, so it leaves at about
// d / (200 dt). Bound: the disk slower than d / (20 dt); momentum kept to round-off; the overlap
// opened within 400 steps.
TEST(Coupling, SuddenDeepDiskOpensGently) {
  fem::Model model = block();
  fem::setBodyVelocity(model, 0, 0.0, 1e-3); // awake
  const double overlap = 3e-6;               // a third of the block's 10 um elements
  coupling::FakeDem dem(disks({{50e-6, 60e-6 - overlap, 0.0, 0.0, 0.0, 10e-6}}), {});
  coupling::FeDemCoupling coupling(model, dem, {.friction = {0.3}});
  fem::Solver solver(model, {});
  solver.addForceProvider(&coupling);
  const auto p0 = test::totalMomentum(model, coupling.disks());
  const double mass = dem.particles().mass[0];
  double fastest = 0.0, worst = 0.0, dt = HUGE_VAL;
  for (int step = 0; step < 400; ++step) {
    dt = std::min(dt, solver.dt());
    solver.step();
    const coupling::Particles d = coupling.disks();
    fastest = std::max(fastest, std::hypot(d.vx[0], d.vy[0]));
    const auto p = test::totalMomentum(model, d);
    worst = std::max({worst, std::abs(p[0] - p0[0]), std::abs(p[1] - p0[1])});
  }
  const double one_step = overlap / dt;
  std::printf(
      "disk %.2f elements deep at once: %zu sudden contacts, fastest %.3g m/s (d / dt = %.3g "
      "m/s), contacts at the end %zu, momentum %.2e of m d / dt\n",
      overlap / 10e-6, coupling.contact().statistics().sudden, fastest, one_step,
      coupling.contact().statistics().contacts, worst / (mass * one_step));
  EXPECT_GT(coupling.contact().statistics().sudden, 0u);
  EXPECT_LT(fastest, one_step / 20.0);
  EXPECT_EQ(coupling.contact().statistics().contacts, 0u);
  EXPECT_LT(worst, 1e-12 * mass * one_step);
}

// A disk pressed into the block a little deeper each step (within what approach can make) moves to
// another process, as LIGGGHTS moves disks between ranks: the depth it was pushed at goes with it
// (takeHeld, putHeld), and the other process's contact gives the force the first would have given,
// to the bit. Without it the other process would find the disk deeper than a step's approach can
// make it, allow for the depth as sudden and push far less.
TEST(Coupling, DiskMovedToAnotherProcessKeepsItsContactHistory) {
  const fem::Model model = block();
  auto pressed = [](int step) { // 0.04 um deeper a step, at rest
    coupling::Particles p = disks({{50e-6, 60e-6 - 0.04e-6 * step, 0.0, 0.0, 0.0, 10e-6}});
    p.id = {7};
    return p;
  };
  auto push = [&](coupling::DiskContact &contact, int step) {
    coupling::ParticleForces f;
    f.reset(1);
    std::vector<coupling::Reaction> reactions;
    contact.addForces(model, pressed(step), f, reactions, 1e-9);
    return f.fy[0];
  };
  coupling::DiskContact first(model, {.friction = {0.3}}), going(model, {.friction = {0.3}});
  for (int step = 1; step <= 10; ++step)
    EXPECT_EQ(push(first, step), push(going, step));
  coupling::DiskContact other(model, {.friction = {0.3}}), fresh(model, {.friction = {0.3}});
  const std::vector<std::int64_t> moved = going.takeHeld([](std::int64_t) { return false; });
  EXPECT_EQ(moved.size(), 5u);
  EXPECT_TRUE(going.takeHeld([](std::int64_t) { return false; }).empty());
  other.putHeld(moved, [](std::int64_t id) { return id == 7; });
  const double staying = push(first, 11), carried = push(other, 11), lost = push(fresh, 11);
  std::printf("force after the move: %.6e N/m staying, %.6e carried, %.6e without the history\n",
              staying, carried, lost);
  EXPECT_GT(staying, 0.0);
  EXPECT_EQ(carried, staying);
  EXPECT_EQ(other.statistics().sudden, 0u);
  EXPECT_GT(fresh.statistics().sudden, 0u);
  EXPECT_LT(lost, 0.5 * staying);
}

namespace {
// A coarse block (cells of 20 um) a disk hits at 100 m/s, obliquely and spinning, beside a fine
// block far away (cells of 2.5 um) that sets the base step: with levels (max_level 2) the coarse
// block steps every fourth base step until the disk comes near.
struct LevelsHit {
  std::array<double, 3> disk{}; // vx, vy, omega after the hit
  double worst_momentum = 0.0;  // over every base step [kg m/s per m]
  double element_steps = 0.0, single_rate = 0.0;
  int coarse_level_before = -1;   // the coarse block's level when the disk was still far
  int coarse_level_at_touch = -1; // its level at the first step the disk touched it
  std::size_t touching_steps = 0, not_due = 0;
  double deepest = 0.0, energy_ratio = 0.0;
};

LevelsHit levelsHit(int max_level, int threads) {
  omp_set_num_threads(threads);
  TestMesh mesh;
  mesh.addRectangle(0.0, 0.0, 100e-6, 60e-6, 5, 3, 0.1, 3);
  mesh.addRectangle(300e-6, 0.0, 10e-6, 5e-6, 4, 2, 0.1, 5);
  fem::Model model = mesh.model(test::oneMaterial("quartz"));
  fem::setBodyVelocity(model, 0, 0.0, 0.0); // awake
  fem::setBodyVelocity(model, 1, 0.0, 0.0);
  coupling::FakeDem dem(disks({{40e-6, 72.5e-6, 20.0, -100.0, 3e5, 10e-6}}), {});
  coupling::FeDemCoupling coupling(model, dem, {.friction = {0.3, 0.3}}, 0.0);
  fem::Solver solver(model, {.max_level = max_level});
  solver.addForceProvider(&coupling);
  const double e0 = coupling.disks().kineticEnergy();
  const auto p0 = test::totalMomentum(model, coupling.disks());
  LevelsHit hit;
  while (solver.time() < 0.4e-6) {
    solver.step();
    const auto p = test::totalMomentum(model, coupling.disks());
    hit.worst_momentum =
        std::max({hit.worst_momentum, std::abs(p[0] - p0[0]), std::abs(p[1] - p0[1])});
    const int level = model.level.empty() ? 0 : model.level[0];
    if (coupling.contact().statistics().contacts > 0) {
      if (hit.touching_steps++ == 0)
        hit.coarse_level_at_touch = level;
    } else if (hit.touching_steps == 0 && solver.steps() == 40) {
      hit.coarse_level_before = level;
    }
  }
  const coupling::Particles d = coupling.disks();
  hit.disk = {d.vx[0], d.vy[0], d.omega[0]};
  hit.element_steps = solver.elementSteps(), hit.single_rate = solver.singleRateElementSteps();
  hit.not_due = coupling.contact().statistics().not_due;
  hit.deepest = coupling.contact().statistics().deepest;
  hit.energy_ratio = (d.kineticEnergy() + solver.energy().kinetic + solver.energy().internal) / e0;
  return hit;
}
} // namespace

// Multiple time stepping with disks: the coarse block steps at level 2 while the disk is far, and
// falls to level 0 before the disk touches it (FeDemCoupling::capLevels), so that no disk is ever
// found touching it between its steps (the FE-DEM contact is computed at the base step). Momentum
// kept to round-off at every base step (1e-12 of m v, as DiskHittingABlockConservesMomentum); the
// disk bounces, energy only lost; the disk leaves as at a single rate to 1e-3 of its speed (the
// block's vibration before the hit is integrated over longer steps); the run is the same for one
// and two threads.
TEST(Coupling, LevelsFallBeforeADiskArrives) {
  const LevelsHit single = levelsHit(0, 1);
  const LevelsHit levels = levelsHit(2, 1);
  const double scale = 2650.0 * M_PI * 10e-6 * 10e-6 * 100.0;
  std::printf("disk on a coarse block with levels: level %d when far, %d at the touch, %zu steps "
              "touching, %zu between its steps, element updates %.3f of single rate, momentum "
              "%.2e of m v, deepest %.4f elements (single rate %.4f), energy after / before "
              "%.4f (%.4f), disk leaves at (%.4f, %.4f) m/s against (%.4f, %.4f)\n",
              levels.coarse_level_before, levels.coarse_level_at_touch, levels.touching_steps,
              levels.not_due, levels.element_steps / levels.single_rate,
              levels.worst_momentum / scale, levels.deepest, single.deepest, levels.energy_ratio,
              single.energy_ratio, levels.disk[0], levels.disk[1], single.disk[0], single.disk[1]);
  EXPECT_EQ(single.element_steps, single.single_rate);
  EXPECT_EQ(levels.coarse_level_before, 2);
  EXPECT_EQ(levels.coarse_level_at_touch, 0);
  EXPECT_GT(levels.touching_steps, 4u);
  EXPECT_EQ(levels.not_due, 0u);
  EXPECT_LT(levels.element_steps, 0.6 * levels.single_rate);
  EXPECT_LT(levels.worst_momentum, 1e-12 * scale);
  EXPECT_GT(levels.disk[1], 0.0); // bounced
  EXPECT_LT(levels.energy_ratio, 1.0);
  EXPECT_LT(levels.deepest, 1.5 * single.deepest);
  for (int k = 0; k < 2; ++k)
    EXPECT_NEAR(levels.disk[k], single.disk[k], 1e-3 * 100.0) << k;
  const LevelsHit two = levelsHit(2, 2);
  EXPECT_EQ(two.disk, levels.disk);
  omp_set_num_threads(omp_get_num_procs());
}
