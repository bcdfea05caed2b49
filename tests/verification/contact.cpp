// Frictional contact against exact answers: Coulomb sliding, a symmetric impact, impenetrability.
#include "contact.hpp"
#include "meshes.hpp"
#include "solver.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

using namespace mesopen;
using test::TestMesh;

namespace {

std::vector<std::uint32_t> bodyNodes(const fem::Model &model, std::size_t b) {
  std::vector<std::uint32_t> nodes(model.bodies[b].node_end - model.bodies[b].node_begin);
  std::iota(nodes.begin(), nodes.end(), static_cast<std::uint32_t>(model.bodies[b].node_begin));
  return nodes;
}

// Deceleration of an elastic block sliding under gravity g on a fixed surface (a fixed body, or a
// rigid wall) with Coulomb friction mu, from v0 until before it stops.
struct Sliding {
  double deceleration, balance_error, friction_energy, kinetic_lost;
};
Sliding slide(bool on_wall, double mu) {
  const double g = 1e4, v0 = 1.0, width = 4e-3, height = 2e-3;
  TestMesh mesh;
  mesh.addRectangle(0, 0, width, height, 8, 4, 0.2, 3);
  if (!on_wall)
    mesh.addRectangle(-2e-3, -1e-3, 12e-3, 1e-3, 24, 2, 0.2, 4);
  fem::Model model = mesh.model(test::oneMaterial("quartz-elastic"));
  if (!on_wall)
    model.constraints.push_back({"surface", bodyNodes(model, 1), true, true, 0.0, 0.0});
  fem::setBodyVelocity(model, 0, v0, 0.0);
  fem::ContactSettings cs;
  cs.friction = {mu};
  cs.wall_friction = mu;
  if (on_wall)
    cs.wall_bottom = 0.0;
  fem::Contact contact(model, cs);
  fem::Solver solver(model, {.gravity_y = -g});
  solver.addForceProvider(&contact);
  const double kinetic0 = solver.energy().kinetic;
  const double end = 0.7 * v0 / (0.3 * g); // well before it stops at mu = 0.3
  while (solver.time() < end)
    solver.step();
  const fem::BodyMotion m = fem::bodyMotion(model, 0);
  return {(v0 - m.px / m.mass) / solver.time(), solver.energy().balance_error,
          solver.energy().friction, kinetic0 - solver.energy().kinetic};
}

} // namespace

// A block sliding on a fixed surface decelerates at mu g. Its vertical bouncing after gravity is
// switched on moves the mean normal force by |dPy| / (m g t), a few 1e-4 here; tolerance 1 %
// (the issue's).
TEST(Contact, SlidingBlockDeceleratesAtMuG) {
  for (bool on_wall : {false, true}) {
    const Sliding s = slide(on_wall, 0.3);
    EXPECT_NEAR(s.deceleration / (0.3 * 1e4), 1.0, 0.01) << (on_wall ? "on a wall" : "on a body");
    EXPECT_LT(std::abs(s.balance_error), 1e-3);
    EXPECT_GT(s.friction_energy, 0.0);
    std::printf("sliding on %s: deceleration / (mu g) = %.5f, balance error %.2e\n",
                on_wall ? "a wall" : "a fixed body", s.deceleration / (0.3 * 1e4), s.balance_error);
  }
  EXPECT_LT(std::abs(slide(false, 0.0).deceleration), 1e-3 * 0.3 * 1e4); // frictionless: no drag
}

