// A scene without keys sets a run up as the solver, the contact and the FE-disk contact are set up
// by default: each default has one owner.
#include "run_settings.hpp"
#include "time_loop.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace mesopen;

TEST(RunSettings, SceneDefaultsAreTheSolversDefaults) {
  const fem::SolverSettings s = solverSettings(Scene(), HUGE_VAL), d;
  EXPECT_EQ(s.safety, d.safety);
  EXPECT_EQ(s.viscosity_linear, d.viscosity_linear);
  EXPECT_EQ(s.viscosity_quadratic, d.viscosity_quadratic);
  EXPECT_EQ(s.anti_locking, d.anti_locking);
  EXPECT_EQ(s.max_dt, d.max_dt);
  EXPECT_EQ(s.max_dt_growth, d.max_dt_growth);
  EXPECT_EQ(s.dt_rise_interval, d.dt_rise_interval);
  EXPECT_EQ(s.min_dt_ratio, d.min_dt_ratio);
  EXPECT_EQ(s.erode_step_ratio, d.erode_step_ratio);
  EXPECT_EQ(s.mass_scaling_step_ratio, d.mass_scaling_step_ratio);
  EXPECT_EQ(s.chunk, d.chunk);
  EXPECT_EQ(s.max_level, d.max_level);
  Scene levels;
  levels.run.max_level = 2;
  EXPECT_EQ(solverSettings(levels, HUGE_VAL).max_level, 2);
  EXPECT_EQ(s.level_gap, d.level_gap);
  levels.run.level_gap = 1;
  EXPECT_EQ(solverSettings(levels, HUGE_VAL).level_gap, 1);
}

TEST(RunSettings, SceneDefaultsAreTheContactsDefaults) {
  const Scene scene;
  const fem::ContactSettings c = contactSettings(scene, false), d;
  ASSERT_EQ(c.friction.size(), 4u); // projectile and grains: the projectile meets no projectile
  for (std::size_t pair = 1; pair < 4; ++pair)
    EXPECT_EQ(c.friction[pair], d.friction.front()) << pair;
  EXPECT_EQ(c.wall_friction, d.wall_friction);
  EXPECT_EQ(c.stiffness, d.stiffness);
  EXPECT_EQ(c.damping, d.damping);
  EXPECT_TRUE(std::isnan(c.wall_left) && std::isnan(c.wall_right) && std::isnan(c.wall_bottom));

  const coupling::DiskContactSettings disks = diskContactSettings(scene, 3), disk_defaults;
  EXPECT_EQ(disks.stiffness, disk_defaults.stiffness);
  EXPECT_EQ(disks.damping, disk_defaults.damping);
  for (double mu : disks.friction)
    EXPECT_EQ(mu, d.friction.front());
}

