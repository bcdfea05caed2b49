#include "run_files.hpp"

#include "output.hpp"
#include "version.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace mesopen {

namespace fs = std::filesystem;

namespace {

// The nodes held by the box's edges.
std::size_t fixedNodes(const fem::Model &model) {
  std::size_t n = 0;
  for (const fem::VelocityConstraint &c : model.constraints)
    if (c.name.starts_with("box "))
      n += c.nodes.size();
  return n;
}

std::string absoluteScenePath(const std::string &path) {
  return fs::absolute(path).lexically_normal().string();
}

// This process's peak resident memory, VmHWM in /proc/self/status (-1: not there).
std::int64_t peakMemoryBytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.starts_with("VmHWM:")) {
      std::istringstream fields(line.substr(6));
      std::int64_t kilobytes = -1;
      std::string unit;
      if (fields >> kilobytes >> unit && unit == "kB" && kilobytes >= 0)
        return kilobytes * 1024;
    }
  return -1;
}

// Each rank's count over `steps`, per step.
nlohmann::json perStep(const std::vector<double> &counts, std::size_t steps) {
  nlohmann::json j = nlohmann::json::array();
  for (double c : counts)
    j.push_back(c / static_cast<double>(std::max<std::size_t>(steps, 1)));
  return j;
}

std::vector<double> asDoubles(const std::vector<std::int64_t> &counts) {
  return std::vector<double>(counts.begin(), counts.end());
}

} // namespace

bool takeRunDirectory(const Scene &scene, const std::string &dir) {
  prepareOutputDirectory(dir, "run", {}); // made, or refused as another command's, before the lock
  if (!lockForProcess(dir + "/.run.lock", false))
    return false;
  prepareOutputDirectory(dir, "run",
                         {"summary.json", "run.h5", "run.h5.tmp", "vtk/run.pvd", "dem.data",
                          "mesopen.log", "liggghts.log", "instability.json", "instability-*"});
  std::error_code ec;
  for (const auto &f : fs::directory_iterator(dir + "/vtk", ec))
    if (f.path().filename().string().starts_with("frame_") ||
        f.path().filename().string().starts_with("disks_"))
      fs::remove(f.path(), ec);
  if (scene.run.vtk && scene.run.frame_interval > 0)
    prepareOutputDirectory(dir + "/vtk", "", {});
  return true;
}

void writeRunAttributes(H5File &h5, const Scene &scene, const std::string &status) {
  const RunSpec &run = scene.run;
  h5.attribute("/", "format", std::string("mesopen-run"));
  h5.attribute("/", "version", 1);
  h5.attribute("/", "program", std::string("mesopen ") + programVersion());
  h5.attribute("/", "status", status);
  h5.attribute("/", "representation",
               std::string(nameOf(run.representation, representation_names)));
  h5.attribute("/", "scene", composedScene(scene));
  h5.attribute("/", "seed", static_cast<std::uint64_t>(scene.target.seed));
  for (auto [name, value] : {std::pair{"velocity", run.velocity},
                             {"spin", run.spin},
                             {"end_time", run.end_time},
                             {"projectile_length", scene.projectile.length}})
    h5.attribute("/", name, value);
  // The impact's attitude, where it is not head-on (absent: 0).
  for (auto [name, value] :
       {std::pair{"obliquity", run.obliquity}, {"yaw", run.yaw}, {"offset", run.offset}})
    if (value != 0.0)
      h5.attribute("/", name, value);
  // The materials' parameters as the run used them: /materials/{projectile, grains}, the preset
  // or type, and each parameter as an attribute.
  h5.createGroup("/materials");
  for (const auto &[group, choice] : materialGroups(scene)) {
    const std::string g = std::string("/materials/") + group;
    h5.createGroup(g);
    h5.attribute(g, materialKey(*choice), choice->name);
    for (const auto &[name, value] : resolvedParameters(*choice))
      h5.attribute(g, name, value);
  }
}

nlohmann::json demFigures(const RunAssembly &run, const parallel::World &world) {
  const coupling::FeDemCoupling &coupled = *run.coupled;
  const coupling::DiskContactStatistics &c = coupled.contact().statistics();
  return {
      {"disks", std::llround(world.sum(static_cast<double>(run.dem->particles().size())))},
      {"fe_dem_contacts_last_step", std::llround(world.sum(static_cast<double>(c.contacts)))},
      {"deepest_fe_dem_overlap_over_element_size", world.max(c.deepest)},
      {"sudden_fe_dem_contacts", std::llround(world.sum(static_cast<double>(c.sudden)))},
      {"fe_dem_contacts_between_steps", std::llround(world.sum(static_cast<double>(c.not_due)))},
      {"work_on_disks", world.sum(c.work_on_disks)},
      {"disks_kinetic_energy", world.sum(coupled.disks().kineticEnergy())},
      {"windows", coupled.windows()},
      {"window", coupled.window()},
      {"seconds", coupled.seconds()}};
}

