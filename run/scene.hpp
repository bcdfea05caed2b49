// Scenes: TOML files in SI units, read strictly. Every key the program knows is listed once, in
// the table in scene.cpp, with its type, default, allowed range and meaning; `mesopen keys`
// prints that table (docs/scene-keys.md is its copy).
#pragma once

#include "contact.hpp"
#include "disks.hpp"
#include "material.hpp"
#include "projectile.hpp"
#include "solver.hpp"
#include "spring_dashpot.hpp"
#include "target.hpp"

#include <toml++/toml.h>

#include <array>
#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>

namespace mesopen {

// How the grains are modelled: every grain meshed (fe), every grain a LIGGGHTS disk (dem), or the
// grains whose centres lie within a band around the projectile's path meshed and the rest disks
// (hybrid).
enum class Representation { fe, dem, hybrid };
inline constexpr Named<Representation> representation_names[] = {
    {"fe", Representation::fe}, {"dem", Representation::dem}, {"hybrid", Representation::hybrid}};

// What `mesopen run` does with the target and the projectile (table [run]).
struct RunSpec {
  Representation representation = Representation::fe;
  double band_half_width = 0.0; // hybrid: meshed grains' centres within this of the axis [m];
                                // 0: one and a half projectile diameters
  double band_depth = 0.0;      // hybrid: and no deeper than this below the tip at the start
                                // [m]; 0: the end depth plus band_half_width
  double end_time = 1e-6;       // simulated time [s]
  double velocity = 1000.0;     // projectile's initial speed, downward [m/s]
  double spin = 0.0;            // projectile's initial spin about its centre of mass [rad/s]
  double obliquity = 0.0; // the velocity's angle to the target's normal (straight down), CCW [deg]
  double yaw = 0.0;       // the axis's angle to the velocity (angle of attack), CCW [deg]
  double offset = 0.0;    // the tip's lateral position from the box's middle [m]
  bool grains = true;     // false: the projectile alone, in free flight
  bool fix_edges = true;  // grain nodes on the box's left, right and bottom edges fixed
  bool smooth_walls = false;      // frictionless walls: edge nodes held normal to their edge only
  bool constant_velocity = false; // the projectile's velocity held at (0, -velocity)
  // The solver's keys, with the solver's defaults (fem::SolverSettings owns them).
  double safety = fem::SolverSettings{}.safety; // time step over the stable step
  double viscosity_linear = fem::SolverSettings{}.viscosity_linear; // artificial viscosity C_L
  double viscosity_quadratic = fem::SolverSettings{}.viscosity_quadratic; // C_Q
  bool anti_locking = fem::SolverSettings{}.anti_locking; // averaged nodal volume (plastic flow)
  // an element whose stable step falls below this fraction of the shortest at the start is
  // eroded; 0: never
  double erode_step_ratio = fem::SolverSettings{}.erode_step_ratio;
  // an element whose stable step falls below this fraction of the shortest at the start gets
  // mass; 0: never
  double mass_scaling_step_ratio = fem::SolverSettings{}.mass_scaling_step_ratio;
  std::int64_t series_interval = 1; // steps between series samples
  // steps between samples of the census of multiple time stepping's levels (fem/levels.hpp); 0:
  // none
  std::int64_t level_census_interval = 0;
  // multiple time stepping: the largest level, a batch of elements updating every 2^level base
  // steps within its own stable step (fem/solver.hpp); 0: every element every step
  std::int64_t max_level = fem::SolverSettings{}.max_level;
  // with levels: the most levels a body steps coarser than the own level of a body it may meet
  std::int64_t level_gap = fem::SolverSettings{}.level_gap;
  double end_depth = 0.0;       // stop when the depth reaches this many projectile lengths
  double frame_interval = 1e-7; // simulated time between frames [s]; 0: no frames
  bool vtk = true;              // frames also as VTK files for ParaView
  std::int64_t max_steps = 100000000;
  // Checkpoints (run/checkpoint.hpp): wall-clock seconds between them, simulated time between
  // them [s]; 0: none of that kind. Either on: also one on SIGINT or SIGTERM.
  double checkpoint_interval = 0.0;
  double checkpoint_time = 0.0;
  // With several MPI ranks: the bodies are partitioned among them anew when the element work's
  // imbalance passes this fraction, and before every rebalance_every-th step (0: not by steps).
  double rebalance_imbalance = fem::SolverSettings{}.rebalance_imbalance;
  std::int64_t rebalance_every = 0;
  bool checkpoints() const { return checkpoint_interval > 0.0 || checkpoint_time > 0.0; }
};

// Contact between the bodies and with the box's walls (table [contact]), with the contact's
// defaults (fem::ContactSettings owns them: its one coefficient for every pair is the friction).
struct ContactSpec {
  bool enabled = true;
  // Coulomb mu between grains, and grains and walls
  double friction = fem::ContactSettings{}.friction.front();
  double projectile_friction = friction;               // between the projectile and grains or walls
  double stiffness = fem::ContactSettings{}.stiffness; // penalty kappa: k = kappa m_eff / dt^2
  double damping = fem::ContactSettings{}.damping;     // fraction of the spring's critical damping
  // with several MPI ranks: the boundary nodes from which a body goes to a halo partner in part
  std::int64_t halo_in_part_from = fem::ContactSettings{}.halo_in_part_from;
};

// The disks' normal contact law in LIGGGHTS (liggghts-inputs/dem.in): linear (hooke/stiffness) or
// Hertzian (hertz/stiffness), stiffening with the overlap as the grains' contacts do.
enum class NormalLaw { hooke, hertz };
inline constexpr Named<NormalLaw> normal_law_names[] = {{"hooke", NormalLaw::hooke},
                                                        {"hertz", NormalLaw::hertz}};

// Named sets of the [dem] keys (dem.preset, applied before the table's other keys):
// quartz-pair, the linear law calibrated on a pair of meshed grains colliding, on inscribed disks;
// quartz-bulk, the Hertzian law on equal-area disks, calibrated on the planar compaction
// (Hugoniot) of the meshed target (tools/studies/calibrate_dem.py; docs/coupling.md).
enum class DemPreset { quartz_pair, quartz_bulk };
inline constexpr Named<DemPreset> dem_preset_names[] = {{"quartz-pair", DemPreset::quartz_pair},
                                                        {"quartz-bulk", DemPreset::quartz_bulk}};

// The DEM grains (table [dem]): LIGGGHTS's hooke/stiffness law per metre of thickness, f_n =
// k_n d - g_n v_n (liggghts-inputs/dem.in), between disks and with the walls; the disks meet the FE
// bodies with the FE contact law (coupling/disk_contact.hpp) and [contact]'s friction.
// The defaults: quartz grains' law, calibrated against pairs of meshed grains (docs/coupling.md).
struct DemSpec {
  DemPreset preset = DemPreset::quartz_pair;
  double stiffness = coupling::quartz_grains.kn;            // k_n [N/m per m]
  double tangential_stiffness = coupling::quartz_grains.kt; // k_t [N/m per m]
  double damping = coupling::quartz_grains.gn;              // g_n, absolute [N s/m per m]
  double tangential_damping = coupling::quartz_grains.gt;   // g_t [N s/m per m]
  DiskSize disk_size = DiskSize::inscribed; // the disks' radii and places (targets/disks.hpp)
  NormalLaw normal_law = NormalLaw::hooke;  // the disks' normal contact law
  double hertz_length = 8e-6;    // hertz: sqrt(r_eff d) where the law has stiffness k_n [m]
  double rolling_friction = 0.0; // LIGGGHTS epsd2 rolling resistance between disks; 0: none
  double skin = 0.0;             // neighbour skin [m]; 0: half the mean diameter
  double step = 0.0; // the disks' step, a time window of many FE steps [s]; 0: their stable step
  // The preset's values for every key it names (the others are left as they are).
  void apply(DemPreset p);
};

// What `mesopen modal` analyses (table [modal]): the scene's projectile, free, or a rectangular
// beam (thesis appendix B), free or clamped at its left end x = 0; both of the material of
// [materials.projectile].
enum class ModalBody { projectile, beam };
enum class ModalSupport { free, clamped };
enum class ModalPlane { strain, stress };
inline constexpr Named<ModalBody> modal_body_names[] = {{"projectile", ModalBody::projectile},
                                                        {"beam", ModalBody::beam}};
inline constexpr Named<ModalSupport> modal_support_names[] = {{"free", ModalSupport::free},
                                                              {"clamped", ModalSupport::clamped}};
inline constexpr Named<ModalPlane> modal_plane_names[] = {{"strain", ModalPlane::strain},
                                                          {"stress", ModalPlane::stress}};

struct ModalSpec {
  ModalBody body = ModalBody::projectile;
  double length = 5.0;    // beam length, along x [m]
  double height = 0.1;    // beam height, along y [m]
  double mesh_size = 0.0; // triangle edge [m]; 0: the projectile's, or height / 10
  ModalSupport support = ModalSupport::free;
  ModalPlane plane = ModalPlane::strain;
  std::int64_t modes = 10; // elastic modes wanted
};

// A body group's material (tables [materials.projectile], [materials.grains]): a preset or a
// type, and parameters by name.
struct MaterialChoice {
  std::string name; // preset or type
  std::map<std::string, double> parameters;
};

struct Scene {
  std::string path;
  TargetSpec target;
  ProjectileSpec projectile;
  RunSpec run;
  ContactSpec contact;
  DemSpec dem;
  ModalSpec modal;
  MaterialChoice projectile_material{"steel", {}}, grain_material{"quartz", {}};
};

// Bad input: the message names the file, the key, the value and what is allowed. Exit code 2.
class InputError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

// Read and validate a scene. Throws InputError.
Scene readScene(const std::string &path);
// The same from its tables; `path` names it in messages.
Scene readScene(const toml::table &root, const std::string &path);
// A TOML file's tables. Throws InputError naming the line of a syntax error.
toml::table parseToml(const std::string &path);
// A TOML value as a scene file writes it (strings quoted), for messages: at most 80 characters
// of it, and its length when longer.
std::string tomlText(const toml::node &n);

// The scene as TOML with every key at its value (defaults included) and every material parameter
// resolved; readScene reads it back to the same scene, and composes it again to the same text.
std::string composedScene(const Scene &scene);
// A material choice's parameters: the type's defaults, the preset's values, the scene's.
fem::Parameters resolvedParameters(const MaterialChoice &choice);
// The scene's material tables by name ([materials.NAME]): projectile, grains.
std::array<std::pair<const char *, const MaterialChoice *>, 2> materialGroups(const Scene &scene);
// How a scene names the choice: "preset" (a preset's name) or "type".
const char *materialKey(const MaterialChoice &choice);

// The reference of every key (Markdown): table, key, type, default, allowed, meaning.
std::string sceneKeysMarkdown();

} // namespace mesopen
