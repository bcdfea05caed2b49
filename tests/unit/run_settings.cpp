// A scene without keys sets a run up as the solver, the contact and the FE-disk contact are set up
// by default: each default has one owner.
#include "run_settings.hpp"

#include <gtest/gtest.h>

#include <cmath>

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
