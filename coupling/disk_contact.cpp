#include "disk_contact.hpp"

#include "contact_law.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <iterator>
#include <limits>
#include <stdexcept>

namespace mesopen::coupling {

namespace {
double sq(double x) { return x * x; }
} // namespace

DiskContact::DiskContact(const fem::Model &model, DiskContactSettings settings)
    : s_(std::move(settings)) {
  if (s_.friction.size() != model.bodies.size())
    throw std::invalid_argument("DiskContact: one friction coefficient per FE body needed");
  boundaryChanged(model);
}

void DiskContact::boundaryChanged(const fem::Model &model) {
  const fem::Nodes &nd = model.nodes;
  boxes_.clear(); // taken anew
  grids_.clear();
  size_.assign(model.bodies.size(), 0.0);
  fe_bodies_.clear();
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    const auto &edges = model.bodies[b].boundary;
    for (std::size_t e = 0; e + 1 < edges.size(); e += 2)
      size_[b] = std::max(size_[b], std::hypot(nd.x[edges[e + 1]] - nd.x[edges[e]],
                                               nd.y[edges[e + 1]] - nd.y[edges[e]]));
    if (!edges.empty())
      fe_bodies_.push_back(static_cast<std::uint32_t>(b));
  }
}

// The closest point of the body's boundary to (cx, cy) among the segments within `reach` (the
// disk's radius: the closest of all when it is that near; distance infinite when none is), of
// those in `near` (offsets into the body's boundary: every segment within reach among them), and
// the side: at a segment's inside by its outward normal (the tangent turned right: boundaries run
// counter-clockwise), at a vertex by the vertex's pseudo-normal, the sum of its two segments'
// normals. A disk wholly inside a body (its centre more than its radius behind the boundary) is
// not seen: the penalty keeps overlaps to a few percent of a radius.
DiskContact::Closest DiskContact::closest(const fem::Model &model, std::size_t body, double cx,
                                          double cy, double reach,
                                          const std::vector<std::uint32_t> &near) const {
  const fem::Nodes &nd = model.nodes;
  const auto &edges = model.bodies[body].boundary;
  double best = std::numeric_limits<double>::infinity(), best_t = 0.0, best_length = 0.0;
  std::size_t best_edge = edges.size();
  for (const std::uint32_t e : near) {
    const double ax = nd.x[edges[e]], ay = nd.y[edges[e]];
    const double bx = nd.x[edges[e + 1]], by = nd.y[edges[e + 1]];
    // a segment whose box is farther than `reach` from the point is farther than that
    if (std::max(ax, bx) < cx - reach || std::min(ax, bx) > cx + reach ||
        std::max(ay, by) < cy - reach || std::min(ay, by) > cy + reach)
      continue;
    const double dx = bx - ax, dy = by - ay;
    const double length = std::sqrt(dx * dx + dy * dy);
    if (!(length > 0.0))
      continue;
    const double t = std::clamp(((cx - ax) * dx + (cy - ay) * dy) / length, 0.0, length);
    const double qx = ax + t * dx / length - cx, qy = ay + t * dy / length - cy;
    const double d2 = qx * qx + qy * qy;
    if (d2 < best)
      best = d2, best_t = t, best_length = length, best_edge = e;
  }
  Closest c;
  if (best_edge == edges.size()) { // nothing within reach
    c.distance = std::numeric_limits<double>::infinity();
    return c;
  }
  c.s1 = edges[best_edge], c.s2 = edges[best_edge + 1];
  c.w = best_t / best_length;
  c.distance = std::sqrt(best);
  const double ax = nd.x[c.s1], ay = nd.y[c.s1], bx = nd.x[c.s2], by = nd.y[c.s2];
  // the segment's outward normal, or the vertex's pseudo-normal
  double mx = (by - ay) / best_length, my = -(bx - ax) / best_length;
  if (best_t == 0.0 || best_t == best_length) {
    const std::uint32_t vertex = best_t == 0.0 ? c.s1 : c.s2;
    for (const std::uint32_t e : near) { // the other edge at the vertex is within reach too
      if (e == best_edge || edges[e + (best_t == 0.0 ? 1 : 0)] != vertex)
        continue;
      const double ox = nd.x[edges[e + 1]] - nd.x[edges[e]],
                   oy = nd.y[edges[e + 1]] - nd.y[edges[e]];
      const double ol = std::sqrt(ox * ox + oy * oy);
      if (ol > 0.0)
        mx += oy / ol, my -= ox / ol;
      break;
    }
  }
  const double qx = ax + c.w * (bx - ax), qy = ay + c.w * (by - ay);
  const double vx = cx - qx, vy = cy - qy;
  const bool outside = vx * mx + vy * my >= 0.0;
  if (c.distance > 0.0) {
    const double sign = outside ? 1.0 : -1.0;
    c.nx = sign * vx / c.distance, c.ny = sign * vy / c.distance;
  } else {
    const double norm = std::hypot(mx, my);
    c.nx = mx / norm, c.ny = my / norm;
  }
  if (!outside)
    c.distance = -c.distance; // the centre inside the body
  return c;
}

