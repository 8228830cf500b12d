// Small deterministic random number generator for the simulator and the experiments.
//
// SplitMix64 (Steele, Lea & Flood 2014) for the bits, Box-Muller for normals: results depend
// only on the seed, never on the standard library's distribution implementations, so every
// figure and test is reproducible across compilers and platforms.
#pragma once

#include <cmath>
#include <cstdint>

namespace ccmap::sim {

/// SplitMix64 step on a state value: a good 64-bit mix, also usable as a stateless hash.
inline std::uint64_t splitmix64_mix(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

/// Hash of a few integers (lattice noise, per-item streams).
inline std::uint64_t hash_combine(std::uint64_t seed, std::uint64_t a, std::uint64_t b = 0,
                                  std::uint64_t c = 0) {
  std::uint64_t h = splitmix64_mix(seed);
  h = splitmix64_mix(h ^ a);
  h = splitmix64_mix(h ^ b);
  return splitmix64_mix(h ^ c);
}

class Rng {
 public:
  explicit Rng(std::uint64_t seed = 1) : state_(seed) {}

  std::uint64_t next_u64() {
    state_ += 0x9E3779B97F4A7C15ULL;
    std::uint64_t z = state_;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }

  /// Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(next_u64() >> 11) * (1.0 / 9007199254740992.0); }

  /// Uniform in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

  /// Standard normal (Box-Muller; the second value of each pair is kept for the next call).
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u1 = uniform();
    while (u1 <= 0.0) u1 = uniform();
    const double u2 = uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    const double a = 6.283185307179586 * u2;
    spare_ = r * std::sin(a);
    has_spare_ = true;
    return r * std::cos(a);
  }

  /// Normal with mean and standard deviation.
  double normal(double mean, double sigma) { return mean + sigma * normal(); }

 private:
  std::uint64_t state_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace ccmap::sim
