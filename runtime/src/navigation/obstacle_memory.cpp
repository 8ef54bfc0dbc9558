/// @file obstacle_memory.cpp
/// The recent obstacles in the odometry frame (see obstacle_memory.hpp).
#include <duet/runtime/navigation/obstacle_memory.hpp>

#include "mapping/cell_key.hpp"

#include <algorithm>

namespace duet {

std::span<const Eigen::Vector2f> ObstacleMemory::add(std::span<const Eigen::Vector2f> obstacles, const Pose2& at, const Pose2& odom,
                                                     double t, float res) {
  const ExplorerSettings& es = settings_;
  const float r2 = es.recent_obstacle_range_m * es.recent_obstacle_range_m;
  const Eigen::Vector2f robot(at.x, at.y);
  // One point per grid cell of this scan (the voxel filter leaves a column of points per cell).
  keys_.clear();
  for (const Eigen::Vector2f& p : obstacles) {
    if (!p.allFinite() || (p - robot).squaredNorm() > r2) continue;
    keys_.push_back(cell_key(p.x(), p.y(), res));
  }
  std::sort(keys_.begin(), keys_.end());
  keys_.erase(std::unique(keys_.begin(), keys_.end()), keys_.end());
  // Map -> odometry at the frames' time: the odometry is exact relative to the robot over the
  // window (its drift is the pose error's source only over minutes).
  const Pose2 odom_from_map = compose(odom, inverse(at));
  RecentScan scan{t, {}};
  scan.points.reserve(keys_.size());
  for (const std::uint64_t k : keys_) {
    const Eigen::Vector2f c = key_center(k, res);
    const Pose2 q = compose(odom_from_map, Pose2{c.x(), c.y(), 0.0f});
    scan.points.emplace_back(q.x, q.y);
  }
  recent_.push_back(std::move(scan));
  while (!recent_.empty() && recent_.front().t < t - static_cast<double>(es.recent_obstacles_s)) recent_.pop_front();
  // Back to the map frame with the correction the frames were integrated with (= the one the
  // control loop uses until the next update); a cell counts when at least min_scans scans of the
  // window put a point in it (a single noisy return does not).
  const Pose2 map_from_odom = compose(at, inverse(odom));
  count_.clear();
  for (std::size_t k = 0; k < recent_.size(); ++k)
    for (const Eigen::Vector2f& p : recent_[k].points) {
      const Pose2 q = compose(map_from_odom, Pose2{p.x(), p.y(), 0.0f});
      count_.emplace_back(cell_key(q.x, q.y, res), static_cast<std::uint32_t>(k));
    }
  std::sort(count_.begin(), count_.end());
  count_.erase(std::unique(count_.begin(), count_.end()), count_.end());
  map_.clear();
  const auto need = static_cast<std::size_t>(es.recent_obstacle_min_scans);
  for (std::size_t b = 0; b < count_.size();) {
    std::size_t e = b + 1;
    while (e < count_.size() && count_[e].first == count_[b].first) ++e;
    if (e - b >= need) map_.push_back(key_center(count_[b].first, res));
    b = e;
  }
  return map_;
}

}  // namespace duet
