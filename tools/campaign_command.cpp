// mesopen campaign CAMPAIGN.toml -o DIR: every run of a campaign (tools/campaign.hpp) on each of
// its replicates, one after another, each as its own `mesopen run` in DIR/runs/NAME/rK (scene.toml,
// log.txt and the run's files); a run already completed with the same scene is not run again.
// Then the measures of every run (instability.json), the tables (runs.csv: one row per replicate;
// table.csv and table.md: per run, mean and 95 % interval, like thesis Table 5.1; the trends' tests
// in table.md), summary.json, and the plots (tools/plots/campaign.py).
#include "analyze.hpp"
#include "campaign.hpp"
#include "commands.hpp"
#include "output.hpp"
#include "simulate.hpp"

#include <nlohmann/json.hpp>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <unistd.h>

namespace mesopen {

namespace fs = std::filesystem;

namespace {

// One replicate of one run.
struct Job {
  const CampaignRun *run = nullptr;
  int replicate = 0; // from 0
  std::string dir, scene;
  toml::table tables; // the scene's
  std::int64_t seed = 0;
  bool reused = false;  // completed before, with the same scene
  bool resumed = false; // interrupted before, with the same scene, at a checkpoint: continued
  bool selected = true; // to run (see --only)
  std::string status;   // completed, failed, interrupted, not run
  std::string failure;
  double wall = 0.0;
  std::size_t steps = 0;
  nlohmann::json measures; // analyzeRun's figures
};

// Whether a run's run.h5 opens and its series read (a file cut short does not: its run is made
// again).
bool readsWhole(const std::string &path) {
  try {
    return fs::is_regular_file(path) && readRunSeries(path).time.size() >= 2;
  } catch (const std::exception &) {
    return false;
  }
}

// The tables of a scene file written before (empty if it is missing or not TOML).
toml::table readSceneText(const std::string &path) {
  try {
    return toml::parse_file(path);
  } catch (const toml::parse_error &) {
    return {};
  }
}

nlohmann::json readJson(const std::string &path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in, nullptr, false);
}

// SIGINT or SIGTERM: passed on to the run going on, which ends as `mesopen run` ends on it (its
// files written, status interrupted); the campaign stops after it with the tables of what is done.
// A second signal ends the campaign at once.
volatile std::sig_atomic_t stop_signal = 0;
extern "C" void requestCampaignStop(int signal) {
  stop_signal = signal;
  std::signal(signal, SIG_DFL);
}

// Markdown table cell: no '|' or line break of the text may end the cell.
std::string cell(const std::string &text) {
  std::string out;
  for (char c : text)
    out += c == '|'                 ? std::string("\\|")
           : c == '\n' || c == '\r' ? std::string(" ")
                                    : std::string(1, c);
  return out;
}

std::string show(double v, int digits = 4) {
  if (std::isnan(v))
    return "";
  std::ostringstream s;
  s.precision(digits);
  s << v;
  return s.str();
}

std::string csvField(const std::string &s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos)
    return s;
  std::string q = "\"";
  for (char c : s)
    q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

// The values of a measure over a run's completed replicates.
std::vector<double> valuesOf(const std::vector<Job> &jobs, const CampaignRun *run,
                             const std::string &measure) {
  std::vector<double> v;
  for (const Job &j : jobs)
    if (j.run == run && j.status == "completed" && j.measures.contains(measure))
      v.push_back(j.measures[measure].get<double>());
  return v;
}

void writeTables(const std::string &dir, const Campaign &c, const std::vector<Job> &jobs,
                 const std::vector<TrendResult> &trends) {
  // runs.csv: a row per replicate.
  std::ostringstream runs;
  runs << "run,replicate,seed,status,wall_seconds,steps";
  for (const auto &m : campaign_measures)
    runs << "," << m.name;
  runs << "\n";
  for (const Job &j : jobs) {
    runs << csvField(j.run->name) << "," << j.replicate + 1 << "," << j.seed << "," << j.status
         << "," << show(j.wall, 6) << "," << j.steps;
    for (const auto &m : campaign_measures)
      runs << "," << (j.measures.contains(m.name) ? show(j.measures[m.name].get<double>(), 8) : "");
    runs << "\n";
  }
  writeText(dir + "/runs.csv", runs.str());

  // table.csv and table.md: per run, mean and 95 % half-width of each measure.
  std::ostringstream csv, md;
  csv << "run,label,replicates,completed,wall_seconds_mean";
  md << "# " << (c.name.empty() ? c.path : c.name) << "\n\nEach figure: mean over the completed "
     << "replicates, and the half-width of its 95 % confidence interval (Student's t) when there "
        "are two or more; in brackets the published value where the campaign gives one.\n\n"
     << "| run | label | n |";
  for (const auto &m : campaign_measures) {
    csv << "," << m.name << "_mean," << m.name << "_ci95," << m.name << "_reference";
    md << " " << m.title << " [" << m.unit << "] |";
  }
  csv << "\n";
  md << " wall time [s] |\n|---|---|---|";
  for (std::size_t k = 0; k < std::size(campaign_measures); ++k)
    md << "---|";
  md << "---|\n";
  for (const CampaignRun &r : c.runs) {
    int replicates = 0, completed = 0;
    std::vector<double> walls;
    for (const Job &j : jobs)
      if (j.run == &r) {
        ++replicates;
        if (j.status == "completed")
          ++completed, walls.push_back(j.wall);
      }
    const Estimate wall = estimate(walls);
    csv << csvField(r.name) << "," << csvField(r.label) << "," << replicates << "," << completed
        << "," << show(wall.mean, 6);
    md << "| " << cell(r.name) << " | " << cell(r.label) << " | " << completed
       << (completed < replicates ? " of " + std::to_string(replicates) : "") << " |";
    for (const auto &m : campaign_measures) {
      const Estimate e = estimate(valuesOf(jobs, &r, m.name));
      const auto ref = r.reference.find(m.name);
      const double reference = ref == r.reference.end() ? NAN : ref->second;
      csv << "," << show(e.mean, 8) << "," << show(e.half_width, 8) << "," << show(reference, 8);
      md << " " << show(e.mean) << (std::isnan(e.half_width) ? "" : " ± " + show(e.half_width, 2))
         << (std::isnan(reference) ? "" : " (" + show(reference) + ")") << " |";
    }
    csv << "\n";
    md << " " << show(wall.mean, 3) << " |\n";
  }
  if (!c.trends.empty()) {
    md << "\n## Trends\n\nOn the magnitude |m| of each replicate's measure (docs/campaign.md). "
          "rises / falls: the least-squares slope of |m| against the parameter x, with its 95 % "
          "interval, confirmed when the interval excludes 0 on the expected side, reversed when on "
          "the other; differs: the difference of the two runs' means, confirmed when its interval "
          "excludes 0; similar: every pair's difference, confirmed when every interval lies within "
          "the tolerance, reversed when one lies beyond it (the effect shown is the pair reaching "
          "farthest). Not tested with fewer than two replicates of a run.\n\n"
       << "| trend | measure | expected | runs (x) | means of abs(m) | seen | effect ± 95 % | "
          "verdict |\n|---|---|---|---|---|---|---|---|\n";
    for (std::size_t t = 0; t < c.trends.size(); ++t) {
      const Trend &tr = c.trends[t];
      std::string runs_text, means;
      for (std::size_t k = 0; k < tr.runs.size(); ++k) {
        runs_text += (k ? ", " : "") + tr.runs[k] + " (" + show(tr.x[k]) + ")";
        means += (k ? ", " : "") + show(trends[t].magnitudes[k].mean, 3);
      }
      md << "| " << cell(tr.name) << " | " << tr.measure << " | "
         << nameOf(tr.expect, trend_kind_names)
         << (tr.expect == TrendKind::similar ? " (within " + show(100 * tr.tolerance, 3) + " %)"
                                             : "")
         << " | " << cell(runs_text) << " | " << means << " | " << trends[t].seen << " | "
         << show(trends[t].effect, 3)
         << (std::isnan(trends[t].half_width) ? "" : " ± " + show(trends[t].half_width, 2)) << " | "
         << trends[t].verdict << " |\n";
    }
  }
  writeText(dir + "/table.csv", csv.str());
  writeText(dir + "/table.md", md.str());
}

} // namespace

