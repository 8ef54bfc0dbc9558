#pragma once
/// @file recent_obstacle_layer.hpp
/// A costmap layer: the recent obstacles (obstacle_memory.hpp) - what the sensors saw in the
/// last seconds, near the robot - block the dynamic window even before the map holds them.
/// Only in the local costmap: where the pose has moved since a place was mapped, the map's copy
/// of a wall and the recent one narrow a door between them, and planning on both can close
/// doors for good.
///
/// A point's cell is marked only if no cell within one cell of it is already an obstacle of the
/// grid as given: such a cell adds nothing the inflation's margin (a cell) does not already
/// hold, and marking it would only thicken walls by the sensors' noise.
#include <duet/runtime/navigation/costmap_layer.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <span>
#include <vector>

namespace duet {

class RecentObstacleLayer final : public CostmapLayer {
 public:
  /// occupied_logodds: a cell at or above it is an obstacle; marked_logodds: the value written.
  RecentObstacleLayer(float occupied_logodds, float marked_logodds) : occupied_(occupied_logodds), marked_(marked_logodds) {}

  /// Replaces the points (map frame); non-finite points are dropped.
  void set(std::span<const Eigen::Vector2f> points);
  [[nodiscard]] const std::vector<Eigen::Vector2f>& points() const noexcept { return points_; }
  /// Cells marked by the last apply().
  [[nodiscard]] std::size_t cells_marked() const noexcept { return cells_.size(); }

  [[nodiscard]] std::string_view name() const override { return "recent_obstacles"; }
  [[nodiscard]] bool active() const override { return !points_.empty(); }
  void apply(OccupancyGrid& grid) override;
  void shift(const Pose2& D) override;

 private:
  float occupied_;
  float marked_;
  std::vector<Eigen::Vector2f> points_;
  std::vector<std::size_t> cells_;
};

}  // namespace duet
