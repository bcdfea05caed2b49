// Campaigns: the file is read strictly (exit 2 naming file, key, value), scenes are composed from a
// base with the runs' keys, the statistics match published tables, and `mesopen campaign` runs
// every replicate once (a second call reruns nothing, a changed run alone is rerun).
#include "campaign.hpp"
#include "checkpoint.hpp"
#include "run.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <csignal>
#include <sstream>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

using namespace mesopen;
using mesopen::test::ScratchDir;

namespace {

const char *tiny_base =
    "[target]\nwidth = 0.6e-3\nheight = 0.3e-3\ndiameter = 60e-6\nmesh_size = 15e-6\n"
    "[projectile]\nlength = 0.3e-3\n[run]\nend_time = 1e-8\n";

// The message of the InputError that reading `campaign` (beside the tiny base scene) raises.
std::string errorOf(const ScratchDir &dir, const std::string &campaign) {
  mesopen::test::writeFile(dir / "base.toml", tiny_base);
  mesopen::test::writeFile(dir / "c.toml", campaign);
  try {
    readCampaign(dir / "c.toml");
  } catch (const InputError &e) {
    return e.what();
  }
  return "";
}

// `mesopen campaign CAMPAIGN -o OUT --threads 1` started in a child process: its pid (-1: none).
pid_t startCampaign(const std::string &campaign, const std::string &out) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::execl(MESOPEN_BINARY, MESOPEN_BINARY, "campaign", campaign.c_str(), "-o", out.c_str(),
            "--threads", "1", static_cast<char *>(nullptr));
    ::_exit(127);
  }
  return pid;
}

} // namespace

// Student's t, two-sided 95 %: the values of standard tables (e.g. NIST/SEMATECH e-Handbook,
// Table 1.3.6.7.2) to their 3 decimals; beyond dof 30 the expansion, against the same table.
TEST(Campaign, StudentQuantileMatchesTables) {
  const std::pair<int, double> table[] = {{1, 12.706}, {2, 4.303},  {4, 2.776},  {9, 2.262},
                                          {30, 2.042}, {40, 2.021}, {60, 2.000}, {100, 1.984}};
  for (auto [dof, t] : table)
    EXPECT_NEAR(studentT95(dof), t, 1.5e-3) << dof;
  EXPECT_NEAR(studentT95(100000), 1.960, 1e-3);
  EXPECT_TRUE(std::isnan(studentT95(0)));
}

TEST(Campaign, EstimateIsMeanAndInterval) {
  const Estimate e = estimate({1, 2, 3, 4, 5});
  EXPECT_DOUBLE_EQ(e.mean, 3.0);
  EXPECT_NEAR(e.sd, std::sqrt(2.5), 1e-12);
  EXPECT_NEAR(e.half_width, 2.7764 * std::sqrt(2.5) / std::sqrt(5.0), 1e-4);
  EXPECT_TRUE(std::isnan(estimate({7}).half_width));
}

