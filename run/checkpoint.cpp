// Layout of DIR/checkpoint/state.h5 (SI units, per metre of depth as run.h5):
//   attributes of /: format = "mesopen-checkpoint", version, number (N), scene_path, ranks,
//     fingerprint (of the model's mesh), time, step, wall (seconds of the run so far), liggghts
//     (its restart file's name, or "")
//   /scene (uint8): the scene composed (scene.toml's text: every key, the seed among them)
//   /model/nodes/{x, y, vx, vy, fx, fy, mass, area0, detached, loaded, external (loaded x 4:
//     fx, fy, friction_x, friction_y)}
//   /model/elements/{area, sxx, syy, sxy, pressure, energy, plastic_strain, viscosity, eroded}
//   /model/bodies/{eroded, at_rest, boundary, boundary_offset}
//   /solver (attributes: fem::Solver::State's numbers, energy_*), {scaled_elements, scaled_mass,
//     energy_shares (with several ranks: each rank's share of the energies, 9 a rank), owner
//     (with several ranks: each body's rank; attributes ranks, and achieved, total: the
//     partition's imbalance and load when made)}
//   /solver/levels (with run.max_level > 0; attributes element_steps, single_rate_element_steps):
//     {level, own_level, due, model_level, part_level, part_own_level (uint8), step_min, kinetic,
//     internal, window, own_step, level_start, element_step, part_step_min, part_weight,
//     part_force, window_start} (fem::Solver::State::Levels)
//   /contact/{pairs, travel, travel_searched, listed, boxes, points, allowed, allowance, rate,
//     pushed, pushed_depth, statistics (its bytes)}, attribute search_due; with levels
//     /contact/levels (attribute pushed_levels): {pushed, depth, time, penalty_step}
//   /series/{time, dt, step, values (samples x columns)}, attribute columns (names, one a line)
//   /frames: attribute next, {times}
//   /loop: attributes element_steps, seconds, solver_seconds
//   /disks/{id, forces (n x 3: fx, fy, torque)}  with disks: their own forces, by id
// coupling-NNNNNN-rR.h5: attributes windows, seconds; {carried_id, carried (n x 3), size, held,
//   last, now, allowance, rate, grid_body, grid_box, grid_x, grid_y, statistics (its bytes)}.
#include "checkpoint.hpp"

#include "stop_signals.hpp"

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <type_traits>

#include <fcntl.h>
#include <unistd.h>

