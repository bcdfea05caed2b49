#include "run_assembly.hpp"

#include "generator.hpp"
#include "measures.hpp"
#include "mesh.hpp"
#include "run_settings.hpp"
#include "stop_signals.hpp"
#include "writers.hpp"
#include "zoltan_partitioner.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace mesopen {

namespace {

// The meshes of the grains marked in `meshed`, in grain order: the target's own when it was
// generated meshed (fe), else those grains meshed now (the generator made polygons only; a hybrid
// band may cover every grain).
Meshes grainMeshes(const Scene &scene, const Target &target, const std::vector<char> &meshed) {
  if (target.mesh.bodies() == meshed.size())
    return target.mesh;
  Polygons chosen;
  for (std::size_t g = 0; g < meshed.size(); ++g)
    if (meshed[g]) {
      const auto first = target.grains.x.begin() + static_cast<long>(target.grains.offset[g]);
      const auto last = target.grains.x.begin() + static_cast<long>(target.grains.offset[g + 1]);
      const auto first_y = target.grains.y.begin() + static_cast<long>(target.grains.offset[g]);
      chosen.add(std::vector<double>(first, last),
                 std::vector<double>(first_y, first_y + (last - first)));
    }
  return meshGrains(chosen, scene.target.mesh, scene.target.mesh_size, scene.target.min_angle);
}

// The projectile's and the grains' meshes as one: the projectile is body 0, the grains follow in
// order (their node indices shifted past those before).
Meshes runMeshes(const Meshes *grains, const PlacedProjectile &p) {
  Meshes all;
  all.x = p.mesh.x, all.y = p.mesh.y, all.tri = p.mesh.tri;
  all.node_offset.push_back(all.x.size());
  all.tri_offset.push_back(all.tri.size() / 3);
  if (!grains)
    return all;
  const Meshes &g = *grains;
  for (std::size_t b = 0; b < g.bodies(); ++b) {
    const auto shift = static_cast<std::uint32_t>(all.x.size() - g.node_offset[b]);
    all.x.insert(all.x.end(), g.x.begin() + g.node_offset[b], g.x.begin() + g.node_offset[b + 1]);
    all.y.insert(all.y.end(), g.y.begin() + g.node_offset[b], g.y.begin() + g.node_offset[b + 1]);
    for (std::size_t k = 3 * g.tri_offset[b]; k < 3 * g.tri_offset[b + 1]; ++k)
      all.tri.push_back(g.tri[k] + shift);
    all.node_offset.push_back(all.x.size());
    all.tri_offset.push_back(all.tri.size() / 3);
  }
  return all;
}

// The grain nodes on the box's left, right and bottom edges (within 1e-3 mesh sizes), held at rest;
// with smooth walls held normal to their edge only (the corners at rest).
std::vector<fem::VelocityConstraint> boxEdges(const fem::Model &model, const TargetSpec &box,
                                              bool smooth) {
  const double tol = 1e-3 * box.mesh_size;
  fem::VelocityConstraint fixed{"box edges", {}, true, true, 0.0, 0.0};
  fem::VelocityConstraint sides{"box sides", {}, true, false, 0.0, 0.0};
  fem::VelocityConstraint bottom{"box bottom", {}, false, true, 0.0, 0.0};
  for (std::size_t a = model.bodies[0].node_end; a < model.nodes.size(); ++a) {
    const double x = model.nodes.x[a], y = model.nodes.y[a];
    const bool side = x <= tol || x >= box.width - tol, low = y <= tol;
    const auto node = static_cast<std::uint32_t>(a);
    if (!smooth && (side || low))
      fixed.nodes.push_back(node);
    if (smooth && side)
      sides.nodes.push_back(node);
    if (smooth && low)
      bottom.nodes.push_back(node);
  }
  if (!smooth)
    return {fixed};
  return {sides, bottom};
}

} // namespace

PlacedProjectile runProjectile(const Scene &scene, const Target *target) {
  const Polygons no_grains;
  const double degree = M_PI / 180.0;
  return placeProjectile(scene.projectile, scene.target.mesh_size, scene.target,
                         target ? target->grains : no_grains,
                         {(scene.run.yaw + scene.run.obliquity) * degree, scene.run.offset});
}

std::array<double, 2> runVelocity(const RunSpec &run) {
  const double obliquity = run.obliquity * (M_PI / 180.0);
  return {run.velocity * std::sin(obliquity), -run.velocity * std::cos(obliquity)};
}

std::vector<char> meshedGrains(const Scene &scene, const Target &target,
                               const PlacedProjectile &p) {
  const std::size_t n = target.grains.size();
  switch (scene.run.representation) {
  case Representation::fe:
    return std::vector<char>(n, 1);
  case Representation::dem:
    return std::vector<char>(n, 0);
  case Representation::hybrid:
    break;
  }
  // The band: within band_half_width of the projectile's axis, from the surface down to band_depth
  // below its tip (by default the depth the run ends at, plus the half-width: deeper grains carry
  // the waves as disks do, and the projectile does not reach them). By default the half-width is
  // one and a half projectile diameters: the narrowest band of those measured whose run 6 stays
  // within the fully meshed runs' seed-to-seed range on every measure (docs/coupling.md).
  const double half =
      scene.run.band_half_width > 0.0 ? scene.run.band_half_width : 1.5 * p.shape.diameter;
  const double depth = scene.run.band_depth > 0.0 ? scene.run.band_depth
                       : scene.run.end_depth > 0.0
                           ? scene.run.end_depth * scene.projectile.length + half
                           : HUGE_VAL;
  const double bottom = *std::min_element(p.mesh.y.begin(), p.mesh.y.end()) - depth;
  const GrainFigures f = grainFigures(target.grains);
  // The distance from the path: the line through the tip along the velocity (sin, -cos of the
  // obliquity).
  const double obliquity = scene.run.obliquity * (M_PI / 180.0);
  const double c = std::cos(obliquity), s = std::sin(obliquity);
  std::vector<char> meshed(n);
  for (std::size_t g = 0; g < n; ++g) {
    const double off_path = (f.centroid_x[g] - p.offset_x) * c + (f.centroid_y[g] - p.offset_y) * s;
    meshed[g] = std::abs(off_path) <= half && f.centroid_y[g] >= bottom;
  }
  return meshed;
}

