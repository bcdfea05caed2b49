// mesopen analyze DIR [DIR...] [-o OUT]: the projectile's measures of instability (thesis section
// 3.4) from each run's run.h5: instability.json in each DIR (figures, curves against scaled depth,
// the spectrum of the rotational momentum), and PNG plots with every run overlaid in OUT (thesis
// Figs 5.3, 5.4, 5.8, 5.24), drawn by tools/plots/instability.py.
#include "analyze.hpp"
#include "commands.hpp"
#include "output.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>

namespace mesopen {

namespace fs = std::filesystem;

namespace {

const char *plot_files[] = {"instability-energy.png",
                            "instability-velocity.png",
                            "instability-axial-force.png",
                            "instability-rotational-momentum.png",
                            "instability-lateral-force.png",
                            "instability-lateral-impulse.png",
                            "instability-lateral-displacement.png",
                            "instability-tilt.png",
                            "instability-depth.png",
                            "instability-radial-momentum.png",
                            "instability-spectrum.png"};

double maxAbs(const std::vector<double> &v) {
  double m = 0.0;
  for (double x : v)
    m = std::max(m, std::abs(x));
  return m;
}

// Every k-th sample (and the last) so that a curve has at most `limit` points.
nlohmann::json thinned(const std::vector<double> &v, std::size_t limit = 2000) {
  nlohmann::json a = nlohmann::json::array();
  if (v.empty())
    return a;
  const std::size_t step = std::max<std::size_t>(1, (v.size() + limit - 1) / limit);
  for (std::size_t i = 0; i < v.size(); i += step)
    a.push_back(v[i]);
  if ((v.size() - 1) % step != 0)
    a.push_back(v.back());
  return a;
}

nlohmann::json spectrumJson(const Spectrum &s, const std::string &unit) {
  return {{"period", s.period},
          {"period_unit", unit},
          {"frequency", s.period > 0 ? 1.0 / s.period : 0.0},
          {"peak_over_median_power", s.peak_over_median},
          {"peak_over_largest_power", s.peak_over_largest},
          {"peak_at_band_edge", s.at_band_edge},
          {"record", {s.x_begin, s.x_end}},
          {"method",
           "H resampled uniformly, least-squares quadratic removed, Hann window, power "
           "from 2 cycles per record up, 8x zero padding, highest local maximum, parabolic peak"},
          {"frequencies", thinned(s.frequency)},
          {"power", thinned(s.power)}};
}

nlohmann::json instabilityJson(const std::string &dir, const RunSeries &s, const Instability &m) {
  const std::size_t last = s.time.size() - 1;
  const double duration = s.time[last] - s.time[0];
  nlohmann::json j;
  j["run"] = fs::absolute(dir).lexically_normal().string();
  j["length"] = s.length;
  j["mass"] = s.mass > 0 ? nlohmann::json(s.mass) : nlohmann::json();
  j["velocity"] = s.velocity;
  j["samples"] = s.time.size();
  j["duration"] = duration;
  j["final_depth_over_length"] = m.scaled_depth[last];
  // Eq. 3.14 as printed is the lateral impulse; the average lateral force is impulse / duration
  // (what thesis Table 5.1 lists).
  j["lateral_impulse"] = m.lateral_impulse[last];
  j["average_lateral_force"] = duration > 0 ? m.lateral_impulse[last] / duration : 0.0;
  j["max_abs_lateral_force"] = maxAbs(s.lateral_force);
  j["lateral_displacement"] = m.lateral_displacement[last];
  j["max_abs_lateral_displacement"] = maxAbs(m.lateral_displacement);
  j["tilt"] = s.tilt[last];
  j["max_abs_tilt"] = maxAbs(s.tilt);
  j["rotational_momentum"] = s.rotational_momentum[last];
  j["max_abs_rotational_momentum"] = maxAbs(s.rotational_momentum);
  if (!m.radial_momentum.empty()) {
    j["radial_momentum"] = m.radial_momentum[last];
    j["max_abs_radial_momentum"] = maxAbs(m.radial_momentum);
  }
  // The oscillation of H: its period in scaled depth per cycle (thesis Table 5.3) and in time.
  j["oscillation_period_scaled_depth"] = m.in_depth.period;
  j["oscillation_period_at_band_edge"] = m.in_depth.at_band_edge;
  j["oscillation_period_time"] = m.in_time.period;
  j["oscillation_frequency_hz"] = m.in_time.period > 0 ? 1.0 / m.in_time.period : 0.0;
  j["oscillation_omega"] = m.in_time.period > 0 ? 2.0 * M_PI / m.in_time.period : 0.0;
  j["units"] = {{"length", "m"},
                {"mass", "kg/m"},
                {"lateral_impulse", "N s/m"},
                {"force", "N/m"},
                {"displacement", "m"},
                {"tilt", "rad, counter-clockwise positive"},
                {"rotational_momentum", "kg m^2/s per m"},
                {"radial_momentum", "kg m/s per m"},
                {"oscillation_period_scaled_depth", "projectile lengths per cycle"},
                {"oscillation_period_time", "s"},
                {"velocity_y", "m/s, negative: down"},
                {"axial_force", "N/m"},
                {"energy", "J/m (balance_error: relative)"}};
  j["spectrum_scaled_depth"] = spectrumJson(m.in_depth, "projectile lengths per cycle");
  j["spectrum_time"] = spectrumJson(m.in_time, "s");
  j["curves"] = {{"time", thinned(s.time)},
                 {"scaled_depth", thinned(m.scaled_depth)},
                 {"rotational_momentum", thinned(s.rotational_momentum)},
                 {"lateral_force", thinned(s.lateral_force)},
                 {"lateral_impulse", thinned(m.lateral_impulse)},
                 {"average_lateral_force", thinned(m.average_lateral_force)},
                 {"lateral_displacement", thinned(m.lateral_displacement)},
                 {"tilt", thinned(s.tilt)},
                 {"radial_momentum", thinned(m.radial_momentum)},
                 {"velocity_y", thinned(s.vy)},
                 {"axial_force", thinned(s.axial_force)}};
  nlohmann::json energy = nlohmann::json::object();
  for (const auto &[term, v] : s.energy)
    energy[term] = thinned(v);
  j["curves"]["energy"] = energy;
  return j;
}

// The plots, drawn by matplotlib from the instability.json files; a missing python3 or
// matplotlib is reported but does not fail the analysis.
bool plot(const std::string &out_dir, const std::vector<std::string> &jsons,
          const std::vector<std::string> &labels) {
  std::vector<std::string> args{out_dir};
  for (std::size_t k = 0; k < jsons.size(); ++k)
    args.push_back(jsons[k]), args.push_back(labels[k]);
  if (runPlotScript("instability.py", args))
    return true;
  std::cerr << "mesopen analyze: warning: no plots (needs /usr/bin/python3 with matplotlib, and "
            << shareDirectory() << "/instability.py)\n";
  return false;
}

// The series of the run in `dir` (its run.h5). Throws InputError.
RunSeries readRun(const std::string &dir) {
  const std::string path = dir + "/run.h5";
  std::error_code ec;
  if (!fs::exists(path, ec))
    throw InputError(path + ": no such file; allowed: directories written by `mesopen run`");
  if (!fs::is_regular_file(path, ec))
    throw InputError(path + ": not a file (a directory?); allowed: directories written by "
                            "`mesopen run`");
  try {
    return readRunSeries(path);
  } catch (const std::runtime_error &e) {
    throw InputError(e.what());
  }
}

// The measures of a run: instability.json written into `dir`, its figures returned (without the
// curves and spectra).
nlohmann::json writeInstability(const std::string &dir, const RunSeries &series) {
  nlohmann::json j = instabilityJson(dir, series, instability(series));
  writeJson(dir + "/instability.json", j);
  j.erase("curves"), j.erase("spectrum_scaled_depth"), j.erase("spectrum_time");
  return j;
}

} // namespace

nlohmann::json analyzeRun(const std::string &dir) { return writeInstability(dir, readRun(dir)); }

int analyzeCommand(const AnalyzeOptions &options) {
  const auto start = Clock::now();
  const std::string out_dir = options.out_dir.empty() ? options.dirs.front() : options.out_dir;
  std::vector<RunSeries> series;
  bool run_dir = false; // out_dir holds a run.h5
  try {
    for (const auto &dir : options.dirs)
      series.push_back(readRun(dir));
    std::vector<std::string> stale(std::begin(plot_files), std::end(plot_files));
    // A run's directory keeps its summary.json; any other must be new or analyze's own.
    std::error_code ec;
    run_dir = fs::exists(fs::path(out_dir) / "run.h5", ec);
    prepareOutputDirectory(out_dir, run_dir ? "" : "analyze", {});
    for (const auto &f : stale) { // an earlier analysis's plots
      fs::remove(fs::path(out_dir) / f, ec);
      if (ec)
        throw InputError(out_dir + ": cannot remove an earlier plot, " + f + " (" + ec.message() +
                         "); allowed: a directory mesopen analyze can write in (-o DIR)");
    }
  } catch (const InputError &e) {
    std::cerr << "mesopen analyze: " << e.what() << '\n';
    return 2;
  }
  try {
    std::vector<std::string> jsons, labels;
    nlohmann::json runs = nlohmann::json::array();
    for (std::size_t r = 0; r < series.size(); ++r) {
      const std::string &dir = options.dirs[r];
      const nlohmann::json j = writeInstability(dir, series[r]);
      jsons.push_back(dir + "/instability.json");
      labels.push_back(fs::path(dir).lexically_normal().filename().string().empty()
                           ? fs::path(dir).lexically_normal().parent_path().filename().string()
                           : fs::path(dir).lexically_normal().filename().string());
      std::printf("%s: depth %.3f L, average lateral force %.4g N/m, lateral impulse %.4g N s/m, "
                  "lateral displacement %.3g m, tilt %.3g rad, max |H| %.4g kg m^2/s, period of H "
                  "%.4f L per cycle (%.4g s)%s\n",
                  dir.c_str(), j["final_depth_over_length"].get<double>(),
                  j["average_lateral_force"].get<double>(), j["lateral_impulse"].get<double>(),
                  j["lateral_displacement"].get<double>(), j["tilt"].get<double>(),
                  j["max_abs_rotational_momentum"].get<double>(),
                  j["oscillation_period_scaled_depth"].get<double>(),
                  j["oscillation_period_time"].get<double>(),
                  j["oscillation_period_at_band_edge"].get<bool>()
                      ? ", at the edge of the band searched (not resolved by this record)"
                      : "");
      runs.push_back(j);
    }
    const bool plotted = !options.no_plot && plot(out_dir, jsons, labels);
    if (!run_dir) {
      // A directory of its own: its summary (a run's directory keeps the run's summary.json).
      nlohmann::json files = nlohmann::json::array({"summary.json"});
      if (plotted)
        for (const char *f : plot_files)
          files.push_back(f);
      writeJson(out_dir + "/summary.json", {{"command", "analyze"},
                                            {"runs", runs},
                                            {"files", files},
                                            {"wall_seconds", secondsSince(start)}});
    }
    std::cout << "mesopen analyze: instability.json in each run's directory"
              << (plotted ? ", plots (instability-*.png) in " + out_dir : std::string()) << "\n";
    return 0;
  } catch (const std::exception &e) {
    std::cerr << "mesopen analyze: failed: " << e.what() << '\n';
    return 1;
  }
}

} // namespace mesopen