// Verdicts on made-up magnitudes: a clear rise, the same reversed, overlapping noise, alike runs
// (within a tolerance, shown; or too few replicates to show it; or clearly apart), and a single
// replicate (not tested). The slope of two runs is their difference of means over
// the difference of x.
TEST(Campaign, TrendVerdicts) {
  Trend rises{"t", "average_lateral_force", TrendKind::rises, {"a", "b"}, {0.0, 2.0}};
  const TrendResult up = testTrend(rises, {{1.0, 1.1, 0.9}, {-3.0, 3.1, 2.9}});
  EXPECT_EQ(up.verdict, "confirmed");
  EXPECT_NEAR(up.effect, 1.0, 1e-12); // (3 - 1) / 2, on |m|
  EXPECT_EQ(up.seen, "rises");
  EXPECT_EQ(testTrend(rises, {{3.0, 3.1, 2.9}, {1.0, 1.1, 0.9}}).verdict, "reversed");
  EXPECT_EQ(testTrend(rises, {{1.0, 3.0, 2.0}, {1.5, 3.5, 2.0}}).verdict, "not confirmed");
  EXPECT_EQ(testTrend(rises, {{1.0}, {3.0}}).verdict, "not tested");
  Trend falls = rises;
  falls.expect = TrendKind::falls;
  EXPECT_EQ(testTrend(falls, {{3.0, 3.1, 2.9}, {1.0, 1.1, 0.9}}).verdict, "confirmed");
  Trend similar{"s", "tilt", TrendKind::similar, {"a", "b", "c"}, {1, 2, 3}, 0.2};
  EXPECT_EQ(testTrend(similar, {{1.0, 1.02, 0.98}, {1.01, 0.99, 1.0}, {1.0, 1.01, 0.99}}).verdict,
            "confirmed");
  EXPECT_EQ(testTrend(similar, {{1.0, 2.0, 3.0}, {1.5, 2.5, 2.0}, {2.0, 1.0, 3.0}}).verdict,
            "not confirmed"); // alike means, but the spread cannot show it
  EXPECT_EQ(testTrend(similar, {{1.0, 1.1, 0.9}, {1.0, 1.1, 0.9}, {5.0, 5.1, 4.9}}).verdict,
            "reversed");
  Trend differs{"d", "tilt", TrendKind::differs, {"a", "b"}, {1, 2}};
  EXPECT_EQ(testTrend(differs, {{1.0, 1.1, 0.9}, {5.0, 5.1, 4.9}}).verdict, "confirmed");
}

TEST(Campaign, ComposesScenesFromTheBase) {
  ScratchDir dir("campaign-compose");
  ASSERT_EQ(errorOf(dir, "[campaign]\nbase = \"base.toml\"\nrepresentation = \"dem\"\n"
                         "[[run]]\nname = \"a\"\nrun.velocity = 700.0\ntarget.seed = 3\n"),
            "");
  const Campaign c = readCampaign(dir / "c.toml");
  std::istringstream in(composeScene(c, c.runs[0], 2));
  const Scene s = readScene(toml::parse(in), "composed");
  EXPECT_EQ(s.target.seed, 3u + 2 * 1000);
  EXPECT_DOUBLE_EQ(s.run.velocity, 700.0);
  EXPECT_DOUBLE_EQ(s.target.width, 0.6e-3); // from the base
  EXPECT_EQ(s.run.representation, Representation::dem);
  EXPECT_EQ(s.run.frame_interval, 0.0); // no frames unless campaign.frames
}

