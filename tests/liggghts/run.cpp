// `mesopen run` with disks: a tiny hybrid scene end to end.
#include "run.hpp"
#include "h5file.hpp"

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
// the disks, dem.data and liggghts.log, and its summary counts the disks and the windows (the
// disks' steps, each of several FE steps); the FE energy balance closes (1e-2: a few dozen steps of
// a stiff impact on a coarse mesh).
TEST(LiggghtsRun, TinyHybridRunWritesItsFiles) {
  ScratchDir dir("run-hybrid");
  test::writeFile(dir / "scene.toml", test::tinyScene("representation = \"hybrid\"\n"
                                                      "frame_interval = 1e-8\n"));
  const auto r =
      test::runMesopen("run " + (dir / "scene.toml") + " -o " + (dir / "out") + " --quiet");
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

// A target of disks, and a hybrid one, with the projectile at rest on them, with either preset
// of disks (inscribed, linear law; equal-area disks pushed apart, Hertzian law with rolling
// resistance): nothing presses on anything at t = 0 (no disk overlaps a wall, another disk, a
// meshed grain or the projectile), so after 1 us every disk and node is still at rest. Tolerance
// 1e-6 m/s: round-off of touching contacts gives about 1e-11 m/s; a disk started across a wall by
// a few per cent of its radius leaves at metres per second (120 m/s measured).
TEST(LiggghtsRun, TargetAtRestStaysAtRest) {
  for (const std::string representation : {"dem", "hybrid", "dem\"\n[dem]\npreset = \"quartz-bulk",
                                           "hybrid\"\n[dem]\npreset = \"quartz-bulk"}) {
    ScratchDir dir("run-rest-" + std::to_string(representation.size()));
    const auto r = test::runScene(
        dir, "[target]\nwidth = 0.8e-3\nheight = 0.5e-3\ndiameter = [42e-6, 78e-6]\n"
             "mesh_size = 12e-6\nseed = 2\n[projectile]\nlength = 0.6e-3\n"
             "[run]\nvelocity = 0\nend_time = 1e-6\nframe_interval = 0.5e-6\nvtk = false\n"
             "band_half_width = 0.15e-3\nrepresentation = \"" +
                 representation + "\"\n");
    ASSERT_EQ(r.code, 0) << r.output;
    const H5File h5 = H5File::open(dir / "out/run.h5");
    for (const char *frame : {"000001", "000002"}) {
      const std::string f = std::string("/frames/") + frame;
      const auto vx = h5.read<double>(f + "/disks/vx"), vy = h5.read<double>(f + "/disks/vy");
      ASSERT_GT(vx.size(), 20u) << representation;
      double fastest = 0.0;
      for (std::size_t i = 0; i < vx.size(); ++i)
        fastest = std::max(fastest, std::hypot(vx[i], vy[i]));
      EXPECT_LT(fastest, 1e-6) << representation << " frame " << frame;
      const auto nx = h5.read<double>(f + "/vx"), ny = h5.read<double>(f + "/vy");
      double node = 0.0;
      for (std::size_t a = 0; a < nx.size(); ++a)
        node = std::max(node, std::hypot(nx[a], ny[a]));
      EXPECT_LT(node, 1e-6) << representation << " frame " << frame;
    }
  }
}

// A dem.step longer than the disks' stable step is bad input: exit 2, the numbers in the message
// readable (they were printed as 0.000000 s), no run.h5.
TEST(LiggghtsRun, TooLongDemStepIsBadInput) {
  ScratchDir dir("run-dem-step");
  const auto r =
      test::runScene(dir, test::tinyScene("representation = \"dem\"\n[dem]\nstep = 1e-6\n"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("dem.step = 1e-06 s is longer than the disks' stable step, "),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("0.000000"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out/run.h5"));
}

// A skin too large for LIGGGHTS's neighbour bins in the box (it exited the process: exit 1, no
// message, no summary) is bad input, said before LIGGGHTS starts; the largest skin allowed runs.
TEST(LiggghtsRun, TooLargeSkinIsBadInput) {
  ScratchDir dir("run-dem-skin");
  auto r = test::runScene(dir, test::tinyScene("representation = \"dem\"\n[dem]\nskin = 0.1\n"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("dem.skin = 0.1 m is too large for LIGGGHTS's neighbour bins in this "
                          "box; allowed: 0 < skin <= 0.00588 m"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out/run.h5"));
  r = test::runScene(dir, test::tinyScene("representation = \"dem\"\n[dem]\nskin = 0.00588\n"));
  EXPECT_EQ(r.code, 0) << r.output;
}

// A hybrid band that covers every grain meshes them all (it dropped them: the run had the
// projectile alone, its kinetic energy constant): the run is then fully meshed, without disks.
TEST(LiggghtsRun, BandOverEveryGrainMeshesThemAll) {
  ScratchDir dir("run-band-all");
  const auto r =
      test::runScene(dir, test::tinyScene("representation = \"hybrid\"\nband_half_width = 10\n"
                                          "frame_interval = 0\nvelocity = 500\n"));
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(dir / "out/summary.json");
  const nlohmann::json s = nlohmann::json::parse(in);
  EXPECT_GT(s["model"]["bodies"].get<int>(), 10);
  EXPECT_FALSE(s.contains("dem"));
  EXPECT_GT(s["model"]["fixed_nodes"].get<int>(), 0);
}
