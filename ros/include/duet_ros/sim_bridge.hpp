#pragma once
/// @file sim_bridge.hpp
/// duet's simulator as a ROS robot (`duet_sim_ros`): a Kobuki with the profile's RGB-D sensors
/// in a world, through the C API's simulator (duet_sim.h), publishing what the real robot's
/// drivers would - so the node, launch files and RViz configs can be tried before the robot
/// exists, and the node is tested end to end through ROS topics only.
///
///   out  /clock (rosgraph_msgs/Clock: the simulator's time; run everything with use_sim_time)
///        odom (nav_msgs/Odometry, 50 Hz, frame odom -> base_link) and tf odom -> base_link
///        NAME/depth_registered/image_raw (16UC1 mm), NAME/rgb/image_rect_color (rgb8),
///        NAME/rgb/camera_info, for each profile sensor NAME; static tf base_link -> NAME_optical
///        ~ground_truth (nav_msgs/Odometry: the true pose, world frame)
///   in   cmd_vel (geometry_msgs/Twist); a command older than ~cmd_timeout is dropped to zero
///        (as the Kobuki's firmware does)
///        map (nav_msgs/OccupancyGrid): scored against the world (coverage) every ~score_period
///
/// Faults (~camera_stop_at/_for, ~malformed_at, ~odom_disorder_at) test a node's handling of a
/// camera that stops, malformed images and odometry out of order, through ROS.
/// At the end (~max_time, SIGINT or shutdown) it writes ~summary (JSON): simulated time, the
/// coverage curve and final coverage of the last map, collisions, path length, what it
/// published and received.
/// Thread safety: run() on the main thread; the subscribers' callbacks on one spinner thread
/// share only atomics and `mutex_`-guarded members.
#include <duet.h>

#include <geometry_msgs/Twist.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include <atomic>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace duet_ros {

struct BridgeOptions {
  std::string world = "lab";            ///< ~world: a built-in world, a world YAML or a map_server YAML
  std::string profile = "dual";         ///< ~profile
  std::vector<std::string> sets;        ///< ~set: KEY=VALUE (list or ';'-separated)
  std::uint64_t seed = 1;               ///< ~seed: the wheel and depth noise
  double sensor_rate_hz = 30.0;         ///< ~sensor_rate: frames per second per sensor, (0, 60] (a Kinect: 30)
  double speed = 1.0;                   ///< ~speed: simulated seconds per wall second; 0 = as fast as it goes
  int threads = 1;                      ///< ~threads: rendering threads (0: all cores); the node needs the rest
  double step_s = 0.01;                 ///< ~step: simulation step and /clock period [s], [0.001, 0.1]
  double max_time_s = 0.0;              ///< ~max_time: stop after this simulated time [s] (0: never)
  double cmd_timeout_s = 0.5;           ///< ~cmd_timeout [s]
  double score_period_s = 10.0;         ///< ~score_period: simulated seconds between scorings of /map
  std::string summary;                  ///< ~summary: the JSON file written at the end ("" = none)
  std::string odom_frame = "odom", base_frame = "base_link";
  // Faults for testing a node through ROS (all off by default):
  double camera_stop_at_s = -1.0;       ///< ~camera_stop_at: sensor 0's topics fall silent at this time [s] ...
  double camera_stop_for_s = 0.0;       ///< ~camera_stop_for: ... for this long [s]
  double malformed_at_s = -1.0;         ///< ~malformed_at: at this time sensor 0 publishes a depth image of a wrong encoding and one of a wrong size
  double odom_disorder_at_s = -1.0;     ///< ~odom_disorder_at: at this time an odometry message stamped 0.5 s in the past is published
};
/// Reads the options from the private node handle; std::invalid_argument names a bad parameter.
[[nodiscard]] BridgeOptions read_bridge_options(const ros::NodeHandle& pnh);

class SimBridge {
 public:
  /// Makes the simulator (std::runtime_error naming the world / profile on error) and
  /// advertises everything.
  SimBridge(ros::NodeHandle& nh, ros::NodeHandle& pnh, BridgeOptions options);
  ~SimBridge();
  SimBridge(const SimBridge&) = delete;
  SimBridge& operator=(const SimBridge&) = delete;
  /// Runs until ~max_time, a non-zero stop_flag or ROS shutdown; writes ~summary. Returns 0, or
  /// 1 when the summary could not be written.
  int run(const std::atomic<int>& stop_flag);

 private:
  void on_cmd(const geometry_msgs::TwistConstPtr& msg);
  void on_map(const nav_msgs::OccupancyGridConstPtr& msg);
  void publish_frames(double t);
  void publish_odometry();
  /// Coverage of the latest /map (-1 without one) and its explored area [m^2].
  std::pair<double, double> score();

  BridgeOptions o_;
  ros::NodeHandle nh_, pnh_;
  duet_device device_ = nullptr;
  duet_sim sim_ = nullptr;
  std::vector<duet_runtime_sensor_info> info_;
  std::vector<std::string> names_;
  std::vector<ros::Publisher> depth_pub_, color_pub_, info_pub_;
  ros::Publisher clock_pub_, odom_pub_, truth_pub_;
  ros::Subscriber cmd_sub_, map_sub_;
  tf2_ros::TransformBroadcaster tf_;
  tf2_ros::StaticTransformBroadcaster static_tf_;

  std::mutex mutex_;                        ///< guards the members down to the next comment
  duet_twist cmd_{0.0f, 0.0f};
  double cmd_t_ = -1e300;                   ///< simulated time of the latest command
  std::uint64_t cmds_received_ = 0;
  nav_msgs::OccupancyGridConstPtr map_;
  std::uint64_t maps_received_ = 0;

  std::atomic<double> now_{0.0};            ///< the simulated time (the callbacks read it)
  std::uint64_t frames_published_ = 0, odometry_published_ = 0;
  std::uint64_t frames_withheld_ = 0, malformed_published_ = 0, disordered_published_ = 0;
  nav_msgs::Odometry last_odom_;
  std::vector<std::uint16_t> depth_buf_;
  std::vector<std::uint8_t> rgb_buf_;
};

}  // namespace duet_ros
