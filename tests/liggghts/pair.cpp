// Two DEM disks collide head on through LIGGGHTS (liggghts-inputs/dem.in, `model hooke/stiffness`
// with absolute damping and the force limited to f >= 0): the contact time and restitution are
// those of coupling::pairCollision, for the calibrated quartz law (docs/coupling.md) at the
// calibration's speeds, and for a strongly damped law, where the force limit changes them.
#include "liggghts_dem.hpp"
#include "run.hpp"
#include "spring_dashpot.hpp"

#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

using namespace mesopen;

namespace {

const std::string script = MESOPEN_SOURCE_DIR "/liggghts-inputs/dem.in";
const coupling::GrainContactLaw &quartz = coupling::quartz_grains;

// A data file of two disks of the calibration's diameter and density on the x axis, 10 nm apart,
// meeting at relative speed v (+v/2 and -v/2), in a 2 x 2 mm box around the origin. The file is
// the process's own: CTest runs this program's tests side by side.
std::string twoDisks(double v) {
  static const test::ScratchDir dir("liggghts-pair");
  const std::string path = dir / "pair.data";
  const double r = 0.5 * quartz.diameter, x = r + 5e-9;
  std::ofstream out(path);
  out.precision(17);
  out << "two disks\n\n2 atoms\n2 atom types\n\n-1e-3 1e-3 xlo xhi\n-1e-3 1e-3 ylo yhi\n"
      << -r << ' ' << r << " zlo zhi\n\nAtoms\n\n"
      << "1 1 " << 2 * r << ' ' << quartz.density << ' ' << -x << " 0 0\n"
      << "2 1 " << 2 * r << ' ' << quartz.density << ' ' << x << " 0 0\n"
      << "\nVelocities\n\n1 " << 0.5 * v << " 0 0 0 0 0\n2 " << -0.5 * v << " 0 0 0 0 0\n";
  return path;
}

std::string number(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", x);
  return text;
}

struct Measured {
  double contact_time, restitution, mass;
};

// The collision at relative speed v under (kn, gn), kt = kn / 3, gt = gn / 3 (no tangential motion
// here), step dt. The force on the left disk at the end of each step is 2 m (v(n+1) - v(n+1/2)) /
// dt (velocity Verlet: the exchange sees v(n+1/2)), exactly zero without contact; the contact time
// is the number of steps with a force times dt, as the FE grains'
// (tests/verification/grain_pair.cpp), the restitution -(relative velocity after) / (before).
Measured collide(const coupling::SpringDashpot &law, double v, double dt) {
  coupling::LiggghtsDem dem(script,
                            {{"data", twoDisks(v)},
                             {"kn", number(law.kn)},
                             {"kt", number(law.kn / 3.0)},
                             {"gn", number(law.gn)},
                             {"gt", number(law.gn / 3.0)},
                             {"mu", "0.3"},
                             {"mu_wall", "0.3"},
                             {"hertz", "0"},
                             {"rolling", "0"},
                             {"h", "1"},
                             {"mref", "1"},
                             {"xlo", "-1e-3"},
                             {"xhi", "1e-3"},
                             {"ylo", "-1e-3"},
                             {"skin", "1e-6"},
                             {"gravity", "0"},
                             {"dt", number(dt)}},
                            "none", MPI_COMM_WORLD);
  const coupling::Particles &p = dem.particles();
  EXPECT_EQ(p.size(), 2u);
  // LIGGGHTS may reorder its particles: the left disk is the one at smaller x.
  auto left = [&] { return p.x[0] < p.x[1] ? 0 : 1; };
  std::size_t steps_with_force = 0, steps_after = 0;
  for (int step = 0; step < 100000 && steps_after < 20; ++step) {
    double v_half = 0.0;
    dem.advance(dt, [&](const coupling::Particles &q, coupling::ParticleForces &) {
      v_half = q.vx[q.x[0] < q.x[1] ? 0 : 1];
    });
    const bool force = p.vx[left()] != v_half;
    steps_with_force += force;
    steps_after += steps_with_force > 0 && !force;
  }
  EXPECT_EQ(steps_after, 20u) << "the disks did not separate";
  const int l = left();
  return {static_cast<double>(steps_with_force) * dt, (p.vx[1 - l] - p.vx[l]) / v, p.mass[l]};
}

} // namespace

// The calibrated quartz law at 10, 100 and 1000 m/s: contact time and restitution are the formula's
// to 1 % (dt = t_c / 500: the count of steps resolves the contact to 0.2 %, velocity Verlet's
// frequency error is (w dt)^2 / 24, 2e-6), whatever the speed. The mass is rho pi r^2.
TEST(LiggghtsPair, CalibratedQuartzLawMatchesTheFormulas) {
  const double m_eff = 0.5 * quartz.mass();
  const coupling::PairCollision expected = coupling::pairCollision({quartz.kn, quartz.gn}, m_eff);
  for (double v : {10.0, 100.0, 1000.0}) {
    const Measured m = collide({quartz.kn, quartz.gn}, v, expected.contact_time / 500);
    std::printf(
        "LIGGGHTS pair at %6.0f m/s: t_c = %.3f ns (formula %.3f), e = %.5f (formula %.5f)\n", v,
        m.contact_time * 1e9, expected.contact_time * 1e9, m.restitution, expected.restitution);
    EXPECT_NEAR(m.mass, quartz.mass(), 1e-12 * m.mass);
    EXPECT_NEAR(m.contact_time / expected.contact_time, 1.0, 0.01) << v << " m/s";
    EXPECT_NEAR(m.restitution / expected.restitution, 1.0, 0.01) << v << " m/s";
  }
}

// A law made for t_c = 30 ns and e = 0.3 by springDashpotFor gives them through LIGGGHTS (1 %,
// as above), while the textbook law (the dashpot pulling until the overlap closes, omega_d =
// pi / t_c) would have put t_c and e more than 10 % off: with limitForce on the force ends when
// kn d = gn |v_n|, before the overlap closes.
TEST(LiggghtsPair, StrongDampingNeedsTheForceLimit) {
  const double m_eff = 0.5 * quartz.mass(), t_c = 30e-9, e = 0.3;
  const coupling::SpringDashpot law = coupling::springDashpotFor(t_c, e, m_eff);
  const Measured m = collide(law, 100.0, t_c / 500);
  const coupling::PairCollision textbook = coupling::pairCollision(law, m_eff, false);
  std::printf("LIGGGHTS pair, kn = %.4g, gn = %.4g: t_c = %.3f ns (asked %.3f; without the limit "
              "%.3f), e = %.4f (asked %.4f; without the limit %.4f)\n",
              law.kn, law.gn, m.contact_time * 1e9, t_c * 1e9, textbook.contact_time * 1e9,
              m.restitution, e, textbook.restitution);
  EXPECT_NEAR(m.contact_time / t_c, 1.0, 0.01);
  EXPECT_NEAR(m.restitution / e, 1.0, 0.01);
  EXPECT_GT(std::abs(textbook.contact_time / t_c - 1.0), 0.1);
  EXPECT_GT(std::abs(textbook.restitution / e - 1.0), 0.1);
}
