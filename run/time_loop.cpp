#include "time_loop.hpp"

#include "stop_signals.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace mesopen {

bool Progress::due() const {
  return (terminal_ || log_) && Clock::now() - last_ >= std::chrono::milliseconds(250);
}

void Progress::update(const fem::Solver &solver, double depth, double speed) {
  last_ = Clock::now();
  const double wall = secondsSince(start_), t = solver.time();
  marks_.push_back({wall, t, depth, speed});
  done_ = std::min(1.0, std::max(t / end_time_, end_depth_ > 0.0 ? depth / end_depth_ : 0.0));
  left_ = estimateLeft();
  char line[240];
  std::snprintf(line, sizeof line,
                "step %zu, t = %.3f ns, depth %.3f mm, dt = %.3g ps, %.0f steps/s, %.0f %% done, "
                "ETA %.0f s",
                solver.steps(), 1e9 * t, 1e3 * depth, 1e12 * solver.dt(),
                solver.steps() / std::max(wall, 1e-9), 100.0 * done_, left_);
  if (terminal_)
    std::fprintf(stderr, "\r\033[Kmesopen run: %s", line);
  if (log_ && static_cast<int>(20.0 * done_) > logged_) {
    logged_ = static_cast<int>(20.0 * done_);
    log_->line(line);
  }
}

// Simulated time left over the pace (wall seconds per simulated second) of the last third of the
// run so far; before two updates, the share left over the pace so far.
double Progress::estimateLeft() const {
  const Mark &now = marks_.back();
  const Mark *then = nullptr;
  for (const Mark &m : marks_)
    if (m.wall <= now.wall * (2.0 / 3.0) && m.time < now.time)
      then = &m;
  if (!then)
    return done_ > 0.0 ? now.wall * (1.0 - done_) / done_ : 0.0;
  const double span = now.time - then->time;
  const double pace = (now.wall - then->wall) / span;
  double time_left = std::max(0.0, end_time_ - now.time);
  if (end_depth_ > 0.0 && now.speed > 0.0) {
    // depth left = v tau - a tau^2 / 2 at the deceleration a of the last third
    const double depth_left = std::max(0.0, end_depth_ - now.depth);
    const double a = (then->speed - now.speed) / span, v = now.speed;
    double tau = depth_left / v;
    if (a > 0.0)
      tau = v * v > 2.0 * a * depth_left ? (v - std::sqrt(v * v - 2.0 * a * depth_left)) / a
                                         : time_left;
    time_left = std::min(time_left, tau);
  }
  return pace * time_left;
}

void Progress::clear() const {
  if (terminal_)
    std::fprintf(stderr, "\r\033[K");
}

std::string runStatus(const LoopResult &loop) {
  return loop.failure.empty() ? "completed" : loop.interrupted ? "interrupted" : "failed";
}

LoopResult timeLoop(const Scene &scene, const fem::Model &model, fem::Solver &solver,
                    Series &series, Frames &frames, Progress &progress) {
  const RunSpec &run = scene.run;
  LoopResult result;
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
    series.sample(model, solver);
    frames.offer(model, solver, true);
    for (bool last = ended(true); !last;) {
      if (stopSignal() != 0) {
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
      if (progress.due())
        progress.update(solver, series.depth(model), -series.last("projectile/vy"));
    }
  } catch (const std::exception &e) {
    result.failure = e.what();
  }
  progress.clear();
  result.seconds = secondsSince(start);
  return result;
}

} // namespace mesopen