// Two identical grains, one the mirror image of the other, meet head on: the motion stays a
// mirror image and the total momentum stays zero. Tolerance: round-off accumulated over the steps
// (1e-8 of the velocity scale; at 200 m/s the impact leaves the grains plastically deformed, at
// 1500 m/s, the thesis's fastest, crushed). The error stays below 1e-10 until the faces part: a
// node whose force falls to zero (f_n = max(0, ...)) in one pass a step before its mirror image,
// by round-off, then makes one jump of a few 1e-9 (3e-9 at 200 m/s at step 305 of 370). Their faces
// meet node on node: a node's closest point is then a vertex of the other face, at the same
// distance from both its segments up to round-off; before the vertex normal (Contact::atVertex) the
// pass took the first segment of its list, or by round-off its corner, and the mirror error reached
// 2e-2. With contact stiffness kappa >= 0.7 the mirror error grows to 1e-1: the doubled stiffness
// of node-on-node contact is then beyond the explicit limit.
class HeadOn : public ::testing::TestWithParam<double> {};
TEST_P(HeadOn, StaysMirrorSymmetric) {
  TestMesh mesh;
  mesh.addRectangle(-0.11e-3, -0.05e-3, 0.1e-3, 0.1e-3, 8, 8, 0.3, 11);
  const std::size_t n = mesh.x.size();
  // The mirror image x -> -x, triangles turned back to counter-clockwise.
  for (std::size_t a = 0; a < n; ++a)
    mesh.x.push_back(-mesh.x[a]), mesh.y.push_back(mesh.y[a]);
  const std::size_t t = mesh.tri.size();
  for (std::size_t k = 0; k < t; k += 3)
    mesh.tri.insert(mesh.tri.end(), {static_cast<std::uint32_t>(mesh.tri[k] + n),
                                     static_cast<std::uint32_t>(mesh.tri[k + 2] + n),
                                     static_cast<std::uint32_t>(mesh.tri[k + 1] + n)});
  mesh.node_offset.push_back(2 * n);
  mesh.tri_offset.push_back(2 * t / 3);
  fem::Model model = mesh.model(test::oneMaterial("quartz"));
  const double v = GetParam();
  fem::setBodyVelocity(model, 0, v, 0.0);
  fem::setBodyVelocity(model, 1, -v, 0.0);
  fem::Contact contact(model, {});
  // Plain constant-strain triangles, as the penetration runs use them: with the averaged nodal
  // volume the grains' spurious pressure modes amplify round-off (mirror error 3e-2 here).
  fem::Solver solver(model, {.anti_locking = false});
  solver.addForceProvider(&contact);
  double worst_mirror = 0.0, worst_momentum = 0.0, mass = 0.0;
  for (std::size_t a = 0; a < model.nodes.size(); ++a)
    mass += model.nodes.mass[a];
  const fem::Nodes &nd = model.nodes;
  while (solver.time() < 0.1e-6) {
    solver.step();
    for (std::size_t a = 0; a < n; ++a)
      worst_mirror =
          std::max({worst_mirror, std::abs(nd.vx[a] + nd.vx[a + n]) / v,
                    std::abs(nd.vy[a] - nd.vy[a + n]) / v, std::abs(nd.x[a] + nd.x[a + n]) / 0.1e-3,
                    std::abs(nd.y[a] - nd.y[a + n]) / 0.1e-3});
    double px = 0.0, py = 0.0;
    for (std::size_t a = 0; a < nd.size(); ++a)
      px += nd.mass[a] * nd.vx[a], py += nd.mass[a] * nd.vy[a];
    worst_momentum = std::max({worst_momentum, std::abs(px), std::abs(py)});
  }
  std::printf(
      "head-on at %g m/s: mirror error %.2e, momentum %.2e of m v, max depth %.3f elements, "
      "plastic work %.3g J/m\n",
      v, worst_mirror, worst_momentum / (mass * v), contact.statistics().max_depth,
      solver.energy().plastic);
  EXPECT_GT(contact.statistics().max_depth, 0.0); // they did meet
  EXPECT_GT(fem::bodyMotion(model, 0).px, -0.9 * fem::bodyMotion(model, 0).mass * v);
  EXPECT_LT(worst_mirror, 1e-8);
  EXPECT_LT(worst_momentum, 1e-12 * mass * v);
}
INSTANTIATE_TEST_SUITE_P(Contact, HeadOn, ::testing::Values(200.0, 1500.0));

