#include "writers.hpp"

#include "disks.hpp"

#include "atomic_file.hpp"
#include "h5file.hpp"
#include "measures.hpp"
#include "polygon.hpp"

#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDoubleArray.h>
#include <vtkErrorCode.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace mesopen {

namespace {

constexpr int target_format_version = 1;

// Shortest text that reads back to the same double; independent of the locale.
void appendNumber(std::string &out, double value) {
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, value).ptr;
  out.append(buffer, end);
}

} // namespace

void writeTargetH5(const std::string &path, const Target &target,
                   const PlacedProjectile *projectile) {
  const Polygons &grains = target.grains;
  if (target.grain_site.size() != grains.size())
    throw std::invalid_argument("writeTargetH5: " + std::to_string(grains.size()) + " grains but " +
                                std::to_string(target.grain_site.size()) + " grain sites");
  const GrainFigures f = grainFigures(grains);
  writeAtomically(path, [&](const std::string &temp) {
    H5File h5 = H5File::create(temp);
    const TargetSpec &spec = target.spec;
    h5.attribute("/", "format", std::string("mesopen-target"));
    h5.attribute("/", "version", target_format_version);
    h5.attribute("/", "width", spec.width);
    h5.attribute("/", "height", spec.height);
    h5.attribute("/", "seed", std::uint64_t{spec.seed});
    h5.attribute("/", "porosity_requested", spec.porosity);
    h5.attribute("/", "diameter_min", spec.diameter_min);
    h5.attribute("/", "diameter_max", spec.diameter_max);
    h5.attribute("/", "void_ratio", spec.void_ratio);
    h5.attribute("/", "mesh_size", spec.mesh_size);
    h5.attribute("/", "density", spec.density);

    h5.createGroup("/sites");
    h5.write("/sites/x", target.sites.x);
    h5.write("/sites/y", target.sites.y);
    h5.write("/sites/r", target.sites.r);
    h5.attribute("/sites", "grains", std::uint64_t{target.sites.grains});

    h5.createGroup("/grains");
    h5.write("/grains/offset", grains.offset);
    h5.write("/grains/x", grains.x);
    h5.write("/grains/y", grains.y);
    h5.write("/grains/site", target.grain_site);
    h5.write("/grains/area", f.area);
    h5.write("/grains/diameter", f.diameter);
    h5.write("/grains/centroid_x", f.centroid_x);
    h5.write("/grains/centroid_y", f.centroid_y);

    const Meshes &mesh = target.mesh;
    if (mesh.bodies() > 0) {
      h5.createGroup("/mesh");
      h5.write("/mesh/node_offset", mesh.node_offset);
      h5.write("/mesh/tri_offset", mesh.tri_offset);
      h5.write("/mesh/x", mesh.x);
      h5.write("/mesh/y", mesh.y);
      h5.write("/mesh/tri", mesh.tri, mesh.triangles(), 3);
    }

    if (projectile) {
      const ProjectileShape &shape = projectile->shape;
      h5.createGroup("/projectile");
      h5.write("/projectile/outline_x", projectile->outline_x);
      h5.write("/projectile/outline_y", projectile->outline_y);
      h5.write("/projectile/x", projectile->mesh.x);
      h5.write("/projectile/y", projectile->mesh.y);
      h5.write("/projectile/tri", projectile->mesh.tri, projectile->mesh.tri.size() / 3, 3);
      h5.attribute("/projectile", "diameter", shape.diameter);
      h5.attribute("/projectile", "length", shape.length);
      h5.attribute("/projectile", "crh", shape.ogive_radius / shape.diameter);
      h5.attribute("/projectile", "nose_length", shape.nose_length);
      h5.attribute("/projectile", "tip_cut", shape.tip_cut);
      h5.attribute("/projectile", "offset_x", projectile->offset_x);
      h5.attribute("/projectile", "offset_y", projectile->offset_y);
    }
    h5.close();
  });
}

void writeLiggghtsData(const std::string &path, const Target &target, const Disks &disks) {
  const std::size_t n = disks.size();
  // LIGGGHTS in 2D still needs a z extent holding z = 0: a slab as thick as the largest disk.
  double d_max = 0.0;
  for (double r : disks.radius)
    d_max = std::max(d_max, 2.0 * r);
  if (!(d_max > 0.0))
    d_max = target.spec.diameter_max;

  std::string text =
      "LIGGGHTS data file by mesopen: atom_style granular, dimension 2, SI units; one disk per "
      "grain, of its mass, touching but not overlapping its neighbours or the walls\n\n";
  // type 2 is left for the walls' material (liggghts-inputs/dem.in)
  text += std::to_string(n) + " atoms\n2 atom types\n\n";
  text += "0 ";
  appendNumber(text, target.spec.width);
  text += " xlo xhi\n0 ";
  appendNumber(text, target.spec.height);
  text += " ylo yhi\n";
  appendNumber(text, -0.5 * d_max);
  text += ' ';
  appendNumber(text, 0.5 * d_max);
  text += " zlo zhi # slab of the largest diameter around z = 0 (2D)\n\nAtoms\n\n";
  for (std::size_t i = 0; i < n; ++i) {
    text += std::to_string(i + 1) + " 1 ";
    appendNumber(text, 2.0 * disks.radius[i]);
    text += ' ';
    appendNumber(text, disks.density[i]);
    text += ' ';
    appendNumber(text, disks.x[i]);
    text += ' ';
    appendNumber(text, disks.y[i]);
    text += " 0\n";
  }
  writeText(path, text);
}

