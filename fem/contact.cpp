#include "contact.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <tuple>

namespace mesopen::fem {

namespace {
constexpr std::uint32_t no_node = 0xffffffffu;
constexpr double touching = 1e-6; // penetration (this fraction of an element) taken as touching
constexpr double deep = 0.5;        // penetration beyond this fraction of an element counts as deep
constexpr std::size_t max_cells = 1u << 22;

bool overlap(double a0, double a1, double b0, double b1) { return a0 <= b1 && b0 <= a1; }
} // namespace

Contact::Contact(const Model &model, ContactSettings settings) : s_(std::move(settings)) {
  n_materials_ = model.materials.size();
  if (s_.friction.size() == 1)
    s_.friction.assign(n_materials_ * n_materials_, s_.friction[0]);
  if (s_.friction.size() != n_materials_ * n_materials_)
    throw std::invalid_argument("contact: friction needs one value or one per pair of materials");
  const Nodes &nd = model.nodes;
  const std::size_t n_bodies = model.bodies.size();
  node_begin_.push_back(0), segment_begin_.push_back(0);
  std::vector<double> extents;
  for (const Body &body : model.bodies) {
    std::vector<std::uint32_t> nodes(body.boundary.begin(), body.boundary.end());
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    nodes_.insert(nodes_.end(), nodes.begin(), nodes.end());
    segments_.insert(segments_.end(), body.boundary.begin(), body.boundary.end());
    node_begin_.push_back(nodes_.size());
    segment_begin_.push_back(segments_.size() / 2);
    double longest = 0.0, x0 = HUGE_VAL, x1 = -HUGE_VAL, y0 = HUGE_VAL, y1 = -HUGE_VAL;
    for (std::size_t k = 0; k + 1 < body.boundary.size(); k += 2) {
      const std::uint32_t a = body.boundary[k], b = body.boundary[k + 1];
      longest = std::max(longest, std::hypot(nd.x[b] - nd.x[a], nd.y[b] - nd.y[a]));
    }
    for (std::uint32_t a : nodes)
      x0 = std::min(x0, nd.x[a]), x1 = std::max(x1, nd.x[a]), y0 = std::min(y0, nd.y[a]),
      y1 = std::max(y1, nd.y[a]);
    size_.push_back(longest);
    if (!nodes.empty())
      extents.push_back(std::max(x1 - x0, y1 - y0));
  }
  // Grid cells about twice the typical body: a grain sits in at most four cells.
  if (!extents.empty()) {
    std::nth_element(extents.begin(), extents.begin() + extents.size() / 2, extents.end());
    cell_ = 2.0 * extents[extents.size() / 2];
  }
  boxes_.resize(n_bodies);
  box_valid_.assign(n_bodies, 0);
  thread_hits_.resize(static_cast<std::size_t>(omp_get_max_threads()));
}

void Contact::addForces(Model &model, double, double dt) {
  const auto start = std::chrono::steady_clock::now();
  updateBoxes(model);
  findPairs(model);

  // Narrow phase: each thread takes a contiguous run of pairs, so that the hits, taken thread by
  // thread, come in pair order whatever the number of threads.
  const std::size_t n_pairs = pairs_.size();
  const int threads = omp_get_max_threads();
  if (thread_hits_.size() < static_cast<std::size_t>(threads))
    thread_hits_.resize(threads);
  for (auto &hits : thread_hits_)
    hits.clear();
#pragma omp parallel num_threads(threads) if (n_pairs > 64)
  {
    const std::size_t t = static_cast<std::size_t>(omp_get_thread_num());
    const std::size_t T = static_cast<std::size_t>(omp_get_num_threads());
    std::vector<Hit> &hits = thread_hits_[t];
    std::vector<Segment> scratch;
    for (std::size_t i = n_pairs * t / T; i < n_pairs * (t + 1) / T; ++i) {
      touch(model, pairs_[i].first, pairs_[i].second, dt, hits, scratch);
      touch(model, pairs_[i].second, pairs_[i].first, dt, hits, scratch);
    }
    if (t + 1 == T)
      walls(model, dt, hits);
  }

  // Into the nodes, in order; every body loaded takes part in the step.
  Nodes &nd = model.nodes;
  stats_.pairs = n_pairs;
  stats_.contacts = 0;
  stats_.depth = 0.0;
  for (const auto &hits : thread_hits_)
    for (const Hit &h : hits) {
      nd.fx_ext[h.node] += h.fx, nd.fy_ext[h.node] += h.fy;
      nd.fx_friction[h.node] += h.friction_x, nd.fy_friction[h.node] += h.friction_y;
      model.wake(nd.body[h.node]);
      if (h.s1 != no_node) {
        for (auto [s, w] : {std::pair{h.s1, h.w1}, {h.s2, h.w2}}) {
          nd.fx_ext[s] -= w * h.fx, nd.fy_ext[s] -= w * h.fy;
          nd.fx_friction[s] -= w * h.friction_x, nd.fy_friction[s] -= w * h.friction_y;
        }
        model.wake(nd.body[h.s1]);
      }
      ++stats_.contacts;
      stats_.depth = std::max(stats_.depth, h.depth);
      stats_.deep += h.depth > deep;
    }
  stats_.max_depth = std::max(stats_.max_depth, stats_.depth);
  stats_.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Bounding boxes of the boundary nodes: of every moving body; of a body at rest once.
void Contact::updateBoxes(const Model &model) {
  const Nodes &nd = model.nodes;
  const long n = static_cast<long>(model.bodies.size());
#pragma omp parallel for schedule(static) if (n > 256)
  for (long b = 0; b < n; ++b) {
    if (model.bodies[b].at_rest && box_valid_[b])
      continue;
    Box box{HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (std::size_t k = node_begin_[b]; k < node_begin_[b + 1]; ++k) {
      const std::uint32_t a = nodes_[k];
      box.x0 = std::min(box.x0, nd.x[a]), box.x1 = std::max(box.x1, nd.x[a]);
      box.y0 = std::min(box.y0, nd.y[a]), box.y1 = std::max(box.y1, nd.y[a]);
    }
    boxes_[b] = box;
    box_valid_[b] = 1;
  }
}

// Broad phase: the boxes in a uniform grid (cell lists); a pair of bodies whose boxes overlap is
// taken once, in the cell that holds the lower-left corner of the overlap.
void Contact::findPairs(const Model &model) {
  pairs_.clear();
  const std::size_t n = model.bodies.size();
  double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL;
  for (std::size_t b = 0; b < n; ++b)
    if (node_begin_[b] < node_begin_[b + 1]) {
      x0 = std::min(x0, boxes_[b].x0), x1 = std::max(x1, boxes_[b].x1);
      y0 = std::min(y0, boxes_[b].y0), y1 = std::max(y1, boxes_[b].y1);
    }
  if (!(x1 >= x0) || !(cell_ > 0.0))
    return;
  double cell = cell_;
  // A body flung far away must not make the grid huge: coarser cells then.
  while (((x1 - x0) / cell + 1) * ((y1 - y0) / cell + 1) > static_cast<double>(max_cells))
    cell *= 2.0;
  const auto nx = static_cast<std::size_t>((x1 - x0) / cell) + 1;
  const auto ny = static_cast<std::size_t>((y1 - y0) / cell) + 1;
  auto ix = [&](double x) { return std::min(static_cast<std::size_t>((x - x0) / cell), nx - 1); };
  auto iy = [&](double y) { return std::min(static_cast<std::size_t>((y - y0) / cell), ny - 1); };
  cell_start_.assign(nx * ny + 1, 0);
  for (int pass = 0; pass < 2; ++pass) {
    for (std::size_t b = 0; b < n; ++b) {
      if (node_begin_[b] == node_begin_[b + 1])
        continue;
      const Box &box = boxes_[b];
      for (std::size_t j = iy(box.y0); j <= iy(box.y1); ++j)
        for (std::size_t i = ix(box.x0); i <= ix(box.x1); ++i) {
          if (pass == 0)
            ++cell_start_[j * nx + i + 1];
          else
            cell_bodies_[cell_start_[j * nx + i]++] = static_cast<std::uint32_t>(b);
        }
    }
    if (pass == 0) {
      for (std::size_t c = 0; c < nx * ny; ++c)
        cell_start_[c + 1] += cell_start_[c];
      cell_bodies_.resize(cell_start_.back());
    } else { // the fill moved each start to the next cell's: shift back
      for (std::size_t c = nx * ny; c > 0; --c)
        cell_start_[c] = cell_start_[c - 1];
      cell_start_[0] = 0;
    }
  }
  for (std::size_t c = 0; c < nx * ny; ++c)
    for (std::size_t i = cell_start_[c]; i < cell_start_[c + 1]; ++i)
      for (std::size_t j = i + 1; j < cell_start_[c + 1]; ++j) {
        const std::uint32_t a = cell_bodies_[i], b = cell_bodies_[j];
        if (model.bodies[a].at_rest && model.bodies[b].at_rest)
          continue;
        const Box &A = boxes_[a], &B = boxes_[b];
        if (!overlap(A.x0, A.x1, B.x0, B.x1) || !overlap(A.y0, A.y1, B.y0, B.y1))
          continue;
        if (iy(std::max(A.y0, B.y0)) * nx + ix(std::max(A.x0, B.x0)) == c)
          pairs_.emplace_back(a, b);
      }
}

// The boundary nodes of body A that are inside body B. A node inside B is in the overlap of the
// two boxes; the segment that decides is the closest to it, within one element size of it.
void Contact::touch(const Model &model, std::size_t A, std::size_t B, double dt,
                    std::vector<Hit> &hits, std::vector<Segment> &segs) const {
  const Nodes &nd = model.nodes;
  const Box &a = boxes_[A], &b = boxes_[B];
  const double rx0 = std::max(a.x0, b.x0), rx1 = std::min(a.x1, b.x1);
  const double ry0 = std::max(a.y0, b.y0), ry1 = std::min(a.y1, b.y1);
  const double h = size_[B], reach = h;
  segs.clear();
  for (std::size_t k = segment_begin_[B]; k < segment_begin_[B + 1]; ++k) {
    const std::uint32_t s1 = segments_[2 * k], s2 = segments_[2 * k + 1];
    const double ax = nd.x[s1], ay = nd.y[s1], bx = nd.x[s2], by = nd.y[s2];
    if (std::max(ax, bx) < rx0 - reach || std::min(ax, bx) > rx1 + reach ||
        std::max(ay, by) < ry0 - reach || std::min(ay, by) > ry1 + reach)
      continue;
    const double length = std::hypot(bx - ax, by - ay);
    if (!(length > 0.0))
      continue;
    const double tx = (bx - ax) / length, ty = (by - ay) / length;
    segs.push_back({s1, s2, ax, ay, tx, ty, length, ty, -tx}); // outward: the tangent turned right
  }
  if (segs.empty())
    return;
  const double mu = s_.friction[model.bodies[A].material * n_materials_ + model.bodies[B].material];
  for (std::size_t k = node_begin_[A]; k < node_begin_[A + 1]; ++k) {
    const std::uint32_t p = nodes_[k];
    const double px = nd.x[p], py = nd.y[p];
    if (px < rx0 || px > rx1 || py < ry0 || py > ry1)
      continue;
    // The closest point of B's boundary: on a segment's inside (the node then lies on the normal
    // through it) or at a corner (the node is then outside a convex corner: no contact).
    double best = HUGE_VAL, depth = 0.0, along = 0.0;
    const Segment *closest = nullptr;
    for (const Segment &s : segs) {
      const double dx = px - s.ax, dy = py - s.ay;
      const double t = dx * s.tx + dy * s.ty, g = dx * s.nx + dy * s.ny;
      const double excess = t < 0.0 ? -t : (t > s.length ? t - s.length : 0.0);
      const double distance = excess * excess + g * g;
      if (distance < best)
        best = distance, closest = excess > 0.0 ? nullptr : &s, depth = -g, along = t;
    }
    if (!closest || depth <= touching * h)
      continue;
    hit(model, p, closest->a, closest->b, along / closest->length, closest->nx, closest->ny,
        depth - touching * h, mu, dt, hits);
    hits.back().depth = depth / h;
  }
}

// The rigid walls: a boundary node of a moving body beyond a wall is pushed back along its normal.
void Contact::walls(const Model &model, double dt, std::vector<Hit> &hits) const {
  const Nodes &nd = model.nodes;
  const bool left = !std::isnan(s_.wall_left), right = !std::isnan(s_.wall_right),
             bottom = !std::isnan(s_.wall_bottom);
  if (!left && !right && !bottom)
    return;
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    if (model.bodies[b].at_rest)
      continue;
    const double tol = touching * size_[b];
    for (std::size_t k = node_begin_[b]; k < node_begin_[b + 1]; ++k) {
      const std::uint32_t p = nodes_[k];
      for (auto [on, depth, nx, ny] : {std::tuple{left, s_.wall_left - nd.x[p], 1.0, 0.0},
                                       {right, nd.x[p] - s_.wall_right, -1.0, 0.0},
                                       {bottom, s_.wall_bottom - nd.y[p], 0.0, 1.0}})
        if (on && depth > tol) {
          hit(model, p, no_node, no_node, 0.0, nx, ny, depth - tol, s_.wall_friction, dt, hits);
          hits.back().depth = depth / size_[b];
        }
    }
  }
}

// The force on `node`, pushed out along (nx, ny) by `depth` from the segment s1-s2 (at weight w2
// from s1) or from a wall (s1 = no_node); relative velocities at mid-step.
void Contact::hit(const Model &model, std::uint32_t p, std::uint32_t s1, std::uint32_t s2,
                  double w2, double nx, double ny, double depth, double mu, double dt,
                  std::vector<Hit> &hits) const {
  const Nodes &nd = model.nodes;
  const double w1 = 1.0 - w2;
  double m_eff = nd.mass[p], vx = nd.vx[p], vy = nd.vy[p];
  if (s1 != no_node) {
    const double m_seg = w1 * nd.mass[s1] + w2 * nd.mass[s2];
    m_eff = m_eff * m_seg / (m_eff + m_seg);
    vx -= w1 * nd.vx[s1] + w2 * nd.vx[s2];
    vy -= w1 * nd.vy[s1] + w2 * nd.vy[s2];
  }
  const double vn = vx * nx + vy * ny; // > 0: separating
  const double kappa = s_.stiffness, c = 2.0 * s_.damping * std::sqrt(kappa);
  const double fn = std::max(0.0, m_eff / dt * (kappa * depth / dt - c * vn));
  const double tx = vx - vn * nx, ty = vy - vn * ny, slip = std::hypot(tx, ty);
  const double ft = slip > 0.0 ? std::min(mu * fn, m_eff * slip / dt) / slip : 0.0;
  hits.push_back({p, s1, s2, w1, w2, fn * nx - ft * tx, fn * ny - ft * ty, -ft * tx, -ft * ty, 0.0});
}

} // namespace mesopen::fem
