// Two meshed quartz grains collide head on: their contact time and coefficient of restitution, the
// figures the DEM contact law is calibrated to (docs/coupling.md, "Calibration of the DEM contact
// law"). Each grain is a regular 12-gon of the baseline's mean size (equal-area diameter 60 um),
// quality-meshed at the baseline's 10 um (targets' meshGrains), of the penetration runs' grain
// material ("quartz", overstress strength) and solver settings (plain constant-strain triangles),
// with fem::Contact at its defaults (friction 0.3, no walls). The right grain is the mirror image
// of a grain turned by its own angle: the mirror image of the left one when the two angles agree.
// Also the baseline's smallest and largest grains (42, 78 um) and finer meshes, printed.
#include "contact.hpp"
#include "mesh.hpp"
#include "meshes.hpp"
#include "solver.hpp"
#include "spring_dashpot.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

using namespace mesopen;

namespace {

constexpr double mean_diameter = 60e-6; // equal-area diameter [m] (the baseline's mean, 42-78 um)
constexpr int corners = 12;
const double speeds[] = {10.0, 100.0, 1000.0}; // relative impact speed [m/s]
// Orientations: the angle of a grain's first corner from the line of impact. The 12-gon repeats
// every 30 degrees; eight angles evenly spaced over a period sample a random orientation. A pair
// of one angle (mirror images) meets corner to corner on the line of impact at 0 ("vertex"), face
// to face at 15 ("flat"); at other equal angles corner to corner beside it.
constexpr int orientations = 8;
constexpr int vertex_orientation = 0, flat_orientation = 4;
double angleOf(int k) { return (30.0 / orientations) * k * M_PI / 180.0; }

struct Collision {
  double contact_time = 0;   // [s], see collide
  double restitution = 0;    // -(relative COM velocity after) / (before), along the line of impact
  double momentum_error = 0; // largest |total momentum| over the run / (grain mass x speed)
  double plastic = 0;        // plastic work / the kinetic energy before impact
  double balance_error = 0;  // the solver's energy balance error at the end
  double mass = 0;           // one grain [kg/m]
  bool separated = false;
};

// Two grains, regular 12-gons of equal-area diameter `diameter` meshed at `mesh_size`: the left one
// turned by `angle`, at x < 0 moving at +v/2, the right one the mirror image of one turned by
// `angle1`, moving at -v/2, 10 nm apart. Their contact time is the time from the first to the last
// step with a nonzero contact force between them, both counted whole: t_c = t_last - t_first + dt.
// The force is sampled once a step, so this is within a step (about 0.33 ns, 1 % here) of the true
// duration, and the DEM test measures its own so (tests/liggghts/pair.cpp). The span, not the
// steps with a force only: where corner nodes meet nodes, the force of the stiff penalty pair is
// nonzero every other step (kappa 0.5 pushed by both passes; fem/contact.hpp), and counting those
// steps alone would halve the duration of the pulse. Separation: the run goes on until the grains
// have been apart, and drawing apart, for as long as they were in contact and at least 100 steps;
// their velocities are then those of free bodies.
Collision collide(double v, double angle, double angle1, double mesh_size, double diameter) {
  const double R =
      0.5 * diameter * std::sqrt(2.0 * M_PI / (corners * std::sin(2.0 * M_PI / corners)));
  auto grainMesh = [&](double turn) {
    std::vector<double> px, py;
    for (int k = 0; k < corners; ++k) {
      const double a = turn + 2.0 * M_PI * k / corners;
      px.push_back(R * std::cos(a)), py.push_back(R * std::sin(a));
    }
    const double half = *std::max_element(px.begin(), px.end()), gap = 10e-9;
    for (double &x : px)
      x -= half + 0.5 * gap;
    Polygons grain;
    grain.add(px, py);
    return meshGrains(grain, MeshKind::quality, mesh_size, 20.7);
  };
  const Meshes one = grainMesh(angle), two = grainMesh(angle1);
  test::TestMesh mesh;
  mesh.x = one.x, mesh.y = one.y, mesh.tri = one.tri;
  const std::size_t n = mesh.x.size(), t = mesh.tri.size();
  mesh.node_offset = {0, n};
  mesh.tri_offset = {0, t / 3};
  for (std::size_t a = 0; a < two.x.size(); ++a)
    mesh.x.push_back(-two.x[a]), mesh.y.push_back(two.y[a]);
  for (std::size_t k = 0; k < two.tri.size(); k += 3)
    mesh.tri.insert(mesh.tri.end(), {static_cast<std::uint32_t>(two.tri[k] + n),
                                     static_cast<std::uint32_t>(two.tri[k + 2] + n),
                                     static_cast<std::uint32_t>(two.tri[k + 1] + n)});
  mesh.node_offset.push_back(mesh.x.size());
  mesh.tri_offset.push_back(mesh.tri.size() / 3);

  fem::Model model = mesh.model(test::oneMaterial("quartz"));
  fem::setBodyVelocity(model, 0, 0.5 * v, 0.0);
  fem::setBodyVelocity(model, 1, -0.5 * v, 0.0);
  fem::Contact contact(model, {});
  fem::Solver solver(model, {.anti_locking = false}); // as `mesopen run` (RunSpec::anti_locking)
  solver.addForceProvider(&contact);

  Collision c;
  c.mass = fem::bodyMotion(model, 0).mass;
  const double kinetic0 = solver.energy().kinetic;
  const fem::Nodes &nd = model.nodes;
  double first = -1.0, last = -1.0, first_dt = 0.0, apart_since = 0.0;
  std::size_t apart_steps = 0;
  const double give_up = 2e-6; // [s]: far beyond any contact here
  while (solver.time() < give_up) {
    const double dt = solver.dt();
    solver.step();
    const fem::BodyMotion m0 = fem::bodyMotion(model, 0), m1 = fem::bodyMotion(model, 1);
    c.momentum_error = std::max({c.momentum_error, std::abs(m0.px + m1.px) / (c.mass * v),
                                 std::abs(m0.py + m1.py) / (c.mass * v)});
    // Contact forces on the left grain this step: exactly zero when no node pushes (f_n = 0).
    bool force = false;
    for (std::uint32_t a : nd.loaded)
      force |= nd.body[a] == 0 && (nd.external[a].fx != 0.0 || nd.external[a].fy != 0.0);
    if (force) {
      if (first < 0.0)
        first = solver.time(), first_dt = dt;
      last = solver.time();
      apart_steps = 0;
      continue;
    }
    if (first < 0.0)
      continue;
    if (apart_steps++ == 0)
      apart_since = solver.time();
    if (m1.px / m1.mass - m0.px / m0.mass <= 0.0) // not drawing apart
      apart_steps = 0;
    if (apart_steps >= 100 && solver.time() - apart_since >= last - first) {
      c.separated = true;
      break;
    }
  }
  const fem::BodyMotion m0 = fem::bodyMotion(model, 0), m1 = fem::bodyMotion(model, 1);
  c.contact_time = last - first + first_dt;
  c.restitution = (m1.px / m1.mass - m0.px / m0.mass) / v;
  c.plastic = solver.energy().plastic / kinetic0;
  c.balance_error = solver.energy().balance_error;
  return c;
}

// The collisions at every speed: the mirror pairs (both grains at angle k), and the means over
// all pairs of orientations (k, l) (8 x 8; (l, k) is the mirror image of (k, l) and gives the same
// figures, so each pair k < l is run once and counted twice), or over the mirror pairs only.
struct Table {
  Collision mirror[3][orientations];
  double mean_time[3] = {}, mean_restitution[3] = {}, mean_plastic[3] = {};
  double worst_momentum = 0.0, worst_balance[3] = {};
  bool all_separated = true;
};
Table measure(double mesh_size, bool all_pairs, double diameter = mean_diameter) {
  Table table;
  for (int s = 0; s < 3; ++s) {
    double weights = 0.0;
    for (int k = 0; k < orientations; ++k)
      for (int l = k; l < (all_pairs ? orientations : k + 1); ++l) {
        const Collision c = collide(speeds[s], angleOf(k), angleOf(l), mesh_size, diameter);
        if (k == l)
          table.mirror[s][k] = c;
        const double w = k == l ? 1.0 : 2.0;
        weights += w;
        table.mean_time[s] += w * c.contact_time;
        table.mean_restitution[s] += w * c.restitution;
        table.mean_plastic[s] += w * c.plastic;
        table.worst_momentum = std::max(table.worst_momentum, c.momentum_error);
        table.worst_balance[s] = std::max(table.worst_balance[s], std::abs(c.balance_error));
        table.all_separated = table.all_separated && c.separated;
      }
    table.mean_time[s] /= weights, table.mean_restitution[s] /= weights;
    table.mean_plastic[s] /= weights;
  }
  return table;
}

// The value that makes the largest relative error |x - x_i| / x_i over a set the smallest:
// x = 2 x_min x_max / (x_min + x_max), both extremes then off by (x_max - x_min) / (x_max + x_min).
double minimax(std::initializer_list<double> values) {
  const auto [lo, hi] = std::minmax(values);
  return 2.0 * lo * hi / (lo + hi);
}

} // namespace

