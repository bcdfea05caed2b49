// `mesopen run`: a tiny scene end to end, its files, bad input, and free flight.
#include "h5file.hpp"
#include "run.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>

using namespace mesopen;
using test::ScratchDir;

namespace {

const char *tiny = R"([target]
width = 0.6e-3
height = 0.3e-3
diameter = 60e-6
mesh_size = 15e-6
[projectile]
length = 0.3e-3
[run]
end_time = 2e-8
frame_interval = 1e-8
)";

} // namespace

TEST(Run, TinySceneWritesEveryOutput) {
  ScratchDir dir("run-tiny");
  test::writeFile(dir / "scene.toml", tiny);
  const auto r = test::runMesopen("run " + (dir / "scene.toml") + " -o " + (dir / "out"));
  ASSERT_EQ(r.code, 0) << r.output;
  H5File h5 = H5File::open(dir / "out/run.h5");
  const std::size_t n = h5.shape("/series/time")[0];
  EXPECT_GT(n, 10u);
  for (const char *name : {"step", "dt", "projectile/com_x", "projectile/com_y", "projectile/vx",
                           "projectile/vy", "projectile/rotational_momentum", "projectile/lateral_force",
                           "projectile/axial_force", "projectile/tilt", "projectile/depth",
                           "energy/kinetic", "energy/internal", "energy/plastic", "energy/viscous",
                           "energy/external", "energy/balance_error"})
    EXPECT_EQ(h5.shape(std::string("/series/") + name)[0], n) << name;
  EXPECT_TRUE(h5.exists("/frames/000000/x"));
  EXPECT_TRUE(h5.exists("/frames/000002/effective_stress"));
  EXPECT_EQ(h5.shape("/mesh/triangles")[1], 3u);
  // The projectile flies down at 1000 m/s: its depth grows by v t.
  const auto depth = h5.read<double>("/series/projectile/depth");
  const auto time = h5.read<double>("/series/time");
  EXPECT_NEAR(depth.back(), 1000.0 * time.back(), 1e-3 * depth.back());
  const std::string pvd = test::readFile(dir / "out/vtk/run.pvd");
  EXPECT_NE(pvd.find("frame_000002.vtu"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir / "out/vtk/frame_000002.vtu"));
  const auto summary = nlohmann::json::parse(test::readFile(dir / "out/summary.json"));
  EXPECT_EQ(summary["status"], "completed");
  EXPECT_EQ(summary["frames"], 3);
}

TEST(Run, BadInputNamesTheKey) {
  ScratchDir dir("run-bad");
  const std::pair<const char *, const char *> cases[] = {
      {"[run]\nspeed = 3\n", "run.speed"},
      {"[run]\nsafety = 1.5\n", "run.safety"},
      {"[materials.grains]\npreset = \"granite\"\n", "granite"},
      {"[materials.grains]\nyield_stress = 1e9\n", "yield_stress"},
      {"[materials.projectile]\nyield_stress = -1.0\n", "yield_stress"},
      {"[materials.projectile]\nplastic = 1\n", "plastic"},
      {"[materials.sand]\n", "materials.sand"},
  };
  for (const auto &[text, key] : cases) {
    test::writeFile(dir / "scene.toml", text);
    const auto r = test::runMesopen("run " + (dir / "scene.toml") + " -o " + (dir / "out"));
    EXPECT_EQ(r.code, 2) << text << r.output;
    EXPECT_NE(r.output.find(key), std::string::npos) << r.output;
  }
}

// The projectile alone, spinning: the series must keep its momentum and H (round-off).
TEST(Run, FreeFlightKeepsMomentum) {
  ScratchDir dir("run-free");
  test::writeFile(dir / "scene.toml", std::string(tiny) + "grains = false\nspin = 1e6\nvtk = false\n");
  const auto r = test::runMesopen("run " + (dir / "scene.toml") + " -o " + (dir / "out"));
  ASSERT_EQ(r.code, 0) << r.output;
  H5File h5 = H5File::open(dir / "out/run.h5");
  const auto vy = h5.read<double>("/series/projectile/vy");
  const auto H = h5.read<double>("/series/projectile/rotational_momentum");
  const auto tilt = h5.read<double>("/series/projectile/tilt");
  for (std::size_t i = 0; i < vy.size(); ++i) {
    EXPECT_NEAR(vy[i], -1000.0, 1e-10 * 1000.0);
    EXPECT_NEAR(H[i], H[0], 1e-10 * std::abs(H[0]));
  }
  EXPECT_NEAR(tilt.back(), 1e6 * 2e-8, 0.002); // it turns at its spin rate
  EXPECT_FALSE(std::filesystem::exists(dir / "out/vtk/run.pvd"));
}
