#include "scene.hpp"

#include "material.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <sstream>
#include <vector>

namespace mesopen {

namespace {

// One scene key: where it lives, what it holds, what is allowed, and how it is stored.
struct Key {
  std::string table, name, type, unit, doc;
  double lo = -HUGE_VAL, hi = HUGE_VAL; // allowed closed range for numbers
  bool lo_open = false;                 // lo itself not allowed
  std::vector<std::string> choices;     // for strings
  std::function<void(Scene &, const toml::node &, const std::string &where)> set;
  std::function<std::string(const Scene &)> get; // the value as a scene writes it
};

std::string show(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// A number as a scene writes it and reads it back to the same double: the shortest text that
// does (std::to_chars), "inf", "-inf" and "nan" as TOML spells them.
std::string exact(double v) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, v).ptr;
  return std::string(text, end);
}

std::string allowed(const Key &k) {
  if (!k.choices.empty()) {
    std::string s;
    for (const auto &c : k.choices)
      s += (s.empty() ? "\"" : ", \"") + c + "\"";
    return "one of " + s;
  }
  if (k.type == "bool")
    return "true or false";
  std::string lo = k.lo == -HUGE_VAL ? "" : show(k.lo) + (k.lo_open ? " < " : " <= ");
  std::string hi = k.hi == HUGE_VAL ? "" : " <= " + show(k.hi);
  return lo + k.name + hi;
}

[[noreturn]] void fail(const std::string &where, const Key &k, const std::string &value,
                       const std::string &why) {
  throw InputError(where + ": " + k.table + "." + k.name + " = " + value + " " + why +
                   "; allowed: " + allowed(k) + (k.unit.empty() ? "" : " [" + k.unit + "]"));
}

double number(const Key &k, const toml::node &n, const std::string &where) {
  double v;
  if (auto f = n.as_floating_point())
    v = f->get();
  else if (auto i = n.as_integer())
    v = static_cast<double>(i->get());
  else
    fail(where, k, tomlText(n), "is not a number");
  if (!std::isfinite(v) || v < k.lo || (k.lo_open && v == k.lo) || v > k.hi)
    fail(where, k, tomlText(n), "is out of range");
  return v;
}

template <class Spec>
Key real(std::string table, std::string name, Spec Scene::*part, double Spec::*field,
         std::string unit, double lo, bool lo_open, double hi, std::string doc) {
  Key k{table, name, "real", unit, doc, lo, hi, lo_open, {}, nullptr, nullptr};
  k.set = [k, part, field](Scene &s, const toml::node &n, const std::string &where) {
    (s.*part).*field = number(k, n, where);
  };
  k.get = [part, field](const Scene &s) { return exact((s.*part).*field); };
  return k;
}

template <class Spec, class Int>
Key integer(std::string table, std::string name, Spec Scene::*part, Int Spec::*field, double lo,
            double hi, std::string doc) {
  Key k{table, name, "integer", "", doc, lo, hi, false, {}, nullptr, nullptr};
  k.set = [k, part, field](Scene &s, const toml::node &n, const std::string &where) {
    auto i = n.as_integer();
    if (!i)
      fail(where, k, tomlText(n), "is not an integer");
    if (static_cast<double>(i->get()) < k.lo || static_cast<double>(i->get()) > k.hi)
      fail(where, k, tomlText(n), "is out of range");
    (s.*part).*field = static_cast<Int>(i->get());
  };
  k.get = [part, field](const Scene &s) { return std::to_string((s.*part).*field); };
  return k;
}

template <class Spec, class Enum, std::size_t N>
Key choice(std::string table, std::string name, Spec Scene::*part, Enum Spec::*field,
           const Named<Enum> (&named)[N], std::string doc) {
  std::vector<std::pair<std::string, Enum>> options;
  for (const auto &n : named)
    options.emplace_back(n.name, n.value);
  Key k{table, name, "string", "", doc, -HUGE_VAL, HUGE_VAL, false, {}, nullptr, nullptr};
  for (const auto &o : options)
    k.choices.push_back(o.first);
  k.set = [k, part, field, options](Scene &s, const toml::node &n, const std::string &where) {
    auto str = n.as_string();
    if (!str)
      fail(where, k, tomlText(n), "is not a string");
    for (const auto &o : options)
      if (o.first == str->get()) {
        (s.*part).*field = o.second;
        return;
      }
    fail(where, k, tomlText(n), "is not known");
  };
  k.get = [part, field, options](const Scene &s) {
    for (const auto &o : options)
      if (o.second == (s.*part).*field)
        return "\"" + o.first + "\"";
    return std::string("?");
  };
  return k;
}

template <class Spec>
Key boolean(std::string table, std::string name, Spec Scene::*part, bool Spec::*field,
            std::string doc) {
  Key k{table, name, "bool", "", doc, -HUGE_VAL, HUGE_VAL, false, {}, nullptr, nullptr};
  k.set = [k, part, field](Scene &s, const toml::node &n, const std::string &where) {
    auto b = n.as_boolean();
    if (!b)
      fail(where, k, tomlText(n), "is not true or false");
    (s.*part).*field = b->get();
  };
  k.get = [part, field](const Scene &s) {
    return std::string((s.*part).*field ? "true" : "false");
  };
  return k;
}

// The grain diameter: one number for a uniform size, or [min, max] for sizes uniformly
// distributed in that range.
Key diameter() {
  Key k{"target",
        "diameter",
        "real or [min, max]",
        "m",
        "grain diameter: one value (uniform size) or a range [min, max] (uniformly distributed)",
        1e-7,
        1.0,
        true,
        {},
        nullptr,
        nullptr};
  k.set = [k](Scene &s, const toml::node &n, const std::string &where) {
    if (auto a = n.as_array()) {
      if (a->size() != 2)
        fail(where, k, tomlText(n), "is not one number or a pair [min, max]");
      const double lo = number(k, *a->get(0), where), hi = number(k, *a->get(1), where);
      if (lo > hi)
        fail(where, k, tomlText(n), "has min > max");
      s.target.diameter_min = lo, s.target.diameter_max = hi;
    } else {
      s.target.diameter_min = s.target.diameter_max = number(k, n, where);
    }
  };
  k.get = [](const Scene &s) {
    std::string text = "[";
    text += exact(s.target.diameter_min);
    text += ", ";
    text += exact(s.target.diameter_max);
    return text + "]";
  };
  return k;
}

// dem.preset: sets the preset's keys too (readScene applies it before the table's other keys).
Key demPreset() {
  Key k = choice("dem", "preset", &Scene::dem, &DemSpec::preset, dem_preset_names,
                 "a named set of the [dem] keys, applied first: quartz-pair (linear law on "
                 "inscribed disks, calibrated on a pair of grains) or quartz-bulk (Hertzian law on "
                 "equal-area disks, calibrated on the meshed target's Hugoniot; docs/coupling.md)");
  k.set = [set = k.set](Scene &s, const toml::node &n, const std::string &where) {
    set(s, n, where);
    s.dem.apply(s.dem.preset);
  };
  return k;
}

const std::vector<Key> &keys() {
  static const std::vector<Key> all = [] {
    using T = TargetSpec;
    using P = ProjectileSpec;
    using R = RunSpec;
    auto t = &Scene::target;
    auto p = &Scene::projectile;
    auto r = &Scene::run;
    using C = ContactSpec;
    auto c = &Scene::contact;
    using M = ModalSpec;
    auto m = &Scene::modal;
    using D = DemSpec;
    auto d = &Scene::dem;
    return std::vector<Key>{
        real("target", "width", t, &T::width, "m", 0, true, 10, "box width W"),
        real("target", "height", t, &T::height, "m", 0, true, 10, "box height H"),
        diameter(),
        real("target", "porosity", t, &T::porosity, "", 0.05, false, 0.6,
             "requested porosity (A_T - A_G) / A_T (thesis Eq. 4.5)"),
        real("target", "void_ratio", t, &T::void_ratio, "", 0.1, false, 0.5,
             "void-site diameter over the mean grain diameter (thesis: 1/4)"),
        choice("target", "placement", t, &T::placement, placement_names,
               "initial sites: one grain per sub-box (regular) or all random (clustered), thesis "
               "4.2.5"),
        integer("target", "seed", t, &T::seed, 0, 9.0e15, "random seed"),
        real("target", "step_scale", t, &T::step_scale, "", 0, true, 3,
             "largest placement move per iteration over the mean diameter (thesis Fig. 4.6)"),
        real("target", "step_decay", t, &T::step_decay, "", 0.1, false, 1,
             "step factor each time the overlap energy rises (1: the thesis's fixed step)"),
        integer("target", "max_iterations", t, &T::max_iterations, 0, 100000,
                "placement iterations at most; 0: 50 for regular, 500 for clustered placement"),
        real("target", "void_scale", t, &T::void_scale, "", 0.05, false, 5,
             "void-site count over the area rule V = (A - sum of grain disk areas) / void disk "
             "area"),
        boolean("target", "calibrate_porosity", t, &T::calibrate_porosity,
                "scale the void cells so that the porosity matches the request"),
        choice(
            "target", "tessellation", t, &T::tessellation, tessellation_names,
            "power (Laguerre) cells weighted by r^2, or Voronoi with the thesis's radius matching "
            "(Eq. 4.4)"),
        choice("target", "mesh", t, &T::mesh, mesh_names,
               "grain meshes: quality triangles at mesh_size, fan (centroid to vertices), or none"),
        real("target", "mesh_size", t, &T::mesh_size, "m", 0, true, 1,
             "triangle edge length; polygon vertices closer than this are merged"),
        real("target", "min_angle", t, &T::min_angle, "deg", 5, false, 20.7,
             "smallest triangle angle of the quality mesh"),
        real("target", "density", t, &T::density, "kg/m^3", 0, true, 1e5,
             "grain density, for target.data (quartz: 2648.5, Table 3.3)"),
        boolean("projectile", "enabled", p, &P::enabled, "make and place the projectile"),
        choice(
            "projectile", "shape", p, &P::shape, projectile_kind_names,
            "an ogive penetrator (the thesis's), or a flat plate as wide as the box and `length` "
            "thick: a piston for planar compaction (docs/hugoniot.md)"),
        real("projectile", "length", p, &P::length, "m", 0, true, 1,
             "length L of the sharp ogive body"),
        real("projectile", "length_over_diameter", p, &P::length_over_diameter, "", 1, false, 50,
             "l/d (thesis: 3.85)"),
        real("projectile", "crh", p, &P::crh, "", 0.5, false, 50,
             "caliber radius head: ogive radius over diameter (thesis: 3.5)"),
        real("projectile", "tip_half_angle", p, &P::tip_half_angle, "deg", 0, true, 89,
             "half-angle of the tip facets to the axis (thesis: 60)"),
        real("projectile", "tip_facet_length", p, &P::tip_facet_length, "m", 0, false, 1,
             "length of each tip facet; 0 keeps the sharp tip"),
        real("projectile", "mesh_size", p, &P::mesh_size, "m", 0, false, 1,
             "triangle edge length; 0 takes target.mesh_size"),
        real("projectile", "min_angle", p, &P::min_angle, "deg", 5, false, 20.7,
             "smallest triangle angle"),
        choice("run", "representation", r, &R::representation, representation_names,
               "the grains: all meshed (fe), all LIGGGHTS disks (dem), or meshed within a band "
               "around the projectile's path and disks beyond (hybrid)"),
        real("run", "band_half_width", r, &R::band_half_width, "m", 0, false, 10,
             "hybrid: grains whose centres lie within this distance of the projectile's axis are "
             "meshed; 0: one and a half projectile diameters"),
        real("run", "band_depth", r, &R::band_depth, "m", 0, false, 10,
             "hybrid: the meshed grains' centres lie no deeper than this below the projectile's "
             "tip at "
             "the start; 0: run.end_depth's depth plus band_half_width (no limit without "
             "end_depth)"),
        real("run", "end_time", r, &R::end_time, "s", 0, true, 1, "simulated time"),
        real("run", "velocity", r, &R::velocity, "m/s", 0, false, 1e4,
             "projectile's initial speed, downward (thesis: 500-1500)"),
        real("run", "spin", r, &R::spin, "rad/s", -1e9, false, 1e9,
             "projectile's initial spin about its centre of mass (counter-clockwise positive)"),
        real("run", "obliquity", r, &R::obliquity, "deg", -80, false, 80,
             "the velocity's angle to the target's normal (straight down), counter-clockwise "
             "positive: velocity (sin, -cos) of it times run.velocity"),
        real("run", "yaw", r, &R::yaw, "deg", -80, false, 80,
             "angle of attack: the projectile axis's angle to its velocity, counter-clockwise "
             "positive; the projectile turned about its tip, placed touching the grains"),
        real("run", "offset", r, &R::offset, "m", -1, false, 1,
             "the tip's lateral position from the box's middle (the projectile stays inside the "
             "box)"),
        boolean("run", "grains", r, &R::grains, "include the grains; false: the projectile alone"),
        boolean("run", "fix_edges", r, &R::fix_edges,
                "fix the grain nodes on the box's left, right and bottom edges"),
        boolean("run", "smooth_walls", r, &R::smooth_walls,
                "frictionless box walls: the edge nodes slide along their edge (held normal to it "
                "only), and the walls' contact, FE and DEM, has no friction; uniaxial strain"),
        boolean("run", "constant_velocity", r, &R::constant_velocity,
                "hold the projectile's velocity at run.velocity, downward, throughout (a rigid "
                "piston or a driven penetrator); false: it flies free from it"),
        real("run", "safety", r, &R::safety, "", 1e-3, false, 1, "time step over the stable step"),
        real("run", "viscosity_linear", r, &R::viscosity_linear, "", 0, false, 10,
             "artificial viscosity, linear coefficient C_L (thesis Table 3.1: 0.5)"),
        real("run", "viscosity_quadratic", r, &R::viscosity_quadratic, "", 0, false, 100,
             "artificial viscosity, quadratic coefficient C_Q (thesis Table 3.1: 4.0)"),
        boolean(
            "run", "anti_locking", r, &R::anti_locking,
            "averaged nodal volume in bodies with plastic flow (against volumetric locking); off "
            "by default: under a penetrator it lets crushed elements collapse (docs/solver.md)"),
        real("run", "erode_step_ratio", r, &R::erode_step_ratio, "", 0, false, 1,
             "an element whose stable step falls below this fraction of the shortest element step "
             "at the start is eroded (a collapsed element; docs/solver.md); 0: never"),
        real(
            "run", "mass_scaling_step_ratio", r, &R::mass_scaling_step_ratio, "", 0, false, 1,
            "selective mass scaling: an element whose stable step falls below this fraction of the "
            "shortest element step at the start gets mass on its nodes (momentum kept) to bring "
            "its "
            "step back to it (docs/solver.md); 0: never"),
        integer("run", "series_interval", r, &R::series_interval, 1, 1e9,
                "steps between samples of the series in run.h5"),
        integer("run", "level_census_interval", r, &R::level_census_interval, 0, 1e9,
                "steps between samples of the census of multiple time stepping's levels: each "
                "body's own stable step, its level on the step taken, the pairs and rings across "
                "levels and the work they would take (/levels in run.h5, `levels` in "
                "summary.json; docs/solver.md); 0: none"),
        integer("run", "max_level", r, &R::max_level, 0, 3,
                "multiple time stepping by body: the largest level, a body stepping every "
                "2^level base steps (the shortest body's step) within its own stable step and "
                "at most level_gap levels coarser than the bodies it may meet, a contact pair "
                "when both its bodies step, a body a disk may reach within its window every "
                "step (docs/solver.md; fe, dem and hybrid); "
                "0: every body every step"),
        integer("run", "level_gap", r, &R::level_gap, 0, 3,
                "multiple time stepping: the most levels a body steps coarser than the own level "
                "of a body it may meet, none beside a body stepped in parts (the projectile) (a "
                "pair across levels is computed at the coarser body's steps, with a softer "
                "penalty; docs/solver.md); 0: no coarser"),
        real("run", "end_depth", r, &R::end_depth, "", 0, false, 100,
             "stop when the projectile's depth reaches this many projectile lengths (thesis: 1); "
             "0: run to end_time"),
        real("run", "frame_interval", r, &R::frame_interval, "s", 0, false, 1,
             "simulated time between frames (fields) in run.h5, also taken at the start and the "
             "end; 0: no frames"),
        boolean("run", "vtk", r, &R::vtk, "write the frames also as VTK files (vtk/run.pvd)"),
        integer("run", "max_steps", r, &R::max_steps, 1, 1e12, "time steps at most"),
        real("run", "checkpoint_interval", r, &R::checkpoint_interval, "s", 0, false, 1e7,
             "wall-clock seconds between checkpoints (DIR/checkpoint; `mesopen run --resume "
             "DIR` continues from the last); 0: none by the clock. With checkpoints on (this or "
             "checkpoint_time) SIGINT and SIGTERM write one too"),
        real("run", "checkpoint_time", r, &R::checkpoint_time, "s", 0, false, 1,
             "simulated time between checkpoints; 0: none by simulated time"),
        real("run", "rebalance_imbalance", r, &R::rebalance_imbalance, "", 0, true, 10,
             "with several MPI ranks: the bodies are partitioned among the ranks anew (Zoltan "
             "RCB, weighted by active elements) when the most loaded rank's active elements pass "
             "the least a partition of whole bodies allows by this fraction (docs/solver.md)"),
        integer("run", "rebalance_every", r, &R::rebalance_every, 0, 1e12,
                "with several MPI ranks: a new partition also before every this many steps, "
                "whatever the imbalance (to exercise a change of owners); 0: only by the "
                "imbalance"),
        boolean("contact", "enabled", c, &C::enabled,
                "contact between the bodies and with the box's walls; false: bodies pass through"),
        real("contact", "friction", c, &C::friction, "", 0, false, 10,
             "Coulomb coefficient between grains and between grains and walls (thesis: 0.3)"),
        real("contact", "projectile_friction", c, &C::projectile_friction, "", 0, false, 10,
             "Coulomb coefficient between the projectile and the grains, meshed or disks (thesis: "
             "0.3); the walls take contact.friction"),
        real("contact", "stiffness", c, &C::stiffness, "", 0, true, 0.6,
             "penalty kappa: normal stiffness kappa m_eff / dt^2 per node (stable up to 0.6)"),
        real("contact", "damping", c, &C::damping, "", 0, false, 2,
             "damping of the contact spring, a fraction of its critical damping (stable up to "
             "about 0.1)"),
        integer("contact", "halo_in_part_from", c, &C::halo_in_part_from, 0, 1e9,
                "with several MPI ranks: a body of at least this many boundary nodes goes to "
                "another rank's contact halo in part, the segments near its pairs there (0: "
                "every body whole); the run is the same"),
        real("dem", "stiffness", d, &D::stiffness, "N/m^2", 0, true, 1e16,
             "normal stiffness k_n of the disks' contacts, per metre of thickness "
             "(docs/coupling.md)"),
        real("dem", "tangential_stiffness", d, &D::tangential_stiffness, "N/m^2", 0, true, 1e16,
             "tangential stiffness k_t"),
        real("dem", "damping", d, &D::damping, "N s/m^2", 0, false, 1e6,
             "normal damping g_n (absolute): f_n = k_n d - g_n v_n"),
        real("dem", "tangential_damping", d, &D::tangential_damping, "N s/m^2", 0, false, 1e6,
             "tangential damping g_t (absolute)"),
        demPreset(),
        choice(
            "dem", "disk_size", d, &D::disk_size, disk_size_names,
            "inscribed: at the grain's centroid, its equal-area radius or less where it would "
            "overlap (covers less than the grains); equal_area: the equal-area radius, the disks "
            "pushed apart until none overlaps (covers what the grains cover; docs/coupling.md)"),
        choice("dem", "normal_law", d, &D::normal_law, normal_law_names,
               "the disks' normal law: hooke, f_n = k_n d - g_n v_n; hertz, the same times "
               "sqrt(r_eff d) / hertz_length (stiffer as the disks are pressed together)"),
        real("dem", "hertz_length", d, &D::hertz_length, "m", 1e-9, false, 1e-3,
             "hertz: the length sqrt(r_eff d) at which the Hertzian law has the stiffness "
             "dem.stiffness and damping dem.damping (a 60 um pair: d = 0.14 r at 8e-6)"),
        real("dem", "rolling_friction", d, &D::rolling_friction, "", 0, false, 10,
             "rolling resistance between disks (LIGGGHTS epsd2: an elastic-plastic torque up to "
             "this times r_eff f_n), standing in for the grains' corners; 0: none"),
        real("dem", "skin", d, &D::skin, "m", 0, false, 1,
             "LIGGGHTS's neighbour skin; 0: half the mean grain diameter"),
        real("dem", "step", d, &D::step, "s", 0, false, 1e-6,
             "the disks' time step, a window of many FE steps (multiple time stepping, "
             "docs/coupling.md); 0: their stable step, a tenth of the lightest disk's contact "
             "time; at most that"),
        choice("modal", "body", m, &M::body, modal_body_names,
               "what `mesopen modal` analyses: the projectile above, or a rectangular beam "
               "(thesis appendix B); both of the material of [materials.projectile]"),
        real("modal", "length", m, &M::length, "m", 0, true, 1e3, "beam length, along x"),
        real("modal", "height", m, &M::height, "m", 0, true, 1e3, "beam height, along y"),
        real("modal", "mesh_size", m, &M::mesh_size, "m", 0, false, 1e3,
             "triangle edge of the modal mesh; 0: the projectile's (as in a run), a beam's "
             "height / 10"),
        choice("modal", "support", m, &M::support, modal_support_names,
               "free, or (a beam only) clamped at its left end x = 0"),
        choice("modal", "plane", m, &M::plane, modal_plane_names,
               "plane strain (as the runs) or plane stress (thesis appendix B's numbers)"),
        integer("modal", "modes", m, &M::modes, 1, 200,
                "elastic modes wanted, lowest first (rigid-body modes removed)"),
    };
  }();
  return all;
}

const Key *findKey(const std::string &table, const std::string &name) {
  for (const auto &k : keys())
    if (k.table == table && k.name == name)
      return &k;
  return nullptr;
}

std::string knownIn(const std::string &table) {
  std::string s;
  for (const auto &k : keys())
    if (k.table == table)
      s += (s.empty() ? "" : ", ") + k.name;
  return s;
}

// Checks that involve more than one key.
void checkTogether(const Scene &s) {
  const TargetSpec &t = s.target;
  auto bad = [&](const std::string &what) { throw InputError(s.path + ": " + what); };
  if (t.width < 4 * t.diameter_max || t.height < 4 * t.diameter_max)
    bad("target.width and target.height must be at least 4 grain diameters (" +
        show(4 * t.diameter_max) + " m); they are " + show(t.width) + " and " + show(t.height));
  if (t.mesh_size > 0.5 * t.diameter_min)
    bad("target.mesh_size = " + show(t.mesh_size) +
        " is more than half the smallest grain diameter; " +
        "allowed: mesh_size <= " + show(0.5 * t.diameter_min) + " [m]");
  // What the target will hold, against what fits in this machine's memory (about 350 bytes a site
  // and 200 a triangle, measured).
  const double grains =
      t.area() * (1 - t.porosity) / (M_PI * t.meanDiameter() * t.meanDiameter() / 4);
  const double void_d = t.void_ratio * t.meanDiameter();
  const double sites = grains + t.void_scale * t.area() * t.porosity / (M_PI * void_d * void_d / 4);
  if (sites > 5.0e7)
    bad("target.width x target.height, target.diameter, target.porosity, target.void_ratio and "
        "target.void_scale give about " +
        show(sites) + " grain and void sites; allowed: at most 5e7");
  if (t.mesh != MeshKind::none) {
    const double triangles = t.area() * (1 - t.porosity) / (0.43 * t.mesh_size * t.mesh_size);
    if (triangles > 5.0e7)
      bad("target.mesh_size = " + show(t.mesh_size) + " gives about " + show(triangles) +
          " triangles; allowed: at most 5e7 (a larger mesh_size, or mesh = \"none\")");
  }
  if (s.projectile.enabled) {
    const bool plate = s.projectile.shape == ProjectileKind::plate;
    const double d = plate ? t.width : s.projectile.length / s.projectile.length_over_diameter;
    const double h = s.projectile.mesh_size > 0 ? s.projectile.mesh_size : t.mesh_size;
    const double triangles = s.projectile.length * d / (0.43 * h * h);
    if (triangles > 5.0e7)
      bad("projectile.length = " + show(s.projectile.length) +
          (plate ? " (a plate as wide as the box)" : "") + " at a mesh size of " + show(h) +
          " m gives about " + show(triangles) +
          " triangles; allowed: at most 5e7 (a larger projectile.mesh_size)");
  }
  const ModalSpec &m = s.modal;
  if (m.body == ModalBody::projectile && m.support == ModalSupport::clamped)
    bad("modal.support = \"clamped\" holds a beam's left end; the projectile is free; allowed: "
        "\"free\" with modal.body = \"projectile\"");
  if (m.body == ModalBody::beam) {
    const double size = m.mesh_size > 0 ? m.mesh_size : m.height / 10;
    if (size > m.height || size > m.length)
      bad("modal.mesh_size = " + show(size) + " is larger than the beam (" + show(m.length) +
          " x " + show(m.height) +
          " m); allowed: mesh_size <= " + show(std::min(m.length, m.height)));
    if (m.length * m.height / (0.43 * size * size) > 5.0e6)
      bad("modal.mesh_size = " + show(size) + " gives about " +
          show(m.length * m.height / (0.43 * size * size)) +
          " triangles for the beam; allowed: at most 5e6");
  }
  if (s.projectile.enabled &&
      std::abs(s.run.offset) + 0.5 * s.projectile.length / s.projectile.length_over_diameter >
          0.5 * s.target.width)
    bad("run.offset = " + show(s.run.offset) + " puts the projectile (diameter " +
        show(s.projectile.length / s.projectile.length_over_diameter) +
        " m) past the box's side; allowed: |offset| <= " +
        show(0.5 * s.target.width - 0.5 * s.projectile.length / s.projectile.length_over_diameter));
  if (s.run.constant_velocity && s.run.spin != 0.0)
    bad("run.spin = " + show(s.run.spin) +
        " with run.constant_velocity = true (a velocity held "
        "without rotation); allowed: 0");
  if (s.projectile.enabled && s.projectile.shape == ProjectileKind::ogive) {
    try {
      projectileShape(s.projectile);
    } catch (const std::invalid_argument &e) {
      bad(std::string("[projectile]: ") + e.what());
    }
  }
}

// "a", "b", "c": the names of the material presets or types.
template <class List> std::string quotedNames(const List &list) {
  std::string s;
  for (const auto &item : list) {
    s += s.empty() ? "\"" : ", \"";
    s += item.name;
    s += '"';
  }
  return s;
}

// What a parameter allows: its closed range, or true/false for a switch.
std::string parameterRange(const fem::ParameterInfo &p) {
  if (p.boolean)
    return "true or false";
  return show(p.lo) + " <= " + p.name + " <= " + show(p.hi);
}

// What a parameter allows, with its unit, for messages.
std::string parameterAllowed(const fem::ParameterInfo &p) {
  return parameterRange(p) + (p.unit.empty() ? "" : " [" + p.unit + "]");
}

// `preset = NAME` or `type = NAME` of a material table; the current choice when neither is given.
std::string materialName(const std::string &where, const toml::table &tab,
                         const std::string &current) {
  if (tab.contains("preset") && tab.contains("type"))
    throw InputError(where + ": give preset or type, not both");
  for (const std::string key : {"preset", "type"}) {
    const toml::node *node = tab.get(key);
    if (!node)
      continue;
    const auto *str = node->as_string();
    const bool preset = key == "preset";
    if (!str || !(preset ? fem::findMaterialPreset(str->get()) != nullptr
                         : fem::findMaterialType(str->get()) != nullptr))
      throw InputError(
          where + "." + key + " = " + tomlText(*node) + " is not known; allowed: one of " +
          (preset ? quotedNames(fem::materialPresets()) : quotedNames(fem::materialTypes())));
    return str->get();
  }
  return current;
}

// A parameter's value as a scene writes it.
std::string parameterText(const fem::ParameterInfo &p, double value) {
  return p.boolean ? (value != 0 ? "true" : "false") : exact(value);
}

// One parameter of a material type: a number in its range, or true/false for a switch.
double parameterValue(const std::string &where, const fem::MaterialType &type,
                      const std::string &key, const toml::node &node) {
  const fem::ParameterInfo *info = nullptr;
  std::string known;
  for (const auto &p : type.parameters) {
    known += ", ";
    known += p.name;
    if (p.name == key)
      info = &p;
  }
  if (!info)
    throw InputError(where + "." + key + " = " + tomlText(node) + ": material type \"" + type.name +
                     "\" has no such parameter; known: preset, type" + known);
  double value = NAN;
  if (const auto *b = node.as_boolean(); b && info->boolean)
    value = b->get() ? 1.0 : 0.0;
  else if (const auto *f = node.as_floating_point(); f && !info->boolean)
    value = f->get();
  else if (const auto *i = node.as_integer(); i && !info->boolean)
    value = static_cast<double>(i->get());
  else
    throw InputError(where + "." + key + " = " + tomlText(node) + " is not " +
                     (info->boolean ? "true or false" : "a number") +
                     "; allowed: " + parameterAllowed(*info));
  if (!(value >= info->lo && value <= info->hi))
    throw InputError(where + "." + key + " = " + tomlText(node) +
                     " is out of range; allowed: " + parameterAllowed(*info));
  return value;
}

// [materials.projectile] and [materials.grains]: `preset` or `type`, then parameters by name.
void readMaterials(Scene &scene, const toml::node &node) {
  const std::string &path = scene.path;
  const toml::table *groups = node.as_table();
  if (!groups)
    throw InputError(path +
                     ": materials must be a table ([materials.projectile], [materials.grains])");
  for (const auto &[gname, gnode] : *groups) {
    const std::string group(gname.str());
    MaterialChoice *choice = group == "projectile" ? &scene.projectile_material
                             : group == "grains"   ? &scene.grain_material
                                                   : nullptr;
    const toml::table *tab = gnode.as_table();
    if (!choice || !tab)
      throw InputError(path + ": unknown material table [materials." + group +
                       "]; known: [materials.projectile], [materials.grains]");
    const std::string where = path + ": materials." + group;
    choice->name = materialName(where, *tab, choice->name);
    choice->parameters.clear();
    const fem::MaterialPreset *preset = fem::findMaterialPreset(choice->name);
    const fem::MaterialType &type = *fem::findMaterialType(preset ? preset->type : choice->name);
    for (const auto &[kname, knode] : *tab) {
      const std::string key(kname.str());
      if (key != "preset" && key != "type")
        choice->parameters[key] = parameterValue(where, type, key, knode);
    }
    try {
      fem::completeParameters(type, preset, choice->parameters);
    } catch (const std::invalid_argument &e) {
      throw InputError(where + ": " + e.what());
    }
  }
}

} // namespace

