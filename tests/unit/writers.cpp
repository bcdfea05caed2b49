// The target writers: HDF5 layout and read-back, byte-identical repeats, the LIGGGHTS data file's
// contents, atomic writing (no temporary left, nothing written on failure).
#include "writers.hpp"
#include "disks.hpp"
#include "h5file.hpp"
#include "mesh.hpp"
#include "polygon.hpp"

#include <vtkCellData.h>
#include <vtkErrorCode.h>
#include <vtkNew.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <gtest/gtest.h>

#include <array>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

namespace fs = std::filesystem;
using namespace mesopen;

namespace {

std::string readFile(const fs::path &p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A fresh directory under the system temporary directory, removed at the end.
class WritersTest : public ::testing::Test {
protected:
  void SetUp() override {
    std::random_device rd;
    dir = fs::temp_directory_path() /
          ("mesopen-writers-" + std::to_string(rd()) + "-" + std::to_string(rd()));
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  std::string file(const std::string &name) const { return (dir / name).string(); }
  bool anyTemporary() const {
    for (const auto &entry : fs::directory_iterator(dir))
      if (entry.path().extension() == ".tmp")
        return true;
    return false;
  }
  fs::path dir;
};

// Two unit squares side by side (50 um) and a hexagon above them, all fan-meshed.
Target smallTarget(bool meshed) {
  Target t;
  t.spec.width = 200e-6;
  t.spec.height = 150e-6;
  t.spec.seed = 42;
  t.spec.density = 2648.5;
  const double s = 50e-6;
  t.grains.add({10e-6, 10e-6 + s, 10e-6 + s, 10e-6}, {10e-6, 10e-6, 10e-6 + s, 10e-6 + s});
  t.grains.add({70e-6, 70e-6 + s, 70e-6 + s, 70e-6}, {10e-6, 10e-6, 10e-6 + s, 10e-6 + s});
  std::vector<double> hx, hy;
  for (int k = 0; k < 6; ++k) {
    hx.push_back(100e-6 + 30e-6 * std::cos(k * M_PI / 3));
    hy.push_back(100e-6 + 30e-6 * std::sin(k * M_PI / 3));
  }
  t.grains.add(hx, hy);
  t.sites.x = {35e-6, 95e-6, 100e-6, 150e-6};
  t.sites.y = {35e-6, 35e-6, 100e-6, 30e-6};
  t.sites.r = {25e-6, 25e-6, 30e-6, 5e-6};
  t.sites.grains = 3;
  t.grain_site = {0, 1, 2};
  if (meshed)
    for (std::size_t g = 0; g < t.grains.size(); ++g)
      appendBody(t.mesh, fanMesh(t.grains.x.data() + t.grains.offset[g],
                                 t.grains.y.data() + t.grains.offset[g], t.grains.corners(g)));
  return t;
}

// A triangle standing in for the projectile (its shape figures set by hand).
PlacedProjectile smallProjectile() {
  PlacedProjectile p{};
  p.shape.diameter = 20e-6;
  p.shape.ogive_radius = 70e-6;
  p.shape.nose_length = 40e-6;
  p.shape.length = 77e-6;
  p.shape.tip_cut = 2e-6;
  p.outline_x = {90e-6, 110e-6, 100e-6};
  p.outline_y = {145e-6, 145e-6, 135e-6};
  p.mesh = fanMesh(p.outline_x.data(), p.outline_y.data(), 3);
  p.offset_x = 100e-6;
  p.offset_y = 135e-6;
  return p;
}

double polygonArea(const Polygons &p, std::size_t g) {
  return signedArea(p.x.data() + p.offset[g], p.y.data() + p.offset[g], p.corners(g));
}

} // namespace

TEST_F(WritersTest, H5ReadsBack) {
  const Target t = smallTarget(true);
  const PlacedProjectile p = smallProjectile();
  writeTargetH5(file("target.h5"), t, &p);

  const H5File h5 = H5File::open(file("target.h5"));
  EXPECT_EQ(h5.readStringAttribute("/", "format"), "mesopen-target");
  EXPECT_EQ(h5.readAttribute<int>("/", "version"), 1);
  EXPECT_EQ(h5.readAttribute<std::uint64_t>("/", "seed"), 42u);
  EXPECT_DOUBLE_EQ(h5.readAttribute<double>("/", "width"), 200e-6);
  for (const char *name : {"height", "porosity_requested", "diameter_min", "diameter_max",
                           "void_ratio", "mesh_size", "density"})
    EXPECT_TRUE(h5.hasAttribute("/", name)) << name;
  EXPECT_EQ(h5.readAttribute<std::uint64_t>("/sites", "grains"), 3u);
  EXPECT_EQ(h5.read<double>("/sites/r"), t.sites.r);

  EXPECT_EQ(h5.read<std::uint64_t>("/grains/offset"), t.grains.offset);
  EXPECT_EQ(h5.read<std::uint32_t>("/grains/site"), t.grain_site);
  const auto area = h5.read<double>("/grains/area");
  const auto diameter = h5.read<double>("/grains/diameter");
  ASSERT_EQ(area.size(), 3u);
  for (std::size_t g = 0; g < 3; ++g) {
    EXPECT_DOUBLE_EQ(area[g], polygonArea(t.grains, g));
    EXPECT_DOUBLE_EQ(diameter[g], equivalentDiameter(area[g]));
  }
  EXPECT_DOUBLE_EQ(area[0], 50e-6 * 50e-6);
  EXPECT_DOUBLE_EQ(h5.read<double>("/grains/centroid_x")[1], 95e-6);
  EXPECT_DOUBLE_EQ(h5.read<double>("/grains/centroid_y")[1], 35e-6);

  EXPECT_EQ(h5.shape("/mesh/tri"), (std::vector<std::uint64_t>{t.mesh.triangles(), 3}));
  EXPECT_EQ(h5.read<std::uint32_t>("/mesh/tri"), t.mesh.tri);
  EXPECT_EQ(h5.read<std::uint64_t>("/mesh/node_offset"), t.mesh.node_offset);
  EXPECT_EQ(h5.read<std::uint64_t>("/mesh/tri_offset"), t.mesh.tri_offset);

  EXPECT_EQ(h5.shape("/projectile/tri"), (std::vector<std::uint64_t>{3, 3}));
  EXPECT_EQ(h5.read<double>("/projectile/outline_y"), p.outline_y);
  EXPECT_DOUBLE_EQ(h5.readAttribute<double>("/projectile", "crh"), 3.5);
  for (const char *name : {"diameter", "length", "nose_length", "tip_cut", "offset_x", "offset_y"})
    EXPECT_TRUE(h5.hasAttribute("/projectile", name)) << name;
  EXPECT_FALSE(anyTemporary());
}

TEST_F(WritersTest, H5OmitsMeshAndProjectile) {
  writeTargetH5(file("target.h5"), smallTarget(false), nullptr);
  const H5File h5 = H5File::open(file("target.h5"));
  EXPECT_TRUE(h5.exists("/grains/area"));
  EXPECT_FALSE(h5.exists("/mesh"));
  EXPECT_FALSE(h5.exists("/projectile"));
  EXPECT_FALSE(h5.exists("/mesh/x"));
}

TEST_F(WritersTest, ByteIdenticalRepeats) {
  const Target t = smallTarget(true);
  const PlacedProjectile p = smallProjectile();
  writeTargetH5(file("a.h5"), t, &p);
  writeLiggghtsData(file("a.data"), t, targetDisks(t));
  writeTargetVtu(file("a.vtu"), t, &p);
  writeYadeSpheres(file("a.txt"), targetDisks(t));
  // HDF5 time stamps have one-second resolution: wait past a second so that any would differ.
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  writeTargetH5(file("b.h5"), t, &p);
  writeLiggghtsData(file("b.data"), t, targetDisks(t));
  writeTargetVtu(file("b.vtu"), t, &p);
  writeYadeSpheres(file("b.txt"), targetDisks(t));
  EXPECT_EQ(readFile(dir / "a.h5"), readFile(dir / "b.h5"));
  EXPECT_EQ(readFile(dir / "a.data"), readFile(dir / "b.data"));
  EXPECT_EQ(readFile(dir / "a.vtu"), readFile(dir / "b.vtu"));
  EXPECT_EQ(readFile(dir / "a.txt"), readFile(dir / "b.txt"));
  // Writing over an existing file gives the same bytes too.
  writeTargetH5(file("a.h5"), t, &p);
  EXPECT_EQ(readFile(dir / "a.h5"), readFile(dir / "b.h5"));
  EXPECT_FALSE(anyTemporary());
}

TEST_F(WritersTest, LiggghtsDataParses) {
  const Target t = smallTarget(false);
  writeLiggghtsData(file("target.data"), t, targetDisks(t));
  std::ifstream in(file("target.data"));
  std::string line;
  std::getline(in, line); // title
  std::size_t declared = 0, atoms = 0;
  bool in_atoms = false, have_z = false;
  std::vector<std::array<double, 3>> disks; // x, y, r
  while (std::getline(in, line)) {
    std::istringstream s(line);
    if (line.find(" atoms") != std::string::npos && !in_atoms) {
      s >> declared;
    } else if (line.find("zlo zhi") != std::string::npos) {
      double zlo, zhi;
      s >> zlo >> zhi;
      EXPECT_LT(zlo, 0.0);
      EXPECT_GT(zhi, 0.0);
      have_z = true;
    } else if (line == "Atoms") {
      in_atoms = true;
    } else if (in_atoms && !line.empty()) {
      long id, type;
      double d, rho, x, y, z;
      ASSERT_TRUE(s >> id >> type >> d >> rho >> x >> y >> z) << line;
      EXPECT_EQ(id, static_cast<long>(atoms + 1));
      EXPECT_EQ(type, 1);
      EXPECT_EQ(z, 0.0);
      // the grain's mass per metre, in a disk no larger than the grain's equal-area one
      const double area = polygonArea(t.grains, atoms);
      const double mass = rho * M_PI * d * d / 4;
      EXPECT_NEAR(mass, t.spec.density * area, 1e-12 * t.spec.density * area);
      EXPECT_GE(rho, t.spec.density * (1.0 - 1e-12));
      disks.push_back({x, y, 0.5 * d});
      const Point c = centroid(t.grains.x.data() + t.grains.offset[atoms],
                               t.grains.y.data() + t.grains.offset[atoms], t.grains.corners(atoms));
      EXPECT_EQ(x, c.x);
      EXPECT_EQ(y, c.y);
      ++atoms;
    }
  }
  EXPECT_TRUE(have_z);
  EXPECT_EQ(declared, t.grains.size());
  EXPECT_EQ(atoms, t.grains.size());
  // No two disks overlap: a DEM target made of them starts at rest.
  for (std::size_t i = 0; i < disks.size(); ++i) {
    double gap = INFINITY;
    for (std::size_t j = 0; j < disks.size(); ++j)
      if (j != i)
        gap = std::min(gap, std::hypot(disks[i][0] - disks[j][0], disks[i][1] - disks[j][1]) -
                                disks[i][2] - disks[j][2]);
    EXPECT_GE(gap, -1e-12 * disks[i][2]) << "disk " << i;
    EXPECT_GE(disks[i][0] - disks[i][2], 0.0) << "disk " << i; // inside the walls
    EXPECT_LE(disks[i][0] + disks[i][2], t.spec.width) << "disk " << i;
    EXPECT_GE(disks[i][1] - disks[i][2], 0.0) << "disk " << i;
  }
}

// The YADE list holds the LIGGGHTS file's disks: the grain's mass per metre in each, no two
// overlapping, none across the walls.
TEST_F(WritersTest, YadeSpheres) {
  const Target t = smallTarget(false);
  const Disks disks = targetDisks(t);
  writeYadeSpheres(file("spheres.txt"), disks);
  std::ifstream in(file("spheres.txt"));
  std::string line;
  std::size_t n = 0;
  while (std::getline(in, line)) {
    ASSERT_FALSE(line.empty());
    if (line[0] == '#')
      continue;
    std::istringstream s(line);
    double x, y, z, r, rho;
    ASSERT_TRUE(s >> x >> y >> z >> r >> rho) << line;
    ASSERT_LT(n, disks.size());
    EXPECT_EQ(z, 0.0);
    EXPECT_EQ(x, disks.x[n]);
    EXPECT_EQ(r, disks.radius[n]);
    const double mass = t.spec.density * polygonArea(t.grains, n);
    EXPECT_NEAR(rho * M_PI * r * r, mass, 1e-12 * mass);
    EXPECT_GE(x - r, 0.0);
    EXPECT_LE(x + r, t.spec.width);
    EXPECT_GE(y - r, 0.0);
    ++n;
  }
  EXPECT_EQ(n, t.grains.size());
}

TEST_F(WritersTest, VtuWritten) {
  const PlacedProjectile p = smallProjectile();
  for (bool meshed : {true, false}) {
    writeTargetVtu(file("target.vtu"), smallTarget(meshed), meshed ? &p : nullptr);
    const std::string text = readFile(dir / "target.vtu");
    EXPECT_NE(text.find("UnstructuredGrid"), std::string::npos);
    EXPECT_NE(text.find("Name=\"body\""), std::string::npos);
    EXPECT_NE(text.find("Name=\"grain_diameter\""), std::string::npos);
    // Fan meshes: 4 + 4 + 6 grain triangles and 3 projectile triangles; or 3 polygons.
    EXPECT_NE(text.find(meshed ? "NumberOfCells=\"17\"" : "NumberOfCells=\"3\""),
              std::string::npos);
  }
  EXPECT_FALSE(anyTemporary());
}

// target.vtu is zlib-compressed and read back whole by VTK's reader: its cells and each grain's
// diameter.
TEST_F(WritersTest, VtuCompressedAndReadBack) {
  const PlacedProjectile p = smallProjectile();
  writeTargetVtu(file("target.vtu"), smallTarget(true), &p);
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(file("target.vtu").c_str());
  reader->Update();
  ASSERT_EQ(reader->GetErrorCode(), vtkErrorCode::NoError);
  vtkUnstructuredGrid *grid = reader->GetOutput();
  EXPECT_EQ(grid->GetNumberOfCells(), 17);
  EXPECT_GT(grid->GetNumberOfPoints(), 0);
  ASSERT_NE(grid->GetCellData()->GetArray("grain_diameter"), nullptr);
  EXPECT_NE(readFile(dir / "target.vtu").find("compressor=\"vtkZLibDataCompressor\""),
            std::string::npos);
}

TEST_F(WritersTest, MissingDirectoryThrowsAndLeavesNothing) {
  const Target t = smallTarget(true);
  const PlacedProjectile p = smallProjectile();
  const fs::path missing = dir / "no" / "such";
  EXPECT_THROW(writeTargetH5((missing / "target.h5").string(), t, &p), std::runtime_error);
  EXPECT_THROW(writeLiggghtsData((missing / "target.data").string(), t, targetDisks(t)),
               std::runtime_error);
  EXPECT_THROW(writeTargetVtu((missing / "target.vtu").string(), t, &p), std::runtime_error);
  EXPECT_THROW(writeYadeSpheres((missing / "spheres.txt").string(), targetDisks(t)),
               std::runtime_error);
  EXPECT_FALSE(fs::exists(dir / "no"));
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST_F(WritersTest, FailedWriteKeepsOldFile) {
  // The destination is a directory: the rename fails, the temporary goes, the directory stays.
  const Target t = smallTarget(false);
  fs::create_directory(dir / "target.data");
  fs::create_directory(dir / "target.data" / "keep");
  EXPECT_ANY_THROW(writeLiggghtsData(file("target.data"), t, targetDisks(t)));
  EXPECT_TRUE(fs::exists(dir / "target.data" / "keep"));
  EXPECT_FALSE(anyTemporary());
}

TEST(H5File, ErrorsNameFileAndObject) {
  const fs::path path =
      fs::temp_directory_path() / ("mesopen-h5file-" + std::to_string(std::random_device{}()));
  {
    H5File h5 = H5File::create(path.string());
    h5.createGroup("/g");
    h5.write("/g/v", std::vector<int>{1, -2, 3});
    h5.write("/g/empty", std::vector<double>{});
    h5.attribute("/g/v", "unit", std::string(""));
    try {
      h5.write("/missing/v", std::vector<double>{1.0});
      ADD_FAILURE() << "no exception";
    } catch (const std::runtime_error &e) {
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("/missing/v"), std::string::npos) << e.what();
    }
    EXPECT_THROW(h5.createGroup("/g"), std::runtime_error);
    h5.close();
  }
  const H5File h5 = H5File::open(path.string());
  EXPECT_EQ(h5.read<int>("/g/v"), (std::vector<int>{1, -2, 3}));
  EXPECT_TRUE(h5.read<double>("/g/empty").empty());
  EXPECT_EQ(h5.readStringAttribute("/g/v", "unit"), "");
  EXPECT_THROW(h5.read<double>("/g/nothing"), std::runtime_error);
  fs::remove(path);
}

// Two squares 1 um apart (their equal-area disks would overlap by 11 um) and a third beside them:
// as disks they share the distance between centres; next to a meshed square a disk keeps out of
// it; every disk keeps its grain's mass.
TEST(GrainDisks, TouchWithoutOverlapAndKeepOutOfMeshedGrains) {
  Polygons grains;
  const double s = 50e-6, gap = 1e-6;
  for (int k = 0; k < 3; ++k) {
    const double x0 = 10e-6 + k * (s + gap);
    grains.add({x0, x0 + s, x0 + s, x0}, {10e-6, 10e-6, 10e-6 + s, 10e-6 + s});
  }
  const double rho = 2650.0, r_equal = s / std::sqrt(M_PI), pitch = s + gap;
  const Disks all = grainDisks(grains, rho);
  ASSERT_EQ(all.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i)
    EXPECT_NEAR(all.density[i] * M_PI * all.radius[i] * all.radius[i], rho * s * s,
                1e-12 * rho * s * s);
  EXPECT_NEAR(all.radius[0], 0.5 * pitch, 1e-15); // shares the distance with its equal neighbour
  EXPECT_LT(all.radius[0], r_equal);
  // the middle grain meshed: its neighbours' disks reach its faces, no farther
  DiskBounds middle_meshed;
  middle_meshed.meshed = {0, 1, 0};
  const Disks beside = grainDisks(grains, rho, middle_meshed);
  ASSERT_EQ(beside.size(), 2u);
  EXPECT_EQ(beside.grain[1], 2u);
  EXPECT_NEAR(beside.radius[0], 0.5 * s + gap, 1e-15);
  EXPECT_NEAR(beside.radius[1], 0.5 * s + gap, 1e-15);
}

// A square grain 2 um from the left wall and the bottom and a lone one under a plate (another FE
// body) 3 um above it: their equal-area disks (28.2 um for 50 um squares) would cross the walls and
// the plate; the disks touch them instead. Without walls they do not.
TEST(GrainDisks, KeepInsideTheWallsAndOutOfOtherBodies) {
  Polygons grains;
  const double s = 50e-6, r_equal = s / std::sqrt(M_PI);
  grains.add({2e-6, 2e-6 + s, 2e-6 + s, 2e-6}, {2e-6, 2e-6, 2e-6 + s, 2e-6 + s});
  grains.add({200e-6, 200e-6 + s, 200e-6 + s, 200e-6}, {100e-6, 100e-6, 100e-6 + s, 100e-6 + s});
  DiskBounds bounds;
  bounds.width = 400e-6;
  bounds.bodies.add({150e-6, 300e-6, 300e-6, 150e-6}, {153e-6, 153e-6, 170e-6, 170e-6});
  const Disks d = grainDisks(grains, 2650.0, bounds);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_NEAR(d.radius[0], 2e-6 + 0.5 * s, 1e-15); // touches both walls
  EXPECT_NEAR(d.radius[1], 3e-6 + 0.5 * s, 1e-15); // touches the plate
  const Disks free = grainDisks(grains, 2650.0);
  EXPECT_NEAR(free.radius[0], r_equal, 1e-15);
  EXPECT_NEAR(free.radius[1], r_equal, 1e-15);
  // a disk in the right wall's reach: x = 390 um, 10 um from the wall x = 400 um
  Polygons right;
  right.add({380e-6, 400e-6, 400e-6, 380e-6}, {100e-6, 100e-6, 120e-6, 120e-6});
  DiskBounds walls;
  walls.width = 400e-6;
  EXPECT_NEAR(grainDisks(right, 2650.0, walls).radius[0], 10e-6, 1e-15);
}

// Equal-area disks: a row of touching squares, staggered by 5 um (their equal-area disks overlap
// by 6 um), under a plate, between walls, with one square meshed: relaxed apart (into a zigzag:
// the row's five diameters are longer than its room), every disk keeps its
// grain's equal-area radius and mass, none overlaps another, a wall, the meshed square or the
// plate (to 1e-6 of a radius, the sweeps' end), and the result does not depend on the order of
// the grains.
TEST(GrainDisks, EqualAreaDisksRelaxedApart) {
  const double s = 50e-6, width = 400e-6, height = 150e-6, rho = 2650.0;
  auto squares = [&](bool reversed) {
    Polygons grains;
    for (int j = 0; j < 6; ++j) {
      const int k = reversed ? 5 - j : j;
      const double x0 = 20e-6 + k * s;
      const double y0 = 20e-6 + (k % 2) * 5e-6;
      grains.add({x0, x0 + s, x0 + s, x0}, {y0, y0, y0 + s, y0 + s});
    }
    return grains;
  };
  DiskBounds bounds;
  bounds.width = width, bounds.height = height, bounds.size = DiskSize::equal_area;
  bounds.meshed = {0, 0, 0, 0, 0, 1};
  bounds.bodies.add({0.0, width, width, 0.0}, {75e-6, 75e-6, 90e-6, 90e-6}); // a plate on top
  const Polygons grains = squares(false);
  const Disks d = grainDisks(grains, rho, bounds);
  ASSERT_EQ(d.size(), 5u);
  const double r_equal = s / std::sqrt(M_PI), tol = 1e-6 * r_equal;
  for (std::size_t i = 0; i < d.size(); ++i) {
    EXPECT_NEAR(d.radius[i], r_equal, tol) << i;
    EXPECT_NEAR(d.density[i] * M_PI * d.radius[i] * d.radius[i], rho * s * s, 1e-9 * rho * s * s);
    EXPECT_GE(d.x[i] - d.radius[i], -tol);
    EXPECT_LE(d.x[i] + d.radius[i], width + tol);
    EXPECT_GE(d.y[i] - d.radius[i], -tol);
    EXPECT_LE(d.y[i] + d.radius[i], 75e-6 + tol);         // under the plate
    EXPECT_LE(d.x[i] + d.radius[i], 20e-6 + 5 * s + tol); // left of the meshed square
    for (std::size_t j = 0; j < i; ++j)
      EXPECT_GE(std::hypot(d.x[i] - d.x[j], d.y[i] - d.y[j]), d.radius[i] + d.radius[j] - tol);
  }
  // the same grains in the other order give the same disks
  DiskBounds reversed = bounds;
  reversed.meshed = {1, 0, 0, 0, 0, 0};
  const Disks r = grainDisks(squares(true), rho, reversed);
  for (std::size_t i = 0; i < d.size(); ++i) {
    EXPECT_DOUBLE_EQ(r.x[4 - i], d.x[i]);
    EXPECT_DOUBLE_EQ(r.y[4 - i], d.y[i]);
  }
}
