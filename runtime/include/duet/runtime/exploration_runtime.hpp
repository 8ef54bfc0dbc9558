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
///  3. pose: the latest wheel odometry (paper §4.2: up to 20 Hz), corrected by scan-to-map
///     matching at every map update (PoseCorrectionSettings: the obstacle points of the new
///     frames are matched against the grid before it integrates them, and the correction
///     map <- odometry then applies to every odometry pose until the next update) - or, for
///     debugging only, a pose the caller overrides;
///  4. loop closure (loop_closure.hpp): after each map update the loop closer may move the map
///     (submaps placed by an optimised pose graph); the correction, the pose and what the
///     explorer holds in the map frame move with it;
///  5. control: the explorer's decision / dynamic window command goes to the chassis.
/// Until visual odometry exists the map frame is the odometry frame corrected by the matcher
/// (with the correction off: the odometry frame itself).
///
/// Thread safety: one thread calls tick(); the kernels run TBB-parallel in the caller's task
/// arena and the results do not depend on the thread count.
#include <duet/kernels/scan_match.hpp>
#include <duet/runtime/explorer.hpp>
#include <duet/runtime/loop_closure.hpp>
#include <duet/runtime/mapper.hpp>
#include <duet/runtime/profile.hpp>
#include <duet/runtime/robot_io.hpp>
#include <duet/runtime/synchronizer.hpp>

#include <deque>
#include <optional>
#include <span>
#include <unordered_map>
#include <vector>

namespace duet {

/// Scan-to-map correction of the wheel odometry (scan_match.hpp), once per map update.
struct PoseCorrectionSettings {
  bool enabled = true;          ///< false: the pose is the raw wheel odometry
  ScanMatchSettings match;      ///< the matcher (window, steps, field, prior, acceptance)
  /// Fraction of an accepted match's offset from the prior that is applied, (0, 1]. One match
  /// is good to ~0.4 deg / 3 cm (lab, 1 Hz frames, 0.05 m cells) while the gyro drifts
  /// 0.005 deg/s: a small gain averages the matches over ~1/gain updates and still tracks the
  /// drift (a complementary filter of odometry and matcher).
  float gain = 0.1f;
  /// Gain of the heading-rate estimate, [0, 1]: the matches' heading offsets divided by the time
  /// between updates feed a rate (a gyro's bias) that predicts the correction's heading at the
  /// next update (an alpha-beta filter with alpha = gain), so a constant bias leaves no steady
  /// lag. 0 = no rate. This is the gain's floor: the n-th update uses
  /// max(rate_gain, 1 / (1 / rate_gain_initial + n)), a running mean at first (the rate is
  /// unknown) that settles here. 0.002: on Willow (seed 1, gyro bias -0.0043 deg/s) a fixed 0.01
  /// let the estimate wander by +-0.01 deg/s, twice the bias it tracks; 0.002 keeps it within
  /// +-0.003 deg/s.
  float rate_gain = 0.002f;
  /// The rate gain of the first update, [rate_gain, 1] (see rate_gain): 0.02, worth a running
  /// mean over 50 updates.
  float rate_gain_initial = 0.02f;
  /// Age of the matcher's reference map [s], [0, 3600]; 0 (the default): the current grid. With
  /// an age, the grid is copied every this many seconds and the scans are matched against the
  /// copy before the latest (the map as it was one to two ages ago), and its distance field is
  /// computed once per age instead of at every update. Against the current grid each update
  /// is compared with what the previous ones added a second earlier, so in newly seen space the
  /// matches' small errors can add up; against an older map they are measured over a longer
  /// baseline, but where the scan sees mostly newer space the match is not confident and only
  /// the odometry carries the pose. Measured: lab with a 7x gyro bias (200 s) 1.2 deg / 0.17 m
  /// with 5 s against 2.7 deg / 0.21 m with 0; Willow seeds 1-3 (5400 s) 89.6 / 82.9 / 84.4 %
  /// coverage with 5 s against 89.3 / 89.3 / 89.2 % with 0, both before view goals (see
  /// bench/RESULTS.md).
  double reference_age_s = 0.0;
  float min_height_m = 0.15f;   ///< obstacle points from this height above the floor [m] (above the floor's noise)
  float max_height_m = 1.20f;   ///< ... up to this height [m] (the segmentation's obstacle band)
  int pixel_step = 4;           ///< every n-th pixel in u and v of each frame, [1, 64]
  std::size_t max_points = 2000;  ///< at most this many points (one per grid cell, then every k-th), >= 1
};
void validate(const PoseCorrectionSettings& s);

struct RuntimeSettings {
  double control_rate_hz = 20.0;   ///< control and pose rate [Hz] (paper §4.2), (0, 1000]
  double map_rate_hz = 1.0;        ///< mapper + grid + explorer map update [Hz] (paper §4.2), (0, control_rate_hz]
  /// The rate the sensors deliver frames at [Hz], (0, 1000]: sizes the odometry queue of the
  /// synchronizer and gives its inter-message lower bounds (0.9 / rate).
  double sensor_rate_hz = 30.0;
  ExplorerSettings explorer;
  ApproximateTimeSettings sync;    ///< queue_size raised to hold two sensor periods of odometry
  PoseCorrectionSettings pose_correction;
  /// Submaps, loop search and pose-graph optimisation (loop_closure.hpp); needs the pose
  /// correction (the loop closer trusts the front end over query_window_s).
  LoopClosureSettings loop_closure;
};
void validate(const RuntimeSettings& s);

struct RuntimeStats {
  std::size_t sets_integrated = 0;       ///< synchronized sets the mapper integrated
  std::size_t sets_not_integrated = 0;   ///< sets between map times (no consumer yet)
  std::uint64_t frames_received = 0;
  std::uint64_t frame_drops = 0;         ///< frames the synchronizer dropped (all sensors)
  std::uint64_t odometry_received = 0;
  std::uint64_t odometry_unmatched = 0;  ///< odometry in no set (50 Hz odometry vs the frame rate: expected)
  std::size_t scan_matches = 0;          ///< map updates whose scan match was accepted (the correction moved)
  std::size_t scan_match_rejected = 0;   ///< ... not accepted (too few points, not confident): correction kept
  double scan_match_time_s = 0.0;        ///< wall time in the correction (points, field, match) [s]
  std::size_t loop_closures = 0;         ///< closures that moved the map frame (LoopCloser::stats() has more)
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