TEST(Campaign, BadInputNamesTheKey) {
  ScratchDir dir("campaign-bad");
  const std::pair<std::string, std::string> cases[] = {
      {"[campaign]\nbase = \"base.toml\"\nreplicates = 0\n[[run]]\nname = \"a\"\n",
       "campaign.replicates = 0"},
      {"[campaign]\nbase = \"base.toml\"\nrepresentation = \"fem\"\n[[run]]\nname = \"a\"\n",
       "campaign.representation = 'fem'"},
      {"[campaign]\nbase = \"base.toml\"\nspeed = 1\n[[run]]\nname = \"a\"\n", "campaign.speed"},
      {"[campaign]\nbase = \"base.toml\"\n", "no [[run]]"},
      {"[[run]]\nname = \"a\"\n", "has no scene"},
      {"[[run]]\nname = \"a\"\nscene = \"nowhere.toml\"\n", "nowhere.toml not found"},
      {"[campaign]\nbase = \"base.toml\"\n[[run]]\nname = \"a/b\"\n", "name = 'a/b'"},
      {"[campaign]\nbase = \"base.toml\"\n[[run]]\nname = \"a\"\n[[run]]\nname = \"a\"\n",
       "two runs are named \"a\""},
      {"[campaign]\nbase = \"base.toml\"\n[[run]]\nname = \"a\"\nrun.velocity = -1.0\n",
       "run.velocity = -1"},
      {"[campaign]\nbase = \"base.toml\"\n[[run]]\nname = \"a\"\nrun.speed = 1.0\n",
       "unknown key run.speed"},
      {"[campaign]\nbase = \"base.toml\"\n[[run]]\nname = \"a\"\nreference = { depth = 1 }\n",
       "reference.depth"},
      {"[campaign]\nbase = \"base.toml\"\n[[run]]\nname = \"a\"\n[[trend]]\nexpect = \"rises\"\n"
       "runs = [\"a\", \"b\"]\n",
       "\"b\", which is no run"},
      {"[campaign]\nbase = \"base.toml\"\n[[run]]\nname = \"a\"\n[[trend]]\nexpect = \"up\"\n"
       "runs = [\"a\"]\n",
       "expect = 'up'"},
      {"[campaign]\nbase = \"base.toml\"\n[[run]]\nname = \"a\"\n[[trend]]\nexpect = \"rises\"\n"
       "measure = \"speed\"\nruns = [\"a\"]\n",
       "measure = \"speed\""},
      {"[campaign]\nbase = \"base.toml\"\n[[run]]\nname = \"a\"\n[[run]]\nname = \"b\"\n"
       "[[trend]]\nexpect = \"similar\"\nruns = [\"a\", \"b\"]\n",
       "needs tolerance"},
      {"[campaign]\nbase = \"base.toml\"\n[[run]]\nname = \"a\"\n[[run]]\nname = \"b\"\n"
       "[[trend]]\nexpect = \"rises\"\nruns = [\"a\", \"b\"]\nx = [2, 1]\n",
       "increasing"},
      {"[campaign]\nbase = \"base.toml\"\n[[run]]\nname = \"a\"\n"
       "[[trend]]\nexpect = \"rises\"\nruns = [\"a\", \"a\"]\n",
       "\"a\" twice"},
      {"[campaign]\nbase = \"base.toml\"\n[[run]]\nname = \"a\"\nscene = 3\n",
       "scene = 3 is not a string"},
      {"[campaign]\nbase = \"base.toml\"\n[[run]]\nname = \"a\"\nreference = 3\n",
       "reference must be a table"},
  };
  for (const auto &[text, needle] : cases) {
    const std::string message = errorOf(dir, text);
    EXPECT_NE(message.find(needle), std::string::npos) << text << "\n-> " << message;
    EXPECT_NE(message.find("c.toml"), std::string::npos) << message;
  }
  const auto r = mesopen::test::runMesopen("campaign " + (dir / "c.toml") + " -o " + (dir / "out"));
  EXPECT_EQ(r.code, 2) << r.output;
}

