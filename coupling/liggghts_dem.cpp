#include "liggghts_dem.hpp"

// LIGGGHTS: the C library interface, and the classes to reach `fix external` and the torques.
#include "atom.h"
#include "fix_external.h"
#include "integrate.h"
#include "lammps.h"
#include "library.h"
#include "modify.h"
#include "neighbor.h"
#include "universe.h"
#include "update.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fcntl.h>
#include <filesystem>
#include <stdexcept>
#include <unistd.h>

namespace mesopen::coupling {

namespace {

LAMMPS_NS::LAMMPS *lammps(void *p) { return static_cast<LAMMPS_NS::LAMMPS *>(p); }

bool isNumber(const std::string &s) {
  char *end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  return !s.empty() && end == s.c_str() + s.size() && std::isfinite(v);
}

bool isName(const std::string &s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  });
}

// Standard output sent to /dev/null while it lives: read_restart prints its file's version there
// whatever -screen says.
class QuietStdout {
public:
  QuietStdout() {
    std::fflush(stdout);
    saved_ = ::dup(STDOUT_FILENO);
    const int null = ::open("/dev/null", O_WRONLY);
    if (saved_ >= 0 && null >= 0)
      ::dup2(null, STDOUT_FILENO);
    if (null >= 0)
      ::close(null);
  }
  ~QuietStdout() {
    std::fflush(stdout);
    if (saved_ >= 0) {
      ::dup2(saved_, STDOUT_FILENO);
      ::close(saved_);
    }
  }
  QuietStdout(const QuietStdout &) = delete;
  QuietStdout &operator=(const QuietStdout &) = delete;

private:
  int saved_ = -1;
};

} // namespace

LiggghtsDem::LiggghtsDem(const std::string &script,
                         std::vector<std::pair<std::string, std::string>> variables,
                         const std::string &log, MPI_Comm comm, bool append_log)
    : own_(comm), comm_(own_.handle()) {
  namespace fs = std::filesystem;
  if (!fs::is_regular_file(script))
    throw std::invalid_argument("LIGGGHTS input script " + script + " not found");
  const bool append = append_log && log != "none";
  std::vector<std::string> args = {"liggghts", "-screen", "none", "-log", append ? "none" : log};
  for (const auto &[name, value] : variables) {
    if (!isName(name))
      throw std::invalid_argument("LIGGGHTS variable name '" + name + "': only a-z, 0-9 and _");
    if (name == "data"
            ? !fs::is_regular_file(value) || value.find_first_of(" \t\n\"'$#&") != std::string::npos
            : !isNumber(value))
      throw std::invalid_argument("LIGGGHTS variable " + name + " = '" + value + "': " +
                                  (name == "data" ? "no such file, or a path with a space or one "
                                                    "of \"'$#&"
                                                  : "not a finite number"));
    if (name == "kn")
      kn_ = std::strtod(value.c_str(), nullptr);
    args.insert(args.end(), {"-var", name, value});
  }
  std::vector<char *> argv;
  for (std::string &a : args)
    argv.push_back(a.data());
  lammps_open(static_cast<int>(argv.size()), argv.data(), comm, &lmp_);
  if (append) {
    // LIGGGHTS's -log opens its file anew; its own `log FILE append` would need the path quoted
    // through its parser. Its log is the first process's (LAMMPS's logfile, closed with it).
    int rank = 0, opened = 1;
    MPI_Comm_rank(comm, &rank);
    if (rank == 0) {
      LAMMPS_NS::LAMMPS *lmp = lammps(lmp_);
      lmp->logfile = lmp->universe->ulogfile = std::fopen(log.c_str(), "a");
      opened = lmp->logfile != nullptr;
      if (opened)
        std::fprintf(lmp->logfile, "\n# continued from a checkpoint\n");
    }
    if (!parallel::allReduce(opened, MPI_MIN, comm)) { // every process stops
      lammps_close(lmp_);
      throw std::runtime_error("cannot append to the LIGGGHTS log " + log);
    }
  }
  {
    const QuietStdout quiet;
    lammps_file(lmp_, const_cast<char *>(script.c_str()));
  }
  LAMMPS_NS::Modify *modify = lammps(lmp_)->modify;
  const int fix = modify->find_fix(const_cast<char *>("mesopen"));
  if (fix < 0 || std::string(modify->fix[fix]->style) != "external") {
    lammps_close(lmp_);
    throw std::invalid_argument("LIGGGHTS input script " + script +
                                " has no `fix mesopen all external pf/callback 1 1`");
  }
  static_cast<LAMMPS_NS::FixExternal *>(modify->fix[fix])->set_callback(callback, this);
  lammps_command(lmp_, const_cast<char *>("run 0")); // set up; no exchange: no forces yet
  dt_ = *static_cast<double *>(lammps_extract_global(lmp_, const_cast<char *>("dt")));
  read();
}

