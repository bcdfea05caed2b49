// `mesopen run`: a tiny scene end to end, its files, bad input, a failure, and free flight.
#include "run.hpp"
#include "h5file.hpp"

#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkErrorCode.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <csignal>
#include <filesystem>

using namespace mesopen;
using test::ScratchDir;

namespace {

using test::tinyScene;

using test::runScene;

const char *series_names[] = {"step",
                              "dt",
                              "projectile/com_x",
                              "projectile/com_y",
                              "projectile/vx",
                              "projectile/vy",
                              "projectile/rotational_momentum",
                              "projectile/lateral_force",
                              "projectile/axial_force",
                              "projectile/tilt",
                              "projectile/depth",
                              "energy/kinetic",
                              "energy/internal",
                              "energy/plastic",
                              "energy/viscous",
                              "energy/friction",
                              "energy/contact",
                              "energy/external",
                              "energy/balance_error"};

} // namespace

// With levels (run.max_level) a projectile of 2,048 elements or more steps in parts, and the
// summary says what the levels did: the level gap, the element updates against a single rate's,
// the active elements by level at the end, the bodies in parts and their parts.
TEST(Run, LevelsAndPartsInTheSummary) {
  ScratchDir dir("run-levels");
  std::string text = tinyScene("frame_interval = 0\nmax_level = 2\nlevel_gap = 1\n");
  text.replace(text.find("[projectile]\n"), 13, "[projectile]\nmesh_size = 3e-6\n");
  const test::Result r = test::runScene(dir, text);
  ASSERT_EQ(r.code, 0) << r.output;
  const auto summary = nlohmann::json::parse(test::readFile(dir / "out/summary.json"));
  const auto &mts = summary["multiple_time_stepping"];
  EXPECT_EQ(mts["max_level"], 2);
  EXPECT_EQ(mts["level_gap"], 1);
  EXPECT_EQ(mts["bodies_in_parts"], 1);
  const std::size_t parts = mts["parts"].get<std::size_t>();
  EXPECT_GE(parts, 4u); // at least 2,048 elements in parts of 512
  const double share = mts["element_update_share"].get<double>();
  EXPECT_GT(share, 0.0);
  EXPECT_LE(share, 1.0);
  // the active elements at the end by level: the projectile's at least, every one counted once
  const auto by_level = mts["active_elements_by_level_at_end"].get<std::vector<std::size_t>>();
  ASSERT_EQ(by_level.size(), 3u);
  const std::size_t active = by_level[0] + by_level[1] + by_level[2];
  EXPECT_GT(active, 512 * (parts - 1));
  EXPECT_LE(active, summary["model"]["elements"].get<std::size_t>());
}

