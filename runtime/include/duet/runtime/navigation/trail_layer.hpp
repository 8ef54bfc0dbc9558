#pragma once
/// @file trail_layer.hpp
/// A costmap layer for the local costmap, where unknown cells are obstacles (an RGB-D sensor
/// sees nothing nearer than its minimum range, so driving into unknown space near the robot is
/// driving blind): where the robot's body has been is free, and so is the spot it was set down
/// on (a robot is placed on free floor).
///  - Along the trail only cells wholly under the body are cleared (centre within the body's
///    radius less half a cell's diagonal): an unseen obstacle corner at the body's edge must
///    stay an obstacle, or the trail creeps into it.
///  - At the first trail point, a disc of start_radius_m plus a cell.
/// Only unknown cells change; known ones keep their value. The trail grows with the distance
/// driven (8 bytes per spacing_m); the cells it clears are cached per grid geometry.
#include <duet/runtime/navigation/costmap_layer.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace duet {

class TrailLayer final : public CostmapLayer {
 public:
  /// body_radius_m: the chassis' radius; start_radius_m: the cleared disc at the start, less a
  /// cell (the dynamic window's footprint: robot radius + safety margin); free_logodds: the
  /// value written; spacing_m: trail points are kept this far apart.
  TrailLayer(float body_radius_m, float start_radius_m, float free_logodds, float spacing_m = 0.05f)
      : body_radius_m_(body_radius_m), start_radius_m_(start_radius_m), free_(free_logodds), spacing_m_(spacing_m) {}

  /// A robot position (map frame); kept if finite and spacing_m from the last one kept.
  void add(const Eigen::Vector2f& p);
  [[nodiscard]] const std::vector<Eigen::Vector2f>& points() const noexcept { return points_; }

  [[nodiscard]] std::string_view name() const override { return "trail"; }
  [[nodiscard]] bool active() const override { return !points_.empty(); }
  void apply(OccupancyGrid& grid) override;
  void shift(const Pose2& D) override;

 private:
  float body_radius_m_;
  float start_radius_m_;
  float free_;
  float spacing_m_;
  std::vector<Eigen::Vector2f> points_;
  // The cells under the trail for one grid geometry (apply() on a patrol's unchanging grid
  // costs the cells, not the trail's length).
  struct Geometry {
    float ox = 0.0f, oy = 0.0f;
    int w = -1, h = -1;
    float res = 0.0f;
    bool operator==(const Geometry&) const = default;
  };
  Geometry geometry_;
  std::vector<std::uint32_t> cells_;   ///< grid indices, each once
  std::vector<std::uint8_t> marked_;   ///< per grid cell: in cells_
  std::size_t done_ = 0;               ///< points_ already in cells_
};

}  // namespace duet
