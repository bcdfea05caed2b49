#include "coupling.hpp"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace mesopen::coupling {

FeDemCoupling::FeDemCoupling(const fem::Model &model, DemParticipant &dem,
                             DiskContactSettings settings, double window)
    : dem_(dem), contact_(model, std::move(settings)), r_max_(dem.largestRadius()) {
  if (window > 0.0)
    planned_ = window;
  else { // (window is the same on every rank: every rank calls it, or none)
    const double stable = dem.stableStep();
    planned_ = std::isfinite(stable) ? stable : 0.0;
  }
}

// The disks' state read, their slow half kick (taken where used: v_h = v + P/2 f/m), no motion
// yet; the disks that hold the last forces of the window before are near, with those forces.
void FeDemCoupling::startWindow(double dt) {
  const Particles &p = dem_.particles();
  // A whole number of steps like the first: the window ends near where the disks' slow path
  // assumed (the FE step changes little over a window)
  length_ = planned_ > dt ? std::floor(planned_ / dt) * dt : dt;
  const std::size_t n = p.size();
  // No motion yet: the last window's near disks cleared (all, if the disks changed in number).
  const std::initializer_list<std::vector<double> *> motion = {
      &motion_.dx, &motion_.dy, &motion_.dvx, &motion_.dvy, &motion_.domega};
  if (is_near_.size() != n) {
    for (auto *v : motion)
      v->assign(n, 0.0);
    is_near_.assign(n, 0);
  } else
    for (const std::uint32_t i : motion_.moved) {
      for (auto *v : motion)
        (*v)[i] = 0.0;
      is_near_[i] = 0;
    }
  motion_.moved.clear();
  fast_.reset(0);
  if (dem_.layout() != layout_ || !listed_) {
    // the disks' places by id (ids run from 1 to about the number of disks)
    std::int64_t top = 0;
    for (std::int64_t id : p.id)
      top = std::max(top, id);
    if (place_.size() < static_cast<std::size_t>(top) + 1)
      place_.resize(static_cast<std::size_t>(top) + 1, -1);
    for (std::size_t i = 0; i < n; ++i)
      place_[p.id[i]] = static_cast<std::int64_t>(i);
    layout_ = dem_.layout(), listed_ = true;
  }
  if (shared()) { // the FE-DEM contact's depths held for disks LIGGGHTS moved to another rank
    auto here = [&](std::int64_t id) {
      const std::int64_t at =
          id >= 0 && id < static_cast<std::int64_t>(place_.size()) ? place_[id] : -1;
      return at >= 0 && static_cast<std::size_t>(at) < n && p.id[at] == id;
    };
    contact_.putHeld(processes_->allGather(contact_.takeHeld(here)), here);
  }
  if (!carried_.empty()) {
    const auto top = static_cast<std::int64_t>(place_.size()) - 1;
    for (const DiskForce &f : carried_) {
      const std::int64_t at = f.id >= 0 && f.id <= top ? place_[f.id] : -1;
      if (at < 0 || static_cast<std::size_t>(at) >= n || p.id[at] != f.id)
        continue; // another rank's (the entry is a disk's place when it was here)
      const auto i = static_cast<std::size_t>(at);
      motion_.moved.push_back(static_cast<std::uint32_t>(i));
      is_near_[i] = 1;
      fast_.fx.push_back(f.fx), fast_.fy.push_back(f.fy), fast_.torque.push_back(f.torque);
    }
  }
  elapsed_ = 0.0;
  window_steps_ = 0;
  open_ = true;
  exchanges_.record(Datum::particle_state, window_ + 1);
}