TEST(Run, TinySceneWritesEveryOutput) {
  ScratchDir dir("run-tiny");
  const auto r = runScene(dir, tinyScene());
  ASSERT_EQ(r.code, 0) << r.output;
  H5File h5 = H5File::open(dir / "out/run.h5");
  EXPECT_EQ(h5.readStringAttribute("/", "status"), "completed");
  const auto time = h5.read<double>("/series/time");
  const std::size_t n = time.size();
  EXPECT_GT(n, 10u);
  EXPECT_GE(time.back(), 2e-8);
  for (const char *name : series_names)
    EXPECT_EQ(h5.shape(std::string("/series/") + name)[0], n) << name;
  const auto step = h5.read<std::uint64_t>("/series/step");
  EXPECT_EQ(step.front(), 0u);
  EXPECT_EQ(step.back(), n - 1); // series_interval 1: every step
  // Frames at 0, 10 and 20 ns, each with every field.
  for (const char *frame : {"000000", "000001", "000002"})
    for (const char *field : {"x", "y", "vx", "vy", "sxx", "syy", "sxy", "szz", "pressure",
                              "effective_stress", "plastic_strain"})
      EXPECT_TRUE(h5.exists("/frames/" + std::string(frame) + "/" + field)) << frame << field;
  EXPECT_FALSE(h5.exists("/frames/000003"));
  EXPECT_NEAR(h5.readAttribute<double>("/frames/000001", "time"), 1e-8, 1e-9);
  const std::size_t nodes = h5.shape("/mesh/x")[0], elements = h5.shape("/mesh/triangles")[0];
  EXPECT_EQ(h5.shape("/mesh/triangles")[1], 3u);
  EXPECT_EQ(h5.shape("/mesh/node_body")[0], nodes);
  EXPECT_EQ(h5.shape("/frames/000002/x")[0], nodes);
  EXPECT_EQ(h5.shape("/frames/000002/effective_stress")[0], elements);
  // The projectile enters at 1000 m/s and the grains push back: deeper than nothing, less deep
  // than free flight, and a force up on it.
  const auto depth = h5.read<double>("/series/projectile/depth");
  EXPECT_GT(depth.back(), 0.2 * 1000.0 * time.back());
  EXPECT_LT(depth.back(), 1000.0 * time.back());
  const auto axial = h5.read<double>("/series/projectile/axial_force");
  EXPECT_GT(*std::max_element(axial.begin(), axial.end()), 0.0);
  const std::string pvd = test::readFile(dir / "out/vtk/run.pvd");
  for (const char *vtu : {"frame_000000.vtu", "frame_000001.vtu", "frame_000002.vtu"}) {
    EXPECT_NE(pvd.find(vtu), std::string::npos) << vtu;
    EXPECT_TRUE(std::filesystem::exists(dir / ("out/vtk/" + std::string(vtu)))) << vtu;
  }
  const auto summary = nlohmann::json::parse(test::readFile(dir / "out/summary.json"));
  EXPECT_EQ(summary["command"], "run");
  EXPECT_EQ(summary["status"], "completed");
  EXPECT_EQ(summary["frames"], 3);
  EXPECT_EQ(summary["steps"], n - 1);
  EXPECT_EQ(summary["model"]["nodes"], nodes);
  EXPECT_GT(summary["model"]["bodies"].get<int>(), 10);
  EXPECT_GT(summary["model"]["fixed_nodes"].get<int>(), 0);
  EXPECT_FALSE(std::filesystem::exists(dir / "out/run.h5.tmp"));
}

TEST(Run, BadInputNamesTheKey) {
  ScratchDir dir("run-bad");
  const std::pair<const char *, const char *> cases[] = {
      {"[run]\nspeed = 3\n", "run.speed"},
      {"[run]\nsafety = 1.5\n", "run.safety"},
      {"[run]\nseries_interval = 0\n", "run.series_interval"},
      {"[materials.grains]\npreset = \"granite\"\n", "materials.grains.preset = 'granite'"},
      {"[materials.grains]\ntype = \"rubber\"\n", "von-mises"},
      {"[materials.grains]\nyield_stress = 1e9\n", "materials.grains.yield_stress"},
      {"[materials.projectile]\nyield_stress = -1.0\n", "0 <= yield_stress"},
      {"[materials.projectile]\nyield_stress = true\n", "materials.projectile.yield_stress"},
      {"[materials.projectile]\nplastic = 1\n", "materials.projectile.plastic"},
      {"[materials.projectile]\npreset = \"steel\"\ntype = \"elastic\"\n", "not both"},
      {"[materials.sand]\n", "materials.sand"},
      {"[run]\nrepresentation = \"disks\"\n", "run.representation"},
      {"[run]\nband_half_width = -1e-3\n", "run.band_half_width"},
      {"[dem]\nstiffness = 0\n", "dem.stiffness"},
      {"[dem]\ndamping = -1\n", "dem.damping"},
      {"[run]\nrepresentation = \"dem\"\ngrains = false\n", "run.representation"},
      {"[run]\noffset = 3.4e-3\n", "run.offset"},
      {"[run]\nyaw = 85\n", "run.yaw"},
      {"[run]\nobliquity = -90\n", "run.obliquity"},
  };
  for (const auto &[text, key] : cases) {
    const auto r = runScene(dir, text);
    EXPECT_EQ(r.code, 2) << text << r.output;
    EXPECT_NE(r.output.find(key), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("scene.toml"), std::string::npos) << r.output;
  }
}