std::string tomlText(const toml::node &n) {
  std::ostringstream s;
  n.visit([&](const auto &v) { s << v; });
  // a message names the value, it does not echo a megabyte of it
  constexpr std::size_t longest = 80;
  std::string text = s.str();
  if (text.size() > longest)
    text = text.substr(0, longest) + "... (" + std::to_string(text.size()) + " characters)";
  return text;
}

toml::table parseToml(const std::string &path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw InputError(path + ": no such file; allowed: a scene file (TOML)");
  if (!std::filesystem::is_regular_file(path, ec))
    throw InputError(path + ": not a file (a directory?); allowed: a scene file (TOML)");
  try {
    return toml::parse_file(path);
  } catch (const toml::parse_error &e) {
    const auto &b = e.source().begin;
    throw InputError(path + ":" + std::to_string(b.line) + ":" + std::to_string(b.column) +
                     ": not valid TOML: " + std::string(e.description()));
  }
}

Scene readScene(const std::string &path) { return readScene(parseToml(path), path); }

void DemSpec::apply(DemPreset p) {
  preset = p;
  stiffness = coupling::quartz_grains.kn, tangential_stiffness = coupling::quartz_grains.kt;
  damping = coupling::quartz_grains.gn, tangential_damping = coupling::quartz_grains.gt;
  const bool bulk = p == DemPreset::quartz_bulk;
  disk_size = bulk ? DiskSize::equal_area : DiskSize::inscribed;
  normal_law = bulk ? NormalLaw::hertz : NormalLaw::hooke;
  // quartz-bulk: the calibration's choices (tools/studies/calibrate_dem.py, docs/coupling.md)
  hertz_length = 8e-6;
  rolling_friction = bulk ? 0.1 : 0.0;
}

