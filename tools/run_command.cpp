// mesopen run SCENE -o DIR (or --resume DIR: continued from its last checkpoint): the scene's
// input checked, its output directory taken, the run made by the run layer (run/simulate.hpp), its
// end said on the terminal and in the log and as the exit code.
#include "checkpoint.hpp"
#include "command_log.hpp"
#include "commands.hpp"
#include "output.hpp"
#include "run_files.hpp"
#include "scene.hpp"
#include "simulate.hpp"
#include "stop_signals.hpp"

#include <omp.h>

#include <filesystem>
#include <iostream>
#include <sstream>
#include <unistd.h>

namespace mesopen {

namespace fs = std::filesystem;

namespace {

// Keys the scene sets that the chosen representation does not use: warnings (said on stderr and
// in the log), not refused (a scene may be switched between representations).
std::vector<std::string> idleKeys(const Scene &scene, const std::string &path) {
  const toml::table root = parseToml(path);
  const bool disks = scene.run.grains && scene.run.representation != Representation::fe;
  std::vector<std::string> idle;
  if (!disks && root.contains("dem"))
    idle.push_back("[dem]");
  if (const toml::table *run = root["run"].as_table())
    for (const char *key : {"band_half_width", "band_depth"})
      if (scene.run.representation != Representation::hybrid && run->contains(key))
        idle.push_back(std::string("run.") + key);
  std::vector<std::string> warnings;
  for (const std::string &what : idle)
    warnings.push_back("warning: " + path + ": " + what +
                       " does nothing with run.representation = \"" +
                       nameOf(scene.run.representation, representation_names) + "\"");
  return warnings;
}

// LIGGGHTS reads the disks from the output directory through a script variable: a path it would
// split or expand is refused before it starts (it exits the process on a bad command).
void checkOutputForLiggghts(const Scene &scene, const std::string &dir) {
  const std::string out = fs::absolute(dir).string();
  if (scene.run.grains && scene.run.representation != Representation::fe &&
      out.find_first_of(" \t\n\"'$#&") != std::string::npos)
    throw InputError(scene.path + ": run.representation = \"" +
                     nameOf(scene.run.representation, representation_names) +
                     "\" needs an output directory without spaces or any of \"'$#& (LIGGGHTS "
                     "reads the disks from it); it is '" +
                     out + "'");
}

// The scene, checked for what a run needs, and the warnings about it: SCENE with --seed, or with
// --resume DIR the one its last checkpoint holds. Throws InputError.
Scene prepareRun(const RunOptions &options, std::vector<std::string> &warnings) {
  if (!options.resume.empty()) {
    if (!options.scene.empty() || !options.out_dir.empty() || options.seed)
      throw InputError("--resume " + options.resume +
                       " continues a run with its checkpoint's scene, seed and directory; "
                       "allowed: --resume DIR without SCENE, -o or --seed (with --threads, "
                       "--quiet)");
    Scene scene = checkpointScene(options.resume);
    checkRunnable(scene, scene.path);
    checkOutputForLiggghts(scene, options.resume);
    return scene;
  }
  if (options.scene.empty() || options.out_dir.empty())
    throw InputError(std::string(options.scene.empty() ? "a scene is required"
                                                       : "--output is required (-o DIR)") +
                     "; allowed: mesopen run SCENE -o DIR, or mesopen run --resume DIR");
  Scene scene = readScene(options.scene);
  if (options.seed)
    scene.target.seed = *options.seed;
  checkRunnable(scene, options.scene);
  checkOutputForLiggghts(scene, options.out_dir);
  warnings = idleKeys(scene, options.scene);
  return scene;
}

// The run's end on the terminal and in the log (rank 0) and as the exit code: 0 completed, 1
// failed, 128 + the signal when stopped by one.
int reportEnd(const RunReport &r, const std::string &dir, bool writer, CommandLog &log) {
  const LoopResult &loop = r.loop;
  if (!writer)
    return loop.failure.empty() ? 0 : loop.interrupted ? 128 + stopSignal() : 1;
  std::ostringstream text;
  text << "t = " << r.time << " s, step " << r.steps;
  if (loop.interrupted) {
    log.lastLine("interrupted: " + loop.failure + ", " + text.str());
    std::cerr << "mesopen run: " << loop.failure << ", t = " << r.time
              << " s\n  what was computed up to there is in " << dir << " (run.h5, summary.json)\n";
    return 128 + stopSignal();
  }
  if (!loop.failure.empty()) {
    log.lastLine("failed at " + text.str() + ": " + loop.failure);
    std::cerr << "mesopen run: failed at t = " << r.time << " s, step " << r.steps << ": "
              << loop.failure << "\n  what was computed up to there is in " << dir
              << " (run.h5, summary.json)\n";
    return 1;
  }
  text.str("");
  text << r.steps << " steps to t = " << r.time << " s, " << r.elements << " elements in "
       << r.bodies << " bodies, " << r.wall << " s (" << r.steps / std::max(loop.seconds, 1e-9)
       << " steps/s); energy balance error " << r.balance_error;
  log.lastLine("completed: " + text.str());
  std::cout << "mesopen run: " << text.str() << "\n  files in " << dir
            << ": run.h5 summary.json scene.toml mesopen.log"
            << (r.vtk ? " vtk/run.pvd (ParaView)" : "") << "\n";
  return 0;
}

} // namespace

int runCommand(const RunOptions &given) {
  const auto start = Clock::now();
  const bool resume = !given.resume.empty();
  RunOptions options = given;
  if (resume)
    options.out_dir = given.resume;
  Scene scene;
  std::vector<std::string> warnings;
  parallel::World world;
  try {
    scene = prepareRun(given, warnings);
    // Under mpirun every rank runs the scene; rank 0 writes the files.
    world = parallel::world(scene.run.grains && scene.run.representation != Representation::fe);
  } catch (const InputError &e) {
    std::cerr << "mesopen run: " << e.what() << '\n';
    return 2;
  }
  // Rank 0 takes the output directory; the other ranks wait for it and end as it does. A
  // directory in use is exit 1, as for a campaign: the input is good, the run can be made later.
  int refused = 0;
  if (world.rank == 0) {
    try {
      if (resume ? !takeResumedDirectory(options.out_dir)
                 : !takeRunDirectory(scene, options.out_dir)) {
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
  CommandLog log;
  if (world.rank == 0) {
    for (const std::string &warning : warnings)
      std::cerr << "mesopen run: " << warning << '\n';
    try {
      log = CommandLog(options.out_dir, options.command_line, resume);
      log.line(std::string(resume ? "resumed from the checkpoint: " : "") + "scene " + scene.path +
               " (composed: scene.toml), seed " + std::to_string(scene.target.seed) + ", " +
               std::to_string(world.size) + " MPI rank" + (world.size > 1 ? "s" : ""));
      for (const std::string &warning : warnings)
        log.line(warning);
    } catch (const std::exception &e) {
      std::cerr << "mesopen run: " << options.out_dir << ": cannot write mesopen.log: " << e.what()
                << '\n';
      refused = 1;
    }
  }
  if (const int code = static_cast<int>(world.max(refused)))
    return code;
  if (options.threads)
    omp_set_num_threads(*options.threads);
  const RunPlace place{options.out_dir, shareDirectory() + "/liggghts-inputs/dem.in",
                       !options.quiet && isatty(STDERR_FILENO), start, &log};
  try {
    return reportEnd(simulate(scene, place, world, resume), options.out_dir, world.rank == 0, log);
  } catch (const Interrupted &e) {
    // during the set-up: no run.h5, a summary saying so
    std::cerr << "mesopen run: " << e.what() << '\n';
    log.lastLine(std::string("interrupted: ") + e.what());
    if (world.rank == 0)
      writeUnstartedSummary(options.out_dir, scene.path, "interrupted", e.what());
    return 128 + stopSignal();
  } catch (const InputError &e) {
    // found once the target or LIGGGHTS is made (dem.step against the disks' stable step), or a
    // checkpoint not of this run: bad input all the same; no run.h5 or summary.json is written
    std::cerr << "mesopen run: " << e.what() << '\n';
    log.lastLine(std::string("bad input: ") + e.what());
    std::error_code ec;
    if (world.rank == 0)
      fs::remove(options.out_dir + "/run.h5.tmp", ec);
    return 2;
  } catch (const std::exception &e) {
    // Before the time loop (target, model) or while writing the files: no run.h5, a summary
    // (rank 0's, the files' writer).
    std::cerr << "mesopen run: failed: " << e.what() << '\n';
    if (world.rank != 0)
      return 1;
    log.lastLine(std::string("failed: ") + e.what());
    std::error_code ec;
    fs::remove(options.out_dir + "/run.h5.tmp", ec);
    try {
      writeUnstartedSummary(options.out_dir, scene.path, "failed", e.what());
    } catch (const std::exception &) {
      // the directory itself cannot be written: the message above is all there is
    }
    return 1;
  }
}

} // namespace mesopen