// With disks, an output directory LIGGGHTS could not read from is bad input, named before any
// run starts.
TEST(Run, DiskRunNeedsAPlainOutputPath) {
  ScratchDir dir("run-dem-path");
  test::writeFile(dir / "scene.toml", tinyScene("representation = \"dem\"\n"));
  const auto r =
      test::runMesopen("run " + (dir / "scene.toml") + " -o '" + (dir / "out put") + "' --quiet");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("run.representation"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("out put"), std::string::npos) << r.output;
}

// A frame that cannot be written (its name taken by a directory) stops the run: exit 1, and
// run.h5 and summary.json hold what was computed until then.
TEST(Run, FailureKeepsWhatWasComputed) {
  ScratchDir dir("run-fail");
  std::filesystem::create_directories(dir / "out/vtk/frame_000001.vtu/in-the-way");
  const auto r = runScene(dir, tinyScene());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("mesopen run: failed at t = "), std::string::npos) << r.output;
  H5File h5 = H5File::open(dir / "out/run.h5");
  EXPECT_EQ(h5.readStringAttribute("/", "status"), "failed");
  const std::size_t n = h5.shape("/series/time")[0];
  EXPECT_GT(n, 1u);
  EXPECT_EQ(h5.shape("/series/projectile/depth")[0], n);
  EXPECT_TRUE(h5.exists("/frames/000000/x"));
  EXPECT_FALSE(h5.exists("/frames/000001"));
  const auto summary = nlohmann::json::parse(test::readFile(dir / "out/summary.json"));
  EXPECT_EQ(summary["status"], "failed");
  EXPECT_FALSE(summary["failure"].get<std::string>().empty());
  EXPECT_EQ(summary["frames"], 1);
  EXPECT_NE(test::readFile(dir / "out/vtk/run.pvd").find("frame_000000.vtu"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "out/run.h5.tmp"));
}

// SIGTERM in the time loop: the loop ends after its step, run.h5 and summary.json are written
// whole with status "interrupted", and the exit code is 128 + 15.
TEST(Run, SignalEndsTheLoopAndKeepsTheFiles) {
  ScratchDir dir("run-signal");
  std::string text = tinyScene("frame_interval = 0\n");
  text.replace(text.find("end_time = 2e-8"), 15, "end_time = 1e-3"); // far: minutes of steps
  test::writeFile(dir / "scene.toml", text);
  const std::string scene = dir / "scene.toml", out = dir / "out";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::execl(MESOPEN_BINARY, MESOPEN_BINARY, "run", scene.c_str(), "-o", out.c_str(), "--quiet",
            "--threads", "1", static_cast<char *>(nullptr));
    ::_exit(127);
  }
  // The loop runs once run.h5.tmp exists (it is opened just before); then a little longer (a
  // second: on a loaded machine 0.3 s was once not enough for a step).
  for (int i = 0; i < 600 && !std::filesystem::exists(dir / "out/run.h5.tmp"); ++i)
    ::usleep(50000);
  ::usleep(1000000);
  ::kill(pid, SIGTERM);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 128 + SIGTERM);
  EXPECT_FALSE(std::filesystem::exists(dir / "out/run.h5.tmp"));
  H5File h5 = H5File::open(dir / "out/run.h5");
  EXPECT_EQ(h5.readStringAttribute("/", "status"), "interrupted");
  EXPECT_GT(h5.shape("/series/time")[0], 1u);
  const auto summary = nlohmann::json::parse(test::readFile(dir / "out/summary.json"));
  EXPECT_EQ(summary["status"], "interrupted");
  EXPECT_NE(summary["failure"].get<std::string>().find("SIGTERM"), std::string::npos);
}

