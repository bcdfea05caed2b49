// The finite-element model and solver pieces: model building, the stable step against the exact
// critical step of an element, the material registry, skipping bodies at rest, and the work
// split among threads.
#include "materials/hyperelastic.hpp"
#include "meshes.hpp"
#include "solver.hpp"
#include "threads.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <omp.h>
#include <random>

using namespace mesopen;
using test::TestMesh;

TEST(Model, LumpedMassesAreasAndBoundaries) {
  TestMesh mesh;
  mesh.addRectangle(0, 0, 2e-3, 1e-3, 4, 2, 0.2);
  mesh.addRectangle(3e-3, 0, 1e-3, 1e-3, 3, 3, 0.2);
  fem::Model model = mesh.model(test::oneMaterial("quartz"));
  ASSERT_EQ(model.bodies.size(), 2u);
  double mass = 0.0, area = 0.0;
  for (std::size_t a = 0; a < model.nodes.size(); ++a)
    mass += model.nodes.mass[a], area += model.nodes.area0[a];
  EXPECT_NEAR(area, 3e-6, 1e-18);
  EXPECT_NEAR(mass, 2648.5 * 3e-6, 1e-15);
  // Boundary edges: the outline of each rectangle, counter-clockwise.
  EXPECT_EQ(model.bodies[0].boundary.size(), 2u * (2 * (4 + 2)));
  EXPECT_EQ(model.bodies[1].boundary.size(), 2u * (2 * (3 + 3)));
  double signed_area = 0.0; // shoelace over the boundary edges: positive when counter-clockwise
  const auto &b = model.bodies[1].boundary;
  for (std::size_t k = 0; k < b.size(); k += 2)
    signed_area += 0.5 * (model.nodes.x[b[k]] * model.nodes.y[b[k + 1]] -
                          model.nodes.x[b[k + 1]] * model.nodes.y[b[k]]);
  EXPECT_NEAR(signed_area, 1e-6, 1e-18);
}

TEST(Model, RejectsClockwiseTriangles) {
  TestMesh mesh;
  mesh.addRectangle(0, 0, 1e-3, 1e-3, 1, 1);
  std::swap(mesh.tri[1], mesh.tri[2]);
  EXPECT_THROW(mesh.model(test::oneMaterial("steel")), std::invalid_argument);
}

// The stable step of one element (safety 1, no viscosity) must not exceed its exact critical
// step 2 / omega_max, omega_max^2 the largest eigenvalue of M^-1 K (lumped mass, plane strain),
// for any shape and for materials from nearly incompressible to nearly fluid; and it should not
// be needlessly small: it is the element's exact bound for its material.
TEST(StableStep, BoundsTheElementCriticalStep) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1e-5);
  for (auto [K, G] : {std::pair{163.9e9, 77.5e9}, {43.19e9, 46.92e9}, {100e9, 1e9}, {1e9, 1e5}}) {
    for (int trial = 0; trial < 300; ++trial) {
      TestMesh mesh;
      mesh.node_offset = {0, 3}, mesh.tri_offset = {0, 1}, mesh.tri = {0, 1, 2};
      if (trial == 0)
        mesh.x = {0, 1e-5, 0.5e-5}, mesh.y = {0, 0, 0.5e-5 * std::sqrt(3.0)};
      else
        mesh.x = {u(rng), u(rng), u(rng)}, mesh.y = {u(rng), u(rng), u(rng)};
      const double area = 0.5 * ((mesh.x[1] - mesh.x[0]) * (mesh.y[2] - mesh.y[0]) -
                                 (mesh.x[2] - mesh.x[0]) * (mesh.y[1] - mesh.y[0]));
      if (std::abs(area) < 1e-15)
        continue; // degenerate
      if (area < 0) {
        std::swap(mesh.x[1], mesh.x[2]);
        std::swap(mesh.y[1], mesh.y[2]);
      }
      const double rho = 3000.0;
      fem::Model model = mesh.model(test::oneMaterial(
          "elastic", {{"density", rho}, {"bulk_modulus", K}, {"shear_modulus", G}}));
      model.nodes.vx[0] = 1e-9; // take part in the time loop
      fem::Solver solver(model,
                         {.safety = 1.0, .viscosity_linear = 0.0, .viscosity_quadratic = 0.0});
      // Exact: K_e = A B^T C B, M = rho A / 3 I.
      const double lam = K - 2.0 * G / 3.0, A = std::abs(area);
      Eigen::Matrix3d C;
      C << lam + 2 * G, lam, 0, lam, lam + 2 * G, 0, 0, 0, G;
      Eigen::Matrix<double, 3, 6> B = Eigen::Matrix<double, 3, 6>::Zero();
      const auto &x = model.nodes.x, &y = model.nodes.y;
      for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3, k = (i + 2) % 3;
        B(0, 2 * i) = B(2, 2 * i + 1) = (y[j] - y[k]) / (2 * A);
        B(1, 2 * i + 1) = B(2, 2 * i) = (x[k] - x[j]) / (2 * A);
      }
      const Eigen::Matrix<double, 6, 6> Ke = A * B.transpose() * C * B / (rho * A / 3.0);
      const double omega = std::sqrt(
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>(Ke).eigenvalues().maxCoeff());
      const double critical = 2.0 / omega;
      // Exact: the element's own bound (see criticalStepGain) is the critical step, slivers
      // included (L / c alone is off by up to 1.5 either way); never above it beyond round-off.
      ASSERT_LE(solver.dt(), critical * (1 + 1e-9))
          << "K " << K << " G " << G << " trial " << trial;
      ASSERT_GT(solver.dt(), critical * (1 - 1e-6))
          << "K " << K << " G " << G << " trial " << trial;
    }
  }
}

