#include "tessellation.hpp"

#include "point_grid.hpp"
#include "polygon.hpp"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Regular_triangulation_2.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace mesopen {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
struct FaceInfo {
  std::int32_t vp = -1;  // index of the face's Voronoi point, -1 until computed
  bool restored = false; // the point stays at the circumcentre (plain Voronoi)
};
using DVb = CGAL::Triangulation_vertex_base_with_info_2<std::uint32_t, K>;
using DFb = CGAL::Triangulation_face_base_with_info_2<FaceInfo, K>;
using Delaunay = CGAL::Delaunay_triangulation_2<K, CGAL::Triangulation_data_structure_2<DVb, DFb>>;
using RVb =
    CGAL::Triangulation_vertex_base_with_info_2<std::uint32_t, K,
                                                CGAL::Regular_triangulation_vertex_base_2<K>>;
using RFb = CGAL::Triangulation_face_base_with_info_2<FaceInfo, K,
                                                      CGAL::Regular_triangulation_face_base_2<K>>;
using Regular = CGAL::Regular_triangulation_2<K, CGAL::Triangulation_data_structure_2<RVb, RFb>>;

// Sites and their mirror images in the four walls (and the corners), so that every cell of a
// site in the box is bounded and the cells meet the walls exactly.
struct Images {
  std::vector<double> x, y;
  std::vector<std::uint32_t> site;
  std::vector<std::uint8_t> real;
  std::vector<std::uint32_t> first; // per site: its images are [first, first + count)
  std::vector<std::uint8_t> count;

  void add(const Sites &s, std::uint32_t i, double w, double h, double reach) {
    if (first.size() <= i) {
      first.resize(i + 1);
      count.resize(i + 1);
    }
    first[i] = static_cast<std::uint32_t>(x.size());
    const double xs = s.x[i], ys = s.y[i];
    const double mx[3] = {xs, -xs, 2.0 * w - xs}, my[3] = {ys, -ys, 2.0 * h - ys};
    const bool nx[3] = {true, xs < reach, w - xs < reach},
               ny[3] = {true, ys < reach, h - ys < reach};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        if (nx[a] && ny[b]) {
          x.push_back(mx[a]);
          y.push_back(my[b]);
          site.push_back(i);
          real.push_back(a == 0 && b == 0);
        }
    count[i] = static_cast<std::uint8_t>(x.size() - first[i]);
  }
};

// Eq. 4.4 in least squares: the point v minimising sum_k (|v - p_k| - r_k)^2, by Gauss-Newton
// from the circumcentre c. Along a wall (tangent t through c) the search is one-dimensional.
struct Relaxer {
  double tolerance;
  Point solve(Point c, const double px[3], const double py[3], const double r[3],
              const double *tangent) const {
    double vx = c.x, vy = c.y;
    const double cap = 0.5 * std::min({r[0], r[1], r[2]});
    for (int it = 0; it < 50; ++it) {
      double a00 = 0, a01 = 0, a11 = 0, g0 = 0, g1 = 0;
      for (int k = 0; k < 3; ++k) {
        const double dx = vx - px[k], dy = vy - py[k], len = std::hypot(dx, dy);
        if (len == 0.0)
          continue;
        const double ux = dx / len, uy = dy / len, e = len - r[k];
        a00 += ux * ux, a01 += ux * uy, a11 += uy * uy;
        g0 += ux * e, g1 += uy * e;
      }
      double sx, sy;
      if (tangent) {
        const double tx = tangent[0], ty = tangent[1];
        const double jj = a00 * tx * tx + 2 * a01 * tx * ty + a11 * ty * ty;
        const double s = jj > 0 ? -(g0 * tx + g1 * ty) / jj : 0.0;
        sx = s * tx, sy = s * ty;
      } else {
        const double det = a00 * a11 - a01 * a01;
        if (det > 1e-12) {
          sx = -(a11 * g0 - a01 * g1) / det;
          sy = -(a00 * g1 - a01 * g0) / det;
        } else { // the three directions are nearly parallel: a plain gradient step
          sx = -g0 / 3.0, sy = -g1 / 3.0;
        }
      }
      const double len = std::hypot(sx, sy);
      if (len > cap)
        sx *= cap / len, sy *= cap / len;
      vx += sx, vy += sy;
      if (len < tolerance)
        break;
    }
    return {vx, vy};
  }
};

