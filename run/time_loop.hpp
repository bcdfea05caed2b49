// A run's time loop: step, sample the series, take the frames, show progress, until the run's end,
// a failure or a signal to stop.
#pragma once

#include "command_log.hpp"
#include "contact.hpp"
#include "levels.hpp"
#include "model.hpp"
#include "output.hpp"
#include "run_output.hpp"
#include "scene.hpp"
#include "solver.hpp"

#include <string>
#include <vector>

namespace mesopen {

class Checkpoints;

// A moment of a run, for the estimate of the time left: wall seconds since the loop's start,
// simulated time [s], the projectile's depth [m] and downward speed [m/s], and the frames written
// so far and the wall seconds they took (within `wall`).
struct ProgressMark {
  double wall, time, depth, speed;
  double output = 0.0;
  std::size_t frames = 0;
};

// The wall seconds left until end_time, or end_depth [m] (0: none) if the projectile gets there
// first, from the marks so far (the last is now). Over the last half of the run so far the wall
// time of the steps (less the frames') is fitted by least squares as a quadratic in the simulated
// time (its pace, wall seconds per simulated second, growing as more grains move and the step
// shrinks; a pace falling is taken as constant), and the depth as reached at the projectile's
// speed now and its mean deceleration over that half; the frames to come, one per
// frame_interval [s] (0: none) and the last, at their mean cost so far. With fewer than four
// marks in that half: the share left at the pace so far.
double wallLeft(const std::vector<ProgressMark> &marks, double end_time, double end_depth,
                double frame_interval = 0.0);

// A run's progress: on a terminal one line, rewritten in place at most four times a second (step,
// simulated time, depth, step size, speed, share done, wall time left: wallLeft); in the log one
// line per 5 % done.
class Progress {
public:
  Progress(bool terminal, CommandLog *log, double end_time, double end_depth, double frame_interval)
      : terminal_(terminal), log_(log && log->on() ? log : nullptr), end_time_(end_time),
        end_depth_(end_depth), frame_interval_(frame_interval) {}
  // Time for an update: a quarter of a second since the last (never when it shows nothing).
  bool due() const;
  // The state now: `depth` and `speed` the projectile's, downward [m, m/s]; the frames written
  // and the wall seconds they took.
  void update(const fem::Solver &solver, double depth, double speed, std::size_t frames,
              double output);
  void clear() const;

private:
  bool terminal_;
  CommandLog *log_;
  double end_time_, end_depth_, frame_interval_;
  Clock::time_point start_ = Clock::now(), last_ = Clock::now();
  std::vector<ProgressMark> marks_; // one per update
  int logged_ = 0;                  // 5 % steps logged
  std::size_t first_step_ = 0;      // the step at the first update
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
// goes on from its step, its figures added to the checkpoint's. With `census` (run.level_census_
// interval), the bodies' own steps are measured every so many steps and `census` samples them with
// `contact`'s pairs and contacts of that step (none without contact).
LoopResult timeLoop(const Scene &scene, const fem::Model &model, fem::Solver &solver,
                    Series &series, Frames &frames, Progress &progress, Checkpoints &checkpoints,
                    fem::LevelCensus *census = nullptr, const fem::Contact *contact = nullptr);

} // namespace mesopen
