// Runs under mpirun: LIGGGHTS decomposed over the ranks, the FE elements shared by body.
#include "h5file.hpp"
#include "run.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
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

// The largest difference between two runs' series, over the series' largest magnitude.
double difference(const std::string &a, const std::string &b, const std::string &series) {
  const auto x = H5File::open(a).read<double>("/series/" + series);
  const auto y = H5File::open(b).read<double>("/series/" + series);
  EXPECT_EQ(x.size(), y.size()) << series;
  double diff = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < std::min(x.size(), y.size()); ++i)
    diff = std::max(diff, std::abs(x[i] - y[i])), scale = std::max(scale, std::abs(x[i]));
  return diff / scale;
}

} // namespace

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

// The reduced default scene fully meshed (1,115 bodies), to 0.3 us (about 2,500 steps) with a frame
// every 0.1 us, on one rank and on two sharing the element work (each computes the bodies it owns,
// the nodes of the other's come by all-gather every step); and the same with time-step erosion at
// 0.4 of the first step (28 elements eroded: the failed elements' states are gathered too, and both
// ranks erode alike). Each body's elements are computed by one rank in the same order, the nodes'
// states are copied exactly and the step is the least of the same values: the projectile's series
// and the frames' fields agree bit for bit (tolerance 1e-14 of the largest value); the energies are
// summed over the ranks in another order (internal energy and balance error to 1e-9 of their
// largest value). And the same with mass scaling at 0.5 of the first step (the mass the elements
// ask for is gathered, and both ranks add the same).
TEST(Mpi, TwoRanksShareTheElementWork) {
  for (const std::string extra :
       {"", "erode_step_ratio = 0.4\n", "mass_scaling_step_ratio = 0.5\n"}) {
    const bool eroding = extra.starts_with("erode"), scaling = extra.starts_with("mass");
    ScratchDir dir(eroding ? "mpi-fe-eroding" : scaling ? "mpi-fe-mass-scaling" : "mpi-fe");
    const char *label = eroding ? ", eroding" : scaling ? ", mass scaling" : "";
    std::ifstream in(std::string(MESOPEN_SOURCE_DIR) + "/examples/quickstart.toml");
    std::string text((std::istreambuf_iterator<char>(in)), {}), line, scene;
    std::istringstream lines(text);
    while (std::getline(lines, line)) {
      if (line.starts_with("frame_interval") || line.starts_with("end_time") ||
          line.starts_with("vtk"))
        continue;
      scene += line + "\n";
      if (line == "[run]")
        scene += "frame_interval = 1e-7\nend_time = 0.3e-6\nvtk = false\n" + extra;
    }
    std::ofstream(dir / "fe.toml") << scene;
    ASSERT_EQ(run(0, dir / "fe.toml", dir / "one").code, 0);
    const test::Result r = run(2, dir / "fe.toml", dir / "two");
    ASSERT_EQ(r.code, 0) << r.output;
    const std::string one_summary = test::readFile(dir / "one/summary.json"),
                      two_summary = test::readFile(dir / "two/summary.json");
    EXPECT_NE(two_summary.find("\"ranks\": 2"), std::string::npos);
    if (!extra.empty()) { // the same elements eroded, the same mass added
      const std::size_t at = one_summary.find(eroding ? "\"eroded_elements\"" : "\"added_mass\"");
      ASSERT_NE(at, std::string::npos);
      const std::string count = one_summary.substr(at, one_summary.find(',', at) - at);
      EXPECT_EQ(count.find(": 0"), std::string::npos) << count;
      EXPECT_NE(two_summary.find(count), std::string::npos) << count;
    }
    for (const char *series : {"projectile/vy", "projectile/vx", "projectile/lateral_force",
                               "projectile/rotational_momentum", "projectile/depth"}) {
      const double d = difference(dir / "one/run.h5", dir / "two/run.h5", series);
      std::printf("2 ranks sharing the elements%s: %s differs by %.2e of its largest value\n",
                  label, series, d);
      EXPECT_LE(d, 1e-14) << series;
    }
    for (const char *series : {"energy/internal", "energy/kinetic", "energy/balance_error"}) {
      const double d = difference(dir / "one/run.h5", dir / "two/run.h5", series);
      std::printf("2 ranks sharing the elements%s: %s differs by %.2e of its largest value\n",
                  label, series, d);
      EXPECT_LT(d, 1e-9) << series;
    }
    const H5File one = H5File::open(dir / "one/run.h5"), two = H5File::open(dir / "two/run.h5");
    for (const char *field : {"x", "vy", "pressure", "sxx", "plastic_strain"}) {
      const auto a = one.read<double>(std::string("/frames/000003/") + field);
      const auto b = two.read<double>(std::string("/frames/000003/") + field);
      ASSERT_EQ(a.size(), b.size()) << field;
      double diff = 0.0, scale = 0.0;
      for (std::size_t i = 0; i < a.size(); ++i)
        diff = std::max(diff, std::abs(a[i] - b[i])), scale = std::max(scale, std::abs(a[i]));
      std::printf("2 ranks sharing the elements%s: frame 3's %s differs by %.2e of its largest "
                  "value\n",
                  label, field, diff / scale);
      EXPECT_LE(diff, 1e-14 * scale) << field;
    }
  }
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
