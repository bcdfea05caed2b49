// A DEM-only target under gravity: the baseline's grains as disks (mesopen's target.data) fall,
// settle and stay in their box.
#include "generator.hpp"
#include "liggghts_dem.hpp"
#include "run.hpp"
#include "writers.hpp"

#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>

using namespace mesopen;

// A 0.6 x 0.4 mm target of the baseline's grains (42-78 um, 30 % porosity) as disks, under a
// gravity of 1e6 m/s^2 (so that it settles within 0.1 ms), walls on the box's sides and bottom,
// restitution about 0.5. After 0.1 ms: no disk outside the box by more than 1 % of its radius (the
// walls' penalty), the disks' centre of mass lower than at the start, and their kinetic energy
// below 1e-3 of the potential energy they lost (settled).
TEST(Liggghts, DemTargetSettlesInItsBox) {
  TargetSpec spec;
  spec.width = 0.6e-3, spec.height = 0.4e-3, spec.mesh = MeshKind::none, spec.seed = 3;
  GeneratorReport report;
  const Target target = generateTarget(spec, report);
  const test::ScratchDir dir("liggghts-settle");
  const std::string data = dir / "target.data";
  writeLiggghtsData(data, target, targetDisks(target));
  const double g = 1e6, kn = 1e10;
  coupling::LiggghtsDem dem(MESOPEN_SOURCE_DIR "/liggghts-inputs/dem.in",
                            {{"data", data},
                             {"kn", "1e10"},
                             {"kt", "1e10"},
                             {"gn", "80"},
                             {"gt", "80"},
                             {"mu", "0.3"},
                             {"mu_wall", "0.3"},
                             {"hertz", "0"},
                             {"rolling", "0"},
                             {"h", "1"},
                             {"mref", "1"},
                             {"xlo", "0"},
                             {"xhi", "0.6e-3"},
                             {"ylo", "0"},
                             {"skin", "6e-6"},
                             {"gravity", "1e6"},
                             {"dt", "1e-9"}},
                            "none", MPI_COMM_WORLD);
  const coupling::Particles &p = dem.particles();
  ASSERT_EQ(p.size(), target.grains.size());
  auto height = [&] {
    double mh = 0.0, m = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i)
      mh += p.mass[i] * p.y[i], m += p.mass[i];
    return std::pair{mh / m, m};
  };
  const auto [y0, mass] = height();
  const double dt = dem.stableStep();
  EXPECT_NEAR(dt, 0.1 * M_PI * std::sqrt(*std::min_element(p.mass.begin(), p.mass.end()) / kn),
              1e-20);
  for (double t = 0.0; t < 1e-4; t += dt)
    dem.advance(dt, [](const coupling::Particles &, coupling::ParticleForces &) {});
  double worst = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i)
    worst = std::max({worst, (p.radius[i] - p.x[i]) / p.radius[i],
                      (p.x[i] + p.radius[i] - spec.width) / p.radius[i],
                      (p.radius[i] - p.y[i]) / p.radius[i]});
  const double drop = y0 - height().first;
  std::printf(
      "%zu disks settled: centre of mass %.2f um lower, kinetic energy %.2e of the potential "
      "energy lost, deepest beyond a wall %.4f radius\n",
      p.size(), 1e6 * drop, p.kineticEnergy() / (mass * g * drop), worst);
  EXPECT_LT(worst, 0.01);
  EXPECT_GT(drop, 0.0);
  EXPECT_LT(p.kineticEnergy(), 1e-3 * mass * g * drop);
}