// The tessellation under construction: triangulation of the images, the points of its faces.
template <class Tri> struct Cells {
  Tri tri;
  Images images;
  std::vector<typename Tri::Vertex_handle> handle; // per image (null when hidden or removed)
  std::vector<double> vpx, vpy;
  std::vector<std::uint8_t> alive; // per site
  double void_factor = 1.0;        // void radii are scaled by this
  double radius(const Sites &s, std::uint32_t i) const {
    return i < s.grains ? s.r[i] : void_factor * s.r[i];
  }
};

std::uint32_t commonVertex(auto f, auto g, auto v) {
  for (int i = 0; i < 3; ++i)
    if (f->vertex(i) != v && g->has_vertex(f->vertex(i)))
      return f->vertex(i)->info();
  throw std::logic_error("tessellation: consecutive faces share no edge");
}

// One grain cell walked counter-clockwise: its faces, their points, and the image across the
// Voronoi edge that follows each point.
template <class Tri> struct Ring {
  std::vector<typename Tri::Face_handle> face;
  std::vector<std::uint32_t> across;
};

template <class Tri> bool ringOf(const Cells<Tri> &c, std::uint32_t site, Ring<Tri> &ring) {
  ring.face.clear();
  ring.across.clear();
  const auto v = c.handle[c.images.first[site]];
  if (v == typename Tri::Vertex_handle())
    return false;
  auto fc = c.tri.incident_faces(v), done = fc;
  do {
    if (c.tri.is_infinite(fc))
      throw std::logic_error("tessellation: a grain cell is unbounded (mirror layer too thin)");
    ring.face.push_back(fc);
  } while (++fc != done);
  const std::size_t n = ring.face.size();
  for (std::size_t k = 0; k < n; ++k)
    ring.across.push_back(commonVertex(ring.face[k], ring.face[(k + 1) % n], v));
  return true;
}

// Into the box, and onto a wall when round-off left the point a hair's breadth from it (points
// between a site and its mirror image lie on the wall exactly in exact arithmetic).
void clampToBox(double &x, double &y, double w, double h) {
  const double snap = 1e-12 * (w + h);
  x = x < snap ? 0.0 : x > w - snap ? w : x;
  y = y < snap ? 0.0 : y > h - snap ? h : y;
}

// Points of every face that touches a real grain and has none yet.
void computeVoronoiPoints(Cells<Delaunay> &c, const Sites &s, const TargetSpec &spec) {
  const Relaxer relax{1e-9 * spec.meanDiameter()};
  const double w = spec.width, h = spec.height;
  for (auto f = c.tri.finite_faces_begin(); f != c.tri.finite_faces_end(); ++f) {
    if (f->info().vp >= 0 && !f->info().restored)
      continue;
    std::uint32_t im[3];
    bool grain = false;
    for (int i = 0; i < 3; ++i) {
      im[i] = f->vertex(i)->info();
      grain |= c.images.real[im[i]] && c.images.site[im[i]] < s.grains;
    }
    if (!grain)
      continue;
    const K::Point_2 cc = c.tri.circumcenter(f);
    Point p{cc.x(), cc.y()};
    if (!f->info().restored) {
      double px[3], py[3], r[3];
      for (int i = 0; i < 3; ++i)
        px[i] = c.images.x[im[i]], py[i] = c.images.y[im[i]],
        r[i] = c.radius(s, c.images.site[im[i]]);
      // Two images of one site: their bisector is a wall, and the point stays on it.
      const std::uint32_t s0 = c.images.site[im[0]], s1 = c.images.site[im[1]],
                          s2 = c.images.site[im[2]];
      if (s0 == s1 && s1 == s2) {
        p = {std::round(p.x / w) * w, std::round(p.y / h) * h}; // a corner
      } else if (s0 == s1 || s1 == s2 || s0 == s2) {
        const int a = s0 == s1 ? 0 : (s1 == s2 ? 1 : 0), b = s0 == s1 ? 1 : 2;
        const bool vertical = px[a] != px[b];
        const double tangent[2] = {vertical ? 0.0 : 1.0, vertical ? 1.0 : 0.0};
        p = relax.solve(p, px, py, r, tangent);
        if (vertical)
          p.x = std::round(p.x / w) * w;
        else
          p.y = std::round(p.y / h) * h;
      } else {
        p = relax.solve(p, px, py, r, nullptr);
      }
    }
    clampToBox(p.x, p.y, w, h);
    if (f->info().vp < 0) {
      f->info().vp = static_cast<std::int32_t>(c.vpx.size());
      c.vpx.push_back(p.x);
      c.vpy.push_back(p.y);
    } else {
      c.vpx[f->info().vp] = p.x;
      c.vpy[f->info().vp] = p.y;
    }
  }
}

