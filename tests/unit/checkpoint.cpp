// Checkpoints of an fe run (run/checkpoint.hpp): a run stopped at a checkpoint and continued with
// `mesopen run --resume` writes the run.h5 of the run not stopped, byte for byte; taking
// checkpoints changes nothing; a run killed outright goes on from its last checkpoint; bad input
// ends with exit 2.
#include "checkpoint.hpp"
#include "h5file.hpp"
#include "run.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <csignal>
#include <filesystem>
#include <sys/wait.h>
#include <unistd.h>

using namespace mesopen;
using test::ScratchDir;

namespace {

namespace fs = std::filesystem;

// The tiny scene (0.6 x 0.3 mm, 60 um grains) to 40 ns, about 140 steps, with frames every 10 ns
// (5 of them) and a checkpoint every 5 ns of simulated time.
std::string scene() {
  std::string text = test::tinyScene("frame_interval = 1e-8\ncheckpoint_time = 5e-9\n");
  return text.replace(text.find("end_time = 2e-8"), 15, "end_time = 4e-8");
}

// The tiny scene with a projectile that erodes (steel at 2000 m/s, erosion at a plastic strain of
// 0.3), frames every 20 ns and a checkpoint every 5 ns, to `end_time`, with `run_keys` in [run].
std::string erodingScene(const std::string &run_keys, const std::string &end_time) {
  std::string text = test::tinyScene("velocity = 2000.0\nframe_interval = 2e-8\n"
                                     "checkpoint_time = 5e-9\n" +
                                     run_keys) +
                     "[materials.projectile]\npreset = \"steel\"\nerosion_strain = 0.3\n";
  return text.replace(text.find("end_time = 2e-8"), 15, "end_time = " + end_time);
}

std::uint64_t checkpointStep(const std::string &out) {
  return H5File::open(out + "/checkpoint/state.h5").readAttribute<std::uint64_t>("/", "step");
}

} // namespace

// Stopped after step 70 (as by SIGTERM, between two scheduled checkpoints: the stop writes its
// own) and continued, on one and two threads: run.h5 holds the same bytes as the run not
// stopped, and so does a run continued from a checkpoint written by another thread count; the
// stopped run said "interrupted" and kept its checkpoint, the completed one removed it.
TEST(Checkpoint, StoppedAndResumedFeRunIsByteIdentical) {
  ScratchDir dir("checkpoint-fe");
  test::writeFile(dir / "scene.toml", scene());
  const auto whole = test::runScene(dir / "scene.toml", dir / "whole", 1);
  ASSERT_EQ(whole.code, 0) << whole.output;
  EXPECT_FALSE(fs::exists(dir / "whole/checkpoint"));
  const auto steps = H5File::open(dir / "whole/run.h5").read<std::uint64_t>("/series/step").back();
  ASSERT_GT(steps, 100u);
  for (const int threads : {1, 2}) {
    SCOPED_TRACE(threads);
    const std::string out = dir / ("stopped-" + std::to_string(threads));
    const auto stopped = test::runStoppedAt(dir / "scene.toml", out, 70, threads);
    ASSERT_EQ(stopped.code, 128 + SIGTERM) << stopped.output;
    EXPECT_EQ(H5File::open(out + "/run.h5").readStringAttribute("/", "status"), "interrupted");
    EXPECT_EQ(checkpointStep(out), 70u);
    const auto resumed = test::resume(out, 3 - threads); // the other thread count
    ASSERT_EQ(resumed.code, 0) << resumed.output;
    EXPECT_TRUE(test::sameBytes(dir / "whole/run.h5", out + "/run.h5"));
    EXPECT_FALSE(fs::exists(out + "/checkpoint"));
    const auto summary = nlohmann::json::parse(test::readFile(out + "/summary.json"));
    EXPECT_EQ(summary["status"], "completed");
    EXPECT_EQ(summary["steps"], steps);
    EXPECT_TRUE(summary["checkpoints"]["resumed"].get<bool>());
    // the VTK frames of both parts, listed once each
    for (const char *vtu : {"frame_000000.vtu", "frame_000002.vtu", "frame_000004.vtu"})
      EXPECT_TRUE(fs::exists(out + "/vtk/" + vtu)) << vtu;
    EXPECT_EQ(test::readFile(out + "/vtk/run.pvd"), test::readFile(dir / "whole/vtk/run.pvd"));
  }
}

// A run whose projectile erodes (steel at 2000 m/s eroding at a plastic strain of 0.3: elements
// removed from step 15 on, boundaries and nodal areas changed, overlaps allowed for) stopped after
// step 200 and continued: the same run.h5.
TEST(Checkpoint, ErodingRunResumesByteIdentical) {
  ScratchDir dir("checkpoint-erosion");
  const std::string text = erodingScene("", "6e-8");
  test::writeFile(dir / "scene.toml", text);
  const auto whole = test::runScene(dir / "scene.toml", dir / "whole", 1);
  ASSERT_EQ(whole.code, 0) << whole.output;
  const auto summary = nlohmann::json::parse(test::readFile(dir / "whole/summary.json"));
  ASSERT_GT(summary["eroded_elements"].get<int>(), 10);
  const auto eroded = H5File::open(dir / "whole/run.h5").read<double>("/series/energy/eroded");
  ASSERT_GT(eroded.size(), 300u);
  ASSERT_GT(eroded[200], 0.0); // erosion under way before the stop
  const auto stopped = test::runStoppedAt(dir / "scene.toml", dir / "stopped", 200, 2);
  ASSERT_EQ(stopped.code, 128 + SIGTERM) << stopped.output;
  const auto resumed = test::resume(dir / "stopped", 1);
  ASSERT_EQ(resumed.code, 0) << resumed.output;
  EXPECT_TRUE(test::sameBytes(dir / "whole/run.h5", dir / "stopped/run.h5"));
}