// A spring tied to the step, k = kappa_n m / dt^2 at one node (the form of the contact penalty),
// on an element at its stable step. The solver scales the step by sqrt(1 - kappa_n / 4): then
// (omega dt)^2 <= (omega_e dt)^2 + kappa_n <= 4 (Weyl's inequality) and the motion stays bounded.
// The same spring undeclared (no scaling) makes it grow without bound, or invert the element.
struct StepSpring final : fem::ForceProvider {
  double kappa, declared, x0, y0;
  void addForces(fem::Model &m, double, double dt) override {
    const double k = kappa * m.nodes.mass[0] / (dt * dt);
    m.nodes.addExternal(0, -k * (m.nodes.x[0] - x0), -k * (m.nodes.y[0] - y0), 0.0, 0.0);
  }
  double stepStiffness() const override { return declared; }
};

TEST(StableStep, ScaledForAPenaltyTiedToTheStep) {
  for (double declared : {2.0, 0.0}) {
    TestMesh mesh;
    mesh.node_offset = {0, 3}, mesh.tri_offset = {0, 1}, mesh.tri = {0, 1, 2};
    mesh.x = {0, 1e-5, 0.5e-5}, mesh.y = {0, 0, 0.5e-5 * std::sqrt(3.0)};
    fem::Model model = mesh.model(test::oneMaterial("steel"));
    model.nodes.vx[1] = 1e-3, model.nodes.vy[2] = -1e-3; // small: the step stays constant
    // safety 0.95: at 1 the bound is the limit itself, where central differences grow linearly
    fem::Solver solver(model,
                       {.safety = 0.95, .viscosity_linear = 0.0, .viscosity_quadratic = 0.0});
    StepSpring spring;
    spring.kappa = 2.0, spring.declared = declared, spring.x0 = 0.0, spring.y0 = 0.0;
    solver.addForceProvider(&spring);
    // The fastest node speed over the first and the second 1000 steps: bounded means no growth
    // (near omega dt = 2 the leapfrog's velocities are several times v0, but they do not grow).
    double fastest[2] = {0.0, 0.0};
    try {
      for (int i = 0; i < 2000 && std::max(fastest[0], fastest[1]) < 1.0; ++i) {
        solver.step();
        for (std::size_t a = 0; a < 3; ++a)
          fastest[i / 1000] =
              std::max(fastest[i / 1000], std::hypot(model.nodes.vx[a], model.nodes.vy[a]));
      }
    } catch (const fem::RunFailure &) {
      fastest[1] = HUGE_VAL; // inverted
    }
    if (declared > 0.0)
      EXPECT_LT(fastest[1], 1.01 * fastest[0]) << "declared stiffness: bounded";
    else
      EXPECT_GT(std::max(fastest[0], fastest[1]), 1.0) << "undeclared: unstable (v0 1e-3)";
  }
}