void computePowerPoints(Cells<Regular> &c, const TargetSpec &spec) {
  std::vector<Regular::Face_handle> faces;
  faces.reserve(c.tri.number_of_faces());
  for (auto f = c.tri.finite_faces_begin(); f != c.tri.finite_faces_end(); ++f)
    faces.push_back(f);
  const std::size_t n = faces.size();
  c.vpx.resize(n);
  c.vpy.resize(n);
#pragma omp parallel for schedule(static)
  for (std::size_t k = 0; k < n; ++k) {
    const auto p = c.tri.weighted_circumcenter(faces[k]);
    double x = p.x(), y = p.y();
    clampToBox(x, y, spec.width, spec.height);
    faces[k]->info().vp = static_cast<std::int32_t>(k);
    c.vpx[k] = x;
    c.vpy[k] = y;
  }
}

template <class Tri> void removeSite(Cells<Tri> &c, std::uint32_t site) {
  for (std::uint32_t k = c.images.first[site]; k < c.images.first[site] + c.images.count[site]; ++k)
    if (c.handle[k] != typename Tri::Vertex_handle()) {
      c.tri.remove(c.handle[k]);
      c.handle[k] = typename Tri::Vertex_handle();
    }
  c.alive[site] = 0;
}

void insertSite(Cells<Delaunay> &c, const Sites &s, std::uint32_t site, double w, double h,
                double reach) {
  c.images.add(s, site, w, h, reach);
  for (std::uint32_t k = c.images.first[site]; k < c.images.first[site] + c.images.count[site];
       ++k) {
    auto v = c.tri.insert(K::Point_2(c.images.x[k], c.images.y[k]));
    v->info() = k;
    c.handle.push_back(v);
  }
  c.alive[site] = 1;
}

