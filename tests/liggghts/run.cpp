// `mesopen run` with disks: a tiny hybrid scene end to end.
#include "h5file.hpp"
#include "run.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <vector>

using namespace mesopen;
using test::ScratchDir;

// The tiny scene's grains near the path meshed, the others LIGGGHTS disks: the run completes,
// writes run.h5 (its frames with the disks), summary.json, the VTK frames of the FE bodies and of
// the disks, dem.data and liggghts.log, and its summary counts the disks and the windows (the disks' steps, each of several FE steps); the FE
// energy balance closes (1e-2: a few dozen steps of a stiff impact on a coarse mesh).
TEST(LiggghtsRun, TinyHybridRunWritesItsFiles) {
  ScratchDir dir("run-hybrid");
  test::writeFile(dir / "scene.toml", test::tinyScene("representation = \"hybrid\"\n"
                                                      "frame_interval = 1e-8\n"));
  const auto r = test::runMesopen("run " + (dir / "scene.toml") + " -o " + (dir / "out") + " --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char *file : {"run.h5", "summary.json", "dem.data", "liggghts.log", "vtk/run.pvd",
                           "vtk/disks_000000.vtu"})
    EXPECT_TRUE(std::filesystem::exists(dir / (std::string("out/") + file))) << file;
  std::ifstream in(dir / "out/summary.json");
  const nlohmann::json s = nlohmann::json::parse(in);
  EXPECT_EQ(s["representation"], "hybrid");
  EXPECT_EQ(s["status"], "completed");
  EXPECT_GT(s["dem"]["disks"].get<int>(), 10);
  EXPECT_GT(s["model"]["bodies"].get<int>(), 1); // the projectile and meshed grains
  // the disks' steps: windows of several FE steps, each a whole number of them
  EXPECT_GT(s["dem"]["windows"].get<int>(), 0);
  EXPECT_LT(s["dem"]["windows"].get<int>(), s["steps"].get<int>());
  EXPECT_GT(s["dem"]["window"].get<double>(), 0.0);
  EXPECT_LT(std::abs(s["energy"]["balance_error"].get<double>()), 1e-2);
  // every frame holds the disks
  const H5File h5 = H5File::open(dir / "out/run.h5");
  for (const char *frame : {"000000", "000001"})
    EXPECT_EQ(h5.read<double>(std::string("/frames/") + frame + "/disks/radius").size(),
              s["dem"]["disks"].get<std::size_t>());
}

// The band of meshed grains reaches band_depth below the projectile's tip and no deeper (grains
// whose centres lie deeper are disks); without it and without an end depth, the whole target's
// height. The tiny target is 0.3 mm high, its grains 60 um: with band_depth = 0.1 mm no node of a
// meshed grain lies deeper than 0.1 mm plus a grain diameter below the tip, and without the limit
// some do.
TEST(LiggghtsRun, HybridBandEndsAtItsDepth) {
  auto deepest = [](const std::string &band) {
    ScratchDir dir("run-hybrid-band");
    const auto r = test::runScene(dir, test::tinyScene("representation = \"hybrid\"\n"
                                                       "frame_interval = 0\nmax_steps = 1\n" +
                                                       band));
    EXPECT_EQ(r.code, 0) << r.output;
    const H5File h5 = H5File::open(dir / "out/run.h5");
    const auto y = h5.read<double>("/mesh/y");
    const auto body = h5.read<std::uint32_t>("/mesh/node_body");
    double tip = HUGE_VAL, lowest = HUGE_VAL;
    for (std::size_t a = 0; a < y.size(); ++a)
      (body[a] == 0 ? tip : lowest) = std::min(body[a] == 0 ? tip : lowest, y[a]);
    return tip - lowest; // how deep below the tip the meshed grains reach
  };
  const double limited = deepest("band_depth = 0.1e-3\n"), whole = deepest("");
  EXPECT_LT(limited, 0.1e-3 + 60e-6);
  EXPECT_GT(whole, limited + 60e-6);
}
