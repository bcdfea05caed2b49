// The narrow phase of FE-FE contact (fem/contact.hpp): the geometry of a boundary node against
// another body's boundary segments. For a node at p and a segment from a, unit tangent t, length
// l, outward normal n (the tangent turned right: boundaries run counter-clockwise):
//   foot  t_p = (p - a) . t         (position along the segment)
//   gap   g   = (p - a) . n         (signed distance from its line, negative behind it)
//   squared distance to the segment  max(-t_p, t_p - l, 0)^2 + g^2.
// The closest segment decides: a node behind its inside is in contact at depth -g along n; a
// node whose closest point is a vertex V is behind the boundary by its depth along V's
// pseudo-normal, the mean of the two segments' normals (Baerentzen & Aanaes 2005, IEEE TVCG
// 11(3), in 2D). A point's being inside a body is decided by the crossing count.
//
// The search for the closest segment runs over blocks of eight segments (lanes) at once; the
// smallest distance of a block and the lanes holding it come from smallestOf and lanesAt, which
// have a fast path (AVX-512) and a scalar reference; both give the same bits (tests/unit/
// contact_narrow.cpp).
// Equations: docs/models.md §8.1.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

// The narrow phase's steps are inlined into the loop over the pairs: called out of line, each
// call would pass its results through memory and the loop wait on them.
#define MESOPEN_INLINE [[gnu::always_inline]] inline

