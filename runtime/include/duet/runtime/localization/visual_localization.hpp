#pragma once
/// @file visual_localization.hpp
/// The localization room's odometry (paper §2.1): the wheels and the visual front end fused by
/// the EKF, as the runtime runs it.
///  - odometry(m): each wheel odometry message moves the EKF on the wheels' increment since the
///    previous message (the robot-frame distance and heading change over the stamps' interval;
///    pose_ekf.hpp) and returns the fused pose - the runtime's odometry from then on.
///  - frames(views, t): each synchronised set of RGB-D frames is tracked against the last
///    location point (visual_odometer.hpp) with the EKF's motion since the previous set as the
///    guess; an accepted motion is the EKF's visual update (planar part, its covariance; gated),
///    and a new location point re-clones the EKF's pose.
///    Time: a set reaches the runtime after the odometry of its stamp (the synchronizer waits
///    for the message after it), so the EKF is ahead of the frames by that lag - 1.4 deg at
///    0.5 rad/s and a 50 ms lag, per update, enough to bias the heading. The fused poses of the
///    last odometry messages are kept; the increment the camera measured between the location
///    point's stamp and this set's is carried to the clone's and the EKF's times by the EKF's
///    own motion over each lag (z' = dc^-1 z dn, dc and dn from the interpolated history).
///  - health(now): good - a visual update was accepted within degraded_after_s with at least
///    good_min_inliers inliers; degraded - vision failed, weak or gated out since then, the
///    wheels (calibrated by vision while it saw) carry the pose; lost - no accepted update for
///    lost_after_s (or none ever after lost_after_s of running).
/// The output is an odom frame in the sense of REP 105: continuous, never jumping more than a
/// gated visual update moves it. The scan-to-map correction and loop closure stay on top of it
/// as the map <- odom correction (pose_corrector.hpp, loop_closure.hpp).
/// Thread safety: one thread at a time - except that frames() is also offered in three parts, so
/// that the front end (the expensive part, ~10 ms per set of two 640 x 480 frames) can run off
/// the control thread: begin() and finish() on the thread that calls odometry(), track() on any
/// one other thread in between (it touches only the visual odometer). One set at a time: the
/// next begin() after the previous finish().
#include <duet/runtime/localization/localization_health.hpp>
#include <duet/runtime/localization/visual_localization_settings.hpp>
#include <duet/runtime/robot/robot_io.hpp>

#include <cstddef>
#include <deque>
#include <utility>
#include <optional>
#include <span>

namespace duet {

struct VisualLocalizationStats {
  std::size_t sets = 0;            ///< frame sets tracked
  std::size_t accepted = 0;        ///< visual updates the EKF took
  std::size_t tracked_not_fused = 0;  ///< sets tracked but not fused (fuse_every_set, fuse_min_inliers)
  std::size_t gated = 0;           ///< ... it rejected (Mahalanobis gate)
  std::size_t failed = 0;          ///< sets the odometry could not track, of which:
  std::size_t too_few_features = 0;  ///< blank, dark or featureless views (or no depth under the features)
  std::size_t too_few_matches = 0;
  std::size_t too_few_inliers = 0;
  std::size_t location_points = 0;
  std::size_t resets = 0;          ///< location points forced after failures (the chain started over)
  std::size_t last_inliers = 0;
  double time_s = 0.0;             ///< wall time of the front end (track()) [s]
  /// The wheels' errors as the EKF has learnt them (pose_ekf.hpp): speed scale (now, lowest,
  /// highest) and yaw-rate bias now [rad/s].
  double wheel_scale = 1.0, wheel_scale_min = 1.0, wheel_scale_max = 1.0;
  double wheel_bias = 0.0;
  /// Mean squared Mahalanobis distance (NIS) of the accepted visual updates: 3 when the visual
  /// covariance is right (3 dof), larger when vision is trusted more than it deserves.
  double mean_nis = 0.0;
};

class VisualLocalization {
 public:
  explicit VisualLocalization(const VisualLocalizationSettings& settings);

  /// One wheel odometry message; returns the fused pose (the first message sets the start).
  Pose2 odometry(const OdometryMsg& m);
  /// One synchronised set (at least one frame with colour for vision to work), taken at t [s]:
  /// finish(begin(t), track(frames, begin's job)).
  void frames(std::span<const SensorFrame> frames, double t);

  /// A set taken at t, as begin() prepares it for track().
  struct Job {
    double t = 0.0;
    Pose2 at_frames;  ///< the fused pose at t
    Eigen::Isometry3d guess = Eigen::Isometry3d::Identity();  ///< the EKF's motion since the previous set's stamp
  };
  /// What track() measured, for finish().
  struct Tracked {
    VisualOdometer::Step step;
    bool has_keyframe = false;  ///< the odometer has a location point (false: a blank first view)
    double time_s = 0.0;        ///< wall time of track() [s]
  };
  /// The odometry thread: the guess for the set taken at t (it becomes the previous set).
  [[nodiscard]] Job begin(double t);
  /// Any thread, one set at a time: the front end on the set (visual_odometer.hpp). Throws what
  /// VisualOdometer::track throws (a malformed frame, named).
  [[nodiscard]] Tracked track(std::span<const SensorFrame> frames, const Job& job);
  /// The odometry thread: fuses what track() measured into the EKF, carried over the EKF's
  /// motion since the frames' stamp - however long the front end took.
  void finish(const Job& job, const Tracked& tracked);

  [[nodiscard]] Pose2 pose() const noexcept { return ekf_.pose(); }
  [[nodiscard]] Twist twist() const noexcept { return ekf_.twist(); }
  [[nodiscard]] LocalizationHealth health(double now_s) const noexcept;
  /// Vision confirms the wheels: health is good, and within lost_after_s no visual increment was
  /// gated out and the chain of location points did not start over (a reset): a kidnapped
  /// robot's first view after the move is gated out when it still matches, or breaks the chain
  /// when it does not, and tracking then goes on from the new place - health alone would stay
  /// good. PoseCorrector::confirm_odometry.
  [[nodiscard]] bool confirms_odometry(double now_s) const noexcept;
  [[nodiscard]] const VisualLocalizationStats& stats() const noexcept { return stats_; }
  [[nodiscard]] const PoseEkf& ekf() const noexcept { return ekf_; }

 private:
  VisualLocalizationSettings settings_;
  VisualOdometer odometer_;
  PoseEkf ekf_;
  /// The fused pose at t, interpolated in the recent history (the nearest end outside it).
  [[nodiscard]] Pose2 pose_at(double t) const;

  std::optional<OdometryMsg> last_odom_;
  std::deque<std::pair<double, Pose2>> history_;  ///< (stamp, fused pose) of the last messages
  Pose2 last_track_pose_;          ///< the fused pose at the previous set's stamp
  Pose2 clone_lag_;                ///< the EKF's motion from the location point's stamp to the clone's time
  bool tracking_ = false;
  double start_s_ = -1.0, last_ok_s_ = -1.0, last_gated_s_ = -1.0, last_reset_s_ = -1.0;
  VisualLocalizationStats stats_;
};

}  // namespace duet