// The disks that may touch an FE body before the window ends: those whose slow path from now to
// the window's end (and a step beyond) comes into the region the bodies may reach by then, moving
// at up to twice the fastest boundary node's speed now (plus half the largest radius). A disk
// left out feels no FE force and is exactly on its slow path; if the bodies leave that region,
// the choice is made again.
void FeDemCoupling::choose(const fem::Model &model, const DiskContact::Region &now, double dt) {
  const Particles &p = dem_.particles();
  const double left = std::max(length_ - elapsed_, 0.0) + 2.0 * dt;
  const double fastest = shared() ? fastest_of_all_ : contact_.fastest(model);
  const double margin = 2.0 * fastest * left + 0.5 * r_max_;
  allowed_ = {now.x0 - margin, now.y0 - margin, now.x1 + margin, now.y1 + margin};
  const std::size_t n = p.size();
  meets_.resize(n);
  const DiskContact::Region a = allowed_;
  const double half = 0.5 * length_;
  const double *x = p.x.data(), *y = p.y.data(), *vx0 = p.vx.data(), *vy0 = p.vy.data(),
               *fx = p.fx.data(), *fy = p.fy.data(), *mass = p.mass.data();
  char *meets = meets_.data();
#pragma omp simd
  for (std::size_t i = 0; i < n; ++i) {
    const double vx = vx0[i] + half * fx[i] / mass[i],
                 vy = vy0[i] + half * fy[i] / mass[i]; // slow()
    const double xa = x[i] + elapsed_ * vx, ya = y[i] + elapsed_ * vy;
    const double xb = xa + left * vx, yb = ya + left * vy;
    meets[i] = (std::max(xa, xb) >= a.x0) & (std::min(xa, xb) <= a.x1) &
               (std::max(ya, yb) >= a.y0) & (std::min(ya, yb) <= a.y1);
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!meets_[i] || is_near_[i])
      continue;
    motion_.moved.push_back(static_cast<std::uint32_t>(i));
    is_near_[i] = 1;
    fast_.fx.push_back(0.0), fast_.fy.push_back(0.0), fast_.torque.push_back(0.0);
  }
}