// A body's boundary segments in cells over its box (each in every cell its box widened by a
// quarter cell meets), with their first nodes' positions (x, y).
void DiskContact::EdgeGrid::build(const std::vector<std::uint32_t> &edges, const double *x,
                                  const double *y, const Box &box_now, double cell_for) {
  box = box_now, cell_size = cell_for;
  const std::size_t n = edges.size() / 2;
  // cells of a few segments' length, or the disks' size if larger
  const double cell =
      std::max(cell_size, 4.0 * std::sqrt((box.x1 - box.x0) * (box.y1 - box.y0) / n));
  slack = 0.25 * cell;
  cells.cover(box.x0 - slack, box.y0 - slack, box.x1 - box.x0 + 2.0 * slack,
              box.y1 - box.y0 + 2.0 * slack, cell);
  built_x.resize(n), built_y.resize(n);
  for (std::size_t e = 0; e < edges.size(); e += 2)
    built_x[e / 2] = x[edges[e]], built_y[e / 2] = y[edges[e]];
  cells.fill(
      n,
      [&](std::size_t k) {
        const double ax = x[edges[2 * k]], ay = y[edges[2 * k]], bx = x[edges[2 * k + 1]],
                     by = y[edges[2 * k + 1]];
        return cells.cells(std::min(ax, bx) - slack, std::min(ay, by) - slack,
                           std::max(ax, bx) + slack, std::max(ay, by) + slack);
      },
      [&](std::size_t k) { return static_cast<std::uint32_t>(2 * k); });
  valid = true;
}

void DiskContact::apply(fem::Model &model, const std::vector<Reaction> &reactions) {
  std::uint32_t woken = std::numeric_limits<std::uint32_t>::max();
  for (const Reaction &r : reactions) {
    model.nodes.addExternal(r.node, r.fx, r.fy, r.friction_x, r.friction_y);
    if (r.body != woken)
      model.wake(r.body), woken = r.body;
  }
}

// A closed boundary's edges start at each of its nodes once: their first nodes are its nodes.
DiskContact::Region DiskContact::measure(const fem::Model &model, double reach) {
  // (a body at rest keeps its box: its nodes have not moved)
  const bool all = boxes_.size() != fe_bodies_.size();
  boxes_.resize(fe_bodies_.size());
  grids_.resize(fe_bodies_.size());
  Region r{INFINITY, INFINITY, -INFINITY, -INFINITY};
  for (std::size_t k = 0; k < fe_bodies_.size(); ++k) {
    if (!looks(model, fe_bodies_[k]))
      continue;
    if (all || !model.at_rest[fe_bodies_[k]])
      measureBody(model, k);
    const Box &box = boxes_[k];
    r = {std::min(r.x0, box.x0 - reach), std::min(r.y0, box.y0 - reach),
         std::max(r.x1, box.x1 + reach), std::max(r.y1, box.y1 + reach)};
  }
  region_ = r, reach_ = reach;
  measured_ = true;
  return r;
}

void DiskContact::measureBodies(const fem::Model &model, const std::vector<std::uint32_t> &bodies) {
  for (const std::uint32_t b : bodies) {
    const auto k = static_cast<std::size_t>(
        std::lower_bound(fe_bodies_.begin(), fe_bodies_.end(), b) - fe_bodies_.begin());
    if (k < fe_bodies_.size() && fe_bodies_[k] == b)
      measureBody(model, k);
  }
}

