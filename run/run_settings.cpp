#include "run_settings.hpp"

#include <cmath>
#include <cstdio>

namespace mesopen {

fem::SolverSettings solverSettings(const Scene &scene, double max_dt) {
  const RunSpec &run = scene.run;
  return {.safety = run.safety,
          .viscosity_linear = run.viscosity_linear,
          .viscosity_quadratic = run.viscosity_quadratic,
          .anti_locking = run.anti_locking,
          .max_dt = max_dt,
          .erode_step_ratio = run.erode_step_ratio,
          .mass_scaling_step_ratio = run.mass_scaling_step_ratio,
          .rebalance_imbalance = run.rebalance_imbalance,
          .rebalance_every = static_cast<std::size_t>(run.rebalance_every),
          .max_level = static_cast<int>(run.max_level),
          .level_gap = static_cast<int>(run.level_gap)};
}

fem::ContactSettings contactSettings(const Scene &scene, bool walls) {
  const ContactSpec &c = scene.contact;
  fem::ContactSettings s;
  s.friction = {0.0, c.projectile_friction, c.projectile_friction, c.friction};
  // grains meet the walls; the projectile does not reach them
  s.wall_friction = scene.run.smooth_walls ? 0.0 : c.friction;
  s.stiffness = c.stiffness;
  s.damping = c.damping;
  s.halo_in_part_from = c.halo_in_part_from;
  if (walls)
    s.wall_left = 0.0, s.wall_right = scene.target.width, s.wall_bottom = 0.0;
  return s;
}

coupling::DiskContactSettings diskContactSettings(const Scene &scene, std::size_t bodies) {
  coupling::DiskContactSettings disk{scene.contact.stiffness, scene.contact.damping, {}};
  disk.friction.assign(bodies, scene.contact.friction);
  disk.friction[0] = scene.contact.projectile_friction;
  return disk;
}

std::vector<std::pair<std::string, std::string>>
liggghtsVariables(const Scene &scene, const std::string &data, const std::string &restart) {
  const DemSpec &d = scene.dem;
  auto text = [](double v) {
    char s[32];
    std::snprintf(s, sizeof s, "%.17g", v);
    return std::string(s);
  };
  // Half a grain: a disk the projectile drives at 1500 m/s crosses a tenth of a grain (the skin's
  // half) in about two of the disks' steps, and each crossing rebuilds every neighbour list; a
  // wider skin costs the pairs' own search little (docs/decisions.md).
  const double skin = d.skin > 0.0 ? d.skin : 0.5 * scene.target.meanDiameter();
  // With checkpoints, lists rebuilt every step and no sorting: LIGGGHTS's set-up after a restart
  // file then builds what the last step built (liggghts-inputs/dem.in, run/checkpoint.hpp).
  return {{"data", restart.empty() ? data : restart},
          {"restart", restart.empty() ? "0" : "1"},
          {"lists", scene.run.checkpoints() ? "1" : "0"},
          {"kn", text(d.stiffness)},
          {"kt", text(d.tangential_stiffness)},
          {"gn", text(d.damping)},
          {"gt", text(d.tangential_damping)},
          {"mu", text(scene.contact.friction)},
          {"mu_wall", text(scene.run.smooth_walls ? 0.0 : scene.contact.friction)},
          {"hertz", d.normal_law == NormalLaw::hertz ? "1" : "0"},
          {"rolling", text(d.rolling_friction)},
          {"h", text(d.hertz_length)},
          // the effective mass of a pair of mean grains, m / 2
          {"mref", text(0.25 * M_PI * scene.target.density * scene.target.meanDiameter() *
                        scene.target.meanDiameter() / 2.0)},
          {"xlo", "0"},
          {"xhi", text(scene.target.width)},
          {"ylo", "0"},
          {"skin", text(skin)},
          {"gravity", "0"},
          {"dt", "1e-9"}};
}

} // namespace mesopen
