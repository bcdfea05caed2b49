// Energy accounting: with the artificial viscosity off, an elastic body vibrating freely keeps
// kinetic + internal energy constant; with imposed velocities the external work closes the
// balance; elastic bodies ringing at their stable step, and grains meeting without viscosity, do
// not create energy; a closed elastic path returns the work it took.
#include "h5file.hpp"
#include "meshes.hpp"
#include "run.hpp"
#include "solver.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace mesopen;
using test::TestMesh;

// Free vibration of an irregularly meshed steel block started with a non-rigid velocity field.
// Central differences conserve a shadow energy; the balance error stays O(dt^2) and bounded.
// Requirement (issue 3): |balance error| <= 0.1 % over many vibration periods.
TEST(Energy, ElasticVibrationConservesEnergy) {
  TestMesh mesh;
  mesh.addRectangle(0, 0, 1e-3, 0.5e-3, 16, 8, 0.3, 5);
  fem::Model model = mesh.model(test::oneMaterial("steel-elastic"));
  for (std::size_t a = 0; a < model.nodes.size(); ++a) {
    const double x = model.nodes.x[a] / 1e-3, y = model.nodes.y[a] / 0.5e-3;
    model.nodes.vx[a] = 20.0 * std::sin(M_PI * y) * (x - 0.5);
    model.nodes.vy[a] = 30.0 * std::cos(M_PI * x) * y;
  }
  fem::Solver solver(model, {.viscosity_linear = 0.0, .viscosity_quadratic = 0.0});
  const double e0 = solver.energy().kinetic;
  double worst = 0.0, most_internal = 0.0;
  while (solver.time() < 2e-6) { // ~10 periods of the lowest modes
    solver.step();
    worst = std::max(worst, std::abs(solver.energy().balance_error));
    most_internal = std::max(most_internal, solver.energy().internal);
  }
  EXPECT_GT(most_internal, 0.3 * e0); // energy really goes back and forth
  EXPECT_LT(worst, 1e-3) << "after " << solver.steps() << " steps";
}

// Work done by a piston on a confined elastic column: kinetic + internal = external work.
TEST(Energy, ExternalWorkOfImposedVelocity) {
  TestMesh mesh;
  mesh.addRectangle(0, 0, 0.1e-3, 2e-3, 2, 40, 0.0);
  fem::Model model = mesh.model(test::oneMaterial("steel-elastic"));
  std::vector<std::uint32_t> all(model.nodes.size());
  for (std::uint32_t a = 0; a < all.size(); ++a)
    all[a] = a;
  model.constraints.push_back({"confined", all, true, false, 0.0, 0.0});
  model.constraints.push_back({"piston",
                               test::nodesWhere(model, [](double, double y) { return y < 1e-12; }),
                               false, true, 0.0, 5.0});
  fem::Solver solver(model, {.viscosity_linear = 0.0, .viscosity_quadratic = 0.0});
  double worst = 0.0;
  while (solver.time() < 0.5e-6) {
    solver.step();
    worst = std::max(worst, std::abs(solver.energy().balance_error));
  }
  EXPECT_GT(solver.energy().external, 0.0);
  EXPECT_LT(worst, 1e-3);
}

// An elastic block whose every node starts with a random velocity (up to 50 m/s each way, strain
// steps of 1 % a step), rung for 20,000 steps without viscosity: its largest |balance error| and
// the share of its energy that is internal at the end.
std::pair<double, double> ringingBlock(std::vector<std::unique_ptr<fem::Material>> material) {
  TestMesh mesh;
  mesh.addRectangle(0, 0, 100e-6, 100e-6, 10, 10, 0.3);
  fem::Model model = mesh.model(std::move(material));
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  for (std::size_t a = 0; a < model.nodes.size(); ++a)
    model.nodes.vx[a] = u(rng), model.nodes.vy[a] = u(rng);
  fem::Solver solver(model,
                     {.viscosity_linear = 0.0, .viscosity_quadratic = 0.0, .anti_locking = false});
  double worst = 0.0;
  while (solver.steps() < 20000) {
    solver.step();
    worst = std::max(worst, std::abs(solver.energy().balance_error));
  }
  return {worst, solver.energy().internal / solver.energy().kinetic};
}

