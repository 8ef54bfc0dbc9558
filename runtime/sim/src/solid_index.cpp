/// @file solid_index.cpp
/// SolidIndex (solid_index.hpp).
#include <duet/kernels/error.hpp>
#include <duet/sim/solid_index.hpp>

#include "world_detail.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace duet::sim {

SolidIndex::SolidIndex(const World& world, float cell_m) : world_(&world), origin_(world.floor.min) {
  if (!(std::isfinite(cell_m) && cell_m > 0.0f && cell_m <= 1000.0f))
    fail(ErrorCode::kInvalidArgument, "SolidIndex: cell_m must be in (0, 1000] m, got " + std::to_string(cell_m));
  const Eigen::Vector2f ext = (world.floor.max - world.floor.min).cwiseMax(Eigen::Vector2f::Zero());
  cell_m_ = std::max(cell_m, std::sqrt(ext.x() * ext.y() / static_cast<float>(1u << 22)));  // at most ~2^22 cells
  width_ = std::max(1, static_cast<int>(std::ceil(ext.x() / cell_m_)));
  height_ = std::max(1, static_cast<int>(std::ceil(ext.y() / cell_m_)));
  const std::size_t cells = static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
  boxes_.resize(world.solids.size());
  // The cell range of a box, clamped to the grid (a disc that reaches past the floor collides
  // with the floor's edge before any solid is looked at).
  auto range = [&](const Eigen::Vector4f& b, int& x0, int& y0, int& x1, int& y1) {
    auto cx = [&](float x) { return std::clamp(static_cast<int>(std::floor((x - origin_.x()) / cell_m_)), 0, width_ - 1); };
    auto cy = [&](float y) { return std::clamp(static_cast<int>(std::floor((y - origin_.y()) / cell_m_)), 0, height_ - 1); };
    x0 = cx(b[0]), y0 = cy(b[1]), x1 = cx(b[2]), y1 = cy(b[3]);
  };
  std::vector<std::uint32_t> count(cells + 1, 0);
  for (std::size_t i = 0; i < world.solids.size(); ++i) {
    Eigen::Vector2f lo, hi;
    world_detail::bbox(world.solids[i].polygon, lo, hi);
    boxes_[i] = {lo.x(), lo.y(), hi.x(), hi.y()};
    int x0, y0, x1, y1;
    range(boxes_[i], x0, y0, x1, y1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) ++count[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x) + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) count[c + 1] += count[c];
  first_ = count;
  ids_.resize(first_.back());
  for (std::size_t i = 0; i < world.solids.size(); ++i) {
    int x0, y0, x1, y1;
    range(boxes_[i], x0, y0, x1, y1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) ids_[count[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)]++] = static_cast<std::uint32_t>(i);
  }
}

bool SolidIndex::collides(const World& world, const Eigen::Vector2f& centre, float radius_m, float z_low_m, float z_high_m) const {
  if (&world != world_) fail(ErrorCode::kInvalidArgument, "SolidIndex::collides: not the world the index was built for");
  if (world_detail::leaves_floor(world.floor, centre, radius_m)) return true;  // sim::collides()'s floor test
  if (!std::isfinite(radius_m)) return sim::collides(world, centre, radius_m, z_low_m, z_high_m);  // no cell range for it
  const float r2 = radius_m * radius_m;
  const int x0 = std::clamp(static_cast<int>(std::floor((centre.x() - radius_m - origin_.x()) / cell_m_)), 0, width_ - 1);
  const int x1 = std::clamp(static_cast<int>(std::floor((centre.x() + radius_m - origin_.x()) / cell_m_)), 0, width_ - 1);
  const int y0 = std::clamp(static_cast<int>(std::floor((centre.y() - radius_m - origin_.y()) / cell_m_)), 0, height_ - 1);
  const int y1 = std::clamp(static_cast<int>(std::floor((centre.y() + radius_m - origin_.y()) / cell_m_)), 0, height_ - 1);
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const std::size_t c = static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x);
      for (std::uint32_t k = first_[c]; k < first_[c + 1]; ++k) {
        const std::uint32_t i = ids_[k];
        const Solid& s = world.solids[i];
        if (!world_detail::height_overlaps(s, z_low_m, z_high_m)) continue;
        const Eigen::Vector4f& b = boxes_[i];
        if (world_detail::disc_overlaps(s, b.head<2>(), b.tail<2>(), centre, radius_m, r2)) return true;
      }
    }
  return false;
}

}  // namespace duet::sim
