#pragma once
/// Small, portable, seedable random generator: identical sequences on every platform and
/// standard library (std::normal_distribution is implementation-defined), so a seed fixes the
/// simulator's output byte for byte.

#include <cmath>
#include <cstdint>
#include <numbers>

namespace ringtrack::sim {

/// xoshiro256** seeded through splitmix64.
class Rng {
 public:
  /// A generator whose whole sequence is fixed by seed.
  explicit Rng(std::uint64_t seed = 1) {
    std::uint64_t x = seed;
    for (auto& s : s_) s = splitmix(x);
  }
  /// Next 64 random bits.
  std::uint64_t next() {
    const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }
  /// Uniform in [0, 1).
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  /// Uniform in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Uniform integer in [0, n).
  int below(int n) { return static_cast<int>(uniform() * n); }
  /// True with probability p.
  bool chance(double p) { return uniform() < p; }
  /// Standard normal sample (Box-Muller; the second value is cached).
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u = uniform();
    while (u <= 0.0) u = uniform();
    const double v = uniform();
    const double r = std::sqrt(-2.0 * std::log(u));
    spare_ = r * std::sin(2.0 * std::numbers::pi * v);
    has_spare_ = true;
    return r * std::cos(2.0 * std::numbers::pi * v);
  }
  /// A seed for an independent sub-stream (actors, noise, layout) derived from this one.
  static std::uint64_t derive(std::uint64_t seed, std::uint64_t stream) {
    std::uint64_t x = seed ^ (0x9e3779b97f4a7c15ULL * (stream + 1));
    return splitmix(x);
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  static std::uint64_t splitmix(std::uint64_t& x) {
    std::uint64_t z = (x += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  std::uint64_t s_[4]{};
  double spare_{0.0};
  bool has_spare_{false};
};

}  // namespace ringtrack::sim
