// Benchmark of the finite-element element pass (kinematics, material, viscosity, nodal forces
// and their gather): nanoseconds per element-step, median of several repetitions (the machine
// may be shared). Cases:
//   - the baseline target's grain mesh (about 435,000 triangles, 6,200 bodies), quartz with its
//     overstress strength active in every element, on 1 and 2 OpenMP threads;
//   - the same with strength off (elastic grains run no plasticity code);
//   - growth with element count on structured quartz meshes;
//   - whole time steps of the baseline scene with the grains at rest (skipped) and all awake, its
//     model and solver settings made as `mesopen run` makes them (run/run_assembly.hpp).
// Prints a table and writes the figures as JSON.
//     mesopen_bench_fem [--out DIR] [--repeats 5] [--passes 20]
#include "generator.hpp"
#include "run_assembly.hpp"
#include "run_settings.hpp"
#include "scene.hpp"
#include "solver.hpp"

#include <nlohmann/json.hpp>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

using namespace mesopen;
using Clock = std::chrono::steady_clock;

namespace {

struct Options {
  std::string out = "bench";
  int repeats = 5, passes = 20;
};

struct MeshData {
  std::vector<std::uint64_t> node_offset{0}, tri_offset{0};
  std::vector<double> x, y;
  std::vector<std::uint32_t> tri;
};

// The thesis's baseline target (Table 3.4, run 6): the scene's defaults.
Target baselineTarget() {
  GeneratorReport report;
  return generateTarget(Scene().target, report);
}

MeshData meshData(const Meshes &m) { return {m.node_offset, m.tri_offset, m.x, m.y, m.tri}; }

// A structured square of n x n cells (2 n^2 triangles) as one body.
MeshData grid(int n) {
  MeshData d;
  const double h = 10e-6;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      d.x.push_back(i * h), d.y.push_back(j * h);
  auto id = [n](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      d.tri.insert(d.tri.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j),
                                 id(i + 1, j + 1), id(i, j + 1)});
  d.node_offset.push_back(d.x.size());
  d.tri_offset.push_back(d.tri.size() / 3);
  return d;
}

// A model where every element strains and (with strength on) stays above its yield surface:
// a rotating shear flow and a deviatoric stress of 3 GPa (the quartz surface is at ~1.9 GPa).
fem::Model stressedModel(const MeshData &d, const std::string &material) {
  std::vector<std::unique_ptr<fem::Material>> materials;
  materials.push_back(fem::makeMaterial(material));
  fem::Model model =
      fem::buildModel({d.node_offset, d.tri_offset, d.x, d.y, d.tri}, std::move(materials),
                      std::vector<int>(d.node_offset.size() - 1, 0), {});
  for (std::size_t a = 0; a < model.nodes.size(); ++a) {
    model.nodes.vx[a] = 1e4 * model.nodes.y[a] + 2e3 * model.nodes.x[a];
    model.nodes.vy[a] = -3e3 * model.nodes.x[a] - 1e3 * model.nodes.y[a];
  }
  for (std::size_t e = 0; e < model.elements.size(); ++e)
    model.elements.sxx[e] = 3e9, model.elements.syy[e] = -3e9;
  return model;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// ns per element-step of the element pass: `passes` calls per repetition, median over repeats.
struct Timing {
  double median_ns, min_ns, max_ns;
};
Timing elementPass(const MeshData &d, const std::string &material, int threads, const Options &o) {
  omp_set_num_threads(threads);
  fem::Model model = stressedModel(d, material);
  fem::Solver solver(model, {});
  const double dt = 1e-11;   // small: the state stays in the same regime over the repetitions
  solver.internalForces(dt); // warm-up
  std::vector<double> ns;
  for (int r = 0; r < o.repeats; ++r) {
    const auto start = Clock::now();
    for (int p = 0; p < o.passes; ++p)
      solver.internalForces(dt);
    const double s = std::chrono::duration<double>(Clock::now() - start).count();
    ns.push_back(1e9 * s / (static_cast<double>(o.passes) * model.elements.size()));
  }
  return {median(ns), *std::min_element(ns.begin(), ns.end()),
          *std::max_element(ns.begin(), ns.end())};
}

// Seconds per whole time step of the baseline scene (projectile moving, grains at rest or all
// awake), median over repeats of `passes` steps.
double stepSeconds(const Target &target, bool wake_all, int threads, const Options &o) {
  omp_set_num_threads(threads);
  const Scene scene; // the defaults: the baseline target, its projectile at 1000 m/s
  const PlacedProjectile p = runProjectile(scene, &target);
  fem::Model model = buildRunModel(scene, &target, p, meshedGrains(scene, target, p));
  if (wake_all)
    for (std::size_t b = 1; b < model.bodies.size(); ++b)
      fem::setBodyVelocity(model, b, 0.0, 0.0, 1.0);
  fem::Solver solver(model, solverSettings(scene, HUGE_VAL));
  solver.step();
  std::vector<double> s;
  for (int r = 0; r < o.repeats; ++r) {
    const auto start = Clock::now();
    for (int k = 0; k < o.passes; ++k)
      solver.step();
    s.push_back(std::chrono::duration<double>(Clock::now() - start).count() / o.passes);
  }
  return median(s);
}

} // namespace

