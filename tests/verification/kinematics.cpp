// Kinematics of the element pass against exact answers: the patch test, rigid rotation (no strain,
// and a stress that turns with the body), and momentum in free flight.
#include "meshes.hpp"
#include "solver.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace mesopen;
using test::TestMesh;

namespace {

double maxAbs(const std::vector<double> &v) {
  double m = 0.0;
  for (double x : v)
    m = std::max(m, std::abs(x));
  return m;
}

} // namespace

// Patch test: a linear velocity field imposed on the boundary of an irregular mesh is a
// homogeneous deformation, which constant-strain triangles represent exactly: every element must
// carry the same stress and the interior nodes must keep the linear field, to round-off.
// Both forms of the deviator: the rate form ("steel", far below yield) and the total form from F
// ("elastic"). Tolerance 1e-9 relative for the stresses (200 steps of round-off on numbers
// of order one), 1e-8 for the nodes (F is taken from positions of 1e-3 m over reference gradients
// of 1e4 1/m: 1.1e-9 measured).
TEST(PatchTest, HomogeneousDeformationIsExact) {
  for (const char *material : {"steel", "elastic"}) {
    SCOPED_TRACE(material);
    TestMesh mesh;
    mesh.addRectangle(0, 0, 1e-3, 1e-3, 8, 8, 0.3, 7);
    fem::Model model = mesh.model(test::oneMaterial(material));
    const double lxx = 40.0, lyy = -25.0, lxy = 15.0, lyx = -5.0; // velocity gradient [1/s]
    auto field = [&](double x, double y) {
      return std::pair{lxx * x + lxy * y, lyx * x + lyy * y};
    };
    for (std::size_t a = 0; a < model.nodes.size(); ++a) {
      auto [vx, vy] = field(model.nodes.x[a], model.nodes.y[a]);
      model.nodes.vx[a] = vx, model.nodes.vy[a] = vy;
    }
    const auto boundary = test::nodesWhere(model, [](double x, double y) {
      return x < 1e-9 || y < 1e-9 || x > 1e-3 - 1e-9 || y > 1e-3 - 1e-9;
    });
    for (std::uint32_t a : boundary) {
      auto [vx, vy] = field(model.nodes.x[a], model.nodes.y[a]);
      model.constraints.push_back({"boundary", {a}, true, true, vx, vy});
    }
    fem::Solver solver(model, {.viscosity_linear = 0.0, .viscosity_quadratic = 0.0});
    for (int i = 0; i < 200; ++i)
      solver.step();
    const auto &el = model.elements;
    const double scale = maxAbs(el.sxx) + maxAbs(el.syy) + maxAbs(el.sxy) + maxAbs(el.pressure);
    ASSERT_GT(scale, 1e5); // the patch is really strained
    for (std::size_t e = 1; e < el.size(); ++e) {
      EXPECT_NEAR(el.sxx[e], el.sxx[0], 1e-9 * scale);
      EXPECT_NEAR(el.syy[e], el.syy[0], 1e-9 * scale);
      EXPECT_NEAR(el.sxy[e], el.sxy[0], 1e-9 * scale);
      EXPECT_NEAR(el.pressure[e], el.pressure[0], 1e-9 * scale);
    }
    // Interior nodes: the imposed field moves them with constant velocity (no net force).
    const double vscale = 40.0 * 1e-3;
    for (std::size_t a = 0; a < model.nodes.size(); ++a) {
      auto [vx, vy] = field(model.nodes.x0[a], model.nodes.y0[a]);
      EXPECT_NEAR(model.nodes.vx[a], vx, 1e-8 * vscale);
      EXPECT_NEAR(model.nodes.vy[a], vy, 1e-8 * vscale);
    }
  }
}

