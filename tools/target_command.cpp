// mesopen target SCENE -o DIR: the sand target, the projectile placed on it, and their files.
#include "atomic_file.hpp"
#include "command_log.hpp"
#include "commands.hpp"
#include "generator.hpp"
#include "measures.hpp"
#include "output.hpp"
#include "projectile.hpp"
#include "scene.hpp"
#include "stop_signals.hpp"
#include "writers.hpp"

#include <nlohmann/json.hpp>
#include <omp.h>

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <future>
#include <iostream>
#include <sstream>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

namespace mesopen {

namespace fs = std::filesystem;

std::string shareDirectory() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("share/mesopen")
            : (exe.parent_path().parent_path() / "share" / "mesopen").string();
}

int runProgram(const std::vector<std::string> &words, const std::string &output,
               const std::function<int()> &waiting, bool append) {
  std::vector<std::string> copy = words;
  std::vector<char *> argv;
  for (std::string &w : copy)
    argv.push_back(w.data());
  argv.push_back(nullptr);
  // In a process group of its own: a terminal's Ctrl-C reaches the caller alone, which passes it on
  // (through `waiting`) once. SIGTERM when the caller dies, however (SIGKILL included): a run then
  // ends as on Ctrl-C, its files whole, and does not go on beside a restarted caller. Between fork
  // and exec only async-signal-safe calls.
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0)
    return -1;
  if (pid == 0) {
    setpgid(0, 0);
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) // the caller died before prctl took effect
      _exit(128 + SIGTERM);
    const int fd = open(output.c_str(), O_WRONLY | O_CREAT | (append ? O_APPEND : O_TRUNC), 0644);
    if (fd < 0 || dup2(fd, STDOUT_FILENO) < 0 || dup2(fd, STDERR_FILENO) < 0)
      _exit(127);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = -1;
  while (true) {
    const pid_t done = waitpid(pid, &status, waiting ? WNOHANG : 0);
    if (done == pid)
      break;
    if (done < 0 && errno != EINTR)
      return -1;
    if (waiting) {
      if (const int signal = waiting())
        kill(pid, signal);
      usleep(200000);
    }
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

bool runPlotScript(const std::string &script, const std::vector<std::string> &args) {
  std::vector<std::string> words{"/usr/bin/python3", shareDirectory() + "/" + script};
  words.insert(words.end(), args.begin(), args.end());
  return runProgram(words, "/dev/null") == 0;
}

namespace {

double peakMemoryBytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss * 1024.0; // Linux reports kilobytes
}

// The grain-size histogram PNG, drawn by matplotlib from target.json; a missing python3 or
// matplotlib is reported but does not fail the target.
bool plotHistogram(const std::string &dir) {
  if (runPlotScript("grain_sizes.py", {dir + "/target.json", dir + "/grain-sizes.png"}))
    return true;
  std::cerr
      << "mesopen target: warning: no grain-size plot (needs /usr/bin/python3 with matplotlib, "
         "and "
      << shareDirectory() << "/grain_sizes.py)\n";
  return false;
}

} // namespace