// Two runs of the tiny scene, two replicates each: every replicate runs once, the tables hold
// them; a second call runs nothing; a changed run is run again, and only it.
TEST(Campaign, RunsEachReplicateOnce) {
  ScratchDir dir("campaign-run");
  mesopen::test::writeFile(dir / "base.toml", tiny_base);
  const std::string campaign = "[campaign]\nbase = \"base.toml\"\nreplicates = 2\n"
                               "[[run]]\nname = \"slow\"\nlabel = \"a | b\"\nrun.velocity = 500.0\n"
                               "[[run]]\nname = \"fast\"\nrun.velocity = VELOCITY\n"
                               "[[trend]]\nexpect = \"rises\"\nruns = [\"slow\", \"fast\"]\n";
  auto write = [&](const std::string &v) {
    std::string text = campaign;
    text.replace(text.find("VELOCITY"), 8, v);
    mesopen::test::writeFile(dir / "c.toml", text);
  };
  const std::string cmd = "campaign " + (dir / "c.toml") + " -o " + (dir / "out") + " --threads 1";
  write("1500.0");
  auto r = mesopen::test::runMesopen(cmd);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("4 to run now, 0 done before"), std::string::npos) << r.output;
  const nlohmann::json s = nlohmann::json::parse(mesopen::test::readFile(dir / "out/summary.json"));
  EXPECT_EQ(s["completed"], 4);
  ASSERT_EQ(s["runs"].size(), 4u);
  EXPECT_EQ(s["runs"][1]["seed"], 1001);
  EXPECT_TRUE(s["runs"][3]["measures"].contains("average_lateral_force"));
  EXPECT_EQ(s["trends"][0]["verdict"].get<std::string>().empty(), false);
  for (const char *f : {"runs.csv", "table.csv", "table.md", "runs/fast/r2/run.h5",
                        "runs/fast/r2/scene.toml", "runs/fast/r2/instability.json"})
    EXPECT_TRUE(std::filesystem::exists(dir / ("out/" + std::string(f)))) << f;
  const std::string table = mesopen::test::readFile(dir / "out/table.md");
  EXPECT_NE(table.find("| slow | a \\| b | 2 |"), std::string::npos) << table;

  // Again, the campaign file named another way: nothing to run.
  r = mesopen::test::runMesopen("campaign " + dir.path.string() + "/./c.toml -o " + (dir / "out") +
                                " --threads 1");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("0 to run now, 4 done before"), std::string::npos) << r.output;

  // A finished replicate whose run.h5 was cut short is made again, not kept as failed.
  const std::string cut = dir / "out/runs/fast/r2/run.h5";
  std::filesystem::resize_file(cut, std::filesystem::file_size(cut) / 2);
  r = mesopen::test::runMesopen(cmd);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("1 to run now, 3 done before"), std::string::npos) << r.output;

  write("1400.0");
  r = mesopen::test::runMesopen(cmd);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("2 to run now, 2 done before"), std::string::npos) << r.output;
}