// With multiple time stepping (run.max_level = 2, level gap 1) and a projectile in parts (3 um
// mesh: about 4,000 elements, 8 parts) that erodes (steel at 2000 m/s, plastic strain 0.3), a run
// stopped within a cycle of levels (after step 203: 203 is no multiple of 4, the coarse bodies are
// between their steps) and continued on the other thread count writes the same run.h5, and its
// summary the same element updates, as the run not stopped; and one of its checkpoints refused for
// another max_level.
TEST(Checkpoint, RunAtLevelsResumesByteIdentical) {
  ScratchDir dir("checkpoint-levels");
  std::string text = erodingScene("max_level = 2\nlevel_gap = 1\n", "5e-8");
  text.replace(text.find("[projectile]\n"), 13, "[projectile]\nmesh_size = 3e-6\n");
  test::writeFile(dir / "scene.toml", text);
  const auto whole = test::runScene(dir / "scene.toml", dir / "whole", 1);
  ASSERT_EQ(whole.code, 0) << whole.output;
  const auto summary = nlohmann::json::parse(test::readFile(dir / "whole/summary.json"));
  ASSERT_GT(summary["eroded_elements"].get<int>(), 10);
  const auto &levels = summary["multiple_time_stepping"];
  ASSERT_EQ(levels["bodies_in_parts"], 1);
  ASSERT_LT(levels["element_update_share"].get<double>(), 0.97); // levels at work (0.93)
  const auto stopped = test::runStoppedAt(dir / "scene.toml", dir / "stopped", 203, 2);
  ASSERT_EQ(stopped.code, 128 + SIGTERM) << stopped.output;
  EXPECT_EQ(checkpointStep(dir / "stopped"), 203u);
  const auto resumed = test::resume(dir / "stopped", 1);
  ASSERT_EQ(resumed.code, 0) << resumed.output;
  EXPECT_TRUE(test::sameBytes(dir / "whole/run.h5", dir / "stopped/run.h5"));
  const auto after = nlohmann::json::parse(test::readFile(dir / "stopped/summary.json"));
  EXPECT_EQ(after["multiple_time_stepping"]["element_updates"], levels["element_updates"]);
  EXPECT_EQ(after["multiple_time_stepping"]["single_rate_element_updates"],
            levels["single_rate_element_updates"]);
}

// A run does not depend on its checkpoints: none (no keys), one every step by the clock, one every
// 0.2 ns of simulated time (every few steps) give the same run.h5 but for the keys in the scene it
// records (test::sameRun).
TEST(Checkpoint, CheckpointsChangeNothing) {
  ScratchDir dir("checkpoint-fe-same");
  const std::pair<const char *, std::string> runs[] = {
      {"none", test::tinyScene("frame_interval = 1e-8\n")},
      {"clock", test::tinyScene("frame_interval = 1e-8\ncheckpoint_interval = 1e-9\n")},
      {"often", test::tinyScene("frame_interval = 1e-8\ncheckpoint_time = 2e-10\n")}};
  for (const auto &[name, text] : runs) {
    test::writeFile(dir / (std::string(name) + ".toml"), text);
    const auto r = test::runScene(dir / (std::string(name) + ".toml"), dir / name, 2);
    ASSERT_EQ(r.code, 0) << name << r.output;
  }
  const auto often = nlohmann::json::parse(test::readFile(dir / "often/summary.json"));
  EXPECT_GT(often["checkpoints"]["written"].get<int>(), 50);
  EXPECT_TRUE(test::sameRun(dir / "none/run.h5", dir / "clock/run.h5"));
  EXPECT_TRUE(test::sameRun(dir / "none/run.h5", dir / "often/run.h5"));
}

