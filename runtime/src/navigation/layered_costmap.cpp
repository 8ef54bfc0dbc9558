/// @file layered_costmap.cpp
/// LayeredCostmap (costmap_layer.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/navigation/costmap_layer.hpp>

#include <string>

namespace duet {

LayeredCostmap::LayeredCostmap(const InflationSettings& inflation, std::vector<std::unique_ptr<CostmapLayer>> layers)
    : inflation_(inflation) {
  validate(inflation_);
  for (auto& l : layers) add(std::move(l));
}

CostmapLayer& LayeredCostmap::add(std::unique_ptr<CostmapLayer> layer) {
  if (!layer) fail(ErrorCode::kInvalidArgument, "LayeredCostmap: layer " + std::to_string(layers_.size()) + " is null");
  layers_.push_back(std::move(layer));
  return *layers_.back();
}

const OccupancyGrid& LayeredCostmap::update(const OccupancyGrid& map) {
  layered_ = false;
  for (const auto& l : layers_) {
    if (!l->active()) continue;
    if (!layered_) grid_ = map;  // the copy, made once and only when a layer has something to add
    layered_ = true;
    l->apply(grid_);
  }
  const OccupancyGrid& out = layered_ ? grid_ : map;
  inflate(GridView(out), inflation_, inflated_);
  return out;
}

void LayeredCostmap::shift(const Pose2& D) {
  for (const auto& l : layers_) l->shift(D);
}

}  // namespace duet