// The FE table, the spring-dashpot per speed, the one set chosen for runs and its errors. Checks:
// momentum conserved to round-off (1e-12 of m v: the contact's forces and reactions sum to zero);
// the grains separate; the set chosen by the rule below is the calibrated set of
// spring_dashpot.hpp (to 1 %: it is stored to 3 digits; a change of the FE grains that moves it
// further asks for a new calibration); the DEM law's contact time and restitution are within 10 %
// of the FE means at 10 and 100 m/s, not at 1000 m/s.
TEST(GrainPair, CalibratesTheDemContactLaw) {
  const Table table = measure(10e-6, true);
  const double mass = table.mirror[0][0].mass, m_eff = 0.5 * mass;
  EXPECT_TRUE(table.all_separated);
  EXPECT_LT(table.worst_momentum, 1e-12);
  std::printf("FE grain pairs: quartz 12-gons of equal-area diameter %.0f um (%.4g kg/m each), "
              "10 um mesh; t_c [ns], e\n",
              mean_diameter * 1e6, mass);
  std::printf("%7s | %15s | %15s | %15s | %15s | %7s %9s\n", "v [m/s]", "flat", "vertex",
              "mirror mean (8)", "all pairs (64)", "plastic", "balance");
  for (int s = 0; s < 3; ++s) {
    const Collision &f = table.mirror[s][flat_orientation],
                    &c = table.mirror[s][vertex_orientation];
    double t = 0.0, e = 0.0;
    for (const Collision &k : table.mirror[s])
      t += k.contact_time / orientations, e += k.restitution / orientations;
    std::printf("%7.0f | %7.2f %7.4f | %7.2f %7.4f | %7.2f %7.4f | %7.2f %7.4f | %7.3f %9.1e\n",
                speeds[s], f.contact_time * 1e9, f.restitution, c.contact_time * 1e9, c.restitution,
                t * 1e9, e, table.mean_time[s] * 1e9, table.mean_restitution[s],
                table.mean_plastic[s], table.worst_balance[s]);
    for (const Collision &k : table.mirror[s]) {
      EXPECT_GT(k.restitution, 0.0);
      EXPECT_LT(k.restitution, 1.0);
    }
  }
  std::printf(
      "(plastic: plastic work over the impact's kinetic energy, mean of all pairs; balance: "
      "the solver's energy balance error, worst of all pairs; momentum error at most %.1e "
      "of m v)\n",
      table.worst_momentum);
  std::printf("mirror pairs, per orientation 0, 3.75, ..., 26.25 deg: t_c [ns] / e\n");
  for (int s = 0; s < 3; ++s) {
    std::printf("%7.0f |", speeds[s]);
    for (const Collision &k : table.mirror[s])
      std::printf(" %5.2f/%.3f", k.contact_time * 1e9, k.restitution);
    std::printf("\n");
  }

  std::printf("\nThe spring-dashpot of the all-pairs mean, per speed (m_eff = m/2 = %.4g kg/m):\n",
              m_eff);
  std::printf("%7s %12s %12s | %12s %12s (force not limited: omega_d = pi / t_c)\n", "v [m/s]",
              "kn [N/m/m]", "gn [Ns/m/m]", "kn", "gn");
  for (int s = 0; s < 3; ++s) {
    const auto law =
        coupling::springDashpotFor(table.mean_time[s], table.mean_restitution[s], m_eff);
    const auto plain =
        coupling::springDashpotFor(table.mean_time[s], table.mean_restitution[s], m_eff, false);
    std::printf("%7.0f %12.4g %12.4g | %12.4g %12.4g\n", speeds[s], law.kn, law.gn, plain.kn,
                plain.gn);
  }

  // The set for runs. A linear spring-dashpot has one contact time and one restitution at every
  // speed: both matched at 10 and 100 m/s (the minimax of the two), where the FE grains stay nearly
  // elastic and the law fits them. At 1000 m/s they crush (most of the energy goes into plastic
  // work), the restitution halves and the contact shortens: no linear law follows that (the best
  // compromise on t_c alone over all three speeds misses both ends by about 10 %); the grains that
  // meet that fast are, in the hybrid runs, meshed.
  const double t_star = minimax({table.mean_time[0], table.mean_time[1]});
  const double e_star = minimax({table.mean_restitution[0], table.mean_restitution[1]});
  const double t_lo = std::min({table.mean_time[0], table.mean_time[1], table.mean_time[2]});
  const double t_hi = std::max({table.mean_time[0], table.mean_time[1], table.mean_time[2]});
  std::printf(
      "\nt_c over all three speeds at best (minimax): %.2f ns, off by %.1f %% at both ends\n",
      minimax({t_lo, t_hi}) * 1e9, 100 * (t_hi - t_lo) / (t_hi + t_lo));
  const coupling::SpringDashpot chosen = coupling::springDashpotFor(t_star, e_star, m_eff);
  const coupling::GrainContactLaw &stored = coupling::quartz_grains;
  std::printf("\nChosen: t_c = %.2f ns, e = %.4f: kn = %.4g N/m/m, gn = %.4g N s/m/m; stored in "
              "spring_dashpot.hpp: kn = %.4g, gn = %.4g, kt = %.4g, gt = %.4g\n",
              t_star * 1e9, e_star, chosen.kn, chosen.gn, stored.kn, stored.gn, stored.kt,
              stored.gt);
  EXPECT_NEAR(chosen.kn / stored.kn, 1.0, 0.01);
  EXPECT_NEAR(chosen.gn / stored.gn, 1.0, 0.01);
  EXPECT_NEAR(stored.mass(), mass, 1e-12 * mass); // the DEM disk: the same area, density

  const coupling::PairCollision dem = coupling::pairCollision({stored.kn, stored.gn}, m_eff);
  std::printf(
      "\nDEM (stored set: t_c = %.2f ns, e = %.4f) against FE, relative error (DEM - FE) / FE:\n",
      dem.contact_time * 1e9, dem.restitution);
  std::printf("%7s | %17s | %17s | %17s\n", "v [m/s]", "all pairs t_c, e", "flat t_c, e",
              "vertex t_c, e");
  for (int s = 0; s < 3; ++s) {
    auto err = [](double dem, double fe) { return (dem - fe) / fe; };
    const Collision &f = table.mirror[s][flat_orientation],
                    &c = table.mirror[s][vertex_orientation];
    const double et = err(dem.contact_time, table.mean_time[s]);
    const double ee = err(dem.restitution, table.mean_restitution[s]);
    std::printf("%7.0f | %+7.1f%% %+7.1f%% | %+7.1f%% %+7.1f%% | %+7.1f%% %+7.1f%%\n", speeds[s],
                100 * et, 100 * ee, 100 * err(dem.contact_time, f.contact_time),
                100 * err(dem.restitution, f.restitution),
                100 * err(dem.contact_time, c.contact_time),
                100 * err(dem.restitution, c.restitution));
    if (speeds[s] <= 100.0) {
      EXPECT_LT(std::abs(et), 0.10) << speeds[s] << " m/s";
      EXPECT_LT(std::abs(ee), 0.10) << speeds[s] << " m/s";
    } else { // what docs/coupling.md says cannot be matched
      EXPECT_GT(std::abs(et), 0.10) << speeds[s] << " m/s";
      EXPECT_GT(std::abs(ee), 0.10) << speeds[s] << " m/s";
    }
  }
}

