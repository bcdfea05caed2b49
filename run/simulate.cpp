#include "simulate.hpp"

#include "checkpoint.hpp"
#include "h5file.hpp"
#include "run_assembly.hpp"
#include "run_files.hpp"
#include "run_output.hpp"
#include "stop_signals.hpp"

#include <algorithm>
#include <filesystem>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace mesopen {

// The census of levels (run.level_census_interval) for every largest level from 1 to this.
constexpr int census_max_level = 4;

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

// The element work's partition among the ranks, for the log: per rank the bodies owned and their
// active elements at the end, the element-steps over the run, the imbalances and rebalances.
std::string partitionLine(const fem::PartitionReport &p) {
  std::ostringstream line;
  line << "element work over " << p.bodies.size() << " ranks (bodies / active elements / "
       << "element-steps):";
  for (std::size_t r = 0; r < p.bodies.size(); ++r)
    line << (r ? "," : "") << " rank " << r << " " << p.bodies[r] << " / " << p.active_elements[r]
         << " / " << p.element_steps[r];
  line << "; imbalance " << p.imbalance << " (over the run " << p.run_imbalance << "); "
       << p.rebalances << " rebalances (" << p.forced << " forced), " << p.migrated_bodies
       << " bodies moved; the last partition took the imbalance from " << p.last_before << " to "
       << p.last_after;
  return line.str();
}

} // namespace

RunReport simulate(const Scene &scene, const RunPlace &place, const parallel::World &world,
                   bool resume) {
  const RunSpec &run = scene.run;
  const bool writer = world.rank == 0; // the files are rank 0's
  const std::string &dir = place.dir, h5_path = dir + "/run.h5";
  catchStopSignals(true); // to the end of the time loop
  if (writer)
    writeText(dir + "/scene.toml", composedScene(scene));
  RunAssembly assembly(scene, dir, place.liggghts_script, world,
                       resume ? checkpointRestart(dir) : std::string());
  const fem::Model &model = assembly.model;
  const fem::Solver &solver = *assembly.solver;
  stopIfAsked(world, "set-up");

  std::optional<H5File> h5;
  if (writer)
    h5.emplace(H5File::create(h5_path + ".tmp"));
  Series series(model);
  // Every rank takes the frames (they gather the disks to rank 0); rank 0 writes them.
  Frames frames(h5 ? &*h5 : nullptr, model, run.frame_interval,
                run.vtk && writer ? dir + "/vtk" : std::string());
  if (assembly.coupled)
    frames.addDisks(assembly.coupled.get());
  if (writer && place.log)
    place.log->line(std::to_string(model.bodies.size()) + " bodies, " +
                    std::to_string(model.nodes.size()) + " nodes, " +
                    std::to_string(model.elements.size()) + " elements (" +
                    nameOf(run.representation, representation_names) + "); the time loop " +
                    (resume ? "continues" : "starts"));
  // The checkpoints (a new run's), or the state of the last one and run.h5 so far (a run
  // continued).
  Checkpoints checkpoints(scene, dir, assembly, series, frames, h5 ? &*h5 : nullptr, world, resume);
  Progress progress(writer && place.progress, writer ? place.log : nullptr, run.end_time,
                    run.end_depth * scene.projectile.length, run.frame_interval,
                    model.elements.size());
  if (assembly.coupled)
    progress.countByTheStep([&coupled = *assembly.coupled] { return coupled.seconds(); });
  // The census of levels covers the steps this process takes (not those before a checkpoint).
  std::optional<fem::LevelCensus> census;
  if (run.level_census_interval > 0)
    census.emplace(model, census_max_level);
  RunReport report;
  report.loop = timeLoop(scene, model, *assembly.solver, series, frames, progress, checkpoints,
                         census ? &*census : nullptr, assembly.contact.get());
  catchStopSignals(false);
  // Every rank takes part, before the files: rank 0 may fail to write them, and end here.
  const RankFigures rank_figures = rankFigures(assembly, report.loop);
  solver.sumEnergy(); // (with several ranks, the energies at the end, however the loop ended)
  const nlohmann::json dem = assembly.coupled ? demFigures(assembly, world) : nlohmann::json();
  // With levels: the element updates and the active elements by level, every rank's summed.
  std::vector<double> level_sums;
  if (scene.run.max_level > 0) {
    level_sums.push_back(solver.elementSteps());
    for (std::size_t count : solver.elementsByLevel())
      level_sums.push_back(static_cast<double>(count));
    level_sums = solver.processes().sumInOrder(std::move(level_sums));
  }
  report.steps = solver.steps();
  report.time = solver.time();
  report.elements = model.elements.size();
  report.bodies = model.bodies.size();
  report.balance_error = solver.energy().balance_error;
  if (writer && place.log && world.size > 1)
    place.log->line(partitionLine(solver.partition()));

  // Whatever happened, the files hold everything computed so far and are whole.
  if (writer) {
    try {
      h5->record(nullptr); // (the checkpoints' journal holds the loop's calls)
      series.write(*h5);
      if (census)
        writeLevels(*h5, *census);
      writeRunAttributes(*h5, scene, runStatus(report.loop));
      h5->close();
    } catch (const std::exception &e) { // (the loop's failure first: it may be the cause)
      if (report.loop.failure.empty())
        throw;
      throw std::runtime_error(report.loop.failure +
                               "; then run.h5 could not be written: " + e.what());
    }
  }
  if (!writer)
    return report;
  std::filesystem::rename(h5_path + ".tmp", h5_path);
  frames.writeCollection();
  report.wall = checkpoints.wallBefore() + secondsSince(place.start);
  report.vtk = frames.vtk();
  nlohmann::json summary = runSummary(scene, assembly, series, frames, report.loop, report.wall,
                                      world.size, rank_figures, dem);
  if (census)
    summary["levels"] = levelFigures(*census, report.loop, assembly.contact.get());
  if (scene.run.max_level > 0) {
    const fem::Solver &solver = *assembly.solver;
    const double single = solver.singleRateElementSteps(), updates = level_sums[0];
    std::vector<std::size_t> by_level;
    for (std::size_t l = 1; l < level_sums.size(); ++l)
      by_level.push_back(static_cast<std::size_t>(level_sums[l]));
    summary["multiple_time_stepping"] = {
        {"max_level", scene.run.max_level},
        {"level_gap", scene.run.level_gap},
        {"element_updates", updates},
        {"single_rate_element_updates", single},
        {"element_update_share", single > 0.0 ? updates / single : 1.0},
        {"active_elements_by_level_at_end", by_level},
        {"bodies_in_parts", solver.bodiesInParts()},
        {"parts", solver.parts()}};
  }
  if (checkpoints.on() || checkpoints.resumed())
    summary["checkpoints"] = {{"written", checkpoints.written()},
                              {"resumed", checkpoints.resumed()},
                              {"seconds", checkpoints.seconds()},
                              {"kept", runStatus(report.loop) != "completed"}};
  writeJson(dir + "/summary.json", summary);
  checkpoints.end(runStatus(report.loop) == "completed"); // after the files it stands in for
  return report;
}

} // namespace mesopen