int campaignCommand(const CampaignOptions &options) {
  const auto start = Clock::now();
  Campaign c;
  std::vector<Job> jobs;
  const std::string &dir = options.out_dir;
  try {
    c = readCampaign(options.campaign);
    if (options.replicates)
      c.replicates = *options.replicates;
    if (options.representation) {
      c.representation = valueOf(*options.representation, representation_names);
      if (!c.representation)
        throw InputError("--representation " + *options.representation +
                         " is not known; allowed: fe, dem, hybrid");
    }
    for (const std::string &name : options.only)
      if (std::none_of(c.runs.begin(), c.runs.end(),
                       [&](const CampaignRun &r) { return r.name == name; }))
        throw InputError("--only " + name + ": no run of " + c.path + " has that name");
    // Every replicate's scene, composed and checked as `mesopen run` checks it before the
    // directory is touched: bad input stops the campaign before anything runs.
    for (const CampaignRun &r : c.runs) {
      const bool selected =
          options.only.empty() ||
          std::find(options.only.begin(), options.only.end(), r.name) != options.only.end();
      for (int k = 0; k < c.replicates; ++k) {
        Job j;
        j.run = &r, j.replicate = k, j.selected = selected;
        j.dir = dir + "/runs/" + r.name + "/r" + std::to_string(k + 1);
        j.scene = composeScene(c, r, k);
        const std::string where = c.path + ", run \"" + r.name + "\", replicate " +
                                  std::to_string(k + 1) + " (scene " + r.scene + ")";
        std::istringstream in(j.scene);
        const Scene scene = readScene(toml::parse(in), where);
        checkRunnable(scene, where);
        // the scene as the run will record it (scene.toml, every key at its value)
        j.scene = composedScene(scene);
        std::istringstream composed(j.scene);
        j.tables = toml::parse(composed);
        j.seed = scene.target.seed;
        jobs.push_back(std::move(j));
      }
    }
    std::error_code made;
    fs::create_directories(dir, made);
    // One campaign at a time in a directory: a second would run the same replicates into the same
    // files. The lock is held while the campaign or a run it started lives: the runs inherit it,
    // and end when the campaign dies (runProgram).
    if (!lockForProcess((fs::path(dir) / ".campaign.lock").string(), true)) {
      std::cerr << "mesopen campaign: " << dir << " is in use by another mesopen campaign\n";
      return 1;
    }
    prepareOutputDirectory(dir, "campaign",
                           {"summary.json", "table.md", "table.csv", "runs.csv",
                            "campaign-rotational-momentum.png", "campaign-trends.png",
                            "campaign-trend-curves.png"});
    for (Job &j : jobs) {
      // Done before: completed, its series there, the same scene (compared as tables: the
      // comment line and the number format do not count).
      const nlohmann::json done = readJson(j.dir + "/summary.json");
      const bool same_scene = readSceneText(j.dir + "/scene.toml") == j.tables;
      j.reused = same_scene && done.is_object() && done.value("status", "") == "completed" &&
                 readsWhole(j.dir + "/run.h5");
      // Interrupted with a checkpoint written (run.checkpoint_interval or checkpoint_time in its
      // scene): continued from it (mesopen run --resume), not made anew.
      j.resumed = !j.reused && same_scene && done.is_object() &&
                  done.value("status", "") == "interrupted" &&
                  fs::is_regular_file(j.dir + "/checkpoint/state.h5");
      j.status = "not run";
      // Not to run now (--only) but run before with this scene: as it ended then.
      if (!j.selected && !j.reused && same_scene && done.is_object() && done.contains("status")) {
        j.status = done.value("status", "failed");
        j.failure = done.value("failure", "");
        j.wall = done.value("wall_seconds", 0.0);
        j.steps = done.value("steps", std::size_t{0});
      }
    }
  } catch (const InputError &e) {
    std::cerr << "mesopen campaign: " << e.what() << '\n';
    return 2;
  } catch (const std::exception &e) {
    std::cerr << "mesopen campaign: " << options.campaign << ": " << e.what() << '\n';
    return 2;
  }

  std::error_code ec;
  const std::string exe = fs::read_symlink("/proc/self/exe", ec).string();
  const bool terminal = !options.quiet && isatty(STDERR_FILENO);
  std::size_t pending = 0;
  std::size_t reused = 0, to_resume = 0;
  for (const Job &j : jobs)
    pending += j.selected && !j.reused, reused += j.reused, to_resume += j.selected && j.resumed;
  std::printf("mesopen campaign: %zu runs, %d replicates each: %zu to run now, %zu done before%s\n",
              c.runs.size(), c.replicates, pending, reused,
              to_resume > 0
                  ? (" (" + std::to_string(to_resume) + " to continue from a checkpoint)").c_str()
                  : "");
  std::fflush(stdout);
  stop_signal = 0;
  for (int s : {SIGINT, SIGTERM})
    std::signal(s, requestCampaignStop);
  std::size_t ran = 0, failed = 0, failed_now = 0; // failed: also before, in runs not run now
  double ran_seconds = 0.0;
  for (Job &j : jobs) {
    if (j.selected && !j.reused && stop_signal == 0) {
      try {
        const auto run_start = Clock::now();
        bool passed_on = false;
        auto show_progress = [&]() -> int {
          if (stop_signal != 0 && !passed_on) {
            passed_on = true;
            return stop_signal;
          }
          if (!terminal)
            return 0;
          const double per_run = ran > 0 ? ran_seconds / ran : NAN;
          const double eta = per_run * (pending - ran) - secondsSince(run_start);
          std::fprintf(stderr,
                       "\r\033[Kmesopen campaign: run %zu of %zu (%s, replicate %d): %.0f s; "
                       "%zu failed; elapsed %.0f s%s",
                       ran + 1, pending, j.run->name.c_str(), j.replicate + 1,
                       secondsSince(run_start), failed, secondsSince(start),
                       std::isnan(eta) ? ""
                                       : (", ETA " + show(std::max(eta, 0.0), 3) + " s").c_str());
          return 0;
        };
        int code = 0;
        for (bool resume = j.resumed;; resume = false) {
          std::vector<std::string> words{exe, "run", "--resume", j.dir, "--quiet"};
          if (!resume) {
            // Nothing of an earlier run may pass for this one's if it fails before writing its
            // own (a run continued keeps its files: `mesopen run --resume` rewrites them).
            fs::create_directories(j.dir);
            for (const char *f : {"summary.json", "run.h5", "run.h5.tmp", "instability.json"})
              fs::remove(fs::path(j.dir) / f);
            fs::remove_all(fs::path(j.dir) / "checkpoint");
            writeText(j.dir + "/scene.toml", j.scene);
            words = {exe, "run", j.dir + "/scene.toml", "-o", j.dir, "--quiet"};
          }
          if (options.threads)
            words.insert(words.end(), {"--threads", std::to_string(*options.threads)});
          code = runProgram(words, j.dir + "/log.txt", show_progress, resume);
          // A checkpoint that cannot be continued (exit 2: another version's, or damaged): the
          // run is made anew.
          if (!resume || code != 2 || stop_signal != 0)
            break;
          std::printf("mesopen campaign: %s replicate %d: its checkpoint cannot be continued (%s); "
                      "made anew\n",
                      j.run->name.c_str(), j.replicate + 1, (j.dir + "/log.txt").c_str());
          j.resumed = false;
        }
        ran_seconds += secondsSince(run_start);
        ++ran;
        if (terminal)
          std::fprintf(stderr, "\r\033[K");
        const nlohmann::json summary = readJson(j.dir + "/summary.json");
        j.status = summary.is_object() ? summary.value("status", "failed") : "failed";
        if (code != 0 && j.status == "completed")
          j.status = "failed";
        if (j.status != "completed")
          j.failure = summary.is_object() && summary.contains("failure")
                          ? summary["failure"].get<std::string>()
                          : "exit code " + std::to_string(code) + " (see " + j.dir + "/log.txt)";
        if (!terminal || j.status != "completed")
          std::printf("mesopen campaign: %s replicate %d%s: %s in %.0f s%s\n", j.run->name.c_str(),
                      j.replicate + 1, j.resumed ? " (continued from its checkpoint)" : "",
                      j.status.c_str(), secondsSince(run_start),
                      j.failure.empty() ? "" : (": " + j.failure).c_str());
        std::fflush(stdout);
      } catch (const std::exception &e) {
        j.status = "failed", j.failure = e.what();
        std::printf("mesopen campaign: %s replicate %d: failed: %s\n", j.run->name.c_str(),
                    j.replicate + 1, e.what());
      }
    } else if (j.reused) {
      j.status = "completed";
    }
    if (j.status == "completed") {
      const nlohmann::json summary = readJson(j.dir + "/summary.json");
      j.wall = summary.value("wall_seconds", 0.0);
      j.steps = summary.value("steps", std::size_t{0});
      try {
        j.measures = analyzeRun(j.dir);
      } catch (const std::exception &e) {
        j.status = "failed", j.failure = std::string("analysis: ") + e.what();
      }
    }
    const bool bad = j.status != "completed" && j.status != "not run" && j.status != "interrupted";
    failed += bad;
    failed_now += bad && j.selected && !j.reused;
  }
  for (int s : {SIGINT, SIGTERM})
    std::signal(s, SIG_DFL);

  try {
    std::vector<TrendResult> trends;
    for (const Trend &tr : c.trends) {
      std::vector<std::vector<double>> values;
      for (const std::string &name : tr.runs)
        for (const CampaignRun &r : c.runs)
          if (r.name == name)
            values.push_back(valuesOf(jobs, &r, tr.measure));
      trends.push_back(testTrend(tr, values));
    }
    writeTables(dir, c, jobs, trends);
    nlohmann::json runs = nlohmann::json::array(), trend_list = nlohmann::json::array();
    std::size_t completed = 0, completed_now = 0;
    for (const Job &j : jobs) {
      completed += j.status == "completed";
      completed_now += j.status == "completed" && !j.reused;
      nlohmann::json r = {{"run", j.run->name},
                          {"label", j.run->label},
                          {"replicate", j.replicate + 1},
                          {"seed", j.seed},
                          {"dir", fs::relative(j.dir, dir).string()},
                          {"status", j.status},
                          {"reused", j.reused},
                          {"wall_seconds", j.wall},
                          {"steps", j.steps},
                          {"measures", j.measures}};
      if (!j.failure.empty())
        r["failure"] = j.failure;
      runs.push_back(r);
    }
    auto orNull = [](double v) { return std::isnan(v) ? nlohmann::json() : nlohmann::json(v); };
    for (std::size_t t = 0; t < c.trends.size(); ++t) {
      const Trend &tr = c.trends[t];
      nlohmann::json means = nlohmann::json::array(), intervals = nlohmann::json::array();
      for (const Estimate &e : trends[t].magnitudes)
        means.push_back(orNull(e.mean)), intervals.push_back(orNull(e.half_width));
      trend_list.push_back({{"name", tr.name},
                            {"measure", tr.measure},
                            {"expect", nameOf(tr.expect, trend_kind_names)},
                            {"runs", tr.runs},
                            {"x", tr.x},
                            {"abs_means", means},
                            {"abs_ci95", intervals},
                            {"seen", trends[t].seen},
                            {"effect", orNull(trends[t].effect)},
                            {"ci95", orNull(trends[t].half_width)},
                            {"verdict", trends[t].verdict}});
    }
    double run_seconds = 0.0;
    for (const Job &j : jobs)
      run_seconds += j.wall;
    nlohmann::json summary = {
        {"command", "campaign"},
        {"campaign", fs::absolute(c.path).lexically_normal().string()},
        {"name", c.name},
        {"representation",
         c.representation ? nameOf(*c.representation, representation_names) : "as in the scenes"},
        {"replicates", c.replicates},
        {"seed_stride", c.seed_stride},
        {"runs", runs},
        {"trends", trend_list},
        {"completed", completed},
        {"failed", failed},
        {"interrupted", stop_signal != 0},
        {"run_seconds_sum", run_seconds},
        {"wall_seconds", secondsSince(start)},
        {"files", {"runs.csv", "table.csv", "table.md", "summary.json"}}};
    // The plots read the summary; then it lists them.
    writeJson(dir + "/summary.json", summary);
    const char *plots[] = {"campaign-rotational-momentum.png", "campaign-trends.png",
                           "campaign-trend-curves.png"};
    for (const char *f : plots)
      fs::remove(fs::path(dir) / f, ec);
    const bool plotted =
        completed > 0 && runPlotScript("campaign.py", {dir + "/summary.json", dir});
    if (completed > 0 && !plotted)
      std::cerr
          << "mesopen campaign: warning: no plots (needs /usr/bin/python3 with matplotlib, and "
          << shareDirectory() << "/campaign.py)\n";
    for (const char *f : plots)
      if (fs::exists(fs::path(dir) / f))
        summary["files"].push_back(f);
    writeJson(dir + "/summary.json", summary);
    std::printf("mesopen campaign: %zu of %zu completed (%zu now, %zu failed) in %.0f s; the runs' "
                "own time %.0f s; tables in %s/table.md%s\n",
                completed, jobs.size(), completed_now, failed, secondsSince(start), run_seconds,
                dir.c_str(), plotted ? ", plots campaign-*.png" : "");
  } catch (const std::exception &e) {
    std::cerr << "mesopen campaign: failed writing the tables in " << dir << ": " << e.what()
              << '\n';
    return 1;
  }
  return stop_signal != 0 ? 128 + stop_signal : failed_now > 0 ? 1 : 0;
}

} // namespace mesopen