// How the figures move with the mesh (printed, for docs/coupling.md; the mirror pairs only, to
// keep the test short): the calibration is to the baseline's 10 um grains; finer meshes give
// corner contacts more compliance and more plastic work. Checked: momentum to round-off,
// separation.
TEST(GrainPair, MeshSize) {
  std::printf("mirror pairs, mean of 8 orientations\n%9s | %-26s | %-26s | %s\n", "mesh [um]",
              "t_c [ns] at 10, 100, 1000", "e at 10, 100, 1000", "t_c flat, vertex at 10 m/s");
  for (double h : {10e-6, 5e-6, 2.5e-6}) {
    const Table t = measure(h, false);
    std::printf("%9.1f | %8.2f %8.2f %8.2f | %8.4f %8.4f %8.4f | %8.2f %8.2f\n", h * 1e6,
                t.mean_time[0] * 1e9, t.mean_time[1] * 1e9, t.mean_time[2] * 1e9,
                t.mean_restitution[0], t.mean_restitution[1], t.mean_restitution[2],
                t.mirror[0][flat_orientation].contact_time * 1e9,
                t.mirror[0][vertex_orientation].contact_time * 1e9);
    EXPECT_TRUE(t.all_separated);
    EXPECT_LT(t.worst_momentum, 1e-12);
  }
}

