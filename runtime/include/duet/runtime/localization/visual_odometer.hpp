#pragma once
/// @file visual_odometer.hpp
/// The visual front end as the localization room runs it (paper §2.1): each synchronised set of
/// RGB-D frames becomes a VisualFrame (ORB features and their 3D points in the robot frame,
/// kernels/visual_odometry.hpp) and is matched against the last location point (a keyframe),
/// with the wheel-odometry increment as the initial guess.
///
/// Location points: the first frame is one; a tracked frame becomes the next when it has moved
/// keyframe_translation_m or keyframe_rotation_deg from the location point, or when its inliers
/// fell below keyframe_inlier_ratio of the first frame tracked against the location point (the
/// view is leaving it). Matching against a location point rather than the previous frame keeps
/// slow motion from adding up per-frame noise (drift grows with location points, not frames).
/// A frame that fails (blank or dark views, too few inliers) leaves the location point in place:
/// the next frame is matched against it again, and the guess carries the pose meanwhile (the
/// EKF fuses the wheels) - one bad frame does not break the chain. After reset_after_failures
/// failures in a row, or once the guess has moved the robot beyond the location-point
/// thresholds, the view has left the location point for good: the next failing frame with
/// enough features (2 x min_inliers with depth) becomes the location point (Step::reset), and
/// tracking starts over from the guessed pose.
///
/// Frames: pose() is T_start_robot, the robot's 3D pose in the robot frame of its first frame.
/// Thread safety: one thread at a time.
#include <duet/kernels/visual_odometry.hpp>

#include <Eigen/Geometry>

#include <cstddef>
#include <span>

namespace duet {

struct VisualOdometerSettings {
  VisualFrameSettings frame;
  VisualOdometrySettings odometry;
  // Defaults measured on 7-Scenes RedKitchen 0-149 (ATE of the chained trajectory): a location
  // point every frame 2.50 cm; 0.1 m / 5 deg / 0.6: 2.11 cm; 0.2 m / 10 deg / 0.5: 1.80 cm;
  // 0.3 m / 15 deg / 0.4: 1.65 cm (bench/RESULTS.md, issue 21).
  float keyframe_translation_m = 0.30f;  ///< new location point after this much motion [m], (0, 10]
  float keyframe_rotation_deg = 15.0f;   ///< ... or this much rotation [deg], (0, 180]
  float keyframe_inlier_ratio = 0.4f;    ///< ... or inliers below this share of the first match's, [0, 1]
  int reset_after_failures = 3;          ///< failures in a row before a new location point is forced, [1, 1000]
};
/// Throws duet::Error(kInvalidArgument) naming the bad field.
void validate(const VisualOdometerSettings& s);

class VisualOdometer {
 public:
  explicit VisualOdometer(const VisualOdometerSettings& settings = {});

  struct Step {
    VisualOdometryResult result;  ///< of this frame against the location point
    bool first = false;           ///< the first frame with enough features (2 x min_inliers with depth): it became the location point
    bool new_keyframe = false;    ///< this frame became the location point
    bool reset = false;           ///< ... because tracking had failed (the chain starts over from the guess)
    /// T_prev_curr: the motion since the previous frame - the estimate when result is kOk,
    /// else the guess.
    Eigen::Isometry3d increment = Eigen::Isometry3d::Identity();
  };

  /// Tracks one set of frames (one per camera, the same cameras every time). `guess` is
  /// T_prev_curr since the previous call, from the wheels (identity without). Throws what
  /// make_visual_frame throws (a malformed frame, named) and duet::Error(kInvalidArgument) when
  /// the camera count changes.
  Step track(std::span<const SensorFrame> frames, const Eigen::Isometry3d& guess = Eigen::Isometry3d::Identity());

  /// The robot's pose in the first frame's robot frame.
  [[nodiscard]] const Eigen::Isometry3d& pose() const noexcept { return pose_; }
  /// The location point's pose.
  [[nodiscard]] const Eigen::Isometry3d& keyframe_pose() const noexcept { return key_pose_; }
  [[nodiscard]] const VisualFrame& keyframe() const noexcept { return key_; }
  [[nodiscard]] bool has_keyframe() const noexcept { return has_key_; }
  [[nodiscard]] std::size_t tracked() const noexcept { return tracked_; }
  [[nodiscard]] std::size_t failed() const noexcept { return failed_; }
  [[nodiscard]] std::size_t keyframes() const noexcept { return keyframes_; }
  [[nodiscard]] std::size_t resets() const noexcept { return resets_; }
  /// Forgets the location point and the pose (the next frame starts over at identity).
  void reset();

 private:
  VisualOdometerSettings settings_;
  VisualFrame key_, current_;
  bool has_key_ = false;
  Eigen::Isometry3d pose_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d key_pose_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d key_to_last_ = Eigen::Isometry3d::Identity();  ///< T_key_prev
  std::size_t key_reference_inliers_ = 0;  ///< inliers of the first frame tracked against the location point
  std::size_t tracked_ = 0, failed_ = 0, keyframes_ = 0, resets_ = 0;
  int failures_in_row_ = 0;
};

}  // namespace duet