// All the block's energy sits in the modes at the stable step, where a rate-form deviator, or a
// step that follows the elements up and down, pumps energy in (the balance reached 0.065 in 8,000
// steps, and 500 m/s inverted an element). With the neo-Hookean deviator and the step rising only
// every 50 steps the leapfrog keeps a shadow energy: the balance stays bounded, 2.7e-4 measured
// over 20,000 steps; the bound 2e-3 is far below what energy creation gives.
TEST(Energy, RingingElasticBlockCreatesNoEnergy) {
  const fem::Parameters quartz{
      {"density", 2648.5}, {"bulk_modulus", 43.19e9}, {"shear_modulus", 46.92e9}};
  const auto [worst, internal_over_kinetic] = ringingBlock(test::oneMaterial("elastic", quartz));
  EXPECT_GT(internal_over_kinetic, 0.3);
  EXPECT_LT(worst, 2e-3);
}

// The same block of the thesis's elastic projectile steel (preset steel-elastic: Mie-Grueneisen
// pressure without tension, "von-mises" without plasticity). With the deviator in rate form the
// balance reached 0.26; with the neo-Hookean deviator 3.3e-3 is measured. The bound 1e-2 leaves
// room for the equation of state's energy update (the trapezoid rule, second order in the volume
// step: 1.1e-3 to 3.3e-3 here with or without the cut-off and the K1, K2, Gamma terms) and is far
// below what energy creation gives.
TEST(Energy, RingingElasticSteelCreatesNoEnergy) {
  const auto [worst, internal_over_kinetic] = ringingBlock(test::oneMaterial("steel-elastic"));
  EXPECT_GT(internal_over_kinetic, 0.3);
  EXPECT_LT(worst, 1e-2);
}

// One quartz element without strength (G follows the pressure: 47 GPa at rest, 71 GPa at
// J = 0.85) driven by its nodes through a closed path of F: compressed to J = 0.846, sheared by
// 0.1, expanded back, unsheared. A stored energy returns all the work it took; the rate form
// dS = 2 G(P) dev(D) dt took the shear at the high modulus and gave it back at the low one, and
// kept a residual shear stress of 9.1 GPa and -0.38 of the largest energy. Tolerance: 1e-3 of the
// largest energy on the path (5e-7 measured: the equation of state's trapezoid, second order in
// the volume step).
TEST(Energy, ClosedElasticPathReturnsItsWork) {
  TestMesh mesh;
  const double side = 10e-6;
  mesh.x = {0.0, side, 0.0}, mesh.y = {0.0, 0.0, side}, mesh.tri = {0, 1, 2};
  mesh.node_offset = {0, 3}, mesh.tri_offset = {0, 1};
  fem::Model model = mesh.model(test::oneMaterial("quartz-elastic"));
  for (std::uint32_t a = 0; a < 3; ++a)
    model.constraints.push_back({"node", {a}, true, true, 0.0, 0.0});
  // Phases: the change of (F_xx, F_xy, F_yx, F_yy), each over `span`.
  const double phases[4][4] = {{-0.08, 0.0, 0.0, -0.08},
                               {0.0, 0.1, 0.0, 0.0},
                               {0.08, 0.0, 0.0, 0.08},
                               {0.0, -0.1, 0.0, 0.0}};
  const double span = 200e-9;
  auto setPhase = [&](const double *dF) { // v = dF/dt X
    for (std::uint32_t a = 0; a < 3; ++a) {
      const double X = model.nodes.x0[a], Y = model.nodes.y0[a];
      model.constraints[a].vx = (dF[0] * X + dF[1] * Y) / span;
      model.constraints[a].vy = (dF[2] * X + dF[3] * Y) / span;
      model.nodes.vx[a] = model.constraints[a].vx, model.nodes.vy[a] = model.constraints[a].vy;
    }
  };
  setPhase(phases[0]);
  fem::Solver solver(model,
                     {.viscosity_linear = 0.0, .viscosity_quadratic = 0.0, .anti_locking = false});
  double most = 0.0, end = 0.0;
  for (const auto &dF : phases) {
    setPhase(dF);
    end += span;
    while (solver.time() < end) {
      solver.step();
      most = std::max(most, model.elements.energy[0]);
    }
  }
  const double moved = std::hypot(model.nodes.x[1] - side, model.nodes.y[2] - side);
  ASSERT_LT(moved, 1e-2 * side); // back where it started, to the step's overshoot
  EXPECT_GT(most, 0.0);
  EXPECT_LT(std::abs(model.elements.energy[0]), 1e-3 * most)
      << "energy " << model.elements.energy[0] << " of " << most << " J/m";
  EXPECT_LT(std::abs(model.elements.sxy[0]), 1e-2 * 0.1 * 47e9) << "a residual shear stress";
}