int targetCommand(const TargetOptions &options) {
  const auto start = Clock::now();
  Scene scene;
  try {
    scene = readScene(options.scene);
    if (options.seed)
      scene.target.seed = *options.seed;
    if (options.no_mesh)
      scene.target.mesh = MeshKind::none;
    prepareOutputDirectory(options.out_dir, "target",
                           {"target.json", "summary.json", "grain-sizes.png", "mesopen.log"});
  } catch (const InputError &e) {
    std::cerr << "mesopen target: " << e.what() << '\n';
    return 2;
  }
  CommandLog log;
  try {
    writeText(options.out_dir + "/scene.toml", composedScene(scene));
    log = CommandLog(options.out_dir, options.command_line);
    log.line("scene " + options.scene + " (composed: scene.toml), seed " +
             std::to_string(scene.target.seed));
  } catch (const std::exception &e) {
    std::cerr << "mesopen target: " << options.out_dir << ": cannot write: " << e.what() << '\n';
    return 1;
  }
  if (options.threads)
    omp_set_num_threads(*options.threads);

  const bool terminal = isatty(STDERR_FILENO);
  std::string phase = "generating the target";
  // A signal during the generation ends the command before the files, with a summary saying so;
  // once they are being written they are finished (each under a temporary name, then renamed).
  catchStopSignals(true);
  auto interrupted = [&] {
    const std::string what = stopSignalName() + " while " + phase;
    std::cerr << "mesopen target: " << what << "\n";
    log.lastLine("interrupted: " + what);
    writeJson(options.out_dir + "/summary.json",
              {{"command", "target"},
               {"scene", fs::absolute(options.scene).lexically_normal().string()},
               {"status", "interrupted"},
               {"failure", what}});
    return 128 + stopSignal();
  };
  try {
    // Progress on a terminal only, one line rewritten in place; nothing in logs.
    auto progress = [&](const std::string &what) {
      std::cerr << "\r\033[Kmesopen target: " << what << std::flush;
    };
    GeneratorReport report;
    const Target target = terminal ? generateTarget(scene.target, report, progress)
                                   : generateTarget(scene.target, report);
    if (terminal)
      std::cerr << "\r\033[K";
    if (stopSignal() != 0)
      return interrupted();
    const TargetMeasures m = measureTarget(target.grains, scene.target);

    phase = "placing the projectile";
    PlacedProjectile projectile;
    if (scene.projectile.enabled)
      projectile =
          placeProjectile(scene.projectile, scene.target.mesh_size, scene.target, target.grains);
    const PlacedProjectile *pp = scene.projectile.enabled ? &projectile : nullptr;

    if (stopSignal() != 0)
      return interrupted();
    catchStopSignals(false);
    phase = "writing the files";
    const std::string dir = options.out_dir;
    // The four files are independent: written side by side (HDF5 is used by one thread only).
    std::vector<std::future<void>> writes;
    writes.push_back(
        std::async(std::launch::async, [&] { writeTargetH5(dir + "/target.h5", target, pp); }));
    writes.push_back(
        std::async(std::launch::async, [&] { writeTargetVtu(dir + "/target.vtu", target, pp); }));
    // The disks of both DEM files, inside the walls; the projectile is not in them.
    const Disks disks = targetDisks(target, scene.dem.disk_size);
    writes.push_back(std::async(std::launch::async,
                                [&] { writeLiggghtsData(dir + "/target.data", target, disks); }));
    writeYadeSpheres(dir + "/target.spheres", disks);
    for (auto &w : writes)
      w.get(); // passes on the first failure
    const double seconds = secondsSince(start);

    const TargetSpec &t = scene.target;
    // What the run could not meet is said, on the terminal and in the files.
    std::vector<std::string> warnings;
    if (std::abs(m.porosity - t.porosity) > 0.005)
      warnings.push_back("porosity " + std::to_string(m.porosity) + " misses the requested " +
                         std::to_string(t.porosity) + " by more than 0.005");
    const double lost = static_cast<double>(report.grain_sites) - static_cast<double>(m.grains);
    if (lost > 0.01 * report.grain_sites)
      warnings.push_back(std::to_string(static_cast<long>(lost)) + " of " +
                         std::to_string(report.grain_sites) +
                         " grain sites lost (merged or without a cell)");
    for (const auto &w : warnings)
      std::cerr << "mesopen target: warning: " << w << '\n';
    nlohmann::json j;
    j["warnings"] = warnings;
    j["grains"] = m.grains;
    j["porosity"] = m.porosity;
    j["mean_diameter"] = m.mean_diameter;
    j["std_diameter"] = m.std_diameter;
    j["min_diameter"] = m.min_diameter;
    j["max_diameter"] = m.max_diameter;
    j["clustering"] = {{"window", m.window}, {"local_porosity_std", m.local_porosity_std}};
    j["seconds"] = seconds;
    j["seconds_by_phase"] = {{"sites", report.seconds_sites},
                             {"porosity_calibration", report.seconds_calibration},
                             {"tessellation", report.seconds_tessellation},
                             {"delaunay", report.tessellation.delaunay_seconds},
                             {"mesh", report.seconds_mesh}};
    j["peak_memory_bytes"] = peakMemoryBytes();
    j["requested"] = {{"width", t.width},
                      {"height", t.height},
                      {"diameter_min", t.diameter_min},
                      {"diameter_max", t.diameter_max},
                      {"porosity", t.porosity},
                      {"void_ratio", t.void_ratio},
                      {"placement", nameOf(t.placement, placement_names)},
                      {"tessellation", nameOf(t.tessellation, tessellation_names)},
                      {"seed", t.seed},
                      {"mesh", nameOf(t.mesh, mesh_names)},
                      {"mesh_size", t.mesh_size}};
    j["sites"] = {{"grains", report.grain_sites}, {"voids", report.void_sites}};
    j["porosity_control"] = {{"void_factor", report.void_factor},
                             {"trial_factors", report.trial_factor},
                             {"trial_porosities", report.trial_porosity}};
    j["placement"] = {{"iterations", report.placement.iterations},
                      {"converged", report.placement.converged},
                      {"energy", report.placement.energy}};
    const TessellationReport &tr = report.tessellation;
    j["tessellation"] = {{"passes", tr.passes},
                         {"merged_grains", tr.merged_grains},
                         {"removed_voids", tr.removed_voids},
                         {"restored_points", tr.restored_points},
                         {"lost_grains", tr.lost_grains},
                         {"merged_vertices", tr.merged_vertices},
                         {"kept_short_edges", tr.kept_short_edges}};
    j["mesh"] = {{"nodes", target.mesh.nodes()}, {"triangles", target.mesh.triangles()}};
    if (pp)
      j["projectile"] = {{"diameter", projectile.shape.diameter},
                         {"length", projectile.shape.length},
                         {"nose_length", projectile.shape.nose_length},
                         {"tip_y", projectile.offset_y + projectile.shape.tip_cut},
                         {"nodes", projectile.mesh.x.size()},
                         {"triangles", projectile.mesh.tri.size() / 3}};
    j["histogram"] = {{"edges", m.histogram_edges}, {"counts", m.histogram_counts}};
    const DiameterRatios ratio = cellOverSiteDiameter(target);
    j["cell_over_site_diameter"] = {{"min", ratio.min},
                                    {"p01", ratio.p01},
                                    {"median", ratio.median},
                                    {"p99", ratio.p99},
                                    {"max", ratio.max}};
    writeJson(dir + "/target.json", j);

    const bool plotted = !options.no_plot && plotHistogram(dir);

    nlohmann::json summary;
    summary["command"] = "target";
    summary["scene"] = fs::absolute(options.scene).lexically_normal().string();
    summary["seed"] = t.seed;
    summary["figures"] = {{"grains", m.grains},
                          {"porosity", m.porosity},
                          {"mean_diameter", m.mean_diameter},
                          {"std_diameter", m.std_diameter},
                          {"local_porosity_std", m.local_porosity_std}};
    summary["files"] = {"target.h5",   "target.data", "target.vtu", "target.spheres",
                        "target.json", "scene.toml",  "mesopen.log"};
    if (plotted)
      summary["files"].push_back("grain-sizes.png");
    summary["warnings"] = warnings;
    summary["wall_seconds"] = seconds;
    writeJson(dir + "/summary.json", summary);
    for (const auto &warning : warnings)
      log.lastLine("warning: " + warning);
    std::ostringstream done;
    done << m.grains << " grains, porosity " << m.porosity << ", " << target.mesh.triangles()
         << " triangles, " << seconds << " s";
    log.lastLine("completed: " + done.str());

    std::cout << "mesopen target: " << m.grains << " grains, porosity " << 100 * m.porosity
              << " %, mean diameter " << 1e6 * m.mean_diameter << " um, std "
              << 1e6 * m.std_diameter << " um, " << target.mesh.triangles() << " triangles, "
              << seconds << " s\n"
              << "  files in " << dir << ": target.h5 target.data target.vtu (ParaView) "
              << "target.spheres target.json summary.json scene.toml mesopen.log\n";
    return 0;
  } catch (const std::exception &e) {
    std::cerr << "mesopen target: failed while " << phase << ": " << e.what() << '\n';
    log.lastLine("failed while " + phase + ": " + e.what());
    try { // the files it wrote are whole (each renamed when complete); the summary says what failed
      writeJson(options.out_dir + "/summary.json",
                {{"command", "target"},
                 {"scene", fs::absolute(options.scene).lexically_normal().string()},
                 {"status", "failed"},
                 {"failure", "while " + phase + ": " + e.what()}});
    } catch (const std::exception &) {
      // the directory itself cannot be written: the message above is all there is
    }
    return 1;
  }
}

} // namespace mesopen