// The run ends exactly at run.end_time (it overshot by up to a step: 5,600 times an end_time of
// 1e-13 s); the steps near the end are made equal, none shorter than 0.95 of the stable step
// (0.9 here, for a stable step that changes on the way) unless the whole run is.
TEST(Run, EndsExactlyAtEndTime) {
  for (const double end : {1e-13, 2.345e-8}) {
    SCOPED_TRACE(end);
    ScratchDir dir("run-end-time");
    std::string text = tinyScene("frame_interval = 0\n");
    char value[32];
    std::snprintf(value, sizeof value, "%.17g", end);
    text.replace(text.find("end_time = 2e-8"), 15, std::string("end_time = ") + value);
    const auto r = runScene(dir, text);
    ASSERT_EQ(r.code, 0) << r.output;
    H5File h5 = H5File::open(dir / "out/run.h5");
    const auto time = h5.read<double>("/series/time");
    const auto stable = h5.read<double>("/series/dt");
    EXPECT_EQ(time.back(), end);
    for (std::size_t i = 1; i + 1 < time.size(); ++i) // every step but a whole run's one
      EXPECT_GE(time[i] - time[i - 1], 0.9 * stable[i - 1]) << i;
  }
}

// SIGTERM or SIGINT during the set-up (here the target's generation, about 4 s for this box; the
// signal at 0.3 s): `run` and `target` end at the next phase with exit 128 + the signal and a
// summary.json with status "interrupted" and no other file (they were killed by it, no summary).
TEST(Run, SignalDuringTheSetUpEndsInterrupted) {
  for (const char *command : {"run", "target"}) {
    SCOPED_TRACE(command);
    ScratchDir dir(std::string("run-signal-setup-") + command);
    test::writeFile(dir / "scene.toml", "[target]\nwidth = 20e-3\nheight = 5e-3\ndiameter = 60e-6\n"
                                        "mesh_size = 15e-6\n[projectile]\nlength = 0.3e-3\n"
                                        "[run]\nend_time = 1e-3\nframe_interval = 0\n");
    const std::string scene = dir / "scene.toml", out = dir / "out";
    const int signal = command == std::string("run") ? SIGTERM : SIGINT;
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      ::execl(MESOPEN_BINARY, MESOPEN_BINARY, command, scene.c_str(), "-o", out.c_str(),
              "--threads", "1", static_cast<char *>(nullptr));
      ::_exit(127);
    }
    ::usleep(300000);
    ::kill(pid, signal);
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFEXITED(status)) << "ended by signal " << WTERMSIG(status);
    EXPECT_EQ(WEXITSTATUS(status), 128 + signal);
    const auto summary = nlohmann::json::parse(test::readFile(dir / "out/summary.json"));
    EXPECT_EQ(summary["status"], "interrupted");
    EXPECT_NE(summary["failure"].get<std::string>().find("generat"), std::string::npos)
        << summary["failure"];
    for (const char *file : {"out/run.h5", "out/run.h5.tmp", "out/target.h5"})
      EXPECT_FALSE(std::filesystem::exists(dir / file)) << file;
  }
}