// The impact without viscosity below: elastic grains (quartz's K and G) and projectile, no
// friction, no contact damping, 300 m/s into a 1.5 x 1 mm target of 50-70 um grains.
const std::string impact_scene = R"([target]
width = 1.5e-3
height = 1.0e-3
diameter = [50e-6, 70e-6]
porosity = 0.30
mesh_size = 10e-6
[projectile]
length = 0.5e-3
[run]
velocity = 300.0
end_time = 3e-6
end_depth = 100.0
viscosity_linear = 0.0
viscosity_quadratic = 0.0
frame_interval = 1e-6
[contact]
friction = 0.0
projectile_friction = 0.0
damping = 0.0
[materials.projectile]
type = "elastic"
[materials.grains]
type = "elastic"
density = 2648.5
bulk_modulus = 43.19e9
shear_modulus = 46.92e9
)";

// `scene` run to its end: the time it reached and its largest |balance error|.
std::pair<double, double> impact(const std::string &name, const std::string &scene) {
  test::ScratchDir dir(name);
  const auto r = test::runScene(dir, scene);
  EXPECT_EQ(r.code, 0) << r.output;
  if (r.code != 0)
    return {0.0, HUGE_VAL};
  H5File h5 = H5File::open(dir / "out/run.h5");
  const auto balance = h5.read<double>("/series/energy/balance_error");
  double worst = 0.0;
  for (double b : balance)
    worst = std::max(worst, std::abs(b));
  return {h5.read<double>("/series/time").back(), worst};
}

// Grains and projectile elastic (the issue's case: quartz constants, no viscosity, no friction,
// no contact damping), 300 m/s into a 1.5 x 1 mm target of 50-70 um grains for 3 us: the balance
// stays within 1e-3 of the initial kinetic energy (5.0e-4 measured; it reached 0.14 at 0.54 us,
// with an inverted element, when the elements created energy).
TEST(Energy, MultiBodyImpactWithoutViscosityClosesItsBalance) {
  const auto [end, worst] = impact("energy-impact", impact_scene);
  EXPECT_EQ(end, 3e-6);
  EXPECT_LT(worst, 1e-3);
}

// The same impact with the thesis's elastic quartz (preset quartz-elastic: Mie-Grueneisen pressure,
// G(J) and the pressure p_G it adds), to 0.3 us: an element inverted at 0.049 us when the stable
// step did not count the stiffness G(J) adds (J G'' (tr b* - 3) / 2 in volume, |G'| |dev b*|
// coupling volume and shear). Balance within 1e-3 (2.1e-4 measured at 0.2 us, 5.8e-4 at 3 us).
TEST(Energy, ElasticQuartzImpactWithoutViscosity) {
  std::string scene = impact_scene;
  scene.replace(scene.find("end_time = 3e-6"), 15, "end_time = 3e-7");
  scene = scene.substr(0, scene.find("[materials.grains]")) +
          "[materials.grains]\npreset = \"quartz-elastic\"\n";
  const auto [end, worst] = impact("energy-impact-quartz", scene);
  EXPECT_EQ(end, 3e-7);
  EXPECT_LT(worst, 1e-3);
}

// The issue's impact with the presets of the thesis's run 6: the elastic projectile steel
// (steel-elastic) and elastic quartz grains (quartz-elastic), without viscosity, for 3 us. With
// the projectile's deviator in rate form the balance reached 9.7e-3 (and before the grains took
// the neo-Hookean deviator an element inverted at 0.18 us); 2.1e-3 is measured. Bound 5e-3: the
// equations of state's trapezoid energy update and the undamped grain collisions leave a few
// 1e-3 that vary with the layout (1.3e-3 to 3.0e-3 over variants of the projectile's pressure).
TEST(Energy, ThesisPresetsImpactWithoutViscosity) {
  std::string scene = impact_scene;
  scene = scene.substr(0, scene.find("[materials.projectile]")) +
          "[materials.projectile]\npreset = \"steel-elastic\"\n"
          "[materials.grains]\npreset = \"quartz-elastic\"\n";
  const auto [end, worst] = impact("energy-impact-presets", scene);
  EXPECT_EQ(end, 3e-6);
  EXPECT_LT(worst, 5e-3);
}