// An element squashed flat: its stable step falls, and once below `min_dt_ratio` of the first
// the step ends the run with a RunFailure that names the element (not a run that stalls).
TEST(StableStep, CollapseEndsTheRunNamingTheElement) {
  TestMesh mesh;
  mesh.node_offset = {0, 3}, mesh.tri_offset = {0, 1}, mesh.tri = {0, 1, 2};
  mesh.x = {0, 1e-5, 0.5e-5}, mesh.y = {0, 0, 0.5e-5 * std::sqrt(3.0)};
  fem::Model model = mesh.model(test::oneMaterial("steel"));
  model.nodes.vy[2] = -3000.0; // the apex driven at the base
  fem::VelocityConstraint drive{"apex", {2}, true, true, 0.0, -3000.0};
  model.constraints.push_back(drive);
  fem::Solver solver(model, {.min_dt_ratio = 0.5, .erode_step_ratio = 0.0});
  std::string message;
  try {
    for (int i = 0; i < 100000; ++i)
      solver.step();
  } catch (const fem::RunFailure &e) {
    message = e.what();
  }
  EXPECT_NE(message.find("the stable step fell"), std::string::npos) << message;
  EXPECT_NE(message.find("element 0 of body"), std::string::npos) << message;
}

// The same element with time-step erosion (`erode_step_ratio` 0.5 of the first step): it leaves
// the model as its step crosses 0.5 of the first, its internal energy booked as eroded, and the
// run goes on. The balance error (not small here: the apex starts at 3000 m/s against nodes at
// rest) moves at the erosion step by no more than at the step before (the eroded energy fills
// the internal energy's place).
TEST(StableStep, CollapsedElementErodes) {
  TestMesh mesh;
  mesh.node_offset = {0, 3}, mesh.tri_offset = {0, 1}, mesh.tri = {0, 1, 2};
  mesh.x = {0, 1e-5, 0.5e-5}, mesh.y = {0, 0, 0.5e-5 * std::sqrt(3.0)};
  fem::Model model = mesh.model(test::oneMaterial("steel"));
  model.nodes.vy[2] = -3000.0;
  model.constraints.push_back({"apex", {2}, true, true, 0.0, -3000.0});
  fem::Solver solver(model, {.min_dt_ratio = 0.1, .erode_step_ratio = 0.5});
  const double first = solver.dt();
  double shortest = first, balance[3] = {0.0, 0.0, 0.0};
  for (int i = 0; i < 200 && solver.erodedElements() == 0; ++i) {
    solver.step();
    balance[0] = balance[1], balance[1] = balance[2], balance[2] = solver.energy().balance_error;
    shortest = std::min(shortest, solver.dt());
  }
  ASSERT_EQ(solver.erodedElements(), 1u);
  EXPECT_EQ(solver.collapsedElements(), 1u);
  EXPECT_EQ(model.elements.eroded[0], 1);
  EXPECT_GT(shortest, 0.45 * first) << "no step taken from the collapsed element";
  EXPECT_NE(solver.energy().eroded, 0.0);
  EXPECT_EQ(solver.energy().internal, 0.0);
  EXPECT_LE(std::abs(balance[2] - balance[1]), 2.0 * std::abs(balance[1] - balance[0]));
  for (int i = 0; i < 10; ++i)
    solver.step(); // nothing left to fail
}

