#include "time_loop.hpp"

#include "checkpoint.hpp"
#include "mpi_communicator.hpp"
#include "stop_signals.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace mesopen {

bool Progress::due() const {
  return (terminal_ || log_) && Clock::now() - last_ >= std::chrono::milliseconds(250);
}

void Progress::update(const fem::Solver &solver, double depth, double speed, std::size_t frames,
                      double output) {
  last_ = Clock::now();
  const double wall = secondsSince(start_), t = solver.time();
  marks_.push_back({wall, t, depth, speed, output, frames, solver.steps(),
                    static_cast<double>(solver.activeElements()), stepwise_ ? stepwise_() : 0.0});
  const double done =
      std::min(1.0, std::max(t / end_time_, end_depth_ > 0.0 ? depth / end_depth_ : 0.0));
  char line[240];
  std::snprintf(line, sizeof line,
                "step %zu, t = %.3f ns, depth %.3f mm, dt = %.3g ps, %.0f steps/s, %.0f %% done, "
                "ETA %.3g s",
                solver.steps(), 1e9 * t, 1e3 * depth, 1e12 * solver.dt(),
                static_cast<double>(solver.steps() - marks_.front().steps) /
                    std::max(wall - marks_.front().wall, 1e-9),
                100.0 * done, wallLeft(marks_, end_time_, end_depth_, frame_interval_, elements_));
  if (terminal_)
    std::fprintf(stderr, "\r\033[Kmesopen run: %s", line);
  if (log_ && static_cast<int>(20.0 * done) > logged_) {
    logged_ = static_cast<int>(20.0 * done);
    log_->line(line);
  }
}

namespace {

// The value that the values holding half the weight lie below: (value, weight) pairs, sorted here.
double weightedMedian(std::vector<std::pair<double, double>> &values) {
  std::sort(values.begin(), values.end());
  double total = 0.0, below = 0.0;
  for (const auto &[value, weight] : values)
    total += weight;
  for (const auto &[value, weight] : values)
    if ((below += weight) >= 0.5 * total)
      return value;
  return values.back().first;
}

} // namespace