LiggghtsDem::~LiggghtsDem() {
  if (lmp_)
    lammps_close(lmp_);
}

// The lightest disk of every rank's (so that every rank takes the same step).
double LiggghtsDem::stableStep() const {
  double lightest = INFINITY;
  for (double m : p_.mass)
    lightest = std::min(lightest, m);
  lightest = parallel::allReduce(lightest, MPI_MIN, comm_);
  return contactStep(std::isfinite(lightest) ? lightest : 0.0, kn_);
}

double LiggghtsDem::largestRadius() const {
  double largest = 0.0;
  for (double r : p_.radius)
    largest = std::max(largest, r);
  return parallel::allReduce(largest, MPI_MAX, comm_);
}

// The atoms' order and number change only where LIGGGHTS rebuilds its neighbour lists (it
// exchanges atoms between ranks and sorts them there): the disks' radii, masses and ids are read
// again only then.
void LiggghtsDem::read() {
  LAMMPS_NS::LAMMPS *lmp = lammps(lmp_);
  const LAMMPS_NS::Atom *atom = lmp->atom;
  const auto n = static_cast<std::size_t>(atom->nlocal);
  if (lmp->neighbor->lastcall != listed_at_ || n != p_.size()) {
    for (auto *v : {&p_.x, &p_.y, &p_.vx, &p_.vy, &p_.omega, &p_.radius, &p_.mass, &p_.fx, &p_.fy,
                    &p_.torque})
      v->resize(n);
    p_.id.resize(n);
    for (std::size_t i = 0; i < n; ++i)
      p_.radius[i] = atom->radius[i], p_.mass[i] = atom->rmass[i], p_.id[i] = atom->tag[i];
    listed_at_ = lmp->neighbor->lastcall;
    ++layout_;
  }
  for (std::size_t i = 0; i < n; ++i) {
    p_.x[i] = atom->x[i][0], p_.y[i] = atom->x[i][1];
    p_.vx[i] = atom->v[i][0], p_.vy[i] = atom->v[i][1], p_.omega[i] = atom->omega[i][2];
    p_.fx[i] = atom->f[i][0], p_.fy[i] = atom->f[i][1], p_.torque[i] = atom->torque[i][2];
  }
}