namespace mesopen::fem::narrow {

constexpr std::uint32_t no_node = 0xffffffffu;
constexpr double end_tie = 1e-9; // a foot this close to a segment's end (relative) is at the end

// A rectangle: a body's bounding box, the overlap of two.
struct Box {
  double x0, y0, x1, y1;
  bool overlaps(const Box &o) const { return x0 <= o.x1 && o.x0 <= x1 && y0 <= o.y1 && o.y0 <= y1; }
  bool contains(double x, double y) const { return x >= x0 && x <= x1 && y >= y0 && y <= y1; }
  Box widened(double margin) const { return {x0 - margin, y0 - margin, x1 + margin, y1 + margin}; }
  // Whether the box of the segment from (ax, ay) to (bx, by) meets it (no branch).
  bool meets(double ax, double ay, double bx, double by) const {
    return (x0 <= std::max(ax, bx)) & (std::min(ax, bx) <= x1) & (y0 <= std::max(ay, by)) &
           (std::min(ay, by) <= y1);
  }
  // How far (x, y), inside, lies from its edge: whatever lies outside is at least as far.
  double edgeDistance(double x, double y) const {
    return std::min(std::min(x - x0, x1 - x), std::min(y - y0, y1 - y));
  }
  // the intersection (empty if x0 > x1 or y0 > y1)
  Box overlap(const Box &o) const {
    return {std::max(x0, o.x0), std::max(y0, o.y0), std::min(x1, o.x1), std::min(y1, o.y1)};
  }
};

// A boundary node's position, the two coordinates side by side: the narrow phase reads them at
// scattered nodes.
struct alignas(16) Point {
  double x, y;
};

struct Segment {
  double ax, ay, tx, ty, length, nx, ny; // start, unit tangent, length, outward normal
  // Where a point lies against it: position along it from the start, signed distance from its
  // line (negative behind it), how far beyond its ends, squared distance to it.
  struct Foot {
    double t, g, excess, distance;
  };
  Foot foot(double px, double py) const {
    const double dx = px - ax, dy = py - ay;
    const double t = dx * tx + dy * ty, g = dx * nx + dy * ny;
    const double excess = std::max(std::max(-t, t - length), 0.0); // before or beyond
    return {t, g, excess, excess * excess + g * g};
  }
};

// Segments near a region, for the search of the closest one to a point: their geometry (see
// Segment) as arrays, their two nodes (indices into the boundary nodes), in blocks of `lanes`
// searched at once. A lane without a near segment (not near, of zero length, padding) lies far
// away (`far`) and is never the closest.
struct Near {
  static constexpr std::size_t lanes = 8;
  static constexpr double far = 1e300;
  std::size_t size = 0, count = 0; // lanes (a multiple of `lanes`), near segments among them
  std::vector<double> ax, ay, tx, ty, length, nx, ny;
  std::vector<std::uint32_t> ends;
  Segment operator[](std::size_t i) const {
    return {ax[i], ay[i], tx[i], ty[i], length[i], nx[i], ny[i]};
  }
  bool in(std::size_t i) const { return length[i] > 0.0; } // a near segment
};

// The closest segment of a list to a point: its index (no_node: none), squared distance, signed
// distance from its line (negative behind it), position along it, whether a corner is closest.
struct Closest {
  std::uint32_t segment = no_node;
  double distance = std::numeric_limits<double>::infinity(), g = 0.0, along = 0.0;
  bool corner = false;
};

// The smallest of a block's eight squared distances (d aligned to 64 bytes), and the lanes that
// hold the value s (bit j: lane j). Scalar reference.
inline double smallestOfReference(const double *d) {
  double smallest = std::numeric_limits<double>::infinity();
  for (std::size_t j = 0; j < Near::lanes; ++j)
    smallest = std::min(smallest, d[j]);
  return smallest;
}
inline unsigned lanesAtReference(const double *d, double s) {
  unsigned at = 0;
  for (std::size_t j = 0; j < Near::lanes; ++j)
    at |= static_cast<unsigned>(d[j] == s) << j;
  return at;
}

// The same, fast: with AVX-512 one vector reduction and one comparison (GCC makes the scalar
// loops a chain of eight minimums and eight comparisons, 9 % of the contact's time on run 6).
// Minimum and equality are exact: the bits are those of the reference.
#if defined(__AVX512F__)
static_assert(Near::lanes == 8);
inline double smallestOf(const double *d) {
  const __m256d four = _mm256_min_pd(_mm256_load_pd(d), _mm256_load_pd(d + 4));
  const __m128d two = _mm_min_pd(_mm256_castpd256_pd128(four), _mm256_extractf128_pd(four, 1));
  return std::min(_mm_cvtsd_f64(two), _mm_cvtsd_f64(_mm_unpackhi_pd(two, two)));
}
inline unsigned lanesAt(const double *d, double s) {
  return _mm512_cmp_pd_mask(_mm512_load_pd(d), _mm512_set1_pd(s), _CMP_EQ_OQ);
}
#else
inline double smallestOf(const double *d) { return smallestOfReference(d); }
inline unsigned lanesAt(const double *d, double s) { return lanesAtReference(d, s); }
#endif

// The near segment closest to (px, py), the first of equals; with `distances`, every lane's
// squared distance goes there. Block by block: the squared distances to the block's segments at
// once (no branch, vectorized), then the first of the smallest if it is closer than those before.
// `fast`: the smallest by smallestOf and lanesAt, else by their references.
template <bool fast = true>
MESOPEN_INLINE Closest closest(const Near &near, double px, double py, double *distances) {
  constexpr std::size_t L = Near::lanes;
  Closest c;
  for (std::size_t base = 0; base < near.size; base += L) {
    alignas(64) double d[L];
    double t[L], g[L];
    for (std::size_t j = 0; j < L; ++j) {
      const Segment::Foot f = near[base + j].foot(px, py);
      d[j] = f.distance, t[j] = f.t, g[j] = f.g;
    }
    if (distances)
      std::copy(d, d + L, distances + base);
    const double smallest = fast ? smallestOf(d) : smallestOfReference(d);
    if (smallest < c.distance) {
      const unsigned at = fast ? lanesAt(d, smallest) : lanesAtReference(d, smallest);
      const auto j = static_cast<std::uint32_t>(std::countr_zero(at));
      // beyond an end (Segment::foot's excess > 0)
      c = {static_cast<std::uint32_t>(base + j), d[j], g[j], t[j],
           static_cast<bool>((t[j] < 0.0) | (t[j] > near.length[base + j]))};
    }
  }
  return c;
}

// Of the segments given by their ends (indices into `points`), those of nonzero length whose boxes
// meet the rectangle `wide`: into `near`, in the given order. The ends of those are gathered first,
// side by side (a list of a whole boundary has most of its segments far, which would fill lanes for
// nothing), then the geometry of all is computed in one pass (vectorized).
MESOPEN_INLINE void nearSegments(const Point *points, const std::uint32_t *ends,
                                 const std::uint32_t *ends_end, const Box &wide, Near &near) {
  constexpr std::size_t L = Near::lanes;
  const std::size_t listed = static_cast<std::size_t>(ends_end - ends) / 2;
  const std::size_t room = (listed + L - 1) / L * L;
  if (near.ax.size() < room) {
    for (auto *v : {&near.ax, &near.ay, &near.tx, &near.ty, &near.length, &near.nx, &near.ny})
      v->resize(room);
    near.ends.resize(2 * room);
  }
  // The start in (ax, ay), the end in (tx, ty) for now.
  double *ax = near.ax.data(), *ay = near.ay.data(), *tx = near.tx.data(), *ty = near.ty.data(),
         *length = near.length.data(), *nx = near.nx.data(), *ny = near.ny.data();
  // (each written where the next near one goes, and counted if its box meets `wide`)
  std::size_t m = 0;
  for (std::size_t i = 0; i < listed; ++i) {
    const Point &a = points[ends[2 * i]], &b = points[ends[2 * i + 1]];
    ax[m] = a.x, ay[m] = a.y, tx[m] = b.x, ty[m] = b.y;
    near.ends[2 * m] = ends[2 * i], near.ends[2 * m + 1] = ends[2 * i + 1];
    m += wide.meets(a.x, a.y, b.x, b.y);
  }
  const std::size_t size = (m + L - 1) / L * L;
  for (std::size_t i = m; i < size; ++i) {
    ax[i] = ay[i] = tx[i] = ty[i] = 0.0;
    near.ends[2 * i] = near.ends[2 * i + 1] = no_node;
  }
  std::size_t count = 0;
#pragma omp simd reduction(+ : count)
  for (std::size_t i = 0; i < size; ++i) {
    const double x0 = ax[i], y0 = ay[i], x1 = tx[i], y1 = ty[i], dx = x1 - x0, dy = y1 - y0;
    const double l = std::sqrt(dx * dx + dy * dy), inv = l > 0.0 ? 1.0 / l : 0.0;
    const bool in = l > 0.0; // (padding: l = 0)
    // outward normal: the tangent turned right (the boundary runs counter-clockwise)
    ax[i] = in ? x0 : Near::far, ay[i] = in ? y0 : 0.0;
    tx[i] = in ? dx * inv : 1.0, ty[i] = in ? dy * inv : 0.0, length[i] = in ? l : 0.0;
    nx[i] = in ? dy * inv : 0.0, ny[i] = in ? -dx * inv : -1.0;
    count += in;
  }
  near.size = size, near.count = count;
}

// Whether the foot of the closest point falls inside segment c, away from both of its ends (beyond
// round-off; no branch on which end is nearer, which would be taken at random). Most contacts are
// there (run 6: 93 %); atVertex decides the others.
inline bool atInside(const Near &near, const Closest &c) {
  const double length = near.length[c.segment];
  return (c.along > end_tie * length) & (c.along < (1.0 - end_tie) * length);
}

enum class At { segment, vertex, unknown }; // see atVertex

// The closest point when the foot on the closest segment c falls at one of its ends V (within
// `end_tie` of it, or beyond): V itself if the foot on the other segment at V falls at V or beyond
// it too, else the inside of that other segment (as close as c or closer: round-off chose c),
// which c then becomes (At::segment). At V, the node is behind the boundary by its depth along
// V's pseudo-normal, the mean of the two segments' normals (At::vertex; depth < 0: in front), and
// the reaction goes to V alone (w2 its weight: 0 at the start of c, 1 at its end). The
// pseudo-normal decides inside or outside exactly for every point whose closest point is V, where
// the side of either segment's line can fail (a node in a dent on the line of one of its segments
// beyond V is at g = 0 from it). The choice depends on the two feet alone, not on which of two
// segments as close round-off took first: the two passes of a mirror-symmetric impact, whose lists
// run in opposite orders, agree (a node meeting a node of a conforming face is at V of both).
// At::unknown: c's foot is beyond V and the other segment is not near. `points` are the boundary
// nodes' positions, `pinched` per boundary node whether it is not the start of exactly one segment.
MESOPEN_INLINE At atVertex(const Near &near, const Point *points, const std::uint8_t *pinched,
                           Closest &c, double px, double py, double &depth, double &nx, double &ny,
                           double &w2) {
  const double length = near.length[c.segment];
  const bool at_start = c.along < 0.5 * length;
  const std::uint32_t vertex = near.ends[2 * c.segment + (at_start ? 0 : 1)];
  // The other segment at V: the one V ends (at_start) or starts, found where the lists keep it,
  // next to c in the boundary's order, unless V is pinched (then the first of them, by a search).
  const std::uint32_t beside = at_start ? c.segment - 1 : c.segment + 1;
  const bool next_to = !pinched[vertex] && beside < near.size && near.in(beside) &&
                       near.ends[2 * beside + (at_start ? 1 : 0)] == vertex;
  for (std::uint32_t j = next_to ? beside : 0; j < near.size; ++j) {
    if (j == c.segment || !near.in(j) || near.ends[2 * j + (at_start ? 1 : 0)] != vertex)
      continue;
    const Segment o = near[j];
    const Segment::Foot f = o.foot(px, py);
    if (at_start ? f.t < (1.0 - end_tie) * o.length : f.t > end_tie * o.length) {
      c = {j, f.distance, f.g, f.t, false};
      return At::segment;
    }
    const Segment s = near[c.segment];
    const double mx = s.nx + o.nx, my = s.ny + o.ny, norm = std::sqrt(mx * mx + my * my);
    if (!(norm > 0.0)) // the two segments fold back onto each other
      break;
    nx = mx / norm, ny = my / norm;
    const double vx = px - points[vertex].x, vy = py - points[vertex].y;
    depth = -(vx * nx + vy * ny);
    w2 = at_start ? 0.0 : 1.0;
    c.distance = vx * vx + vy * vy;
    return At::vertex;
  }
  return c.corner ? At::unknown : At::segment;
}

// The closest of the near segments that (px, py) lies behind, nearer than `within`, with its foot
// on the segment's inside (segment no_node: none): where a body's boundary is folded over itself,
// the segment beneath the fold (see Contact::touch).
inline Closest closestBehind(const Near &near, double px, double py, double within) {
  Closest c;
  c.distance = within * within;
  for (std::size_t i = 0; i < near.size; ++i) {
    const double length = near.length[i];
    const Segment::Foot f = near[i].foot(px, py);
    if (near.in(i) && f.g < 0.0 && f.t > end_tie * length && f.t < (1.0 - end_tie) * length &&
        f.distance < c.distance)
      c = {static_cast<std::uint32_t>(i), f.distance, f.g, f.t, false};
  }
  return c;
}

// Whether (px, py) lies inside the polygon of the segments given by their ends (indices into
// `points`): the number of segments a ray in +x crosses is odd.
inline bool inside(const Point *points, const std::uint32_t *ends, const std::uint32_t *ends_end,
                   double px, double py) {
  bool in = false;
  for (; ends != ends_end; ends += 2) {
    const Point &a = points[ends[0]], &b = points[ends[1]];
    if ((a.y > py) != (b.y > py) && px < a.x + (py - a.y) * (b.x - a.x) / (b.y - a.y))
      in = !in;
  }
  return in;
}

} // namespace mesopen::fem::narrow