// Body k's box from its nodes now, and whether its grid still holds.
void DiskContact::measureBody(const fem::Model &model, std::size_t k) {
  const fem::Nodes &nd = model.nodes;
  const auto &edges = model.bodies[fe_bodies_[k]].boundary;
  Box &box = boxes_[k];
  box = {INFINITY, INFINITY, -INFINITY, -INFINITY};
  for (std::size_t e = 0; e < edges.size(); e += 2) {
    const std::uint32_t a = edges[e];
    box = {std::min(box.x0, nd.x[a]), std::min(box.y0, nd.y[a]), std::max(box.x1, nd.x[a]),
           std::max(box.y1, nd.y[a])};
  }
  EdgeGrid &grid = grids_[k];
  if (grid.valid) { // does it still hold?
    double moved2 = 0.0;
    for (std::size_t e = 0; e < edges.size(); e += 2)
      moved2 = std::max(moved2, sq(nd.x[edges[e]] - grid.built_x[e / 2]) +
                                    sq(nd.y[edges[e]] - grid.built_y[e / 2]));
    grid.valid = moved2 < grid.slack * grid.slack;
  }
}

double DiskContact::fastest(const fem::Model &model) const {
  const fem::Nodes &nd = model.nodes;
  double fastest2 = 0.0;
  for (const std::uint32_t b : fe_bodies_)
    if (!model.at_rest[b] && looks(model, b)) {
      const auto &edges = model.bodies[b].boundary;
      for (std::size_t e = 0; e < edges.size(); e += 2)
        fastest2 = std::max(fastest2,
                            nd.vx[edges[e]] * nd.vx[edges[e]] + nd.vy[edges[e]] * nd.vy[edges[e]]);
    }
  return std::sqrt(fastest2);
}