void FeDemCoupling::addForces(fem::Model &model, double, double dt) {
  const auto start = std::chrono::steady_clock::now();
  const bool first = !open_;
  if (first)
    startWindow(dt);
  const Particles &p = dem_.particles();
  WindowMotion &m = motion_;
  // The near disks under the FE bodies' forces of the last step: half kick, drift.
  auto kick = [&](std::size_t c, double half_dt) {
    const std::uint32_t i = m.moved[c];
    m.dvx[i] += half_dt * fast_.fx[c] / p.mass[i], m.dvy[i] += half_dt * fast_.fy[c] / p.mass[i];
    m.domega[i] += half_dt * fast_.torque[c] / p.inertia(i);
  };
  for (std::size_t c = 0; c < m.moved.size(); ++c) {
    const std::uint32_t i = m.moved[c];
    kick(c, 0.5 * dt);
    m.dx[i] += dt * m.dvx[i], m.dy[i] += dt * m.dvy[i];
  }
  elapsed_ += dt;
  if (shared()) { // this process's bodies are current, the others' come with exchangeBoundaries
    const int me = processes_->rank();
    current_.resize(model.bodies.size());
    for (std::size_t b = 0; b < current_.size(); ++b)
      current_[b] = (*owner_)[b] == me;
  }
  DiskContact::Region now = contact_.measure(model, r_max_);
  // With the FE bodies shared: the region and the fastest node over every process's bodies, and
  // every process's marks (exchangeBoundaries) on the cells of the last step's region widened by
  // the largest disk's diameter, in one all-gather; when the region now is not within those cells
  // (a process's near disk beyond them within reach of a body could have gone unmarked: the first
  // step, a jump), or the near disks are chosen anew, the marks again on the region now.
  std::vector<std::int64_t> marks_of_all;
  if (shared()) {
    nearDisksNow();
    const std::vector<std::int64_t> all = shareRegion(model, now);
    const MarkGrid last(marks_region_, marks_set_);
    const double most[5] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL, -HUGE_VAL, 0.0};
    double largest[5];
    std::copy(most, most + 5, largest);
    const std::size_t each = 5 + static_cast<std::size_t>(last.each);
    for (std::size_t at = 0; at < all.size(); at += each)
      for (std::size_t k = 0; k < 5; ++k)
        largest[k] = std::max(largest[k], std::bit_cast<double>(all[at + k]));
    contact_.useRegion(now = {-largest[0], -largest[1], largest[2], largest[3]});
    region_of_all_ = now;
    fastest_of_all_ = largest[4];
    const DiskContact::Region &g = marks_region_;
    if (marks_set_ && now.x0 >= g.x0 && now.y0 >= g.y0 && now.x1 <= g.x1 && now.y1 <= g.y1)
      for (std::size_t at = 0; at < all.size(); at += each)
        marks_of_all.insert(marks_of_all.end(), all.begin() + static_cast<long>(at + 5),
                            all.begin() + static_cast<long>(at + each));
  }
  if (first || now.x0 < allowed_.x0 || now.y0 < allowed_.y0 || now.x1 > allowed_.x1 ||
      now.y1 > allowed_.y1) {
    choose(model, now, dt);
    marks_of_all.clear();
  }
  // Their state now (velocities at the step's middle, as the FE nodes'), the FE-DEM contact, and
  // the second half kick of its forces.
  nearDisksNow();
  const std::size_t nc = m.moved.size();
  if (shared()) {
    if (marks_of_all.empty()) {
      marks_region_ = now, marks_set_ = true;
      std::vector<std::int64_t> mine = markCells(MarkGrid(marks_region_, true), model);
      const auto size = static_cast<std::int64_t>(mine.size());
      marks_of_all = processes_->allGather(
          std::move(mine),
          std::vector<std::int64_t>(static_cast<std::size_t>(processes_->size()), size));
    }
    exchangeBoundaries(model, MarkGrid(marks_region_, marks_set_), marks_of_all);
    // (the cells of the next step's marks)
    const double reach = 4.0 * r_max_;
    marks_region_ = {now.x0 - reach, now.y0 - reach, now.x1 + reach, now.y1 + reach};
    marks_set_ = std::isfinite(now.x1 - now.x0) && std::isfinite(now.y1 - now.y0);
  }
  fast_.reset(nc);
  reactions_.clear();
  contact_.addForces(model, now_, fast_, reactions_, dt);
  for (std::size_t c = 0; c < nc; ++c)
    kick(c, 0.5 * dt);
  applyReactions(model);
  if (!model.due.empty())
    measureForLevels(model, dt);
  exchanges_.record(Datum::reaction_force, window_ + 1);
  ++window_steps_;
  if (elapsed_ + 0.5 * dt >= length_) // the FE step nearest to the planned end
    endWindow();
  seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void FeDemCoupling::measureForLevels(const fem::Model &model, double dt) {
  const std::size_t nc = now_.x.size();
  double fastest_disk = 0.0, x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL;
  for (std::size_t c = 0; c < nc; ++c) {
    fastest_disk = std::max(fastest_disk, std::hypot(now_.vx[c], now_.vy[c]) +
                                              std::abs(now_.omega[c]) * now_.radius[c]);
    x0 = std::min(x0, now_.x[c]), x1 = std::max(x1, now_.x[c]);
    y0 = std::min(y0, now_.y[c]), y1 = std::max(y1, now_.y[c]);
  }
  fastest_node_ = contact_.fastest(model), fastest_disk_ = fastest_disk;
  closing_speed_ = fastest_node_ + fastest_disk_; // (over every process's: stepReduced)
  level_dt_ = dt;
  const std::vector<std::uint32_t> &bodies = contact_.bodies();
  box_current_.resize(bodies.size());
  for (std::size_t k = 0; k < bodies.size(); ++k)
    box_current_[k] = !shared() || model.at_rest[bodies[k]] || current_[bodies[k]];
  if (nc == 0)
    return;
  level_disks_.cover(x0, y0, x1 - x0, y1 - y0, std::max(2.0 * r_max_, 1e-12));
  level_disks_.fillPoints(
      nc, [&](std::size_t c) { return now_.x[c]; }, [&](std::size_t c) { return now_.y[c]; },
      [&](std::size_t c) { return static_cast<std::uint32_t>(c); });
}

namespace {
// The gap from the box [x0, x1] x [y0, y1] to the surface of a disk at (x, y) of `radius`.
double boxGap(double x0, double y0, double x1, double y1, double x, double y, double radius) {
  return std::hypot(std::max({x0 - x, 0.0, x - x1}), std::max({y0 - y, 0.0, y - y1})) - radius;
}
} // namespace

