// A seeded random stream whose numbers are the same on every platform and library
// (std::mt19937_64 is specified exactly; the standard distributions are not, so the
// conversions to doubles are written out here).
#pragma once

#include <cstdint>
#include <random>
#include <vector>

namespace mesopen {

class Random {
public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}
  // Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Uniform integer in [0, n) (Lemire's multiply-shift; bias below 2^-64 n, negligible here).
  std::uint64_t below(std::uint64_t n) {
    return static_cast<std::uint64_t>((static_cast<unsigned __int128>(engine_()) * n) >> 64);
  }
  // Fisher-Yates shuffle with this stream.
  template <class T> void shuffle(std::vector<T> &v) {
    for (std::size_t i = v.size(); i > 1; --i)
      std::swap(v[i - 1], v[below(i)]);
  }

private:
  std::mt19937_64 engine_;
};

} // namespace mesopen