Scene readScene(const toml::table &root, const std::string &path) {
  Scene scene;
  scene.path = path;
  for (const auto &[tname, tnode] : root) {
    const std::string table(tname.str());
    if (table == "materials") {
      readMaterials(scene, tnode);
      continue;
    }
    if (knownIn(table).empty())
      throw InputError(path + ": unknown table [" + table +
                       "]; known tables: target, projectile, run, contact, modal, materials");
    const toml::table *tab = tnode.as_table();
    if (!tab)
      throw InputError(path + ": " + table + " must be a table ([" + table + "])");
    if (const toml::node *preset = tab->get("preset"); preset && findKey(table, "preset"))
      findKey(table, "preset")->set(scene, *preset, path); // before the keys it may set
    for (const auto &[kname, knode] : *tab) {
      if (kname.str() == "preset" && findKey(table, "preset"))
        continue;
      const Key *k = findKey(table, std::string(kname.str()));
      if (!k)
        throw InputError(path + ": unknown key " + table + "." + std::string(kname.str()) +
                         "; known keys in [" + table + "]: " + knownIn(table));
      k->set(scene, knode, path);
    }
  }
  checkTogether(scene);
  return scene;
}

std::string sceneKeysMarkdown() {
  const Scene defaults;
  std::ostringstream out;
  out << "| key | type | default | allowed | unit | meaning |\n|---|---|---|---|---|---|\n";
  for (const auto &k : keys())
    out << "| " << k.table << "." << k.name << " | " << k.type << " | " << k.get(defaults) << " | "
        << allowed(k) << " | " << k.unit << " | " << k.doc << " |\n";
  out << "\n## Materials\n\n"
         "[materials.projectile] (default preset \"steel\") and [materials.grains] "
         "(default preset \"quartz\") take `preset = NAME` or `type = NAME`, then any parameter of "
         "that type by name.\n\n"
         "| preset | type | values (beside the type's defaults) | meaning |\n|---|---|---|---|\n";
  for (const auto &p : fem::materialPresets()) {
    const fem::MaterialType &type = *fem::findMaterialType(p.type);
    std::string values;
    for (const auto &info : type.parameters)
      if (auto v = p.values.find(info.name); v != p.values.end()) {
        values += values.empty() ? "" : ", ";
        values += info.name + " = " + parameterText(info, v->second);
      }
    out << "| " << p.name << " | " << p.type << " | " << values << " | " << p.doc << " |\n";
  }
  for (const auto &t : fem::materialTypes()) {
    out << "\n### type \"" << t.name << "\"\n\n"
        << t.doc << "\n\n"
        << "| parameter | type | default | allowed | unit | meaning |\n|---|---|---|---|---|---|\n";
    for (const auto &p : t.parameters)
      out << "| " << p.name << " | " << (p.boolean ? "bool" : "real") << " | "
          << parameterText(p, p.value) << " | " << parameterRange(p) << " | " << p.unit << " | "
          << p.doc << " |\n";
  }
  return out.str();
}

} // namespace mesopen