template <class Visit>
void FeDemCoupling::forDisksNear(double x0, double y0, double x1, double y1, Visit visit) const {
  if (now_.x.empty() || !std::isfinite(x0) || !(x0 <= x1 && y0 <= y1))
    return;
  const double search = levelSearch(), reach = r_max_ + search;
  level_disks_.forEach(
      level_disks_.cells(x0 - reach, y0 - reach, x1 + reach, y1 + reach), [&](std::uint32_t c) {
        const double g = boxGap(x0, y0, x1, y1, now_.x[c], now_.y[c], now_.radius[c]);
        if (g <= search)
          visit(c, g);
      });
}

double FeDemCoupling::gapToDisks(double x0, double y0, double x1, double y1,
                                 const std::vector<double> &more) const {
  double gap = HUGE_VAL;
  if (!std::isfinite(x0) || !(x0 <= x1 && y0 <= y1))
    return gap;
  forDisksNear(x0, y0, x1, y1, [&](std::uint32_t, double g) { gap = std::min(gap, g); });
  const double search = levelSearch();
  for (std::size_t i = 0; i + 3 <= more.size(); i += 3)
    if (const double g = boxGap(x0, y0, x1, y1, more[i], more[i + 1], more[i + 2]); g <= search)
      gap = std::min(gap, g);
  return gap;
}

std::uint8_t FeDemCoupling::levelClearOf(double gap, std::uint8_t top) const {
  const double unit = 2.0 * level_dt_ * closing_speed_; // the reach of level l: 2^l unit
  std::uint8_t level = 0;
  while (level < top && std::ldexp(unit, level + 1) < gap)
    ++level;
  return level;
}

// Each body's gap to the near disks, and its cap. With the FE bodies shared, every process
// gives the gaps of the moving bodies whose boxes are current here, as (body, gap), and the
// near disks within the search of a body in parts it does not own, as (-1 - body, x, y, radius),
// in one all-gather: every process takes the least gap of each body, the owner of a body in parts
// keeps the disks for capParts.
void FeDemCoupling::capLevels(const fem::Model &model, const std::vector<std::uint8_t> &,
                              std::vector<std::uint8_t> &cap) {
  const std::vector<std::uint32_t> &bodies = contact_.bodies();
  std::vector<double> gaps(model.bodies.size(), HUGE_VAL);
  parts_disks_.assign(in_parts_.size(), {});
  std::vector<double> given;
  for (std::size_t k = 0; k < bodies.size() && k < box_current_.size(); ++k) {
    const std::uint32_t b = bodies[k];
    if (!box_current_[k] || (shared() && model.at_rest[b]))
      continue;
    const DiskContact::Region box = contact_.box(k);
    const double gap = gapToDisks(box.x0, box.y0, box.x1, box.y1);
    if (!shared())
      gaps[b] = gap;
    else if (gap < HUGE_VAL)
      given.insert(given.end(), {static_cast<double>(b), gap});
  }
  if (shared()) {
    for (const std::uint32_t b : in_parts_) {
      const auto k = static_cast<std::size_t>(std::lower_bound(bodies.begin(), bodies.end(), b) -
                                              bodies.begin());
      if (k >= box_current_.size() || bodies[k] != b || !box_current_[k] || model.at_rest[b] ||
          (*owner_)[b] == processes_->rank())
        continue;
      const DiskContact::Region box = contact_.box(k);
      forDisksNear(box.x0, box.y0, box.x1, box.y1, [&](std::uint32_t c, double) {
        given.insert(given.end(),
                     {-1.0 - static_cast<double>(b), now_.x[c], now_.y[c], now_.radius[c]});
      });
    }
    const std::vector<double> all = processes_->allGather(std::move(given));
    for (std::size_t i = 0; i < all.size();) {
      if (all[i] >= 0.0) {
        double &gap = gaps[static_cast<std::size_t>(all[i])];
        gap = std::min(gap, all[i + 1]);
        i += 2;
        continue;
      }
      const auto b = static_cast<std::uint32_t>(-1.0 - all[i]);
      const auto p = static_cast<std::size_t>(std::find(in_parts_.begin(), in_parts_.end(), b) -
                                              in_parts_.begin());
      if ((*owner_)[b] == processes_->rank())
        parts_disks_[p].insert(parts_disks_[p].end(), all.begin() + static_cast<long>(i + 1),
                               all.begin() + static_cast<long>(i + 4));
      i += 4;
    }
  }
  for (const std::uint32_t b : bodies)
    cap[b] = std::min(cap[b], levelClearOf(gaps[b], cap[b]));
}