// A grain dropped on a rigid wall, corner first and face first, at 1 to 100 m/s: its nodes never
// get further into the wall than 1 % of the element size (the bound). Penetration grows
// with the speed: about 2 % corner first at 1000 m/s (printed, not asserted).
TEST(Contact, DroppedGrainDoesNotPenetrateTheWall) {
  for (double angle : {0.0, 0.6})
    for (double speed : {1.0, 10.0, 100.0, 1000.0}) {
      TestMesh mesh;
      mesh.addRectangle(-30e-6, -30e-6, 60e-6, 60e-6, 6, 6, 0.2, 5);
      for (std::size_t a = 0; a < mesh.x.size(); ++a) { // turned, lowest point just above y = 0
        const double x = mesh.x[a], y = mesh.y[a];
        mesh.x[a] = std::cos(angle) * x - std::sin(angle) * y;
        mesh.y[a] = std::sin(angle) * x + std::cos(angle) * y;
      }
      const double lowest = *std::min_element(mesh.y.begin(), mesh.y.end());
      for (double &y : mesh.y)
        y += 1e-7 - lowest;
      fem::Model model = mesh.model(test::oneMaterial("quartz"));
      fem::setBodyVelocity(model, 0, 0.0, -speed);
      fem::ContactSettings cs;
      cs.wall_bottom = 0.0;
      fem::Contact contact(model, cs);
      fem::Solver solver(model, {.gravity_y = -9.81});
      solver.addForceProvider(&contact);
      double deepest = 0.0;
      bool rebounded = false;
      while (solver.time() < 3 * 60e-6 / 5000.0 + 2e-7 / speed && !rebounded) {
        solver.step();
        for (double y : model.nodes.y)
          deepest = std::max(deepest, -y);
        rebounded = fem::bodyMotion(model, 0).py > 0.0 && solver.time() > 1e-9;
      }
      std::printf("dropped at %5.1f m/s, angle %.1f: deepest %.2e m = %.4f elements, rebound %d\n",
                  speed, angle, deepest, deepest / 10e-6, rebounded);
      EXPECT_TRUE(rebounded);
      if (speed <= 100.0) {
        EXPECT_LT(deepest, 0.01 * 10e-6) << speed << " m/s, angle " << angle;
      }
    }
}

// An elastic-plastic steel bar hits a fixed steel block at 1000 m/s and its face fails: elements
// past the erosion strain leave the model, and contact goes on against the new boundary (the
// nodes they leave without elements fly on as free masses). No node gets half an element into
// the block, and the energy balance, with the eroded elements' internal energy counted, closes
// to 2e-5 (bound 1e-3: the eroded elements take their energy and their forces with them).
TEST(Contact, ErodingBarKeepsContactAndEnergyBalance) {
  TestMesh mesh;
  mesh.addRectangle(-20e-6, 0.1e-6, 40e-6, 120e-6, 8, 24, 0.2, 11);
  mesh.addRectangle(-80e-6, -60e-6, 160e-6, 60e-6, 32, 12, 0.2, 12);
  std::vector<std::unique_ptr<fem::Material>> materials;
  materials.push_back(fem::makeMaterial("steel", {{"erosion_strain", 0.8}}));
  materials.push_back(fem::makeMaterial("steel-elastic"));
  fem::Model model = mesh.model(std::move(materials), {0, 1});
  model.constraints.push_back({"block", bodyNodes(model, 1), true, true, 0.0, 0.0});
  fem::setBodyVelocity(model, 0, 0.0, -1000.0);
  fem::Contact contact(model, {});
  fem::Solver solver(model, {});
  solver.addForceProvider(&contact);
  while (solver.time() < 60e-9)
    solver.step();
  const fem::Energy &e = solver.energy();
  std::size_t detached = 0;
  for (std::uint8_t d : model.nodes.detached)
    detached += d;
  std::printf(
      "eroding bar: %zu elements eroded (%.3g J/m of %.3g), %zu nodes detached, balance %.2e, "
      "deepest %.3f elements\n",
      solver.erodedElements(), e.eroded, e.initial, detached, e.balance_error,
      contact.statistics().max_depth);
  EXPECT_GT(solver.erodedElements(), 0u);
  EXPECT_GT(e.eroded, 0.0);
  EXPECT_LT(std::abs(e.balance_error), 1e-3);
  EXPECT_EQ(contact.statistics().deep, 0u);
  EXPECT_LT(contact.statistics().max_depth, 0.5);
}