// One pass of the thesis's repairs. Returns the number of changes made.
std::size_t repair(Cells<Delaunay> &c, Sites &s, const TargetSpec &spec, int pass,
                   TessellationReport &report) {
  const double reach = 2.0 * spec.diameter_max;
  std::vector<std::uint32_t> remove_voids;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> merges;
  std::vector<Delaunay::Face_handle> restore;
  std::vector<std::uint8_t> busy(s.size(), 0);
  Ring<Delaunay> ring;
  std::vector<double> px, py;
  std::vector<std::size_t> at; // ring index of each distinct polygon vertex
  for (std::uint32_t g = 0; g < s.grains; ++g) {
    if (!c.alive[g] || !ringOf(c, g, ring))
      continue;
    const std::size_t n = ring.face.size();
    auto vp = [&](std::size_t k) { return ring.face[k % n]->info().vp; };
    bool bad = false;
    // Overlap: the Voronoi edge towards image t runs backwards (cross(t - g, b - a) < 0).
    const double gx = s.x[g], gy = s.y[g];
    for (std::size_t k = 0; k < n; ++k) {
      const std::uint32_t t = ring.across[k];
      const double ax = c.vpx[vp(k)], ay = c.vpy[vp(k)], bx = c.vpx[vp(k + 1)],
                   by = c.vpy[vp(k + 1)];
      const double tx = c.images.x[t] - gx, ty = c.images.y[t] - gy;
      if (cross(tx, ty, bx - ax, by - ay) >=
          -1e-12 * std::hypot(tx, ty) * std::hypot(bx - ax, by - ay))
        continue;
      bad = true;
      const std::uint32_t ts = c.images.site[t];
      if (ts >= s.grains) {
        remove_voids.push_back(ts);
      } else if (c.images.real[t] && ts != g && !busy[g] && !busy[ts]) {
        merges.push_back({g, ts});
        busy[g] = busy[ts] = 1;
      } else {
        restore.push_back(ring.face[k]);
        restore.push_back(ring.face[(k + 1) % n]);
      }
    }
    // Concavity: at a point where the cell turns right.
    px.clear(), py.clear(), at.clear();
    for (std::size_t k = 0; k < n; ++k) {
      const double x = c.vpx[vp(k)], y = c.vpy[vp(k)];
      if (!px.empty() && x == px.back() && y == py.back())
        continue;
      px.push_back(x), py.push_back(y), at.push_back(k);
    }
    while (px.size() > 1 && px.front() == px.back() && py.front() == py.back())
      px.pop_back(), py.pop_back(), at.pop_back();
    const std::size_t m = px.size();
    for (std::size_t i = 0; i < m && m >= 3; ++i) {
      const std::size_t p = (i + m - 1) % m, q = (i + 1) % m;
      const double ax = px[i] - px[p], ay = py[i] - py[p], bx = px[q] - px[i], by = py[q] - py[i];
      if (cross(ax, ay, bx, by) >= -1e-9 * std::hypot(ax, ay) * std::hypot(bx, by))
        continue;
      bad = true;
      const auto f = ring.face[at[i]];
      bool had_void = false;
      for (int j = 0; j < 3; ++j) {
        const std::uint32_t ts = c.images.site[f->vertex(j)->info()];
        if (ts >= s.grains) {
          remove_voids.push_back(ts);
          had_void = true;
        }
      }
      if (!had_void) {
        // Three grains: back to the Voronoi point; if it already is, its neighbours too.
        restore.push_back(f);
        if (f->info().restored) {
          restore.push_back(ring.face[(at[i] + n - 1) % n]);
          restore.push_back(ring.face[(at[i] + 1) % n]);
        }
      }
    }
    if (bad && pass >= 20) // last resort, never needed so far: the plain Voronoi cell
      restore.insert(restore.end(), ring.face.begin(), ring.face.end());
  }
  // A void cell turned inside out lets the grains around it overlap: such a void goes too.
  for (std::uint32_t v = static_cast<std::uint32_t>(s.grains); v < s.size(); ++v) {
    if (!c.alive[v] || !ringOf(c, v, ring))
      continue;
    const std::size_t n = ring.face.size();
    for (std::size_t k = 0; k < n; ++k) {
      const int a = ring.face[k]->info().vp, b = ring.face[(k + 1) % n]->info().vp;
      if (a < 0 || b < 0)
        continue;
      const std::uint32_t t = ring.across[k];
      const double tx = c.images.x[t] - s.x[v], ty = c.images.y[t] - s.y[v];
      const double ex = c.vpx[b] - c.vpx[a], ey = c.vpy[b] - c.vpy[a];
      if (cross(tx, ty, ex, ey) < -1e-12 * std::hypot(tx, ty) * std::hypot(ex, ey)) {
        remove_voids.push_back(v);
        break;
      }
    }
  }
  std::sort(remove_voids.begin(), remove_voids.end());
  remove_voids.erase(std::unique(remove_voids.begin(), remove_voids.end()), remove_voids.end());

  std::size_t changes = 0;
  for (auto f : restore)
    if (!f->info().restored) {
      f->info().restored = true;
      ++report.restored_points, ++changes;
    }
  for (std::uint32_t v : remove_voids)
    if (c.alive[v]) {
      removeSite(c, v);
      ++report.removed_voids, ++changes;
    }
  for (auto [a, b] : merges) {
    if (!c.alive[a] || !c.alive[b])
      continue;
    // Two overlapping grains become one of the same total area at their area centroid.
    const double aa = s.r[a] * s.r[a], ab = s.r[b] * s.r[b];
    removeSite(c, a);
    removeSite(c, b);
    s.x[a] = (aa * s.x[a] + ab * s.x[b]) / (aa + ab);
    s.y[a] = (aa * s.y[a] + ab * s.y[b]) / (aa + ab);
    s.r[a] = std::sqrt(aa + ab);
    insertSite(c, s, a, spec.width, spec.height, reach);
    ++report.merged_grains, ++changes;
  }
  return changes;
}

