// What coupling costs a DEM step: baseline-dem (run 6's grains as LIGGGHTS disks, the FE projectile
// entering them at 1500 m/s), set up as `mesopen run` sets it up (run/run_assembly.hpp). A DEM step
// is a time window of several FE steps (multiple time stepping, coupling.hpp). The coupled DEM step
// (the window: the disks near the projectile moved and in contact with it on every FE step of the
// window, their motion written into LIGGGHTS, LIGGGHTS's step, the state read) against LIGGGHTS's
// own step in the same run (the window less the exchange): the same disks moving the same way.
// Also LIGGGHTS alone advancing the disks at rest by the same step (one `run N`): it rebuilds its
// neighbour lists less often. Per DEM step: microseconds and ratios (goal 1.2), median of the
// repeats. The FE participant's own step (the projectile's elements and its contact with the
// walls) is shown apart, per FE step.
//
//   mesopen_bench_coupling [--steps 2000] [--repeats 5] [--out build/bench]   (FE steps)
#include "run_assembly.hpp"
#include "run_settings.hpp"
#include "scene.hpp"

#include "library.h"

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
  const parallel::World world = parallel::world(true);
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
  // dem.data and liggghts.log of the run, apart from the other benchmarks' files
  const std::string dir = out + "/bench_coupling";
  std::filesystem::create_directories(dir);
  const Scene scene = readScene(std::string(MESOPEN_SOURCE_DIR) + "/examples/baseline-dem.toml");
  const std::string script = std::string(MESOPEN_SOURCE_DIR) + "/liggghts-inputs/dem.in";
  std::size_t disks = 0;
  std::vector<double> alone, own, coupled, fe;
  std::size_t contacts = 0;
  int windows = 0;
  double mean_dt = 0.0; // the mean DEM step
  for (int r = 0; r < repeats; ++r) {
    { // the coupled run, as `mesopen run` makes it
      RunAssembly run(scene, dir, script, world);
      fem::Solver &solver = *run.solver;
      const coupling::FeDemCoupling &coupling = *run.coupled;
      const auto start = Clock::now();
      for (int s = 0; s < steps; ++s)
        solver.step();
      const double all = std::chrono::duration<double>(Clock::now() - start).count();
      windows = static_cast<int>(coupling.windows());
      coupled.push_back(coupling.seconds() / windows);
      own.push_back((run.dem->windowSeconds() - run.dem->exchangeSeconds()) / windows);
      fe.push_back((all - coupling.seconds()) / steps);
      contacts = coupling.contact().statistics().contacts;
      disks = run.dem->particles().size();
      mean_dt = solver.time() / windows;
    }
    { // LIGGGHTS alone on the same disks, the same step: one run
      auto variables = liggghtsVariables(scene, dir + "/dem.data");
      char dt[32];
      std::snprintf(dt, sizeof dt, "%.17g", mean_dt);
      for (auto &[name, value] : variables)
        if (name == "dt")
          value = dt;
      coupling::LiggghtsDem dem(script, variables, "none", MPI_COMM_WORLD);
      const std::string run = "run " + std::to_string(windows) + " pre no post no";
      const auto start = Clock::now();
      lammps_command(dem.handle(), const_cast<char *>(run.c_str()));
      alone.push_back(std::chrono::duration<double>(Clock::now() - start).count() / windows);
    }
  }
  const double a = median(alone), o = median(own), c = median(coupled), f = median(fe);
  std::printf("DEM step of run 6's %zu grains as disks with the projectile entering at 1500 m/s, "
              "%d DEM steps of %.3g s over %d FE steps, median of %d repeats\n",
              disks, windows, mean_dt, steps, repeats);
  std::printf("  %-60s %8.1f us  %5.2f\n", "LIGGGHTS's own step in the coupled run", 1e6 * o, 1.0);
  std::printf("  %-60s %8.1f us  %5.2f  (goal 1.2)\n",
              "coupled DEM step: LIGGGHTS's, the exchange, the FE-DEM contact", 1e6 * c, c / o);
  std::printf("  %-60s %8.1f us  %5.2f\n", "LIGGGHTS alone, the same disks at rest (one run)",
              1e6 * a, a / o);
  std::printf("  %-60s %8.1f us\n", "(the FE participant's own step, per FE step: the projectile)",
              1e6 * f);
  std::printf("  FE-DEM contacts in the last step: %zu\n", contacts);
  nlohmann::json j{{"disks", disks},
                   {"fe_steps", steps},
                   {"dem_steps", windows},
                   {"repeats", repeats},
                   {"dem_dt", mean_dt},
                   {"us_per_step_liggghts_own", 1e6 * o},
                   {"us_per_step_coupled_dem", 1e6 * c},
                   {"ratio", c / o},
                   {"us_per_step_liggghts_alone_at_rest", 1e6 * a},
                   {"us_per_step_fe", 1e6 * f},
                   {"contacts_last_step", contacts},
                   {"samples_own", own},
                   {"samples_coupled", coupled},
                   {"samples_alone", alone},
                   {"samples_fe", fe}};
  std::ofstream(out + "/bench_coupling.json") << j.dump(2) << "\n";
  std::printf("figures in %s/bench_coupling.json\n", out.c_str());
  return 0;
}