void FeDemCoupling::capParts(const std::vector<std::uint8_t> &, std::uint32_t body,
                             const std::vector<double> &boxes,
                             std::vector<std::uint8_t> &cap) const {
  static const std::vector<double> none;
  const auto i = static_cast<std::size_t>(std::find(in_parts_.begin(), in_parts_.end(), body) -
                                          in_parts_.begin());
  const std::vector<double> &more = i < parts_disks_.size() ? parts_disks_[i] : none;
  for (std::size_t p = 0; p < cap.size(); ++p)
    cap[p] = std::min(cap[p], levelClearOf(gapToDisks(boxes[4 * p], boxes[4 * p + 1],
                                                      boxes[4 * p + 2], boxes[4 * p + 3], more),
                                           cap[p]));
}

// The DEM participant's step with the window's motion; the last FE forces on the disks are
// carried to the next window's first half kick, by id (the step may move disks to other ranks).
void FeDemCoupling::endWindow() {
  const Particles &p = dem_.particles();
  carried_.clear();
  for (std::size_t c = 0; c < motion_.moved.size(); ++c)
    if (fast_.fx[c] != 0.0 || fast_.fy[c] != 0.0 || fast_.torque[c] != 0.0)
      carried_.push_back({p.id[motion_.moved[c]], fast_.fx[c], fast_.fy[c], fast_.torque[c]});
  dem_.endWindow(elapsed_, length_, motion_);
  exchanges_.record(Datum::particle_motion, window_ + 1);
  exchanges_.checkWindow(window_ + 1, window_steps_);
  dem_.gatherDiskForces(carried_);
  ++window_;
  open_ = false;
}

void FeDemCoupling::boundaryChanged(const fem::Model &model, const std::vector<std::uint32_t> &) {
  contact_.boundaryChanged(model);
  if (!shared())
    return;
  // The moving bodies' element sizes from their owners (the others' nodes here may be stale).
  const int me = processes_->rank();
  const std::vector<std::uint32_t> &bodies = contact_.bodies();
  std::size_t count = 0;
  for (const std::uint32_t b : bodies)
    count += !model.at_rest[b] && (*owner_)[b] == me;
  processes_->share(
      count,
      [&](double *out) {
        for (const std::uint32_t b : bodies)
          if (!model.at_rest[b] && (*owner_)[b] == me)
            *out++ = contact_.elementSize(b);
      },
      [&](const double *all) {
        for (int r = 0; r < processes_->size(); ++r)
          for (const std::uint32_t b : bodies)
            if (!model.at_rest[b] && (*owner_)[b] == r)
              contact_.elementSize(b) = *all++;
      });
}

void FeDemCoupling::shareWork(const parallel::Communicator &processes,
                              const std::vector<int> &owner) {
  processes_ = &processes, owner_ = &owner;
  contact_.lookAt(shared() ? &current_ : nullptr);
}

// The near disks' state now (velocities at the step's middle, as the FE nodes'): now_.
void FeDemCoupling::nearDisksNow() {
  const Particles &p = dem_.particles();
  const WindowMotion &m = motion_;
  const std::size_t nc = m.moved.size();
  for (auto *v : {&now_.x, &now_.y, &now_.vx, &now_.vy, &now_.omega, &now_.radius, &now_.mass})
    v->resize(nc);
  now_.id.resize(nc);
  for (std::size_t c = 0; c < nc; ++c) {
    const std::uint32_t i = m.moved[c];
    const auto [vx, vy, spin] = slow(p, i);
    now_.x[c] = p.x[i] + elapsed_ * vx + m.dx[i], now_.y[c] = p.y[i] + elapsed_ * vy + m.dy[i];
    now_.vx[c] = vx + m.dvx[i], now_.vy[c] = vy + m.dvy[i];
    now_.omega[c] = spin + m.domega[i];
    now_.radius[c] = p.radius[i], now_.mass[c] = p.mass[i], now_.id[c] = p.id[i];
  }
}

