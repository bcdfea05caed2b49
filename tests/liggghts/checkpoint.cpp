// Checkpoints of runs with disks (run/checkpoint.hpp): a dem or hybrid run stopped at a
// checkpoint and continued with `mesopen run --resume` writes the run.h5 of the run not stopped,
// byte for byte, on one and two threads, and LIGGGHTS's log goes on from the stopped run's; and the
// run's bytes do not depend on when it took its checkpoints (LIGGGHTS's restart file and set-up
// leave it as it was).
#include "checkpoint.hpp"
#include "h5file.hpp"
#include "run.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <csignal>
#include <filesystem>

using namespace mesopen;
using test::ScratchDir;

namespace {

namespace fs = std::filesystem;

// The tiny scene with disks (all of them, or beyond the meshed band; equal-area disks touching
// their neighbours, Hertzian law with rolling friction: the quartz-bulk preset) to 100 ns, about
// 300 FE steps in 25 of the disks' windows, frames every 20 ns, and `checkpoints` in [run].
std::string scene(const std::string &representation, const std::string &checkpoints) {
  std::string text = test::tinyScene("representation = \"" + representation +
                                     "\"\nframe_interval = 2e-8\n" + checkpoints) +
                     "[dem]\npreset = \"quartz-bulk\"\n";
  return text.replace(text.find("end_time = 2e-8"), 15, "end_time = 1e-7");
}

// Stopped after step 30 on one thread and continued on two, and after step 150 the other way round
// (within a window: the run steps on to its end and writes its checkpoint there): run.h5 holds the
// bytes of the run not stopped, which took no checkpoint (its one checkpoint time lies past its
// end). (The stop after step 30 of the dem run fails without LIGGGHTS's lists rebuilt at every
// step, liggghts-inputs/dem.in's `lists`: the set-up after the restart file builds other lists.)
void stopAndResume(const std::string &representation) {
  ScratchDir dir("checkpoint-" + representation);
  test::writeFile(dir / "scene.toml", scene(representation, "checkpoint_time = 1\n"));
  const auto whole = test::runScene(dir / "scene.toml", dir / "whole", 2);
  ASSERT_EQ(whole.code, 0) << whole.output;
  const auto summary = nlohmann::json::parse(test::readFile(dir / "whole/summary.json"));
  ASSERT_GT(summary["steps"].get<int>(), 250);
  EXPECT_GT(summary["dem"]["work_on_disks"].get<double>(), 0.0); // the FE bodies met disks
  for (const auto &[stop, threads] : {std::pair{30, 1}, {150, 2}}) {
    SCOPED_TRACE(threads);
    const std::string out = dir / ("stopped-" + std::to_string(threads));
    const auto stopped = test::runStoppedAt(dir / "scene.toml", out, stop, threads);
    ASSERT_EQ(stopped.code, 128 + SIGTERM) << stopped.output;
    const auto step =
        H5File::open(out + "/checkpoint/state.h5").readAttribute<std::uint64_t>("/", "step");
    EXPECT_GE(step, static_cast<std::uint64_t>(stop));
    EXPECT_LT(step, static_cast<std::uint64_t>(stop) + 50);
    EXPECT_FALSE(fs::exists(out + "/run.h5.tmp"));
    const std::string log_stopped = test::readFile(out + "/liggghts.log");
    const auto resumed = test::resume(out, 3 - threads);
    ASSERT_EQ(resumed.code, 0) << resumed.output;
    // LIGGGHTS's log goes on after the stopped run's
    const std::string log = test::readFile(out + "/liggghts.log");
    EXPECT_NE(log_stopped.find("LIGGGHTS"), std::string::npos);
    EXPECT_EQ(log.substr(0, log_stopped.size()), log_stopped);
    EXPECT_NE(log.find("# continued from a checkpoint", log_stopped.size()), std::string::npos);
    EXPECT_TRUE(test::sameBytes(dir / "whole/run.h5", out + "/run.h5"));
    EXPECT_FALSE(fs::exists(out + "/checkpoint"));
  }
}

} // namespace

TEST(LiggghtsCheckpoint, StoppedAndResumedDemRunIsByteIdentical) { stopAndResume("dem"); }

TEST(LiggghtsCheckpoint, StoppedAndResumedHybridRunIsByteIdentical) { stopAndResume("hybrid"); }

// With disks a run's bytes do not depend on when it took checkpoints: none taken (its one
// checkpoint time past the end), one every 10 ns, one at every window's end (the clock's
// interval shorter than a window) give the same run.h5 but for the keys in the scene it records.
TEST(LiggghtsCheckpoint, CheckpointsChangeNothingWithDisks) {
  ScratchDir dir("checkpoint-dem-same");
  const std::pair<const char *, const char *> runs[] = {{"none", "checkpoint_time = 1\n"},
                                                        {"often", "checkpoint_time = 1e-8\n"},
                                                        {"clock", "checkpoint_interval = 1e-9\n"}};
  for (const auto &[name, keys] : runs) {
    test::writeFile(dir / (std::string(name) + ".toml"), scene("dem", keys));
    const auto r = test::runScene(dir / (std::string(name) + ".toml"), dir / name, 1);
    ASSERT_EQ(r.code, 0) << name << r.output;
  }
  const auto clock = nlohmann::json::parse(test::readFile(dir / "clock/summary.json"));
  // every window's end but the run's last step's, if a window ends there
  EXPECT_GE(clock["checkpoints"]["written"].get<int>(), clock["dem"]["windows"].get<int>() - 1);
  EXPECT_TRUE(test::sameRun(dir / "none/run.h5", dir / "often/run.h5"));
  EXPECT_TRUE(test::sameRun(dir / "none/run.h5", dir / "clock/run.h5"));
}