void writeLevels(H5File &h5, const fem::LevelCensus &census) {
  h5.createGroup("/levels");
  h5.attribute("/levels", "samples", static_cast<std::uint64_t>(census.samples()));
  for (int L = 1; L <= census.maxLevel(); ++L)
    h5.createGroup(std::string("/levels/L") + std::to_string(L));
  for (const auto &c : census.columns()) {
    const std::string name = "/levels/" + c.name;
    h5.write(name, c.values);
    h5.attribute(name, "unit", c.unit);
    h5.attribute(name, "meaning", c.meaning);
  }
}

nlohmann::json levelFigures(const fem::LevelCensus &census, const LoopResult &loop,
                            const fem::Contact *contact) {
  nlohmann::json j;
  const double elements = census.total("active_elements"), pairs = census.total("pairs");
  const double contact_seconds = contact ? contact->statistics().seconds : 0.0;
  const double contact_share = contact_seconds / std::max(loop.solver_seconds, 1e-300);
  j["samples"] = census.samples();
  j["mean_active_elements"] = elements / std::max<double>(census.samples(), 1.0);
  j["mean_pairs"] = pairs / std::max<double>(census.samples(), 1.0);
  j["contact_share_of_steps"] = contact_share;
  j["contact_node_element_share"] = census.total("contact_node_elements") / std::max(elements, 1.0);
  for (int L = 1; L <= census.maxLevel(); ++L) {
    std::string p("L"); // the census's columns of largest level L: "L<L>/..."
    p += std::to_string(L);
    p += '/';
    nlohmann::json l;
    std::vector<double> share, promoted;
    for (int k = 0; k <= L; ++k)
      share.push_back(census.total(p + "elements_level_" + std::to_string(k)) /
                      std::max(elements, 1.0));
    for (int k = 0; k < L; ++k)
      promoted.push_back(census.total(p + "ring_elements_to_level_" + std::to_string(k)) /
                         std::max(elements, 1.0));
    l["element_share_by_level"] = share;
    l["ring_share_by_level"] = promoted;
    l["mean_ring_elements"] =
        census.total(p + "ring_elements") / std::max<double>(census.samples(), 1.0);
    nlohmann::json by_levels;
    for (int a = 0; a <= L; ++a)
      for (int b = a; b <= L; ++b)
        by_levels[std::to_string(a) + "_" + std::to_string(b)] =
            census.total(p + "pairs_" + std::to_string(a) + "_" + std::to_string(b)) /
            std::max(pairs, 1.0);
    l["pair_share_by_levels"] = by_levels;
    const double element_ratio = census.total(p + "element_work") / std::max(elements, 1.0);
    const double pair_ratio = pairs > 0.0 ? census.total(p + "pair_work") / pairs : 1.0;
    l["element_work_ratio"] = element_ratio;
    l["pair_work_ratio"] = pair_ratio;
    l["projected_cost_ratio"] = (1.0 - contact_share) * element_ratio + contact_share * pair_ratio;
    l["whole_body_element_work_ratio"] =
        census.total(p + "whole_body_element_work") / std::max(elements, 1.0);
    l["whole_body_node_work_ratio"] =
        census.total(p + "whole_body_node_work") / std::max(census.total("active_nodes"), 1.0);
    l["pair_promoted_element_work_ratio"] =
        census.total(p + "pair_promoted_element_work") / std::max(elements, 1.0);
    l["pair_promoted_node_work_ratio"] =
        census.total(p + "pair_promoted_node_work") / std::max(census.total("active_nodes"), 1.0);
    j[p.substr(0, p.size() - 1)] = l;
  }
  return j;
}

RankFigures rankFigures(const RunAssembly &run, const LoopResult &loop) {
  const std::int64_t pair_steps =
      run.contact ? static_cast<std::int64_t>(run.contact->statistics().pair_steps) : 0;
  const std::int64_t halo =
      (run.contact ? static_cast<std::int64_t>(run.contact->statistics().halo_nodes) : 0) +
      (run.coupled ? static_cast<std::int64_t>(run.coupled->haloNodes()) : 0);
  const std::vector<std::int64_t> mine{loop.step_bytes,
                                       loop.max_step_bytes,
                                       loop.step_operations,
                                       loop.other_bytes,
                                       pair_steps,
                                       peakMemoryBytes(),
                                       halo,
                                       loop.step_messages};
  const std::vector<std::int64_t> all = run.solver->processes().allGather(mine);
  RankFigures f;
  f.steps = loop.counted_steps;
  std::vector<std::int64_t> *const fields[] = {
      &f.step_bytes,         &f.max_step_bytes,    &f.step_operations, &f.other_bytes,
      &f.contact_pair_steps, &f.peak_memory_bytes, &f.halo_node_steps, &f.step_messages};
  for (std::size_t k = 0; k < all.size(); ++k)
    fields[k % mine.size()]->push_back(all[k]);
  if (run.contact)
    f.contact = run.contact->statisticsOfAll();
  return f;
}