void DiskContact::addForces(const fem::Model &model, const Particles &disks, ParticleForces &forces,
                            std::vector<Reaction> &reactions, double dt) {
  const fem::Nodes &nd = model.nodes;
  const std::size_t n = disks.size();
  stats_.contacts = 0;
  // The depths of the last step; the allowances let go by a step's share.
  for (auto it = held_.begin(); it != held_.end();) {
    Held &h = it->second;
    h.last = h.now, h.now = 0.0, h.allowance = std::max(0.0, h.allowance - h.rate);
    it = h.last == 0.0 && h.allowance == 0.0 ? held_.erase(it) : std::next(it);
  }
  if (n == 0 || fe_bodies_.empty())
    return;
  // The region the FE bodies cover widened by the largest disk: only the disks whose centres lie
  // in it can touch a body (disks thrown far off do not widen the grid).
  double r_max = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    r_max = std::max(r_max, disks.radius[i]);
  if (!measured_ || reach_ < r_max)
    measure(model, r_max);
  measured_ = false;
  const Box region{region_.x0, region_.y0, region_.x1, region_.y1};
  auto inRegion = [&](std::size_t i) {
    return region.x0 <= disks.x[i] && disks.x[i] <= region.x1 && region.y0 <= disks.y[i] &&
           disks.y[i] <= region.y1;
  };
  // Those disks in a grid of cells as wide as the largest disk.
  in_region_.clear();
  for (std::size_t i = 0; i < n; ++i)
    if (inRegion(i))
      in_region_.push_back(static_cast<std::uint32_t>(i));
  disk_grid_.cover(region.x0, region.y0, region.x1 - region.x0, region.y1 - region.y0,
                   std::max(2.0 * r_max, 1e-12));
  disk_grid_.fillPoints(
      in_region_.size(), [&](std::size_t k) { return disks.x[in_region_[k]]; },
      [&](std::size_t k) { return disks.y[in_region_[k]]; },
      [&](std::size_t k) { return in_region_[k]; });

  const double kappa = 2.0 * s_.stiffness, c_damping = fem::dampingCoefficient(s_.damping, kappa);
  for (std::size_t kb = 0; kb < fe_bodies_.size(); ++kb) {
    const std::uint32_t b = fe_bodies_[kb];
    if (!looks(model, b))
      continue;
    const Box &box = boxes_[kb];
    const bool due = model.due.empty() || model.due[b];
    const std::size_t n_edges = model.bodies[b].boundary.size() / 2;
    bool binned = false; // its segments, binned when a disk first comes near (many) or listed (few)
    disk_grid_.forEach(
        disk_grid_.cells(box.x0 - r_max, box.y0 - r_max, box.x1 + r_max, box.y1 + r_max),
        [&](const std::uint32_t i) {
          const double cx = disks.x[i], cy = disks.y[i], r = disks.radius[i];
          if (cx + r < box.x0 || cx - r > box.x1 || cy + r < box.y0 || cy - r > box.y1)
            return;
          if (!binned) {
            binned = true;
            if (n_edges > 64) {
              if (!grids_[kb].valid)
                grids_[kb].build(model.bodies[b].boundary, nd.x.data(), nd.y.data(), box,
                                 2.0 * r_max);
            } else
              for (std::uint32_t e = 0, j = 0; j < n_edges; ++j, e += 2)
                j == 0 ? near_edges_.assign(1, e) : near_edges_.push_back(e);
          }
          if (n_edges > 64) { // the segments in the cells the disk's box meets
            const CellGrid<> &g = grids_[kb].cells;
            near_edges_.clear();
            g.forEach(g.cells(cx - r, cy - r, cx + r, cy + r),
                      [&](std::uint32_t e) { near_edges_.push_back(e); });
          }
          const Closest c = closest(model, b, cx, cy, r, near_edges_);
          const double found = r - c.distance; // c.distance < 0: the centre inside
          if (!(found > 0.0))
            return;
          if (!due) { // its nodes stand still between its steps: found at its next step
            ++stats_.not_due;
            return;
          }
          // relative velocity of the disk's contact point to the boundary point
          const double w1 = 1.0 - c.w, w2 = c.w;
          const double om = disks.omega[i];
          const double vx = disks.vx[i] + om * r * c.ny - (w1 * nd.vx[c.s1] + w2 * nd.vx[c.s2]);
          const double vy = disks.vy[i] - om * r * c.nx - (w1 * nd.vy[c.s1] + w2 * nd.vy[c.s2]);
          const double vn = fem::normalVelocity(vx, vy, c.nx, c.ny); // > 0: separating
          // A depth no step's approach makes (a boundary that erosion laid bare over the disk, a
          // dented body) is allowed for and let go over release_steps steps, as in FE-FE contact
          // (fem::approachReach).
          Held &held = held_[disks.id.empty() ? static_cast<std::int64_t>(i) : disks.id[i]];
          double depth = found - held.allowance;
          if (!(depth > 0.0))
            return;
          const double reach = fem::approachReach(held.last, size_[b], vn, dt);
          if (depth > reach) {
            held.allowance += depth - reach, held.rate = held.allowance / fem::release_steps;
            depth = reach, ++stats_.sudden;
          }
          held.now = std::max(held.now, depth);
          const double m = disks.mass[i], m_seg = w1 * nd.mass[c.s1] + w2 * nd.mass[c.s2];
          // the disk's tangential inertia with its spin: 1/m + r^2/I = 3/m
          const double m_eff = fem::reducedMass(m, m_seg), m_t = fem::reducedMass(m / 3.0, m_seg);
          const fem::ContactForce f_c = fem::contactForce(m_eff, m_t, depth, vx, vy, vn, c.nx, c.ny,
                                                          kappa, c_damping, s_.friction[b], dt);
          const double fx = f_c.fx, fy = f_c.fy, ft = f_c.ft, tx = f_c.tx, ty = f_c.ty;
          const double torque = -r * (c.nx * fy - c.ny * fx);
          forces.fx[i] += fx, forces.fy[i] += fy, forces.torque[i] += torque;
          reactions.push_back({c.s1, b, -w1 * fx, -w1 * fy, w1 * ft * tx, w1 * ft * ty});
          reactions.push_back({c.s2, b, -w2 * fx, -w2 * fy, w2 * ft * tx, w2 * ft * ty});
          stats_.work_on_disks += dt * (fx * disks.vx[i] + fy * disks.vy[i] + torque * om);
          stats_.deepest = std::max(stats_.deepest, found / size_[b]);
          ++stats_.contacts;
        });
  }
}