// The same law for the baseline's smallest and largest grains (42 and 78 um, all pairs of
// orientations, printed for docs/coupling.md): in 2D kn [N/m per m] is a modulus, so the FE
// contact time grows about as the size and the one kn follows it; gn, absolute, gives smaller
// disks a lower restitution (b t_c ~ 1 / d). Both stay within 10 % of the FE means at 10 and
// 100 m/s over the baseline's range of sizes.
TEST(GrainPair, OneLawForTheBaselineSizes) {
  std::printf("%8s %7s | %9s %9s | %8s %8s | %8s %8s\n", "d [um]", "v [m/s]", "FE t_c", "DEM t_c",
              "FE e", "DEM e", "err t_c", "err e");
  for (double d : {42e-6, 78e-6}) {
    const Table t = measure(10e-6, true, d);
    EXPECT_TRUE(t.all_separated);
    EXPECT_LT(t.worst_momentum, 1e-12);
    const double m_eff = 0.5 * t.mirror[0][0].mass;
    const coupling::PairCollision dem =
        coupling::pairCollision({coupling::quartz_grains.kn, coupling::quartz_grains.gn}, m_eff);
    for (int s = 0; s < 3; ++s) {
      const double et = dem.contact_time / t.mean_time[s] - 1.0;
      const double ee = dem.restitution / t.mean_restitution[s] - 1.0;
      std::printf("%8.0f %7.0f | %9.2f %9.2f | %8.4f %8.4f | %+7.1f%% %+7.1f%%\n", d * 1e6,
                  speeds[s], t.mean_time[s] * 1e9, dem.contact_time * 1e9, t.mean_restitution[s],
                  dem.restitution, 100 * et, 100 * ee);
      if (speeds[s] <= 100.0) {
        EXPECT_LT(std::abs(et), 0.10) << d << " m, " << speeds[s] << " m/s";
        EXPECT_LT(std::abs(ee), 0.10) << d << " m, " << speeds[s] << " m/s";
      }
    }
  }
}
