// mesopen run SCENE -o DIR: the target and the projectile of a scene as finite-element bodies,
// integrated in time; run.h5 (series and frames), vtk/run.pvd, summary.json.
#include "atomic_file.hpp"
#include "commands.hpp"
#include "generator.hpp"
#include "projectile.hpp"
#include "run_output.hpp"
#include "scene.hpp"
#include "solver.hpp"

#include <nlohmann/json.hpp>
#include <omp.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <unistd.h>

namespace mesopen {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

// The projectile as body 0, then every grain; materials from the scene; the fixed box edges.
fem::Model buildRunModel(const Scene &scene, const Target *target, const PlacedProjectile &p) {
  Meshes all;
  auto addBody = [&](const std::vector<double> &x, const std::vector<double> &y,
                     const std::uint32_t *tri, std::size_t triangles, std::uint32_t first_node) {
    const std::uint32_t shift = static_cast<std::uint32_t>(all.x.size());
    all.x.insert(all.x.end(), x.begin(), x.end());
    all.y.insert(all.y.end(), y.begin(), y.end());
    for (std::size_t k = 0; k < 3 * triangles; ++k)
      all.tri.push_back(tri[k] - first_node + shift);
    all.node_offset.push_back(all.x.size());
    all.tri_offset.push_back(all.tri.size() / 3);
  };
  addBody(p.mesh.x, p.mesh.y, p.mesh.tri.data(), p.mesh.tri.size() / 3, 0);
  std::vector<std::string> names{"projectile"};
  if (target) {
    const Meshes &m = target->mesh;
    for (std::size_t b = 0; b < m.bodies(); ++b) {
      const std::vector<double> x(m.x.begin() + m.node_offset[b], m.x.begin() + m.node_offset[b + 1]);
      const std::vector<double> y(m.y.begin() + m.node_offset[b], m.y.begin() + m.node_offset[b + 1]);
      addBody(x, y, m.tri.data() + 3 * m.tri_offset[b], m.tri_offset[b + 1] - m.tri_offset[b],
              static_cast<std::uint32_t>(m.node_offset[b]));
      names.push_back("grain-" + std::to_string(b));
    }
  }
  std::vector<std::unique_ptr<fem::Material>> materials;
  materials.push_back(fem::makeMaterial(scene.projectile_material.name, scene.projectile_material.parameters));
  materials.push_back(fem::makeMaterial(scene.grain_material.name, scene.grain_material.parameters));
  std::vector<int> body_material(all.bodies(), 1);
  body_material[0] = 0;
  fem::Model model = fem::buildModel({all.node_offset, all.tri_offset, all.x, all.y, all.tri},
                                     std::move(materials), body_material, names);
  if (target && scene.run.fix_edges) {
    const double tol = 1e-3 * scene.target.mesh_size, W = scene.target.width;
    fem::VelocityConstraint fixed{"box edges", {}, true, true, 0.0, 0.0};
    for (std::size_t a = model.bodies[0].node_end; a < model.nodes.size(); ++a)
      if (model.nodes.x[a] <= tol || model.nodes.x[a] >= W - tol || model.nodes.y[a] <= tol)
        fixed.nodes.push_back(static_cast<std::uint32_t>(a));
    model.constraints.push_back(std::move(fixed));
  }
  fem::setBodyVelocity(model, 0, 0.0, -scene.run.velocity, scene.run.spin);
  return model;
}

// One line, rewritten in place: step, simulated time, step size, speed, time left.
void progress(const fem::Solver &solver, double end_time, Clock::time_point start) {
  const double wall = std::chrono::duration<double>(Clock::now() - start).count();
  const double rate = solver.steps() / std::max(wall, 1e-9);
  const double eta = wall * (end_time - solver.time()) / std::max(solver.time(), 1e-30);
  std::fprintf(stderr, "\r\033[Kmesopen run: step %zu, t = %.2f ns of %.2f, dt = %.3g ps, %.0f steps/s, ETA %.0f s",
               solver.steps(), 1e9 * solver.time(), 1e9 * end_time, 1e12 * solver.dt(), rate, eta);
}

} // namespace