fem::Model buildRunModel(const Scene &scene, const Target *target, const PlacedProjectile &p,
                         const std::vector<char> &meshed) {
  const Meshes grains = target ? grainMeshes(scene, *target, meshed) : Meshes{};
  const Meshes all = runMeshes(target ? &grains : nullptr, p);
  std::vector<std::string> names{"projectile"};
  for (std::size_t g = 0; g < meshed.size(); ++g)
    if (meshed[g])
      names.push_back("grain-" + std::to_string(g));
  std::vector<std::unique_ptr<fem::Material>> materials;
  materials.push_back(
      fem::makeMaterial(scene.projectile_material.name, scene.projectile_material.parameters));
  materials.push_back(
      fem::makeMaterial(scene.grain_material.name, scene.grain_material.parameters));
  std::vector<int> body_material(all.bodies(), 1);
  body_material[0] = 0;
  fem::Model model = fem::buildModel({all.node_offset, all.tri_offset, all.x, all.y, all.tri},
                                     std::move(materials), body_material, names);
  if (target && scene.run.fix_edges)
    for (fem::VelocityConstraint &c : boxEdges(model, scene.target, scene.run.smooth_walls))
      model.constraints.push_back(std::move(c));
  const auto [vx, vy] = runVelocity(scene.run);
  fem::setBodyVelocity(model, 0, vx, vy, scene.run.spin);
  if (scene.run.constant_velocity) {
    fem::VelocityConstraint driven{"projectile driven", {}, true, true, vx, vy};
    for (std::size_t a = model.bodies[0].node_begin; a < model.bodies[0].node_end; ++a)
      driven.nodes.push_back(static_cast<std::uint32_t>(a));
    model.constraints.push_back(std::move(driven));
  }
  return model;
}

RunAssembly::RunAssembly(const Scene &scene, const std::string &dir,
                         const std::string &liggghts_script, const parallel::World &world,
                         const std::string &liggghts_restart) {
  const RunSpec &run = scene.run;
  std::unique_ptr<Target> target;
  if (run.grains) {
    // With disks, the grains to mesh are chosen first and meshed alone (grainMeshes).
    TargetSpec spec = scene.target;
    if (run.representation != Representation::fe)
      spec.mesh = MeshKind::none;
    GeneratorReport report;
    target = std::make_unique<Target>(generateTarget(spec, report));
    stopIfAsked(world, "target's generation");
  }
  const PlacedProjectile projectile = runProjectile(scene, target.get());
  const std::vector<char> meshed =
      target ? meshedGrains(scene, *target, projectile) : std::vector<char>{};
  model = buildRunModel(scene, target.get(), projectile, meshed);
  stopIfAsked(world, "model's assembly");
  const bool walls = target != nullptr;
  // The grains not meshed are LIGGGHTS's disks, coupled to the FE bodies.
  if (target && std::find(meshed.begin(), meshed.end(), 0) != meshed.end()) {
    if (world.rank == 0) // the files are rank 0's
      writeLiggghtsData(dir + "/dem.data", *target,
                        targetDisks(*target, scene.dem.disk_size, meshed, &projectile));
    world.barrier();
    dem = std::make_unique<coupling::LiggghtsDem>(
        liggghts_script, liggghtsVariables(scene, dir + "/dem.data", liggghts_restart),
        dir + "/liggghts.log", MPI_COMM_WORLD, !liggghts_restart.empty());
  }
  target.reset();
  const double dem_step = dem ? dem->stableStep() : HUGE_VAL; // every rank calls it
  if (world.size > 1) {
    processes = std::make_unique<parallel::MpiCommunicator>(MPI_COMM_WORLD);
    partitioner = std::make_unique<parallel::ZoltanRcb>(MPI_COMM_WORLD);
  } else {
    processes = std::make_unique<parallel::SerialCommunicator>();
    partitioner = std::make_unique<parallel::SerialPartitioner>();
  }
  solver = std::make_unique<fem::Solver>(model, solverSettings(scene, dem_step), *processes,
                                         *partitioner);
  solver->endAt(run.end_time);
  if (scene.contact.enabled) {
    contact = std::make_unique<fem::Contact>(model, contactSettings(scene, walls));
    solver->addForceProvider(contact.get());
  }
  if (dem) {
    // Windows up to the disks' stable step (a longer one is refused: the disks' own contacts
    // would be unstable).
    if (scene.dem.step > dem_step) {
      char text[160];
      std::snprintf(text, sizeof text,
                    ": dem.step = %.6g s is longer than the disks' stable step, %.6g s (a tenth of "
                    "the lightest disk's contact time); allowed: 0 to %.6g [s]",
                    scene.dem.step, dem_step, dem_step);
      throw InputError(scene.path + text);
    }
    coupled = std::make_unique<coupling::FeDemCoupling>(
        model, *dem, diskContactSettings(scene, model.bodies.size()),
        scene.dem.step > 0.0 ? scene.dem.step : dem_step);
    solver->addForceProvider(coupled.get());
  }
}

} // namespace mesopen
