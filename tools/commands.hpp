// The program's subcommands. Each returns the exit code: 0 success, 2 bad input (InputError,
// message names file, key, value, allowed range), 1 a failure while running.
#pragma once

#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace mesopen {

// What every scene command takes.
struct SceneOptions {
  std::string scene;
  std::string out_dir;
  std::optional<std::uint64_t> seed; // overrides target.seed
  std::optional<int> threads;
  std::string command_line; // as typed, for the log
};

struct TargetOptions : SceneOptions {
  bool no_mesh = false; // skip meshing (grains as polygons only)
  bool no_plot = false; // skip the histogram PNG
};

int targetCommand(const TargetOptions &options);

struct RunOptions : SceneOptions {
  bool quiet = false; // no progress line
  std::string resume; // an output directory to continue from its last checkpoint
};

int runCommand(const RunOptions &options);

struct ModalOptions {
  std::string input;        // scene (.toml), target.h5 or run.h5
  std::string command_line; // as typed, for the log
  std::string out_dir;
  std::optional<int> modes; // overrides modal.modes
  std::optional<int> threads;
};

int modalCommand(const ModalOptions &options);

struct AnalyzeOptions {
  std::vector<std::string> dirs; // run directories (each with run.h5)
  std::string out_dir;           // plots; empty: the first run's directory
  bool no_plot = false;
};

int analyzeCommand(const AnalyzeOptions &options);

// The measures of instability of the run in `dir` from its run.h5: instability.json written there
// (with the curves and spectra), its figures returned (without them). Throws InputError when
// run.h5 is missing or not a run's.
nlohmann::json analyzeRun(const std::string &dir);

struct CampaignOptions {
  std::string campaign; // campaign file (TOML)
  std::string out_dir;
  std::optional<int> replicates;             // overrides campaign.replicates
  std::optional<std::string> representation; // overrides campaign.representation
  std::vector<std::string> only;             // run only these entries (by name); empty: all
  std::optional<int> threads;                // per run
  bool quiet = false;                        // no progress line
};

int campaignCommand(const CampaignOptions &options);

// Where the program's data files are (build/share/mesopen beside build/bin/mesopen).
std::string shareDirectory();

// Runs a program (words[0], a path) with its arguments, without a shell, its standard output and
// error into the file `output` (made anew, or appended to if `append`); while it runs, `waiting`
// (if given) is called about five times a second, and a signal it returns (not 0) is sent to the
// program. The program runs in a process group of its own (a terminal's Ctrl-C does not reach it).
// Returns its exit code (128 + the signal if one ended it), -1 if it did not start.
int runProgram(const std::vector<std::string> &words, const std::string &output,
               const std::function<int()> &waiting = {}, bool append = false);

// Runs /usr/bin/python3 with a plot script of shareDirectory() and its arguments, without a shell
// (paths stay paths) and with its output discarded; true when it exits with 0.
bool runPlotScript(const std::string &script, const std::vector<std::string> &args);

} // namespace mesopen