// The impact's attitude: the projectile alone with obliquity 20 degrees, yaw 10 and offset 50 um
// flies at run.velocity along (sin 20, -cos 20), keeps its momentum and its yaw (no tilt, to
// round-off: 1e-12 rad), and its mesh is the head-on run's turned by 30 degrees (node by node to
// 1e-12 of the length) and moved sideways by the offset; run.h5 says the attitude, the head-on
// run's file does not (its attributes are those of before).
TEST(Run, AttitudeTurnsAndAimsTheProjectile) {
  ScratchDir dir("run-attitude"), straight_dir("run-attitude-straight");
  const std::string free = "grains = false\nframe_interval = 0\n";
  ASSERT_EQ(runScene(straight_dir, tinyScene(free)).code, 0);
  const auto r = runScene(dir, tinyScene(free + "obliquity = 20.0\nyaw = 10.0\noffset = 50e-6\n"));
  ASSERT_EQ(r.code, 0) << r.output;
  H5File h5 = H5File::open(dir / "out/run.h5"), h0 = H5File::open(straight_dir / "out/run.h5");
  const double o = 20.0 * M_PI / 180.0, turn = 30.0 * M_PI / 180.0;
  const auto vx = h5.read<double>("/series/projectile/vx");
  const auto vy = h5.read<double>("/series/projectile/vy");
  const auto tilt = h5.read<double>("/series/projectile/tilt");
  ASSERT_GT(vx.size(), 10u);
  for (std::size_t i = 0; i < vx.size(); ++i) {
    EXPECT_NEAR(vx[i], 1000.0 * std::sin(o), 1e-10 * 1000.0);
    EXPECT_NEAR(vy[i], -1000.0 * std::cos(o), 1e-10 * 1000.0);
    EXPECT_NEAR(tilt[i], 0.0, 1e-12);
  }
  // The mesh: x = R(30 deg) x0 + d, the same nodes in the same order (d from the first node).
  const auto x = h5.read<double>("/mesh/x"), y = h5.read<double>("/mesh/y");
  const auto x0 = h0.read<double>("/mesh/x"), y0 = h0.read<double>("/mesh/y");
  ASSERT_EQ(x.size(), x0.size());
  const double c = std::cos(turn), s = std::sin(turn);
  auto turned = [&](std::size_t a) {
    return std::array<double, 2>{c * x0[a] - s * y0[a], s * x0[a] + c * y0[a]};
  };
  const auto t0 = turned(0);
  const double dx = x[0] - t0[0], dy = y[0] - t0[1];
  double worst = 0.0;
  for (std::size_t a = 0; a < x.size(); ++a) {
    const auto ta = turned(a);
    worst = std::max({worst, std::abs(ta[0] + dx - x[a]), std::abs(ta[1] + dy - y[a])});
  }
  EXPECT_LT(worst, 1e-12 * 0.3e-3);
  // The offset moves it sideways only: the same attitude without it, node by node.
  ScratchDir centred_dir("run-attitude-centred");
  ASSERT_EQ(runScene(centred_dir, tinyScene(free + "obliquity = 20.0\nyaw = 10.0\n")).code, 0);
  H5File hc = H5File::open(centred_dir / "out/run.h5");
  const auto xc = hc.read<double>("/mesh/x"), yc = hc.read<double>("/mesh/y");
  for (std::size_t a = 0; a < x.size(); a += 7) {
    EXPECT_NEAR(x[a] - xc[a], 50e-6, 1e-15);
    EXPECT_EQ(y[a], yc[a]);
  }
  EXPECT_EQ(h5.readAttribute<double>("/", "yaw"), 10.0);
  EXPECT_EQ(h5.readAttribute<double>("/", "obliquity"), 20.0);
  EXPECT_EQ(h5.readAttribute<double>("/", "offset"), 50e-6);
  EXPECT_FALSE(h0.hasAttribute("/", "yaw"));
}

// The projectile alone, spinning: the series must keep its momentum and H (round-off). No frames,
// and no files of an earlier run left beside the new ones.
TEST(Run, FreeFlightKeepsMomentum) {
  ScratchDir dir("run-free");
  std::filesystem::create_directories(dir / "out/vtk");
  for (const char *old : {"out/vtk/run.pvd", "out/vtk/frame_000007.vtu", "out/run.h5"})
    test::writeFile(dir / old, "from an earlier run");
  const auto r = runScene(dir, tinyScene("grains = false\nspin = 1e6\nframe_interval = 0\n"));
  ASSERT_EQ(r.code, 0) << r.output;
  H5File h5 = H5File::open(dir / "out/run.h5");
  const auto vx = h5.read<double>("/series/projectile/vx");
  const auto vy = h5.read<double>("/series/projectile/vy");
  const auto H = h5.read<double>("/series/projectile/rotational_momentum");
  const auto tilt = h5.read<double>("/series/projectile/tilt");
  ASSERT_GT(vy.size(), 10u);
  for (std::size_t i = 0; i < vy.size(); ++i) {
    EXPECT_NEAR(vx[i], 0.0, 1e-10 * 1000.0);
    EXPECT_NEAR(vy[i], -1000.0, 1e-10 * 1000.0);
    EXPECT_NEAR(H[i], H[0], 1e-10 * std::abs(H[0]));
  }
  EXPECT_GT(std::abs(H[0]), 0.0);
  // It turns at its spin rate: tilt = w t (measured: 1.3e-4 relative less, the elastic stretch).
  const double turned = 1e6 * h5.read<double>("/series/time").back();
  EXPECT_NEAR(tilt.back(), turned, 1e-3 * turned);
  EXPECT_EQ(h5.shape("/mesh/element_body").size(), 1u);
  EXPECT_FALSE(h5.exists("/frames"));
  EXPECT_FALSE(std::filesystem::exists(dir / "out/vtk/run.pvd"));
  EXPECT_FALSE(std::filesystem::exists(dir / "out/vtk/frame_000007.vtu"));
  const auto summary = nlohmann::json::parse(test::readFile(dir / "out/summary.json"));
  EXPECT_EQ(summary["model"]["bodies"], 1);
  EXPECT_EQ(summary["frames"], 0);
}