nlohmann::json partitionSummary(const fem::PartitionReport &p, const RankFigures &f) {
  nlohmann::json memory = nlohmann::json::array();
  for (std::int64_t m : f.peak_memory_bytes)
    memory.push_back(m >= 0 ? nlohmann::json(m) : nlohmann::json());
  return {{"method", p.bodies.size() > 1 ? "zoltan rcb" : "one rank"},
          {"bodies", p.bodies},
          {"active_elements", p.active_elements},
          {"element_steps", p.element_steps},
          {"imbalance", p.imbalance},
          {"run_imbalance", p.run_imbalance},
          {"rebalances", p.rebalances},
          {"forced_rebalances", p.forced},
          {"migrated_bodies", p.migrated_bodies},
          {"last_partition_imbalance_before", p.last_before},
          {"last_partition_imbalance_after", p.last_after},
          {"steps_measured", f.steps},
          {"active_elements_per_step", perStep(p.element_steps, f.steps)},
          {"active_nodes_per_step", perStep(p.node_steps, f.steps)},
          {"halo_nodes_per_step", perStep(asDoubles(f.halo_node_steps), f.steps)},
          {"contact_pairs_per_step", perStep(asDoubles(f.contact_pair_steps), f.steps)},
          {"bytes_received_per_step", perStep(asDoubles(f.step_bytes), f.steps)},
          {"max_bytes_received_in_a_step", f.max_step_bytes},
          {"collectives_per_step", perStep(asDoubles(f.step_operations), f.steps)},
          {"messages_per_step", perStep(asDoubles(f.step_messages), f.steps)},
          {"bytes_received_outside_steps_per_step", perStep(asDoubles(f.other_bytes), f.steps)},
          {"peak_memory_bytes", memory}};
}

nlohmann::json runSummary(const Scene &scene, const RunAssembly &run, const Series &series,
                          const Frames &frames, const LoopResult &loop, double wall, int ranks,
                          const RankFigures &rank_figures, const nlohmann::json &dem) {
  const fem::Model &model = run.model;
  const fem::Solver &solver = *run.solver;
  const fem::Energy &e = solver.energy();
  nlohmann::json j;
  j["command"] = "run";
  j["program"] = std::string("mesopen ") + programVersion();
  j["scene"] = absoluteScenePath(scene.path);
  j["composed_scene"] = composedScene(scene);
  for (const auto &[group, choice] : materialGroups(scene))
    j["materials"][group] = {{materialKey(*choice), choice->name},
                             {"parameters", resolvedParameters(*choice)}};
  j["seed"] = scene.target.seed;
  j["status"] = runStatus(loop);
  if (!loop.failure.empty())
    j["failure"] = loop.failure;
  j["run"] = {{"end_time", scene.run.end_time},
              {"velocity", scene.run.velocity},
              {"spin", scene.run.spin},
              {"obliquity", scene.run.obliquity},
              {"yaw", scene.run.yaw},
              {"offset", scene.run.offset},
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
  if (run.contact) {
    const fem::ContactStatistics &c = rank_figures.contact;
    j["contact"] = {{"seconds", c.seconds},
                    {"share_of_steps", c.seconds / std::max(loop.solver_seconds, 1e-9)},
                    {"deepest_penetration_over_element_size", c.max_depth},
                    {"deep_node_steps", c.deep},
                    {"sudden_contacts", c.sudden},
                    {"contacts_beneath_folds", c.beneath_folds},
                    {"last_step_pairs", c.pairs},
                    {"pair_searches", c.searches},
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
  j["files"] = {"run.h5", "summary.json", "scene.toml", "mesopen.log"};
  if (frames.vtk())
    j["files"].push_back("vtk/run.pvd");
  j["representation"] = nameOf(scene.run.representation, representation_names);
  j["ranks"] = ranks;
  j["partition"] = partitionSummary(solver.partition(), rank_figures);
  if (!dem.is_null()) {
    j["dem"] = dem;
    j["files"].push_back("dem.data");
    j["files"].push_back("liggghts.log");
  }
  return j;
}

void writeUnstartedSummary(const std::string &dir, const std::string &scene_path,
                           const std::string &status, const std::string &failure) {
  writeJson(dir + "/summary.json", {{"command", "run"},
                                    {"scene", absoluteScenePath(scene_path)},
                                    {"status", status},
                                    {"failure", failure}});
}

} // namespace mesopen