std::vector<std::int64_t> DiskContact::takeHeld(const std::function<bool(std::int64_t)> &here) {
  std::vector<std::int64_t> ids;
  for (const auto &[id, h] : held_)
    if (!here(id))
      ids.push_back(id);
  std::sort(ids.begin(), ids.end()); // (the map's order depends on its history)
  std::vector<std::int64_t> values;
  for (const std::int64_t id : ids) {
    const Held &h = held_.at(id);
    values.insert(values.end(),
                  {id, std::bit_cast<std::int64_t>(h.last), std::bit_cast<std::int64_t>(h.now),
                   std::bit_cast<std::int64_t>(h.allowance), std::bit_cast<std::int64_t>(h.rate)});
    held_.erase(id);
  }
  return values;
}

void DiskContact::putHeld(const std::vector<std::int64_t> &values,
                          const std::function<bool(std::int64_t)> &here) {
  for (std::size_t k = 0; k + 5 <= values.size(); k += 5)
    if (here(values[k]))
      held_[values[k]] = {
          std::bit_cast<double>(values[k + 1]), std::bit_cast<double>(values[k + 2]),
          std::bit_cast<double>(values[k + 3]), std::bit_cast<double>(values[k + 4])};
}

DiskContact::State DiskContact::state() const {
  State st;
  st.size = size_;
  // the disks in id order (the map's order depends on its history)
  std::vector<std::int64_t> ids;
  for (const auto &[id, h] : held_)
    ids.push_back(id);
  std::sort(ids.begin(), ids.end());
  for (std::int64_t id : ids) {
    const Held &h = held_.at(id);
    st.held.push_back(id);
    st.last.push_back(h.last), st.now.push_back(h.now);
    st.allowance.push_back(h.allowance), st.rate.push_back(h.rate);
  }
  for (std::size_t k = 0; k < grids_.size(); ++k) {
    const EdgeGrid &g = grids_[k];
    if (!g.valid)
      continue;
    st.grid_body.push_back(fe_bodies_[k]);
    st.grid_box.insert(st.grid_box.end(), {g.box.x0, g.box.y0, g.box.x1, g.box.y1, g.cell_size});
    st.grid_x.insert(st.grid_x.end(), g.built_x.begin(), g.built_x.end());
    st.grid_y.insert(st.grid_y.end(), g.built_y.begin(), g.built_y.end());
  }
  st.statistics = stats_;
  return st;
}

void DiskContact::restore(const fem::Model &model, const State &st) {
  boundaryChanged(model); // the bodies with a boundary; boxes measured anew at the next step
  const std::size_t n = st.held.size();
  if (st.size.size() != model.bodies.size() || st.last.size() != n || st.now.size() != n ||
      st.allowance.size() != n || st.rate.size() != n ||
      st.grid_box.size() != 5 * st.grid_body.size() || st.grid_x.size() != st.grid_y.size())
    throw std::invalid_argument("FE-DEM contact state: sizes not of this model");
  size_ = st.size;
  held_.clear();
  for (std::size_t i = 0; i < n; ++i)
    held_[st.held[i]] = {st.last[i], st.now[i], st.allowance[i], st.rate[i]};
  // Each grid built again from its nodes' positions then: a copy of the positions with the
  // body's boundary nodes put back there.
  grids_.resize(fe_bodies_.size());
  std::vector<double> x, y;
  std::size_t at = 0;
  for (std::size_t g = 0; g < st.grid_body.size(); ++g) {
    const auto k = static_cast<std::size_t>(
        std::lower_bound(fe_bodies_.begin(), fe_bodies_.end(), st.grid_body[g]) -
        fe_bodies_.begin());
    if (k == fe_bodies_.size() || fe_bodies_[k] != st.grid_body[g])
      throw std::invalid_argument("FE-DEM contact state: a grid of a body without a boundary");
    const auto &edges = model.bodies[fe_bodies_[k]].boundary;
    if (at + edges.size() / 2 > st.grid_x.size())
      throw std::invalid_argument("FE-DEM contact state: a grid not of this model");
    if (x.empty())
      x = model.nodes.x, y = model.nodes.y;
    for (std::size_t e = 0; e < edges.size(); e += 2)
      x[edges[e]] = st.grid_x[at + e / 2], y[edges[e]] = st.grid_y[at + e / 2];
    const double *b = &st.grid_box[5 * g];
    grids_[k].build(edges, x.data(), y.data(), Box{b[0], b[1], b[2], b[3]}, b[4]);
    at += edges.size() / 2;
  }
  stats_ = st.statistics;
}

} // namespace mesopen::coupling