// A second campaign in a directory that one is using stops at once (exit 1), touching nothing.
TEST(Campaign, OneCampaignADirectory) {
  ScratchDir dir("campaign-lock");
  mesopen::test::writeFile(dir / "base.toml", tiny_base);
  mesopen::test::writeFile(dir / "c.toml",
                           "[campaign]\nbase = \"base.toml\"\n[[run]]\nname = \"a\"\n");
  std::filesystem::create_directories(dir / "out");
  const int held = open((dir / "out/.campaign.lock").c_str(), O_RDWR | O_CREAT, 0644);
  ASSERT_GE(held, 0);
  ASSERT_EQ(flock(held, LOCK_EX | LOCK_NB), 0); // as a running campaign holds it
  const auto r = mesopen::test::runMesopen("campaign " + (dir / "c.toml") + " -o " + (dir / "out"));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("in use by another mesopen campaign"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out/runs"));
  close(held);
}

// A campaign killed (SIGKILL, no chance to pass anything on) takes its run with it: the run gets
// SIGTERM and ends as on Ctrl-C, its summary saying "interrupted", and holds the directory's lock
// until then. It went on alone in its own process group (here for 30 s), and a restarted campaign
// could run the same replicate into the same files beside it.
TEST(Campaign, RunEndsWithItsKilledCampaign) {
  ScratchDir dir("campaign-killed");
  std::string base = tiny_base;
  base.replace(base.find("end_time = 1e-8"), 15, "end_time = 1e-5"); // about 30 s of steps
  mesopen::test::writeFile(dir / "base.toml", base);
  mesopen::test::writeFile(dir / "c.toml",
                           "[campaign]\nbase = \"base.toml\"\n[[run]]\nname = \"a\"\n");
  const std::string campaign = dir / "c.toml", out = dir / "out";
  const pid_t pid = startCampaign(campaign, out);
  ASSERT_GE(pid, 0);
  auto find = [&](const std::string &name) {
    std::error_code ec;
    for (const auto &f : std::filesystem::recursive_directory_iterator(out, ec))
      if (f.path().filename() == name)
        return f.path().string();
    return std::string();
  };
  std::string running;
  for (int i = 0; i < 600 && (running = find("run.h5.tmp")).empty(); ++i)
    ::usleep(50000);
  ASSERT_FALSE(running.empty()) << "the campaign's run did not start";
  ::kill(pid, SIGKILL);
  ::waitpid(pid, nullptr, 0);
  const std::string summary = std::filesystem::path(running).parent_path() / "summary.json";
  for (int i = 0; i < 200 && !std::filesystem::exists(summary); ++i)
    ::usleep(50000);
  ASSERT_TRUE(std::filesystem::exists(summary)) << "the run went on after its campaign died";
  EXPECT_EQ(nlohmann::json::parse(mesopen::test::readFile(summary))["status"], "interrupted");
  // The run gone, the lock is free.
  const int lock = open((dir / "out/.campaign.lock").c_str(), O_RDWR);
  ASSERT_GE(lock, 0);
  bool free = false;
  for (int i = 0; i < 100 && !(free = flock(lock, LOCK_EX | LOCK_NB) == 0); ++i)
    ::usleep(50000);
  EXPECT_TRUE(free);
  close(lock);
}

// A campaign stopped (SIGTERM) while its run, with checkpoints on, has written one: at the next
// call the run goes on from its checkpoint (`mesopen run --resume`), its log.txt appended to, and
// its run.h5 is the bytes of the same campaign never stopped. A checkpoint that cannot be
// continued (cut short here) is left and the run made anew, to the same bytes.
TEST(Campaign, InterruptedRunContinuesFromItsCheckpoint) {
  ScratchDir dir("campaign-resume");
  std::string base = tiny_base;
  base.replace(base.find("end_time = 1e-8"), 15, "end_time = 1e-6\ncheckpoint_time = 1e-7");
  mesopen::test::writeFile(dir / "base.toml", base);
  mesopen::test::writeFile(dir / "c.toml",
                           "[campaign]\nbase = \"base.toml\"\n[[run]]\nname = \"a\"\n");
  const std::string campaign = dir / "c.toml";
  auto r =
      mesopen::test::runMesopen("campaign " + campaign + " -o " + (dir / "whole") + " --threads 1");
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string whole = dir / "whole/runs/a/r1/run.h5";

  for (const bool damaged : {false, true}) {
    SCOPED_TRACE(damaged ? "damaged checkpoint" : "checkpoint");
    const std::string out = dir / (damaged ? "damaged" : "stopped");
    const std::string replicate = out + "/runs/a/r1";
    const pid_t pid = startCampaign(campaign, out);
    ASSERT_GE(pid, 0);
    for (int i = 0; i < 1200 && !std::filesystem::exists(replicate + "/checkpoint/state.h5"); ++i)
      ::usleep(25000);
    ::kill(pid, SIGTERM);
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFEXITED(status));
    ASSERT_EQ(WEXITSTATUS(status), 128 + SIGTERM);
    ASSERT_EQ(nlohmann::json::parse(mesopen::test::readFile(replicate + "/summary.json"))["status"],
              "interrupted");
    ASSERT_TRUE(std::filesystem::exists(replicate + "/checkpoint/state.h5"));
    const std::string log_before = mesopen::test::readFile(replicate + "/log.txt");
    if (damaged)
      std::filesystem::resize_file(replicate + "/checkpoint/state.h5", 1000);

    r = mesopen::test::runMesopen("campaign " + campaign + " -o " + out + " --threads 1");
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("1 to run now, 0 done before (1 to continue from a checkpoint)"),
              std::string::npos)
        << r.output;
    EXPECT_EQ(r.output.find("cannot be continued") != std::string::npos, damaged) << r.output;
    EXPECT_TRUE(mesopen::test::sameBytes(whole, replicate + "/run.h5"));
    EXPECT_FALSE(std::filesystem::exists(replicate + "/checkpoint"));
    if (!damaged) { // the stopped run's output kept before the continued run's
      const std::string log = mesopen::test::readFile(replicate + "/log.txt");
      EXPECT_GT(log.size(), log_before.size());
      EXPECT_EQ(log.substr(0, log_before.size()), log_before);
    }
  }
}