// A run's VTK frames: zlib-compressed, single precision, read back whole by VTK's reader with the
// values of run.h5's frame (to float precision: 6e-8 relative), and at least 3 times smaller than
// the same grid written as plain doubles (the quickstart's frames: 3.7 to 11 times, 5.2 over a
// run).
TEST(Run, VtkFramesCompressedAndReadBack) {
  ScratchDir dir("run-vtk");
  ASSERT_EQ(runScene(dir, tinyScene("frame_interval = 1e-8\n")).code, 0);
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  const std::string frame = dir / "out/vtk/frame_000001.vtu";
  reader->SetFileName(frame.c_str());
  reader->Update();
  ASSERT_EQ(reader->GetErrorCode(), vtkErrorCode::NoError);
  vtkUnstructuredGrid *grid = reader->GetOutput();
  H5File h5 = H5File::open(dir / "out/run.h5");
  const auto x = h5.read<double>("/frames/000001/x");
  const auto vy = h5.read<double>("/frames/000001/vy");
  const auto sxx = h5.read<double>("/frames/000001/sxx");
  ASSERT_EQ(grid->GetNumberOfPoints(), static_cast<vtkIdType>(x.size()));
  ASSERT_EQ(grid->GetNumberOfCells(), static_cast<vtkIdType>(sxx.size()));
  vtkDataArray *velocity = grid->GetPointData()->GetArray("velocity");
  vtkDataArray *stress = grid->GetCellData()->GetArray("sxx");
  ASSERT_NE(velocity, nullptr);
  ASSERT_NE(stress, nullptr);
  EXPECT_EQ(stress->GetDataType(), VTK_FLOAT);
  double largest = 0.0;
  for (double v : sxx)
    largest = std::max(largest, std::abs(v));
  for (std::size_t a = 0; a < x.size(); ++a) {
    EXPECT_NEAR(grid->GetPoint(static_cast<vtkIdType>(a))[0], x[a], 6e-8 * 1e-3);
    EXPECT_NEAR(velocity->GetComponent(static_cast<vtkIdType>(a), 1), vy[a], 6e-8 * 1000.0);
  }
  for (std::size_t e = 0; e < sxx.size(); ++e)
    EXPECT_NEAR(stress->GetComponent(static_cast<vtkIdType>(e), 0), sxx[e], 6e-8 * largest);
  // The same grid in doubles, written plain.
  vtkNew<vtkUnstructuredGrid> plain;
  plain->DeepCopy(grid);
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->DeepCopy(grid->GetPoints());
  plain->SetPoints(points);
  for (vtkDataSetAttributes *data : {static_cast<vtkDataSetAttributes *>(plain->GetPointData()),
                                     static_cast<vtkDataSetAttributes *>(plain->GetCellData())})
    for (int k = 0; k < data->GetNumberOfArrays(); ++k)
      if (data->GetArray(k)->GetDataType() == VTK_FLOAT) {
        vtkNew<vtkDoubleArray> d;
        d->DeepCopy(data->GetArray(k));
        d->SetName(data->GetArray(k)->GetName());
        data->AddArray(d); // replaces the array of that name
      }
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  const std::string plain_path = dir / "plain.vtu";
  writer->SetFileName(plain_path.c_str());
  writer->SetInputData(plain);
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  writer->SetCompressorTypeToNone();
  writer->SetHeaderTypeToUInt64();
  ASSERT_EQ(writer->Write(), 1);
  const double ratio = static_cast<double>(std::filesystem::file_size(plain_path)) /
                       static_cast<double>(std::filesystem::file_size(frame));
  std::printf("frame 1: %.2f times smaller than plain doubles\n", ratio);
  EXPECT_GT(ratio, 3.0);
}

