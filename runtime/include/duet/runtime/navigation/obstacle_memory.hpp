#pragma once
/// @file obstacle_memory.hpp
/// The recent obstacles (ExplorerSettings::recent_obstacles_s; a local costmap's obstacle
/// layer): the mapper's obstacle points of the last seconds, kept in the odometry frame - exact
/// relative to the robot over seconds - and handed to the navigator in the map frame of the
/// latest correction. A cell counts when at least recent_obstacle_min_scans scans put a point
/// in it (a single noisy return does not block).
/// Thread safety: one thread at a time.
#include <duet/kernels/motion_model.hpp>
#include <duet/runtime/navigation/explorer_settings.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <deque>
#include <span>
#include <utility>
#include <vector>

namespace duet {

class ObstacleMemory {
 public:
  explicit ObstacleMemory(const ExplorerSettings& settings) : settings_(settings) {}
  /// The obstacle points (map frame xy) of a scan integrated at map pose `at` while the odometry
  /// said `odom`, stamped t [s], on a grid of `resolution_m`. Returns the cells (centres, map
  /// frame of `at`) seen in enough scans of the window.
  std::span<const Eigen::Vector2f> add(std::span<const Eigen::Vector2f> obstacles, const Pose2& at, const Pose2& odom,
                                       double t, float resolution_m);

 private:
  struct RecentScan {
    double t = 0.0;                        ///< stamp of the frames [s]
    std::vector<Eigen::Vector2f> points;   ///< obstacle points, one per grid cell, odometry frame
  };
  ExplorerSettings settings_;
  std::deque<RecentScan> recent_;
  std::vector<Eigen::Vector2f> map_;       ///< the result of add()
  std::vector<std::uint64_t> keys_;        ///< scratch: cells of one scan
  std::vector<std::pair<std::uint64_t, std::uint32_t>> count_;  ///< scratch: (cell, scan) pairs
};

}  // namespace duet
