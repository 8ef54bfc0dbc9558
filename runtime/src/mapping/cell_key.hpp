#pragma once
/// @file cell_key.hpp
/// A grid cell of resolution `res` (cells at multiples of res) as one sortable 64-bit key, for
/// any coordinate in +-2^30 cells, and back to its centre (runtime-private).
#include <Eigen/Core>

#include <cmath>
#include <cstdint>

namespace duet {

inline std::uint64_t cell_key(float x, float y, float res) {
  const auto cx = static_cast<std::int64_t>(std::floor(x / res)), cy = static_cast<std::int64_t>(std::floor(y / res));
  return (static_cast<std::uint64_t>(cx + (1 << 30)) << 32) | static_cast<std::uint64_t>(cy + (1 << 30));
}

inline Eigen::Vector2f key_center(std::uint64_t k, float res) {
  return {(static_cast<float>(static_cast<std::int64_t>(k >> 32) - (1 << 30)) + 0.5f) * res,
          (static_cast<float>(static_cast<std::int64_t>(k & 0xFFFFFFFFull) - (1 << 30)) + 0.5f) * res};
}

}  // namespace duet
