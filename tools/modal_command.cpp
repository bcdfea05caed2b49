// mesopen modal INPUT -o DIR: free vibration modes of the projectile (thesis section 5.9, Table
// 5.2) or of a beam (appendix B): modes.json (frequencies in Hz and rad/s), modes.vtu (mode
// shapes for ParaView), summary.json. INPUT is a scene (its [modal] table, [projectile] and
// [materials.projectile]) or a mesh file: target.h5 (its /projectile mesh) or run.h5 (body 0 of
// its /mesh), with the thesis's steel (Table 3.2) in plane strain.
#include "command_log.hpp"
#include "commands.hpp"
#include "h5file.hpp"
#include "material.hpp"
#include "mesh.hpp"
#include "modal.hpp"
#include "output.hpp"
#include "projectile.hpp"
#include "scene.hpp"
#include "writers.hpp"

#include <omp.h>
#include <vtkCellType.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>

namespace mesopen {

namespace fs = std::filesystem;

namespace {

// What is analysed: the mesh, its material, and how to read the modes.
struct ModalProblem {
  std::string body; // "projectile", "beam", or "mesh" (from a file)
  fem::ModalMesh mesh;
  fem::ElasticSolid solid;
  double axis_angle = 0.0; // direction of the body's long axis [rad]
  double length = 0.0;     // along that axis [m]
  double height = 0.0;     // across it (a beam's height) [m]
  double mesh_size = 0.0;  // [m]; 0 when read from a file
  double velocity = 0.0;   // for the scaled depth per cycle [m/s]
  bool clamped = false;
  int modes = 10;    // elastic modes wanted
  std::string scene; // composed (scene.toml), when the input is a scene
};

// The elastic constants of [materials.projectile] (any type: density, bulk_modulus and the shear
// modulus, "shear_modulus" or quartz's zero-pressure "g0").
fem::ElasticSolid elasticSolid(const Scene &scene) {
  const MaterialChoice &choice = scene.projectile_material;
  const fem::MaterialPreset *preset = fem::findMaterialPreset(choice.name);
  const fem::MaterialType &type = *fem::findMaterialType(preset ? preset->type : choice.name);
  const fem::Parameters p = fem::completeParameters(type, preset, choice.parameters);
  fem::ElasticSolid s;
  s.density = p.at("density");
  s.bulk_modulus = p.at("bulk_modulus");
  s.shear_modulus = p.count("shear_modulus") ? p.at("shear_modulus") : p.at("g0");
  s.plane =
      scene.modal.plane == ModalPlane::stress ? fem::PlaneModel::stress : fem::PlaneModel::strain;
  return s;
}

// The rectangle [0, length] x [0, height] as a quality mesh (as the thesis's Cubit beam meshes:
// unstructured triangles of about `size`), smallest angle 20.7 degrees.
fem::ModalMesh beamMesh(double length, double height, double size) {
  const double cx[4] = {0.0, length, length, 0.0}, cy[4] = {0.0, 0.0, height, height};
  std::vector<double> ox, oy;
  for (int k = 0; k < 4; ++k) {
    const double dx = cx[(k + 1) % 4] - cx[k], dy = cy[(k + 1) % 4] - cy[k];
    const int pieces = edgePieces(std::hypot(dx, dy), size);
    for (int i = 0; i < pieces; ++i)
      ox.push_back(cx[k] + dx * i / pieces), oy.push_back(cy[k] + dy * i / pieces);
  }
  const TriangleMesh t = qualityMesh(ox.data(), oy.data(), ox.size(), size, 20.7);
  return {t.x, t.y, t.tri, {}};
}

ModalProblem sceneProblem(const std::string &path) {
  const Scene scene = readScene(path);
  const ModalSpec &m = scene.modal;
  ModalProblem p;
  p.scene = composedScene(scene);
  p.solid = elasticSolid(scene);
  p.velocity = scene.run.velocity;
  p.modes = static_cast<int>(m.modes);
  if (m.body == ModalBody::beam) {
    p.body = "beam";
    p.length = m.length, p.height = m.height;
    p.mesh_size = m.mesh_size > 0 ? m.mesh_size : m.height / 10;
    p.mesh = beamMesh(m.length, m.height, p.mesh_size);
    p.clamped = m.support == ModalSupport::clamped;
    if (p.clamped) {
      p.mesh.fixed.assign(p.mesh.nodes(), 0);
      for (std::size_t a = 0; a < p.mesh.nodes(); ++a)
        p.mesh.fixed[a] = p.mesh.x[a] <= 1e-9 * m.length;
    }
    return p;
  }
  if (!scene.projectile.enabled)
    throw InputError(path + ": projectile.enabled = false, and modal.body = \"projectile\"; "
                            "allowed: projectile.enabled = true, or modal.body = \"beam\"");
  p.body = "projectile";
  const ProjectileShape shape = projectileShape(scene.projectile);
  p.mesh_size = m.mesh_size > 0                  ? m.mesh_size
                : scene.projectile.mesh_size > 0 ? scene.projectile.mesh_size
                                                 : scene.target.mesh_size;
  std::vector<double> ox, oy;
  const TriangleMesh t = projectileMesh(shape, scene.projectile, p.mesh_size, ox, oy);
  p.mesh = {t.x, t.y, t.tri, {}};
  p.axis_angle = M_PI / 2;
  p.length = shape.length, p.height = shape.diameter;
  return p;
}

// The projectile's mesh from target.h5 (/projectile) or run.h5 (body 0 of /mesh), the steel of
// thesis Table 3.2 (preset "steel-elastic") in plane strain, the run's speed when run.h5 has it.
ModalProblem fileProblem(const std::string &path) {
  ModalProblem p;
  p.body = "mesh";
  p.axis_angle = M_PI / 2;
  Scene defaults;
  defaults.projectile_material = {"steel-elastic", {}};
  p.solid = elasticSolid(defaults);
  p.velocity = defaults.run.velocity;
  try {
    const H5File h5 = H5File::open(path);
    if (h5.exists("/projectile/tri")) {
      p.mesh.x = h5.read<double>("/projectile/x");
      p.mesh.y = h5.read<double>("/projectile/y");
      p.mesh.tri = h5.read<std::uint32_t>("/projectile/tri");
    } else if (h5.exists("/mesh/triangles") && h5.exists("/mesh/node_body")) {
      const auto x = h5.read<double>("/mesh/x"), y = h5.read<double>("/mesh/y");
      const auto tri = h5.read<std::uint32_t>("/mesh/triangles");
      const auto node_body = h5.read<std::uint32_t>("/mesh/node_body");
      const auto element_body = h5.read<std::uint32_t>("/mesh/element_body");
      // Body 0's nodes come first (run_output.hpp).
      std::size_t n = 0;
      while (n < node_body.size() && node_body[n] == 0)
        ++n;
      p.mesh.x.assign(x.begin(), x.begin() + n), p.mesh.y.assign(y.begin(), y.begin() + n);
      for (std::size_t e = 0; e < element_body.size(); ++e)
        if (element_body[e] == 0)
          p.mesh.tri.insert(p.mesh.tri.end(), &tri[3 * e], &tri[3 * e] + 3);
      if (h5.hasAttribute("/", "velocity"))
        p.velocity = h5.readAttribute<double>("/", "velocity");
    } else {
      throw InputError(path + ": holds neither /projectile/tri (target.h5) nor /mesh/triangles "
                              "and /mesh/node_body (run.h5); allowed: a scene (.toml), target.h5 "
                              "or run.h5");
    }
  } catch (const std::runtime_error &e) {
    if (dynamic_cast<const InputError *>(&e))
      throw;
    throw InputError(path + ": cannot read the mesh (" + e.what() + ")");
  }
  if (p.mesh.tri.empty())
    throw InputError(path + ": the projectile's mesh is empty");
  for (std::uint32_t a : p.mesh.tri)
    if (a >= p.mesh.nodes())
      throw InputError(path + ": a triangle uses node " + std::to_string(a) + " of " +
                       std::to_string(p.mesh.nodes()));
  const auto [lo, hi] = std::minmax_element(p.mesh.y.begin(), p.mesh.y.end());
  const auto [xlo, xhi] = std::minmax_element(p.mesh.x.begin(), p.mesh.x.end());
  p.length = *hi - *lo, p.height = *xhi - *xlo;
  return p;
}

// Euler-Bernoulli bending frequencies of a uniform beam, omega_n = (beta_n L)^2 sqrt(E I / (rho A
// L^4)), I / A = h^2 / 12, with E the plane's modulus: E for plane stress, E / (1 - nu^2) for
// plane strain (Timoshenko and Gere; thesis Eq. 5.2, appendix B). beta_n L: the roots of
// cos cosh = -1 (clamped-free) or cos cosh = 1 (free-free).
std::vector<double> eulerBernoulli(const ModalProblem &p) {
  static const double clamped[] = {1.875104069, 4.694091133, 7.854757438, 10.99554073};
  static const double free_free[] = {4.730040745, 7.853204624, 10.99560784, 14.13716549};
  const double nu = p.solid.poisson_ratio();
  const double e =
      p.solid.youngs_modulus() / (p.solid.plane == fem::PlaneModel::strain ? 1.0 - nu * nu : 1.0);
  const double scale =
      std::sqrt(e * p.height * p.height / 12.0 / (p.solid.density * std::pow(p.length, 4)));
  std::vector<double> omega;
  for (double bl : p.clamped ? clamped : free_free)
    omega.push_back(bl * bl * scale);
  return omega;
}

// Mode shapes as point vectors "mode_NN" (scaled to a largest displacement of 1).
void writeModesVtu(const std::string &path, const fem::ModalMesh &mesh, const fem::ModalResult &r) {
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(static_cast<vtkIdType>(mesh.nodes()));
  for (std::size_t a = 0; a < mesh.nodes(); ++a)
    points->SetPoint(static_cast<vtkIdType>(a), mesh.x[a], mesh.y[a], 0.0);
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(points);
  grid->AllocateExact(static_cast<vtkIdType>(mesh.triangles()), 3);
  for (std::size_t e = 0; e < mesh.triangles(); ++e) {
    const vtkIdType ids[3] = {mesh.tri[3 * e], mesh.tri[3 * e + 1], mesh.tri[3 * e + 2]};
    grid->InsertNextCell(VTK_TRIANGLE, 3, ids);
  }
  for (std::size_t k = 0; k < r.shapes.size(); ++k) {
    const std::vector<double> &u = r.shapes[k];
    double largest = 0.0;
    for (std::size_t a = 0; a < mesh.nodes(); ++a)
      largest = std::max(largest, std::hypot(u[2 * a], u[2 * a + 1]));
    char name[32];
    std::snprintf(name, sizeof name, "mode_%02zu", k + 1);
    vtkNew<vtkDoubleArray> shape;
    shape->SetName(name);
    shape->SetNumberOfComponents(3);
    shape->SetNumberOfTuples(static_cast<vtkIdType>(mesh.nodes()));
    for (std::size_t a = 0; a < mesh.nodes(); ++a)
      shape->SetTuple3(static_cast<vtkIdType>(a), u[2 * a] / largest, u[2 * a + 1] / largest, 0.0);
    grid->GetPointData()->AddArray(shape);
  }
  writeVtu(path, grid);
}

nlohmann::json modesJson(const ModalOptions &options, const ModalProblem &p,
                         const fem::ModalResult &r) {
  nlohmann::json j;
  j["input"] = fs::absolute(options.input).lexically_normal().string();
  j["body"] = p.body;
  j["support"] = p.clamped ? "clamped" : "free";
  j["plane"] = p.solid.plane == fem::PlaneModel::strain ? "strain" : "stress";
  j["material"] = {{"density", p.solid.density},
                   {"bulk_modulus", p.solid.bulk_modulus},
                   {"shear_modulus", p.solid.shear_modulus},
                   {"youngs_modulus", p.solid.youngs_modulus()},
                   {"poisson_ratio", p.solid.poisson_ratio()}};
  j["mesh"] = {
      {"nodes", p.mesh.nodes()}, {"triangles", p.mesh.triangles()}, {"mesh_size", p.mesh_size}};
  j["mass"] = r.mass;
  j["length"] = p.length;
  const bool penetrator = p.body != "beam"; // a beam does not penetrate: no depth per cycle
  if (penetrator)
    j["velocity"] = p.velocity;
  j["rigid_modes_removed"] = r.rigid_modes;
  j["rigid_mode_omega"] = r.rigid_omega;
  // Thesis Table 5.2's "depth of penetration per cycle" (projectiles only): the distance travelled
  // at `velocity` in one period, over the body's length, v T / L with T = 1 / f.
  j["modes"] = nlohmann::json::array();
  std::vector<double> hz, rad;
  for (std::size_t k = 0; k < r.omega.size(); ++k) {
    const double f = r.omega[k] / (2 * M_PI);
    const double axial = fem::directionShare(p.mesh, p.solid, r.shapes[k], p.axis_angle);
    nlohmann::json mode = {{"mode", k + 1},        {"omega", r.omega[k]},
                           {"frequency", f},       {"period", 1.0 / f},
                           {"axial_share", axial}, {"kind", axial > 0.5 ? "axial" : "bending"}};
    if (penetrator)
      mode["scaled_depth_per_cycle"] = p.velocity / f / p.length;
    j["modes"].push_back(mode);
    hz.push_back(f), rad.push_back(r.omega[k]);
  }
  j["frequency_hz"] = hz;
  j["omega_rad_per_s"] = rad;
  if (p.body == "beam") {
    // The bending modes (in order) against Euler-Bernoulli: ratio FE / theory.
    const std::vector<double> theory = eulerBernoulli(p);
    nlohmann::json eb = nlohmann::json::array();
    std::size_t n = 0;
    for (std::size_t k = 0; k < r.omega.size() && n < theory.size(); ++k)
      if (j["modes"][k]["kind"] == "bending") {
        eb.push_back({{"bending_mode", n + 1},
                      {"mode", k + 1},
                      {"omega", r.omega[k]},
                      {"euler_bernoulli_omega", theory[n]},
                      {"ratio", r.omega[k] / theory[n]}});
        ++n;
      }
    j["euler_bernoulli"] = eb;
  }
  j["solver"] = {{"unknowns", r.unknowns},
                 {"factor_nonzeros", r.factor_nonzeros},
                 {"shift", r.shift},
                 {"shift_invert_solves", r.operations},
                 {"assemble_seconds", r.assemble_seconds},
                 {"factor_seconds", r.factor_seconds},
                 {"solve_seconds", r.solve_seconds},
                 {"seconds", r.assemble_seconds + r.factor_seconds + r.solve_seconds}};
  return j;
}

} // namespace

int modalCommand(const ModalOptions &options) {
  const auto start = Clock::now();
  ModalProblem problem;
  try {
    const std::string ext = fs::path(options.input).extension().string();
    std::error_code ec;
    if (!fs::exists(options.input, ec))
      throw InputError(options.input + ": no such file; allowed: a scene (.toml), target.h5 or "
                                       "run.h5");
    if (!fs::is_regular_file(options.input, ec))
      throw InputError(options.input + ": not a file (a directory?); allowed: a scene (.toml), "
                                       "target.h5 or run.h5");
    problem = ext == ".h5" ? fileProblem(options.input) : sceneProblem(options.input);
    prepareOutputDirectory(
        options.out_dir, "modal",
        {"modes.json", "modes.vtu", "summary.json", "scene.toml", "mesopen.log"});
  } catch (const InputError &e) {
    std::cerr << "mesopen modal: " << e.what() << '\n';
    return 2;
  }
  CommandLog log;
  try {
    if (!problem.scene.empty())
      writeText(options.out_dir + "/scene.toml", problem.scene);
    log = CommandLog(options.out_dir, options.command_line);
    log.line("input " + options.input + (problem.scene.empty() ? "" : " (composed: scene.toml)"));
  } catch (const std::exception &e) {
    std::cerr << "mesopen modal: " << options.out_dir << ": cannot write: " << e.what() << '\n';
    return 1;
  }
  if (options.threads)
    omp_set_num_threads(*options.threads);
  try {
    fem::ModalSettings settings;
    settings.modes = options.modes ? *options.modes : problem.modes;
    const fem::ModalResult result = fem::freeVibration(problem.mesh, problem.solid, settings);
    const nlohmann::json modes = modesJson(options, problem, result);
    writeJson(options.out_dir + "/modes.json", modes);
    writeModesVtu(options.out_dir + "/modes.vtu", problem.mesh, result);
    const double wall = secondsSince(start);
    nlohmann::json summary = {{"command", "modal"},
                              {"input", modes["input"]},
                              {"body", problem.body},
                              {"nodes", problem.mesh.nodes()},
                              {"frequency_hz", modes["frequency_hz"]},
                              {"omega_rad_per_s", modes["omega_rad_per_s"]},
                              {"files", {"modes.json", "modes.vtu", "summary.json", "mesopen.log"}},
                              {"wall_seconds", wall}};
    if (!problem.scene.empty())
      summary["files"].push_back("scene.toml");
    writeJson(options.out_dir + "/summary.json", summary);
    log.lastLine("completed: " + std::to_string(result.omega.size()) + " modes, " +
                 std::to_string(problem.mesh.nodes()) + " nodes, " + std::to_string(wall) + " s");
    std::cout << "mesopen modal: " << problem.body << ", " << problem.mesh.nodes() << " nodes, "
              << result.omega.size() << " modes in " << wall << " s\n";
    for (std::size_t k = 0; k < result.omega.size(); ++k)
      std::printf("  mode %2zu: f = %.6g Hz, omega = %.6g rad/s (%s)\n", k + 1,
                  result.omega[k] / (2 * M_PI), result.omega[k],
                  modes["modes"][k]["kind"].get<std::string>().c_str());
    std::cout << "  files in " << options.out_dir << ": modes.json modes.vtu summary.json\n";
    return 0;
  } catch (const std::invalid_argument &e) {
    std::cerr << "mesopen modal: " << options.input << ": " << e.what() << '\n';
    log.lastLine(std::string("bad input: ") + e.what());
    return 2;
  } catch (const std::exception &e) {
    std::cerr << "mesopen modal: failed: " << e.what() << '\n';
    log.lastLine(std::string("failed: ") + e.what());
    return 1;
  }
}

} // namespace mesopen
