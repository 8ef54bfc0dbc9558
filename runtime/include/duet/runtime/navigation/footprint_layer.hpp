#pragma once
/// @file footprint_layer.hpp
/// A costmap layer for the planning costmap (and so the local one): the cells wholly under the
/// robot's body at its estimated pose are not obstacles - the robot stands there (nav2's obstacle
/// layer clears its footprint the same way).
///  - Why: a map cell can sit under the estimated body when the pose is a few centimetres off
///    (a thin post kept by GridUpdateSettings::keep_occupied_within_m, a wall drawn 0.1 m too
///    near). The dynamic window and A* then find every move in collision and the robot stays
///    where it is: belgioioso seed 2 sat 2700 s beside a post 0.09 m from its estimated centre,
///    0.30 m from the true one (issue 23).
///  - Only occupied cells change, and only in the costmaps: the map keeps the obstacle, and it is
///    an obstacle again once the robot has moved off it.
///  - Cells wholly under the body: centre within the body's radius less half a cell's diagonal
///    (an obstacle at the body's edge stays one).
/// The Navigator sets the pose at each map update only when an occupied cell lies under the
/// body, so the layer is inactive (no copy of the map) otherwise.
#include <duet/runtime/navigation/costmap_layer.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <optional>

namespace duet {

class FootprintLayer final : public CostmapLayer {
 public:
  /// body_radius_m: the chassis' radius [m], > 0; occupied_logodds: cells at or above it are
  /// obstacles; free_logodds: the value written.
  FootprintLayer(float body_radius_m, float occupied_logodds, float free_logodds);
  /// The number of occupied cells of `grid` wholly under a body centred at `xy` (map frame).
  [[nodiscard]] std::size_t occupied_under(const OccupancyGrid& grid, const Eigen::Vector2f& xy) const;
  /// Clears the cells under a body at `xy` from the next apply() on (ignored if not finite).
  void set(const Eigen::Vector2f& xy);
  /// No footprint: the layer is inactive.
  void reset() noexcept { at_.reset(); }
  [[nodiscard]] std::string_view name() const override { return "footprint"; }
  [[nodiscard]] bool active() const override { return at_.has_value(); }
  void apply(OccupancyGrid& grid) override;
  void shift(const Pose2& D) override;
  /// Cells the last apply() cleared.
  [[nodiscard]] std::size_t cells_cleared() const noexcept { return cleared_; }

 private:
  template <class F>
  void for_each_under(const OccupancyGrid& grid, const Eigen::Vector2f& xy, F&& fn) const;

  float body_radius_m_;
  float occupied_;
  float free_;
  std::optional<Eigen::Vector2f> at_;
  std::size_t cleared_ = 0;
};

}  // namespace duet