void writeTargetVtu(const std::string &path, const Target &target,
                    const PlacedProjectile *projectile) {
  const Polygons &grains = target.grains;
  const Meshes &mesh = target.mesh;
  const GrainFigures f = grainFigures(grains);

  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  vtkNew<vtkUnstructuredGrid> grid;
  vtkNew<vtkIntArray> body;
  body->SetName("body");
  vtkNew<vtkDoubleArray> diameter;
  diameter->SetName("grain_diameter");
  const std::size_t cells = (mesh.triangles() > 0 ? mesh.triangles() : grains.size()) +
                            (projectile ? projectile->mesh.tri.size() / 3 : 0);
  grid->AllocateEstimate(static_cast<vtkIdType>(cells), 3);
  std::vector<vtkIdType> ids;
  auto addCell = [&](int type, int body_id, double d) {
    grid->InsertNextCell(type, static_cast<vtkIdType>(ids.size()), ids.data());
    body->InsertNextValue(body_id);
    diameter->InsertNextValue(d);
  };

  if (mesh.triangles() > 0) {
    for (std::size_t i = 0; i < mesh.nodes(); ++i)
      points->InsertNextPoint(mesh.x[i], mesh.y[i], 0.0);
    for (std::size_t b = 0; b < mesh.bodies(); ++b)
      for (std::uint64_t t = mesh.tri_offset[b]; t < mesh.tri_offset[b + 1]; ++t) {
        ids.assign(mesh.tri.begin() + 3 * t, mesh.tri.begin() + 3 * t + 3);
        addCell(VTK_TRIANGLE, static_cast<int>(b + 1), b < f.diameter.size() ? f.diameter[b] : 0.0);
      }
  } else {
    for (std::size_t i = 0; i < grains.x.size(); ++i)
      points->InsertNextPoint(grains.x[i], grains.y[i], 0.0);
    for (std::size_t g = 0; g < grains.size(); ++g) {
      ids.clear();
      for (std::uint64_t v = grains.offset[g]; v < grains.offset[g + 1]; ++v)
        ids.push_back(static_cast<vtkIdType>(v));
      addCell(VTK_POLYGON, static_cast<int>(g + 1), f.diameter[g]);
    }
  }

  if (projectile) {
    const TriangleMesh &m = projectile->mesh;
    const vtkIdType base = points->GetNumberOfPoints();
    for (std::size_t i = 0; i < m.x.size(); ++i)
      points->InsertNextPoint(m.x[i], m.y[i], 0.0);
    for (std::size_t t = 0; t + 2 < m.tri.size(); t += 3) {
      ids = {base + m.tri[t], base + m.tri[t + 1], base + m.tri[t + 2]};
      addCell(VTK_TRIANGLE, 0, 0.0);
    }
  }

  grid->SetPoints(points);
  grid->GetCellData()->AddArray(body);
  grid->GetCellData()->AddArray(diameter);

  writeVtu(path, grid);
}

void writeVtu(const std::string &path, vtkUnstructuredGrid *grid) {
  writeAtomically(path, [&](const std::string &temp) {
    // Open the file once here so that a bad path gives our error, not VTK's printed one.
    if (!std::ofstream(temp, std::ios::binary | std::ios::trunc))
      throw std::runtime_error("cannot create '" + temp + "': " + std::strerror(errno));
    vtkNew<vtkXMLUnstructuredGridWriter> writer;
    writer->SetFileName(temp.c_str());
    writer->SetInputData(grid);
    writer->SetDataModeToAppended();
    writer->EncodeAppendedDataOff();
    writer->SetCompressorTypeToZLib(); // raw appended data, zlib blocks: ParaView reads it
    writer->SetCompressionLevel(1);    // the fastest level: most of the gain
    writer->SetHeaderTypeToUInt64();
    // Write() returns 1 after a failed write too (a full disk): the error code tells, and our
    // message says it (VTK's own, a page of pipeline state, is not shown).
    const int shown = vtkObject::GetGlobalWarningDisplay();
    vtkObject::SetGlobalWarningDisplay(0);
    const int written = writer->Write();
    vtkObject::SetGlobalWarningDisplay(shown);
    if (written != 1 || writer->GetErrorCode() != vtkErrorCode::NoError)
      throw std::runtime_error("cannot write VTU file '" + temp + "': " +
                               vtkErrorCode::GetStringFromErrorCode(writer->GetErrorCode()));
  });
}

void writeYadeSpheres(const std::string &path, const Disks &disks) {
  std::string text =
      "# mesopen target as YADE spheres (yade.ymport.text reads x y z r; lines with # are "
      "skipped)\n"
      "# one per grain, z = 0: the LIGGGHTS disks (target.data), of which no two overlap and none\n"
      "# crosses the walls x = 0, x = width, y = 0\n"
      "# density: the grain's mass per metre over pi r^2 (a disk 1 m thick keeps the grain's "
      "mass)\n"
      "# x y z r [m] density [kg/m^3]\n";
  for (std::size_t i = 0; i < disks.size(); ++i) {
    appendNumber(text, disks.x[i]);
    text += ' ';
    appendNumber(text, disks.y[i]);
    text += " 0 ";
    appendNumber(text, disks.radius[i]);
    text += ' ';
    appendNumber(text, disks.density[i]);
    text += '\n';
  }
  writeText(path, text);
}

} // namespace mesopen