namespace mesopen {

std::string composedScene(const Scene &scene) {
  std::string text = "# The scene as run: every key at its value (defaults included), every\n"
                     "# material parameter resolved. `mesopen run` reads it back to the same "
                     "scene.\n";
  std::string table;
  for (const Key &k : keys()) {
    if (k.table != table) {
      table = k.table;
      text += "\n[" + table + "]\n";
      if (const Key *preset = findKey(table, "preset")) // first: it sets the keys below
        text += "preset = " + preset->get(scene) + "\n";
    }
    if (k.name != "preset")
      text += k.name + " = " + k.get(scene) + "\n";
  }
  for (const auto &[group, choice] : materialGroups(scene)) {
    const fem::MaterialPreset *preset = fem::findMaterialPreset(choice->name);
    const fem::MaterialType &type = *fem::findMaterialType(preset ? preset->type : choice->name);
    text += std::string("\n[materials.") + group + "]\n" + materialKey(*choice) + " = \"" +
            choice->name + "\"\n";
    const fem::Parameters values = resolvedParameters(*choice);
    for (const fem::ParameterInfo &info : type.parameters)
      text += info.name + " = " + parameterText(info, values.at(info.name)) + "\n";
  }
  return text;
}

std::array<std::pair<const char *, const MaterialChoice *>, 2> materialGroups(const Scene &scene) {
  return {{{"projectile", &scene.projectile_material}, {"grains", &scene.grain_material}}};
}

const char *materialKey(const MaterialChoice &choice) {
  return fem::findMaterialPreset(choice.name) ? "preset" : "type";
}

fem::Parameters resolvedParameters(const MaterialChoice &choice) {
  const fem::MaterialPreset *preset = fem::findMaterialPreset(choice.name);
  const fem::MaterialType &type = *fem::findMaterialType(preset ? preset->type : choice.name);
  return fem::completeParameters(type, preset, choice.parameters);
}

} // namespace mesopen