// Every process's region (x0, y0 negated, x1, y1) and fastest boundary node (as bits), each with
// its marks on the cells of the last step's (markCells), when there was one: one all-gather.
std::vector<std::int64_t> FeDemCoupling::shareRegion(const fem::Model &model,
                                                     const DiskContact::Region &mine) const {
  std::vector<std::int64_t> values;
  for (double v : {-mine.x0, -mine.y0, mine.x1, mine.y1, contact_.fastest(model)})
    values.push_back(std::bit_cast<std::int64_t>(v));
  if (marks_set_) {
    const std::vector<std::int64_t> marks = markCells(MarkGrid(marks_region_, true), model);
    values.insert(values.end(), marks.begin(), marks.end());
  }
  const auto size = static_cast<std::int64_t>(values.size());
  return processes_->allGather(
      std::move(values),
      std::vector<std::int64_t>(static_cast<std::size_t>(processes_->size()), size));
}

FeDemCoupling::MarkGrid::MarkGrid(const DiskContact::Region &region, bool set) : r(region) {
  const double width = r.x1 - r.x0, height = r.y1 - r.y0;
  bodies_there =
      set && std::isfinite(width) && std::isfinite(height) && width > 0.0 && height > 0.0;
  nx = bodies_there ? static_cast<int>(std::clamp(std::round(std::sqrt(cells * width / height)),
                                                  1.0, 1.0 * cells))
                    : 1;
  ny = cells / nx;
  cw = bodies_there ? width / nx : 1.0, ch = bodies_there ? height / ny : 1.0;
  bx = (nx + 3) / 4, by = (ny + 3) / 4, block_words = (bx * by + 63) / 64;
  each = words + block_words;
}

// The marks of this process on `grid`'s cells: those its near disks reach (centre and largest
// radius, with levels the levels' search further; a disk farther than that from the grid's region
// is left out, as no FE body is within its reach), then in blocks of 4 x 4 cells those its bodies'
// boxes cover (at rest too: every process may load those), so that every process knows who may send
// whom a body or a reaction.
std::vector<std::int64_t> FeDemCoupling::markCells(const MarkGrid &grid,
                                                   const fem::Model &model) const {
  const DiskContact::Region &r = grid.r;
  std::vector<std::int64_t> marks(static_cast<std::size_t>(grid.each), 0);
  const double reach = r_max_ + (model.due.empty() ? 0.0 : levelSearch());
  for (std::size_t c = 0; grid.bodies_there && c < now_.size(); ++c) {
    const double x = now_.x[c], y = now_.y[c];
    if (x + reach < r.x0 || x - reach > r.x1 || y + reach < r.y0 || y - reach > r.y1)
      continue; // (no FE body within its reach)
    for (int j = grid.row(y - reach); j <= grid.row(y + reach); ++j)
      for (int i = grid.column(x - reach); i <= grid.column(x + reach); ++i)
        MarkGrid::set(marks.data(), j * grid.nx + i);
  }
  const int me = processes_->rank();
  const std::vector<std::uint32_t> &bodies = contact_.bodies();
  for (std::size_t k = 0; grid.bodies_there && k < bodies.size(); ++k) {
    if ((*owner_)[bodies[k]] != me)
      continue;
    const DiskContact::Region box = contact_.box(k);
    for (int j = grid.row(box.y0) / 4; j <= grid.row(box.y1) / 4; ++j)
      for (int i = grid.column(box.x0) / 4; i <= grid.column(box.x1) / 4; ++i)
        MarkGrid::set(marks.data() + MarkGrid::words, j * grid.bx + i);
  }
  return marks;
}

