#pragma once
/// @file visual_odometry.hpp
/// Frame-to-frame visual odometry of a robot with one or more RGB-D cameras (paper §2.1,
/// "location point generation"):
///  1. make_visual_frame(): ORB features of every camera's colour image (orb.hpp) and their 3D
///     points in the robot frame, through the depth image at the feature's pixel and the
///     camera's extrinsics (T_robot_camera). A pixel without depth takes the median of the
///     valid depths of its 3 x 3 neighbours when at least 3 are valid and all lie within 3 % of
///     that median (Kinect depth has holes right on the edges where corners are; a neighbourhood
///     across a depth edge gives no point);
///  2. estimate_motion(), from the previous frame to the current one:
///     a. matching per camera, current features against the previous frame's (Hamming
///        distance, ratio test and cross check; descriptor_match.hpp), optionally guided by
///        the initial guess (the wheel-odometry increment);
///     b. fundamental-matrix RANSAC per camera (the epipolar constraint x'^T F x = 0; OpenCV's
///        8-point RANSAC), matches off the epipolar lines are dropped - unless F explains fewer
///        than half of the camera's matches: an 8-point RANSAC cannot find the true F among
///        mostly wrong matches in its iteration budget (0.3^8: 1 sample in 15000 is clean) and
///        its mask would then drop good matches, which step c handles far better (3 points);
///     c. RANSAC over the matches of all cameras together: a hypothesis is the rigid motion of
///        3 matches with depth in both frames (Horn / Umeyama, no scale), plus the initial
///        guess itself; it is scored by the PnP model - the reprojection error of every
///        previous 3D point in the current camera that saw it, truncated at the threshold
///        (MSAC, Torr & Zisserman 2000) - and the best hypothesis wins (ties: the lowest
///        hypothesis index);
///     d. Gauss-Newton on the reprojection error of the inliers (PnP refinement), inliers
///        re-chosen, refined again;
///     d'. search by projection (as ORB-SLAM's tracking does): every previous 3D point is projected
///        with the refined motion and matched again among the current features within
///        rematch_radius_px (guided matching, same tests); the new matches are refined as in d;
///     e. the covariance: sigma^2 (J^T J)^-1 with sigma^2 the inliers' mean squared error.
///
/// Frames: the motion is T_prev_curr, the current robot frame expressed in the previous one
/// (robot frame: REP 103, x forward, z up; camera optical frame: z forward, x right, y down).
/// A single camera with T_robot_camera = identity gives the camera's own motion.
///
/// Determinism: RANSAC hypotheses come from counter-seeded streams (seed, hypothesis index) and
/// are evaluated in fixed blocks; the result does not depend on the thread count.
/// Thread safety: reentrant; parallel inside (TBB) in the caller's task arena. OpenCV's own
/// threads are not used for the fundamental matrix (a fixed-seed, single-threaded RANSAC).
#include <duet/kernels/back_projection.hpp>
#include <duet/kernels/descriptor_match.hpp>
#include <duet/kernels/orb.hpp>

#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace duet {

/// One camera's features, with their 3D points.
struct VisualCamera {
  OrbFeatures features;
  /// Per feature: the 3D point in the robot frame; NaN where the depth at the pixel is missing
  /// or outside [min_depth_m, max_depth_m].
  std::vector<Eigen::Vector3f> points_robot;
  std::vector<float> depths_m;  ///< per feature: the depth [m], NaN as above
  PinholeIntrinsics intrinsics;
  Eigen::Isometry3f T_robot_camera = Eigen::Isometry3f::Identity();
  float scale_factor = 1.2f;  ///< the ORB pyramid's (octave k measures at scale_factor^k)
};

/// Everything the odometry keeps of one synchronised set of frames (a location point's
/// visual part).
struct VisualFrame {
  std::vector<VisualCamera> cameras;
  [[nodiscard]] std::size_t features() const noexcept;
  [[nodiscard]] std::size_t features_with_depth() const noexcept;
};

struct VisualFrameSettings {
  OrbSettings orb;
  float min_depth_m = 0.3f;  ///< nearer depths give no 3D point [m], [0, max_depth_m)
  float max_depth_m = 6.0f;  ///< farther depths give no 3D point [m], (min_depth_m, 100]
};
/// Throws duet::Error(kInvalidArgument) naming the bad field.
void validate(const VisualFrameSettings& s);

