// Benchmark of the modal analysis (fem/modal.hpp): the lowest 10 elastic modes of the baseline
// projectile (thesis run 6) meshed at about 20,000 nodes, and of the run's 10 um mesh; assembly,
// factorisation and Lanczos times, median of several repetitions (the machine may be shared).
// The goal: 20,000 nodes in at most 0.5 s. Prints a table and writes the figures as JSON.
//     mesopen_bench_modal [--out DIR] [--repeats 7] [--nodes 20000] [--lanczos N] [--tolerance T]
#include "modal.hpp"
#include "projectile.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

using namespace mesopen;
using Clock = std::chrono::steady_clock;

namespace {

fem::ModalMesh projectileAt(double size) {
  const ProjectileSpec spec; // the defaults are the thesis's baseline projectile
  std::vector<double> ox, oy;
  const TriangleMesh t = projectileMesh(projectileShape(spec), spec, size, ox, oy);
  return {t.x, t.y, t.tri, {}};
}

// The mesh size that gives about `nodes` nodes (nodes scale as 1 / size^2).
double sizeForNodes(double nodes) {
  double size = 10e-6;
  for (int i = 0; i < 3; ++i)
    size *= std::sqrt(static_cast<double>(projectileAt(size).nodes()) / nodes);
  return size;
}

// CPU time of this process [s]: what the solve costs when other jobs share the cores.
double cpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

} // namespace

int main(int argc, char **argv) {
  std::string out = "bench";
  int repeats = 7;
  double target_nodes = 20000;
  fem::ModalSettings settings;
  settings.modes = 10;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--out"))
      out = argv[i + 1];
    else if (!std::strcmp(argv[i], "--repeats"))
      repeats = std::max(1, std::atoi(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--nodes"))
      target_nodes = std::atof(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--lanczos"))
      settings.lanczos = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--tolerance"))
      settings.tolerance = std::atof(argv[i + 1]);
  }
  const double goal_seconds = 0.5;
  nlohmann::json cases = nlohmann::json::array();
  std::printf("%-24s %7s %9s %9s %9s %9s %9s %9s %7s  %s\n", "case", "nodes", "assemble", "factor",
              "lanczos", "total", "cpu", "goal", "solves", "f1 [Hz]");
  for (const double size : {sizeForNodes(target_nodes), 10e-6}) {
    const fem::ModalMesh mesh = projectileAt(size);
    const fem::ElasticSolid steel; // thesis Table 3.2, plane strain
    std::vector<double> assemble, factor, solve, total, cpu;
    fem::ModalResult r;
    for (int k = 0; k < repeats; ++k) {
      const auto start = Clock::now();
      const double cpu_start = cpuSeconds();
      r = fem::freeVibration(mesh, steel, settings);
      total.push_back(std::chrono::duration<double>(Clock::now() - start).count());
      cpu.push_back(cpuSeconds() - cpu_start);
      assemble.push_back(r.assemble_seconds), factor.push_back(r.factor_seconds),
          solve.push_back(r.solve_seconds);
    }
    char name[64];
    std::snprintf(name, sizeof name, "projectile %.2f um", 1e6 * size);
    const bool goal = mesh.nodes() >= 0.95 * target_nodes;
    std::printf("%-24s %7zu %9.4f %9.4f %9.4f %9.4f %9.4f %9s %7ld  %.6g\n", name, mesh.nodes(),
                median(assemble), median(factor), median(solve), median(total), median(cpu),
                goal ? (median(total) <= goal_seconds ? "met" : "MISSED") : "-", r.operations,
                r.omega[0] / (2 * M_PI));
    cases.push_back({{"case", name},
                     {"mesh_size", size},
                     {"nodes", mesh.nodes()},
                     {"triangles", mesh.triangles()},
                     {"unknowns", r.unknowns},
                     {"factor_nonzeros", r.factor_nonzeros},
                     {"modes", settings.modes},
                     {"repeats", repeats},
                     {"median_assemble_seconds", median(assemble)},
                     {"median_factor_seconds", median(factor)},
                     {"median_lanczos_seconds", median(solve)},
                     {"median_seconds", median(total)},
                     {"all_seconds", total},
                     {"median_cpu_seconds", median(cpu)},
                     {"shift_invert_solves", r.operations},
                     {"omega", r.omega},
                     {"goal_seconds", goal ? nlohmann::json(goal_seconds) : nlohmann::json()}});
  }
  std::filesystem::create_directories(out);
  std::ofstream(out + "/bench_modal.json") << nlohmann::json{{"cases", cases}}.dump(2) << "\n";
  std::printf("figures in %s/bench_modal.json\n", out.c_str());
  return 0;
}