// Called by `fix external` where the forces go in: within a window's step, after the drift (the
// exchange); and once when the run is set up (in the constructor: no forces yet).
void LiggghtsDem::callback(void *self, std::int64_t step, int n, int *, double **, double **f) {
  auto *dem = static_cast<LiggghtsDem *>(self);
  if (!dem->exchange_ || step != dem->exchange_step_) {
    for (int i = 0; i < n; ++i)
      f[i][0] = f[i][1] = f[i][2] = 0.0;
    return;
  }
  const auto start = std::chrono::steady_clock::now();
  dem->read(); // x(n+1), v(n+1/2)
  dem->forces_.reset(dem->p_.size());
  (*dem->exchange_)(dem->p_, dem->forces_);
  double **torque = lammps(dem->lmp_)->atom->torque;
  for (int i = 0; i < n; ++i) {
    f[i][0] = dem->forces_.fx[i], f[i][1] = dem->forces_.fy[i], f[i][2] = 0.0;
    torque[i][2] += dem->forces_.torque[i];
  }
  dem->exchange_seconds_ +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// A new step length goes to the integrator and the fixes as LAMMPS's `timestep` does between
// runs (update->dt, then every fix's reset_dt): a `timestep` command would need the next run set
// up again, which rebuilds the neighbour lists (a third of a hybrid run's time when the FE step
// changes every window).
void LiggghtsDem::setStep(double dt) {
  if (dt == dt_)
    return;
  LAMMPS_NS::LAMMPS *lmp = lammps(lmp_);
  lmp->update->dt = dt;
  for (int i = 0; i < lmp->modify->nfix; ++i)
    lmp->modify->fix[i]->reset_dt();
  lmp->update->integrate->reset_dt();
  dt_ = dt;
}

// One step of the integrator, as `run 1` takes it but without the run's set-up, which would
// compute every force once more at x(n) (LAMMPS's setup_minimal): the forces of the last step are
// still there for the first half kick. No output is due (the set-up run's last step is behind).
// With `exchange`, the FE bodies' forces go in inside the step (callback).
void LiggghtsDem::step(const Exchange *exchange) {
  const auto start = std::chrono::steady_clock::now();
  LAMMPS_NS::Update *update = lammps(lmp_)->update;
  update->nsteps = 1;
  update->firststep = update->beginstep = update->ntimestep;
  update->laststep = update->endstep = update->ntimestep + 1;
  update->whichflag = 1;
  exchange_ = exchange;
  exchange_step_ = update->ntimestep + 1;
  update->integrate->run(1);
  exchange_ = nullptr;
  update->whichflag = 0;
  const auto stepped = std::chrono::steady_clock::now();
  read();
  const auto end = std::chrono::steady_clock::now();
  window_seconds_ += std::chrono::duration<double>(end - start).count();
  exchange_seconds_ += std::chrono::duration<double>(end - stepped).count();
}

void LiggghtsDem::advance(double dt, const Exchange &exchange) {
  setStep(dt);
  step(&exchange);
}

// The window's motion put into the state at its start, so that LIGGGHTS's step of length D (half
// kick with the forces f(n) it holds, drift, forces, half kick) ends as DemParticipant::endWindow
// says. The positions written here are local atoms': the step then sends them to the ghosts (or
// re-neighbours, its displacement check seeing the change).
void LiggghtsDem::endWindow(double length, double planned, const WindowMotion &m) {
  const auto start = std::chrono::steady_clock::now();
  LAMMPS_NS::Atom *atom = lammps(lmp_)->atom;
  const double shift = 0.5 * length * (planned - length);
  for (const std::uint32_t i : m.moved) {
    atom->v[i][0] += m.dvx[i], atom->v[i][1] += m.dvy[i], atom->omega[i][2] += m.domega[i];
    atom->x[i][0] += m.dx[i] - length * m.dvx[i] + shift * atom->f[i][0] / atom->rmass[i];
    atom->x[i][1] += m.dy[i] - length * m.dvy[i] + shift * atom->f[i][1] / atom->rmass[i];
  }
  exchange_seconds_ +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  setStep(length);
  step(nullptr);
}

void LiggghtsDem::gatherDiskForces(std::vector<DiskForce> &forces) const {
  forces = parallel::allGatherItems(std::move(forces), comm_);
}

// The disks of every rank on rank 0, ordered by id (the same order on any number of ranks).
void LiggghtsDem::gatherParticles(const Particles &local, Particles &all) const {
  struct Disk { // one disk's id (as LIGGGHTS's tags, exact in a double) and fields, side by side
    double id, x, y, vx, vy, omega, radius, mass;
  };
  std::vector<Disk> mine(local.size());
  for (std::size_t i = 0; i < mine.size(); ++i)
    mine[i] = {static_cast<double>(local.id[i]),
               local.x[i],
               local.y[i],
               local.vx[i],
               local.vy[i],
               local.omega[i],
               local.radius[i],
               local.mass[i]};
  const std::vector<Disk> gathered = parallel::gatherItems(std::move(mine), 0, comm_);
  std::vector<std::size_t> order(gathered.size());
  for (std::size_t i = 0; i < order.size(); ++i)
    order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return gathered[a].id < gathered[b].id; });
  all = Particles{};
  std::pair<std::vector<double> Particles::*, double Disk::*> const fields[] = {
      {&Particles::x, &Disk::x},         {&Particles::y, &Disk::y},
      {&Particles::vx, &Disk::vx},       {&Particles::vy, &Disk::vy},
      {&Particles::omega, &Disk::omega}, {&Particles::radius, &Disk::radius},
      {&Particles::mass, &Disk::mass}};
  for (const auto &[field, member] : fields) {
    std::vector<double> &out = all.*field;
    out.resize(gathered.size());
    for (std::size_t i = 0; i < order.size(); ++i)
      out[i] = gathered[order[i]].*member;
  }
}

std::vector<DiskForce> LiggghtsDem::writeRestart(const std::string &path) {
  const LAMMPS_NS::Atom *atom = lammps(lmp_)->atom;
  std::vector<DiskForce> forces(static_cast<std::size_t>(atom->nlocal));
  for (std::size_t i = 0; i < forces.size(); ++i)
    forces[i] = {atom->tag[i], atom->f[i][0], atom->f[i][1], atom->torque[i][2]};
  if (path.find_first_of(" \t\n\"'$#&") != std::string::npos)
    throw std::invalid_argument("LIGGGHTS restart file '" + path +
                                "': a path with a space or one of \"'$#&");
  std::string command = "write_restart " + path;
  lammps_command(lmp_, command.data());
  lammps_command(lmp_, const_cast<char *>("run 0"));
  restoreForces(forces);
  gatherDiskForces(forces);
  return forces;
}

void LiggghtsDem::restoreForces(const std::vector<DiskForce> &forces) {
  LAMMPS_NS::Atom *atom = lammps(lmp_)->atom;
  for (const DiskForce &d : forces) {
    const int i = d.id > 0 && d.id <= atom->map_tag_max ? atom->map(static_cast<int>(d.id)) : -1;
    if (i < 0 || i >= atom->nlocal) // another rank's
      continue;
    atom->f[i][0] = d.fx, atom->f[i][1] = d.fy, atom->torque[i][2] = d.torque;
  }
  read();
}

} // namespace mesopen::coupling
