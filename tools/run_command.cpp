// mesopen run SCENE -o DIR: the target and the projectile of a scene as finite-element bodies,
// integrated in time; run.h5 (series and frames), vtk/run.pvd, summary.json.
#include "commands.hpp"
#include "contact.hpp"
#include "coupling.hpp"
#include "generator.hpp"
#include "liggghts_dem.hpp"
#include "measures.hpp"
#include "mesh.hpp"
#include "output.hpp"
#include "projectile.hpp"
#include "run_output.hpp"
#include "scene.hpp"
#include "solver.hpp"
#include "stop_signals.hpp"
#include "writers.hpp"

#include <omp.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <unistd.h>

namespace mesopen {

namespace fs = std::filesystem;

namespace {

// Keys the scene sets that the chosen representation does not use: said on stderr, not refused
// (a scene may be switched between representations).
void warnIdleKeys(const Scene &scene, const std::string &path) {
  const toml::table root = parseToml(path);
  const bool disks = scene.run.grains && scene.run.representation != Representation::fe;
  std::vector<std::string> idle;
  if (!disks && root.contains("dem"))
    idle.push_back("[dem]");
  if (const toml::table *run = root["run"].as_table())
    for (const char *key : {"band_half_width", "band_depth"})
      if (scene.run.representation != Representation::hybrid && run->contains(key))
        idle.push_back(std::string("run.") + key);
  for (const std::string &what : idle)
    std::cerr << "mesopen run: warning: " << path << ": " << what
              << " does nothing with run.representation = \""
              << nameOf(scene.run.representation, representation_names) << "\"\n";
}

} // namespace

void checkRunnable(const Scene &scene, const std::string &where) {
  if (scene.run.grains && scene.target.mesh == MeshKind::none)
    throw InputError(where + ": target.mesh = \"none\" leaves the grains without elements; "
                             "allowed: \"quality\" or \"fan\" (or run.grains = false)");
  if (!scene.run.grains && scene.run.representation != Representation::fe)
    throw InputError(where + ": run.representation = \"dem\" or \"hybrid\" needs the "
                             "grains; allowed with run.grains = false: \"fe\"");
  if (!scene.projectile.enabled)
    throw InputError(where + ": projectile.enabled = false; `mesopen run` needs the projectile");
  // LIGGGHTS bins its neighbours by half the cut-off (largest disk diameter + skin) and exits
  // when a bin exceeds 100 times an extent of the box: its width, height, or the 2D slab, the
  // largest disk diameter (half the smallest grain's at least: inscribed disks are larger).
  if (scene.run.grains && scene.run.representation != Representation::fe && scene.dem.skin > 0.0) {
    const TargetSpec &t = scene.target;
    const double extent = std::min({t.width, t.height, 0.5 * t.diameter_min});
    const double largest = 0.99 * 200.0 * extent - t.diameter_max;
    auto number = [](double v) {
      std::ostringstream text;
      text << v;
      return text.str();
    };
    if (scene.dem.skin > largest)
      throw InputError(
          where + ": dem.skin = " + number(scene.dem.skin) +
          " m is too large for LIGGGHTS's neighbour bins in this box; allowed: 0 < skin <= " +
          number(std::max(largest, 0.0)) + " m (half of diameter + skin within 100 times " +
          "the box's width, height or half the smallest grain diameter)");
  }
}

namespace {

// The scene, checked for what a run needs. Throws InputError.
Scene prepareRun(const RunOptions &options) {
  Scene scene = readScene(options.scene);
  if (options.seed)
    scene.target.seed = *options.seed;
  checkRunnable(scene, options.scene);
  // LIGGGHTS reads the disks from the output directory through a script variable: a path it
  // would split or expand is refused before it starts (it exits the process on a bad command).
  const std::string out = fs::absolute(options.out_dir).string();
  if (scene.run.grains && scene.run.representation != Representation::fe &&
      out.find_first_of(" \t\n\"'$#&") != std::string::npos)
    throw InputError(options.scene + ": run.representation = \"" +
                     nameOf(scene.run.representation, representation_names) +
                     "\" needs an output directory without spaces or any of \"'$#& (LIGGGHTS "
                     "reads the disks from it); it is '" +
                     out + "'");
  warnIdleKeys(scene, options.scene);
  return scene;
}

// The output directory taken for this run and cleared of an earlier run's files (frames
// included). Its lock, DIR/.run.lock, is held to the end of the process: a second run into the
// directory would remove this one's run.h5.tmp and frames. False when another run holds it.
bool takeOutput(const Scene &scene, const std::string &dir) {
  prepareOutputDirectory(dir, "run", {}); // made, or refused as another command's, before the lock
  if (!lockForProcess(dir + "/.run.lock", false))
    return false;
  prepareOutputDirectory(dir, "run",
                         {"summary.json", "run.h5", "run.h5.tmp", "vtk/run.pvd", "dem.data",
                          "liggghts.log", "instability.json", "instability-*"});
  std::error_code ec;
  for (const auto &f : fs::directory_iterator(dir + "/vtk", ec))
    if (f.path().filename().string().starts_with("frame_") ||
        f.path().filename().string().starts_with("disks_"))
      fs::remove(f.path(), ec);
  if (scene.run.vtk && scene.run.frame_interval > 0)
    prepareOutputDirectory(dir + "/vtk", "", {});
  return true;
}

// Which grains are meshed: every one (fe), none (dem), or those whose centroids lie within the
// band around the projectile's path (hybrid): within band_half_width of its axis, from the surface
// down to band_depth below its tip (by default the depth the run ends at, plus the half-width:
// deeper grains carry the waves as disks do, and the projectile does not reach them).
std::vector<char> meshedGrains(const Scene &scene, const Target &target,
                               const PlacedProjectile &p) {
  const std::size_t n = target.grains.size();
  switch (scene.run.representation) {
  case Representation::fe:
    return std::vector<char>(n, 1);
  case Representation::dem:
    return std::vector<char>(n, 0);
  case Representation::hybrid:
    break;
  }
  // By default one and a half projectile diameters: the narrowest band of those measured whose run
  // 6 stays within the fully meshed runs' seed-to-seed range on every measure (docs/coupling.md)
  const double half =
      scene.run.band_half_width > 0.0 ? scene.run.band_half_width : 1.5 * p.shape.diameter;
  const double depth = scene.run.band_depth > 0.0 ? scene.run.band_depth
                       : scene.run.end_depth > 0.0
                           ? scene.run.end_depth * scene.projectile.length + half
                           : HUGE_VAL;
  const double bottom = *std::min_element(p.mesh.y.begin(), p.mesh.y.end()) - depth;
  const GrainFigures f = grainFigures(target.grains);
  std::vector<char> meshed(n);
  for (std::size_t g = 0; g < n; ++g)
    meshed[g] = std::abs(f.centroid_x[g] - p.offset_x) <= half && f.centroid_y[g] >= bottom;
  return meshed;
}

// The meshes of the grains marked in `meshed`, in grain order: the target's own when it was
// generated meshed (fe), else those grains meshed now (the generator made polygons only; a hybrid
// band may cover every grain).
Meshes grainMeshes(const Scene &scene, const Target &target, const std::vector<char> &meshed) {
  if (target.mesh.bodies() == meshed.size())
    return target.mesh;
  Polygons chosen;
  for (std::size_t g = 0; g < meshed.size(); ++g)
    if (meshed[g]) {
      const auto first = target.grains.x.begin() + static_cast<long>(target.grains.offset[g]);
      const auto last = target.grains.x.begin() + static_cast<long>(target.grains.offset[g + 1]);
      const auto first_y = target.grains.y.begin() + static_cast<long>(target.grains.offset[g]);
      chosen.add(std::vector<double>(first, last),
                 std::vector<double>(first_y, first_y + (last - first)));
    }
  return meshGrains(chosen, scene.target.mesh, scene.target.mesh_size, scene.target.min_angle);
}

// The projectile's and the grains' meshes as one: the projectile is body 0, the grains follow in
// order (their node indices shifted past those before).
Meshes runMeshes(const Meshes *grains, const PlacedProjectile &p) {
  Meshes all;
  all.x = p.mesh.x, all.y = p.mesh.y, all.tri = p.mesh.tri;
  all.node_offset.push_back(all.x.size());
  all.tri_offset.push_back(all.tri.size() / 3);
  if (!grains)
    return all;
  const Meshes &g = *grains;
  for (std::size_t b = 0; b < g.bodies(); ++b) {
    const auto shift = static_cast<std::uint32_t>(all.x.size() - g.node_offset[b]);
    all.x.insert(all.x.end(), g.x.begin() + g.node_offset[b], g.x.begin() + g.node_offset[b + 1]);
    all.y.insert(all.y.end(), g.y.begin() + g.node_offset[b], g.y.begin() + g.node_offset[b + 1]);
    for (std::size_t k = 3 * g.tri_offset[b]; k < 3 * g.tri_offset[b + 1]; ++k)
      all.tri.push_back(g.tri[k] + shift);
    all.node_offset.push_back(all.x.size());
    all.tri_offset.push_back(all.tri.size() / 3);
  }
  return all;
}

// The grain nodes on the box's left, right and bottom edges (within 1e-3 mesh sizes), held at rest;
// with smooth walls held normal to their edge only (the corners at rest).
std::vector<fem::VelocityConstraint> boxEdges(const fem::Model &model, const TargetSpec &box,
                                              bool smooth) {
  const double tol = 1e-3 * box.mesh_size;
  fem::VelocityConstraint fixed{"box edges", {}, true, true, 0.0, 0.0};
  fem::VelocityConstraint sides{"box sides", {}, true, false, 0.0, 0.0};
  fem::VelocityConstraint bottom{"box bottom", {}, false, true, 0.0, 0.0};
  for (std::size_t a = model.bodies[0].node_end; a < model.nodes.size(); ++a) {
    const double x = model.nodes.x[a], y = model.nodes.y[a];
    const bool side = x <= tol || x >= box.width - tol, low = y <= tol;
    const auto node = static_cast<std::uint32_t>(a);
    if (!smooth && (side || low))
      fixed.nodes.push_back(node);
    if (smooth && side)
      sides.nodes.push_back(node);
    if (smooth && low)
      bottom.nodes.push_back(node);
  }
  if (!smooth)
    return {fixed};
  return {sides, bottom};
}

// One model of the projectile (body 0, "projectile") and the meshed grains ("grain-<g>", g the
// grain's number in the target), with the scene's materials, the projectile's initial velocity
// (0, -v) and spin, and the fixed box edges.
fem::Model buildRunModel(const Scene &scene, const Target *target, const PlacedProjectile &p,
                         const std::vector<char> &meshed) {
  const Meshes grains = target ? grainMeshes(scene, *target, meshed) : Meshes{};
  const Meshes all = runMeshes(target ? &grains : nullptr, p);
  std::vector<std::string> names{"projectile"};
  for (std::size_t g = 0; g < meshed.size(); ++g)
    if (meshed[g])
      names.push_back("grain-" + std::to_string(g));
  std::vector<std::unique_ptr<fem::Material>> materials;
  materials.push_back(
      fem::makeMaterial(scene.projectile_material.name, scene.projectile_material.parameters));
  materials.push_back(
      fem::makeMaterial(scene.grain_material.name, scene.grain_material.parameters));
  std::vector<int> body_material(all.bodies(), 1);
  body_material[0] = 0;
  fem::Model model = fem::buildModel({all.node_offset, all.tri_offset, all.x, all.y, all.tri},
                                     std::move(materials), body_material, names);
  if (target && scene.run.fix_edges)
    for (fem::VelocityConstraint &c : boxEdges(model, scene.target, scene.run.smooth_walls))
      model.constraints.push_back(std::move(c));
  fem::setBodyVelocity(model, 0, 0.0, -scene.run.velocity, scene.run.spin);
  if (scene.run.constant_velocity) {
    fem::VelocityConstraint driven{"projectile driven", {}, true, true, 0.0, -scene.run.velocity};
    for (std::size_t a = model.bodies[0].node_begin; a < model.bodies[0].node_end; ++a)
      driven.nodes.push_back(static_cast<std::uint32_t>(a));
    model.constraints.push_back(std::move(driven));
  }
  return model;
}

// The variables of liggghts-inputs/dem.in: the disks' data file, the [dem] law, [contact]'s
// friction between grains, the box's walls.
std::vector<std::pair<std::string, std::string>> demVariables(const Scene &scene,
                                                              const std::string &data) {
  const DemSpec &d = scene.dem;
  auto text = [](double v) {
    char s[32];
    std::snprintf(s, sizeof s, "%.17g", v);
    return std::string(s);
  };
  // Half a grain: a disk the projectile drives at 1500 m/s crosses a tenth of a grain (the skin's
  // half) in about two of the disks' steps, and each crossing rebuilds every neighbour list (run 6
  // as disks: 3.1 s with a tenth, 2.5 s with half or more, the pairs' own cost barely changed).
  const double skin = d.skin > 0.0 ? d.skin : 0.5 * scene.target.meanDiameter();
  return {{"data", data},
          {"kn", text(d.stiffness)},
          {"kt", text(d.tangential_stiffness)},
          {"gn", text(d.damping)},
          {"gt", text(d.tangential_damping)},
          {"mu", text(scene.contact.friction)},
          {"mu_wall", text(scene.run.smooth_walls ? 0.0 : scene.contact.friction)},
          {"hertz", d.normal_law == NormalLaw::hertz ? "1" : "0"},
          {"rolling", text(d.rolling_friction)},
          {"h", text(d.hertz_length)},
          // the effective mass of a pair of mean grains, m / 2
          {"mref", text(0.25 * M_PI * scene.target.density * scene.target.meanDiameter() *
                        scene.target.meanDiameter() / 2.0)},
          {"xlo", "0"},
          {"xhi", text(scene.target.width)},
          {"ylo", "0"},
          {"skin", text(skin)},
          {"gravity", "0"},
          {"dt", "1e-9"}};
}

// Contact of the scene: Coulomb coefficients per pair of materials (0 the projectile's, 1 the
// grains'), the box's left, right and bottom walls when there is a target.
fem::ContactSettings contactSettings(const Scene &scene, bool walls) {
  const ContactSpec &c = scene.contact;
  fem::ContactSettings s;
  s.friction = {0.0, c.projectile_friction, c.projectile_friction, c.friction};
  // grains meet the walls; the projectile does not reach them
  s.wall_friction = scene.run.smooth_walls ? 0.0 : c.friction;
  s.stiffness = c.stiffness;
  s.damping = c.damping;
  if (walls)
    s.wall_left = 0.0, s.wall_right = scene.target.width, s.wall_bottom = 0.0;
  return s;
}

// One line on a terminal, rewritten in place at most four times a second: step, simulated time,
// depth, step size, speed and time left (from the simulated time or the depth, whichever is
// further along).
class Progress {
public:
  Progress(bool on, double end_time, double end_depth)
      : on_(on), end_time_(end_time), end_depth_(end_depth) {}
  bool due() const { return on_ && Clock::now() - last_ >= std::chrono::milliseconds(250); }
  void show(const fem::Solver &solver, double depth) {
    last_ = Clock::now();
    const double wall = secondsSince(start_), t = solver.time();
    const double done = std::max(t / end_time_, end_depth_ > 0.0 ? depth / end_depth_ : 0.0);
    std::fprintf(stderr,
                 "\r\033[Kmesopen run: step %zu, t = %.3f ns, depth %.3f mm, dt = %.3g ps, "
                 "%.0f steps/s, %.0f %% done, ETA %.0f s",
                 solver.steps(), 1e9 * t, 1e3 * depth, 1e12 * solver.dt(),
                 solver.steps() / std::max(wall, 1e-9), 100.0 * done,
                 std::max(0.0, wall * (1.0 - done) / std::max(done, 1e-30)));
  }
  void clear() const {
    if (on_)
      std::fprintf(stderr, "\r\033[K");
  }

private:
  bool on_;
  double end_time_, end_depth_;
  Clock::time_point start_ = Clock::now(), last_ = Clock::now();
};

// SIGINT or SIGTERM during the time loop: the loop ends after its step and the files are written
// as for a failure; during the set-up (target, meshes, model, LIGGGHTS) the run ends at the next
// phase with status interrupted (stopIfAsked). A second signal ends the process at once.
// A signal received during the set-up, found between its phases.
struct Interrupted : std::runtime_error {
  using std::runtime_error::runtime_error;
};
void stopIfAsked(const coupling::World &world, const std::string &phase) {
  // every rank ends at the same phase (mpirun passes the signal to each, not at the same moment)
  const double s = world.size > 1 ? world.max(stopSignal()) : stopSignal();
  if (s != 0) {
    setStopSignal(static_cast<int>(s));
    throw Interrupted(stopSignalName() + " during the " + phase);
  }
}

struct LoopResult {
  std::string failure;      // empty when the run reached its end
  bool interrupted = false; // by a signal
  std::string end;          // what ended it: end_time, end_depth or max_steps
  double element_steps = 0.0;
  double seconds = 0.0, solver_seconds = 0.0; // the whole loop; the steps alone
};

// The time loop: step, sample the series, take frames, show progress; until run.end_time,
// run.end_depth or run.max_steps, a failure (an inverted element, a frame that cannot be
// written) or a signal to stop.
LoopResult timeLoop(const Scene &scene, const fem::Model &model, fem::Solver &solver,
                    Series &series, Frames &frames, Progress &progress) {
  const RunSpec &run = scene.run;
  LoopResult result;
  const auto start = Clock::now();
  const auto max_steps = static_cast<std::size_t>(run.max_steps);
  const auto every = static_cast<std::size_t>(run.series_interval);
  const double end_depth = run.end_depth * scene.projectile.length;
  // (the depth is the series' own when it was just sampled)
  auto ended = [&](bool sampled) {
    if (solver.time() >= run.end_time)
      result.end = "end_time";
    else if (end_depth > 0.0 &&
             (sampled ? series.last("projectile/depth") : series.depth(model)) >= end_depth)
      result.end = "end_depth";
    else if (solver.steps() >= max_steps)
      result.end = "max_steps";
    return !result.end.empty();
  };
  try {
    series.sample(model, solver);
    frames.offer(model, solver, true);
    for (bool last = ended(true); !last;) {
      if (stopSignal() != 0) {
        result.interrupted = true;
        result.failure = std::string("stopped by ") + stopSignalName() + " at step " +
                         std::to_string(solver.steps());
        break;
      }
      const auto step_start = Clock::now();
      const double before = solver.time();
      solver.step();
      if (!(solver.time() > before)) {
        char text[200];
        std::snprintf(text, sizeof text,
                      "step %zu did not advance the time (t = %.6g s, dt = %.6g s): the stable "
                      "step has fallen to nothing",
                      solver.steps(), before, solver.dt());
        throw std::runtime_error(text);
      }
      result.solver_seconds += secondsSince(step_start);
      result.element_steps += static_cast<double>(solver.activeElements());
      const bool due = solver.steps() % every == 0;
      if (due)
        series.sample(model, solver);
      last = ended(due);
      if (last && !due)
        series.sample(model, solver);
      frames.offer(model, solver, last);
      if (progress.due())
        progress.show(solver, series.depth(model));
    }
  } catch (const std::exception &e) {
    result.failure = e.what();
  }
  progress.clear();
  result.seconds = secondsSince(start);
  return result;
}

// The nodes held by the box's edges.
std::size_t fixedNodes(const fem::Model &model) {
  std::size_t n = 0;
  for (const fem::VelocityConstraint &c : model.constraints)
    if (c.name.starts_with("box "))
      n += c.nodes.size();
  return n;
}

std::string runStatus(const LoopResult &loop) {
  return loop.failure.empty() ? "completed" : loop.interrupted ? "interrupted" : "failed";
}

// summary.json: what ran, how it ended, its figures and files.
nlohmann::json runSummary(const Scene &scene, const RunOptions &options, const fem::Model &model,
                          const fem::Solver &solver, const Series &series, const Frames &frames,
                          const LoopResult &loop, const fem::Contact *contact, double wall) {
  const fem::Energy &e = solver.energy();
  nlohmann::json j;
  j["command"] = "run";
  j["scene"] = fs::absolute(options.scene).lexically_normal().string();
  j["seed"] = scene.target.seed;
  j["status"] = runStatus(loop);
  if (!loop.failure.empty())
    j["failure"] = loop.failure;
  j["run"] = {{"end_time", scene.run.end_time},
              {"velocity", scene.run.velocity},
              {"spin", scene.run.spin},
              {"grains", scene.run.grains},
              {"projectile_material", scene.projectile_material.name},
              {"grain_material", scene.grain_material.name}};
  j["model"] = {{"bodies", model.bodies.size()},
                {"nodes", model.nodes.size()},
                {"elements", model.elements.size()},
                {"fixed_nodes", fixedNodes(model)}};
  if (!loop.end.empty())
    j["ended_by"] = loop.end;
  j["steps"] = solver.steps();
  j["time"] = solver.time();
  j["threads"] = omp_get_max_threads();
  j["wall_seconds"] = wall;
  j["loop_seconds"] = loop.seconds;
  j["steps_per_second"] = solver.steps() / std::max(loop.seconds, 1e-9);
  j["solver_seconds"] = loop.solver_seconds;
  j["element_steps_per_second"] = loop.element_steps / std::max(loop.solver_seconds, 1e-9);
  // Bodies at rest are skipped: the element-steps computed, against every element every step.
  j["element_steps"] = loop.element_steps;
  j["active_element_share"] =
      loop.element_steps /
      std::max(1.0, static_cast<double>(model.elements.size()) * solver.steps());
  j["ns_per_element_step"] = 1e9 * loop.solver_seconds / std::max(loop.element_steps, 1.0);
  j["energy"] = {{"kinetic", e.kinetic},
                 {"internal", e.internal},
                 {"plastic", e.plastic},
                 {"viscous", e.viscous},
                 {"friction", e.friction},
                 {"contact", e.contact},
                 {"external", e.external},
                 {"eroded", e.eroded},
                 {"mass_scaling", e.mass_scaling},
                 {"initial", e.initial},
                 {"balance_error", e.balance_error}};
  j["eroded_elements"] = solver.erodedElements();
  j["collapsed_elements"] = solver.collapsedElements(); // of those, eroded for a collapsed step
  if (scene.run.mass_scaling_step_ratio > 0.0) {
    double mass = 0.0;
    for (double m : model.nodes.mass)
      mass += m;
    j["mass_scaling"] = {
        {"elements", solver.massScaledElements()},
        {"added_mass", solver.addedMass()},
        {"added_mass_share", solver.addedMass() / std::max(mass - solver.addedMass(), 1e-300)},
        {"projectile_added_mass", solver.addedMass(0)}};
  }
  if (contact) {
    const fem::ContactStatistics &c = contact->statistics();
    j["contact"] = {{"seconds", c.seconds},
                    {"share_of_steps", c.seconds / std::max(loop.solver_seconds, 1e-9)},
                    {"deepest_penetration_over_element_size", c.max_depth},
                    {"deep_node_steps", c.deep},
                    {"sudden_contacts", c.sudden},
                    {"last_step_pairs", c.pairs},
                    {"pair_sides_skipped_as_clear",
                     static_cast<double>(c.skipped) / std::max<double>(c.sides, 1.0)},
                    {"pair_sides_hot_nodes_only",
                     static_cast<double>(c.partial) / std::max<double>(c.sides, 1.0)},
                    {"last_step_contacts", c.contacts}};
  }
  j["projectile"] = {{"depth", series.last("projectile/depth")},
                     {"tilt", series.last("projectile/tilt")},
                     {"vx", series.last("projectile/vx")},
                     {"vy", series.last("projectile/vy")},
                     {"rotational_momentum", series.last("projectile/rotational_momentum")}};
  j["samples"] = series.size();
  j["frames"] = frames.size();
  j["files"] = {"run.h5", "summary.json"};
  if (frames.vtk())
    j["files"].push_back("vtk/run.pvd");
  return j;
}

// The element work shared by the MPI ranks (fem::Sharing): all-gathers over MPI_COMM_WORLD.
class MpiSharing final : public fem::Sharing {
public:
  explicit MpiSharing(const coupling::World &world) : rank_(world.rank), size_(world.size) {}
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  std::vector<double> allGather(const std::vector<double> &mine) const override {
    std::vector<double> all = mine;
    coupling::allGather(all, MPI_COMM_WORLD);
    return all;
  }

private:
  int rank_, size_;
};

// Everything a run does once the scene is read: target, model, time loop, files.
int simulate(const Scene &scene, const RunOptions &options, const coupling::World &world,
             Clock::time_point start) {
  const RunSpec &run = scene.run;
  const bool writer = world.rank == 0; // the files are rank 0's
  const std::string &dir = options.out_dir, h5_path = dir + "/run.h5";
  GeneratorReport report;
  std::unique_ptr<Target> target;
  if (run.grains) {
    // With disks, the grains to mesh are chosen first and meshed alone (grainMeshes).
    TargetSpec spec = scene.target;
    if (run.representation != Representation::fe)
      spec.mesh = MeshKind::none;
    target = std::make_unique<Target>(generateTarget(spec, report));
    stopIfAsked(world, "target's generation");
  }
  const Polygons no_grains;
  const PlacedProjectile projectile = placeProjectile(
      scene.projectile, scene.target.mesh_size, scene.target, target ? target->grains : no_grains);
  const std::vector<char> meshed =
      target ? meshedGrains(scene, *target, projectile) : std::vector<char>{};
  fem::Model model = buildRunModel(scene, target.get(), projectile, meshed);
  stopIfAsked(world, "model's assembly");
  const bool walls = target != nullptr;
  // The grains not meshed are LIGGGHTS's disks, coupled to the FE bodies.
  std::unique_ptr<coupling::LiggghtsDem> dem;
  std::unique_ptr<coupling::FeDemCoupling> coupled;
  if (target && std::find(meshed.begin(), meshed.end(), 0) != meshed.end()) {
    if (writer)
      writeLiggghtsData(dir + "/dem.data", *target,
                        targetDisks(*target, scene.dem.disk_size, meshed, &projectile));
    world.barrier();
    dem = std::make_unique<coupling::LiggghtsDem>(shareDirectory() + "/liggghts-inputs/dem.in",
                                                  demVariables(scene, dir + "/dem.data"),
                                                  dir + "/liggghts.log", MPI_COMM_WORLD);
  }
  target.reset();
  const MpiSharing sharing(world);
  const double dem_step = dem ? dem->stableStep() : HUGE_VAL; // every rank calls it
  fem::Solver solver(model, {.safety = run.safety,
                             .viscosity_linear = run.viscosity_linear,
                             .viscosity_quadratic = run.viscosity_quadratic,
                             .anti_locking = run.anti_locking,
                             .max_dt = dem_step,
                             .erode_dt_ratio = run.erode_step_ratio,
                             .mass_scaling_dt_ratio = run.mass_scaling_step_ratio,
                             .sharing = world.size > 1 ? &sharing : nullptr});
  solver.endAt(run.end_time);
  std::unique_ptr<fem::Contact> contact;
  if (scene.contact.enabled) {
    contact = std::make_unique<fem::Contact>(model, contactSettings(scene, walls));
    solver.addForceProvider(contact.get());
  }
  if (dem) {
    coupling::DiskContactSettings disk{scene.contact.stiffness, scene.contact.damping, {}};
    disk.friction.assign(model.bodies.size(), scene.contact.friction);
    disk.friction[0] = scene.contact.projectile_friction;
    // Windows up to the disks' stable step (a longer one is refused: the disks' own contacts
    // would be unstable).
    if (scene.dem.step > dem_step) {
      char text[160];
      std::snprintf(text, sizeof text,
                    ": dem.step = %.6g s is longer than the disks' stable step, %.6g s (a tenth of "
                    "the lightest disk's contact time); allowed: 0 to %.6g [s]",
                    scene.dem.step, dem_step, dem_step);
      throw InputError(options.scene + text);
    }
    coupled = std::make_unique<coupling::FeDemCoupling>(
        model, *dem, disk, scene.dem.step > 0.0 ? scene.dem.step : dem_step);
    solver.addForceProvider(coupled.get());
  }

  stopIfAsked(world, "set-up"); // signals are caught from the start of the set-up
  std::optional<H5File> h5;
  if (writer)
    h5.emplace(H5File::create(h5_path + ".tmp"));
  Series series(model);
  // Every rank takes the frames (they gather the disks to rank 0); rank 0 writes them.
  Frames frames(h5 ? &*h5 : nullptr, model, run.frame_interval,
                run.vtk && writer ? dir + "/vtk" : std::string());
  if (coupled)
    frames.addDisks(coupled.get());
  Progress progress(writer && !options.quiet && isatty(STDERR_FILENO), run.end_time,
                    run.end_depth * scene.projectile.length);
  const LoopResult loop = timeLoop(scene, model, solver, series, frames, progress);
  catchStopSignals(false);

  // Whatever happened, the files hold everything computed so far and are whole.
  if (writer) {
    series.write(*h5);
    h5->attribute("/", "format", std::string("mesopen-run"));
    h5->attribute("/", "version", 1);
    h5->attribute("/", "status", runStatus(loop));
    h5->attribute("/", "seed", static_cast<std::uint64_t>(scene.target.seed));
    for (auto [name, value] : {std::pair{"velocity", run.velocity},
                               {"spin", run.spin},
                               {"end_time", run.end_time},
                               {"projectile_length", scene.projectile.length}})
      h5->attribute("/", name, value);
    h5->close();
  }
  nlohmann::json dem_figures; // over all ranks' disks: every rank takes part
  if (coupled) {
    const coupling::DiskContactStatistics &c = coupled->contact().statistics();
    dem_figures = {
        {"disks", std::llround(world.sum(static_cast<double>(dem->particles().size())))},
        {"fe_dem_contacts_last_step", std::llround(world.sum(static_cast<double>(c.contacts)))},
        {"deepest_fe_dem_overlap_over_element_size", world.max(c.deepest)},
        {"sudden_fe_dem_contacts", std::llround(world.sum(static_cast<double>(c.sudden)))},
        {"work_on_disks", world.sum(c.work_on_disks)},
        {"disks_kinetic_energy", world.sum(coupled->disks().kineticEnergy())},
        {"windows", coupled->windows()},
        {"window", coupled->window()},
        {"seconds", coupled->seconds()}};
  }
  if (!writer)
    return loop.failure.empty() ? 0 : loop.interrupted ? 128 + stopSignal() : 1;
  fs::rename(h5_path + ".tmp", h5_path);
  frames.writeCollection();
  const double wall = secondsSince(start);
  nlohmann::json summary =
      runSummary(scene, options, model, solver, series, frames, loop, contact.get(), wall);
  summary["representation"] = nameOf(scene.run.representation, representation_names);
  summary["ranks"] = world.size;
  if (coupled) {
    summary["dem"] = dem_figures;
    summary["files"].push_back("dem.data");
    summary["files"].push_back("liggghts.log");
  }
  writeJson(dir + "/summary.json", summary);

  if (loop.interrupted) {
    std::cerr << "mesopen run: " << loop.failure << ", t = " << solver.time()
              << " s\n  what was computed up to there is in " << dir << " (run.h5, summary.json)\n";
    return 128 + stopSignal();
  }
  if (!loop.failure.empty()) {
    std::cerr << "mesopen run: failed at t = " << solver.time() << " s, step " << solver.steps()
              << ": " << loop.failure << "\n  what was computed up to there is in " << dir
              << " (run.h5, summary.json)\n";
    return 1;
  }
  std::cout << "mesopen run: " << solver.steps() << " steps to t = " << solver.time() << " s, "
            << model.elements.size() << " elements in " << model.bodies.size() << " bodies, "
            << wall << " s (" << solver.steps() / std::max(loop.seconds, 1e-9)
            << " steps/s); energy balance error " << solver.energy().balance_error
            << "\n  files in " << dir << ": run.h5 summary.json"
            << (frames.vtk() ? " vtk/run.pvd (ParaView)" : "") << "\n";
  return 0;
}

} // namespace

int runCommand(const RunOptions &options) {
  const auto start = Clock::now();
  Scene scene;
  coupling::World world;
  try {
    scene = prepareRun(options);
    // Under mpirun every rank runs the scene; rank 0 writes the files.
    world = coupling::world(scene.run.grains && scene.run.representation != Representation::fe);
  } catch (const InputError &e) {
    std::cerr << "mesopen run: " << e.what() << '\n';
    return 2;
  }
  // Rank 0 takes the output directory; the other ranks wait for it and end as it does. A
  // directory in use is exit 1, as for a campaign: the input is good, the run can be made later.
  int refused = 0;
  if (world.rank == 0) {
    try {
      if (!takeOutput(scene, options.out_dir)) {
        std::cerr << "mesopen run: " << options.out_dir
                  << " is in use by another mesopen run; allowed: another output directory, or "
                     "this one once that run has ended\n";
        refused = 1;
      }
    } catch (const InputError &e) {
      std::cerr << "mesopen run: " << e.what() << '\n';
      refused = 2;
    }
  }
  if (const int code = static_cast<int>(world.max(refused)))
    return code;
  if (options.threads)
    omp_set_num_threads(*options.threads);
  catchStopSignals(true); // to the end of the time loop
  try {
    return simulate(scene, options, world, start);
  } catch (const Interrupted &e) {
    // during the set-up: no run.h5, a summary saying so
    std::cerr << "mesopen run: " << e.what() << '\n';
    if (world.rank == 0)
      writeJson(options.out_dir + "/summary.json",
                {{"command", "run"},
                 {"scene", fs::absolute(options.scene).lexically_normal().string()},
                 {"status", "interrupted"},
                 {"failure", e.what()}});
    return 128 + stopSignal();
  } catch (const InputError &e) {
    // found once the target or LIGGGHTS is made (dem.step against the disks' stable step): bad
    // input all the same; no run.h5 or summary.json is written
    std::cerr << "mesopen run: " << e.what() << '\n';
    return 2;
  } catch (const std::exception &e) {
    // Before the time loop (target, model) or while writing the files: no run.h5, a summary
    // (rank 0's, the files' writer).
    std::cerr << "mesopen run: failed: " << e.what() << '\n';
    if (world.rank != 0)
      return 1;
    std::error_code ec;
    fs::remove(options.out_dir + "/run.h5.tmp", ec);
    try {
      writeJson(options.out_dir + "/summary.json",
                {{"command", "run"},
                 {"scene", fs::absolute(options.scene).lexically_normal().string()},
                 {"status", "failed"},
                 {"failure", e.what()}});
    } catch (const std::exception &) {
      // the directory itself cannot be written: the message above is all there is
    }
    return 1;
  }
}

} // namespace mesopen