// Rigid rotation driven exactly, step by step (x(n+1) = R(theta(n+1)) X): the strain rate on the
// mid-step configuration is zero, so an unstressed body stays unstressed (the total form of
// "elastic": F = R, b = I), and a stressed body's stress turns with it (the objective rate
// of "steel", far below yield). After a quarter turn S_xx and S_yy have swapped.
// Tolerances: 1e-6 of the stress scale for the turned stress (the rotation angle per step is
// first-order accurate: error ~ N theta^3 / 3 ~ 1e-7 rad here); round-off for the unstressed body.
TEST(RigidRotation, StaysStressFreeAndStressTurns) {
  TestMesh mesh;
  mesh.addRectangle(-0.5e-3, -0.3e-3, 1e-3, 0.6e-3, 10, 6, 0.25, 3);
  mesh.addRectangle(-0.5e-3, 1e-3, 1e-3, 0.6e-3, 10, 6, 0.25, 4); // a second, pre-stressed body
  std::vector<std::unique_ptr<fem::Material>> materials;
  materials.push_back(fem::makeMaterial("elastic"));
  materials.push_back(fem::makeMaterial("steel"));
  fem::Model model = mesh.model(std::move(materials), {0, 1});
  const double s0 = 1e8;
  for (std::size_t e = model.bodies[1].element_begin; e < model.bodies[1].element_end; ++e)
    model.elements.sxx[e] = s0, model.elements.syy[e] = -0.5 * s0, model.elements.sxy[e] = 0.2 * s0;
  const std::vector<double> X = model.nodes.x, Y = model.nodes.y;
  const int steps = 2000;
  const double dt = 1e-9, omega = 0.5 * M_PI / (steps * dt);
  for (std::size_t b = 0; b < 2; ++b)
    fem::setBodyVelocity(model, b, 0.0, 0.0, omega); // both bodies take part
  fem::Solver solver(model, {.viscosity_linear = 0.0, .viscosity_quadratic = 0.0});
  ASSERT_EQ(solver.activeElements(), model.elements.size());
  for (int n = 1; n <= steps; ++n) {
    const double c = std::cos(omega * n * dt), s = std::sin(omega * n * dt);
    for (std::size_t a = 0; a < model.nodes.size(); ++a) {
      const double x = c * X[a] - s * Y[a], y = s * X[a] + c * Y[a];
      model.nodes.vx[a] = (x - model.nodes.x[a]) / dt,
      model.nodes.vy[a] = (y - model.nodes.y[a]) / dt;
      model.nodes.x[a] = x, model.nodes.y[a] = y;
    }
    solver.internalForces(dt);
  }
  const auto &el = model.elements;
  for (std::size_t e = model.bodies[0].element_begin; e < model.bodies[0].element_end; ++e) {
    EXPECT_NEAR(el.sxx[e], 0.0, 1e-3); // Pa, against G ~ 1e11 Pa: round-off
    EXPECT_NEAR(el.sxy[e], 0.0, 1e-3);
    EXPECT_NEAR(el.pressure[e], 0.0, 1e-3);
  }
  for (std::size_t e = model.bodies[1].element_begin; e < model.bodies[1].element_end; ++e) {
    EXPECT_NEAR(el.sxx[e], -0.5 * s0, 1e-6 * s0); // a quarter turn: xx <-> yy, xy -> -xy
    EXPECT_NEAR(el.syy[e], s0, 1e-6 * s0);
    EXPECT_NEAR(el.sxy[e], -0.2 * s0, 1e-6 * s0);
    EXPECT_NEAR(el.pressure[e], 0.0, 1e-6 * s0);
  }
}

// Free flight of the deformable projectile-like body with spin: the internal forces are
// equilibrated and torque-free, so central differences keep the linear and the angular momentum
// exactly; tolerance 1e-12 relative (round-off of sums over ~300 nodes over 500 steps).
TEST(FreeFlight, ConservesLinearAndAngularMomentum) {
  TestMesh mesh;
  mesh.addRectangle(0, 0, 0.44e-3, 1.7e-3, 6, 24, 0.3, 11);
  fem::Model model = mesh.model(test::oneMaterial("steel"));
  fem::setBodyVelocity(model, 0, 30.0, -1000.0, 2e6); // 2e6 rad/s: rim speed ~1.7 km/s
  const fem::BodyMotion before = fem::bodyMotion(model, 0);
  fem::Solver solver(model, {});
  for (int i = 0; i < 500; ++i)
    solver.step();
  const fem::BodyMotion after = fem::bodyMotion(model, 0);
  const double p = std::hypot(before.px, before.py);
  EXPECT_NEAR(after.px, before.px, 1e-12 * p);
  EXPECT_NEAR(after.py, before.py, 1e-12 * p);
  EXPECT_NEAR(after.angular_momentum, before.angular_momentum,
              1e-12 * std::abs(before.angular_momentum));
  // The spin really loads the body (hoop stress) and turns it through a sizeable angle.
  EXPECT_GT(maxAbs(model.elements.sxx), 1e6);
  EXPECT_GT(2e6 * solver.time(), 0.1);
}
