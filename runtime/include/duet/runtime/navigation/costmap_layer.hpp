#pragma once
/// @file costmap_layer.hpp
/// Costmap layers, as nav2's costmap_2d composes them: each layer marks or clears cells of a
/// working copy of the map, in order, and the result is inflated (inflation.hpp) for planning
/// and for the dynamic window. The Navigator (navigator.hpp) keeps two LayeredCostmaps:
///  - the planning costmap: the map, with no obstacle under the robot's estimated body
///    (footprint_layer.hpp), + the contact obstacles (contact_layer.hpp), inflated;
///  - the local costmap (the dynamic window's): the planning costmap's grid + the recent
///    obstacles (recent_obstacle_layer.hpp) + the body's trail (trail_layer.hpp), inflated with
///    unknown cells as obstacles.
/// A caller may append layers of its own (Navigator::add_layer()), e.g. keep-out zones.
///
/// Life cycle: the owner adds its data to a layer between map updates (points in the map
/// frame); update() applies every active layer to a copy of the map and inflates it; shift()
/// moves every layer's points when the map frame moves (loop closure).
/// Thread safety: none (the Navigator's thread).
#include <duet/kernels/grid.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/kernels/types.hpp>

#include <memory>
#include <string_view>
#include <vector>

namespace duet {

class CostmapLayer {
 public:
  virtual ~CostmapLayer() = default;
  /// A short name for logs and errors ("contacts", "recent_obstacles", "trail", ...).
  [[nodiscard]] virtual std::string_view name() const = 0;
  /// Whether apply() would change any cell: when no layer of a costmap is active, the map is
  /// inflated as it is, without a copy.
  [[nodiscard]] virtual bool active() const = 0;
  /// Marks or clears cells of `grid` (map frame): the map with the layers before this one applied.
  virtual void apply(OccupancyGrid& grid) = 0;
  /// The map frame moved by D (loop closure): the layer's map-frame data moves with it.
  virtual void shift(const Pose2& D) = 0;
};

/// A map, its layers applied in order, inflated.
class LayeredCostmap {
 public:
  /// `layers` may be empty; none may be null.
  LayeredCostmap(const InflationSettings& inflation, std::vector<std::unique_ptr<CostmapLayer>> layers);

  /// Appends a layer (applied after the others, from the next update() on); returns it.
  CostmapLayer& add(std::unique_ptr<CostmapLayer> layer);

  /// Applies the active layers to a copy of `map` (no copy when none is active) and inflates the
  /// result. Returns the grid that was inflated: the copy, or `map` itself (then valid as long
  /// as `map` is).
  const OccupancyGrid& update(const OccupancyGrid& map);
  /// Whether the last update() applied a layer (then grid() holds the layered map).
  [[nodiscard]] bool layered() const noexcept { return layered_; }
  /// The layered map of the last update() (meaningful only when layered()).
  [[nodiscard]] const OccupancyGrid& grid() const noexcept { return grid_; }
  [[nodiscard]] const InflatedGrid& inflated() const noexcept { return inflated_; }
  [[nodiscard]] const InflationSettings& inflation() const noexcept { return inflation_; }
  [[nodiscard]] const std::vector<std::unique_ptr<CostmapLayer>>& layers() const noexcept { return layers_; }

  /// Every layer's shift().
  void shift(const Pose2& D);

 private:
  InflationSettings inflation_;
  std::vector<std::unique_ptr<CostmapLayer>> layers_;
  OccupancyGrid grid_{0.05f};
  bool layered_ = false;
  InflatedGrid inflated_;
};

}  // namespace duet
