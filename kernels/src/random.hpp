#pragma once
// Internal: small counter-seeded random streams, so parallel kernels are deterministic whatever the
// thread count (each work item derives its own stream from the seed and its indices).
// The distributions are written here, not taken from <random>, whose normal distribution is
// implementation-defined: the same seed gives the same numbers with any standard library.
#include <cmath>
#include <cstdint>

namespace duet::detail {

/// SplitMix64 step (Steele, Lea, Flood 2014): a good mixer for deriving seeds.
inline std::uint64_t splitmix64(std::uint64_t& x) noexcept {
  std::uint64_t z = (x += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

/// A stream seed from a base seed and up to three indices.
inline std::uint64_t stream_seed(std::uint64_t seed, std::uint64_t a, std::uint64_t b = 0,
                                 std::uint64_t c = 0) noexcept {
  std::uint64_t x = seed;
  std::uint64_t h = splitmix64(x);
  x = h ^ (a * 0xD1B54A32D192ED03ull);
  h = splitmix64(x);
  x = h ^ (b * 0xABC98388FB8FAC03ull);
  h = splitmix64(x);
  x = h ^ (c * 0x8CB92BA72F3D8DD7ull);
  return splitmix64(x);
}

/// xoshiro256** (Blackman, Vigna 2018).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) noexcept {
    for (auto& v : s_) v = splitmix64(seed);
  }
  std::uint64_t next() noexcept {
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
  /// Uniform in [0, 1) with 24 random bits.
  float uniform01() noexcept { return static_cast<float>(next() >> 40) * 0x1p-24f; }
  /// Uniform in (0, 1] (never 0: safe for log).
  double uniform01_open0() noexcept { return (static_cast<double>(next() >> 11) + 1.0) * 0x1p-53; }
  float uniform(float lo, float hi) noexcept { return lo + (hi - lo) * uniform01(); }
  /// Standard normal by Box-Muller (one of the pair; the other is dropped for simplicity).
  float normal() noexcept {
    const double u1 = uniform01_open0();
    const double u2 = static_cast<double>(next() >> 11) * 0x1p-53;
    return static_cast<float>(std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2));
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) noexcept { return (x << k) | (x >> (64 - k)); }
  std::uint64_t s_[4];
};

}  // namespace duet::detail
