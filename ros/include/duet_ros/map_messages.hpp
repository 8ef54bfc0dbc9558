#pragma once
/// @file map_messages.hpp
/// duet's outputs as ROS messages: the occupancy grid (nav_msgs/OccupancyGrid, the values
/// duet's map_server export uses: 100 at p >= 0.65, 0 at p <= 0.45, -1 unknown), the 3D map
/// (sensor_msgs/PointCloud2: x y z float32 + rgb packed as RViz reads it), the path, the
/// frontier cells (visualization_msgs/MarkerArray, one CUBE_LIST), planar poses and the
/// map -> odom transform. Thread safety: pure functions (the C API calls are thread-safe).
#include <duet.h>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <sensor_msgs/PointCloud2.h>
#include <visualization_msgs/MarkerArray.h>

#include <vector>
#include <string>

namespace duet_ros {

/// A grid handle (duet_runtime_get_grid) as a map in `frame`. An empty grid gives 0 x 0.
[[nodiscard]] nav_msgs::OccupancyGrid to_occupancy_grid(duet_grid grid, const std::string& frame, const ros::Time& stamp);
/// A cloud handle as an unordered PointCloud2 (x, y, z, rgb) in `frame`.
[[nodiscard]] sensor_msgs::PointCloud2 to_point_cloud2(duet_cloud cloud, const std::string& frame, const ros::Time& stamp);
/// x, y pairs (map frame) as a path; every pose's heading points to the next point.
[[nodiscard]] nav_msgs::Path to_path(const std::vector<float>& xy, const std::string& frame, const ros::Time& stamp);
/// A heading [rad] as a quaternion about z.
[[nodiscard]] geometry_msgs::Quaternion yaw_quaternion(double yaw);
/// An odometry message's planar pose (x, y, yaw) and twist (forward speed, yaw rate), as pushed
/// to duet_runtime_push_odometry().
[[nodiscard]] duet_pose2 planar_pose(const nav_msgs::Odometry& m);
[[nodiscard]] duet_twist planar_twist(const nav_msgs::Odometry& m);
/// A planar pose as a PoseStamped.
[[nodiscard]] geometry_msgs::PoseStamped to_pose_stamped(const duet_pose2& p, const std::string& frame, const ros::Time& stamp);
/// map -> odom such that map_from_odom * odom_from_base = map_from_base (both planar).
[[nodiscard]] geometry_msgs::TransformStamped map_to_odom(const duet_pose2& map_from_base, const duet_pose2& odom_from_base,
                                                         const std::string& map_frame, const std::string& odom_frame,
                                                         const ros::Time& stamp);
/// The frontier cells of `map` (free cells with an unknown 8-neighbour) as one CUBE_LIST marker
/// (namespace "frontiers", id 0; an empty list when there is none).
[[nodiscard]] visualization_msgs::MarkerArray frontier_markers(const nav_msgs::OccupancyGrid& map);
/// `map` as map_server files (`stem`.pgm, trinary: 0 occupied, 254 free, 205 unknown; `stem`.yaml
/// with map_saver's thresholds), the format duet_grid_load_map_server() and map_server read.
/// Returns false (and `error`) when a file cannot be written or the map is empty.
bool save_map_server(const nav_msgs::OccupancyGrid& map, const std::string& stem, std::string& error);
/// The number of frontier cells frontier_markers() marks.
[[nodiscard]] std::size_t count_frontier_cells(const nav_msgs::OccupancyGrid& map);

}  // namespace duet_ros
