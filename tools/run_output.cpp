#include "run_output.hpp"

#include "atomic_file.hpp"

#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDoubleArray.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace mesopen {

namespace {

const char *projectile_columns[] = {"com_x",         "com_y",       "vx",   "vy", "rotational_momentum",
                                    "lateral_force", "axial_force", "tilt", "depth"};
const char *energy_columns[] = {"kinetic", "internal", "plastic", "viscous", "external", "balance_error"};

std::string frameName(std::size_t i) {
  char name[32];
  std::snprintf(name, sizeof name, "%06zu", i);
  return name;
}

} // namespace

Series::Series(const fem::Model &model) {
  const fem::Body &p = model.bodies[0];
  const fem::BodyMotion m = fem::bodyMotion(model, 0);
  lowest0_ = HUGE_VAL;
  for (std::size_t a = p.node_begin; a < p.node_end; ++a) {
    x0_.push_back(model.nodes.x[a] - m.com_x);
    y0_.push_back(model.nodes.y[a] - m.com_y);
    lowest0_ = std::min(lowest0_, model.nodes.y[a]);
  }
  for (const char *c : projectile_columns)
    columns_.push_back({std::string("projectile/") + c, {}});
  for (const char *c : energy_columns)
    columns_.push_back({std::string("energy/") + c, {}});
}

std::vector<double> &Series::column(const std::string &name) {
  for (auto &c : columns_)
    if (c.first == name)
      return c.second;
  throw std::logic_error("no series " + name);
}

double Series::last(const std::string &name) const {
  for (const auto &c : columns_)
    if (c.first == name && !c.second.empty())
      return c.second.back();
  return NAN;
}

void Series::sample(const fem::Model &model, const fem::Solver &solver) {
  const fem::Body &p = model.bodies[0];
  const fem::Nodes &nd = model.nodes;
  const fem::BodyMotion m = fem::bodyMotion(model, 0);
  // Forces from outside the projectile (contact); zero while nothing touches it.
  double fx = 0.0, fy = 0.0, cross = 0.0, dot = 0.0, lowest = HUGE_VAL;
  for (std::size_t a = p.node_begin, i = 0; a < p.node_end; ++a, ++i) {
    fx += nd.fx_ext[a], fy += nd.fy_ext[a];
    // Least-squares rigid rotation from the initial shape: tan(theta) = sum m X' x x' / sum m X'.x'.
    const double x = nd.x[a] - m.com_x, y = nd.y[a] - m.com_y;
    cross += nd.mass[a] * (x0_[i] * y - y0_[i] * x);
    dot += nd.mass[a] * (x0_[i] * x + y0_[i] * y);
    lowest = std::min(lowest, nd.y[a]);
  }
  time_.push_back(solver.time());
  step_.push_back(static_cast<double>(solver.steps()));
  dt_.push_back(solver.dt());
  const fem::Energy &e = solver.energy();
  const double values[] = {m.com_x, m.com_y,  m.px / m.mass, m.py / m.mass, m.angular_momentum,
                           fx,      fy,       std::atan2(cross, dot), lowest0_ - lowest,
                           e.kinetic, e.internal, e.plastic, e.viscous, e.external, e.balance_error};
  for (std::size_t c = 0; c < columns_.size(); ++c)
    columns_[c].second.push_back(values[c]);
}

void Series::write(H5File &h5) const {
  h5.createGroup("/series");
  h5.createGroup("/series/projectile");
  h5.createGroup("/series/energy");
  h5.write("/series/time", time_);
  h5.write("/series/step", step_);
  h5.write("/series/dt", dt_);
  for (const auto &[name, values] : columns_)
    h5.write("/series/" + name, values);
  h5.attribute("/series/projectile/depth", "meaning",
               std::string("initial lowest point of the projectile minus its current lowest point [m]"));
  h5.attribute("/series/projectile/tilt", "meaning",
               std::string("rigid rotation from the initial shape, counter-clockwise [rad]"));
}

Frames::Frames(H5File &h5, const fem::Model &model, const std::string &vtk_dir)
    : h5_(h5), vtk_dir_(vtk_dir) {
  const fem::Elements &el = model.elements;
  std::vector<std::uint32_t> node_body(model.nodes.body.begin(), model.nodes.body.end());
  h5_.createGroup("/mesh");
  h5_.write("/mesh/triangles", el.node, el.size(), 3);
  h5_.write("/mesh/element_body", el.body);
  h5_.write("/mesh/node_body", node_body);
  h5_.createGroup("/frames");
}