// Two grains closing at 2 m/s that overlap by 0.3 of an element at the start, as a node a folded
// grain closes over, or a boundary that a change of closest segment puts deep at once: the contact
// is found deeper than any step's approach could make it. Pushed out in one step the nodes would
// leave at about kappa d / dt (1,000 m/s here); the excess depth is allowed for and let go over
// release_steps (200) steps, so the grains part at about d / (200 dt). Bound: no node faster
// than a twentieth of d / dt (the one-step push is ten times that); the overlap has opened
// (deepest contact below check_depth, 5 % of an element) after 300 steps; momentum stays zero to
// round-off.
TEST(Contact, SuddenDeepOverlapOpensGently) {
  const double h = 10e-6, overlap = 0.3 * h;
  TestMesh mesh;
  mesh.addRectangle(-6 * h, 0.0, 6 * h, 6 * h, 6, 6, 0.2, 7);
  mesh.addRectangle(-overlap, 0.5 * h, 6 * h, 6 * h, 6, 6, 0.2, 8);
  fem::Model model = mesh.model(test::oneMaterial("quartz"));
  fem::setBodyVelocity(model, 0, 1.0, 0.0); // closing slowly (bodies at rest are not computed)
  fem::setBodyVelocity(model, 1, -1.0, 0.0);
  fem::ContactSettings cs;
  cs.friction = {0.0};
  fem::Contact contact(model, cs);
  fem::Solver solver(model, {});
  solver.addForceProvider(&contact);
  const fem::Nodes &nd = model.nodes;
  double mass = 0.0, fastest = 0.0, worst_momentum = 0.0, dt = HUGE_VAL;
  for (std::size_t a = 0; a < nd.size(); ++a)
    mass += nd.mass[a];
  for (int step = 0; step < 300; ++step) {
    solver.step();
    dt = std::min(dt, solver.dt());
    double px = 0.0, py = 0.0;
    for (std::size_t a = 0; a < nd.size(); ++a) {
      fastest = std::max(fastest, std::hypot(nd.vx[a], nd.vy[a]));
      px += nd.mass[a] * nd.vx[a], py += nd.mass[a] * nd.vy[a];
    }
    worst_momentum = std::max({worst_momentum, std::abs(px), std::abs(py)});
  }
  const double one_step = overlap / dt;
  std::printf("sudden overlap of %.2f elements: %zu contacts found deeper than a step's approach, "
              "fastest node %.3g m/s (d / dt = %.3g m/s), deepest at the end %.4f elements, "
              "momentum %.2e of m d / dt\n",
              overlap / h, contact.statistics().sudden, fastest, one_step,
              contact.statistics().depth, worst_momentum / (mass * one_step));
  EXPECT_GT(contact.statistics().sudden, 0u);
  EXPECT_LT(fastest, one_step / 20.0);
  EXPECT_LT(contact.statistics().depth, 0.05);
  EXPECT_LT(worst_momentum, 1e-12 * mass * one_step);
}

namespace {

// Two bodies closing at 2 m/s, frictionless: the contact's figures after one step.
fem::ContactStatistics closingStep(const TestMesh &mesh) {
  fem::Model model = mesh.model(test::oneMaterial("quartz"));
  fem::setBodyVelocity(model, 0, 0.0, -1.0); // closing slowly (bodies at rest are not computed)
  fem::setBodyVelocity(model, 1, 0.0, 1.0);
  fem::ContactSettings cs;
  cs.friction = {0.0};
  fem::Contact contact(model, cs);
  fem::Solver solver(model, {});
  solver.addForceProvider(&contact);
  solver.step();
  return contact.statistics();
}

// A square grain of side 0.8 h (one cell) whose two lower corner nodes lie `inside` above the lower
// face of a bar 10 h long (cells h wide) and `thickness` thick, closing at 2 m/s: the contacts
// found in one step and the deepest (over the bar's element size, its longest edge).
fem::ContactStatistics grainCornersInABar(double h, double inside, double thickness) {
  TestMesh mesh;
  mesh.addRectangle(0.0, 0.0, 0.8 * h, 0.8 * h, 1, 1, 0.0, 1);              // the grain
  mesh.addRectangle(-4.1 * h, -inside, 10.0 * h, thickness, 10, 1, 0.0, 2); // the bar
  return closingStep(mesh);
}

} // namespace