// Selective mass scaling (`mass_scaling_step_ratio` 0.5): a free triangle of a soft plastic
// material (yield stress 1 MPa) whose apex is thrown along its base, the total momentum zero, is
// drawn out into a sliver (the shape that sets the step late in a penetration run). Without mass
// scaling its step falls below 0.3 of the first; with it, the step stays at 0.5 of the first (to
// round-off), and at each step that adds mass it is 0.9 (`safety`) of the element's exact critical
// step 2 / omega_max with the nodes' grown masses (elastic stiffness, no viscosity), to 1e-6: the
// mass added is what brings it there, no more. The momentum stays zero to round-off, and the
// balance, the kinetic energy the added mass took booked, closes as without mass scaling (1e-5; a
// single element).
TEST(StableStep, MassScalingHoldsTheStepAndMomentum) {
  const double rho = 7823.0, K = 163.9e9, G = 77.5e9;
  // Exact: K_e = A B^T C B on the current shape, M the nodes' masses.
  auto critical = [&](const fem::Model &model) {
    const fem::Nodes &nd = model.nodes;
    const double lam = K - 2.0 * G / 3.0, A = model.elements.area[0];
    Eigen::Matrix3d C;
    C << lam + 2 * G, lam, 0, lam, lam + 2 * G, 0, 0, 0, G;
    Eigen::Matrix<double, 3, 6> B = Eigen::Matrix<double, 3, 6>::Zero();
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3, k = (i + 2) % 3;
      B(0, 2 * i) = B(2, 2 * i + 1) = (nd.y[j] - nd.y[k]) / (2 * A);
      B(1, 2 * i + 1) = B(2, 2 * i) = (nd.x[k] - nd.x[j]) / (2 * A);
    }
    Eigen::Matrix<double, 6, 1> inv_sqrt_m;
    for (int i = 0; i < 6; ++i)
      inv_sqrt_m[i] = 1.0 / std::sqrt(nd.mass[i / 2]);
    const Eigen::Matrix<double, 6, 6> Ke =
        inv_sqrt_m.asDiagonal() * (A * B.transpose() * C * B) * inv_sqrt_m.asDiagonal();
    return 2.0 / std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>(Ke)
                               .eigenvalues()
                               .maxCoeff());
  };
  struct Result {
    double first = 0, shortest = 0, px = 0, py = 0, balance = 0, added = 0;
    double lowest_ratio = HUGE_VAL, highest_ratio = 0; // dt / critical at the steps adding mass
    fem::Energy energy;
  };
  auto drawOut = [&](double ratio) {
    TestMesh mesh;
    mesh.node_offset = {0, 3}, mesh.tri_offset = {0, 1}, mesh.tri = {0, 1, 2};
    mesh.x = {0, 1e-5, 0.5e-5}, mesh.y = {0, 0, 0.5e-5 * std::sqrt(3.0)};
    fem::Model model = mesh.model(test::oneMaterial("von-mises", {{"density", rho},
                                                                  {"bulk_modulus", K},
                                                                  {"shear_modulus", G},
                                                                  {"yield_stress", 1e6},
                                                                  {"hardening_modulus", 0.0}}));
    model.nodes.vx = {-150.0, -150.0, 300.0};
    fem::Solver solver(model, {.viscosity_linear = 0.0,
                               .viscosity_quadratic = 0.0, // undamped
                               .mass_scaling_step_ratio = ratio});
    Result r;
    r.first = r.shortest = solver.dt();
    for (int i = 0; i < 300; ++i) {
      const double added = solver.addedMass();
      solver.step();
      r.shortest = std::min(r.shortest, solver.dt());
      r.balance = std::max(r.balance, std::abs(solver.energy().balance_error));
      if (solver.addedMass() > added) {
        const double dt_over_critical = solver.dt() / critical(model);
        r.lowest_ratio = std::min(r.lowest_ratio, dt_over_critical);
        r.highest_ratio = std::max(r.highest_ratio, dt_over_critical);
      }
    }
    for (std::size_t a = 0; a < 3; ++a)
      r.px += model.nodes.mass[a] * model.nodes.vx[a],
          r.py += model.nodes.mass[a] * model.nodes.vy[a];
    r.added = solver.addedMass();
    r.energy = solver.energy();
    EXPECT_EQ(solver.massScaledElements(), r.added > 0.0 ? 1u : 0u);
    return r;
  };
  const Result without = drawOut(0.0), with = drawOut(0.5);
  const double element_mass = rho * 0.25e-10 * std::sqrt(3.0);
  std::printf("without: shortest step %.4f of the first, balance %.2e; with: %.4f, balance %.2e, "
              "added mass %.3g of the element's, mass-scaling energy %.3g of the initial, steps "
              "adding mass at %.7f-%.7f of the exact critical step\n",
              without.shortest / without.first, without.balance, with.shortest / with.first,
              with.balance, with.added / element_mass,
              with.energy.mass_scaling / with.energy.initial, with.lowest_ratio,
              with.highest_ratio);
  EXPECT_LT(without.shortest, 0.3 * without.first) << "the element is not drawn out enough";
  EXPECT_GE(with.shortest, 0.5 * with.first * (1.0 - 1e-12));
  EXPECT_GT(with.added, 0.0);
  EXPECT_GT(with.energy.mass_scaling, 0.0);
  EXPECT_LE(with.highest_ratio, 0.9 * (1.0 + 1e-6));
  EXPECT_GE(with.lowest_ratio, 0.9 * (1.0 - 1e-6));
  EXPECT_LE(std::abs(with.px) + std::abs(with.py), 1e-12 * element_mass * 300.0);
  EXPECT_LE(without.balance, 1e-5);
  EXPECT_LE(with.balance, 1e-5);
}

