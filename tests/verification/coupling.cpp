// FE-DEM coupling without LIGGGHTS (the fake DEM participant): the exchanged forces balance, a
// disk hitting an FE block conserves momentum, and every declared exchange happens each window.
#include "coupling.hpp"
#include "fake_dem.hpp"
#include "coupled.hpp"
#include "meshes.hpp"
#include "solver.hpp"

#include <gtest/gtest.h>

#include <cmath>

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

// A disk hits a free elastic block at 100 m/s, obliquely and spinning, with friction: the total
// momentum of block and disk stays what it was, to round-off (1e-12 of m v: the forces balance at
// every step, and both solvers kick by the same forces over the same windows); the disk bounces
// back, every exchange happens in every window, and the overlap stays a small fraction of the
// block's elements.
TEST(Coupling, DiskHittingABlockConservesMomentum) {
  fem::Model model = block();
  fem::setBodyVelocity(model, 0, 0.0, 0.0); // awake: the step is the block's stable step
  coupling::FakeDem dem(disks({{40e-6, 62e-6, 20.0, -100.0, 3e5, 10e-6}}), {});
  coupling::FeDemCoupling coupling(model, dem, {.friction = {0.3}});
  fem::Solver solver(model, {});
  solver.addForceProvider(&coupling);
  auto momentum = [&] { return test::totalMomentum(model, dem.particles()); };
  const auto p0 = momentum();
  const double e0 = dem.particles().kineticEnergy();
  const double scale = dem.particles().mass[0] * 100.0;
  double worst = 0.0;
  bool touched = false;
  while (solver.time() < 0.4e-6) {
    solver.step();
    const auto p = momentum();
    worst = std::max({worst, std::abs(p[0] - p0[0]), std::abs(p[1] - p0[1])});
    touched |= coupling.contact().statistics().contacts > 0;
  }
  const coupling::Particles &d = dem.particles();
  // Energy: the contact's damping and friction dissipate, nothing is created.
  const double e1 = dem.particles().kineticEnergy() + solver.energy().kinetic + solver.energy().internal;
  std::printf("disk on block: momentum error %.2e of m v, disk vy %.2f m/s after -100, energy "
              "after / before %.4f, deepest %.4f elements, %llu windows\n",
              worst / scale, d.vy[0], e1 / e0, coupling.contact().statistics().deepest,
              static_cast<unsigned long long>(coupling.windows()));
  EXPECT_LT(e1, e0);
  EXPECT_GT(e1, 0.1 * e0);
  EXPECT_TRUE(touched);
  EXPECT_GT(d.vy[0], 0.0); // bounced
  EXPECT_LT(worst, 1e-12 * scale);
  EXPECT_LT(coupling.contact().statistics().deepest, 0.1);
  EXPECT_EQ(coupling.windows(), solver.steps());
  for (const coupling::Data &data : coupling.data())
    EXPECT_EQ(data.window, coupling.windows()) << data.name;
}

// A participant that does not call the exchange: the coupling says which data was missed.
TEST(Coupling, MissedExchangeIsAnError) {
  struct Silent : coupling::DemParticipant {
    coupling::Particles p = disks({{0.0, 1.0, 0.0, 0.0, 0.0, 1e-6}});
    const coupling::Particles &particles() const override { return p; }
    double stableStep() const override { return INFINITY; }
    void advance(double, const Exchange &) override {}
  } silent;
  fem::Model model = block();
  coupling::FeDemCoupling coupling(model, silent, {.friction = {0.3}});
  fem::Solver solver(model, {});
  solver.addForceProvider(&coupling);
  try {
    solver.step();
    FAIL() << "no error";
  } catch (const fem::RunFailure &e) {
    EXPECT_NE(std::string(e.what()).find("Particle-State"), std::string::npos) << e.what();
  }
}