// A grain's corner nodes 0.07 of an element inside a thin bar, just above its lower face: the
// grain's box ends at those nodes, so the bar's lower face lies 0.07 elements beyond the overlap
// of the two boxes, out of the narrow phase's reach around it (0.05 elements), while the bar's
// upper face, 0.43 elements away, is within it. The depth is the distance to the closest
// boundary, 0.07 elements (an eroding tip meets grains this way); measured against the upper
// face instead, the contact would be 0.43 deep and its excess let go as a sudden depth. Tolerance
// 0.002: the nodes move by about 1e-4 of an element in the step.
TEST(Contact, DepthIsToTheClosestSegmentBeyondTheOverlapsReach) {
  const double h = 10e-6;
  const fem::ContactStatistics st = grainCornersInABar(h, 0.07 * h, 0.5 * h);
  std::printf("grain nodes 0.070 elements inside the bar: deepest contact %.4f elements\n",
              st.depth);
  EXPECT_GT(st.contacts, 0u);
  EXPECT_NEAR(st.depth, 0.07, 0.002);
}

// The same grain 0.5 h inside a bar 1.2 h thick (its element size, its longest edge, then 1.2 h):
// its corner nodes lie deeper than a pair's list margin and the reach (0.5 of the smaller element
// size and 0.05 of the bar's: 0.46 h), so the bar's lower face lies beyond the region the lists
// are taken in, and the upper face, 0.7 h away, inside it. The lists hold every node's closest
// segment: the depth is 0.5 h (0.417 of the bar's element), not 0.7 h (0.583). Tolerance as above.
TEST(Contact, ListsHoldTheClosestSegmentOfANodeDeeperThanTheMargin) {
  const double h = 10e-6;
  const fem::ContactStatistics st = grainCornersInABar(h, 0.5 * h, 1.2 * h);
  std::printf("grain nodes 0.417 of the bar's elements inside it: deepest contact %.4f\n",
              st.depth);
  EXPECT_GT(st.contacts, 0u);
  EXPECT_NEAR(st.depth, 0.5 / 1.2, 0.002);
}

// A body whose boundary is folded over itself (an eroding tip's flap pressed into the body
// beneath; a body has no contact with itself): a bar of cells h wide, and in the same body a flap
// (a triangle) whose lower face lies 0.03 h below the bar's upper face. A grain's two lower corner
// nodes lie 0.04 h below that face: inside the bar, 0.01 h in front of the flap's lower face, the
// closest segment. They are in contact with the bar's upper face, 0.04 h deep (found at once:
// sudden). Taken for the closest, the flap's face would find them outside, and the grain would
// sink into the bar unseen (as a grain's node did under a fold of run 1's eroding tip, 0.306 of
// an element deep when the bar's face became its closest segment). Tolerance 0.002 as above.
TEST(Contact, NodeBeneathAFoldOfTheBoundaryIsInContact) {
  const double h = 10e-6;
  for (const bool fold : {false, true}) {
    TestMesh mesh;
    mesh.addRectangle(0.1 * h, -0.04 * h, 0.8 * h, 0.3 * h, 1, 1, 0.0, 1);   // the grain
    mesh.addRectangle(-4.0 * h, -1.0 * h, 10.0 * h, 1.0 * h, 10, 1, 0.0, 2); // the bar
    if (fold) { // the flap, a part of the bar's body
      const auto first = static_cast<std::uint32_t>(mesh.x.size());
      mesh.x.insert(mesh.x.end(), {0.05 * h, 0.95 * h, 0.5 * h});
      mesh.y.insert(mesh.y.end(), {-0.03 * h, -0.03 * h, 0.6 * h});
      mesh.tri.insert(mesh.tri.end(), {first, first + 1, first + 2});
      mesh.node_offset.back() = mesh.x.size(), mesh.tri_offset.back() = mesh.tri.size() / 3;
    }
    const fem::ContactStatistics st = closingStep(mesh);
    std::printf("grain nodes 0.04 h inside a bar%s: %zu contacts, deepest %.4f elements, %zu "
                "beneath a fold\n",
                fold ? " under a fold of it" : "", st.contacts, st.depth, st.beneath_folds);
    EXPECT_EQ(st.contacts, 2u);
    EXPECT_NEAR(st.depth, 0.04, 0.002);
    EXPECT_EQ(st.beneath_folds, fold ? 2u : 0u);
  }
}
