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

// The time left, on a made-up run whose pace (wall seconds per simulated second) grows linearly
// with the simulated time, as when more grains move and the step shrinks, and whose projectile
// slows at a constant rate: the estimate is within 2 % of the truth over the last half of the run
// (the fit is exact but for the marks' spacing); with a pace that falls to half, taken as
// constant, it errs long, by less than half; frames written as it goes do not upset it.
TEST(Progress, WallLeftFollowsAGrowingPaceAndAProjectileSlowing) {
  const double v0 = 1500.0, a = 2.0e8, end_depth = 1.4e-3; // reached at t = 1.0268 us
  const double T = (v0 - std::sqrt(v0 * v0 - 2.0 * a * end_depth)) / a;
  for (const double growth : {3.0, 0.0, -0.5}) {
    // wall(t) = p0 (t + growth t^2 / (2 T)): the pace p0 (1 + growth t / T)
    const double p0 = 60.0 / T;
    auto wall = [&](double t) { return p0 * (t + growth * t * t / (2.0 * T)); };
    std::vector<ProgressMark> marks;
    double worst = 0.0, shortest = HUGE_VAL;
    for (int i = 1; i < 400; ++i) {
      const double t = T * i / 400.0;
      marks.push_back({wall(t), t, v0 * t - 0.5 * a * t * t, v0 - a * t});
      const double left = wallLeft(marks, 5e-6, end_depth), truth = wall(T) - wall(t);
      if (wall(t) > 0.5 * wall(T) && truth > 0.02 * wall(T)) {
        worst = std::max(worst, std::abs(left - truth) / truth);
        shortest = std::min(shortest, left / truth);
      }
    }
    EXPECT_LT(worst, growth >= 0.0 ? 0.02 : 0.5) << "growth " << growth;
    if (growth < 0.0) {
      EXPECT_GE(shortest, 1.0);
    }
  }
  // Frames every 0.093 T costing 0.5 s each (5.5 s against the steps' 150 s): their time is
  // taken out of the fit and the frames to come added at their mean cost, within 2 %.
  {
    const double p0 = 60.0 / T, interval = 0.093 * T, cost = 0.5;
    auto compute = [&](double t) { return p0 * (t + 3.0 * t * t / (2.0 * T)); };
    auto frames = [&](double t) { return std::floor(t / interval); };
    std::vector<ProgressMark> marks;
    double worst = 0.0;
    const double total = compute(T) + (frames(T) + 1.0) * cost;
    for (int i = 1; i < 400; ++i) {
      const double t = T * i / 400.0, output = frames(t) * cost;
      marks.push_back({compute(t) + output, t, v0 * t - 0.5 * a * t * t, v0 - a * t, output,
                       static_cast<std::size_t>(frames(t))});
      const double left = wallLeft(marks, 5e-6, end_depth, interval);
      const double truth = total - marks.back().wall;
      if (marks.back().wall > 0.5 * total && truth > 0.02 * total && frames(t) > 0)
        worst = std::max(worst, std::abs(left - truth) / truth);
    }
    EXPECT_LT(worst, 0.02);
  }
  // no depth to reach: to end_time at the pace so far; one mark: the share left
  const std::vector<ProgressMark> one{{10.0, 1e-7, 0.0, 0.0}};
  EXPECT_DOUBLE_EQ(wallLeft(one, 4e-7, 0.0), 30.0);
  std::vector<ProgressMark> steady;
  for (int i = 1; i <= 100; ++i)
    steady.push_back({0.1 * i, 1e-9 * i, 0.0, 0.0});
  EXPECT_NEAR(wallLeft(steady, 2e-7, 0.0), 10.0, 1e-9);
}
