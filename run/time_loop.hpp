// A run's time loop: step, sample the series, take the frames, show progress, until the run's end,
// a failure or a signal to stop.
#pragma once

#include "model.hpp"
#include "output.hpp"
#include "run_output.hpp"
#include "scene.hpp"
#include "solver.hpp"

#include <string>

namespace mesopen {

class Checkpoints;

// One line on a terminal, rewritten in place at most four times a second: step, simulated time,
// depth, step size, speed and time left (from the simulated time or the depth, whichever is
// further along).
class Progress {
public:
  Progress(bool on, double end_time, double end_depth)
      : on_(on), end_time_(end_time), end_depth_(end_depth) {}
  bool due() const;
  void show(const fem::Solver &solver, double depth);
  void clear() const;

private:
  bool on_;
  double end_time_, end_depth_;
  Clock::time_point start_ = Clock::now(), last_ = Clock::now();
};

struct LoopResult {
  std::string failure;      // empty when the run reached its end
  bool interrupted = false; // by a signal
  std::string end;          // what ended it: end_time, end_depth or max_steps
  double element_steps = 0.0;
  double seconds = 0.0, solver_seconds = 0.0; // the whole loop; the steps alone
};

// "completed", "failed" or "interrupted".
std::string runStatus(const LoopResult &loop);

// The time loop: step, sample the series, take frames, show progress, write checkpoints; until
// run.end_time, run.end_depth or run.max_steps, a failure (an inverted element, a frame or a
// checkpoint that cannot be written) or SIGINT or SIGTERM (caught by catchStopSignals; the loop
// ends after its step, with a checkpoint when they are on). A run continued from a checkpoint
// goes on from its step, its figures added to the checkpoint's.
LoopResult timeLoop(const Scene &scene, const fem::Model &model, fem::Solver &solver,
                    Series &series, Frames &frames, Progress &progress, Checkpoints &checkpoints);

} // namespace mesopen