int main(int argc, char **argv) {
  Options o;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--out"))
      o.out = argv[i + 1];
    else if (!std::strcmp(argv[i], "--repeats"))
      o.repeats = std::max(1, std::atoi(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--passes"))
      o.passes = std::max(1, std::atoi(argv[i + 1]));
    else {
      std::fprintf(stderr, "usage: mesopen_bench_fem [--out DIR] [--repeats N] [--passes N]\n");
      return 2;
    }
  }
  nlohmann::json j;
  const Target target = baselineTarget();
  const MeshData baseline = meshData(target.mesh);
  const std::size_t n_base = baseline.tri.size() / 3;
  std::printf("Element pass, ns per element-step, median (min-max) of %d x %d passes\n", o.repeats,
              o.passes);
  std::printf("%-44s %10s %8s %22s\n", "case", "elements", "threads", "ns/element-step");
  auto row = [&](const std::string &name, std::size_t elements, int threads, Timing t) {
    std::printf("%-44s %10zu %8d %10.1f (%.1f-%.1f)\n", name.c_str(), elements, threads,
                t.median_ns, t.min_ns, t.max_ns);
    std::fflush(stdout);
    j["element_pass"].push_back({{"case", name},
                                 {"elements", elements},
                                 {"threads", threads},
                                 {"ns_per_element_step", t.median_ns},
                                 {"min", t.min_ns},
                                 {"max", t.max_ns}});
  };
  for (int threads : {1, 2})
    row("baseline grains, quartz, overstress active", n_base, threads,
        elementPass(baseline, "quartz", threads, o));
  row("baseline grains, quartz, strength off", n_base, 1,
      elementPass(baseline, "quartz-elastic", 1, o));
  for (int n : {100, 200, 450, 900}) {
    const MeshData g = grid(n);
    row("structured square, quartz, overstress active", g.tri.size() / 3, 1,
        elementPass(g, "quartz", 1, o));
  }
  std::printf("\nWhole time step of the baseline scene (projectile at 1000 m/s), ms per step\n");
  for (int threads : {1, 2}) {
    const double rest = stepSeconds(target, false, threads, o),
                 awake = stepSeconds(target, true, threads, o);
    std::printf(
        "threads %d: grains at rest (skipped) %.3f ms, all grains awake %.3f ms, saving x%.1f\n",
        threads, 1e3 * rest, 1e3 * awake, awake / rest);
    j["time_step"].push_back(
        {{"threads", threads}, {"grains_at_rest_seconds", rest}, {"all_awake_seconds", awake}});
  }
  std::filesystem::create_directories(o.out);
  std::ofstream(o.out + "/bench_fem.json") << j.dump(2) << "\n";
  std::printf("\nwritten: %s/bench_fem.json\n", o.out.c_str());
  return 0;
}