  /// The pose estimate: correction() applied to the latest odometry (or the override).
  [[nodiscard]] const Pose2& pose() const noexcept { return pose_; }
  /// The scan matcher's correction map <- odometry frame (identity until a match is accepted).
  [[nodiscard]] const Pose2& correction() const noexcept { return correction_; }
  /// The estimated drift rate of the odometry's heading [rad/s] (see PoseCorrectionSettings::rate_gain).
  [[nodiscard]] float heading_rate() const noexcept { return heading_rate_; }
  [[nodiscard]] const Twist& last_command() const noexcept { return last_cmd_; }
  [[nodiscard]] Mapper& mapper() noexcept { return mapper_; }
  [[nodiscard]] const Mapper& mapper() const noexcept { return mapper_; }
  [[nodiscard]] const Explorer& explorer() const noexcept { return explorer_; }
  /// The loop closer (nullptr when LoopClosureSettings::enabled or the pose correction is off).
  [[nodiscard]] const LoopCloser* loop_closer() const noexcept { return loop_ ? &*loop_ : nullptr; }
  [[nodiscard]] const RuntimeStats& stats() const noexcept { return stats_; }
  [[nodiscard]] const ApproximateTimeCore& synchronizer() const noexcept { return sync_; }
  [[nodiscard]] const Profile& profile() const noexcept { return profile_; }

 private:
  void integrate(const ApproximateTimeCore::Set& set, double now_s);
  /// Odometry pose at time t, interpolated between the two recent messages around it; the
  /// fallback message's pose if t is not inside the history.
  [[nodiscard]] Pose2 odometry_at(double t, const OdometryMsg& fallback) const;
  /// Scan-to-map match of the frames' obstacle points around `prior`; updates correction_ from
  /// `odom` when accepted and returns the pose to integrate at.
  Pose2 correct(std::span<const SensorFrame> frames, const Pose2& odom, Pose2 prior, double t);
  /// Keeps the mapper's latest obstacle points near the robot in the odometry frame (they were
  /// integrated at `at`, the odometry said `odom`), forgets those older than the explorer's
  /// recent_obstacles_s, and hands the rest to the explorer in the map frame of `at`'s correction.
  void remember_obstacles(const Pose2& at, const Pose2& odom, double t);

  Profile profile_;
  RuntimeSettings settings_;
  ChassisInterface& chassis_;
  std::vector<RgbdSensorInterface*> sensors_;
  Mapper mapper_;
  Explorer explorer_;
  std::optional<LoopCloser> loop_;
  ApproximateTimeCore sync_;
  // Payloads waiting in the synchronizer, by id (moved in and out, never copied).
  std::unordered_map<std::uint64_t, RgbdImage> frames_;
  std::unordered_map<std::uint64_t, OdometryMsg> odometry_;
  std::uint64_t next_id_ = 0;
  double next_map_t_ = 0.0;
  Pose2 pose_;
  Pose2 odom_pose_;             ///< latest raw wheel odometry
  static constexpr std::size_t kOdomHistory = 256;  ///< odometry messages kept for interpolation (5 s at 50 Hz)
  std::deque<OdometryMsg> odom_history_;
  Pose2 correction_;            ///< map <- odometry (scan matching)
  float heading_rate_ = 0.0f;   ///< estimated drift of the odometry's heading [rad/s] (PoseCorrectionSettings::rate_gain)
  double last_match_t_ = -1.0;  ///< stamp of the last correction update [s]
  std::size_t rate_updates_ = 0;  ///< updates of heading_rate_ so far
  PointCloud scan_cloud_;       ///< scratch of correct()
  std::vector<Eigen::Vector2f> scan_points_;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> scan_keys_;
  InflatedGrid distance_;       ///< distance to the nearest occupied cell of the reference map
  bool have_reference_ = false; ///< distance_ holds a reference
  OccupancyGrid pending_grid_;  ///< the grid copied at pending_t_ (the next reference)
  double pending_t_ = -1.0;     ///< when pending_grid_ was copied [s] (-1: never)
  struct RecentScan {
    double t = 0.0;                        ///< stamp of the frames [s]
    std::vector<Eigen::Vector2f> points;   ///< obstacle points, one per grid cell, odometry frame
  };
  std::deque<RecentScan> recent_;          ///< see remember_obstacles()
  std::vector<Eigen::Vector2f> recent_map_;  ///< scratch: their map-frame points
  std::vector<std::uint64_t> recent_keys_;   ///< scratch: cells of one scan
  std::vector<std::pair<std::uint64_t, std::uint32_t>> recent_count_;  ///< scratch: (cell, scan) pairs
  Twist odom_twist_;
  Twist last_cmd_;
  std::optional<Pose2> pose_override_;
  RuntimeStats stats_;
};

}  // namespace duet
