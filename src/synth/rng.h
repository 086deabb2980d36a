// Small deterministic random number generator for the synthetic world. Written out (not
// std::normal_distribution) so a seed gives the same numbers with every standard library, and
// so every (seed, frame, row, stream) gets its own independent generator: results then do not
// depend on the number of threads.
//
// One draw per statement (or within a braced list, which C++ evaluates left to right): the
// arguments of one call, overloaded operators included, are evaluated in an unspecified order
// (GCC: right to left on x86-64, left to right on aarch64), so `f(rng.uniform(), rng.uniform())`
// would make a different scene of the same seed on each platform. Where a call drew several
// values, they are written out in the order x86-64 drew them, so that every seed keeps its scene.
#pragma once

#include <cmath>
#include <cstdint>

namespace emf::synth {

/// SplitMix64 finaliser: a good 64-bit mixing function (used to derive seeds).
inline uint64_t mix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

/// Seed of an independent stream for (seed, a, b, c), e.g. (seed, frame, row, kStreamNoise).
inline uint64_t streamSeed(uint64_t seed, uint64_t a, uint64_t b = 0, uint64_t c = 0) {
  return mix64(mix64(mix64(mix64(seed) ^ a) ^ (b + 0x632be59bd9b4e019ull)) ^ (c + 0x85157af5ull));
}

/// xoshiro256** generator with uniform and normal variates.
class Rng {
 public:
  explicit Rng(uint64_t seed) {
    uint64_t x = seed;
    for (auto& s : s_) {
      x = mix64(x);
      s = x;
    }
  }

  uint64_t next() {
    const uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const uint64_t t = s_[1] << 17;
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
  /// Uniform integer in [lo, hi] (inclusive).
  int uniformInt(int lo, int hi) {
    const uint64_t span = static_cast<uint64_t>(static_cast<int64_t>(hi) - lo + 1);
    return lo + static_cast<int>(next() % span);
  }
  /// True with probability p.
  bool bernoulli(double p) { return uniform() < p; }
  /// Standard normal variate (Marsaglia's polar method, both values used).
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double x, y, r2;
    do {
      x = 2.0 * uniform() - 1.0;
      y = 2.0 * uniform() - 1.0;
      r2 = x * x + y * y;
    } while (r2 >= 1.0 || r2 == 0.0);
    const double f = std::sqrt(-2.0 * std::log(r2) / r2);
    spare_ = y * f;
    has_spare_ = true;
    return x * f;
  }

 private:
  static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  uint64_t s_[4];
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace emf::synth
