#pragma once
/// @file scan_match.hpp
/// 2D scan-to-map matching: the planar pose (x, y, theta) near a prior at which a set of
/// obstacle points (robot frame, projected on the floor) best lies on the map's occupied cells.
/// It corrects the drift of wheel odometry between map updates (the pose source until visual
/// odometry exists; DESIGN.md §1 puts odometry + EKF + loop closure there later).
///
/// Score of a pose T (a likelihood field, as in Thrun et al., Probabilistic Robotics §6.4):
///   S(T) = (1/N) sum_i exp(-d(T p_i)^2 / (2 sigma^2)),
/// d = distance from the point to the nearest occupied cell centre (the ClearanceView of
/// inflate() with only occupied cells blocking), bilinearly interpolated between cell centres
/// and clamped to max_distance_m; points off the grid score 0.
/// The prior weighs each candidate (a Gaussian on the correction, as the translation and
/// rotation weights of Cartographer's real-time correlative matcher do):
///   W(T) = S(T) * exp(-|dt|^2 / (2 prior_sigma_m^2) - dtheta^2 / (2 prior_sigma_rad^2)),
/// so where the scan constrains nothing (a corridor's length) the prior is kept.
/// Search: every candidate of a regular lattice (linear_step_m, angular_step_deg) within the
/// window (exhaustive, the correlative scan matcher of Olson 2009 without its multi-resolution
/// bound), then the same around the best at a quarter of the steps, then below the lattice: a
/// quadratic in (x, y, theta) fitted by least squares to W on the 3 x 3 x 3 quarter-step
/// neighbourhood of the best; if it is concave its peak (clamped to one quarter step per axis)
/// replaces the best when its W is at least the best's.
///
/// The result is accepted (kMatched) when at least min_points points were given and the best
/// S reaches min_score; else kNotConfident (too little structure or a bad map) or
/// kTooFewPoints, and `pose` is the prior.
///
/// Runner-up (optional, runner_up_distance_m): the coarse lattice's scores are kept, and the best
/// S farther than that distance from the coarse best is reported; it does not change the match.
///
/// Determinism: ties go to the candidate with the lowest lattice index; the result does not
/// depend on the thread count.
/// Thread safety: reentrant; parallel inside (TBB, over angles) in the caller's task arena.
#include <duet/kernels/grid_view.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/kernels/motion_model.hpp>

#include <cstddef>
#include <span>

namespace duet {

/// Work budget of one match: (2 nl + 1)^2 (2 na + 1) lattice poses at most (nl, na: the windows
/// over the steps), each scoring every point (the defaults: 343; a relocalisation's: 18k).
inline constexpr double kMaxScanMatchPoses = 1e6;

struct ScanMatchSettings {
  float linear_window_m = 0.15f;     ///< search +-this in x and y around the prior [m], [0, 5]
  float angular_window_deg = 1.5f;   ///< search +-this in heading [deg], [0, 45]
  float linear_step_m = 0.05f;       ///< coarse lattice step in x and y [m], (0, 1]
  float angular_step_deg = 0.5f;     ///< coarse lattice step in heading [deg], (0, 10]
  float sigma_m = 0.05f;             ///< std of the likelihood field [m], (0, 1]
  float max_distance_m = 0.25f;      ///< distances are clamped to this [m], (0, 10]
  float prior_sigma_m = 0.1f;        ///< std of the translation prior [m], (0, inf)
  float prior_sigma_deg = 2.0f;      ///< std of the heading prior [deg], (0, inf)
  std::size_t min_points = 50;       ///< fewer points: kTooFewPoints, >= 1
  float min_score = 0.35f;           ///< best mean score below this: kNotConfident, [0, 1]
  /// > 0: also report the runner-up (ScanMatchResult::runner_up_score), the best S of the coarse
  /// lattice's candidates whose translation lies farther than this from the coarse best's [m],
  /// [0, 5]; 0 = not computed (no extra work).
  float runner_up_distance_m = 0.0f;
};
/// Throws duet::Error(kInvalidArgument) naming the bad field.
void validate(const ScanMatchSettings& s);

enum class ScanMatchStatus {
  kMatched = 0,       ///< pose is the best candidate
  kTooFewPoints = 1,  ///< pose is the prior
  kNotConfident = 2,  ///< pose is the prior (best score below min_score)
};

struct ScanMatchResult {
  ScanMatchStatus status = ScanMatchStatus::kTooFewPoints;
  Pose2 pose;                 ///< the matched pose, or the prior
  float score = 0.0f;         ///< S of `pose` (mean per point, [0, 1])
  float prior_score = 0.0f;   ///< S of the prior
  std::size_t candidates = 0; ///< poses scored
  /// With ScanMatchSettings::runner_up_distance_m > 0: the best S of a coarse candidate that
  /// places the scan elsewhere (translation farther than that from the coarse best, any
  /// heading); 0 when there is none. A runner-up near `score` means the window holds two fits:
  /// the match is ambiguous (a corridor's repeat, a second room of the same shape).
  float runner_up_score = 0.0f;
};

/// The distance field scan_match() reads: inflate() of `grid` with only occupied cells blocking
/// (unknown and uncertain cells do not, radius 0); `out.clearance()` is the view to pass.
void occupied_distance(const GridView& grid, const CellThresholds& thresholds, InflatedGrid& out);

/// S(T) of one pose (the definition above), for tests and diagnostics. Points with a non-finite
/// coordinate are skipped (they count in N). 0 for no points.
[[nodiscard]] float scan_match_score(ClearanceView distance, std::span<const Eigen::Vector2f> points_robot,
                                     const Pose2& pose, const ScanMatchSettings& settings);

/// Matches `points_robot` (robot frame [m]) against `distance` (distance to the nearest occupied
/// cell centre: the clearance() of occupied_distance()) around `prior` (map frame). Points with
/// a non-finite coordinate or one beyond kMaxCoordinateM (grid.hpp) are skipped. Throws
/// duet::Error(kInvalidArgument) for invalid settings, a non-finite prior, or a view whose size
/// does not match its span; kOutOfRange for a prior beyond kMaxCoordinateM.
[[nodiscard]] ScanMatchResult scan_match(ClearanceView distance, std::span<const Eigen::Vector2f> points_robot,
                                         const Pose2& prior, const ScanMatchSettings& settings = {});

}  // namespace duet
