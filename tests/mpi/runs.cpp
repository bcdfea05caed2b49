// Runs under mpirun: LIGGGHTS decomposed over the ranks, the FE elements shared by body (Zoltan's
// RCB partition of the bodies).
#include "h5file.hpp"
#include "run.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

using namespace mesopen;
using test::ScratchDir;

namespace {

// The reduced default scene with every grain a disk, to 0.3 us (about 1,000 steps).
std::string demScene(const ScratchDir &dir) {
  std::ifstream in(std::string(MESOPEN_SOURCE_DIR) + "/examples/quickstart.toml");
  std::string text((std::istreambuf_iterator<char>(in)), {}), line, out;
  std::istringstream lines(text);
  while (std::getline(lines, line)) {
    if (line.starts_with("frame_interval") || line.starts_with("end_time"))
      continue;
    out += line + "\n";
    if (line == "[run]")
      out += "representation = \"dem\"\nframe_interval = 0\nend_time = 0.3e-6\n";
  }
  const std::string path = dir / "dem.toml";
  std::ofstream(path) << out;
  return path;
}

test::Result run(int ranks, const std::string &scene, const std::string &out) {
  const std::string mpirun = "mpirun --allow-run-as-root --oversubscribe -np " +
                             std::to_string(ranks) + " " + MESOPEN_BINARY;
  const std::string cmd = (ranks > 0 ? mpirun : std::string(MESOPEN_BINARY)) + " run " + scene +
                          " -o " + out + " --threads 1 --quiet 2>&1";
  test::Result r{-1, {}};
  FILE *pipe = ::popen(cmd.c_str(), "r");
  char buffer[4096];
  std::size_t n;
  while (pipe && (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0)
    r.output.append(buffer, n);
  const int status = pipe ? ::pclose(pipe) : -1;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// The largest difference between two runs' series, over the series' largest magnitude (the
// difference itself for a series that is 0 throughout).
double difference(const std::string &a, const std::string &b, const std::string &series) {
  const auto x = H5File::open(a).read<double>("/series/" + series);
  const auto y = H5File::open(b).read<double>("/series/" + series);
  EXPECT_EQ(x.size(), y.size()) << series;
  double diff = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < std::min(x.size(), y.size()); ++i)
    diff = std::max(diff, std::abs(x[i] - y[i])), scale = std::max(scale, std::abs(x[i]));
  return scale > 0.0 ? diff / scale : diff;
}

// One rank and 2 and 4 (oversubscribed) ranks give the same run but for round-off: the disks'
// forces may be summed in another order when LIGGGHTS's particles are split over ranks, and the
// granular dynamics amplifies that. Every rank chooses the disks near the FE bodies by the same
// rule (the largest disk taken over all ranks), and to 0.3 us the series agree bit for bit.
// Tolerance 1e-6 of each series' largest value.
TEST(Mpi, OneTwoAndFourRanksAgree) {
  ScratchDir dir("mpi-ranks");
  const std::string scene = demScene(dir);
  ASSERT_EQ(run(0, scene, dir / "one").code, 0);
  for (int ranks : {2, 4}) {
    const std::string out = dir / ("ranks-" + std::to_string(ranks));
    const test::Result r = run(ranks, scene, out);
    ASSERT_EQ(r.code, 0) << r.output;
    const std::string summary = test::readFile(out + "/summary.json");
    EXPECT_NE(summary.find("\"ranks\": " + std::to_string(ranks)), std::string::npos);
    for (const char *series : {"projectile/vy", "projectile/vx", "projectile/lateral_force",
                               "projectile/rotational_momentum", "projectile/depth"}) {
      const double d = difference(dir / "one/run.h5", out + "/run.h5", series);
      std::printf("%d ranks: %s differs by %.2e of its largest value\n", ranks, series, d);
      EXPECT_LT(d, 1e-6) << series;
    }
  }
}

// The reduced default scene fully meshed (1,115 bodies), to `end_time` with a frame every 0.1 us
// and no VTK files, `extra` added to [run] and `contact` to [contact].
std::string feScene(const ScratchDir &dir, const std::string &name, const std::string &end_time,
                    const std::string &extra, const std::string &contact = "") {
  std::ifstream in(std::string(MESOPEN_SOURCE_DIR) + "/examples/quickstart.toml");
  std::string text((std::istreambuf_iterator<char>(in)), {}), line, scene;
  std::istringstream lines(text);
  while (std::getline(lines, line)) {
    if (line.starts_with("frame_interval") || line.starts_with("end_time") ||
        line.starts_with("vtk"))
      continue;
    scene += line + "\n";
    if (line == "[run]")
      scene += "frame_interval = 1e-7\nend_time = " + end_time + "\nvtk = false\n" + extra;
    if (line == "[contact]")
      scene += contact;
  }
  const std::string path = dir / name;
  std::ofstream(path) << scene;
  return path;
}

// The same FE run but for the order of the energy sums: the projectile's series and every frame's
// element and node fields equal to the last bit; the energies, summed over the ranks in another
// order, within 1e-9 of their largest value.
void expectSameFeRun(const std::string &a, const std::string &b, const std::string &label) {
  for (const char *series : {"projectile/vy", "projectile/vx", "projectile/lateral_force",
                             "projectile/rotational_momentum", "projectile/depth"}) {
    const double d = difference(a + "/run.h5", b + "/run.h5", series);
    std::printf("%s: %s differs by %.2e of its largest value\n", label.c_str(), series, d);
    EXPECT_EQ(d, 0.0) << label << ": " << series;
  }
  for (const char *series : {"energy/internal", "energy/kinetic", "energy/balance_error"}) {
    const double d = difference(a + "/run.h5", b + "/run.h5", series);
    std::printf("%s: %s differs by %.2e of its largest value\n", label.c_str(), series, d);
    EXPECT_LT(d, 1e-9) << label << ": " << series;
  }
  const H5File one = H5File::open(a + "/run.h5"), two = H5File::open(b + "/run.h5");
  for (int frame = 0;; ++frame) {
    char group[32];
    std::snprintf(group, sizeof group, "/frames/%06d/", frame);
    if (!one.exists(group + std::string("x")))
      break;
    for (const char *field : {"x", "y", "vx", "vy", "pressure", "sxx", "plastic_strain"}) {
      const auto x = one.read<double>(group + std::string(field));
      const auto y = two.read<double>(group + std::string(field));
      EXPECT_TRUE(x == y) << label << ": frame " << frame << "'s " << field << " differs";
    }
  }
}

// Every frame's disks (positions, velocities, spins) equal to the last bit, in more than one frame.
void expectSameDisks(const std::string &a, const std::string &b, const std::string &label) {
  const H5File one = H5File::open(a + "/run.h5"), two = H5File::open(b + "/run.h5");
  int frames = 0;
  for (;; ++frames) {
    char group[40];
    std::snprintf(group, sizeof group, "/frames/%06d/disks/", frames);
    if (!one.exists(group + std::string("x")))
      break;
    for (const char *field : {"x", "y", "vx", "vy", "omega"})
      EXPECT_TRUE(one.read<double>(group + std::string(field)) ==
                  two.read<double>(group + std::string(field)))
          << label << ": frame " << frames << "'s disks' " << field << " differ";
  }
  EXPECT_GT(frames, 1) << label;
}

// A script that runs mesopen with its arguments, rank 1 of mpirun stopping itself after `step`
// (MESOPEN_STOP_AT_STEP, as a SIGTERM there).
void writeStopScript(const std::string &path, int step, const char *variable = "STOP_AT_STEP") {
  std::ofstream(path) << "#!/bin/sh\nif [ \"$OMPI_COMM_WORLD_RANK\" = 1 ]; then "
                         "export MESOPEN_"
                      << variable << "=" << step << "; fi\nexec " << MESOPEN_BINARY << " \"$@\"\n";
  std::filesystem::permissions(path, std::filesystem::perms::owner_all);
}

// The exit code of `command` run quietly on one thread a rank (-1 if it did not exit).
int exitCode(const std::string &command) {
  const int status = std::system((command + " --threads 1 --quiet >/dev/null 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

nlohmann::json summaryOf(const std::string &out) {
  return nlohmann::json::parse(test::readFile(out + "/summary.json"));
}

// The scene on `ranks` ranks into `out`: it ends well, with as many steps, eroded elements and
// searches for pairs as the one-rank run whose summary is `one` (the ranks search when one rank
// alone does: the travel bound of the step's reduction never keeps a search from them); its
// summary (null if it did not end well).
nlohmann::json onRanks(int ranks, const std::string &scene, const std::string &out,
                       const nlohmann::json &one, const std::string &label) {
  const test::Result r = run(ranks, scene, out);
  EXPECT_EQ(r.code, 0) << label << ": " << r.output;
  if (r.code != 0)
    return nullptr;
  const nlohmann::json many = summaryOf(out);
  EXPECT_EQ(many["steps"], one["steps"]) << label;
  EXPECT_EQ(many["eroded_elements"], one["eroded_elements"]) << label;
  EXPECT_EQ(many["contact"]["pair_searches"], one["contact"]["pair_searches"]) << label;
  return many;
}

// Whether two run.h5 files hold the same run (tests/support/same_run.py: every bit, but for the
// checkpoint and rebalance keys of the scene).
void expectSameRunFile(const std::string &a, const std::string &b) {
  const std::string same = "/usr/bin/python3 " + std::string(MESOPEN_SOURCE_DIR) +
                           "/tests/support/same_run.py " + a + " " + b;
  EXPECT_EQ(std::system(same.c_str()), 0) << same;
}

// `scene` on two ranks into dir/stopped, rank 1 stopping itself after step `step` (the run
// interrupted with a checkpoint there, exit 143; its summary then into `stopped`), resumed there;
// the same run whole into dir/whole: the same run.h5.
void stopResumeAndRunWhole(const ScratchDir &dir, const std::string &scene, int step,
                           nlohmann::json *stopped = nullptr) {
  writeStopScript(dir / "stop1.sh", step);
  const std::string mpirun = "timeout 300 mpirun --allow-run-as-root --oversubscribe -np 2 ";
  ASSERT_EQ(exitCode(mpirun + (dir / "stop1.sh") + " run " + scene + " -o " + (dir / "stopped")),
            143);
  EXPECT_EQ(summaryOf(dir / "stopped")["status"], "interrupted");
  if (stopped)
    *stopped = summaryOf(dir / "stopped");
  ASSERT_EQ(exitCode(mpirun + MESOPEN_BINARY + " run --resume " + (dir / "stopped")), 0);
  ASSERT_EQ(exitCode(mpirun + MESOPEN_BINARY + " run " + scene + " -o " + (dir / "whole")), 0);
  expectSameRunFile(dir / "whole/run.h5", dir / "stopped/run.h5");
}

// A small scene of the tests of stops and failures: a 1 x 0.5 mm target of 60 um grains, its
// [run] table open for `run` keys.
std::string smallScene(const std::string &run) {
  return "[target]\nwidth = 1.0e-3\nheight = 0.5e-3\ndiameter = 60e-6\nmesh_size = 15e-6\n"
         "[projectile]\nlength = 0.3e-3\n[run]\n" +
         run;
}

} // namespace

// One rank and two sharing the element work (each computes the bodies it owns, the nodes of the
// other's come by all-gather every step), on the reduced default scene fully meshed to 0.3 us
// (about 2,700 steps); and the same with time-step erosion at 0.4 of the first step (28 elements
// eroded: the failed elements' states are gathered too, and both ranks erode alike) and a new
// partition forced every 400 steps; and with mass scaling at 0.5 of the first step (the mass the
// elements ask for is gathered, and both ranks add the same). Each body's elements are computed by
// one rank in the same order, a body that changes owner brings its elements' state, the nodes'
// states are copied exactly and the step is the least of the same values: the projectile's
// series and the frames' fields agree bit for bit. The bodies are Zoltan's RCB partition weighted
// by active elements: over the plain run the ranks' element-steps differ from their mean by less
// than 5 % (round-robin ownership, body b on rank b mod 2: 21 %).
TEST(Mpi, TwoRanksShareTheElementWork) {
  for (const std::string extra :
       {"", "erode_step_ratio = 0.4\nrebalance_every = 400\n", "mass_scaling_step_ratio = 0.5\n"}) {
    const bool eroding = extra.starts_with("erode"), scaling = extra.starts_with("mass");
    ScratchDir dir(eroding ? "mpi-fe-eroding" : scaling ? "mpi-fe-mass-scaling" : "mpi-fe");
    const std::string label = std::string("2 ranks sharing the elements") +
                              (eroding   ? ", eroding, rebalanced every 400 steps"
                               : scaling ? ", mass scaling"
                                         : "");
    const std::string scene = feScene(dir, "fe.toml", "0.3e-6", extra);
    ASSERT_EQ(run(0, scene, dir / "one").code, 0);
    const test::Result r = run(2, scene, dir / "two");
    ASSERT_EQ(r.code, 0) << r.output;
    const nlohmann::json one = summaryOf(dir / "one"), two = summaryOf(dir / "two");
    EXPECT_EQ(two["ranks"], 2);
    if (eroding) {
      EXPECT_GT(one["eroded_elements"].get<int>(), 0);
      EXPECT_EQ(two["eroded_elements"], one["eroded_elements"]);
    }
    if (scaling) {
      EXPECT_GT(one["mass_scaling"]["added_mass"].get<double>(), 0.0);
      EXPECT_EQ(two["mass_scaling"]["added_mass"], one["mass_scaling"]["added_mass"]);
    }
    expectSameFeRun(dir / "one", dir / "two", label);
    const nlohmann::json &p = two["partition"];
    std::printf("%s: partition %s\n", label.c_str(), p.dump().c_str());
    EXPECT_EQ(p["method"], "zoltan rcb");
    if (extra.empty()) { // rebalanced by the imbalance alone, as the grains woke
      EXPECT_GT(p["rebalances"].get<int>(), 0);
      EXPECT_EQ(p["forced_rebalances"], 0);
      EXPECT_LT(p["run_imbalance"].get<double>(), 0.05);
    }
  }
}

// One, two and four ranks on the fully meshed scene to 0.1 us (548 steps) with time-step erosion
// at 0.4 of the first step (5 elements eroded) and a new partition forced every 100 steps (5 in
// the run, every body's owner as RCB gives it for the loads of that step): the same run but for
// the energies' sum order, and each rank's figures add up to the run's (bodies, active elements,
// element-steps). Each rank's halo (the other ranks' boundary nodes its pairs need) is fewer than
// half the moving nodes it does not own, and every step it receives at least their positions and
// velocities (4 doubles each); each rank searches only the pairs of bodies of its own (fewer than
// one rank searches), and the ranks together at least every pair one rank searches and at most
// twice as many (a pair of two ranks' bodies is searched by both, each pushing its own nodes); a
// step makes at most 1.5 collective calls on average (its one reduction, which bounds the moving
// bodies' travel at the next step, so that their travel itself is reduced only near a search;
// their boxes all-gathered at a search and otherwise sent to the ranks whose pairs hold them; the
// halo and the loads are messages; the failed elements' states and a repartition only at their
// steps: 3.04 before the travel bound and the exchange without sizes); a body that changes owner
// goes to its new owner alone (with the bodies at rest, the same everywhere, staying), so no rank
// receives in one step more than the state of every moving element and node (8 values each; sent to
// every rank, 2.5 to 5.1 times as much at 4 ranks); one rank receives nothing. On one rank the keys
// change nothing: run.h5 is the same bytes as without them.
TEST(Mpi, OneTwoAndFourRanksAgreeWhileRebalancing) {
  ScratchDir dir("mpi-fe-rebalancing");
  const std::string scene =
      feScene(dir, "fe.toml", "0.1e-6", "erode_step_ratio = 0.4\nrebalance_every = 100\n");
  const std::string plain = feScene(dir, "plain.toml", "0.1e-6", "erode_step_ratio = 0.4\n");
  ASSERT_EQ(run(0, scene, dir / "one").code, 0);
  ASSERT_EQ(run(0, plain, dir / "plain").code, 0);
  expectSameRunFile(dir / "one/run.h5", dir / "plain/run.h5");
  const nlohmann::json one = summaryOf(dir / "one");
  EXPECT_GT(one["eroded_elements"].get<int>(), 0);
  EXPECT_EQ(one["partition"]["method"], "one rank");
  EXPECT_EQ(one["partition"]["rebalances"], 0);
  const nlohmann::json &alone = one["partition"];
  EXPECT_EQ(alone["bytes_received_per_step"][0], 0.0);
  EXPECT_EQ(alone["halo_nodes_per_step"][0], 0.0);
  EXPECT_GT(alone["contact_pairs_per_step"][0].get<double>(), 0.0);
  EXPECT_GT(alone["peak_memory_bytes"][0].get<double>(), 0.0);
  const double moving_nodes = alone["active_nodes_per_step"][0].get<double>();
  for (int ranks : {2, 4}) {
    const std::string out = dir / ("ranks-" + std::to_string(ranks));
    const std::string label = std::to_string(ranks) + " ranks rebalanced every 100 steps";
    const nlohmann::json summary = onRanks(ranks, scene, out, one, label);
    ASSERT_FALSE(summary.is_null()) << label;
    expectSameFeRun(dir / "one", out, label);
    const nlohmann::json &p = summary["partition"];
    std::printf("%s: partition %s\n", label.c_str(), p.dump().c_str());
    const auto steps = summary["steps"].get<std::size_t>();
    EXPECT_EQ(p["forced_rebalances"].get<std::size_t>(), (steps - 1) / 100);
    EXPECT_GE(p["rebalances"], p["forced_rebalances"]);
    EXPECT_GT(p["migrated_bodies"].get<int>(), 0);
    ASSERT_EQ(p["bodies"].size(), static_cast<std::size_t>(ranks));
    std::size_t bodies = 0;
    double element_steps = 0.0;
    for (int rank = 0; rank < ranks; ++rank) {
      bodies += p["bodies"][rank].get<std::size_t>();
      element_steps += p["element_steps"][rank].get<double>();
    }
    EXPECT_EQ(bodies, summary["model"]["bodies"].get<std::size_t>());
    EXPECT_EQ(element_steps, summary["element_steps"].get<double>());
    const double pairs_alone = alone["contact_pairs_per_step"][0].get<double>();
    double pairs = 0.0;
    for (int rank = 0; rank < ranks; ++rank) {
      const double halo = p["halo_nodes_per_step"][rank].get<double>();
      EXPECT_LT(halo, 0.5 * (moving_nodes - p["active_nodes_per_step"][rank].get<double>()))
          << rank;
      EXPECT_GT(halo, 0.0);
      EXPECT_GE(p["bytes_received_per_step"][rank].get<double>(), 32.0 * halo) << rank;
      EXPECT_GE(p["max_bytes_received_in_a_step"][rank].get<double>(),
                p["bytes_received_per_step"][rank].get<double>());
      pairs += p["contact_pairs_per_step"][rank].get<double>();
      EXPECT_LT(p["contact_pairs_per_step"][rank].get<double>(), pairs_alone) << rank;
      EXPECT_LE(p["collectives_per_step"][rank].get<double>(), 1.5) << rank;
      EXPECT_GT(p["peak_memory_bytes"][rank].get<double>(), 0.0);
    }
    EXPECT_GE(pairs, pairs_alone);
    EXPECT_LE(pairs, 2.0 * pairs_alone);
    double moving_state = 0.0; // bytes: 8 values per moving element and node, over the run's mean
    for (int rank = 0; rank < ranks; ++rank)
      moving_state += 64.0 * (p["active_elements_per_step"][rank].get<double>() +
                              p["active_nodes_per_step"][rank].get<double>());
    for (int rank = 0; rank < ranks; ++rank)
      EXPECT_LT(p["max_bytes_received_in_a_step"][rank].get<double>(), moving_state) << rank;
  }
}

// Multiple time stepping (run.max_level = 2, level gap 1) on one, two and four ranks, on the fully
// meshed scene to 0.2 us (about 1,160 steps) with time-step erosion at 0.4 of the first step, mass
// scaling at 0.5 and a new partition forced every 100 steps: the projectile steps in 8 parts, each
// at a level of its own.
// Every process chooses every body's level alike (the bodies' own steps from their owners), a body
// in parts takes its owner's level, and a body that changes owner brings what its owner alone kept
// of its levels (its elements' last steps, its energies, its parts' levels, forces and window
// starts; the contact's pushed depths per level of pair). The same run but for the energies' sum
// order, with as many element updates and as many active elements by level at the end.
TEST(Mpi, OneTwoAndFourRanksAgreeAtLevels) {
  ScratchDir dir("mpi-fe-levels");
  const std::string scene =
      feScene(dir, "levels.toml", "0.2e-6",
              "max_level = 2\nerode_step_ratio = 0.4\nmass_scaling_step_ratio = 0.5\n"
              "rebalance_every = 100\n");
  ASSERT_EQ(run(0, scene, dir / "one").code, 0);
  const nlohmann::json one = summaryOf(dir / "one");
  const nlohmann::json &levels = one["multiple_time_stepping"];
  EXPECT_GT(one["mass_scaling"]["added_mass"].get<double>(), 0.0);
  EXPECT_EQ(levels["bodies_in_parts"], 1);
  EXPECT_LT(levels["element_update_share"].get<double>(), 1.0);
  EXPECT_GT(levels["active_elements_by_level_at_end"][1].get<int>(), 0);
  EXPECT_GT(one["eroded_elements"].get<int>(), 0);
  for (int ranks : {2, 4}) {
    const std::string out = dir / ("ranks-" + std::to_string(ranks));
    const std::string label = std::to_string(ranks) + " ranks at levels";
    const nlohmann::json many = onRanks(ranks, scene, out, one, label);
    ASSERT_FALSE(many.is_null()) << label;
    EXPECT_EQ(many["multiple_time_stepping"], levels) << label;
    EXPECT_EQ(many["mass_scaling"]["added_mass"], one["mass_scaling"]["added_mass"]) << label;
    EXPECT_GT(many["partition"]["migrated_bodies"].get<int>(), 0) << label;
    expectSameFeRun(dir / "one", out, label);
  }
}

// Selective mass scaling at levels (0.22 of the first step, as run 6; time-step erosion at its
// default) on one and two ranks, the reduced scene fully meshed to 1 us (about 5,400 steps): the
// same run but for the energies' sum order, as much mass added. The elements asking for mass are
// gathered from the chunks computed in the step; a chunk not due kept what it had asked for at its
// last pass, which a rank then sent beyond the count the step's reduction gave (step 5,261 on two
// ranks: "padTo: 4 values, more than the 2 the step's reduction said").
TEST(Mpi, MassScalingAtLevelsOnTwoRanks) {
  ScratchDir dir("mpi-levels-mass-scaling");
  const std::string scene = feScene(dir, "levels.toml", "1.0e-6",
                                    "max_level = 2\nmass_scaling_step_ratio = 0.22\n"
                                    "rebalance_every = 100\n");
  ASSERT_EQ(run(0, scene, dir / "one").code, 0);
  const test::Result r = run(2, scene, dir / "two");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json one = summaryOf(dir / "one"), two = summaryOf(dir / "two");
  EXPECT_GT(one["mass_scaling"]["added_mass"].get<double>(), 0.0);
  EXPECT_EQ(two["mass_scaling"]["added_mass"], one["mass_scaling"]["added_mass"]);
  EXPECT_EQ(two["multiple_time_stepping"], one["multiple_time_stepping"]);
  expectSameFeRun(dir / "one", dir / "two", "2 ranks at levels, mass scaling");
}

// Multiple time stepping with disks (run.max_level = 2) on one, two and four ranks, the hybrid
// scene of HybridRunsAgreeOnOneTwoAndFourRanks: a body or part that a disk may reach within twice
// its window steps at level 0 (FeDemCoupling::capLevels; without that cap the one-process run
// itself has 657 FE-DEM contacts between a body's steps). Each process holds only its own disks:
// the moving bodies' gaps to them are gathered, the disks near the projectile (a body in parts)
// reach its owner, the closing speed's two maxima ride in the step's reduction. The same run but
// for the energies' sum order, as many element updates, no disk touching a body between its steps.
TEST(Mpi, HybridRunsAgreeAtLevelsOnOneTwoAndFourRanks) {
  ScratchDir dir("mpi-hybrid-levels");
  const std::string scene = feScene(dir, "hybrid.toml", "0.6e-6",
                                    "representation = \"hybrid\"\nerode_step_ratio = 0.4\n"
                                    "rebalance_every = 200\nmax_level = 2\n");
  ASSERT_EQ(run(0, scene, dir / "one").code, 0);
  const nlohmann::json one = summaryOf(dir / "one");
  const nlohmann::json &levels = one["multiple_time_stepping"];
  EXPECT_EQ(levels["bodies_in_parts"], 1);
  EXPECT_GT(levels["active_elements_by_level_at_end"][1].get<int>(), 0);
  EXPECT_EQ(one["dem"]["fe_dem_contacts_between_steps"], 0);
  EXPECT_GT(one["dem"]["fe_dem_contacts_last_step"].get<int>(), 0);
  for (int ranks : {2, 4}) {
    const std::string out = dir / ("ranks-" + std::to_string(ranks));
    const std::string label = std::to_string(ranks) + " ranks, hybrid at levels";
    const nlohmann::json many = onRanks(ranks, scene, out, one, label);
    ASSERT_FALSE(many.is_null()) << label;
    EXPECT_EQ(many["multiple_time_stepping"], levels) << label;
    EXPECT_EQ(many["dem"]["fe_dem_contacts_between_steps"], 0) << label;
    expectSameFeRun(dir / "one", out, label);
    expectSameDisks(dir / "one", out, label);
  }
}

// The same with every grain a disk (the projectile alone meshed, in parts, each capped by the
// disks near it, which the projectile's owner gathers from the other ranks): as many element
// updates on two ranks, and the projectile's series as OneTwoAndFourRanksAgree's (LIGGGHTS may sum
// a disk's forces in another order: within 1e-6 of each series' largest value).
TEST(Mpi, DemRunsAgreeAtLevelsOnOneAndTwoRanks) {
  ScratchDir dir("mpi-dem-levels");
  const std::string scene =
      feScene(dir, "dem.toml", "0.3e-6", "representation = \"dem\"\nmax_level = 2\n");
  ASSERT_EQ(run(0, scene, dir / "one").code, 0);
  const test::Result r = run(2, scene, dir / "two");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json one = summaryOf(dir / "one"), two = summaryOf(dir / "two");
  EXPECT_EQ(one["multiple_time_stepping"]["bodies_in_parts"], 1);
  EXPECT_EQ(two["multiple_time_stepping"], one["multiple_time_stepping"]);
  EXPECT_EQ(two["dem"]["fe_dem_contacts_between_steps"], 0);
  for (const char *series : {"projectile/vy", "projectile/vx", "projectile/lateral_force",
                             "projectile/rotational_momentum", "projectile/depth"})
    EXPECT_LT(difference(dir / "one/run.h5", dir / "two/run.h5", series), 1e-6) << series;
}

// The run of OneTwoAndFourRanksAgreeAtLevels on two ranks, stopped by rank 1 after step 600 (so at
// step 601, within a cycle of levels: the bodies at level 1 and 2 between their steps) and resumed,
// against the same run whole: the checkpoint holds what only the owners keep of the levels (their
// elements' last steps, energies, the projectile's parts; the contact's pushed depths per level
// of pair), gathered to the first process. run.h5 is the same bytes, and the element updates the
// same.
TEST(Mpi, StoppedAndResumedAtLevelsIsTheSameRun) {
  ScratchDir dir("mpi-levels-resume");
  const std::string scene = feScene(dir, "levels.toml", "0.2e-6",
                                    "max_level = 2\nerode_step_ratio = 0.4\nrebalance_every = 100\n"
                                    "checkpoint_interval = 1e6\n");
  nlohmann::json stopped;
  stopResumeAndRunWhole(dir, scene, 600, &stopped);
  EXPECT_EQ(stopped["steps"], 601);
  EXPECT_EQ(summaryOf(dir / "stopped")["multiple_time_stepping"],
            summaryOf(dir / "whole")["multiple_time_stepping"]);
}

// A projectile driven at constant velocity (run.constant_velocity: every node's velocity imposed)
// on one, two and four ranks: the contact's forces on its nodes are complete at its owner only,
// and the work they do, which the imposed velocities correct at both half-kicks, is taken there
// and summed over the ranks. The same run but for the energies' sum order (within 1e-9 of their
// largest value), whichever rank owns the projectile (a new partition every 50 steps). And the same
// with every body of 16 boundary nodes or more in part in the contact's halos (contact.
// halo_in_part_from, the grains too): with the part the overlaps widened by two element sizes alone
// (not by their diagonal as well), a pair's lists there missed a segment a grain's node then
// touched, and the work differed by 6e-7 of it at four ranks.
TEST(Mpi, DrivenProjectilesContactWorkIsSummedOverTheRanks) {
  for (const std::string contact : {"", "halo_in_part_from = 16\n"}) {
    ScratchDir dir(contact.empty() ? "mpi-fe-driven" : "mpi-fe-driven-in-part");
    const std::string scene = feScene(dir, "driven.toml", "0.1e-6",
                                      "constant_velocity = true\nrebalance_every = 50\n", contact);
    ASSERT_EQ(run(0, scene, dir / "one").code, 0);
    const nlohmann::json one = summaryOf(dir / "one");
    EXPECT_GT(one["energy"]["contact"].get<double>(), 0.0);
    for (int ranks : {2, 4}) {
      const std::string out = dir / ("ranks-" + std::to_string(ranks));
      const test::Result r = run(ranks, scene, out);
      ASSERT_EQ(r.code, 0) << r.output;
      const std::string label = std::to_string(ranks) + " ranks, a driven projectile" +
                                (contact.empty() ? "" : ", the grains in part");
      expectSameFeRun(dir / "one", out, label);
      const nlohmann::json many = summaryOf(out);
      for (const char *energy : {"contact", "friction", "external"})
        EXPECT_NEAR(many["energy"][energy].get<double>(), one["energy"][energy].get<double>(),
                    1e-9 * std::abs(one["energy"]["external"].get<double>()))
            << label << ": " << energy;
    }
  }
}

// The reduced default scene hybrid (the grains near the projectile's path meshed, the others
// disks), with time-step erosion at 0.4 of the first step and a new partition forced every 200
// steps, on one, two and four ranks to 0.6 us (about 3,600 steps): the FE bodies' contact, the
// FE-DEM contact and LIGGGHTS's disks on ranks of their own. The projectile's series, every
// frame's element, node and disk fields agree bit for bit, the energies within 1e-9 of their
// largest value (summed over the ranks in another order). No rank receives every moving node: its
// halo (the FE-FE pairs' and its disks' FE boundary nodes) stays below a quarter of the moving
// nodes it does not own (6-12 % here; with the FE bodies sent to every rank whose near disks' box
// they met, 10-35 %), and the bytes it receives a step below 8 bytes a node of those (an
// all-gather of their positions and velocities is 32); a step makes at most 8 collective calls on
// average (the solver's and the FE-FE contact's 3; the FE-DEM contact's region, the cells its disks
// reach, the sizes of its halo and of its reactions, one each; the disks' contact history, two a
// window; LIGGGHTS's own not counted).
TEST(Mpi, HybridRunsAgreeOnOneTwoAndFourRanks) {
  ScratchDir dir("mpi-hybrid");
  const std::string scene =
      feScene(dir, "hybrid.toml", "0.6e-6",
              "representation = \"hybrid\"\nerode_step_ratio = 0.4\nrebalance_every = 200\n");
  ASSERT_EQ(run(0, scene, dir / "one").code, 0);
  const nlohmann::json one = summaryOf(dir / "one");
  EXPECT_GT(one["eroded_elements"].get<int>(), 0);
  EXPECT_GT(one["dem"]["disks"].get<int>(), 0);
  EXPECT_GT(one["dem"]["fe_dem_contacts_last_step"].get<int>(), 0);
  const double moving_nodes = one["partition"]["active_nodes_per_step"][0].get<double>();
  for (int ranks : {2, 4}) {
    const std::string out = dir / ("ranks-" + std::to_string(ranks));
    const std::string label = std::to_string(ranks) + " ranks, hybrid";
    const nlohmann::json many = onRanks(ranks, scene, out, one, label);
    ASSERT_FALSE(many.is_null()) << label;
    const nlohmann::json &p = many["partition"];
    EXPECT_GT(p["forced_rebalances"].get<int>(), 0) << label;
    std::printf("%s: partition %s\n", label.c_str(), p.dump().c_str());
    for (int rank = 0; rank < ranks; ++rank) {
      const double others = moving_nodes - p["active_nodes_per_step"][rank].get<double>();
      const double halo = p["halo_nodes_per_step"][rank].get<double>();
      EXPECT_GT(halo, 0.0) << label << ", rank " << rank;
      EXPECT_LT(halo, 0.25 * others) << label << ", rank " << rank;
      EXPECT_LT(p["bytes_received_per_step"][rank].get<double>(), 8.0 * others)
          << label << ", rank " << rank;
      EXPECT_LE(p["collectives_per_step"][rank].get<double>(), 8.0) << label << ", rank " << rank;
    }
    expectSameFeRun(dir / "one", out, label);
    expectSameDisks(dir / "one", out, label);
  }
}

// The hybrid run of HybridRunsAgreeOnOneTwoAndFourRanks on two ranks, stopped by rank 1 at step
// 1,500 (a checkpoint, taken at the end of that step's window) and resumed, against the same run
// whole: the FE-DEM halo, the disks' contact history and the partition come back as they were.
// run.h5 is the same bytes, energies included: each rank's share of the energies and every body's
// owner are in the checkpoint (with the partition made anew at the resume, the ranks' shares were
// summed in another order: the energies differed by 2.5e-16 of the internal energy from the first
// step after it). Every frame's disk fields are identical.
TEST(Mpi, HybridStoppedAndResumedOnTwoRanksIsTheSameRun) {
  ScratchDir dir("mpi-hybrid-resume");
  const std::string scene =
      feScene(dir, "hybrid.toml", "0.6e-6",
              "representation = \"hybrid\"\nerode_step_ratio = 0.4\nrebalance_every = 200\n"
              "checkpoint_interval = 1e6\n");
  stopResumeAndRunWhole(dir, scene, 1500);
  expectSameDisks(dir / "whole", dir / "stopped", "hybrid, resumed on two ranks");
}

// The same at levels (the scene of HybridRunsAgreeAtLevelsOnOneTwoAndFourRanks): the disks' caps
// are measured anew at each step, so the resumed run chooses the levels the whole one did; run.h5
// is the same bytes, the element updates the same.
TEST(Mpi, HybridStoppedAndResumedAtLevelsOnTwoRanksIsTheSameRun) {
  ScratchDir dir("mpi-hybrid-levels-resume");
  const std::string scene = feScene(dir, "hybrid.toml", "0.6e-6",
                                    "representation = \"hybrid\"\nerode_step_ratio = 0.4\n"
                                    "rebalance_every = 200\nmax_level = 2\n"
                                    "checkpoint_interval = 1e6\n");
  stopResumeAndRunWhole(dir, scene, 1500);
  expectSameDisks(dir / "whole", dir / "stopped", "hybrid at levels, resumed on two ranks");
  EXPECT_EQ(summaryOf(dir / "stopped")["multiple_time_stepping"],
            summaryOf(dir / "whole")["multiple_time_stepping"]);
}

// The coupled baseline (examples/baseline-dem.toml: run 6's 6,198 grains as disks) runs to one
// projectile length on 2 ranks.
TEST(Mpi, CoupledBaselineRunsOnTwoRanks) {
  ScratchDir dir("mpi-baseline");
  std::ifstream in(std::string(MESOPEN_SOURCE_DIR) + "/examples/baseline-dem.toml");
  std::string text((std::istreambuf_iterator<char>(in)), {});
  const std::size_t at = text.find("frame_interval");
  text.replace(at, text.find('\n', at) - at, "frame_interval = 0");
  std::ofstream(dir / "baseline-dem.toml") << text;
  const test::Result r = run(2, dir / "baseline-dem.toml", dir / "out");
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string summary = test::readFile(dir / "out/summary.json");
  EXPECT_NE(summary.find("\"ended_by\": \"end_depth\""), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"disks\": 6198"), std::string::npos) << summary;
}

namespace {

// `mesopen run DIR/scene.toml -o DIR/out` on two processes, every process's files limited to
// `blocks` of 512 bytes (SIGXFSZ ignored: a write past it fails with EFBIG), at most 120 s:
// mpirun's exit code (124 when it was stopped for taking longer), -1 if it did not exit.
int runWithFilesLimited(const ScratchDir &dir, int blocks = 50) {
  std::ofstream(dir / "limited.sh") << "#!/bin/sh\ntrap '' XFSZ\nulimit -f " << blocks << "\nexec "
                                    << MESOPEN_BINARY << " \"$@\"\n";
  std::filesystem::permissions(dir / "limited.sh", std::filesystem::perms::owner_all);
  const std::string cmd = "timeout 120 mpirun --allow-run-as-root --oversubscribe -np 2 " +
                          (dir / "limited.sh") + " run " + (dir / "scene.toml") + " -o " +
                          (dir / "out") + " --threads 1 --quiet >/dev/null 2>&1";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

} // namespace

// A file the first process cannot write (a frame past the file-size limit, as on a full disk) ends
// the run on every process, with exit code 1 and a failed summary: the other process does not wait
// for it in the next step's exchanges (it did, until mpirun was killed).
TEST(Mpi, OutputFailureEndsEveryRank) {
  ScratchDir dir("mpi-output-failure");
  std::ofstream(dir / "scene.toml") << smallScene("end_time = 2e-7\nframe_interval = 1e-8\n");
  EXPECT_EQ(runWithFilesLimited(dir), 1) << "124: a process waited for the failed one";
  const auto summary = nlohmann::json::parse(test::readFile(dir / "out/summary.json"));
  EXPECT_EQ(summary["status"], "failed");
}

// A frame the first process cannot write at a step where a checkpoint is due: the first process
// still takes part in the checkpoint's gathers (the other waited for it there: 124), writes
// nothing more, and the run ends on both with exit code 1, its first failure said first. Files
// limited to 52 KiB: the first frame's VTU file (48 KiB) is written, the second's (55 KiB) is not.
TEST(Mpi, FrameFailureAtACheckpointEndsEveryRank) {
  ScratchDir dir("mpi-frame-failure-checkpoint");
  std::ofstream(dir / "scene.toml")
      << smallScene("end_time = 2e-7\nframe_interval = 5e-8\ncheckpoint_time = 5e-8\nvtk = true\n");
  EXPECT_EQ(runWithFilesLimited(dir, 104), 1) << "124: a process waited for the failed one";
  const auto summary = nlohmann::json::parse(test::readFile(dir / "out/summary.json"));
  EXPECT_EQ(summary["status"], "failed");
  EXPECT_TRUE(summary["failure"].get<std::string>().starts_with(
      "cannot write VTU file '" + (dir / "out/vtk/frame_000001.vtu.tmp") + "'"))
      << summary["failure"];
}

// The same after the loop, with disks: run.h5 fails on the first process as it is closed (no
// frames, the series written at the end); the others, gathering the disks' figures for the
// summary, must not wait for it there.
TEST(Mpi, OutputFailureAfterTheLoopEndsEveryRankWithDisks) {
  ScratchDir dir("mpi-output-failure-dem");
  std::ofstream(dir / "scene.toml")
      << smallScene("representation = \"dem\"\nend_time = 2e-7\nframe_interval = 0\nvtk = false\n");
  EXPECT_EQ(runWithFilesLimited(dir), 1) << "124: a process waited for the failed one";
  EXPECT_FALSE(std::filesystem::exists(dir / "out/run.h5")) << "a run.h5 that could not be whole";
}

// A stop signal caught by one process only (MESOPEN_STOP_AT_STEP=40 on rank 1, as a SIGTERM after
// step 40) stops every process at one step, the next: the ranks agree on it in that step's one
// reduction (a process stopping alone would leave the others waiting: mpirun killed at 120 s, 124).
// The checkpoint written there continues, on two ranks, to the same run as one never stopped.
TEST(Mpi, StopOnOneRankStopsEveryRankAtOneStep) {
  ScratchDir dir("mpi-stop-one-rank");
  std::ofstream(dir / "scene.toml") << smallScene(
      "end_time = 1e-7\nframe_interval = 0\nvtk = false\ncheckpoint_interval = 1e6\n");
  writeStopScript(dir / "stop1.sh", 40);
  const std::string mpirun = "timeout 120 mpirun --allow-run-as-root --oversubscribe -np 2 ";
  EXPECT_EQ(exitCode(mpirun + (dir / "stop1.sh") + " run " + (dir / "scene.toml") + " -o " +
                     (dir / "stopped")),
            143)
      << "124: a process went on alone";
  const auto stopped = nlohmann::json::parse(test::readFile(dir / "stopped/summary.json"));
  EXPECT_EQ(stopped["status"], "interrupted");
  EXPECT_EQ(stopped["steps"], 41);
  EXPECT_EQ(exitCode(mpirun + MESOPEN_BINARY + " run --resume " + (dir / "stopped")), 0);
  EXPECT_EQ(
      exitCode(mpirun + MESOPEN_BINARY + " run " + (dir / "scene.toml") + " -o " + (dir / "whole")),
      0);
  expectSameRunFile(dir / "stopped/run.h5", dir / "whole/run.h5");
}

// Checkpoints by the wall clock (run.checkpoint_interval) on two ranks: rank 0's clock decides,
// and the ranks agree on it in the next step's one reduction, so both write each checkpoint at
// the same step (a rank writing alone would wait for the other in its gathers: 124). Due every
// step, one comes after every step but the last, as on one rank, and the run is the one without
// them.
TEST(Mpi, CheckpointsByTheClockComeAtOneStepOnEveryRank) {
  ScratchDir dir("mpi-clock-checkpoints");
  const std::string base =
      smallScene("end_time = 1e-7\nmax_steps = 40\nframe_interval = 0\nvtk = false\n");
  std::ofstream(dir / "clock.toml") << base << "checkpoint_interval = 1e-9\n";
  std::ofstream(dir / "none.toml") << base;
  const std::string mpirun = "timeout 120 mpirun --allow-run-as-root --oversubscribe -np 2 ";
  for (const char *name : {"clock", "none"})
    ASSERT_EQ(exitCode(mpirun + MESOPEN_BINARY + " run " + (dir / (std::string(name) + ".toml")) +
                       " -o " + (dir / name)),
              0)
        << name << " (124: a rank waited for the other)";
  const nlohmann::json clock = summaryOf(dir / "clock");
  EXPECT_EQ(clock["steps"], 40);
  EXPECT_EQ(clock["checkpoints"]["written"], 39); // after steps 1 to 39
  expectSameRunFile(dir / "clock/run.h5", dir / "none/run.h5");
}

// A failure of one process alone within a step (MESOPEN_FAIL_AT_STEP=40 on rank 1, as a bug or an
// exhausted memory would throw there) ends every process with exit code 1 and says where: the
// other would wait for it in the step's next exchange (mpirun killed at 120 s: 124).
TEST(Mpi, FailureOfOneRankInAStepEndsEveryRank) {
  ScratchDir dir("mpi-fail-one-rank");
  std::ofstream(dir / "scene.toml")
      << smallScene("end_time = 1e-7\nframe_interval = 0\nvtk = false\n");
  writeStopScript(dir / "fail1.sh", 40, "FAIL_AT_STEP");
  const std::string command = "timeout 120 mpirun --allow-run-as-root --oversubscribe -np 2 " +
                              (dir / "fail1.sh") + " run " + (dir / "scene.toml") + " -o " +
                              (dir / "out") + " --threads 1 --quiet 2>&1";
  const test::Result r = test::runCommand(command);
  EXPECT_EQ(r.code, 1) << "124: a process waited for the failed one\n" << r.output;
  EXPECT_NE(r.output.find("process 1 of 2: step 40: a failure asked for by MESOPEN_FAIL_AT_STEP"),
            std::string::npos)
      << r.output;
}