// The area a body's boundary encloses, by Green's theorem over its edges (holes count negative).
double enclosedArea(const fem::Model &model, std::size_t b) {
  const std::vector<std::uint32_t> &edges = model.bodies[b].boundary;
  const fem::Nodes &nd = model.nodes;
  double area = 0.0;
  for (std::size_t k = 0; k < edges.size(); k += 2)
    area += 0.5 * (nd.x[edges[k]] * nd.y[edges[k + 1]] - nd.x[edges[k + 1]] * nd.y[edges[k]]);
  return area;
}

// Eroding elements: the boundary becomes the edges of one remaining element each, in its
// counter-clockwise order (a hole's loop then runs clockwise, and the enclosed area is the
// remaining elements' exactly); the nodal reference areas lose the elements' thirds; the masses
// stay; a node left without elements is detached and no longer counts in the body's motion; the
// elements' internal energy is returned.
TEST(Erosion, BoundaryAreasAndDetachedNodes) {
  TestMesh mesh;
  mesh.addRectangle(0, 0, 3e-5, 3e-5, 3, 3, 0.2, 7);
  fem::Model model = mesh.model(test::oneMaterial("steel"));
  const fem::Nodes &nd = model.nodes;
  auto sum = [](const std::vector<double> &v) { return std::accumulate(v.begin(), v.end(), 0.0); };
  const double mass = sum(nd.mass), area = sum(model.elements.area0);
  EXPECT_EQ(model.bodies[0].boundary.size(), 2u * 12);
  model.elements.energy[8] = 1.5, model.elements.energy[9] = 2.5;
  EXPECT_DOUBLE_EQ(fem::erodeElements(model, {8, 9}), 4.0); // the middle cell: a hole
  const double hole = model.elements.area0[8] + model.elements.area0[9];
  EXPECT_EQ(model.bodies[0].boundary.size(), 2u * 16);
  EXPECT_NEAR(enclosedArea(model, 0), area - hole, 1e-12 * area);
  EXPECT_NEAR(sum(nd.area0), area - hole, 1e-12 * area);
  EXPECT_EQ(sum(nd.mass), mass);
  EXPECT_EQ(model.bodies[0].eroded, 2u);
  // Every boundary edge is an edge of exactly one remaining element, in the same direction.
  const auto &b = model.bodies[0].boundary;
  for (std::size_t k = 0; k < b.size(); k += 2) {
    int uses = 0;
    for (std::size_t e = 0; e < model.elements.size(); ++e)
      for (int i = 0; i < 3 && !model.elements.eroded[e]; ++i)
        uses += model.elements.node[3 * e + i] == b[k] &&
                model.elements.node[3 * e + (i + 1) % 3] == b[k + 1];
    EXPECT_EQ(uses, 1) << "edge " << b[k] << "-" << b[k + 1];
  }
  // The two elements at the corner node 0: it is left alone, a free mass.
  const fem::BodyMotion before = fem::bodyMotion(model, 0);
  fem::erodeElements(model, {0, 1});
  EXPECT_EQ(nd.detached[0], 1);
  EXPECT_EQ(std::accumulate(nd.detached.begin(), nd.detached.end(), 0), 1);
  EXPECT_NEAR(fem::bodyMotion(model, 0).mass, before.mass - nd.mass[0], 1e-15 * mass);
  EXPECT_NEAR(enclosedArea(model, 0), sum(nd.area0), 1e-12 * area);
}