/// Builds `out` (replaced) from the frames of all cameras (one VisualCamera per frame, in
/// order; the cameras are processed in parallel). A frame without colour gives a camera with
/// no features. Throws duet::Error(kInvalidArgument) naming the camera when its depth or
/// colour image does not have the intrinsics' size, or a view is malformed.
void make_visual_frame(std::span<const SensorFrame> frames, const VisualFrameSettings& settings, VisualFrame& out);

struct VisualOdometrySettings {
  DescriptorMatchSettings match;
  /// > 0: guided matching, candidates within this of where the initial guess puts the previous
  /// feature's 3D point [px] - and brute force again when that fails (a guess too far off);
  /// 0: brute force. [0, 1000]
  float guided_radius_px = 0.0f;
  bool fundamental_filter = true;        ///< step b on or off
  float fundamental_threshold_px = 1.5f; ///< epipolar distance of an inlier [px], (0, 50]
  int min_fundamental_matches = 15;      ///< cameras with fewer matches skip step b, [8, 10000]
  float inlier_threshold_px = 2.5f;      ///< reprojection error of an inlier at octave 0 [px] (x scale^octave), (0, 50]
  int max_hypotheses = 1000;             ///< RANSAC hypotheses at most, [1, 100000]
  float confidence = 0.999f;             ///< stop when an outlier-free sample was drawn with this probability, (0, 1)
  int refine_iterations = 8;             ///< Gauss-Newton steps per refinement, [0, 100]
  /// Step d': search radius around the projection [px]; 0 turns the step off. [0, 1000]
  float rematch_radius_px = 8.0f;
  int min_inliers = 20;                  ///< fewer inliers: kTooFewInliers, [4, 100000]
  std::uint64_t seed = 1;                ///< RANSAC streams
};
/// Throws duet::Error(kInvalidArgument) naming the bad field.
void validate(const VisualOdometrySettings& s);

enum class VisualOdometryStatus {
  kOk = 0,              ///< motion estimated
  kTooFewFeatures = 1,  ///< a frame has fewer than min_inliers features with depth (blank or dark view)
  kTooFewMatches = 2,   ///< fewer than min_inliers matches survive steps a-b
  kTooFewInliers = 3,   ///< the best hypothesis has fewer than min_inliers inliers
};
[[nodiscard]] const char* to_string(VisualOdometryStatus s) noexcept;

struct VisualOdometryResult {
  VisualOdometryStatus status = VisualOdometryStatus::kTooFewFeatures;
  /// T_prev_curr; the initial guess unless status is kOk.
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  /// Covariance of xi = (omega, v) [rad, m] with true motion = motion * exp(xi) (a perturbation
  /// in the current robot frame); zero unless kOk.
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  std::size_t matches = 0;              ///< after step a, all cameras
  std::size_t fundamental_inliers = 0;  ///< after step b (= matches when it is off or skipped)
  std::size_t inliers = 0;              ///< of the final motion
  std::vector<std::size_t> camera_inliers;  ///< per camera
  std::size_t hypotheses = 0;           ///< RANSAC hypotheses scored
  double rms_px = 0.0;                  ///< inliers' reprojection error [px]
};

/// The motion from `prev` to `curr` (steps a-e above). `guess` is T_prev_curr from another
/// source (wheels; identity when there is none). The two frames must have the same number of
/// cameras (else duet::Error(kInvalidArgument)). Frames without enough features, matches or
/// inliers give a status other than kOk and `guess` as the motion - never an exception.
[[nodiscard]] VisualOdometryResult estimate_motion(const VisualFrame& prev, const VisualFrame& curr,
                                                   const Eigen::Isometry3d& guess,
                                                   const VisualOdometrySettings& settings);

/// The planar part of a result: the 3 x 3 covariance of (x, y, theta) of `motion` in the
/// previous robot frame, from its 6 x 6 `covariance` (first order).
[[nodiscard]] Eigen::Matrix3d planar_covariance(const Eigen::Isometry3d& motion,
                                                const Eigen::Matrix<double, 6, 6>& covariance);

}  // namespace duet
