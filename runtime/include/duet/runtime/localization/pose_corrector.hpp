#pragma once
/// @file pose_corrector.hpp
/// Scan-to-map correction of the wheel odometry (localization room), once per map update: the
/// obstacle points of the new frames (robot frame, one per grid cell) are matched against the
/// grid before it integrates them (scan_match.hpp: likelihood field, exhaustive lattice,
/// Gaussian prior), and a complementary filter moves the correction map <- odometry a gain's
/// fraction of the way, with an alpha-beta estimate of the heading's drift rate (a gyro's bias).
/// It only corrects what the map constrains over a small window; loop closure
/// (loop_closure.hpp) corrects the drift that builds up over minutes.
/// Thread safety: one thread at a time.
#include <duet/kernels/back_projection.hpp>
#include <duet/kernels/grid.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/kernels/scan_match.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/localization/pose_correction_settings.hpp>

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace duet {



/// A relocalisation's mean scan scores, [0, 1].
struct RelocalizationScores {
  float score = 0.0f;      ///< at the new pose
  float prior = 0.0f;      ///< at the prediction
  float runner_up = 0.0f;  ///< of the best other fit in the wide window (PoseCorrectionSettings::relocalize_distinct_m away)
};

class PoseCorrector {
 public:
  PoseCorrector(const Profile& profile, const PoseCorrectionSettings& settings);

  /// One map update: the frames (robot frame, stamped t [s]) were taken at wheel odometry pose
  /// `odom`; returns the pose to integrate them at (the prior correction applied to `odom`,
  /// moved towards the scan match against `grid` when one is accepted) and updates correction().
  Pose2 update(std::span<const SensorFrame> frames, const Pose2& odom, const OccupancyGrid& grid, double t);
  /// The same with the frames already back-projected (back_project_camera() with the mapping's
  /// settings): the matcher takes every pixel_step-th pixel of them, so each depth image is read
  /// once per map update. The same result as update(frames, ...), bit for bit.
  Pose2 update(const CameraPoints& points, std::span<const SensorFrame> frames, const Pose2& odom, const OccupancyGrid& grid,
               double t);
  /// The odometry is confirmed by another sensor (VisualLocalization::confirms_odometry): the next
  /// updates do not relocalise. A wide re-match that contradicts odometry vision confirms is a
  /// false fit of a scan that sees little of the map (lab seed 7 with vision: 1.24 m off at a
  /// score of 0.62 against 0.17 - then 2.5 m of error and a collision); a robot that is pushed
  /// or lifted shows vision a jump the wheels did not make. Counted in relocalizations_held().
  void confirm_odometry(bool confirmed) noexcept { odometry_confirmed_ = confirmed; }
  /// Another sensor saw the odometry jump (VisualLocalization: a visual increment the EKF gated
  /// out - the view moved in a way the wheels did not report: pushed, lifted, slipped): the next
  /// update matches its scan over the wide window at once, before the scan is integrated where
  /// it may not belong, instead of waiting for the matcher to grow suspicious (it may not: a
  /// kidnapped robot's first scan can fit the map it is wrongly placed in, lab kidnap seed 2). The
  /// ExplorationRuntime also asks after a stall: the robot drove into something where its map
  /// shows free floor. The wide match moves the pose only when it explains the scan clearly
  /// better than the prediction, as always. Counted in relocalizations_asked().
  void contradict_odometry() noexcept { relocalize_asked_ = true; }
  /// The map frame moved by D (loop closure): the correction moves with it, the reference map is dropped.
  void shift(const Pose2& D);

  /// map <- odometry (identity until a match is accepted).
  [[nodiscard]] const Pose2& correction() const noexcept { return correction_; }
  /// The rate the correction adds to the odometry's heading [rad/s]: minus the odometry
  /// heading's drift (a gyro's bias) when the estimate is right.
  [[nodiscard]] float heading_rate() const noexcept { return heading_rate_; }
  [[nodiscard]] std::size_t matches() const noexcept { return matches_; }
  [[nodiscard]] std::size_t rejected() const noexcept { return rejected_; }
  /// Wide re-matches that moved the pose (PoseCorrectionSettings::relocalize_after), and the
  /// last one's offset from the prediction (map frame, [m, rad]).
  [[nodiscard]] std::size_t relocalizations() const noexcept { return relocalizations_; }
  [[nodiscard]] const Pose2& last_relocalization() const noexcept { return last_relocalization_; }
  /// Wide re-matches not tried because the odometry was confirmed (confirm_odometry).
  [[nodiscard]] std::size_t relocalizations_held() const noexcept { return relocalizations_held_; }
  /// Wide re-matches not tried because the scan saw new space (relocalize_min_conflict).
  [[nodiscard]] std::size_t relocalizations_new_space() const noexcept { return relocalizations_new_space_; }
  /// The share of the scan's points on cells the map holds as free, at the prediction of the
  /// last update a wide re-match was due (relocalize_min_conflict), [0, 1].
  [[nodiscard]] float last_conflict() const noexcept { return last_conflict_; }
  /// Wide re-matches tried because another sensor contradicted the odometry (contradict_odometry).
  [[nodiscard]] std::size_t relocalizations_asked() const noexcept { return relocalizations_asked_; }
  /// Wide re-matches that would have moved the pose but had a runner-up within
  /// relocalize_min_margin of their score (ambiguous): not taken.
  [[nodiscard]] std::size_t relocalizations_ambiguous() const noexcept { return relocalizations_ambiguous_; }
  /// Wide re-matches that fit clearly and unambiguously but put the robot's centre nearer than
  /// relocalize_min_clearance_m to an occupied cell of the map: not taken.
  [[nodiscard]] std::size_t relocalizations_in_obstacle() const noexcept { return relocalizations_in_obstacle_; }
  /// Wide re-matches that fit clearly and unambiguously but lie within relocalize_edge_steps
  /// of the window's edge (the scan fits better outside the window): not taken.
  [[nodiscard]] std::size_t relocalizations_at_edge() const noexcept { return relocalizations_at_edge_; }
  /// The last relocalisation's mean scan score at the new pose, at the prediction and of its
  /// runner-up (the best fit farther than relocalize_distinct_m from it), [0, 1].
  [[nodiscard]] const RelocalizationScores& last_relocalization_scores() const noexcept { return last_relocalization_scores_; }
  [[nodiscard]] double time_s() const noexcept { return time_s_; }  ///< wall time spent [s]

 private:
  /// Share of scan_points_ that fall, at `pose`, on cells `grid` holds as free, [0, 1].
  [[nodiscard]] float free_conflict(const OccupancyGrid& grid, const Pose2& pose) const;

  Profile profile_;
  PoseCorrectionSettings settings_;
  Pose2 correction_;
  float heading_rate_ = 0.0f;
  double last_match_t_ = -1.0;
  std::size_t rate_updates_ = 0;
  std::size_t relocalizations_new_space_ = 0;
  float last_conflict_ = 0.0f;  ///< wide matches due but not tried: the scan saw new space
  /// The matcher's points of the frames (robot frame): pixel_step's lattice of `points`.
  void scan_from(const CameraPoints& points, std::span<const SensorFrame> frames);
  CameraPoints own_points_;             ///< when the caller's were sampled on another lattice
  std::vector<Eigen::Vector3f> scan_cloud_;
  std::vector<Eigen::Vector2f> scan_points_;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> scan_keys_;
  InflatedGrid distance_;       ///< distance to the nearest occupied cell of the reference map
  bool have_reference_ = false;
  OccupancyGrid pending_grid_;  ///< the grid copied at pending_t_ (the next reference)
  double pending_t_ = -1.0;
  std::size_t matches_ = 0, rejected_ = 0;
  unsigned suspect_ = 0;  ///< the last 8 updates, a bit each: match failed or sat at the window's edge
  std::size_t relocalizations_ = 0, relocalizations_held_ = 0, relocalizations_asked_ = 0;
  bool odometry_confirmed_ = false;
  bool relocalize_asked_ = false;
  Pose2 last_relocalization_;
  RelocalizationScores last_relocalization_scores_;
  std::size_t relocalizations_ambiguous_ = 0;
  std::size_t relocalizations_in_obstacle_ = 0;
  std::size_t relocalizations_at_edge_ = 0;
  double time_s_ = 0.0;
};

}  // namespace duet
