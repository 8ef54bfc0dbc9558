#pragma once
/// @file solid_index.hpp
/// A uniform grid over a world's floor that lists, per cell, the solids whose bounding box
/// overlaps the cell, so that a collision test looks at the solids near the disc instead of
/// every solid: a map_server building becomes thousands of wall rectangles, and the chassis
/// tests its body at every 5 ms physics step (before this index, ~8 % of a late Willow run's
/// CPU time went to that test). Answers exactly as collides() (world.hpp): the same floor test
/// and the same test of each solid, on the solids the disc's bounding square can reach.
/// Thread safety: a built index is read-only; concurrent collides() calls are safe.
#include <duet/sim/world.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace duet::sim {

class SolidIndex {
 public:
  SolidIndex() = default;
  /// Indexes `world`'s solids in cells of cell_m [m], (0, 1000] (at most 2^22 cells: larger cells
  /// on a huge floor). The world must outlive the index and keep its solids unchanged.
  explicit SolidIndex(const World& world, float cell_m = 1.0f);

  /// collides(world, centre, radius_m, z_low_m, z_high_m) for the indexed world. Throws
  /// kInvalidArgument if `world` is not the world the index was built for.
  [[nodiscard]] bool collides(const World& world, const Eigen::Vector2f& centre, float radius_m, float z_low_m, float z_high_m) const;

 private:
  const World* world_ = nullptr;
  Eigen::Vector2f origin_{0.0f, 0.0f};
  float cell_m_ = 1.0f;
  int width_ = 0, height_ = 0;
  std::vector<std::uint32_t> first_;     ///< per cell: its solids are ids_[first_[c], first_[c + 1])
  std::vector<std::uint32_t> ids_;       ///< solid indices, cell by cell
  std::vector<Eigen::Vector4f> boxes_;   ///< per solid: bounding box (lo.x, lo.y, hi.x, hi.y)
};

}  // namespace duet::sim