// The FE bodies that may touch this process's near disks: a region covering every FE body (and
// every near disk within reach of one) is cut into at most 4,096 cells, every process's marks on
// them (markCells, all-gathered: `all`, each process's in rank order) say which cells its near
// disks reach and which blocks its bodies cover, and the owner of a moving body whose box meets a
// cell another process marked sends that process the body's boundary nodes, positions and
// velocities. (A disk that touches a body has a point of the body's box within its reach: that
// point's cell is marked and in the box's cells.)
void FeDemCoupling::exchangeBoundaries(fem::Model &model, const MarkGrid &grid,
                                       const std::vector<std::int64_t> &all) {
  fem::Nodes &nd = model.nodes;
  const int nx = grid.nx, words = MarkGrid::words, bx = grid.bx, block_words = grid.block_words;
  const int each = grid.each;
  const bool bodies_there = grid.bodies_there;
  auto set = MarkGrid::set;
  auto marked = [&](std::size_t rank, const DiskContact::Region &box) {
    if (!bodies_there)
      return false;
    const std::int64_t *m = &all[rank * static_cast<std::size_t>(each)];
    for (int j = grid.row(box.y0); j <= grid.row(box.y1); ++j)
      for (int i = grid.column(box.x0); i <= grid.column(box.x1); ++i) {
        const int c = j * nx + i;
        if ((m[c / 64] >> (c % 64)) & 1)
          return true;
      }
    return false;
  };
  const int me = processes_->rank();
  const std::vector<std::uint32_t> &bodies = contact_.bodies();
  const auto ranks = static_cast<std::size_t>(processes_->size());
  // q may send r a body (a moving one) when one of q's bodies covers a block with a cell r's
  // disks reach, and r send q reactions on it (on one at rest too, which every process holds)
  std::vector<std::int64_t> reached(ranks * static_cast<std::size_t>(block_words), 0);
  for (std::size_t q = 0; bodies_there && q < ranks; ++q)
    for (int w = 0; w < words; ++w)
      for (auto bits = static_cast<std::uint64_t>(
               all[q * static_cast<std::size_t>(each) + static_cast<std::size_t>(w)]);
           bits != 0; bits &= bits - 1) {
        const int c = 64 * w + std::countr_zero(bits);
        set(reached.data() + q * static_cast<std::size_t>(block_words),
            c / nx / 4 * bx + c % nx / 4);
      }
  auto sends = [&](std::size_t q, std::size_t to_rank) {
    for (int w = 0; w < block_words; ++w)
      if (all[q * static_cast<std::size_t>(each) + static_cast<std::size_t>(words + w)] &
          reached[to_rank * static_cast<std::size_t>(block_words) + static_cast<std::size_t>(w)])
        return true;
    return false;
  };
  partners_.clear();
  const auto mine = static_cast<std::size_t>(me);
  for (std::size_t q = 0; q < ranks; ++q)
    if (q != mine && (sends(q, mine) || sends(mine, q)))
      partners_.push_back(static_cast<int>(q));
  std::vector<std::vector<std::int64_t>> to(ranks);
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    const std::uint32_t b = bodies[k];
    if (model.at_rest[b] || (*owner_)[b] != me)
      continue;
    const DiskContact::Region box = contact_.box(k);
    const auto &edges = model.bodies[b].boundary;
    for (std::size_t q = 0; q < to.size(); ++q) {
      if (static_cast<int>(q) == me || !marked(q, box))
        continue;
      std::vector<std::int64_t> &message = to[q];
      message.push_back(b);
      for (std::size_t e = 0; e < edges.size(); e += 2) { // (their first nodes are its nodes)
        const std::uint32_t a = edges[e];
        message.insert(message.end(),
                       {std::bit_cast<std::int64_t>(nd.x[a]), std::bit_cast<std::int64_t>(nd.y[a]),
                        std::bit_cast<std::int64_t>(nd.vx[a]),
                        std::bit_cast<std::int64_t>(nd.vy[a])});
      }
    }
  }
  std::vector<std::uint32_t> received;
  for (const std::vector<std::int64_t> &message :
       processes_->exchangeWith(std::move(to), partners_))
    for (std::size_t i = 0; i < message.size();) {
      const auto b = static_cast<std::uint32_t>(message[i++]);
      const auto &edges = model.bodies[b].boundary;
      for (std::size_t e = 0; e < edges.size(); e += 2, i += 4) {
        const std::uint32_t a = edges[e];
        nd.x[a] = std::bit_cast<double>(message[i]);
        nd.y[a] = std::bit_cast<double>(message[i + 1]);
        nd.vx[a] = std::bit_cast<double>(message[i + 2]);
        nd.vy[a] = std::bit_cast<double>(message[i + 3]);
      }
      current_[b] = 1;
      received.push_back(b);
      halo_nodes_ += edges.size() / 2;
    }
  contact_.measureBodies(model, received);
}