namespace mesopen {

namespace fs = std::filesystem;

namespace {

constexpr int format_version = 2;

std::string statePath(const std::string &dir) { return dir + "/checkpoint/state.h5"; }

// FNV-1a over the model's mesh and its bodies: a checkpoint is taken only by the model it was
// written from.
std::uint64_t fingerprint(const fem::Model &model) {
  std::uint64_t h = 1469598103934665603ull;
  auto add = [&](const void *data, std::size_t bytes) {
    const auto *p = static_cast<const unsigned char *>(data);
    for (std::size_t i = 0; i < bytes; ++i)
      h = (h ^ p[i]) * 1099511628211ull;
  };
  auto addVector = [&](const auto &v) { add(v.data(), v.size() * sizeof(v[0])); };
  addVector(model.nodes.x0), addVector(model.nodes.y0), addVector(model.nodes.body);
  addVector(model.elements.node), addVector(model.elements.body);
  const std::uint64_t bodies = model.bodies.size();
  add(&bodies, sizeof bodies);
  return h;
}

// A dataset read back, checked to hold `n` values (a damaged or foreign checkpoint is refused).
template <H5Number T>
std::vector<T> readSized(const H5File &h5, const std::string &name, std::size_t n) {
  std::vector<T> v = h5.read<T>(name);
  if (v.size() != n)
    throw std::runtime_error(name + " holds " + std::to_string(v.size()) + " values, not " +
                             std::to_string(n));
  return v;
}

// A trivially copyable struct (figures of a run) as bytes, and back.
template <class T> std::vector<std::uint8_t> bytesOf(const T &value) {
  static_assert(std::is_trivially_copyable_v<T>);
  std::vector<std::uint8_t> b(sizeof(T));
  std::memcpy(b.data(), &value, sizeof(T));
  return b;
}
template <class T> T fromBytes(const H5File &h5, const std::string &name) {
  const std::vector<std::uint8_t> b = readSized<std::uint8_t>(h5, name, sizeof(T));
  T value;
  std::memcpy(&value, b.data(), sizeof(T));
  return value;
}

void syncFile(const std::string &path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

// --- the model's state ---------------------------------------------------------------------

// The nodes' and the elements' arrays a checkpoint holds, by name (/model/nodes/NAME,
// /model/elements/NAME).
const std::pair<const char *, std::vector<double> fem::Nodes::*> node_arrays[] = {
    {"x", &fem::Nodes::x},       {"y", &fem::Nodes::y},        {"vx", &fem::Nodes::vx},
    {"vy", &fem::Nodes::vy},     {"fx", &fem::Nodes::fx},      {"fy", &fem::Nodes::fy},
    {"mass", &fem::Nodes::mass}, {"area0", &fem::Nodes::area0}};
const std::pair<const char *, std::vector<double> fem::Elements::*> element_arrays[] = {
    {"area", &fem::Elements::area},
    {"sxx", &fem::Elements::sxx},
    {"syy", &fem::Elements::syy},
    {"sxy", &fem::Elements::sxy},
    {"pressure", &fem::Elements::pressure},
    {"energy", &fem::Elements::energy},
    {"plastic_strain", &fem::Elements::plastic_strain},
    {"viscosity", &fem::Elements::viscosity}};

void writeModel(H5File &h5, const fem::Model &model) {
  const fem::Nodes &nd = model.nodes;
  const fem::Elements &el = model.elements;
  for (const char *g : {"/model", "/model/nodes", "/model/elements", "/model/bodies"})
    h5.createGroup(g);
  for (auto [name, array] : node_arrays)
    h5.write(std::string("/model/nodes/") + name, nd.*array);
  h5.write("/model/nodes/detached", nd.detached);
  std::vector<double> external;
  for (std::uint32_t a : nd.loaded) {
    const fem::Nodes::External &e = nd.external[a];
    external.insert(external.end(), {e.fx, e.fy, e.friction_x, e.friction_y});
  }
  h5.write("/model/nodes/loaded", nd.loaded);
  h5.write("/model/nodes/external", external, nd.loaded.size(), 4);
  for (auto [name, array] : element_arrays)
    h5.write(std::string("/model/elements/") + name, el.*array);
  h5.write("/model/elements/eroded", el.eroded);
  std::vector<std::uint64_t> eroded, offset{0};
  std::vector<std::uint32_t> boundary;
  for (const fem::Body &b : model.bodies) {
    eroded.push_back(b.eroded);
    boundary.insert(boundary.end(), b.boundary.begin(), b.boundary.end());
    offset.push_back(boundary.size());
  }
  h5.write("/model/bodies/eroded", eroded);
  h5.write("/model/bodies/at_rest", model.at_rest);
  h5.write("/model/bodies/boundary", boundary);
  h5.write("/model/bodies/boundary_offset", offset);
}

void readModel(const H5File &h5, fem::Model &model) {
  fem::Nodes &nd = model.nodes;
  fem::Elements &el = model.elements;
  const std::size_t n = nd.size(), m = el.size(), b = model.bodies.size();
  for (auto [name, array] : node_arrays)
    nd.*array = readSized<double>(h5, std::string("/model/nodes/") + name, n);
  nd.detached = readSized<std::uint8_t>(h5, "/model/nodes/detached", n);
  const std::vector<std::uint32_t> loaded = h5.read<std::uint32_t>("/model/nodes/loaded");
  const std::vector<double> external =
      readSized<double>(h5, "/model/nodes/external", 4 * loaded.size());
  nd.clearExternal();
  for (std::size_t k = 0; k < loaded.size(); ++k) {
    const std::uint32_t a = loaded[k];
    if (a >= n || nd.is_loaded[a])
      throw std::runtime_error("/model/nodes/loaded holds a node twice or not of the model");
    nd.is_loaded[a] = 1, nd.loaded.push_back(a);
    nd.external[a] = {external[4 * k], external[4 * k + 1], external[4 * k + 2],
                      external[4 * k + 3]};
  }
  for (auto [name, array] : element_arrays)
    el.*array = readSized<double>(h5, std::string("/model/elements/") + name, m);
  el.eroded = readSized<std::uint8_t>(h5, "/model/elements/eroded", m);
  const auto eroded = readSized<std::uint64_t>(h5, "/model/bodies/eroded", b);
  model.at_rest = readSized<std::uint8_t>(h5, "/model/bodies/at_rest", b);
  const auto boundary = h5.read<std::uint32_t>("/model/bodies/boundary");
  const auto offset = readSized<std::uint64_t>(h5, "/model/bodies/boundary_offset", b + 1);
  for (std::size_t k = 0; k < b; ++k) {
    fem::Body &body = model.bodies[k];
    if (offset[k] > offset[k + 1] || offset[k + 1] > boundary.size())
      throw std::runtime_error("/model/bodies/boundary_offset is not of the boundaries");
    body.eroded = eroded[k];
    body.boundary.assign(boundary.begin() + static_cast<long>(offset[k]),
                         boundary.begin() + static_cast<long>(offset[k + 1]));
    for (std::uint32_t a : body.boundary)
      if (a < body.node_begin || a >= body.node_end)
        throw std::runtime_error("/model/bodies/boundary holds a node of another body");
  }
}

// --- the solver's and the contact's states --------------------------------------------------

// The solver's numbers, by name (attributes of /solver).
struct SolverNumbers {
  double fem::Solver::State::*field;
  const char *name;
};
constexpr SolverNumbers solver_numbers[] = {
    {&fem::Solver::State::time, "time"},
    {&fem::Solver::State::dt, "dt"},
    {&fem::Solver::State::next_dt, "next_dt"},
    {&fem::Solver::State::shortest_allowed, "shortest_allowed"},
    {&fem::Solver::State::first_dt, "first_dt"},
    {&fem::Solver::State::erode_below, "erode_below"},
    {&fem::Solver::State::scale_below, "scale_below"},
    {&fem::Solver::State::shortest_step, "shortest_step"}};
struct EnergyNumbers {
  double fem::Energy::*field;
  const char *name;
};
constexpr EnergyNumbers energy_numbers[] = {{&fem::Energy::kinetic, "energy_kinetic"},
                                            {&fem::Energy::internal, "energy_internal"},
                                            {&fem::Energy::plastic, "energy_plastic"},
                                            {&fem::Energy::viscous, "energy_viscous"},
                                            {&fem::Energy::friction, "energy_friction"},
                                            {&fem::Energy::contact, "energy_contact"},
                                            {&fem::Energy::external, "energy_external"},
                                            {&fem::Energy::eroded, "energy_eroded"},
                                            {&fem::Energy::mass_scaling, "energy_mass_scaling"},
                                            {&fem::Energy::initial, "energy_initial"},
                                            {&fem::Energy::balance_error, "balance_error"}};

// The levels' arrays (multiple time stepping), by name (/solver/levels/NAME).
using Levels = fem::Solver::State::Levels;
const std::pair<const char *, std::vector<std::uint8_t> Levels::*> level_bytes[] = {
    {"level", &Levels::level},
    {"own_level", &Levels::own_level},
    {"due", &Levels::due},
    {"model_level", &Levels::model_level},
    {"part_level", &Levels::part_level},
    {"part_own_level", &Levels::part_own_level}};
const std::pair<const char *, std::vector<double> Levels::*> level_values[] = {
    {"step_min", &Levels::step_min},         {"kinetic", &Levels::kinetic},
    {"internal", &Levels::internal},         {"window", &Levels::window},
    {"own_step", &Levels::own_step},         {"level_start", &Levels::level_start},
    {"element_step", &Levels::element_step}, {"part_step_min", &Levels::part_step_min},
    {"part_weight", &Levels::part_weight},   {"part_force", &Levels::part_force},
    {"window_start", &Levels::window_start}};

void writeLevels(H5File &h5, const Levels &st) {
  h5.createGroup("/solver/levels");
  for (auto [name, array] : level_bytes)
    h5.write(std::string("/solver/levels/") + name, st.*array);
  for (auto [name, array] : level_values)
    h5.write(std::string("/solver/levels/") + name, st.*array);
  h5.attribute("/solver/levels", "element_steps", st.element_steps);
  h5.attribute("/solver/levels", "single_rate_element_steps", st.single_rate_element_steps);
}

Levels readLevels(const H5File &h5) {
  Levels st;
  for (auto [name, array] : level_bytes)
    st.*array = h5.read<std::uint8_t>(std::string("/solver/levels/") + name);
  for (auto [name, array] : level_values)
    st.*array = h5.read<double>(std::string("/solver/levels/") + name);
  st.element_steps = h5.readAttribute<double>("/solver/levels", "element_steps");
  st.single_rate_element_steps =
      h5.readAttribute<double>("/solver/levels", "single_rate_element_steps");
  return st;
}

void writeSolver(H5File &h5, const fem::Solver::State &st) {
  h5.createGroup("/solver");
  for (auto [field, name] : solver_numbers)
    h5.attribute("/solver", name, st.*field);
  for (auto [field, name] : energy_numbers)
    h5.attribute("/solver", name, st.energy.*field);
  h5.attribute("/solver", "steps", st.steps);
  h5.attribute("/solver", "eroded_elements", st.eroded_elements);
  h5.attribute("/solver", "collapsed_elements", st.collapsed_elements);
  h5.write("/solver/scaled_elements", st.scaled_elements);
  h5.write("/solver/scaled_mass", st.scaled_mass);
  if (!st.energy_shares.empty())
    h5.write("/solver/energy_shares", st.energy_shares);
  if (!st.levels.level.empty())
    writeLevels(h5, st.levels);
  if (!st.owner.empty()) {
    h5.write("/solver/owner", std::vector<std::int32_t>(st.owner.begin(), st.owner.end()));
    h5.attribute("/solver/owner", "ranks", st.partition_ranks);
    h5.attribute("/solver/owner", "achieved", st.partition_achieved);
    h5.attribute("/solver/owner", "total", st.partition_total);
  }
}

fem::Solver::State readSolver(const H5File &h5) {
  fem::Solver::State st;
  for (auto [field, name] : solver_numbers)
    st.*field = h5.readAttribute<double>("/solver", name);
  for (auto [field, name] : energy_numbers)
    st.energy.*field = h5.readAttribute<double>("/solver", name);
  st.steps = h5.readAttribute<std::uint64_t>("/solver", "steps");
  st.eroded_elements = h5.readAttribute<std::uint64_t>("/solver", "eroded_elements");
  st.collapsed_elements = h5.readAttribute<std::uint64_t>("/solver", "collapsed_elements");
  st.scaled_elements = h5.read<std::uint32_t>("/solver/scaled_elements");
  st.scaled_mass = readSized<double>(h5, "/solver/scaled_mass", st.scaled_elements.size());
  if (h5.exists("/solver/energy_shares"))
    st.energy_shares = h5.read<double>("/solver/energy_shares");
  if (h5.exists("/solver/levels"))
    st.levels = readLevels(h5);
  if (h5.exists("/solver/owner")) {
    const std::vector<std::int32_t> owner = h5.read<std::int32_t>("/solver/owner");
    st.owner.assign(owner.begin(), owner.end());
    st.partition_ranks = h5.readAttribute<int>("/solver/owner", "ranks");
    st.partition_achieved = h5.readAttribute<double>("/solver/owner", "achieved");
    st.partition_total = h5.readAttribute<double>("/solver/owner", "total");
  }
  return st;
}

void writeContact(H5File &h5, const fem::Contact::State &st) {
  h5.createGroup("/contact");
  h5.attribute("/contact", "search_due", static_cast<std::uint8_t>(st.search_due));
  h5.write("/contact/pairs", st.pairs);
  h5.write("/contact/travel", st.travel);
  h5.write("/contact/travel_searched", st.travel_searched);
  h5.write("/contact/listed", st.listed);
  h5.write("/contact/boxes", st.boxes);
  h5.write("/contact/points", st.points);
  h5.write("/contact/allowed", st.allowed);
  h5.write("/contact/allowance", st.allowance);
  h5.write("/contact/rate", st.rate);
  h5.write("/contact/pushed", st.pushed);
  h5.write("/contact/pushed_depth", st.pushed_depth);
  if (st.pushed_levels > 0) {
    h5.createGroup("/contact/levels");
    h5.attribute("/contact/levels", "pushed_levels", st.pushed_levels);
    h5.write("/contact/levels/pushed", st.level_pushed);
    h5.write("/contact/levels/depth", st.level_pushed_depth);
    h5.write("/contact/levels/time", st.level_pushed_time);
    h5.write("/contact/levels/penalty_step", st.level_pushed_penalty);
  }
  h5.write("/contact/statistics", bytesOf(st.statistics));
}

fem::Contact::State readContact(const H5File &h5) {
  fem::Contact::State st;
  st.search_due = h5.readAttribute<std::uint8_t>("/contact", "search_due") != 0;
  st.pairs = h5.read<std::uint32_t>("/contact/pairs");
  st.travel = h5.read<double>("/contact/travel");
  st.travel_searched = h5.read<double>("/contact/travel_searched");
  st.listed = h5.read<std::uint8_t>("/contact/listed");
  st.boxes = h5.read<double>("/contact/boxes");
  st.points = h5.read<double>("/contact/points");
  st.allowed = h5.read<std::uint32_t>("/contact/allowed");
  st.allowance = h5.read<double>("/contact/allowance");
  st.rate = h5.read<double>("/contact/rate");
  st.pushed = h5.read<std::uint32_t>("/contact/pushed");
  st.pushed_depth = h5.read<double>("/contact/pushed_depth");
  if (h5.exists("/contact/levels")) {
    st.pushed_levels = h5.readAttribute<std::uint64_t>("/contact/levels", "pushed_levels");
    st.level_pushed = h5.read<std::uint64_t>("/contact/levels/pushed");
    st.level_pushed_depth = h5.read<double>("/contact/levels/depth");
    st.level_pushed_time = h5.read<double>("/contact/levels/time");
    st.level_pushed_penalty = h5.read<double>("/contact/levels/penalty_step");
  }
  st.statistics = fromBytes<fem::ContactStatistics>(h5, "/contact/statistics");
  return st;
}

void writeDiskForces(H5File &h5, const std::string &group,
                     const std::vector<coupling::DiskForce> &forces) {
  std::vector<std::int64_t> id;
  std::vector<double> values;
  for (const coupling::DiskForce &f : forces)
    id.push_back(f.id), values.insert(values.end(), {f.fx, f.fy, f.torque});
  h5.write(group + "_id", id);
  h5.write(group, values, forces.size(), 3);
}

std::vector<coupling::DiskForce> readDiskForces(const H5File &h5, const std::string &group) {
  const std::vector<std::int64_t> id = h5.read<std::int64_t>(group + "_id");
  const std::vector<double> values = readSized<double>(h5, group, 3 * id.size());
  std::vector<coupling::DiskForce> forces;
  for (std::size_t k = 0; k < id.size(); ++k)
    forces.push_back({id[k], values[3 * k], values[3 * k + 1], values[3 * k + 2]});
  return forces;
}

// The FE-DEM contact's arrays a checkpoint holds, by name.
const std::pair<const char *, std::vector<double> coupling::DiskContact::State::*>
    disk_contact_arrays[] = {{"/last", &coupling::DiskContact::State::last},
                             {"/now", &coupling::DiskContact::State::now},
                             {"/allowance", &coupling::DiskContact::State::allowance},
                             {"/rate", &coupling::DiskContact::State::rate},
                             {"/grid_box", &coupling::DiskContact::State::grid_box},
                             {"/grid_x", &coupling::DiskContact::State::grid_x},
                             {"/grid_y", &coupling::DiskContact::State::grid_y}};

void writeCoupling(const std::string &path, const coupling::FeDemCoupling::State &st) {
  writeAtomically(path, [&](const std::string &temp) {
    H5File h5 = H5File::create(temp);
    h5.attribute("/", "windows", st.windows);
    h5.attribute("/", "seconds", st.seconds);
    writeDiskForces(h5, "/carried", st.carried);
    const coupling::DiskContact::State &c = st.contact;
    h5.write("/size", c.size);
    h5.write("/held", c.held);
    for (auto [name, array] : disk_contact_arrays)
      h5.write(name, c.*array);
    h5.write("/grid_body", c.grid_body);
    h5.write("/statistics", bytesOf(c.statistics));
    h5.close();
    syncFile(temp);
  });
}

coupling::FeDemCoupling::State readCoupling(const std::string &path) {
  const H5File h5 = H5File::open(path);
  coupling::FeDemCoupling::State st;
  st.windows = h5.readAttribute<std::uint64_t>("/", "windows");
  st.seconds = h5.readAttribute<double>("/", "seconds");
  st.carried = readDiskForces(h5, "/carried");
  coupling::DiskContact::State &c = st.contact;
  c.size = h5.read<double>("/size");
  c.held = h5.read<std::int64_t>("/held");
  for (auto [name, array] : disk_contact_arrays)
    c.*array = h5.read<double>(name);
  c.grid_body = h5.read<std::uint32_t>("/grid_body");
  c.statistics = fromBytes<coupling::DiskContactStatistics>(h5, "/statistics");
  return st;
}

} // namespace

// --- the checkpoint's scene and directory -----------------------------------------------------

Scene checkpointScene(const std::string &dir) {
  const std::string path = statePath(dir);
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    throw InputError(dir + ": no checkpoint to continue from (" + path +
                     " not found); allowed: the output directory of a run with "
                     "run.checkpoint_interval or run.checkpoint_time that did not complete");
  std::string text, scene_path;
  try {
    const H5File h5 = H5File::open(path);
    if (!h5.hasAttribute("/", "format") ||
        h5.readStringAttribute("/", "format") != "mesopen-checkpoint" ||
        h5.readAttribute<int>("/", "version") != format_version)
      throw std::runtime_error("not a checkpoint of this version of mesopen (format " +
                               std::to_string(format_version) + ")");
    const std::vector<std::uint8_t> bytes = h5.read<std::uint8_t>("/scene");
    text.assign(bytes.begin(), bytes.end());
    scene_path = h5.readStringAttribute("/", "scene_path");
  } catch (const std::runtime_error &e) {
    throw InputError(path + ": not a whole checkpoint: " + e.what());
  }
  toml::table root;
  try {
    root = toml::parse(text, scene_path);
  } catch (const toml::parse_error &e) {
    throw InputError(path + ": its scene (" + scene_path +
                     ") is not valid TOML: " + std::string(e.description()));
  }
  return readScene(root, scene_path);
}

std::string checkpointRestart(const std::string &dir) {
  const H5File h5 = H5File::open(statePath(dir));
  const std::string name = h5.readStringAttribute("/", "liggghts");
  return name.empty() ? name : dir + "/checkpoint/" + name;
}

bool takeResumedDirectory(const std::string &dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw InputError(dir + ": no such directory; allowed: the output directory of a run with "
                           "checkpoints");
  if (!lockForProcess(dir + "/.run.lock", false))
    return false;
  fs::remove(dir + "/run.h5.tmp", ec);
  return true;
}

// --- checkpoints ------------------------------------------------------------------------------

Checkpoints::Checkpoints(const Scene &scene, const std::string &dir, RunAssembly &run,
                         Series &series, Frames &frames, H5File *h5, const parallel::World &world,
                         bool resume)
    : scene_(scene), dir_(dir), checkpoint_dir_(dir + "/checkpoint"), run_(run), series_(series),
      frames_(frames), h5_(h5), world_(world), on_(scene.run.checkpoints()), resumed_(resume),
      last_wall_(Clock::now()), start_(Clock::now()) {
  if (const char *stop = std::getenv("MESOPEN_STOP_AT_STEP"))
    stop_at_ = std::strtoull(stop, nullptr, 10);
  if (scene.run.checkpoint_time > 0.0)
    next_time_ = scene.run.checkpoint_time;
  if (resume) {
    try {
      this->resume();
    } catch (const InputError &) {
      throw;
    } catch (const std::exception &e) {
      throw InputError(statePath(dir_) + ": not a checkpoint of this run: " + e.what());
    }
  } else if (world_.rank == 0) {
    // An earlier run's checkpoints would continue that run, over this one's files.
    std::error_code ec;
    fs::remove_all(checkpoint_dir_, ec);
    if (on_)
      fs::create_directories(checkpoint_dir_);
  }
  if (on_ && h5_)
    openJournal();
}

Checkpoints::~Checkpoints() {
  if (h5_)
    h5_->record(nullptr);
}

std::string Checkpoints::file(const std::string &stem, std::uint64_t number,
                              const std::string &end) const {
  char text[32];
  std::snprintf(text, sizeof text, "-%06llu", static_cast<unsigned long long>(number));
  return stem + text + end;
}

// The calls made on run.h5 from now to the next checkpoint, under a temporary name until then.
void Checkpoints::openJournal() {
  journal_ =
      std::make_unique<H5Journal>(checkpoint_dir_ + "/" + file("journal", number_ + 1, ".h5j.tmp"));
  h5_->record(journal_.get());
}

void Checkpoints::afterStep(const LoopResult &loop, bool late, bool failed) {
  const fem::Solver &solver = *run_.solver;
  if (stop_at_ > 0 && solver.steps() == stop_at_)
    setStopSignal(SIGTERM);
  if (!on_)
    return;
  const bool due = late || (next_time_ > 0.0 && solver.time() >= next_time_);
  if (due && !(run_.coupled && run_.coupled->windowOpen()))
    write(loop, failed);
}

bool Checkpoints::lateByClock() const {
  return on_ && world_.rank == 0 && scene_.run.checkpoint_interval > 0.0 &&
         secondsSince(last_wall_) >= scene_.run.checkpoint_interval;
}

bool Checkpoints::stopBySignal(const LoopResult &loop, int signal) {
  if (signal == 0)
    return false;
  if (!on_)
    return true;
  if (run_.coupled && run_.coupled->windowOpen())
    return false;
  if (last_step_ != run_.solver->steps())
    write(loop);
  return true;
}

void Checkpoints::write(const LoopResult &loop, bool failed) {
  const auto began = Clock::now();
  const std::uint64_t n = number_ + 1;
  const fem::Solver &solver = *run_.solver;
  std::string failure;                // this process's first
  auto own = [&](const auto &files) { // this process's files alone, while none failed
    if (failed || !failure.empty())
      return;
    try {
      files();
    } catch (const std::exception &e) {
      failure = e.what();
    }
  };
  // every rank's elements, its nodes' velocities, forces and external forces and its nodes'
  // contact state, for rank 0 to write
  run_.solver->collectCheckpoint();
  std::optional<fem::Contact::State> contact;
  if (run_.contact)
    contact = run_.contact->state(run_.model);
  std::vector<coupling::DiskForce> disk_forces;
  const std::string restart = run_.dem ? file("liggghts", n, ".restart") : std::string();
  if (run_.dem) {
    const std::string path = checkpoint_dir_ + "/" + restart;
    disk_forces = run_.dem->writeRestart(path + ".tmp");
    if (world_.rank == 0)
      own([&] { fs::rename(path + ".tmp", path); });
    own([&] {
      writeCoupling(checkpoint_dir_ + "/" +
                        file("coupling", n, "-r" + std::to_string(world_.rank) + ".h5"),
                    run_.coupled->state());
    });
    world_.barrier(); // every rank's file written before the checkpoint is
  }
  if (failed)
    return;
  if (!failure.empty())
    throw std::runtime_error(failure);
  const double wall = wall_before_ + secondsSince(start_);
  if (world_.rank == 0) {
    journal_->close();
    fs::rename(journal_->path(), checkpoint_dir_ + "/" + file("journal", n, ".h5j"));
    writeAtomically(statePath(dir_), [&](const std::string &temp) {
      H5File h5 = H5File::create(temp);
      h5.attribute("/", "format", std::string("mesopen-checkpoint"));
      h5.attribute("/", "version", format_version);
      h5.attribute("/", "number", n);
      const std::string scene = composedScene(scene_);
      h5.write("/scene", std::vector<std::uint8_t>(scene.begin(), scene.end()));
      h5.attribute("/", "scene_path", scene_.path);
      h5.attribute("/", "ranks", world_.size);
      h5.attribute("/", "fingerprint", fingerprint(run_.model));
      h5.attribute("/", "time", solver.time());
      h5.attribute("/", "step", static_cast<std::uint64_t>(solver.steps()));
      h5.attribute("/", "wall", wall);
      h5.attribute("/", "liggghts", restart);
      writeModel(h5, run_.model);
      writeSolver(h5, solver.state());
      if (contact)
        writeContact(h5, *contact);
      h5.createGroup("/series");
      h5.write("/series/time", series_.time_);
      h5.write("/series/dt", series_.dt_);
      h5.write("/series/step", series_.step_);
      std::string names;
      std::vector<double> values;
      for (std::size_t i = 0; i < series_.size(); ++i)
        for (const Series::Column &c : series_.columns_)
          values.push_back(c.values[i]);
      for (const Series::Column &c : series_.columns_)
        names += c.name + "\n";
      h5.write("/series/values", values, series_.size(), series_.columns_.size());
      h5.attribute("/series", "columns", names);
      h5.createGroup("/frames");
      h5.attribute("/frames", "next", frames_.next_);
      h5.write("/frames/times", frames_.times_);
      h5.createGroup("/loop");
      h5.attribute("/loop", "element_steps", loop.element_steps);
      h5.attribute("/loop", "seconds", before_.seconds + secondsSince(start_));
      h5.attribute("/loop", "solver_seconds", loop.solver_seconds);
      if (run_.dem) {
        h5.createGroup("/disks");
        writeDiskForces(h5, "/disks/forces", disk_forces);
      }
      h5.close();
      syncFile(temp);
    });
  }
  // What the checkpoint before held and this one replaces.
  const std::uint64_t before = number_;
  number_ = n;
  if (h5_)
    openJournal();
  std::error_code ec;
  if (before > 0 && run_.dem) {
    fs::remove(checkpoint_dir_ + "/" +
                   file("coupling", before, "-r" + std::to_string(world_.rank) + ".h5"),
               ec);
    if (world_.rank == 0)
      fs::remove(checkpoint_dir_ + "/" + file("liggghts", before, ".restart"), ec);
  }
  last_step_ = solver.steps();
  last_wall_ = Clock::now();
  if (scene_.run.checkpoint_time > 0.0) // the next multiple after now
    next_time_ =
        scene_.run.checkpoint_time * (std::floor(solver.time() / scene_.run.checkpoint_time) + 1.0);
  seconds_ += secondsSince(began);
}

void Checkpoints::resume() {
  const H5File h5 = H5File::open(statePath(dir_));
  fem::Model &model = run_.model;
  if (h5.readAttribute<std::uint64_t>("/", "fingerprint") != fingerprint(model))
    throw InputError(statePath(dir_) + ": the model made from its scene (" + scene_.path +
                     ") is not the one the checkpoint was written from (another version of "
                     "mesopen or of its target generator?); allowed: a checkpoint of this "
                     "mesopen's run");
  if (run_.dem && h5.readAttribute<int>("/", "ranks") != world_.size)
    throw InputError(statePath(dir_) + ": written by a run on " +
                     std::to_string(h5.readAttribute<int>("/", "ranks")) +
                     " MPI ranks; allowed with disks: the same number of ranks (now " +
                     std::to_string(world_.size) + ")");
  number_ = h5.readAttribute<std::uint64_t>("/", "number");
  wall_before_ = h5.readAttribute<double>("/", "wall");
  readModel(h5, model);
  run_.solver->restore(readSolver(h5));
  if (run_.contact)
    run_.contact->restore(model, readContact(h5));
  if (run_.dem) {
    run_.coupled->restore(
        model, readCoupling(checkpoint_dir_ + "/" +
                            file("coupling", number_, "-r" + std::to_string(world_.rank) + ".h5")));
    run_.dem->restoreForces(readDiskForces(h5, "/disks/forces"));
  }
  // The series so far (its columns in this build's order) and the frames' times.
  series_.time_ = h5.read<double>("/series/time");
  const std::size_t samples = series_.time_.size();
  series_.dt_ = readSized<double>(h5, "/series/dt", samples);
  series_.step_ = readSized<std::uint64_t>(h5, "/series/step", samples);
  std::string names;
  for (const Series::Column &c : series_.columns_)
    names += c.name + "\n";
  if (h5.readStringAttribute("/series", "columns") != names)
    throw std::runtime_error("its series has other columns than this mesopen's");
  const std::size_t columns = series_.columns_.size();
  const std::vector<double> values = readSized<double>(h5, "/series/values", samples * columns);
  for (std::size_t c = 0; c < columns; ++c) {
    series_.columns_[c].values.resize(samples);
    for (std::size_t i = 0; i < samples; ++i)
      series_.columns_[c].values[i] = values[i * columns + c];
  }
  frames_.next_ = h5.readAttribute<double>("/frames", "next");
  frames_.times_ = h5.read<double>("/frames/times");
  before_.element_steps = h5.readAttribute<double>("/loop", "element_steps");
  before_.seconds = h5.readAttribute<double>("/loop", "seconds");
  before_.solver_seconds = h5.readAttribute<double>("/loop", "solver_seconds");
  last_step_ = run_.solver->steps();
  const double t = run_.solver->time();
  if (scene_.run.checkpoint_time > 0.0)
    next_time_ = scene_.run.checkpoint_time * (std::floor(t / scene_.run.checkpoint_time) + 1.0);
  if (world_.rank != 0)
    return;
  // run.h5 as the run had written it by the checkpoint: its frames' calls made again.
  for (std::uint64_t k = 1; k <= number_; ++k)
    H5Journal::replay(checkpoint_dir_ + "/" + file("journal", k, ".h5j"), *h5_);
  // What the run wrote after the checkpoint is written again.
  std::error_code ec;
  for (const auto &entry : fs::directory_iterator(checkpoint_dir_, ec)) {
    const std::string name = entry.path().filename().string();
    const bool later = name.starts_with("journal-") && name.size() >= 14 &&
                       std::strtoull(name.c_str() + 8, nullptr, 10) > number_;
    if (later || name.ends_with(".tmp"))
      fs::remove(entry.path(), ec);
  }
}

void Checkpoints::end(bool completed) {
  if (h5_)
    h5_->record(nullptr);
  std::error_code ec;
  if (journal_) { // the calls after the last checkpoint: a run continued makes them again
    const std::string part = journal_->path();
    journal_.reset();
    fs::remove(part, ec);
  }
  if (completed && world_.rank == 0)
    fs::remove_all(checkpoint_dir_, ec);
}

} // namespace mesopen
