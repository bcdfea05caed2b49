#include "disk_contact.hpp"

#include "contact.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <stdexcept>

namespace mesopen::coupling {

namespace {
constexpr std::size_t max_cells = 1u << 22;
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
// those in `near` (offsets into the body's boundary: every segment within reach among them), and the
// side: at a segment's inside by its outward normal (the tangent turned right: boundaries run
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
      const double ox = nd.x[edges[e + 1]] - nd.x[edges[e]], oy = nd.y[edges[e + 1]] - nd.y[edges[e]];
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
// quarter cell meets), with their first nodes' positions now.
void DiskContact::EdgeGrid::build(const fem::Model &model, std::size_t body, const Box &box,
                                  double cell_size) {
  const fem::Nodes &nd = model.nodes;
  const auto &edges = model.bodies[body].boundary;
  const std::size_t n = edges.size() / 2;
  // cells of a few segments' length, or the disks' size if larger
  cell = std::max(cell_size, 4.0 * std::sqrt((box.x1 - box.x0) * (box.y1 - box.y0) / n));
  inverse = 1.0 / cell;
  slack = 0.25 * cell;
  x0 = box.x0 - slack, y0 = box.y0 - slack;
  nx = static_cast<std::size_t>((box.x1 - box.x0 + 2.0 * slack) / cell) + 1;
  ny = static_cast<std::size_t>((box.y1 - box.y0 + 2.0 * slack) / cell) + 1;
  start.assign(nx * ny + 1, 0);
  built_x.resize(n), built_y.resize(n);
  for (std::size_t e = 0; e < edges.size(); e += 2)
    built_x[e / 2] = nd.x[edges[e]], built_y[e / 2] = nd.y[edges[e]];
  auto span = [&](std::size_t e, auto visit) {
    const double ax = nd.x[edges[e]], ay = nd.y[edges[e]], bx = nd.x[edges[e + 1]],
                 by = nd.y[edges[e + 1]];
    const std::size_t i0 = ix(std::min(ax, bx) - slack), i1 = ix(std::max(ax, bx) + slack);
    const std::size_t j0 = iy(std::min(ay, by) - slack), j1 = iy(std::max(ay, by) + slack);
    for (std::size_t j = j0; j <= j1; ++j)
      for (std::size_t i = i0; i <= i1; ++i)
        visit(j * nx + i);
  };
  for (std::size_t e = 0; e < edges.size(); e += 2)
    span(e, [&](std::size_t c) { ++start[c + 1]; });
  for (std::size_t c = 0; c < nx * ny; ++c)
    start[c + 1] += start[c];
  items.resize(start.back());
  std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
  for (std::size_t e = 0; e < edges.size(); e += 2)
    span(e, [&](std::size_t c) { items[fill[c]++] = static_cast<std::uint32_t>(e); });
  valid = true;
}

std::size_t DiskContact::EdgeGrid::ix(double x) const {
  const double i = (x - x0) * inverse;
  return i <= 0.0 ? 0 : std::min(static_cast<std::size_t>(i), nx - 1);
}
std::size_t DiskContact::EdgeGrid::iy(double y) const {
  const double j = (y - y0) * inverse;
  return j <= 0.0 ? 0 : std::min(static_cast<std::size_t>(j), ny - 1);
}

// The segments in the cells the rectangle meets (a segment may come more than once).
void DiskContact::EdgeGrid::nearBox(double xa, double ya, double xb, double yb,
                                    std::vector<std::uint32_t> &out) const {
  out.clear();
  for (std::size_t j = iy(ya); j <= iy(yb); ++j)
    for (std::size_t i = ix(xa); i <= ix(xb); ++i)
      out.insert(out.end(), items.begin() + start[j * nx + i], items.begin() + start[j * nx + i + 1]);
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
  const fem::Nodes &nd = model.nodes;
  // (a body at rest keeps its box: its nodes have not moved)
  const bool all = boxes_.size() != fe_bodies_.size();
  boxes_.resize(fe_bodies_.size());
  grids_.resize(fe_bodies_.size());
  Region r{INFINITY, INFINITY, -INFINITY, -INFINITY};
  for (std::size_t k = 0; k < fe_bodies_.size(); ++k) {
    Box &box = boxes_[k];
    if (all || !model.at_rest[fe_bodies_[k]]) {
      const auto &edges = model.bodies[fe_bodies_[k]].boundary;
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
    r = {std::min(r.x0, box.x0 - reach), std::min(r.y0, box.y0 - reach),
         std::max(r.x1, box.x1 + reach), std::max(r.y1, box.y1 + reach)};
  }
  region_ = r, reach_ = reach;
  measured_ = true;
  return r;
}

double DiskContact::fastest(const fem::Model &model) const {
  const fem::Nodes &nd = model.nodes;
  double fastest2 = 0.0;
  for (const std::uint32_t b : fe_bodies_)
    if (!model.at_rest[b]) {
      const auto &edges = model.bodies[b].boundary;
      for (std::size_t e = 0; e < edges.size(); e += 2)
        fastest2 = std::max(fastest2, nd.vx[edges[e]] * nd.vx[edges[e]] + nd.vy[edges[e]] * nd.vy[edges[e]]);
    }
  return std::sqrt(fastest2);
}

void DiskContact::addForces(const fem::Model &model, const Particles &disks,
                            ParticleForces &forces, std::vector<Reaction> &reactions, double dt) {
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
  const double x0 = region.x0, y0 = region.y0;
  double cell = std::max(2.0 * r_max, 1e-12);
  std::size_t gx = 0, gy = 0;
  for (;; cell *= 2.0) {
    gx = static_cast<std::size_t>((region.x1 - x0) / cell) + 1;
    gy = static_cast<std::size_t>((region.y1 - y0) / cell) + 1;
    if (gx * gy <= max_cells)
      break;
  }
  auto cellOf = [&](std::size_t i) {
    const auto ix = std::min(gx - 1, static_cast<std::size_t>((disks.x[i] - x0) / cell));
    const auto iy = std::min(gy - 1, static_cast<std::size_t>((disks.y[i] - y0) / cell));
    return iy * gx + ix;
  };
  cell_start_.assign(gx * gy + 1, 0);
  for (std::size_t i = 0; i < n; ++i)
    if (inRegion(i))
      ++cell_start_[cellOf(i) + 1];
  for (std::size_t c = 0; c < gx * gy; ++c)
    cell_start_[c + 1] += cell_start_[c];
  cell_disks_.resize(cell_start_.back());
  {
    std::vector<std::size_t> fill(cell_start_.begin(), cell_start_.end() - 1);
    for (std::size_t i = 0; i < n; ++i)
      if (inRegion(i))
        cell_disks_[fill[cellOf(i)]++] = static_cast<std::uint32_t>(i);
  }

  const double kappa = 2.0 * s_.stiffness, zeta_c = 2.0 * s_.damping * std::sqrt(kappa);
  for (std::size_t kb = 0; kb < fe_bodies_.size(); ++kb) {
    const std::uint32_t b = fe_bodies_[kb];
    const Box &box = boxes_[kb];
    const std::size_t n_edges = model.bodies[b].boundary.size() / 2;
    bool binned = false; // its segments, binned when a disk first comes near (many) or listed (few)
    const auto ix0 = static_cast<std::size_t>(std::max(0.0, (box.x0 - r_max - x0) / cell));
    const auto iy0 = static_cast<std::size_t>(std::max(0.0, (box.y0 - r_max - y0) / cell));
    const auto ix1 = std::min(gx - 1, static_cast<std::size_t>(std::max(0.0, (box.x1 + r_max - x0) / cell)));
    const auto iy1 = std::min(gy - 1, static_cast<std::size_t>(std::max(0.0, (box.y1 + r_max - y0) / cell)));
    for (std::size_t iy = iy0; iy <= iy1; ++iy)
      for (std::size_t ix = ix0; ix <= ix1; ++ix)
        for (std::size_t k = cell_start_[iy * gx + ix]; k < cell_start_[iy * gx + ix + 1]; ++k) {
          const std::uint32_t i = cell_disks_[k];
          const double cx = disks.x[i], cy = disks.y[i], r = disks.radius[i];
          if (cx + r < box.x0 || cx - r > box.x1 || cy + r < box.y0 || cy - r > box.y1)
            continue;
          if (!binned) {
            binned = true;
            if (n_edges > 64) {
              if (!grids_[kb].valid)
                grids_[kb].build(model, b, box, 2.0 * r_max);
            } else
              for (std::uint32_t e = 0, j = 0; j < n_edges; ++j, e += 2)
                j == 0 ? near_edges_.assign(1, e) : near_edges_.push_back(e);
          }
          if (n_edges > 64)
            grids_[kb].nearBox(cx - r, cy - r, cx + r, cy + r, near_edges_);
          const Closest c = closest(model, b, cx, cy, r, near_edges_);
          const double found = r - c.distance; // c.distance < 0: the centre inside
          if (!(found > 0.0))
            continue;
          // relative velocity of the disk's contact point to the boundary point
          const double w1 = 1.0 - c.w, w2 = c.w;
          const double om = disks.omega[i];
          const double vx = disks.vx[i] + om * r * c.ny - (w1 * nd.vx[c.s1] + w2 * nd.vx[c.s2]);
          const double vy = disks.vy[i] - om * r * c.nx - (w1 * nd.vy[c.s1] + w2 * nd.vy[c.s2]);
          const double vn = vx * c.nx + vy * c.ny; // > 0: separating
          // A depth no step's approach makes (a boundary that erosion laid bare over the disk, a
          // dented body) is allowed for and let go over release_steps steps, as in FE-FE contact
          // (fem::approachReach).
          Held &held = held_[disks.id.empty() ? static_cast<std::int64_t>(i) : disks.id[i]];
          double depth = found - held.allowance;
          if (!(depth > 0.0))
            continue;
          const double reach = fem::approachReach(held.last, size_[b], vn, dt);
          if (depth > reach) {
            held.allowance += depth - reach, held.rate = held.allowance / fem::release_steps;
            depth = reach, ++stats_.sudden;
          }
          held.now = std::max(held.now, depth);
          const double m = disks.mass[i], m_seg = w1 * nd.mass[c.s1] + w2 * nd.mass[c.s2];
          const double m_eff = m * m_seg / (m + m_seg), m_t = (m / 3.0) * m_seg / (m / 3.0 + m_seg);
          const double fn = std::max(0.0, m_eff / dt * (kappa * depth / dt - zeta_c * vn));
          const double tx = vx - vn * c.nx, ty = vy - vn * c.ny, slip = std::sqrt(tx * tx + ty * ty);
          const double ft = slip > 0.0 ? std::min(s_.friction[b] * fn, m_t * slip / dt) / slip : 0.0;
          const double fx = fn * c.nx - ft * tx, fy = fn * c.ny - ft * ty;
          const double torque = -r * (c.nx * fy - c.ny * fx);
          forces.fx[i] += fx, forces.fy[i] += fy, forces.torque[i] += torque;
          reactions.push_back({c.s1, b, -w1 * fx, -w1 * fy, w1 * ft * tx, w1 * ft * ty});
          reactions.push_back({c.s2, b, -w2 * fx, -w2 * fy, w2 * ft * tx, w2 * ft * ty});
          stats_.work_on_disks += dt * (fx * disks.vx[i] + fy * disks.vy[i] + torque * om);
          stats_.deepest = std::max(stats_.deepest, found / size_[b]);
          ++stats_.contacts;
        }
  }
}

} // namespace mesopen::coupling