// The reactions into the FE nodes. With the FE bodies shared, each goes to its node's owner (a
// partner: it sent this process the body), who adds every process's in rank order (as if every
// process's reactions were gathered). A body at rest they load wakes at its owner with them, at
// the others after the step's reduction (stepReduced).
void FeDemCoupling::applyReactions(fem::Model &model) {
  if (!shared()) {
    DiskContact::apply(model, reactions_);
    return;
  }
  const int me = processes_->rank();
  const auto ranks = static_cast<std::size_t>(processes_->size());
  woken_.clear();
  for (const Reaction &r : reactions_)
    if (model.at_rest[r.body] && (woken_.empty() || woken_.back() != r.body))
      woken_.push_back(r.body);
  std::sort(woken_.begin(), woken_.end());
  woken_.erase(std::unique(woken_.begin(), woken_.end()), woken_.end());
  std::vector<std::vector<std::int64_t>> to(ranks);
  std::vector<Reaction> own;
  for (const Reaction &r : reactions_)
    if (const int owner = (*owner_)[r.body]; owner == me)
      own.push_back(r);
    else
      to[static_cast<std::size_t>(owner)].insert(
          to[static_cast<std::size_t>(owner)].end(),
          {r.node, r.body, std::bit_cast<std::int64_t>(r.fx), std::bit_cast<std::int64_t>(r.fy),
           std::bit_cast<std::int64_t>(r.friction_x), std::bit_cast<std::int64_t>(r.friction_y)});
  const std::vector<std::vector<std::int64_t>> from =
      processes_->exchangeWith(std::move(to), partners_);
  std::vector<Reaction> received;
  for (std::size_t r = 0; r < ranks; ++r) {
    if (static_cast<int>(r) == me) {
      DiskContact::apply(model, own);
      continue;
    }
    const std::vector<std::int64_t> &message = from[r];
    received.clear();
    for (std::size_t i = 0; i + 6 <= message.size(); i += 6)
      received.push_back(
          {static_cast<std::uint32_t>(message[i]), static_cast<std::uint32_t>(message[i + 1]),
           std::bit_cast<double>(message[i + 2]), std::bit_cast<double>(message[i + 3]),
           std::bit_cast<double>(message[i + 4]), std::bit_cast<double>(message[i + 5])});
    DiskContact::apply(model, received);
  }
}

void FeDemCoupling::stepFigures(const fem::Model &model, double,
                                std::vector<double> &figures) const {
  figures.push_back(static_cast<double>(woken_.size()));
  if (!model.due.empty())
    figures.insert(figures.end(), {fastest_node_, fastest_disk_});
}

void FeDemCoupling::stepReduced(fem::Model &model, const double *largest) {
  fem::wakeEverywhere(model, *processes_, woken_, static_cast<std::size_t>(largest[0]));
  if (!model.due.empty())
    closing_speed_ = largest[1] + largest[2];
}

Particles FeDemCoupling::disks() const {
  Particles d = dem_.particles();
  if (!open_)
    return d;
  const WindowMotion &m = motion_;
  for (std::size_t i = 0; i < d.size(); ++i) {
    const auto [vx, vy, spin] = slow(d, i);
    d.x[i] += elapsed_ * vx + m.dx[i], d.y[i] += elapsed_ * vy + m.dy[i];
    d.vx[i] = vx + m.dvx[i], d.vy[i] = vy + m.dvy[i];
    d.omega[i] = spin + m.domega[i];
  }
  return d;
}

FeDemCoupling::State FeDemCoupling::state() const {
  if (open_)
    throw std::logic_error("the coupling's state is taken between windows");
  return {window_, carried_, seconds_, contact_.state()};
}

void FeDemCoupling::restore(const fem::Model &model, const State &state) {
  contact_.restore(model, state.contact);
  window_ = state.windows, carried_ = state.carried, seconds_ = state.seconds;
  open_ = false, listed_ = false; // the disks' places by id taken at the next window's start
}

} // namespace mesopen::coupling