void Frames::take(const fem::Model &model, double time) {
  const fem::Nodes &nd = model.nodes;
  const fem::Elements &el = model.elements;
  const std::size_t n = el.size();
  std::vector<double> sxx(n), syy(n), sxy(n), szz(n), effective(n);
  for (std::size_t e = 0; e < n; ++e) {
    const double zz = -el.sxx[e] - el.syy[e]; // deviator, plane strain
    sxx[e] = el.sxx[e] - el.pressure[e], syy[e] = el.syy[e] - el.pressure[e];
    sxy[e] = el.sxy[e], szz[e] = zz - el.pressure[e];
    effective[e] = std::sqrt(1.5 * (el.sxx[e] * el.sxx[e] + el.syy[e] * el.syy[e] + zz * zz +
                                    2.0 * el.sxy[e] * el.sxy[e]));
  }
  const std::string g = "/frames/" + frameName(times_.size());
  h5_.createGroup(g);
  h5_.attribute(g, "time", time);
  h5_.attribute(g, "stress", std::string("total stress sigma = S - p I [Pa]"));
  for (auto [name, v] : {std::pair{"x", &nd.x}, {"y", &nd.y}, {"vx", &nd.vx}, {"vy", &nd.vy}})
    h5_.write(g + "/" + name, *v);
  h5_.write(g + "/sxx", sxx);
  h5_.write(g + "/syy", syy);
  h5_.write(g + "/sxy", sxy);
  h5_.write(g + "/szz", szz);
  h5_.write(g + "/pressure", el.pressure);
  h5_.write(g + "/effective_stress", effective);
  h5_.write(g + "/plastic_strain", el.plastic_strain);

  if (!vtk_dir_.empty()) {
    vtkNew<vtkPoints> points;
    points->SetDataTypeToDouble();
    points->SetNumberOfPoints(static_cast<vtkIdType>(nd.size()));
    vtkNew<vtkDoubleArray> velocity;
    velocity->SetName("velocity");
    velocity->SetNumberOfComponents(3);
    velocity->SetNumberOfTuples(static_cast<vtkIdType>(nd.size()));
    for (std::size_t a = 0; a < nd.size(); ++a) {
      points->SetPoint(static_cast<vtkIdType>(a), nd.x[a], nd.y[a], 0.0);
      velocity->SetTuple3(static_cast<vtkIdType>(a), nd.vx[a], nd.vy[a], 0.0);
    }
    vtkNew<vtkUnstructuredGrid> grid;
    grid->SetPoints(points);
    grid->AllocateExact(static_cast<vtkIdType>(n), 3);
    for (std::size_t e = 0; e < n; ++e) {
      const vtkIdType ids[3] = {el.node[3 * e], el.node[3 * e + 1], el.node[3 * e + 2]};
      grid->InsertNextCell(VTK_TRIANGLE, 3, ids);
    }
    grid->GetPointData()->AddArray(velocity);
    auto cellArray = [&](const char *name, const std::vector<double> &v) {
      vtkNew<vtkDoubleArray> a;
      a->SetName(name);
      a->SetNumberOfTuples(static_cast<vtkIdType>(n));
      for (std::size_t e = 0; e < n; ++e)
        a->SetValue(static_cast<vtkIdType>(e), v[e]);
      grid->GetCellData()->AddArray(a);
    };
    cellArray("stress_xx", sxx), cellArray("stress_yy", syy), cellArray("stress_xy", sxy);
    cellArray("stress_zz", szz), cellArray("pressure", el.pressure);
    cellArray("effective_stress", effective), cellArray("plastic_strain", el.plastic_strain);
    vtkNew<vtkIntArray> body;
    body->SetName("body");
    body->SetNumberOfTuples(static_cast<vtkIdType>(n));
    for (std::size_t e = 0; e < n; ++e)
      body->SetValue(static_cast<vtkIdType>(e), static_cast<int>(el.body[e]));
    grid->GetCellData()->AddArray(body);
    const std::string path = vtk_dir_ + "/frame_" + frameName(times_.size()) + ".vtu";
    writeAtomically(path, [&](const std::string &temp) {
      vtkNew<vtkXMLUnstructuredGridWriter> writer;
      writer->SetFileName(temp.c_str());
      writer->SetInputData(grid);
      writer->SetDataModeToAppended();
      writer->EncodeAppendedDataOff();
      writer->SetCompressorTypeToNone();
      writer->SetHeaderTypeToUInt64();
      if (writer->Write() != 1)
        throw std::runtime_error("cannot write VTU file '" + temp + "'");
    });
  }
  times_.push_back(time);
}

void Frames::writeCollection() const {
  if (vtk_dir_.empty())
    return;
  std::string text = "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n";
  for (std::size_t i = 0; i < times_.size(); ++i) {
    char line[160];
    std::snprintf(line, sizeof line, "    <DataSet timestep=\"%.17g\" file=\"frame_%06zu.vtu\"/>\n", times_[i], i);
    text += line;
  }
  text += "  </Collection>\n</VTKFile>\n";
  writeText(vtk_dir_ + "/run.pvd", text);
}

} // namespace mesopen
