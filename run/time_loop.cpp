#include "time_loop.hpp"

#include "checkpoint.hpp"
#include "stop_signals.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <stdexcept>

namespace mesopen {

bool Progress::due() const { return on_ && Clock::now() - last_ >= std::chrono::milliseconds(250); }

void Progress::show(const fem::Solver &solver, double depth) {
  last_ = Clock::now();
  const double wall = secondsSince(start_), t = solver.time();
  const double done = std::max(t / end_time_, end_depth_ > 0.0 ? depth / end_depth_ : 0.0);
  std::fprintf(stderr,
               "\r\033[Kmesopen run: step %zu, t = %.3f ns, depth %.3f mm, dt = %.3g ps, "
               "%.0f steps/s, %.0f %% done, ETA %.0f s",
               solver.steps(), 1e9 * t, 1e3 * depth, 1e12 * solver.dt(),
               solver.steps() / std::max(wall, 1e-9), 100.0 * done,
               std::max(0.0, wall * (1.0 - done) / std::max(done, 1e-30)));
}

void Progress::clear() const {
  if (on_)
    std::fprintf(stderr, "\r\033[K");
}

std::string runStatus(const LoopResult &loop) {
  return loop.failure.empty() ? "completed" : loop.interrupted ? "interrupted" : "failed";
}

LoopResult timeLoop(const Scene &scene, const fem::Model &model, fem::Solver &solver,
                    Series &series, Frames &frames, Progress &progress, Checkpoints &checkpoints) {
  const RunSpec &run = scene.run;
  LoopResult result = checkpoints.before();
  const auto start = Clock::now();
  const auto max_steps = static_cast<std::size_t>(run.max_steps);
  const auto every = static_cast<std::size_t>(run.series_interval);
  const double end_depth = run.end_depth * scene.projectile.length;
  // (the depth is the series' own when it was just sampled)
  auto ended = [&](bool sampled) {
    if (solver.time() >= run.end_time)
      result.end = "end_time";
    else if (end_depth > 0.0 &&
             (sampled ? series.last("projectile/depth") : series.depth(model)) >= end_depth)
      result.end = "end_depth";
    else if (solver.steps() >= max_steps)
      result.end = "max_steps";
    return !result.end.empty();
  };
  try {
    // (a run continued from a checkpoint has its first sample and frame, and had not ended)
    if (!checkpoints.resumed()) {
      series.sample(model, solver);
      frames.offer(model, solver, true);
    }
    for (bool last = !checkpoints.resumed() && ended(true); !last;) {
      if (checkpoints.stopBySignal(result)) {
        result.interrupted = true;
        result.failure = std::string("stopped by ") + stopSignalName() + " at step " +
                         std::to_string(solver.steps());
        break;
      }
      const auto step_start = Clock::now();
      const double before = solver.time();
      solver.step();
      if (!(solver.time() > before)) {
        char text[200];
        std::snprintf(text, sizeof text,
                      "step %zu did not advance the time (t = %.6g s, dt = %.6g s): the stable "
                      "step has fallen to nothing",
                      solver.steps(), before, solver.dt());
        throw std::runtime_error(text);
      }
      result.solver_seconds += secondsSince(step_start);
      result.element_steps += static_cast<double>(solver.activeElements());
      const bool due = solver.steps() % every == 0;
      if (due)
        series.sample(model, solver);
      last = ended(due);
      if (last && !due)
        series.sample(model, solver);
      frames.offer(model, solver, last);
      if (!last)
        checkpoints.afterStep(result);
      if (progress.due())
        progress.show(solver, series.depth(model));
    }
  } catch (const std::exception &e) {
    result.failure = e.what();
  }
  progress.clear();
  result.seconds = checkpoints.before().seconds + secondsSince(start);
  return result;
}

} // namespace mesopen
