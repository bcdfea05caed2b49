// The narrow phase's search for the closest segment (fem/contact_narrow.hpp): its fast path
// (AVX-512 where the build has it) against the scalar reference, on random boundaries and points.
// Tolerance: none, the results must be the same bits. Both paths compute the same distances; the
// fast one only takes their minimum and the lanes equal to it by vector instructions, and minimum
// and equality are exact operations.
#include "contact_narrow.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace {

using namespace mesopen::fem::narrow;

struct Boundary {
  std::vector<Point> points;
  std::vector<std::uint32_t> ends; // segments: pairs of indices into points
};

// A star-shaped polygon of n vertices (counter-clockwise) about (cx, cy), radii in [0.5, 1.5] r;
// some vertices repeated (segments of zero length) and some at a neighbour's place.
Boundary randomBoundary(std::mt19937_64 &rng, std::size_t n, double cx, double cy, double r) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Boundary b;
  for (std::size_t k = 0; k < n; ++k) {
    const double angle = 2.0 * M_PI * (k + 0.8 * u(rng)) / n, radius = r * (0.5 + u(rng));
    b.points.push_back({cx + radius * std::cos(angle), cy + radius * std::sin(angle)});
    if (k > 0 && u(rng) < 0.05)
      b.points.back() = b.points[k - 1]; // zero length
  }
  for (std::size_t k = 0; k < n; ++k)
    b.ends.push_back(static_cast<std::uint32_t>(k)),
        b.ends.push_back(static_cast<std::uint32_t>((k + 1) % n));
  return b;
}

bool same(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

void expectSame(const Closest &fast, const Closest &reference) {
  EXPECT_EQ(fast.segment, reference.segment);
  EXPECT_TRUE(same(fast.distance, reference.distance))
      << fast.distance << " " << reference.distance;
  EXPECT_TRUE(same(fast.g, reference.g));
  EXPECT_TRUE(same(fast.along, reference.along));
  EXPECT_EQ(fast.corner, reference.corner);
}

TEST(ContactNarrow, FastClosestIsTheScalarReferenceBitForBit) {
#if defined(__AVX512F__)
  RecordProperty("fast_path", "AVX-512");
#else
  RecordProperty("fast_path", "scalar (no AVX-512 in this build)");
#endif
  std::mt19937_64 rng(20240607);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::size_t compared = 0, at_vertices = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const std::size_t n = 3 + static_cast<std::size_t>(u(rng) * 60);
    const double scale = std::pow(10.0, -6.0 + 3.0 * u(rng)); // grains of microns to millimetres
    const double cx = scale * (u(rng) - 0.5), cy = scale * (u(rng) - 0.5);
    const Boundary b = randomBoundary(rng, n, cx, cy, scale);
    // the segments near a random part of the body (padding and far lanes among them)
    const double x0 = cx + scale * (2.0 * u(rng) - 1.5), y0 = cy + scale * (2.0 * u(rng) - 1.5);
    const Box region{x0, y0, x0 + scale * 2.0 * u(rng), y0 + scale * 2.0 * u(rng)};
    Near near;
    nearSegments(b.points.data(), b.ends.data(), b.ends.data() + b.ends.size(), region, near);
    std::vector<double> d_fast(near.size), d_reference(near.size);
    auto compare = [&](double px, double py) {
      const Closest fast = closest<true>(near, px, py, d_fast.data());
      const Closest reference = closest<false>(near, px, py, d_reference.data());
      expectSame(fast, reference);
      for (std::size_t i = 0; i < near.size; ++i)
        ASSERT_TRUE(same(d_fast[i], d_reference[i]));
      ++compared;
    };
    for (int k = 0; k < 50; ++k) // points about the region
      compare(region.x0 + (region.x1 - region.x0) * (2.0 * u(rng) - 0.5),
              region.y0 + (region.y1 - region.y0) * (2.0 * u(rng) - 0.5));
    for (const Point &p : b.points) // at the vertices: ties between their two segments
      compare(p.x, p.y), ++at_vertices;
  }
  EXPECT_GT(compared, 20000u);
  EXPECT_GT(at_vertices, 1000u);
}

// The fast minimum and lanes on blocks with ties, infinities and the far lanes' values.
TEST(ContactNarrow, FastSmallestAndLanesAreTheReference) {
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> pick(0, 5);
  const double values[] = {0.0, 1e-12, 1.0, 1e300, INFINITY, 2.5e-9};
  for (int trial = 0; trial < 20000; ++trial) {
    alignas(64) double d[Near::lanes];
    for (double &x : d)
      x = values[pick(rng)];
    const double s = smallestOf(d), s_reference = smallestOfReference(d);
    ASSERT_TRUE(same(s, s_reference));
    ASSERT_EQ(lanesAt(d, s), lanesAtReference(d, s_reference));
  }
}

} // namespace