TEST(Materials, RegistryAndPresets) {
  for (const auto &preset : fem::materialPresets())
    EXPECT_NO_THROW(fem::makeMaterial(preset.name)) << preset.name;
  EXPECT_TRUE(fem::makeMaterial("steel")->plastic());
  EXPECT_FALSE(fem::makeMaterial("steel-elastic")->plastic());
  EXPECT_FALSE(fem::makeMaterial("quartz-elastic")->plastic());
  EXPECT_DOUBLE_EQ(fem::makeMaterial("quartz")->density(), 2648.5);
  EXPECT_DOUBLE_EQ(fem::makeMaterial("steel")->density(), 7823.0);
  EXPECT_DOUBLE_EQ(fem::makeMaterial("steel", {{"density", 2 * 7823.0}})->density(), 2 * 7823.0);
  EXPECT_THROW(fem::makeMaterial("granite"), std::invalid_argument);
  try {
    fem::makeMaterial("quartz", {{"relaxation_time", -1.0}});
    FAIL();
  } catch (const std::invalid_argument &e) {
    EXPECT_NE(std::string(e.what()).find("relaxation_time"), std::string::npos) << e.what();
  }
  EXPECT_THROW(fem::makeMaterial("steel", {{"yield", 1e9}}), std::invalid_argument);
}

// J^(-1/3) by the vectorized Newton iteration: within 1e-15 (5 ulp) of 1 / std::cbrt in its range,
// and the same as 1 / std::cbrt outside it (the elements that take the library call), in a batch
// mixing both.
TEST(Materials, InverseCubeRootsToRounding) {
  std::vector<double> J;
  for (double j = 0.05; j < 20.0; j *= 1.0013)
    J.push_back(j);
  std::vector<double> r(J.size());
  fem::inverseCubeRoots(J.data(), r.data(), J.size());
  for (std::size_t i = 0; i < J.size(); ++i) {
    const double exact = 1.0 / std::cbrt(J[i]);
    if (J[i] < 0.35 || J[i] > 2.0)
      EXPECT_EQ(r[i], exact) << "J = " << J[i];
    else
      EXPECT_NEAR(r[i], exact, 1e-15 * exact) << "J = " << J[i];
  }
}

// Bodies at rest and unloaded are not updated; a body that moves is.
TEST(Solver, SkipsBodiesAtRest) {
  TestMesh mesh;
  mesh.addRectangle(0, 0, 1e-3, 1e-3, 4, 4);
  mesh.addRectangle(2e-3, 0, 1e-3, 1e-3, 8, 8);
  fem::Model model = mesh.model(test::oneMaterial("quartz"));
  fem::setBodyVelocity(model, 0, 10.0, 0.0);
  fem::Solver solver(model, {});
  for (int i = 0; i < 10; ++i)
    solver.step();
  EXPECT_EQ(solver.activeElements(), 32u);
  EXPECT_EQ(model.nodes.x[model.bodies[1].node_begin], 2e-3); // untouched
  model.wake(1);
  solver.step();
  EXPECT_EQ(solver.activeElements(), 32u + 128u);
  EXPECT_NEAR(model.nodes.vx[0], 10.0, 1e-10); // round-off of the stresses in free flight
}

// Two threads give the same numbers as one: element forces are gathered per node in a fixed order.
TEST(Solver, SameResultWithAnyThreadCount) {
  auto run = [](int threads) {
    omp_set_num_threads(threads);
    TestMesh mesh;
    mesh.addRectangle(0, 0, 1e-3, 1e-3, 30, 30, 0.3);
    fem::Model model = mesh.model(test::oneMaterial("quartz"));
    fem::setBodyVelocity(model, 0, 0.0, -200.0, 1e5);
    model.constraints.push_back({"base",
                                 test::nodesWhere(model, [](double, double y) { return y < 1e-9; }),
                                 true, true, 0, 0});
    fem::Solver solver(model, {.chunk = 64});
    for (int i = 0; i < 100; ++i)
      solver.step();
    return std::pair{model.nodes.x, solver.energy().internal};
  };
  const auto one = run(1), two = run(2);
  omp_set_num_threads(omp_get_num_procs());
  EXPECT_EQ(one.first, two.first);
  EXPECT_EQ(one.second, two.second);
}