// A run killed outright (SIGKILL: no checkpoint of its own, a run.h5.tmp and frames past its last
// checkpoint left behind) goes on from its last checkpoint to the same run.h5.
TEST(Checkpoint, KilledRunResumesFromItsLastCheckpoint) {
  ScratchDir dir("checkpoint-fe-kill");
  test::writeFile(dir / "scene.toml", scene());
  const auto whole = test::runScene(dir / "scene.toml", dir / "whole", 1);
  ASSERT_EQ(whole.code, 0) << whole.output;
  const std::string scene_path = dir / "scene.toml", out = dir / "killed";
  ::setenv("MESOPEN_STOP_AT_STEP", "130", 1); // a stop that the kill comes before
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::execl(MESOPEN_BINARY, MESOPEN_BINARY, "run", scene_path.c_str(), "-o", out.c_str(), "--quiet",
            "--threads", "1", static_cast<char *>(nullptr));
    ::_exit(127);
  }
  ::unsetenv("MESOPEN_STOP_AT_STEP");
  // Killed once a checkpoint past the first frame is there (the run then has more to lose).
  for (int i = 0; i < 2000; ++i) {
    if (fs::exists(out + "/checkpoint/state.h5") && checkpointStep(out) > 60)
      break;
    ::usleep(5000);
  }
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  if (!WIFSIGNALED(status))
    GTEST_SKIP() << "the run ended before it was killed (exit " << WEXITSTATUS(status) << ")";
  EXPECT_FALSE(fs::exists(out + "/run.h5"));
  const auto resumed = test::resume(out, 2);
  ASSERT_EQ(resumed.code, 0) << resumed.output;
  EXPECT_TRUE(test::sameBytes(dir / "whole/run.h5", out + "/run.h5"));
}

// Bad input: --resume where there is no checkpoint, with a scene or an output directory, a damaged
// checkpoint, keys out of range: exit 2 and a message naming what is wrong.
TEST(Checkpoint, BadInputEndsWithExit2) {
  ScratchDir dir("checkpoint-bad");
  fs::create_directories(dir / "empty");
  test::writeFile(dir / "scene.toml", scene());
  auto expect = [&](const std::string &args, const std::string &words) {
    const auto r = test::runMesopen(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(words), std::string::npos) << args << "\n" << r.output;
  };
  expect("run --resume " + (dir / "empty"), "no checkpoint to continue from");
  expect("run --resume " + (dir / "nowhere"), "no checkpoint to continue from");
  expect("run " + (dir / "scene.toml") + " --resume " + (dir / "empty"),
         "without SCENE, -o or --seed");
  expect("run " + (dir / "scene.toml"), "mesopen run --resume DIR");
  for (const auto &[key, text] :
       {std::pair{"run.checkpoint_time", "checkpoint_time = -1e-9\n"},
        {"run.checkpoint_interval", "checkpoint_interval = 1e9\n"},
        {"run.checkpoint_interval", "checkpoint_interval = \"often\"\n"}}) {
    test::writeFile(dir / "bad.toml", test::tinyScene(text));
    expect("run " + (dir / "bad.toml") + " -o " + (dir / "bad"), key);
  }
  // A checkpoint cut short (as no rename would leave it: only a damaged disk or a hand can).
  const auto stopped = test::runStoppedAt(dir / "scene.toml", dir / "cut", 20, 1);
  ASSERT_EQ(stopped.code, 128 + SIGTERM) << stopped.output;
  const std::string state = test::readFile(dir / "cut/checkpoint/state.h5");
  test::writeFile(dir / "cut/checkpoint/state.h5", state.substr(0, state.size() / 2));
  expect("run --resume " + (dir / "cut"), "not a whole checkpoint");
}

// SIGTERM itself (not the test's stop): the run writes a checkpoint at the step it stopped after
// and exits 143; continued, it goes on from there (stopped again, its next checkpoint is later).
TEST(Checkpoint, SigtermWritesACheckpoint) {
  ScratchDir dir("checkpoint-sigterm");
  std::string text = scene();
  text.replace(text.find("end_time = 4e-8"), 15, "end_time = 1e-3"); // far: minutes of steps
  test::writeFile(dir / "scene.toml", text);
  const std::string scene_path = dir / "scene.toml", out = dir / "out";
  auto stopAfter = [&](std::vector<const char *> args, useconds_t wait) {
    const pid_t pid = ::fork();
    if (pid == 0) {
      args.push_back(nullptr);
      ::execv(MESOPEN_BINARY, const_cast<char *const *>(args.data()));
      ::_exit(127);
    }
    for (int i = 0; i < 600 && !fs::exists(out + "/run.h5.tmp"); ++i)
      ::usleep(50000);
    ::usleep(wait);
    ::kill(pid, SIGTERM);
    int status = 0;
    ::waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  ASSERT_EQ(stopAfter({MESOPEN_BINARY, "run", scene_path.c_str(), "-o", out.c_str(), "--quiet",
                       "--threads", "1"},
                      300000),
            128 + SIGTERM);
  const auto first = checkpointStep(out);
  const auto series = H5File::open(out + "/run.h5").read<std::uint64_t>("/series/step");
  EXPECT_EQ(first, series.back()); // the checkpoint of the last step taken
  ASSERT_EQ(stopAfter({MESOPEN_BINARY, "run", "--resume", out.c_str(), "--quiet", "--threads", "1"},
                      300000),
            128 + SIGTERM);
  EXPECT_GT(checkpointStep(out), first);
  const auto steps = H5File::open(out + "/run.h5").read<std::uint64_t>("/series/step");
  EXPECT_EQ(steps.front(), 0u);
  EXPECT_EQ(steps.back(), checkpointStep(out));
  for (std::size_t i = 1; i < steps.size(); ++i)
    ASSERT_EQ(steps[i], steps[i - 1] + 1) << i; // every step once, across the two parts
}
