// A run's time loop: step, sample the series, take the frames, show progress, until the run's end,
// a failure or a signal to stop.
#pragma once

#include "command_log.hpp"
#include "model.hpp"
#include "output.hpp"
#include "run_output.hpp"
#include "scene.hpp"
#include "solver.hpp"

#include <string>
#include <vector>

namespace mesopen {

// A run's progress: on a terminal one line, rewritten in place at most four times a second (step,
// simulated time, depth, step size, speed, share done, wall time left); in the log one line per
// 5 % done. The time left is the simulated time left at the pace of the last third of the run so
// far: to end_time, or to end_depth at the projectile's speed and deceleration over that third
// (a constant deceleration), whichever comes first.
class Progress {
public:
  Progress(bool terminal, CommandLog *log, double end_time, double end_depth)
      : terminal_(terminal), log_(log && log->on() ? log : nullptr), end_time_(end_time),
        end_depth_(end_depth) {}
  // Time for an update: a quarter of a second since the last (never when it shows nothing).
  bool due() const;
  // The state now: `depth` and `speed` the projectile's, downward [m, m/s].
  void update(const fem::Solver &solver, double depth, double speed);
  void clear() const;
  double done() const { return done_; } // the share of the run done, at the last update
  double left() const { return left_; } // the wall seconds left, estimated at the last update

private:
  struct Mark {
    double wall, time, depth, speed;
  };
  double estimateLeft() const;
  bool terminal_;
  CommandLog *log_;
  double end_time_, end_depth_;
  Clock::time_point start_ = Clock::now(), last_ = Clock::now();
  std::vector<Mark> marks_; // one per update
  double done_ = 0.0, left_ = 0.0;
  int logged_ = 0; // 5 % steps logged
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

// The time loop: step, sample the series, take frames, show progress; until run.end_time,
// run.end_depth or run.max_steps, a failure (an inverted element, a frame that cannot be
// written) or SIGINT or SIGTERM (caught by catchStopSignals; the loop ends after its step).
LoopResult timeLoop(const Scene &scene, const fem::Model &model, fem::Solver &solver,
                    Series &series, Frames &frames, Progress &progress);

} // namespace mesopen