// A state that is no longer finite ends the run with RunFailure naming the element (a NaN ran on
// to the end, reported as completed, its energies null): here one element's stress is made NaN.
TEST(Solver, StateNotFiniteEndsTheRun) {
  TestMesh mesh;
  mesh.addRectangle(0, 0, 1e-4, 1e-4, 4, 4, 0.2);
  fem::Model model = mesh.model(test::oneMaterial("steel"));
  fem::setBodyVelocity(model, 0, 10.0, 0.0);
  fem::Solver solver(model, {});
  solver.step();
  model.elements.sxx[5] = std::nan("");
  try {
    for (int i = 0; i < 3; ++i)
      solver.step();
    ADD_FAILURE() << "a NaN stress ran on";
  } catch (const fem::RunFailure &e) {
    EXPECT_NE(std::string(e.what()).find("the stress of element 5 of body"), std::string::npos)
        << e.what();
  }
}

// Contiguous runs of items with a share of its own for each run (the levels' units among the
// threads, Solver::shareLevelsAmongThreads): an item goes to the run whose share holds its middle.
TEST(Threads, ContiguousSharesFollowTheirTargets) {
  const std::vector<std::size_t> ten(10, 1);
  // equal targets: the equal split
  EXPECT_EQ(fem::contiguousShares(ten, std::vector<double>{1.0, 1.0}),
            fem::contiguousShares(ten, 2));
  EXPECT_EQ(fem::contiguousShares(ten, std::vector<double>{1.0, 1.0}),
            (std::vector<std::size_t>{0, 5, 10}));
  // three quarters to the first run, none to a run whose target is 0
  EXPECT_EQ(fem::contiguousShares(ten, std::vector<double>{3.0, 1.0}),
            (std::vector<std::size_t>{0, 7, 10})); // (item 7 at the boundary: the next run)
  EXPECT_EQ(fem::contiguousShares(ten, std::vector<double>{0.0, 1.0}),
            (std::vector<std::size_t>{0, 0, 10}));
  EXPECT_EQ(fem::contiguousShares(ten, std::vector<double>{1.0, 0.0, 1.0}),
            (std::vector<std::size_t>{0, 5, 5, 10}));
  // every target 0 (nothing to share against): all to the first run; no items: empty runs
  EXPECT_EQ(fem::contiguousShares(ten, std::vector<double>{0.0, 0.0}),
            (std::vector<std::size_t>{0, 10, 10}));
  EXPECT_EQ(fem::contiguousShares(std::vector<std::size_t>{}, std::vector<double>{1.0, 1.0}),
            (std::vector<std::size_t>{0, 0, 0}));
  // a heavy item goes where its middle lies
  EXPECT_EQ(
      fem::contiguousShares(std::vector<std::size_t>{1, 10, 1}, std::vector<double>{1.0, 1.0}),
      (std::vector<std::size_t>{0, 1, 3}));
}

// Work lists: every item taken once, whatever the team (fewer threads than lists, or more), a
// thread's own list first; and taken again after a reset.
TEST(Threads, WorkListsTakeEveryItemOnce) {
  fem::WorkLists lists;
  for (int round = 0; round < 2; ++round) { // (the lists' cursors reused)
    EXPECT_EQ((lists.reset(3), lists.size()), 3u);
    for (int team : {1, 2, 3, 5}) {
      lists.reset(3); // (the same lists again, none taken)
      for (std::size_t i = 0; i < 3000; ++i)
        lists.list(i % 7 == 0 ? 2 : i % 2).push_back(i);
      std::vector<int> taken(3000, 0);
      std::vector<std::size_t> order; // (one thread's)
#pragma omp parallel num_threads(team)
      {
        const auto me = static_cast<std::size_t>(omp_get_thread_num());
        for (std::size_t item; (item = lists.next(me)) != fem::WorkLists::none;) {
#pragma omp atomic
          ++taken[item];
          if (team == 1)
            order.push_back(item);
        }
      }
      EXPECT_EQ(std::count(taken.begin(), taken.end(), 1), 3000) << team << " threads";
      EXPECT_EQ(lists.next(0), fem::WorkLists::none);
      if (team == 1) { // its own list, then the next lists in turn
        std::vector<std::size_t> expected;
        for (std::size_t t = 0; t < 3; ++t)
          expected.insert(expected.end(), lists.list(t).begin(), lists.list(t).end());
        EXPECT_EQ(order, expected);
      }
    }
  }
  lists.reset(2); // empty lists: nothing to take
  EXPECT_EQ(lists.next(1), fem::WorkLists::none);
}