// The time left, on a made-up run whose active elements grow linearly with the simulated time, as
// when more grains start to move, at a constant cost per element-step, and whose projectile slows
// at a constant rate: the estimate is within 1 % of the truth over the last half of the run (it
// is exact but for the half's first mark); a burst of other work on the machine, four times the
// pace for 4 % of the run (an eighth of its wall time), upsets it by less than 1 % once over;
// frames written as it goes do not upset it either, nor work whose cost goes by the step.
TEST(Progress, WallLeftCountsTheElementStepsLeftAndSkipsABurstOfOtherWork) {
  const double v0 = 1500.0, a = 2.0e8, end_depth = 1.4e-3; // reached at t = 1.0268 us
  const double T = (v0 - std::sqrt(v0 * v0 - 2.0 * a * end_depth)) / a;
  const double dt = T / 4000.0, cost = 40e-9; // 10 steps between marks
  auto elements = [&](double t) { return 20000.0 + 50000.0 * t / T; };
  // the wall seconds of the steps to t: cost * integral of elements(t) dt / dt
  auto compute = [&](double t) { return cost * (20000.0 * t + 25000.0 * t * t / T) / dt; };
  auto mark = [&](double wall, double t, double output = 0.0, std::size_t frames = 0) {
    return ProgressMark{wall,
                        t,
                        v0 * t - 0.5 * a * t * t,
                        v0 - a * t,
                        output,
                        frames,
                        static_cast<std::size_t>(std::lround(t / dt)),
                        elements(t)};
  };
  for (const bool burst : {false, true}) {
    // the burst: from 0.58 T to 0.62 T the wall time runs four times as fast as the work
    auto wall = [&](double t) {
      const double b0 = 0.58 * T, b1 = 0.62 * T, in = std::clamp(t, b0, b1);
      return compute(t) + (burst ? 3.0 * (compute(in) - compute(b0)) : 0.0);
    };
    std::vector<ProgressMark> marks;
    double worst = 0.0;
    for (int i = 1; i < 400; ++i) {
      const double t = T * i / 400.0;
      marks.push_back(mark(wall(t), t));
      const double left = wallLeft(marks, 5e-6, end_depth), truth = wall(T) - wall(t);
      if (wall(t) > 0.5 * wall(T) && truth > 0.02 * wall(T) && (!burst || t > 0.62 * T))
        worst = std::max(worst, std::abs(left - truth) / truth);
    }
    EXPECT_LT(worst, 0.01) << (burst ? "with" : "without") << " a burst";
  }
  // Frames every 0.093 T costing 0.5 s each: their time is taken out of the pace and the frames
  // to come added at their mean cost, within 1 %.
  {
    const double interval = 0.093 * T, frame_cost = 0.5;
    auto frames = [&](double t) { return std::floor(t / interval); };
    std::vector<ProgressMark> marks;
    double worst = 0.0;
    const double total = compute(T) + (frames(T) + 1.0) * frame_cost;
    for (int i = 1; i < 400; ++i) {
      const double t = T * i / 400.0, output = frames(t) * frame_cost;
      marks.push_back(mark(compute(t) + output, t, output, static_cast<std::size_t>(frames(t))));
      const double left = wallLeft(marks, 5e-6, end_depth, interval);
      const double truth = total - marks.back().wall;
      if (marks.back().wall > 0.5 * total && truth > 0.02 * total && frames(t) > 0)
        worst = std::max(worst, std::abs(left - truth) / truth);
    }
    EXPECT_LT(worst, 0.01);
  }
  // Work that costs the same every step whatever the elements (the DEM steps of a hybrid run),
  // 2 ms a step, as much as the elements' at the start: counted by the step, within 1 % (counted
  // by the element-step it would be 18 % high at the half and 8 % high near the end).
  {
    const double per_step = 2e-3;
    auto stepwise = [&](double t) { return per_step * t / dt; };
    std::vector<ProgressMark> marks;
    double worst = 0.0;
    const double total = compute(T) + stepwise(T);
    for (int i = 1; i < 400; ++i) {
      const double t = T * i / 400.0;
      ProgressMark m = mark(compute(t) + stepwise(t), t);
      m.stepwise = stepwise(t);
      marks.push_back(m);
      const double left = wallLeft(marks, 5e-6, end_depth), truth = total - m.wall;
      if (m.wall > 0.5 * total && truth > 0.02 * total)
        worst = std::max(worst, std::abs(left - truth) / truth);
    }
    EXPECT_LT(worst, 0.01);
  }
  // Every element of the model active from 0.7 T on (55,000): the line fitted to the active
  // elements stops there, within 1 % (without that stop, 14 % high).
  {
    const double all = 55000.0, full = 0.7 * T; // elements(full) = all
    auto capped = [&](double t) { return std::min(elements(t), all); };
    auto work = [&](double t) { // cost * integral of capped(t) dt / dt
      const double u = std::min(t, full);
      return cost * (20000.0 * u + 25000.0 * u * u / T + all * std::max(0.0, t - full)) / dt;
    };
    std::vector<ProgressMark> marks;
    double worst = 0.0;
    for (int i = 1; i < 400; ++i) {
      const double t = T * i / 400.0;
      ProgressMark m = mark(work(t), t);
      m.elements = capped(t);
      marks.push_back(m);
      const double left = wallLeft(marks, 5e-6, end_depth, 0.0, all), truth = work(T) - m.wall;
      if (m.wall > 0.5 * work(T) && truth > 0.02 * work(T))
        worst = std::max(worst, std::abs(left - truth) / truth);
    }
    EXPECT_LT(worst, 0.01);
  }
  // no depth to reach: to end_time at the pace so far; one mark: the share left
  const std::vector<ProgressMark> one{{10.0, 1e-7, 0.0, 0.0, 0.0, 0, 100, 5000.0}};
  EXPECT_DOUBLE_EQ(wallLeft(one, 4e-7, 0.0), 30.0);
  std::vector<ProgressMark> steady;
  for (int i = 1; i <= 100; ++i)
    steady.push_back({0.1 * i, 1e-9 * i, 0.0, 0.0, 0.0, 0, 10u * i, 5000.0});
  EXPECT_NEAR(wallLeft(steady, 2e-7, 0.0), 10.0, 1e-9);
}
