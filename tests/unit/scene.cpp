// Scenes are strict: every bad input stops with a message that names the file, the key, the
// value and what is allowed, and the program exits with code 2.
#include "scene.hpp"
#include "run.hpp"

#include <gtest/gtest.h>

using namespace mesopen;
using mesopen::test::ScratchDir;

namespace {

// The message of the InputError that reading `text` as a scene raises ("" if none).
std::string errorOf(const ScratchDir &dir, const std::string &text) {
  const std::string path = dir / "scene.toml";
  mesopen::test::writeFile(path, text);
  try {
    readScene(path);
  } catch (const InputError &e) {
    return e.what();
  }
  return "";
}

} // namespace

TEST(Scene, ReadsTheBaselineExample) {
  const Scene s = readScene(std::string(MESOPEN_SOURCE_DIR) + "/examples/targets/baseline.toml");
  EXPECT_DOUBLE_EQ(s.target.width, 7.076e-3);
  EXPECT_DOUBLE_EQ(s.target.diameter_min, 42e-6);
  EXPECT_DOUBLE_EQ(s.target.diameter_max, 78e-6);
  EXPECT_EQ(s.target.placement, Placement::regular);
  EXPECT_EQ(s.target.mesh, MeshKind::quality);
  EXPECT_DOUBLE_EQ(s.projectile.crh, 3.5);
}

TEST(Scene, OneDiameterMeansUniformSize) {
  ScratchDir dir("scene-uniform");
  mesopen::test::writeFile(dir / "s.toml", "[target]\ndiameter = 60e-6\n");
  const Scene s = readScene(dir / "s.toml");
  EXPECT_DOUBLE_EQ(s.target.diameter_min, 60e-6);
  EXPECT_DOUBLE_EQ(s.target.diameter_max, 60e-6);
}

TEST(Scene, UnknownKeyNamesFileKeyAndKnownKeys) {
  ScratchDir dir("scene-unknown");
  const std::string e = errorOf(dir, "[target]\nporosty = 0.3\n");
  EXPECT_NE(e.find("scene.toml"), std::string::npos) << e;
  EXPECT_NE(e.find("target.porosty"), std::string::npos) << e;
  EXPECT_NE(e.find("porosity"), std::string::npos) << e; // the known keys are listed
}

TEST(Scene, UnknownTableIsRejected) {
  ScratchDir dir("scene-table");
  EXPECT_NE(errorOf(dir, "[targets]\nwidth = 1e-3\n").find("unknown table [targets]"),
            std::string::npos);
}

TEST(Scene, OutOfRangeNamesValueAndRange) {
  ScratchDir dir("scene-range");
  const std::string e = errorOf(dir, "[target]\nporosity = 1.2\n");
  EXPECT_NE(e.find("target.porosity = 1.2"), std::string::npos) << e;
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;
  EXPECT_NE(e.find("0.05 <= porosity <= 0.6"), std::string::npos) << e;
}

TEST(Scene, WrongTypesAreRejected) {
  ScratchDir dir("scene-type");
  EXPECT_NE(errorOf(dir, "[target]\nseed = \"one\"\n").find("is not an integer"),
            std::string::npos);
  EXPECT_NE(errorOf(dir, "[target]\nwidth = \"wide\"\n").find("is not a number"),
            std::string::npos);
  EXPECT_NE(
      errorOf(dir, "[target]\nplacement = \"random\"\n").find("one of \"regular\", \"clustered\""),
      std::string::npos);
  EXPECT_NE(errorOf(dir, "[projectile]\nenabled = 1\n").find("true or false"), std::string::npos);
  EXPECT_NE(errorOf(dir, "[target]\ndiameter = [80e-6, 40e-6]\n").find("min > max"),
            std::string::npos);
}

TEST(Scene, KeysThatMustAgreeAreChecked) {
  ScratchDir dir("scene-together");
  EXPECT_NE(errorOf(dir, "[target]\nwidth = 1e-4\n").find("at least 4 grain diameters"),
            std::string::npos);
  EXPECT_NE(errorOf(dir, "[target]\nmesh_size = 40e-6\n").find("half the smallest grain"),
            std::string::npos);
  EXPECT_NE(errorOf(dir, "[projectile]\ntip_half_angle = 20\n").find("[projectile]"),
            std::string::npos);
}

TEST(Scene, BadTomlSaysWhere) {
  ScratchDir dir("scene-toml");
  const std::string e = errorOf(dir, "[target]\nwidth = = 3\n");
  EXPECT_NE(e.find("scene.toml:2:"), std::string::npos) << e;
}

