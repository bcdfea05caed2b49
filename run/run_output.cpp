#include "run_output.hpp"

#include "writers.hpp"

#include "atomic_file.hpp"
#include "output.hpp"

#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkFloatArray.h>
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
#include <tuple>

namespace mesopen {

namespace {

// The series' columns, in the order Series::sample fills them.
const Series::Column series_columns[] = {
    {"projectile/com_x", "m", "centre of mass, x", {}},
    {"projectile/com_y", "m", "centre of mass, y", {}},
    {"projectile/vx", "m/s", "velocity of the centre of mass, x", {}},
    {"projectile/vy", "m/s", "velocity of the centre of mass, y (negative: down)", {}},
    {"projectile/rotational_momentum",
     "kg m^2/s per m",
     "H = sum r_i x m_i v_i about the centre of mass (counter-clockwise positive)",
     {}},
    {"projectile/lateral_force",
     "N/m",
     "contact force on the projectile, x (sum of its external nodal forces)",
     {}},
    {"projectile/axial_force",
     "N/m",
     "contact force on the projectile, y (sum of its external nodal forces)",
     {}},
    {"projectile/tilt",
     "rad",
     "least-squares rigid rotation from the initial shape, counter-clockwise positive",
     {}},
    {"projectile/depth", "m", "initial lowest point minus the current lowest point", {}},
    {"energy/kinetic", "J/m", "kinetic energy of every body", {}},
    {"energy/internal", "J/m", "internal energy (includes the plastic and viscous work)", {}},
    {"energy/plastic", "J/m", "plastic work", {}},
    {"energy/viscous", "J/m", "work of the artificial viscosity", {}},
    {"energy/friction",
     "J/m",
     "energy the frictional contact forces took out (minus their work)",
     {}},
    {"energy/contact",
     "J/m",
     "energy the normal contact forces took out: held in the penalty springs or dissipated",
     {}},
    {"energy/external", "J/m", "work of the imposed velocities (fixed nodes) and gravity", {}},
    {"energy/eroded", "J/m", "internal energy the eroded elements took with them", {}},
    {"energy/mass_scaling",
     "J/m",
     "kinetic energy the mass added by mass scaling took (momentum kept)",
     {}},
    {"energy/balance_error",
     "",
     "(kinetic + internal + friction + contact + eroded + mass_scaling - initial - external) / "
     "max(|total|, initial, "
     "|external|)",
     {}},
};

std::string frameName(std::size_t i) {
  char name[32];
  std::snprintf(name, sizeof name, "%06zu", i);
  return name;
}

// Element stresses of a frame: the total stress sigma = S - p I (plane strain, S_zz = -S_xx -
// S_yy) and the von Mises stress sqrt(3/2 S:S).
struct FrameStress {
  std::vector<double> sxx, syy, sxy, szz, effective;
};

FrameStress frameStress(const fem::Elements &el) {
  const std::size_t n = el.size();
  FrameStress s{std::vector<double>(n), std::vector<double>(n), std::vector<double>(n),
                std::vector<double>(n), std::vector<double>(n)};
  for (std::size_t e = 0; e < n; ++e) {
    const double xx = el.sxx[e], yy = el.syy[e], xy = el.sxy[e], zz = -xx - yy, p = el.pressure[e];
    s.sxx[e] = xx - p, s.syy[e] = yy - p, s.sxy[e] = xy, s.szz[e] = zz - p;
    s.effective[e] = std::sqrt(1.5 * (xx * xx + yy * yy + zz * zz + 2.0 * xy * xy));
  }
  return s;
}

// The frames are for viewing: single precision (7 digits; run.h5 keeps every double), which with
// zlib makes them 3 to 8 times smaller than doubles written plain.
vtkNew<vtkFloatArray> vtkArray(const char *name, const std::vector<double> &values) {
  vtkNew<vtkFloatArray> a;
  a->SetName(name);
  a->SetNumberOfTuples(static_cast<vtkIdType>(values.size()));
  for (std::size_t i = 0; i < values.size(); ++i)
    a->SetValue(static_cast<vtkIdType>(i), values[i]);
  return a;
}

// One frame as a VTK unstructured grid (binary, appended), written whole or not at all.
// The grid's points (x, y, 0), with their velocities (vx, vy, 0) as the point array "velocity".
void setPoints(vtkUnstructuredGrid *grid, const std::vector<double> &x,
               const std::vector<double> &y, const std::vector<double> &vx,
               const std::vector<double> &vy) {
  vtkNew<vtkPoints> points;
  points->SetDataTypeToFloat();
  points->SetNumberOfPoints(static_cast<vtkIdType>(x.size()));
  vtkNew<vtkFloatArray> velocity;
  velocity->SetName("velocity");
  velocity->SetNumberOfComponents(3);
  velocity->SetNumberOfTuples(static_cast<vtkIdType>(x.size()));
  for (std::size_t a = 0; a < x.size(); ++a) {
    points->SetPoint(static_cast<vtkIdType>(a), x[a], y[a], 0.0);
    velocity->SetTuple3(static_cast<vtkIdType>(a), vx[a], vy[a], 0.0);
  }
  grid->SetPoints(points);
  grid->GetPointData()->AddArray(velocity);
}

void writeFrameVtu(const std::string &path, const fem::Model &model, const FrameStress &s) {
  const fem::Nodes &nd = model.nodes;
  const fem::Elements &el = model.elements;
  vtkNew<vtkUnstructuredGrid> grid;
  setPoints(grid, nd.x, nd.y, nd.vx, nd.vy);
  grid->AllocateExact(static_cast<vtkIdType>(el.size()), 3);
  vtkNew<vtkIntArray> body;
  body->SetName("body");
  body->SetNumberOfTuples(static_cast<vtkIdType>(el.size()));
  for (std::size_t e = 0; e < el.size(); ++e) {
    const vtkIdType ids[3] = {el.node[3 * e], el.node[3 * e + 1], el.node[3 * e + 2]};
    grid->InsertNextCell(el.eroded[e] ? VTK_EMPTY_CELL : VTK_TRIANGLE, el.eroded[e] ? 0 : 3, ids);
    body->SetValue(static_cast<vtkIdType>(e), static_cast<int>(el.body[e]));
  }
  vtkCellData *cells = grid->GetCellData();
  cells->AddArray(vtkArray("sxx", s.sxx));
  cells->AddArray(vtkArray("syy", s.syy));
  cells->AddArray(vtkArray("sxy", s.sxy));
  cells->AddArray(vtkArray("szz", s.szz));
  cells->AddArray(vtkArray("pressure", el.pressure));
  cells->AddArray(vtkArray("effective_stress", s.effective));
  cells->AddArray(vtkArray("plastic_strain", el.plastic_strain));
  cells->AddArray(body);
  writeVtu(path, grid);
}

// The disks as points (VTK_VERTEX cells) with their radius, velocity and spin.
void writeDisksVtu(const std::string &path, const coupling::Particles &d) {
  vtkNew<vtkUnstructuredGrid> grid;
  setPoints(grid, d.x, d.y, d.vx, d.vy);
  grid->AllocateExact(static_cast<vtkIdType>(d.size()), 1);
  for (std::size_t i = 0; i < d.size(); ++i) {
    const auto id = static_cast<vtkIdType>(i);
    grid->InsertNextCell(VTK_VERTEX, 1, &id);
  }
  grid->GetPointData()->AddArray(vtkArray("radius", d.radius));
  grid->GetPointData()->AddArray(vtkArray("omega", d.omega));
  writeVtu(path, grid);
}

} // namespace

Series::Series(const fem::Model &model)
    : columns_(std::begin(series_columns), std::end(series_columns)) {
  const fem::Body &p = model.bodies[0];
  const fem::BodyMotion m = fem::bodyMotion(model, 0);
  mass_ = m.mass;
  lowest0_ = HUGE_VAL;
  for (std::size_t a = p.node_begin; a < p.node_end; ++a) {
    x0_.push_back(model.nodes.x[a] - m.com_x);
    y0_.push_back(model.nodes.y[a] - m.com_y);
    lowest0_ = std::min(lowest0_, model.nodes.y[a]);
  }
}

double Series::last(const std::string &name) const {
  for (const auto &c : columns_)
    if (c.name == name && !c.values.empty())
      return c.values.back();
  return NAN;
}

double Series::depth(const fem::Model &model, const fem::Solver &solver) const {
  double lowest = HUGE_VAL;
  for (std::size_t a = model.bodies[0].node_begin; a < model.bodies[0].node_end; ++a)
    if (!model.nodes.detached[a]) // eroded material has left the projectile
      lowest = std::min(lowest, model.nodes.y[a]);
  // (with the work shared, the projectile's nodes are current at its owner only)
  if (const parallel::Communicator &processes = solver.processes(); processes.size() > 1)
    lowest = processes.allGather(std::vector<double>{lowest})
                 .at(static_cast<std::size_t>(solver.owner(0)));
  return lowest0_ - lowest;
}

void Series::sample(const fem::Model &model, const fem::Solver &solver) {
  const fem::Body &p = model.bodies[0];
  const fem::Nodes &nd = model.nodes;
  const fem::BodyMotion m = fem::bodyMotion(model, 0);
  // Forces from outside the projectile (contact); zero while nothing touches it. Its nodes that
  // eroded material left behind (detached) are no longer the projectile's.
  double fx = 0.0, fy = 0.0, cross = 0.0, dot = 0.0, lowest = HUGE_VAL;
  for (std::size_t a = p.node_begin, i = 0; a < p.node_end; ++a, ++i) {
    if (nd.detached[a])
      continue;
    fx += nd.external[a].fx, fy += nd.external[a].fy;
    // Least-squares rigid rotation from the initial shape: tilt = atan2(sum m X' x x', sum m X'.x')
    // with X' and x' the initial and current positions relative to the centre of mass.
    const double x = nd.x[a] - m.com_x, y = nd.y[a] - m.com_y;
    cross += nd.mass[a] * (x0_[i] * y - y0_[i] * x);
    dot += nd.mass[a] * (x0_[i] * x + y0_[i] * y);
    lowest = std::min(lowest, nd.y[a]);
  }
  std::vector<double> motion{
      m.com_x, m.com_y, m.px / m.mass,          m.py / m.mass,    m.angular_momentum,
      fx,      fy,      std::atan2(cross, dot), lowest0_ - lowest};
  // (with the work shared, the projectile's velocities and external forces are current at its
  // owner only: every rank takes its figures)
  if (const parallel::Communicator &processes = solver.processes(); processes.size() > 1) {
    const std::vector<double> all = processes.allGather(motion);
    const auto owner = motion.size() * static_cast<std::size_t>(solver.owner(0));
    std::copy(all.begin() + owner, all.begin() + owner + motion.size(), motion.begin());
  }
  time_.push_back(solver.time());
  step_.push_back(solver.steps());
  dt_.push_back(solver.dt());
  const fem::Energy &e = solver.sumEnergy();
  const double values[] = {motion[0],  motion[1], motion[2],      motion[3],      motion[4],
                           motion[5],  motion[6], motion[7],      motion[8],      e.kinetic,
                           e.internal, e.plastic, e.viscous,      e.friction,     e.contact,
                           e.external, e.eroded,  e.mass_scaling, e.balance_error};
  static_assert(std::size(values) == std::size(series_columns));
  for (std::size_t c = 0; c < columns_.size(); ++c)
    columns_[c].values.push_back(values[c]);
}

void Series::write(H5File &h5) const {
  for (const char *group : {"/series", "/series/projectile", "/series/energy"})
    h5.createGroup(group);
  h5.write("/series/time", time_);
  h5.write("/series/step", step_);
  h5.write("/series/dt", dt_);
  h5.attribute("/series/time", "unit", std::string("s"));
  h5.attribute("/series/dt", "meaning", std::string("the step the solver takes next [s]"));
  h5.attribute("/series/projectile", "mass", mass_);
  h5.attribute("/series/projectile", "mass_unit", std::string("kg/m"));
  for (const auto &c : columns_) {
    const std::string name = "/series/" + c.name;
    h5.write(name, c.values);
    h5.attribute(name, "unit", c.unit);
    h5.attribute(name, "meaning", c.meaning);
  }
}

Frames::Frames(H5File *h5, const fem::Model &model, double interval, std::string vtk_dir)
    : h5_(h5), interval_(interval), vtk_dir_(interval > 0 ? std::move(vtk_dir) : std::string()) {
  if (!h5_)
    return;
  const fem::Elements &el = model.elements;
  const std::vector<std::uint32_t> node_body(model.nodes.body.begin(), model.nodes.body.end());
  h5->createGroup("/mesh");
  h5->write("/mesh/x", model.nodes.x0);
  h5->write("/mesh/y", model.nodes.y0);
  h5->write("/mesh/triangles", el.node, el.size(), 3);
  h5->write("/mesh/element_body", el.body);
  h5->write("/mesh/node_body", node_body);
  h5->attribute(
      "/mesh", "body_names",
      std::string("body 0: projectile; body b >= 1: grain-(b-1), the target's grain b - 1"));
  if (interval_ > 0)
    h5->createGroup("/frames");
}

void Frames::offer(const fem::Model &model, const fem::Solver &solver, bool force) {
  if (interval_ <= 0 || (!force && solver.time() < next_))
    return;
  const auto start = Clock::now();
  take(model, solver);
  seconds_ += secondsSince(start);
  // The next multiple of the interval after now: one frame per interval even when a step is longer.
  next_ = interval_ * (std::floor(solver.time() / interval_) + 1.0);
}

void Frames::take(const fem::Model &model, const fem::Solver &solver) {
  coupling::Particles disks;
  if (coupled_) // every rank takes part; rank 0 holds them all
    coupled_->dem().gatherParticles(coupled_->disks(), disks);
  solver.collectFrame(); // every rank takes part
  if (!h5_) {
    times_.push_back(solver.time());
    return;
  }
  H5File &h5 = *h5_;
  const fem::Nodes &nd = model.nodes;
  const fem::Elements &el = model.elements;
  const FrameStress s = frameStress(el);
  if (!vtk_dir_.empty())
    writeFrameVtu(vtk_dir_ + "/frame_" + frameName(times_.size()) + ".vtu", model, s);
  const std::string g = "/frames/" + frameName(times_.size());
  h5.createGroup(g);
  h5.attribute(g, "time", solver.time());
  h5.attribute(g, "step", static_cast<std::uint64_t>(solver.steps()));
  h5.attribute(g, "stress",
               std::string("total stress sigma = S - p I [Pa]; effective_stress: "
                           "von Mises sqrt(3/2 S:S) [Pa]; pressure compression positive"));
  // each dataset with its unit
  auto put = [&](const std::string &name, const auto &values, const char *unit) {
    h5.write(name, values);
    h5.attribute(name, "unit", std::string(unit));
  };
  for (auto [name, v] : {std::pair{"x", &nd.x}, {"y", &nd.y}})
    put(g + "/" + name, *v, "m");
  for (auto [name, v] : {std::pair{"vx", &nd.vx}, {"vy", &nd.vy}})
    put(g + "/" + name, *v, "m/s");
  for (auto [name, v] : {std::pair{"sxx", &s.sxx},
                         {"syy", &s.syy},
                         {"sxy", &s.sxy},
                         {"szz", &s.szz},
                         {"pressure", &el.pressure},
                         {"effective_stress", &s.effective}})
    put(g + "/" + name, *v, "Pa");
  put(g + "/plastic_strain", el.plastic_strain, "1");
  put(g + "/eroded", el.eroded, "1 (eroded), 0");
  if (coupled_) {
    h5.createGroup(g + "/disks");
    for (auto [name, v, unit] : {std::tuple{"x", &disks.x, "m"},
                                 {"y", &disks.y, "m"},
                                 {"radius", &disks.radius, "m"},
                                 {"vx", &disks.vx, "m/s"},
                                 {"vy", &disks.vy, "m/s"},
                                 {"omega", &disks.omega, "rad/s"}})
      put(g + "/disks/" + name, *v, unit);
    if (!vtk_dir_.empty())
      writeDisksVtu(vtk_dir_ + "/disks_" + frameName(times_.size()) + ".vtu", disks);
  }
  times_.push_back(solver.time());
}

void Frames::writeCollection() const {
  if (!vtk())
    return;
  std::string text = "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n"
                     "  <Collection>\n";
  for (std::size_t i = 0; i < times_.size(); ++i) {
    char line[160];
    std::snprintf(line, sizeof line,
                  "    <DataSet timestep=\"%.17g\" part=\"0\" file=\"frame_%06zu.vtu\"/>\n",
                  times_[i], i);
    text += line;
    if (coupled_) {
      std::snprintf(line, sizeof line,
                    "    <DataSet timestep=\"%.17g\" part=\"1\" file=\"disks_%06zu.vtu\"/>\n",
                    times_[i], i);
      text += line;
    }
  }
  text += "  </Collection>\n</VTKFile>\n";
  writeText(vtk_dir_ + "/run.pvd", text);
}

} // namespace mesopen
