#pragma once
/// @file seed_mix.hpp
/// splitmix64's finaliser: derives independent seeds (chassis, sensors, Procedure 1) from a run's seed.
#include <cstdint>

namespace duet {

inline std::uint64_t mix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

}  // namespace duet