TEST(Cli, BadInputExitsWithTwo) {
  ScratchDir dir("cli-bad");
  mesopen::test::writeFile(dir / "bad.toml", "[target]\nvoid_ratio = 7\n");
  const auto r = mesopen::test::runMesopen("target " + (dir / "bad.toml") + " -o " + (dir / "out"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("target.void_ratio = 7"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out/target.h5"));
  EXPECT_EQ(
      mesopen::test::runMesopen("target " + (dir / "missing.toml") + " -o " + (dir / "out")).code,
      2);
  EXPECT_EQ(mesopen::test::runMesopen("target").code, 2);
  EXPECT_EQ(mesopen::test::runMesopen("--help").code, 0);
}

// docs/scene-keys.md holds the table `mesopen keys` prints (regenerate it with that command).
TEST(Cli, SceneKeysDocumentIsCurrent) {
  const std::string doc =
      mesopen::test::readFile(std::string(MESOPEN_SOURCE_DIR) + "/docs/scene-keys.md");
  const std::string table = sceneKeysMarkdown();
  EXPECT_NE(doc.find(table), std::string::npos)
      << "docs/scene-keys.md is out of date: regenerate it with `build/bin/mesopen keys`";
}

// A target that cannot meet its request still gets made, and says so (stderr, summary.json).
TEST(Cli, MissedRequestIsAWarning) {
  ScratchDir dir("cli-warn");
  // 60 % porosity with very many, very small voids: the void cells cannot shrink far enough
  // (measured: 68 %).
  mesopen::test::writeFile(dir / "miss.toml",
                           "[target]\nwidth = 1e-3\nheight = 1e-3\nporosity = 0.6\n"
                           "void_ratio = 0.1\nvoid_scale = 5\nmesh = \"none\"\n"
                           "[projectile]\nenabled = false\n");
  const auto r = mesopen::test::runMesopen("target " + (dir / "miss.toml") + " -o " +
                                           (dir / "out") + " --no-plot");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("warning: porosity"), std::string::npos) << r.output;
  EXPECT_NE(mesopen::test::readFile(dir / "out/summary.json").find("misses the requested"),
            std::string::npos);
}

TEST(Cli, TooLargeTargetsAreRefusedBeforeTheyStart) {
  ScratchDir dir("cli-big");
  mesopen::test::writeFile(dir / "big.toml",
                           "[target]\nwidth = 0.3\nheight = 0.3\ndiameter = 60e-6\n");
  const auto r = mesopen::test::runMesopen("target " + (dir / "big.toml") + " -o " + (dir / "out"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("allowed: at most 5e7"), std::string::npos) << r.output;
}

// The planar compaction test's keys: a plate projectile, its velocity held, smooth walls. A held
// velocity with spin is refused (the plate is held without rotation), as are an unknown shape and
// a plate too large to mesh.
TEST(Scene, PlateDrivenBetweenSmoothWalls) {
  ScratchDir dir("scene-plate");
  mesopen::test::writeFile(dir / "s.toml",
                           "[projectile]\nshape = \"plate\"\nlength = 1e-4\n"
                           "[run]\nconstant_velocity = true\nsmooth_walls = true\n");
  const Scene s = readScene(dir / "s.toml");
  EXPECT_EQ(s.projectile.shape, ProjectileKind::plate);
  EXPECT_TRUE(s.run.constant_velocity);
  EXPECT_TRUE(s.run.smooth_walls);
  const Scene d = readScene(std::string(MESOPEN_SOURCE_DIR) + "/examples/baseline.toml");
  EXPECT_EQ(d.projectile.shape, ProjectileKind::ogive);
  EXPECT_FALSE(d.run.constant_velocity);
  EXPECT_FALSE(d.run.smooth_walls);
  std::string e = errorOf(dir, "[run]\nconstant_velocity = true\nspin = 100\n");
  EXPECT_NE(e.find("run.spin = 100"), std::string::npos) << e;
  EXPECT_NE(e.find("allowed: 0"), std::string::npos) << e;
  e = errorOf(dir, "[projectile]\nshape = \"disk\"\n");
  EXPECT_NE(e.find("projectile.shape"), std::string::npos) << e;
  EXPECT_NE(e.find("\"plate\""), std::string::npos) << e;
  e = errorOf(dir, "[projectile]\nshape = \"plate\"\nlength = 0.5\n");
  EXPECT_NE(e.find("projectile.length = 0.5 (a plate as wide as the box)"), std::string::npos) << e;
  EXPECT_NE(e.find("allowed: at most 5e7"), std::string::npos) << e;
}

// dem.preset sets its keys first, whatever the order in the file; keys given beside it win.
TEST(Scene, DemPresetFirstThenTheTablesKeys) {
  ScratchDir dir("scene-dem-preset");
  mesopen::test::writeFile(dir / "s.toml",
                           "[dem]\nhertz_length = 5e-6\npreset = \"quartz-bulk\"\n");
  const Scene s = readScene(dir / "s.toml");
  EXPECT_EQ(s.dem.preset, DemPreset::quartz_bulk);
  EXPECT_EQ(s.dem.disk_size, DiskSize::equal_area);
  EXPECT_EQ(s.dem.normal_law, NormalLaw::hertz);
  EXPECT_DOUBLE_EQ(s.dem.hertz_length, 5e-6);
  mesopen::test::writeFile(dir / "p.toml",
                           "[dem]\npreset = \"quartz-pair\"\ndisk_size = \"equal_area\"\n");
  const Scene p = readScene(dir / "p.toml");
  EXPECT_EQ(p.dem.normal_law, NormalLaw::hooke);
  EXPECT_EQ(p.dem.disk_size, DiskSize::equal_area);
  const std::string e = errorOf(dir, "[dem]\npreset = \"sand\"\n");
  EXPECT_NE(e.find("dem.preset"), std::string::npos) << e;
  EXPECT_NE(e.find("\"quartz-bulk\""), std::string::npos) << e;
}

// Command lines a new user gets wrong end with exit 2 and say why: a directory or a missing file
// given as the scene, an empty output directory, a seed outside target.seed's range (it was read
// as unsigned and wrapped: -1 became 18446744073709551615).
TEST(Cli, BadCommandLinesExitTwo) {
  ScratchDir dir("cli-bad");
  mesopen::test::writeFile(dir / "s.toml",
                           "[target]\nwidth = 1e-3\nheight = 1e-3\nmesh = \"none\"\n"
                           "[projectile]\nenabled = false\n");
  for (const char *command : {"target", "run"}) {
    auto r = mesopen::test::runMesopen(std::string(command) + " " + dir.path.string() + " -o " +
                                       (dir / "out"));
    EXPECT_EQ(r.code, 2) << command << ": " << r.output;
    EXPECT_NE(r.output.find("not a file"), std::string::npos) << r.output;
    r = mesopen::test::runMesopen(std::string(command) + " " + (dir / "missing.toml") + " -o " +
                                  (dir / "out"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("no such file"), std::string::npos) << r.output;
    r = mesopen::test::runMesopen(std::string(command) + " " + (dir / "s.toml") + " -o ''");
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("empty name"), std::string::npos) << r.output;
    for (const char *seed : {"-1", "9.1e15", "x"}) {
      r = mesopen::test::runMesopen(std::string(command) + " " + (dir / "s.toml") + " -o " +
                                    (dir / "out") + " --seed " + seed);
      EXPECT_EQ(r.code, 2) << seed << ": " << r.output;
    }
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "out/summary.json"));
}

// The documented ranges are the stable ones: a contact stiffness of 2 gave a stable step of 0 (the
// run hung at t = 0), a safety of 5e-324 a step that did not advance the time.
TEST(Scene, RangesAreTheStableOnes) {
  ScratchDir dir("scene-stable");
  std::string e = errorOf(dir, "[contact]\nstiffness = 2\n");
  EXPECT_NE(e.find("contact.stiffness = 2"), std::string::npos) << e;
  EXPECT_NE(e.find("0.6"), std::string::npos) << e;
  e = errorOf(dir, "[run]\nsafety = 5e-324\n");
  EXPECT_NE(e.find("run.safety"), std::string::npos) << e;
  EXPECT_NE(e.find("0.001"), std::string::npos) << e;
  EXPECT_EQ(errorOf(dir, "[contact]\nstiffness = 0.6\n[run]\nsafety = 0.001\n"), "");
}

// A value far too long is named, not echoed whole; keys a representation does not use are warned
// of (a fe run with a [dem] table and a band).
TEST(Cli, LongValuesAreCutAndIdleKeysWarned) {
  ScratchDir dir("cli-long");
  const std::string e =
      errorOf(dir, "[target]\nplacement = \"" + std::string(1 << 20, 'x') + "\"\n");
  EXPECT_LT(e.size(), 600u) << e.substr(0, 200);
  EXPECT_NE(e.find("(1048578 characters)"), std::string::npos) << e.substr(0, 300);
  mesopen::test::writeFile(
      dir / "fe.toml",
      "[target]\nwidth = 0.6e-3\nheight = 0.3e-3\ndiameter = 60e-6\nmesh_size = 15e-6\n"
      "[projectile]\nlength = 0.3e-3\n[run]\nend_time = 1e-9\nband_half_width = 1e-4\n"
      "frame_interval = 0\n[dem]\nstiffness = 1e10\n");
  const auto r =
      mesopen::test::runMesopen("run " + (dir / "fe.toml") + " -o " + (dir / "out") + " --quiet");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("warning: " + (dir / "fe.toml") +
                          ": [dem] does nothing with run.representation = \"fe\""),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("run.band_half_width does nothing"), std::string::npos) << r.output;
}

// A rerun leaves nothing of the run before beside its files (the earlier analysis), and one
// command's output directory is refused to another (target or modal into a run's directory
// overwrote its summary.json).
TEST(Cli, NoStaleResultsNoOverwrittenSummaries) {
  ScratchDir dir("cli-stale");
  mesopen::test::writeFile(dir / "s.toml", mesopen::test::tinyScene("frame_interval = 0\n"));
  ASSERT_EQ(
      mesopen::test::runMesopen("run " + (dir / "s.toml") + " -o " + (dir / "out") + " --quiet")
          .code,
      0);
  mesopen::test::writeFile(dir / "out/instability.json", "{}");
  mesopen::test::writeFile(dir / "out/instability-tilt.png", "");
  ASSERT_EQ(
      mesopen::test::runMesopen("run " + (dir / "s.toml") + " -o " + (dir / "out") + " --quiet")
          .code,
      0);
  EXPECT_FALSE(std::filesystem::exists(dir / "out/instability.json"));
  EXPECT_FALSE(std::filesystem::exists(dir / "out/instability-tilt.png"));
  const std::string summary = mesopen::test::readFile(dir / "out/summary.json");
  for (const std::string command : {"target", "modal"}) {
    const auto r =
        mesopen::test::runMesopen(command + " " + (dir / "s.toml") + " -o " + (dir / "out"));
    EXPECT_EQ(r.code, 2) << command << ": " << r.output;
    EXPECT_NE(r.output.find("holds the output of `mesopen run`"), std::string::npos) << r.output;
  }
  EXPECT_EQ(mesopen::test::readFile(dir / "out/summary.json"), summary);
}

// The composed scene (scene.toml of every output directory) is the whole scene: read back, it
// gives the same scene, whose composition is the same text, for every example and for values
// no short decimal holds (a default of 1.1166666666666666e10, a parameter set to 1/3).
TEST(Scene, ComposedSceneReadsBackToItself) {
  ScratchDir dir("scene-composed");
  std::vector<std::string> paths;
  for (const auto &entry :
       std::filesystem::recursive_directory_iterator(std::string(MESOPEN_SOURCE_DIR) + "/examples"))
    if (entry.path().extension() == ".toml" && !entry.path().string().ends_with("campaign.toml"))
      paths.push_back(entry.path().string());
  mesopen::test::writeFile(dir / "odd.toml",
                           "[run]\nvelocity = 333.33333333333331\n"
                           "[dem]\npreset = \"quartz-bulk\"\n"
                           "[materials.grains]\npreset = \"quartz\"\ndensity = 2648.4999999999995\n"
                           "[materials.projectile]\ntype = \"elastic\"\n");
  paths.push_back(dir / "odd.toml");
  ASSERT_GT(paths.size(), 5u);
  std::size_t scenes = 0;
  for (const std::string &path : paths) {
    Scene scene;
    try {
      scene = readScene(path);
    } catch (const InputError &) {
      continue; // a campaign or another kind of file
    }
    ++scenes;
    const std::string text = composedScene(scene);
    mesopen::test::writeFile(dir / "composed.toml", text);
    const Scene again = readScene(dir / "composed.toml");
    EXPECT_EQ(composedScene(again), text) << path;
    EXPECT_EQ(again.run.velocity, scene.run.velocity) << path;
    EXPECT_EQ(again.dem.tangential_stiffness, scene.dem.tangential_stiffness) << path;
    EXPECT_EQ(resolvedParameters(again.grain_material), resolvedParameters(scene.grain_material))
        << path;
    EXPECT_EQ(again.projectile_material.name, scene.projectile_material.name) << path;
  }
  EXPECT_GT(scenes, 5u);
  const Scene odd = readScene(dir / "odd.toml");
  EXPECT_NE(composedScene(odd).find("velocity = 333.3333333333333\n"), std::string::npos);
  EXPECT_NE(composedScene(odd).find("density = 2648.4999999999995\n"), std::string::npos);
}
