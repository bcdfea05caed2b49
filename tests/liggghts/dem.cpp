// The LIGGGHTS participant: forces put in exactly, and a disk hitting an FE block through LIGGGHTS
// as through the fake participant (both take the same velocity-Verlet steps).
#include "coupled.hpp"
#include "coupling.hpp"
#include "fake_dem.hpp"
#include "liggghts_dem.hpp"
#include "meshes.hpp"
#include "run.hpp"
#include "solver.hpp"

#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <fstream>

using namespace mesopen;

namespace {

const std::string script = MESOPEN_SOURCE_DIR "/liggghts-inputs/dem.in";

// A data file of one quartz disk of radius r at (x, y), moving at (vx, vy) and spinning at omega,
// in a 2 x 2 mm box around the origin.
std::string oneDisk(double x, double y, double r, double vx = 0.0, double vy = 0.0,
                    double omega = 0.0) {
  static const test::ScratchDir dir("liggghts-dem"); // the process's own: tests run side by side
  const std::string path = dir / "one.data";
  std::ofstream out(path);
  out.precision(17);
  out << "one disk\n\n1 atoms\n2 atom types\n\n-1e-3 1e-3 xlo xhi\n-1e-3 1e-3 ylo yhi\n"
      << -r << ' ' << r << " zlo zhi\n\nAtoms\n\n1 1 " << 2 * r << " 2650 " << x << ' ' << y
      << " 0\n\nVelocities\n\n1 " << vx << ' ' << vy << " 0 0 0 " << omega << "\n";
  return path;
}

std::vector<std::pair<std::string, std::string>> variables(const std::string &data) {
  return {{"data", data},   {"kn", "1e5"},      {"kt", "1e5"},   {"gn", "0"},      {"gt", "0"},
          {"mu", "0.3"},    {"mu_wall", "0.3"}, {"hertz", "0"},  {"rolling", "0"}, {"h", "1"},
          {"mref", "1"},    {"xlo", "-1e-3"},   {"xhi", "1e-3"}, {"ylo", "-1e-3"}, {"skin", "1e-6"},
          {"gravity", "0"}, {"dt", "1e-9"}};
}

} // namespace

// A constant force and torque over windows of changing length: v = F (t - dt_1 / 2) / m, omega =
// T (t - dt_1 / 2) / I to round-off (1e-12): the force goes in within the step, a new step length
// re-initialises the integrator and keeps the last force for the first half kick; the first
// window's first half kick has no force yet (velocity Verlet, the force taken at x(n+1)).
TEST(Liggghts, ForcesGoInExactly) {
  coupling::LiggghtsDem dem(script, variables(oneDisk(0.0, 0.0, 1e-5)), "none", MPI_COMM_WORLD);
  ASSERT_EQ(dem.particles().size(), 1u);
  const double m = dem.particles().mass[0], inertia = dem.particles().inertia(0);
  EXPECT_NEAR(m, 2650.0 * M_PI * 1e-10, 1e-12 * m); // a disk 1 m thick
  const double F = 1e-3, T = 1e-9;
  double t = 0.0;
  for (int k = 0; k < 60; ++k) {
    const double dt = k < 20 ? 1e-9 : k < 40 ? 1.3e-9 : 0.7e-9;
    dem.advance(dt, [&](const coupling::Particles &, coupling::ParticleForces &f) {
      f.fx[0] = F, f.torque[0] = T;
    });
    t += dt;
  }
  t -= 0.5e-9;
  EXPECT_NEAR(dem.particles().vx[0], F * t / m, 1e-12 * F * t / m);
  EXPECT_NEAR(dem.particles().omega[0], T * t / inertia, 1e-12 * T * t / inertia);
  EXPECT_EQ(dem.particles().vy[0], 0.0);
}

// Bad variables never reach LIGGGHTS.
TEST(Liggghts, BadVariablesAreRefused) {
  auto vars = variables(oneDisk(0.0, 0.0, 1e-5));
  vars[1].second = "1e5; quit";
  EXPECT_THROW(coupling::LiggghtsDem(script, vars, "none", MPI_COMM_WORLD), std::invalid_argument);
  vars = variables("/nonexistent/target.data");
  EXPECT_THROW(coupling::LiggghtsDem(script, vars, "none", MPI_COMM_WORLD), std::invalid_argument);
}

// A disk hits a free elastic block at 100 m/s, obliquely and spinning: momentum is conserved to
// round-off (1e-12 of m v), the disk bounces, and it leaves as it does with the fake participant
// (1e-9 of the speed: the same steps, summed in another order). LIGGGHTS takes windows of its
// stable step (multiple time stepping), the fake participant, without a stiffness, a window each
// FE step: a disk with no forces of its own moves alike in both.
TEST(Liggghts, DiskHittingABlockMatchesTheFakeParticipant) {
  auto run = [](coupling::DemParticipant &dem, double &worst) {
    test::TestMesh mesh;
    mesh.addRectangle(0.0, 0.0, 100e-6, 50e-6, 10, 5, 0.2, 7);
    fem::Model model = mesh.model(test::oneMaterial("quartz"));
    fem::setBodyVelocity(model, 0, 0.0, 0.0);
    coupling::FeDemCoupling coupling(model, dem, {.friction = {0.3}});
    fem::Solver solver(model, {});
    solver.addForceProvider(&coupling);
    auto momentum = [&] { return test::totalMomentum(model, coupling.disks()); };
    const auto p0 = momentum();
    worst = 0.0;
    while (solver.time() < 0.4e-6) {
      solver.step();
      const auto p = momentum();
      worst = std::max({worst, std::abs(p[0] - p0[0]), std::abs(p[1] - p0[1])});
    }
    worst /= dem.particles().mass[0] * 100.0;
    const coupling::Particles d = coupling.disks();
    return std::array<double, 3>{d.vx[0], d.vy[0], d.omega[0]};
  };
  coupling::LiggghtsDem liggghts(script, variables(oneDisk(40e-6, 62e-6, 10e-6, 20.0, -100.0, 3e5)),
                                 "none", MPI_COMM_WORLD);
  ASSERT_EQ(liggghts.particles().vy[0], -100.0);
  coupling::FakeDem fake(liggghts.particles(), {});
  double worst_fake = 0.0, worst_liggghts = 0.0;
  const auto v_fake = run(fake, worst_fake);
  const auto v = run(liggghts, worst_liggghts);
  std::printf("disk on block through LIGGGHTS: momentum error %.2e of m v; leaves at (%.6f, %.6f) "
              "m/s, %.6g rad/s; the fake participant (%.6f, %.6f) m/s, %.6g rad/s\n",
              worst_liggghts, v[0], v[1], v[2], v_fake[0], v_fake[1], v_fake[2]);
  EXPECT_LT(worst_liggghts, 1e-12);
  EXPECT_GT(v[1], 0.0);
  for (int k = 0; k < 2; ++k)
    EXPECT_NEAR(v[k], v_fake[k], 1e-9 * 100.0);
  EXPECT_NEAR(v[2], v_fake[2], 1e-9 * std::abs(v_fake[2]));
}
