#pragma once
/// @file exploration_runtime.hpp
/// The real-time exploration loop of a robot (issue 4, DESIGN.md §3), independent of where the
/// data comes from: it reads the ChassisInterface and RgbdSensorInterface of robot_io.hpp (the
/// simulator today; recorded-data replay, the C API and real drivers later) and runs, once per
/// control period (tick):
///  1. odometry and frames -> the approximate-time synchronizer (streams: sensor 0..n-1, then
///     odometry; drops counted per stream);
///  2. every synchronized set whose stamp reaches the next map time is integrated by the mapper
///     at the pose of its odometry message and the explorer gets the new grid (map and grid at
///     map_rate_hz, paper §4.2: 1 Hz); sets between map times are counted as not integrated
///     (they are for visual odometry, not built yet);
///  3. pose: the latest wheel odometry (paper §4.2: up to 20 Hz) - or, for debugging only, a
///     pose the caller overrides;
///  4. control: the explorer's decision / dynamic window command goes to the chassis.
/// Until visual odometry exists the map frame is the odometry frame.
///
/// Thread safety: one thread calls tick(); the kernels run TBB-parallel in the caller's task
/// arena and the results do not depend on the thread count.
#include <duet/runtime/explorer.hpp>
#include <duet/runtime/mapper.hpp>
#include <duet/runtime/profile.hpp>
#include <duet/runtime/robot_io.hpp>
#include <duet/runtime/synchronizer.hpp>

#include <optional>
#include <span>
#include <unordered_map>
#include <vector>

namespace duet {

struct RuntimeSettings {
  double control_rate_hz = 20.0;   ///< control and pose rate [Hz] (paper §4.2), (0, 1000]
  double map_rate_hz = 1.0;        ///< mapper + grid + explorer map update [Hz] (paper §4.2), (0, control_rate_hz]
  /// The rate the sensors deliver frames at [Hz], (0, 1000]: sizes the odometry queue of the
  /// synchronizer and gives its inter-message lower bounds (0.9 / rate).
  double sensor_rate_hz = 30.0;
  ExplorerSettings explorer;
  ApproximateTimeSettings sync;    ///< queue_size raised to hold two sensor periods of odometry
};
void validate(const RuntimeSettings& s);

struct RuntimeStats {
  std::size_t sets_integrated = 0;       ///< synchronized sets the mapper integrated
  std::size_t sets_not_integrated = 0;   ///< sets between map times (no consumer yet)
  std::uint64_t frames_received = 0;
  std::uint64_t frame_drops = 0;         ///< frames the synchronizer dropped (all sensors)
  std::uint64_t odometry_received = 0;
  std::uint64_t odometry_unmatched = 0;  ///< odometry in no set (50 Hz odometry vs the frame rate: expected)
};

class ExplorationRuntime {
 public:
  /// `chassis` and `sensors` (one per profile sensor, in the profile's order) must outlive the
  /// runtime. Throws duet::Error(kInvalidArgument) for a sensor count that does not match the
  /// profile or invalid settings.
  ExplorationRuntime(const Profile& profile, ChassisInterface& chassis, std::span<RgbdSensorInterface* const> sensors,
                     const RuntimeSettings& settings = {});

  /// One control period at runtime time now_s [s] (non-decreasing).
  void tick(double now_s);

  /// DEBUGGING ONLY: map and plan with this pose instead of the odometry (nullopt: odometry).
  void override_pose(const std::optional<Pose2>& pose) { pose_override_ = pose; }

  [[nodiscard]] const Pose2& pose() const noexcept { return pose_; }
  [[nodiscard]] const Twist& last_command() const noexcept { return last_cmd_; }
  [[nodiscard]] Mapper& mapper() noexcept { return mapper_; }
  [[nodiscard]] const Mapper& mapper() const noexcept { return mapper_; }
  [[nodiscard]] const Explorer& explorer() const noexcept { return explorer_; }
  [[nodiscard]] const RuntimeStats& stats() const noexcept { return stats_; }
  [[nodiscard]] const ApproximateTimeCore& synchronizer() const noexcept { return sync_; }
  [[nodiscard]] const Profile& profile() const noexcept { return profile_; }

 private:
  void integrate(const ApproximateTimeCore::Set& set, double now_s);

  Profile profile_;
  RuntimeSettings settings_;
  ChassisInterface& chassis_;
  std::vector<RgbdSensorInterface*> sensors_;
  Mapper mapper_;
  Explorer explorer_;
  ApproximateTimeCore sync_;
  // Payloads waiting in the synchronizer, by id (moved in and out, never copied).
  std::unordered_map<std::uint64_t, RgbdImage> frames_;
  std::unordered_map<std::uint64_t, OdometryMsg> odometry_;
  std::uint64_t next_id_ = 0;
  double next_map_t_ = 0.0;
  Pose2 pose_;
  Twist odom_twist_;
  Twist last_cmd_;
  std::optional<Pose2> pose_override_;
  RuntimeStats stats_;
};

}  // namespace duet