// Depth by which convex polygon b reaches into convex polygon a across a's edges (negative: a
// separating edge exists, so they do not overlap; separating axis theorem, one direction).
double reach(const std::vector<Point> &a, const std::vector<Point> &b) {
  double depth = HUGE_VAL;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const Point p = a[i], q = a[(i + 1) % a.size()];
    const double ex = q.x - p.x, ey = q.y - p.y, len = std::hypot(ex, ey);
    if (len == 0.0)
      continue;
    double deepest = -HUGE_VAL;
    for (const Point &v : b)
      deepest = std::max(deepest, cross(ex, ey, v.x - p.x, v.y - p.y) / len);
    depth = std::min(depth, deepest);
  }
  return depth;
}

// Grains whose relaxed cells overlap a nearby grain's. The local repairs look at one cell and
// its Delaunay neighbours; this catches what slips between them (cells across a void).
std::vector<std::uint32_t> overlappingGrains(const Cells<Delaunay> &c, const Sites &s,
                                             const TargetSpec &spec) {
  std::vector<std::vector<Point>> poly(s.grains);
  Ring<Delaunay> ring;
  for (std::uint32_t g = 0; g < s.grains; ++g)
    if (c.alive[g] && ringOf(c, g, ring))
      for (auto f : ring.face)
        poly[g].push_back({c.vpx[f->info().vp], c.vpy[f->info().vp]});
  PointGrid grid = pointGrid(spec.width, spec.height, spec.diameter_max);
  binPoints(grid, s.x.data(), s.y.data(), s.r.data(), 0, static_cast<std::uint32_t>(s.grains));
  const double tolerance = 1e-9 * spec.meanDiameter();
  std::vector<std::uint32_t> bad;
  for (std::uint32_t g = 0; g < s.grains; ++g) {
    if (poly[g].empty())
      continue;
    grid.forNear(s.x[g], s.y[g], 2.0 * spec.diameter_max, [&](const GridPoint &item) {
      const std::uint32_t h = item.index;
      if (h <= g || poly[h].empty())
        return;
      if (std::min(reach(poly[g], poly[h]), reach(poly[h], poly[g])) > tolerance)
        bad.push_back(g), bad.push_back(h);
    });
  }
  std::sort(bad.begin(), bad.end());
  bad.erase(std::unique(bad.begin(), bad.end()), bad.end());
  return bad;
}

// Vertex table shared by the grains, so that a merge of two points moves them for every grain.
// Polygons are stored flat (grain g: ids[start[g] .. start[g] + size[g]), counter-clockwise);
// merges only shorten them, in place.
struct Planar {
  std::vector<double> x, y;
  std::vector<std::uint64_t> start;
  std::vector<std::uint32_t> size, ids, grain_site;
  std::size_t grains() const { return size.size(); }
  std::uint32_t *poly(std::size_t g) { return ids.data() + start[g]; }
};

