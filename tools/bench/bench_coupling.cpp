// What coupling costs a DEM step: run 6's grains as disks (6,198, the baseline target's
// target.data) with the FE projectile entering them at 1500 m/s, as in baseline-dem. A DEM step is
// a time window of several FE steps (multiple time stepping, coupling.hpp). The coupled DEM step
// (the window: the disks near the projectile moved and in contact with it on every FE step of the
// window, their motion written into LIGGGHTS, LIGGGHTS's step, the state read) against LIGGGHTS's
// own step in the same run (the window less the exchange): the same disks moving the same way.
// Also LIGGGHTS alone advancing the disks at rest by the same step (one `run N`): it rebuilds its
// neighbour lists less often. Per DEM step: microseconds and ratios (goal 1.2), median of the
// repeats. The FE participant's own step (the projectile's elements) is shown apart, per FE step.
//
//   mesopen_bench_coupling [--steps 2000] [--repeats 5] [--out build/bench]   (FE steps)
#include "coupling.hpp"
#include "generator.hpp"
#include "liggghts_dem.hpp"
#include "model.hpp"
#include "projectile.hpp"
#include "writers.hpp"

#include "library.h"

#include <mpi.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

using namespace mesopen;
using Clock = std::chrono::steady_clock;

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

} // namespace

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  int steps = 2000, repeats = 5;
  std::string out = "bench";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--steps")
      steps = std::stoi(argv[i + 1]);
    else if (a == "--repeats")
      repeats = std::stoi(argv[i + 1]);
    else if (a == "--out")
      out = argv[i + 1];
  }
  std::filesystem::create_directories(out);
  // The baseline target (run 6) as disks, and the projectile placed on it.
  TargetSpec spec; // the defaults are the baseline's
  spec.mesh = MeshKind::none;
  GeneratorReport report;
  const Target target = generateTarget(spec, report);
  const std::string data = out + "/bench_coupling.data";
  ProjectileSpec ps;
  ps.length = 1.7e-3, ps.tip_facet_length = 40e-6;
  const PlacedProjectile p = placeProjectile(ps, 10e-6, spec, target.grains);
  writeLiggghtsData(data, target, targetDisks(target, DiskSize::inscribed, {}, &p));
  const std::string script = std::string(MESOPEN_SOURCE_DIR) + "/liggghts-inputs/dem.in";
  auto variables = [&](double dt) {
    char text[32];
    std::snprintf(text, sizeof text, "%.17g", dt);
    return std::vector<std::pair<std::string, std::string>>{
        {"data", data},      {"kn", "3.39e10"}, {"kt", "1.13e10"},  {"gn", "29.7"},
        {"gt", "9.9"},       {"mu", "0.3"},     {"mu_wall", "0.3"}, {"hertz", "0"},
        {"rolling", "0"},    {"h", "1"},        {"mref", "1"},      {"xlo", "0"},
        {"xhi", "7.076e-3"}, {"ylo", "0"},      {"skin", "30e-6"},  {"gravity", "0"},
        {"dt", text}};
  };
  std::vector<double> alone, own, coupled, fe;
  std::size_t contacts = 0;
  int windows = 0;
  double mean_dt = 0.0; // the mean DEM step
  for (int r = 0; r < repeats; ++r) {
    { // the coupled run: the projectile (elastic steel, 1500 m/s) entering the disks
      std::vector<std::unique_ptr<fem::Material>> materials;
      materials.push_back(fem::makeMaterial("steel-elastic", {}));
      const std::vector<std::uint64_t> node_offset{0, p.mesh.x.size()},
          tri_offset{0, p.mesh.tri.size() / 3};
      fem::Model model = fem::buildModel({node_offset, tri_offset, p.mesh.x, p.mesh.y, p.mesh.tri},
                                         std::move(materials), {0}, {"projectile"});
      fem::setBodyVelocity(model, 0, 0.0, -1500.0);
      coupling::LiggghtsDem dem(script, variables(1e-10), "none", MPI_COMM_WORLD);
      coupling::FeDemCoupling coupling(model, dem, {.friction = {0.3}});
      fem::Solver solver(model, {.max_dt = dem.stableStep()});
      solver.addForceProvider(&coupling);
      const auto start = Clock::now();
      for (int s = 0; s < steps; ++s)
        solver.step();
      const double all = std::chrono::duration<double>(Clock::now() - start).count();
      windows = static_cast<int>(coupling.windows());
      coupled.push_back(coupling.seconds() / windows);
      own.push_back((dem.windowSeconds() - dem.exchangeSeconds()) / windows);
      fe.push_back((all - coupling.seconds()) / steps);
      contacts = coupling.contact().statistics().contacts;
      mean_dt = solver.time() / windows;
    }
    { // LIGGGHTS alone on the same disks, the same step: one run
      coupling::LiggghtsDem dem(script, variables(mean_dt), "none", MPI_COMM_WORLD);
      const std::string run = "run " + std::to_string(windows) + " pre no post no";
      const auto start = Clock::now();
      lammps_command(dem.handle(), const_cast<char *>(run.c_str()));
      alone.push_back(std::chrono::duration<double>(Clock::now() - start).count() / windows);
    }
  }
  const double a = median(alone), o = median(own), c = median(coupled), f = median(fe);
  std::printf("DEM step of run 6's %zu grains as disks with the projectile entering at 1500 m/s, "
              "%d DEM steps of %.3g s over %d FE steps, median of %d repeats\n",
              target.grains.size(), windows, mean_dt, steps, repeats);
  std::printf("  %-60s %8.1f us  %5.2f\n", "LIGGGHTS's own step in the coupled run", 1e6 * o, 1.0);
  std::printf("  %-60s %8.1f us  %5.2f  (goal 1.2)\n",
              "coupled DEM step: LIGGGHTS's, the exchange, the FE-DEM contact", 1e6 * c, c / o);
  std::printf("  %-60s %8.1f us  %5.2f\n", "LIGGGHTS alone, the same disks at rest (one run)",
              1e6 * a, a / o);
  std::printf("  %-60s %8.1f us\n", "(the FE participant's own step, per FE step: the projectile)",
              1e6 * f);
  std::printf("  FE-DEM contacts in the last step: %zu\n", contacts);
  nlohmann::json j{{"disks", target.grains.size()}, {"fe_steps", steps}, {"dem_steps", windows},
                   {"repeats", repeats}, {"dem_dt", mean_dt}, {"us_per_step_liggghts_own", 1e6 * o},
                   {"us_per_step_coupled_dem", 1e6 * c}, {"ratio", c / o},
                   {"us_per_step_liggghts_alone_at_rest", 1e6 * a},
                   {"us_per_step_fe", 1e6 * f}, {"contacts_last_step", contacts},
                   {"samples_own", own}, {"samples_coupled", coupled}, {"samples_alone", alone},
                   {"samples_fe", fe}};
  std::ofstream(out + "/bench_coupling.json") << j.dump(2) << "\n";
  std::printf("figures in %s/bench_coupling.json\n", out.c_str());
  MPI_Finalize();
  return 0;
}
