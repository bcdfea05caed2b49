#include "time_loop.hpp"

#include "checkpoint.hpp"
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

void Progress::update(const fem::Solver &solver, double depth, double speed, std::size_t frames,
                      double output) {
  last_ = Clock::now();
  const double wall = secondsSince(start_), t = solver.time();
  if (marks_.empty())
    first_step_ = solver.steps();
  marks_.push_back({wall, t, depth, speed, output, frames});
  const double done =
      std::min(1.0, std::max(t / end_time_, end_depth_ > 0.0 ? depth / end_depth_ : 0.0));
  char line[240];
  std::snprintf(line, sizeof line,
                "step %zu, t = %.3f ns, depth %.3f mm, dt = %.3g ps, %.0f steps/s, %.0f %% done, "
                "ETA %.3g s",
                solver.steps(), 1e9 * t, 1e3 * depth, 1e12 * solver.dt(),
                static_cast<double>(solver.steps() - first_step_) /
                    std::max(wall - marks_.front().wall, 1e-9),
                100.0 * done, wallLeft(marks_, end_time_, end_depth_, frame_interval_));
  if (terminal_)
    std::fprintf(stderr, "\r\033[Kmesopen run: %s", line);
  if (log_ && static_cast<int>(20.0 * done) > logged_) {
    logged_ = static_cast<int>(20.0 * done);
    log_->line(line);
  }
}

double wallLeft(const std::vector<ProgressMark> &marks, double end_time, double end_depth,
                double frame_interval) {
  if (marks.empty())
    return 0.0;
  const ProgressMark &now = marks.back();
  std::size_t first = marks.size() - 1; // the first mark of the last half
  while (first > 0 && marks[first - 1].wall >= 0.5 * now.wall)
    --first;
  const double span = now.time - marks[first].time;
  if (marks.size() - first < 4 || !(span > 0.0)) {
    auto done = [&](const ProgressMark &m) {
      return std::max(m.time / end_time, end_depth > 0.0 ? m.depth / end_depth : 0.0);
    };
    // the share left at the pace since the first mark (a resumed run's first is not at 0)
    const ProgressMark &start = marks.size() > 1 ? marks.front() : ProgressMark{0.0, 0.0, 0.0, 0.0};
    const double gained = done(now) - done(start);
    return gained > 0.0 ? std::max(0.0, (now.wall - start.wall) * (1.0 - done(now)) / gained) : 0.0;
  }
  // Simulated time left: to end_time, or to end_depth at deceleration a if it comes first,
  // depth left = v tau - a tau^2 / 2.
  double time_left = std::max(0.0, end_time - now.time);
  if (end_depth > 0.0 && now.speed > 0.0) {
    const double depth_left = std::max(0.0, end_depth - now.depth), v = now.speed;
    const double a = (marks[first].speed - v) / span;
    double tau = depth_left / v;
    if (a > 0.0)
      tau = v * v > 2.0 * a * depth_left ? (v - std::sqrt(v * v - 2.0 * a * depth_left)) / a
                                         : time_left;
    time_left = std::min(time_left, tau);
  }
  // wall = c0 + c1 x + c2 x^2 by least squares, x = (t - t_now) / span in [-1, 0]: the normal
  // equations' sums of x^k (k = 0..4) and of wall x^k (k = 0..2), solved by Cramer's rule; a
  // falling pace (c2 < 0) is fitted again as a line.
  double sx[5] = {}, sw[3] = {};
  for (std::size_t i = first; i < marks.size(); ++i) {
    const double x = (marks[i].time - now.time) / span;
    double xk = 1.0;
    for (int k = 0; k < 5; ++k, xk *= x) {
      sx[k] += xk;
      if (k < 3)
        sw[k] += (marks[i].wall - marks[i].output) * xk;
    }
  }
  auto det3 = [](double a, double b, double c, double d, double e, double f, double g, double h,
                 double i) {
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g);
  };
  const double d = det3(sx[0], sx[1], sx[2], sx[1], sx[2], sx[3], sx[2], sx[3], sx[4]);
  double c1 = 0.0, c2 = -1.0;
  if (d != 0.0) {
    c1 = det3(sx[0], sw[0], sx[2], sx[1], sw[1], sx[3], sx[2], sw[2], sx[4]) / d;
    c2 = det3(sx[0], sx[1], sw[0], sx[1], sx[2], sw[1], sx[2], sx[3], sw[2]) / d;
  }
  if (!(c2 >= 0.0)) {
    c2 = 0.0;
    const double d2 = sx[0] * sx[2] - sx[1] * sx[1];
    c1 = d2 != 0.0 ? (sx[0] * sw[1] - sx[1] * sw[0]) / d2
                   : (now.wall - now.output) - (marks[first].wall - marks[first].output);
  }
  const double X = time_left / span;
  // the frames to come: one per frame_interval to the end, and the last
  double frames_left = 0.0;
  if (frame_interval > 0.0 && now.frames > 0)
    frames_left = std::floor((now.time + time_left) / frame_interval) -
                  std::floor(now.time / frame_interval) + 1.0;
  const double frame_cost = now.frames > 0 ? now.output / static_cast<double>(now.frames) : 0.0;
  return std::max(0.0, c1 * X + c2 * X * X) + frames_left * frame_cost;
}

void Progress::clear() const {
  if (terminal_)
    std::fprintf(stderr, "\r\033[K");
}

std::string runStatus(const LoopResult &loop) {
  return loop.failure.empty() ? "completed" : loop.interrupted ? "interrupted" : "failed";
}

LoopResult timeLoop(const Scene &scene, const fem::Model &model, fem::Solver &solver,
                    Series &series, Frames &frames, Progress &progress, Checkpoints &checkpoints,
                    fem::LevelCensus *census, const fem::Contact *contact) {
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
    // the frames of the loop and the wall time they take, for the time left (Progress)
    const std::size_t frames_before = frames.size();
    const double output_before = frames.seconds();
    for (bool last = !checkpoints.resumed() && ended(true); !last;) {
      if (checkpoints.stopBySignal(result)) {
        result.interrupted = true;
        result.failure = std::string("stopped by ") + stopSignalName() + " at step " +
                         std::to_string(solver.steps());
        break;
      }
      const auto census_every = static_cast<std::size_t>(run.level_census_interval);
      if (census && (solver.steps() + 1) % census_every == 0)
        solver.measureBodySteps();
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
      if (census && solver.bodyStepsAt() == solver.steps())
        census->sample(model, solver.time(), solver.steps(), solver.bodySteps(), solver.dt(),
                       contact ? contact->overlappingPairs()
                               : std::vector<std::pair<std::uint32_t, std::uint32_t>>{},
                       contact ? contact->lastContacts()
                               : std::vector<fem::Contact::BodyContact>{});
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
        progress.update(solver, series.depth(model), -series.last("projectile/vy"),
                        frames.size() - frames_before, frames.seconds() - output_before);
    }
  } catch (const std::exception &e) {
    result.failure = e.what();
  }
  progress.clear();
  result.seconds = checkpoints.before().seconds + secondsSince(start);
  return result;
}

} // namespace mesopen