template <class Tri>
Planar collectGrains(const Cells<Tri> &c, const Sites &s, TessellationReport &report) {
  Planar out;
  // Points of faces become shared vertices, numbered in the order the grains meet them. Points
  // at one position (cocircular sites) stay apart here and meet in mergeShortEdges.
  std::vector<std::uint32_t> vertex_of_vp(c.vpx.size(), UINT32_MAX);
  Ring<Tri> ring;
  for (std::uint32_t g = 0; g < s.grains; ++g) {
    if (!c.alive[g])
      continue;
    if (!ringOf(c, g, ring)) {
      ++report.lost_grains;
      continue;
    }
    const std::size_t first = out.ids.size();
    for (auto f : ring.face) {
      const std::int32_t vp = f->info().vp;
      if (vertex_of_vp[vp] == UINT32_MAX) {
        vertex_of_vp[vp] = static_cast<std::uint32_t>(out.x.size());
        out.x.push_back(c.vpx[vp]);
        out.y.push_back(c.vpy[vp]);
      }
      if (out.ids.size() == first || out.ids.back() != vertex_of_vp[vp])
        out.ids.push_back(vertex_of_vp[vp]);
    }
    while (out.ids.size() > first + 1 && out.ids[first] == out.ids.back())
      out.ids.pop_back();
    if (out.ids.size() - first < 3) {
      out.ids.resize(first);
      ++report.lost_grains;
      continue;
    }
    out.start.push_back(first);
    out.size.push_back(static_cast<std::uint32_t>(out.ids.size() - first));
    out.grain_site.push_back(g);
  }
  return out;
}

