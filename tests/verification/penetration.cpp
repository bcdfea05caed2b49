// The thesis's run 6 (examples/baseline.toml: every grain meshed, elastic projectile at 1500 m/s,
// plastic quartz grains, friction 0.3) to one projectile length, without frames: it must end at
// that depth, with no inverted element, no NaN and no node found half an element deep in another
// body, and the energy balance of the whole run, friction and contact counted, must close within
// 2 % of the initial kinetic energy (the bound; measured 4e-4). A few minutes on two cores.
#include "run.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <regex>

using namespace mesopen;

TEST(Penetration, Run6ReachesOneLengthAndClosesItsEnergyBalance) {
  test::ScratchDir dir("run6");
  std::string scene = test::readFile(std::string(MESOPEN_SOURCE_DIR) + "/examples/baseline.toml");
  scene = std::regex_replace(scene, std::regex("frame_interval = [^\n]*"), "frame_interval = 0");
  test::writeFile(dir / "scene.toml", scene);
  const auto r =
      test::runMesopen("run " + (dir / "scene.toml") + " -o " + (dir / "out") + " --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto s = nlohmann::json::parse(test::readFile(dir / "out/summary.json"));
  EXPECT_EQ(s["status"], "completed");
  EXPECT_EQ(s["ended_by"], "end_depth");
  const double length = 1.7e-3, depth = s["projectile"]["depth"];
  EXPECT_GE(depth, length);
  EXPECT_LT(depth, 1.01 * length);
  const auto &e = s["energy"];
  const double initial = e["initial"];
  EXPECT_LT(std::abs(static_cast<double>(e["balance_error"])), 0.02);
  EXPECT_GT(static_cast<double>(e["friction"]), 0.0);
  EXPECT_GT(static_cast<double>(e["plastic"]), 0.0);
  EXPECT_LT(static_cast<double>(e["kinetic"]), initial);
  EXPECT_EQ(s["contact"]["deep_node_steps"], 0);
  EXPECT_LT(static_cast<double>(s["contact"]["deepest_penetration_over_element_size"]), 0.5);
  for (const char *k : {"vx", "vy", "tilt", "rotational_momentum"})
    EXPECT_TRUE(std::isfinite(static_cast<double>(s["projectile"][k]))) << k;
  std::printf(
      "run 6: %s steps, t = %.4g s, depth / length %.4f, balance error %.2e, tilt %.4f rad, "
      "deepest penetration %.3f elements, %.1f s\n",
      s["steps"].dump().c_str(), static_cast<double>(s["time"]), depth / length,
      static_cast<double>(e["balance_error"]), static_cast<double>(s["projectile"]["tilt"]),
      static_cast<double>(s["contact"]["deepest_penetration_over_element_size"]),
      static_cast<double>(s["wall_seconds"]));
}