// A run records what it ran: scene.toml (the scene composed) and mesopen.log in its directory;
// run.h5 and summary.json hold the program's version, the representation, the composed scene
// and the materials' resolved parameters. The record is whole: the run made again from
// DIR/scene.toml writes the same run.h5 byte for byte, and the same scene.toml.
TEST(Run, RecordsWhatItRanAndRunsAgainFromIt) {
  ScratchDir dir("run-provenance");
  const auto r = runScene(dir, tinyScene("frame_interval = 1e-8\nvtk = false\n"
                                         "[materials.grains]\nyield_cap = 4.5e9\n"));
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string scene = test::readFile(dir / "out/scene.toml");
  EXPECT_NE(scene.find("\n[run]\n"), std::string::npos) << scene;
  EXPECT_NE(scene.find("\nsafety = "), std::string::npos) << scene; // a default, written out
  EXPECT_NE(scene.find("\n[materials.grains]\npreset = \"quartz\"\n"), std::string::npos);
  EXPECT_NE(scene.find("\nyield_cap = 4.5e+09\n"), std::string::npos) << scene;
  const std::string log = test::readFile(dir / "out/mesopen.log");
  EXPECT_EQ(log.rfind("mesopen 0.", 0), 0u) << log;
  EXPECT_NE(log.find("command: "), std::string::npos) << log;
  EXPECT_NE(log.find(" run " + (dir / "scene.toml") + " -o "), std::string::npos) << log;
  EXPECT_NE(log.find("] completed: "), std::string::npos) << log;
  {
    const H5File h5 = H5File::open(dir / "out/run.h5");
    EXPECT_EQ(h5.readStringAttribute("/", "program").rfind("mesopen 0.", 0), 0u);
    EXPECT_EQ(h5.readStringAttribute("/", "representation"), "fe");
    EXPECT_EQ(h5.readStringAttribute("/", "scene"), scene);
    EXPECT_EQ(h5.readStringAttribute("/materials/grains", "preset"), "quartz");
    EXPECT_EQ(h5.readAttribute<double>("/materials/grains", "yield_cap"), 4.5e9);
    EXPECT_EQ(h5.readStringAttribute("/materials/projectile", "preset"), "steel");
    EXPECT_GT(h5.readAttribute<double>("/materials/projectile", "density"), 7000.0);
    EXPECT_EQ(h5.readStringAttribute("/frames/000001/sxx", "unit"), "Pa");
    EXPECT_EQ(h5.readStringAttribute("/frames/000001/vx", "unit"), "m/s");
  }
  const auto summary = nlohmann::json::parse(test::readFile(dir / "out/summary.json"));
  EXPECT_EQ(summary["composed_scene"], scene);
  EXPECT_EQ(summary["program"],
            H5File::open(dir / "out/run.h5").readStringAttribute("/", "program"));
  EXPECT_EQ(summary["materials"]["grains"]["parameters"]["yield_cap"], 4.5e9);
  EXPECT_EQ(summary["materials"]["projectile"]["preset"], "steel");
  // h5py reads the strings as str, not bytes
  const auto py = test::runCommand(
      "/usr/bin/python3 -c \"import h5py, sys; f = h5py.File(sys.argv[1]); "
      "assert isinstance(f.attrs['scene'], str) and isinstance(f.attrs['status'], str); "
      "assert f['/frames/000000/pressure'].attrs['unit'] == 'Pa'\" " +
      (dir / "out/run.h5"));
  EXPECT_EQ(py.code, 0) << py.output;
  const auto again =
      test::runMesopen("run " + (dir / "out/scene.toml") + " -o " + (dir / "again") + " --quiet");
  ASSERT_EQ(again.code, 0) << again.output;
  EXPECT_EQ(test::readFile(dir / "again/scene.toml"), scene);
  EXPECT_TRUE(test::readFile(dir / "again/run.h5") == test::readFile(dir / "out/run.h5"));
}