// Merge the ends of every grain edge shorter than `h` (thesis 4.2.2), shortest first, where
// every grain at either end stays convex up to a slight dent. Points on a wall stay on it.
void mergeShortEdges(Planar &p, double w, double h_box, double h, TessellationReport &report) {
  const std::size_t nv = p.x.size();
  // The grains at each vertex: three at most where cells meet, a few more after merges.
  constexpr int most = 8;
  std::vector<std::array<std::uint32_t, most>> grains_at(nv);
  std::vector<std::uint8_t> count(nv, 0);
  for (std::uint32_t g = 0; g < p.grains(); ++g)
    for (std::uint32_t k = 0; k < p.size[g]; ++k) {
      const std::uint32_t v = p.poly(g)[k];
      if (count[v] < most)
        grains_at[v][count[v]++] = g;
    }
  auto walls = [&](std::uint32_t v) {
    return (p.x[v] == 0.0) | (p.x[v] == w) << 1 | (p.y[v] == 0.0) << 2 | (p.y[v] == h_box) << 3;
  };
  struct Edge {
    double len;
    std::uint32_t a, b;
  };
  std::vector<Edge> edges;
  for (std::uint32_t g = 0; g < p.grains(); ++g)
    for (std::uint32_t k = 0; k < p.size[g]; ++k) {
      const std::uint32_t a = p.poly(g)[k], b = p.poly(g)[(k + 1) % p.size[g]];
      const double len = std::hypot(p.x[a] - p.x[b], p.y[a] - p.y[b]);
      if (len < h)
        edges.push_back({len, std::min(a, b), std::max(a, b)});
    }
  std::sort(edges.begin(), edges.end(), [](const Edge &e, const Edge &f) {
    return e.len < f.len || (e.len == f.len && (e.a < f.a || (e.a == f.a && e.b < f.b)));
  });
  edges.erase(std::unique(edges.begin(), edges.end(),
                          [](const Edge &e, const Edge &f) { return e.a == f.a && e.b == f.b; }),
              edges.end());
  std::vector<std::uint32_t> parent(nv);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t v) {
    while (parent[v] != v)
      v = parent[v] = parent[parent[v]];
    return v;
  };
  std::vector<std::uint32_t> affected, trial, trial_start;
  std::vector<double> tx, ty;
  for (const Edge &e : edges) {
    const std::uint32_t a = find(e.a), b = find(e.b);
    if (a == b || std::hypot(p.x[a] - p.x[b], p.y[a] - p.y[b]) >= h)
      continue;
    const int wa = walls(a), wb = walls(b);
    double mx, my;
    if (wa == 0 && wb == 0) {
      mx = 0.5 * (p.x[a] + p.x[b]), my = 0.5 * (p.y[a] + p.y[b]);
    } else if (wb == 0 || (wa & wb) == wb) {
      mx = p.x[a], my = p.y[a]; // a is on a wall (or a corner of b's wall)
    } else if (wa == 0 || (wa & wb) == wa) {
      mx = p.x[b], my = p.y[b];
    } else {
      ++report.kept_short_edges;
      continue;
    }
    if (wa != 0 && wa == wb)
      mx = 0.5 * (p.x[a] + p.x[b]), my = 0.5 * (p.y[a] + p.y[b]); // same wall: stays on it
    // Try the collapse on every grain at a or b.
    affected.assign(grains_at[a].begin(), grains_at[a].begin() + count[a]);
    affected.insert(affected.end(), grains_at[b].begin(), grains_at[b].begin() + count[b]);
    std::sort(affected.begin(), affected.end());
    affected.erase(std::unique(affected.begin(), affected.end()), affected.end());
    bool ok = affected.size() <= static_cast<std::size_t>(most);
    trial.clear(), trial_start.clear();
    for (std::size_t i = 0; i < affected.size() && ok; ++i) {
      const std::uint32_t g = affected[i];
      const std::size_t first = trial.size();
      trial_start.push_back(static_cast<std::uint32_t>(first));
      for (std::uint32_t k = 0; k < p.size[g]; ++k) {
        const std::uint32_t v = p.poly(g)[k], u = v == b ? a : v;
        if (trial.size() == first || trial.back() != u)
          trial.push_back(u);
      }
      while (trial.size() > first + 1 && trial[first] == trial.back())
        trial.pop_back();
      const std::size_t n = trial.size() - first;
      tx.clear(), ty.clear();
      for (std::size_t k = first; k < trial.size(); ++k)
        tx.push_back(trial[k] == a ? mx : p.x[trial[k]]),
            ty.push_back(trial[k] == a ? my : p.y[trial[k]]);
      // An edge of round-off length always goes; otherwise the grains must stay convex but for
      // a slight dent (see max_dent_turn).
      ok = n >= 3 && signedArea(tx.data(), ty.data(), n) > 0.0 &&
           (e.len < 1e-9 * h || isConvex(tx.data(), ty.data(), n, max_dent_turn));
    }
    if (!ok) {
      ++report.kept_short_edges;
      continue;
    }
    p.x[a] = mx, p.y[a] = my;
    parent[b] = a;
    trial_start.push_back(static_cast<std::uint32_t>(trial.size()));
    for (std::size_t i = 0; i < affected.size(); ++i) {
      const std::uint32_t g = affected[i];
      p.size[g] = trial_start[i + 1] - trial_start[i];
      std::copy(trial.begin() + trial_start[i], trial.begin() + trial_start[i + 1], p.poly(g));
    }
    std::copy(affected.begin(), affected.end(), grains_at[a].begin());
    count[a] = static_cast<std::uint8_t>(affected.size());
    count[b] = 0;
    ++report.merged_vertices;
  }
}

Polygons toPolygons(Planar &p) {
  Polygons out;
  out.offset.reserve(p.grains() + 1);
  out.x.reserve(p.ids.size());
  out.y.reserve(p.ids.size());
  for (std::size_t g = 0; g < p.grains(); ++g) {
    for (std::uint32_t k = 0; k < p.size[g]; ++k)
      out.x.push_back(p.x[p.poly(g)[k]]), out.y.push_back(p.y[p.poly(g)[k]]);
    out.offset.push_back(out.x.size());
  }
  return out;
}