double wallLeft(const std::vector<ProgressMark> &marks, double end_time, double end_depth,
                double frame_interval, double max_elements) {
  if (marks.empty())
    return 0.0;
  const ProgressMark &now = marks.back();
  std::size_t first = marks.size() - 1; // the first mark of the last half
  while (first > 0 && marks[first - 1].wall >= 0.5 * now.wall)
    --first;
  const double span = now.time - marks[first].time;
  if (marks.size() - first < 5 || !(span > 0.0) || now.steps <= marks[first].steps) {
    auto done = [&](const ProgressMark &m) {
      return std::max(m.time / end_time, end_depth > 0.0 ? m.depth / end_depth : 0.0);
    };
    // the share left at the pace since the first mark (a resumed run's first is not at 0)
    const ProgressMark &start = marks.size() > 1 ? marks.front() : ProgressMark{};
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
  // Element-steps left: time_left / dt steps at the step's mean over the half, of the active
  // elements fitted as a line in the simulated time (they grow as grains start to move),
  // n(t_now + tau) = n0 + g tau up to max_elements, averaged over the time left.
  double st = 0.0, sn = 0.0, stt = 0.0, stn = 0.0;
  const double count = static_cast<double>(marks.size() - first);
  for (std::size_t i = first; i < marks.size(); ++i) {
    const double x = marks[i].time - now.time, n = marks[i].elements;
    st += x, sn += n, stt += x * x, stn += x * n;
  }
  const double d = count * stt - st * st;
  const double g = d > 0.0 ? (count * stn - st * sn) / d : 0.0, n0 = (sn - g * st) / count;
  double elements = std::max(0.0, n0 + 0.5 * g * time_left);
  if (max_elements > 0.0 && g > 0.0 && time_left > 0.0 && n0 + g * time_left > max_elements) {
    const double reached = std::clamp((max_elements - n0) / g, 0.0, time_left); // n = max there
    elements =
        (std::max(0.0, n0 + 0.5 * g * reached) * reached + max_elements * (time_left - reached)) /
        time_left;
  }
  const double dt = span / static_cast<double>(now.steps - marks[first].steps);
  const double element_steps_left = time_left / dt * elements;
  // Wall seconds per element-step: the median over the element-steps of the half (the pace that
  // half of them ran faster than). An interval slowed by other work on the machine holds few
  // element-steps, so a burst of it weighs little, where the intervals' plain mean follows it.
  // The stepwise work's wall seconds per step likewise, over the steps of the half.
  std::vector<std::pair<double, double>> per_element, per_step; // (wall seconds per unit, units)
  for (std::size_t i = first + 1; i < marks.size(); ++i) {
    const ProgressMark &m = marks[i], &p = marks[i - 1];
    const double steps = static_cast<double>(m.steps - p.steps);
    const double work = 0.5 * (std::max(m.elements, 1.0) + std::max(p.elements, 1.0)) * steps;
    if (work > 0.0) {
      const double stepwise = m.stepwise - p.stepwise;
      per_element.emplace_back(((m.wall - m.output) - (p.wall - p.output) - stepwise) / work, work);
      per_step.emplace_back(stepwise / steps, steps);
    }
  }
  if (per_element.empty())
    return 0.0;
  const double steps_left = time_left / dt;
  // the frames to come: one per frame_interval to the end, and the last
  double frames_left = 0.0;
  if (frame_interval > 0.0 && now.frames > 0)
    frames_left = std::floor((now.time + time_left) / frame_interval) -
                  std::floor(now.time / frame_interval) + 1.0;
  const double frame_cost = now.frames > 0 ? now.output / static_cast<double>(now.frames) : 0.0;
  return weightedMedian(per_element) * element_steps_left + weightedMedian(per_step) * steps_left +
         frames_left * frame_cost;
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
             (sampled ? series.last("projectile/depth") : series.depth(model, solver)) >= end_depth)
      result.end = "end_depth";
    else if (solver.steps() >= max_steps)
      result.end = "max_steps";
    return !result.end.empty();
  };
  // The output of a step (frames, checkpoints: the first process writes the files), its failure
  // known to every process, which all end together: the others would otherwise wait for the
  // failed one in the next step's exchanges. The processes agree on it, on a stop signal (the
  // largest any caught; the loop stops on it) and on whether rank 0's clock calls for a checkpoint
  // in the next step's one reduction (Solver::agreeInNextStep; `now`: in one of their own, before
  // the loop and after its last step).
  const parallel::Communicator &processes = solver.processes();
  const bool shared = processes.size() > 1;
  constexpr double failed = 65536.0; // above every signal number
  int agreed_signal = 0;
  bool agreed_late = false; // (with several processes) a checkpoint by the clock, agreed on
  std::string failure;      // this process's output failure, until the processes agree on it
  auto agree = [&](const std::vector<double> &worst) {
    if (worst.empty()) // (the first step carries nothing)
      return;
    if (worst.at(0) >= failed && failure.empty())
      failure = "another process failed (its message is in mpirun's output); stopped at step " +
                std::to_string(solver.steps());
    agreed_signal = static_cast<int>(std::fmod(worst[0], failed));
    if (agreed_signal != 0)
      setStopSignal(agreed_signal);
    agreed_late = worst.at(1) > 0.0;
    if (!failure.empty())
      throw std::runtime_error(failure);
  };
  auto together = [&](const auto &output, bool now) {
    try {
      output();
    } catch (const std::exception &e) {
      failure = e.what();
    }
    // (the clock read after the output: a checkpoint it wrote set it back)
    std::vector<double> mine = {(failure.empty() ? 0.0 : failed) +
                                    static_cast<double>(stopSignal()),
                                shared && checkpoints.lateByClock() ? 1.0 : 0.0};
    if (!shared)
      agree(mine);
    else if (now)
      agree(processes.max(std::move(mine)));
    else
      solver.agreeInNextStep(std::move(mine));
  };
  // (a test's failure of one process in a step: MESOPEN_FAIL_AT_STEP=N, before step N)
  const char *fail_text = std::getenv("MESOPEN_FAIL_AT_STEP");
  const std::size_t fail_at = fail_text ? std::strtoull(fail_text, nullptr, 10) : 0;
  const parallel::Traffic loop_start = parallel::traffic();
  try {
    // (a run continued from a checkpoint has its first sample and frame, and had not ended)
    together(
        [&] {
          if (!checkpoints.resumed()) {
            series.sample(model, solver);
            frames.offer(model, solver, true);
          }
        },
        true);
    // the frames of the loop and the wall time they take, for the time left (Progress)
    const std::size_t frames_before = frames.size();
    const double output_before = frames.seconds();
    for (bool last = !checkpoints.resumed() && ended(true); !last;) {
      // (before a stop the processes agree on an output failure since, at once: it is the run's)
      if (shared && agreed_signal != 0)
        together([] {}, true);
      if (checkpoints.stopBySignal(result, agreed_signal)) {
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
      const parallel::Traffic traffic_before = parallel::traffic();
      try {
        if (fail_at > 0 && solver.steps() + 1 == fail_at)
          throw std::logic_error("a failure asked for by MESOPEN_FAIL_AT_STEP");
        solver.step();
      } catch (const fem::RunFailure &) {
        throw; // (every process's: the step's reduction said so)
      } catch (const std::exception &e) {
        if (!shared)
          throw;
        // (this process's alone: the others would wait for it in the step's next exchange)
        parallel::abortEveryProcess("step " + std::to_string(solver.steps() + 1) + ": " + e.what());
      }
      const parallel::Traffic traffic_after = parallel::traffic();
      const std::int64_t step_bytes = traffic_after.bytes - traffic_before.bytes;
      result.step_bytes += step_bytes;
      result.max_step_bytes = std::max(result.max_step_bytes, step_bytes);
      result.step_operations += traffic_after.operations - traffic_before.operations;
      result.step_messages += traffic_after.messages - traffic_before.messages;
      ++result.counted_steps;
      if (shared)
        agree(solver.agreedInLastStep());
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
      // (the series, in memory, is every process's: all end at the same step; the files are
      // written in `together`)
      const bool due = solver.steps() % every == 0;
      if (due)
        series.sample(model, solver);
      last = ended(due);
      if (last && !due)
        series.sample(model, solver);
      together(
          [&] {
            // (a frame failed on this process: it takes part in the checkpoint's gathers)
            std::string frame_failure;
            try {
              frames.offer(model, solver, last);
            } catch (const std::exception &e) {
              frame_failure = e.what();
            }
            if (!last)
              checkpoints.afterStep(result, shared ? agreed_late : checkpoints.lateByClock(),
                                    !frame_failure.empty());
            if (!frame_failure.empty())
              throw std::runtime_error(frame_failure);
          },
          last);
      if (progress.due())
        progress.update(solver, series.last("projectile/depth"), -series.last("projectile/vy"),
                        frames.size() - frames_before, frames.seconds() - output_before);
    }
  } catch (const std::exception &e) {
    result.failure = e.what();
  }
  progress.clear();
  result.other_bytes = parallel::traffic().bytes - loop_start.bytes - result.step_bytes;
  result.seconds = checkpoints.before().seconds + secondsSince(start);
  return result;
}

} // namespace mesopen
