#pragma once
/// @file bag_replay.hpp
/// `duet replay RUN.bag`: maps a ROS 1 bag of the node's input topics (each sensor's depth,
/// colour and camera_info, the odometry, optionally the IMU) through the C API's runtime, as the
/// node would have: the same depth/colour pairing (FrameSync), the same checks (image_view.hpp),
/// the runtime ticked once per control period of the bag's recorded clock (lockstep, so one bag
/// always maps to the same grid). Nothing is driven: the commands are computed and dropped.
///
/// Errors (std::runtime_error naming the bag): not a readable bag, none of the topics in it
/// (the message lists the bag's topics), a profile the runtime rejects, outputs not writable.
/// Malformed messages and messages of another type than their topic's are counted drops (in the
/// result and summary.json's "bag" block). The runtime expects frames at runtime.sensor_rate_hz:
/// unless a --set gives it, it is the bag's measured depth rate when that differs from the
/// profile's by more than 10 %.
#include <duet_ros/frame_sync.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace duet_ros {

struct BagReplayOptions {
  std::string bag;                        ///< the .bag file
  std::string profile = "dual";           ///< a built-in profile name or a YAML file
  std::vector<std::string> sets;          ///< KEY=VALUE overrides, as `duet explore --set`
  std::uint64_t seed = 1;
  std::string output_dir = "out/replay";
  std::string odom_topic = "/odom";
  std::string imu_topic;                  ///< empty: no IMU
  std::string topic_prefix = "/";         ///< each sensor's topics are PREFIX + NAME + "/depth_registered/image_raw" ...
  FrameSyncSettings sync;
  /// Asked between messages; false stops the replay early (the maps so far are saved).
  std::function<bool()> keep_going;
};

struct BagReplayResult {
  double duration_s = 0.0;                ///< bag time replayed [s]
  std::uint64_t messages = 0;             ///< messages read on the topics
  std::uint64_t frames_pushed = 0, frames_dropped = 0, odometry = 0, imu = 0;
  std::uint64_t control_periods = 0;
  std::uint64_t wrong_type = 0;           ///< messages of another type than the topic's (dropped)
  std::string last_drop;                  ///< the last dropped message's reason
  double sensor_rate_hz = 0.0;            ///< runtime.sensor_rate_hz as replayed [Hz]
  double bag_sensor_rate_hz = 0.0;        ///< the bag's depth rate (busiest sensor; 0: too few frames) [Hz]
  double profile_sensor_rate_hz = 0.0;    ///< the profile's (with the caller's sets) [Hz]
  bool interrupted = false;               ///< keep_going stopped it
};

[[nodiscard]] BagReplayResult replay_bag(const BagReplayOptions& options);

}  // namespace duet_ros
