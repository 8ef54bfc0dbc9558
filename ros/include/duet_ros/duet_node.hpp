#pragma once
/// @file duet_node.hpp
/// The duet ROS node: a thin layer over the C API's runtime (duet_runtime.h). ROS topics in,
/// duet_runtime_push_*; one control period per odometry message (at the profile's control rate,
/// 20 Hz) on the node's own control thread, the command published at once; maps, path, goal,
/// frontiers and state published by a second thread at the map rate. The runtime runs with
/// background execution: the map update, loop closure and decisions never hold the control
/// thread (runtime.execution=background is forced).
///
/// Topics (relative to the node's namespace: remap them), for each profile sensor NAME:
///   in   NAME/depth_registered/image_raw  sensor_msgs/Image   16UC1 mm or 32FC1 m, registered
///        NAME/rgb/image_rect_color        sensor_msgs/Image   rgb8 / bgr8 (~use_color)
///        NAME/rgb/camera_info             sensor_msgs/CameraInfo (optional: K overrides the profile's)
///        odom                             nav_msgs/Odometry   wheel odometry (the pose and the twist)
///        imu                              sensor_msgs/Imu     yaw rate (~use_imu)
///   out  cmd_vel                          geometry_msgs/Twist at the control rate
///        map                              nav_msgs/OccupancyGrid, latched, every ~map_period s
///        ~cloud                           sensor_msgs/PointCloud2 (~cloud_period; 0: on save and at exit)
///        ~goal, ~path, ~frontiers, ~state (latched std_msgs/String), ~events (std_msgs/String)
///        tf map -> odom
///   services ~start ~stop ~return_home ~save (std_srvs/Trigger)
///
/// Thread safety: the object is made and run() on the main thread; its callbacks run on ROS's
/// spinner threads and its own two threads, and share only the C API's thread-safe handles and
/// members guarded by `mutex_` or atomics.
#include <duet.h>
#include <duet/runtime/robot/latency.hpp>
#include <duet_ros/frame_sync.hpp>

#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/transform_broadcaster.h>

#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace duet_ros {

/// The node's own settings (private ROS parameters; the profile's keys come through ~profile,
/// ~set and ~config).
struct NodeOptions {
  std::string profile = "dual";        ///< ~profile: a built-in name or a YAML file
  std::vector<std::string> sets;       ///< ~set (list or ';'-separated) and ~config (flattened): KEY=VALUE overrides
  std::uint64_t seed = 1;              ///< ~seed: Procedure 1's simulation seed
  std::string output_dir = "duet_maps";///< ~output_dir: where ~save and the exit save write
  std::string map_frame = "map", odom_frame = "odom";
  bool use_color = true;               ///< ~use_color: pair colour with depth
  bool use_imu = false;                ///< ~use_imu: the imu topic's yaw rate for the heading
  FrameSyncSettings sync;              ///< ~sync_queue, ~sync_max_interval
  double map_period_s = 1.0;           ///< ~map_period: map, frontiers, path, goal, state [s]
  double cloud_period_s = 0.0;         ///< ~cloud_period: 0 = the cloud only on save and at exit [s]
  double transform_tolerance_s = 0.1;  ///< ~transform_tolerance: map -> odom is stamped this far ahead [s]
  bool autostart = true;               ///< ~autostart: explore at once (else wait for ~start)
  bool save_on_exit = true;            ///< ~save_on_exit
  bool exit_when_done = false;         ///< ~exit_when_done: save and exit once the explorer is done
  double max_time_s = 0.0;             ///< ~max_time: save and exit after this much ROS time [s] (0: never)
  int threads = 0;                     ///< ~threads: duet's worker threads (0: all cores)
  bool mounts_from_tf = false;         ///< ~mounts_from_tf: the sensors' mounts from tf (base_frame <- each
                                       ///< depth image's frame_id) instead of the profile's extrinsics
  std::string base_frame = "base_link";///< ~base_frame: the robot frame of the mounts
  double tf_wait_s = 10.0;             ///< ~tf_wait: how long to wait for each sensor's first image and tf [s]
};
/// Reads the options from the private node handle; throws std::invalid_argument naming the
/// parameter for a value of the wrong type or out of range.
[[nodiscard]] NodeOptions read_options(const ros::NodeHandle& pnh);

class DuetNode {
 public:
  /// Makes the runtime from the options' profile (errors name the file and key: thrown as
  /// std::runtime_error) and advertises and subscribes everything.
  DuetNode(ros::NodeHandle& nh, ros::NodeHandle& pnh, NodeOptions options);
  ~DuetNode();
  DuetNode(const DuetNode&) = delete;
  DuetNode& operator=(const DuetNode&) = delete;

  /// Runs until ROS shuts down, `stop_flag` becomes non-zero (SIGINT, SIGTERM), ~max_time passes
  /// or (~exit_when_done) the explorer is done; then stops the robot and, with ~save_on_exit,
  /// saves the maps. Returns 0, or 1 when the save failed.
  int run(const std::atomic<int>& stop_flag);

 private:
  struct SensorIo;
  void make_runtime(const std::vector<std::string>& sets);
  [[nodiscard]] std::vector<std::string> mounts_from_tf();
  void on_pair(std::size_t sensor, const sensor_msgs::ImageConstPtr& depth, const sensor_msgs::ImageConstPtr& color);
  void on_odometry(const nav_msgs::OdometryConstPtr& msg);
  void on_imu(const sensor_msgs::ImuConstPtr& msg);
  void control_loop();
  void publish_loop();
  void tick(double now_s, bool by_odometry, double odom_wall_s);
  void publish_maps(bool with_cloud);
  bool save(const std::string& dir, std::string& message);
  static void on_event(void* self, double time_s, const char* message);
  static void on_error(void* self, duet_error code, const char* message);

  NodeOptions o_;
  ros::NodeHandle nh_, pnh_;
  duet_device device_ = nullptr;
  duet_runtime rt_ = nullptr;
  double period_s_ = 0.05;
  std::vector<std::string> sensor_names_;
  std::vector<duet_runtime_sensor_info> sensor_info_;
  std::unique_ptr<FrameSync> sync_;
  std::vector<std::unique_ptr<SensorIo>> io_;
  ros::Subscriber odom_sub_, imu_sub_;
  ros::Publisher cmd_pub_, map_pub_, cloud_pub_, goal_pub_, path_pub_, frontier_pub_, state_pub_, event_pub_;
  ros::ServiceServer start_srv_, stop_srv_, home_srv_, save_srv_;
  tf2_ros::TransformBroadcaster tf_;

  std::mutex mutex_;                 ///< guards the members down to the next comment
  duet_pose2 odom_pose_{};           ///< the latest odometry's pose (map -> odom)
  bool odom_seen_ = false;
  double odom_wall_s_ = -1.0;        ///< wall time the latest odometry arrived [s] (-1: taken)
  std::uint64_t odometry_received_ = 0, imu_received_ = 0, push_errors_ = 0;
  duet::LatencyStats topic_to_command_, control_period_;
  std::uint64_t ticks_ = 0, ticks_by_timeout_ = 0;
  std::string last_state_;
  std::condition_variable odom_cv_;

  double last_tick_start_ = -1.0;     ///< the control thread's: wall time the last period started
  double last_tf_s_ = -1.0;          ///< the control thread's: the ROS time of the last map -> odom sent

  std::atomic<bool> running_{true};
  std::atomic<bool> done_{false};
  std::mutex save_mutex_;            ///< one save at a time
  std::thread control_thread_, publish_thread_;
};

}  // namespace duet_ros
