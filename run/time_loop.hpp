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

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace mesopen {

class Checkpoints;

// A moment of a run, for the estimate of the time left: wall seconds since the loop's start,
// simulated time [s], the projectile's depth [m] and downward speed [m/s], the frames written so
// far and the wall seconds they took (within `wall`), the steps taken, the active elements, and
// the wall seconds (within `wall`) of the work whose cost goes by the step, not by the element
// (the FE-DEM coupling: the DEM steps and the disks' contact).
struct ProgressMark {
  double wall = 0.0, time = 0.0, depth = 0.0, speed = 0.0;
  double output = 0.0;
  std::size_t frames = 0, steps = 0;
  double elements = 0.0;
  double stepwise = 0.0;
};

// The wall seconds left until end_time, or end_depth [m] (0: none) if the projectile gets there
// first, from the marks so far (the last is now). The work left is counted in element-steps: the
// depth is reached at the projectile's speed now and its mean deceleration over the last half of
// the run so far, in steps of the mean step over that half, with the active elements growing as
// a line fitted over it, up to max_elements (the model's: 0, none). An element-step costs the
// median of its wall time over the element-steps of that half (the frames' and the stepwise work's
// time taken out), a step of the stepwise work the median over the steps of that half; the frames
// to come, one per frame_interval [s] (0: none) and the last, cost their mean so far. With fewer
// than five marks in that half: the share left at the pace so far.
double wallLeft(const std::vector<ProgressMark> &marks, double end_time, double end_depth,
                double frame_interval = 0.0, double max_elements = 0.0);

// A run's progress: on a terminal one line, rewritten in place at most four times a second (step,
// simulated time, depth, step size, speed, share done, wall time left: wallLeft); in the log one
// line per 5 % done.
class Progress {
public:
  // elements: the model's, which the active ones never pass.
  Progress(bool terminal, CommandLog *log, double end_time, double end_depth, double frame_interval,
           std::size_t elements)
      : terminal_(terminal), log_(log && log->on() ? log : nullptr), end_time_(end_time),
        end_depth_(end_depth), frame_interval_(frame_interval),
        elements_(static_cast<double>(elements)) {}
  // Time for an update: a quarter of a second since the last (never when it shows nothing).
  bool due() const;
  // The state now: `depth` and `speed` the projectile's, downward [m, m/s]; the frames written
  // and the wall seconds they took.
  void update(const fem::Solver &solver, double depth, double speed, std::size_t frames,
              double output);
  void clear() const;
  // The wall seconds so far of the work whose cost goes by the step (ProgressMark::stepwise).
  void countByTheStep(std::function<double()> seconds) { stepwise_ = std::move(seconds); }

private:
  bool terminal_;
  CommandLog *log_;
  double end_time_, end_depth_, frame_interval_, elements_;
  Clock::time_point start_ = Clock::now(), last_ = Clock::now();
  std::function<double()> stepwise_;
  std::vector<ProgressMark> marks_; // one per update
  int logged_ = 0;                  // 5 % steps logged
};

struct LoopResult {
  std::string failure;      // empty when the run reached its end
  bool interrupted = false; // by a signal
  std::string end;          // what ended it: end_time, end_depth or max_steps
  double element_steps = 0.0;
  double seconds = 0.0, solver_seconds = 0.0; // the whole loop; the steps alone
  // This process's messages from the others (parallel::traffic: bytes as a gather counts them)
  // over the steps it took (not those before a checkpoint): within the steps (the solver's
  // exchanges, the coupling's, a new partition's), the most within one step and the collective
  // operations within them; and in the loop outside the steps (the series, frames and checkpoints,
  // the flags of a signal or of a failure). Not kept in checkpoints.
  std::int64_t step_bytes = 0, max_step_bytes = 0, step_operations = 0, step_messages = 0,
               other_bytes = 0;
  std::size_t counted_steps = 0;
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