int runCommand(const RunOptions &options) {
  const auto start = Clock::now();
  Scene scene;
  try {
    scene = readScene(options.scene);
    if (options.seed)
      scene.target.seed = *options.seed;
    if (scene.run.grains && scene.target.mesh == MeshKind::none)
      throw InputError(options.scene + ": target.mesh = \"none\" leaves the grains without elements; "
                                       "allowed: \"quality\" or \"fan\" (or run.grains = false)");
    if (!scene.projectile.enabled)
      throw InputError(options.scene + ": projectile.enabled = false; `mesopen run` needs the projectile");
    std::error_code ec;
    fs::create_directories(fs::path(options.out_dir) / "vtk", ec);
    if (ec)
      throw InputError(options.out_dir + ": cannot create the output directory (" + ec.message() + ")");
    for (const char *old : {"summary.json", "run.h5"})
      fs::remove(fs::path(options.out_dir) / old, ec);
  } catch (const InputError &e) {
    std::cerr << "mesopen run: " << e.what() << '\n';
    return 2;
  }
  if (options.threads)
    omp_set_num_threads(*options.threads);
  const bool terminal = !options.quiet && isatty(STDERR_FILENO);
  const std::string dir = options.out_dir, h5_path = dir + "/run.h5";
  const RunSpec &run = scene.run;

  nlohmann::json summary;
  summary["command"] = "run";
  summary["scene"] = fs::absolute(options.scene).lexically_normal().string();
  summary["seed"] = scene.target.seed;
  std::string phase = "building the model";
  try {
    GeneratorReport report;
    std::unique_ptr<Target> target;
    Polygons no_grains;
    if (run.grains)
      target = std::make_unique<Target>(generateTarget(scene.target, report));
    const PlacedProjectile projectile = placeProjectile(scene.projectile, scene.target.mesh_size, scene.target,
                                                        target ? target->grains : no_grains);
    fem::Model model = buildRunModel(scene, target.get(), projectile);
    fem::Solver solver(model, {.safety = run.safety,
                               .viscosity_linear = run.viscosity_linear,
                               .viscosity_quadratic = run.viscosity_quadratic,
                               .anti_locking = run.anti_locking});
    summary["model"] = {{"bodies", model.bodies.size()}, {"nodes", model.nodes.size()},
                        {"elements", model.elements.size()}};

    // The time loop: step, sample the series, take frames, show progress.
    phase = "running";
    H5File h5 = H5File::create(h5_path + ".tmp");
    Series series(model);
    Frames frames(h5, model, run.vtk ? dir + "/vtk" : std::string());
    std::string failure;
    double element_steps = 0.0, next_frame = run.frame_interval;
    auto last_progress = Clock::now();
    series.sample(model, solver);
    frames.take(model, solver.time());
    try {
      while (solver.time() < run.end_time && solver.steps() < static_cast<std::size_t>(run.max_steps)) {
        solver.step();
        element_steps += static_cast<double>(solver.activeElements());
        const bool last = solver.time() >= run.end_time;
        if (solver.steps() % run.series_interval == 0 || last)
          series.sample(model, solver);
        if (run.frame_interval > 0 && solver.time() >= next_frame && !last) {
          frames.take(model, solver.time());
          next_frame += run.frame_interval * std::floor((solver.time() - next_frame) / run.frame_interval + 1);
        }
        if (terminal && Clock::now() - last_progress > std::chrono::milliseconds(250)) {
          progress(solver, run.end_time, start);
          last_progress = Clock::now();
        }
      }
      frames.take(model, solver.time());
    } catch (const std::exception &e) {
      failure = e.what();
      series.sample(model, solver);
    }
    if (terminal)
      std::cerr << "\r\033[K";

    // Whatever happened, the files hold everything computed so far and are whole.
    phase = "writing the files";
    series.write(h5);
    h5.attribute("/", "format", std::string("mesopen-run"));
    h5.attribute("/", "version", 1);
    h5.close();
    fs::rename(h5_path + ".tmp", h5_path);
    frames.writeCollection();
    const double wall = std::chrono::duration<double>(Clock::now() - start).count();
    summary["status"] = failure.empty() ? "completed" : "failed";
    if (!failure.empty())
      summary["failure"] = failure;
    summary["steps"] = solver.steps();
    summary["time"] = solver.time();
    summary["frames"] = frames.size();
    summary["wall_seconds"] = wall;
    summary["steps_per_second"] = solver.steps() / wall;
    summary["element_steps_per_second"] = element_steps / wall;
    const fem::Energy &e = solver.energy();
    summary["energy"] = {{"kinetic", e.kinetic},   {"internal", e.internal}, {"plastic", e.plastic},
                         {"viscous", e.viscous},   {"external", e.external}, {"balance_error", e.balance_error}};
    summary["projectile"] = {{"depth", series.last("projectile/depth")},
                             {"vy", series.last("projectile/vy")},
                             {"tilt", series.last("projectile/tilt")}};
    summary["files"] = {"run.h5", "summary.json"};
    if (run.vtk)
      summary["files"].push_back("vtk/run.pvd");
    writeText(dir + "/summary.json", summary.dump(2) + "\n");
    if (!failure.empty()) {
      std::cerr << "mesopen run: failed at t = " << solver.time() << " s, step " << solver.steps() << ": "
                << failure << "\n  what was computed is in " << dir << " (run.h5, summary.json)\n";
      return 1;
    }
    std::cout << "mesopen run: " << solver.steps() << " steps to t = " << solver.time() << " s, "
              << model.elements.size() << " elements in " << model.bodies.size() << " bodies, " << wall
              << " s; energy balance error " << e.balance_error << "\n  files in " << dir
              << ": run.h5 summary.json" << (run.vtk ? " vtk/run.pvd (ParaView)" : "") << "\n";
    return 0;
  } catch (const std::exception &e) {
    std::cerr << "mesopen run: failed while " << phase << ": " << e.what() << '\n';
    return 1;
  }
}

} // namespace mesopen
