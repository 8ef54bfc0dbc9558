#pragma once
/// @file pose_correction_settings.hpp
/// Settings of the scan-to-map correction of the wheel odometry (pose_corrector.hpp). YAML:
/// localization.pose_correction (config/profile.hpp).
#include <duet/kernels/scan_match.hpp>

#include <cstddef>

namespace duet {

/// Scan-to-map correction of the wheel odometry (scan_match.hpp), once per map update.
struct PoseCorrectionSettings {
  bool enabled = true;          ///< false: the pose is the raw wheel odometry
  ScanMatchSettings match;      ///< the matcher (window, steps, field, prior, acceptance)
  /// Fraction of an accepted match's offset from the prior that is applied, (0, 1]. One match is
  /// noisier than the gyro's drift between updates: a small gain averages the matches over ~1/gain updates and still tracks the
  /// drift (a complementary filter of odometry and matcher).
  float gain = 0.1f;
  /// Gain of the heading-rate estimate, [0, 1]: the matches' heading offsets divided by the time
  /// between updates feed a rate (a gyro's bias) that predicts the correction's heading at the
  /// next update (an alpha-beta filter with alpha = gain), so a constant bias leaves no steady
  /// lag. 0 = no rate. This is the gain's floor: the n-th update uses
  /// max(rate_gain, 1 / (1 / rate_gain_initial + n)), a running mean at first (the rate is
  /// unknown) that settles here: small, so the estimate does not wander by more than the bias
  /// it tracks (the measurement is in bench/RESULTS.md).
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
  /// the odometry carries the pose (bench/RESULTS.md: the default 0 explored Willow better).
  double reference_age_s = 0.0;
  float min_height_m = 0.15f;   ///< obstacle points from this height above the floor [m] (above the floor's noise)
  float max_height_m = 1.20f;   ///< ... up to this height [m] (the segmentation's obstacle band)
  int pixel_step = 4;           ///< every n-th pixel in u and v of each frame, [1, 64]
  std::size_t max_points = 2000;  ///< at most this many points (one per grid cell, then every k-th), >= 1
  /// Relocalisation (issue 19: a robot pushed, a burst of wheel slip): when this many of the last
  /// five updates had their match rejected or at the window's edge - or at once when the
  /// prediction explains almost none of a scan the matcher rejects (score below half of
  /// min_score) - the scan is matched over a wide window; a pose that explains it clearly better
  /// than the prediction replaces it at once. [0, 5]; 0 = never. Only with reference_age_s = 0
  /// (an aged reference lacks what was just seen: a wide window finds false fits in it).
  int relocalize_after = 3;
  float relocalize_window_m = 1.0f;     ///< +- this in x and y [m], (0, 5]
  /// +- this in heading [deg], (0, 45]. A push or a slip turns the robot by a few degrees; a
  /// wider window lets a map bent by drift (a long corridor) offer false fits turned by more
  /// (bench/RESULTS.md, stop 45).
  float relocalize_window_deg = 10.0f;
  float relocalize_step_m = 0.1f;       ///< lattice step [m] (then refined to a quarter), (0, 1]
  float relocalize_step_deg = 1.0f;     ///< [deg], (0, 10]
  /// The wide match's mean score must beat the prediction's by this, and match.min_score by
  /// this (scores in [0, 1]), (0, 1].
  float relocalize_min_gain = 0.15f;
  /// ... and only when the map contradicts the prediction: at least this share of the scan's
  /// points fall, at the predicted pose, on cells the map holds as free, [0, 1]; 0 = no such
  /// check (the lab robot carried 0.6 m sideways: 14-15 %, test_pose_corrector_hold.cpp). A scan of space not seen yet explains nothing at the prediction either, but its
  /// points fall on unknown cells - not a sign of being lost, and a wide window then finds a
  /// false fit of the new walls on old ones (freiburg-101: 1.3 m / 20.7 deg at 140 s, issue 23).
  /// Vision's request to re-match (VisualLocalization) is not subject to it. 0.1 is a guard: a
  /// scan mostly of new space contradicts the map on few points, and such a scan was re-matched
  /// the wrong way (bench/RESULTS.md, stop 45).
  float relocalize_min_conflict = 0.1f;
  /// ... and only when it is not ambiguous: its score must beat, by this, the best score of any
  /// other fit in the window - a pose farther than relocalize_distinct_m from it (the wide
  /// match's runner-up, ScanMatchSettings::runner_up_distance_m), [0, 1]; 0 = no such check.
  /// Measured (issue 23): freiburg-101 seed 1's false re-match at 713 s, which took a pose 1.15 m
  /// off to a heading 6 deg off, tied with its runner-up (0.73 and 0.73; the true pose lay
  /// outside the window); the right ones beat theirs by 0.11 (belgioioso seed 3, 699 s), 0.14
  /// (freiburg-101, 2002 s) and 0.37 (the lab robot carried 0.6 m).
  float relocalize_min_margin = 0.05f;
  float relocalize_distinct_m = 0.3f;  ///< [m], (0, 5]
  /// ... and only where the robot can stand: the new pose's centre at least this far from
  /// every cell the map holds occupied, [m], [0, 1]; 0 = no such check. The robot is never in
  /// a wall, so a fit there is a false one however well the scan matches (issue 23,
  /// belgioioso single sensor: a 1.31 m re-match scoring 0.96 against a runner-up's 0.89 put
  /// the robot inside a wall's inflation, 2 m from the truth, and the run gave up blocked).
  /// 0.1 m is below any chassis' radius, and above the map's own noise of one 5 cm cell.
  float relocalize_min_clearance_m = 0.1f;
  /// ... and only when it is a peak inside the window: a fit within this many lattice steps
  /// (relocalize_step_m, relocalize_step_deg) of the window's edge in x, y or heading is not
  /// taken, [0, 5]; 0 = no such check. At the edge the fit is the best the window allows, not a
  /// maximum of the score: the scan fits better still outside it, so where the robot is the
  /// window does not say (issue 23, edmonton seed 5: re-matches at -11.0 and +10.8 deg in a
  /// +-10 deg window moved a pose 0.18 m off the truth by 1.0 m, and the robot hit a wall; the
  /// refinement's quarter steps can reach half a step past the edge, hence 0.5). The price: a
  /// robot pushed by more than the window is not relocalised in one go but stays with its
  /// odometry until the loop closer (or vision) brings it back.
  float relocalize_edge_steps = 0.5f;
};
void validate(const PoseCorrectionSettings& s);

}  // namespace duet