// Keep the sites that are alive, grains first; return the new index of each old site.
std::vector<std::uint32_t> compactSites(Sites &s, const std::vector<std::uint8_t> &alive) {
  std::vector<std::uint32_t> index(s.size(), UINT32_MAX);
  Sites out;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (alive[i]) {
      index[i] = static_cast<std::uint32_t>(out.x.size());
      out.x.push_back(s.x[i]), out.y.push_back(s.y[i]), out.r.push_back(s.r[i]);
      if (i < s.grains)
        ++out.grains;
    }
  s = std::move(out);
  return index;
}

template <class Tri, class MakePoint>
void build(Cells<Tri> &c, const Sites &s, const TargetSpec &spec, MakePoint make_point,
           TessellationReport &report) {
  const double reach = 2.0 * spec.diameter_max;
  c.alive.assign(s.size(), 1);
  for (std::uint32_t i = 0; i < s.size(); ++i)
    c.images.add(s, i, spec.width, spec.height, reach);
  std::vector<std::pair<decltype(make_point(0u)), std::uint32_t>> points;
  points.reserve(c.images.x.size());
  for (std::uint32_t k = 0; k < c.images.x.size(); ++k)
    points.emplace_back(make_point(k), k);
  const auto t0 = std::chrono::steady_clock::now();
  c.tri.insert(points.begin(), points.end());
  report.delaunay_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  c.handle.assign(c.images.x.size(), typename Tri::Vertex_handle());
  for (auto v = c.tri.finite_vertices_begin(); v != c.tri.finite_vertices_end(); ++v)
    c.handle[v->info()] = v;
}

} // namespace

Polygons tessellate(Sites &s, const TargetSpec &spec, double void_factor,
                    std::vector<std::uint32_t> &grain_site, TessellationReport &report) {
  Planar planar;
  std::vector<std::uint8_t> alive;
  if (spec.tessellation == Tessellation::voronoi) {
    Cells<Delaunay> c;
    c.void_factor = void_factor;
    build(
        c, s, spec, [&](std::uint32_t k) { return K::Point_2(c.images.x[k], c.images.y[k]); },
        report);
    for (int pass = 0;; ++pass) {
      computeVoronoiPoints(c, s, spec);
      report.passes = pass + 1;
      if (repair(c, s, spec, pass, report) > 0)
        continue;
      // Overlaps the local repairs missed: both cells back to plain Voronoi, which never overlap.
      const std::vector<std::uint32_t> bad = overlappingGrains(c, s, spec);
      if (bad.empty())
        break;
      Ring<Delaunay> ring;
      for (std::uint32_t g : bad)
        if (ringOf(c, g, ring))
          for (auto f : ring.face)
            if (!f->info().restored)
              f->info().restored = true, ++report.restored_points;
      if (pass > 40)
        throw std::runtime_error(
            "tessellation: grain cells still overlap or are concave after 40 passes");
    }
    planar = collectGrains(c, s, report);
    alive = c.alive;
  } else {
    Cells<Regular> c;
    c.void_factor = void_factor;
    build(
        c, s, spec,
        [&](std::uint32_t k) {
          const double r = c.radius(s, c.images.site[k]);
          return K::Weighted_point_2(K::Point_2(c.images.x[k], c.images.y[k]), r * r);
        },
        report);
    computePowerPoints(c, spec);
    planar = collectGrains(c, s, report);
    alive = c.alive;
    for (std::uint32_t g = 0; g < s.grains; ++g) // hidden grains have no cell
      if (c.handle[c.images.first[g]] == Regular::Vertex_handle())
        alive[g] = 0;
  }
  mergeShortEdges(planar, spec.width, spec.height, spec.mesh_size, report);
  const std::vector<std::uint32_t> index = compactSites(s, alive);
  grain_site.clear();
  for (std::uint32_t g : planar.grain_site)
    grain_site.push_back(index[g]);
  return toPolygons(planar);
}

} // namespace mesopen
