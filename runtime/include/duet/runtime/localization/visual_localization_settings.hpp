#pragma once
/// @file visual_localization_settings.hpp
/// Settings of the fused visual and wheel odometry (visual_localization.hpp). YAML:
/// localization.visual_odometry (config/profile.hpp).
#include <duet/runtime/localization/pose_ekf.hpp>
#include <duet/runtime/localization/visual_odometer.hpp>

namespace duet {

/// YAML: localization.visual_odometry (config/profile.hpp).
struct VisualLocalizationSettings {
  bool enabled = false;            ///< false: the runtime's odometry is the wheels' (as before issue 21)
  /// Sets tracked per second at most [Hz], (0, 1000]: a 30 Hz camera's sets in between are left
  /// to the mapper (two cameras cost ~11 ms per set on the control thread, bench Odometry/duet/
  /// dual_640x480). The simulator renders at this rate when vision is on and `--sensor-rate` is
  /// the pipeline's (duet explore).
  double rate_hz = 5.0;
  /// The visual odometer; in the runtime its matching is guided by the EKF's motion (40 px
  /// around the predicted pixel: repeated textures - bricks, tiles - defeat the ratio test of a
  /// brute-force match), falling back to brute force when the guided match fails.
  VisualOdometerSettings odometer = [] {
    VisualOdometerSettings o;
    o.odometry.guided_radius_px = 40.0f;
    return o;
  }();
  PoseEkfSettings ekf;
  /// The odometry's heading comes from a yaw gyro (a Kobuki's driver reports the gyro's heading
  /// by default; so does duet's simulator): the EKF takes its yaw rate with ekf.gyro_sigma and
  /// no wheel bias. false: the wheels' (ekf.wheel_yaw_rate_sigma, bias learnt from vision).
  bool odometry_heading_from_gyro = true;
  /// true: every tracked set updates the EKF. false: only a set that becomes a location point
  /// does (one increment per location point; the sets between still tell the health). Sets
  /// tracked against one location point share its features' depth errors, so false is the
  /// sounder filter - but measured (bench/RESULTS.md, issue 21) it holds slipping wheels far
  /// worse (0.36 m against 0.05 m max error) and the lab's ATE is the same within the seeds'
  /// spread: true.
  bool fuse_every_set = true;
  int good_min_inliers = 40;       ///< fewer inliers: degraded, [0, 100000]
  /// Fewer inliers: tracked but not fused - the wheels carry the pose, [0, 100000]. A view with
  /// few features (a plain corridor: distant corners only) constrains the motion weakly, and
  /// its covariance is least reliable there.
  int fuse_min_inliers = 0;
  /// Fewer inliers: the increment corrects the pose but does not teach the EKF the wheels' scale
  /// and bias (PoseEkf::update_visual's consider update), [0, 100000]. Meant for weak increments
  /// (a plain corridor's distant corners), which taught a wrong scale the wheels then carried;
  /// measured (bench/RESULTS.md, issue 21) 40 does not make the corridor better - the scale
  /// still reached 0.78 from increments with more inliers - so it is off (0) by default.
  int learn_wheels_min_inliers = 0;
  double degraded_after_s = 1.0;   ///< no accepted visual update for this long: degraded [s], (0, 3600]
  double lost_after_s = 10.0;      ///< ... for this long: lost [s], [degraded_after_s, 3600]
};
/// Throws duet::Error(kInvalidArgument) naming the bad field.
void validate(const VisualLocalizationSettings& s);

}  // namespace duet
