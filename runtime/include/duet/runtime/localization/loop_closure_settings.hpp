#pragma once
/// @file loop_closure_settings.hpp
/// Settings of loop closure (loop_closure.hpp): submaps, the loop search, its verification and
/// the pose graph. YAML: localization.loop_closure (config/profile.hpp).
#include <duet/kernels/pose_graph.hpp>
#include <duet/kernels/scan_match.hpp>

#include <cstddef>

namespace duet {

/// The wide-window matcher of loop closure (defaults differ from the front end's).
[[nodiscard]] inline ScanMatchSettings loop_match_defaults() {
  return ScanMatchSettings{.linear_window_m = 1.5f, .angular_window_deg = 6.0f, .linear_step_m = 0.1f, .angular_step_deg = 1.0f,
                           .sigma_m = 0.05f, .max_distance_m = 0.3f, .prior_sigma_m = 3.0f, .prior_sigma_deg = 20.0f,
                           .min_points = 150, .min_score = 0.55f};
}

struct LoopClosureSettings {
  bool enabled = true;               ///< false: no submaps, no loop search (the map is the front end's)
  double submap_duration_s = 30.0;   ///< a submap closes after this long [s], (0, 3600]
  float submap_travel_m = 5.0f;      ///< ... or after the robot drove this far in it [m], > 0
  double check_period_s = 5.0;       ///< a loop search every this often [s], > 0
  double query_window_s = 10.0;      ///< the query: obstacle points of the frames of the last this long [s], > 0
  double min_age_s = 60.0;           ///< submaps closed at least this long ago form the old map [s], >= 0
  float search_radius_m = 6.0f;      ///< old submaps whose extent comes this near the robot are searched [m], > 0
  std::size_t max_query_points = 700;   ///< the query is thinned to at most this many points (one per cell first)
  ScanMatchSettings match = loop_match_defaults();  ///< the wide-window matcher and its acceptance
  float verify_hit_m = 0.10f;        ///< a matched query point this near an old wall is a hit [m], >= 0
  float verify_free_m = 0.25f;       ///< ... one on old free floor farther than this from any wall a conflict [m], >= verify_hit_m
  std::size_t min_hits = 100;        ///< a match needs at least this many hits ...
  float max_conflict_ratio = 0.05f;  ///< ... and at most this many conflicts per hit, >= 0
  /// A match that would move the map (beyond min_correction_m / min_correction_deg) is believed
  /// only when the old map contradicts the prediction: at least this share of the query's points,
  /// at the predicted pose, on old free floor farther than max(verify_hit_m, half the correction)
  /// from any old wall, [0, 1]; 0 = no such check. A drift of d puts a wall's points about d
  /// off it; a right prediction puts them on old walls or on cells the old map never saw, and a
  /// wide window then finds an alias that lays the new walls on old ones (the lab's shelves:
  /// 0.9 m along an aisle with the pose 0.05 m from the truth, issue 23).
  float min_prediction_conflict = 0.03f;
  /// The check above applies to corrections that move the query's points by at least this on
  /// average [m], >= 0. A smaller drift leaves a wall's points within about verify_hit_m plus a
  /// cell of the old wall, so the old map cannot contradict the prediction whether it is right
  /// or not: the check has no power there, and turning such matches down only keeps a small
  /// drift in (freiburg-101: ten 0.10-0.13 m corrections of a pose 0.8-0.9 m off turned down).
  /// An alias's shift is a shelf's or a door's repeat, far above it (the lab's: 0.86 m).
  float prediction_check_min_shift_m = 0.20f;
  float confirm_m = 0.15f;           ///< two consecutive matches confirm a loop when their offsets agree within this [m]
  float confirm_deg = 1.5f;          ///< ... and this [deg]
  float min_correction_m = 0.10f;    ///< optimise when a confirmed loop is off the graph by more than this [m]
  float min_correction_deg = 1.0f;   ///< ... or this [deg]
  float odom_sigma_xy_m = 0.02f;     ///< odometry edge std: this [m] ...
  float odom_sigma_xy_per_m = 0.02f; ///< ... plus this per metre driven [m/m]
  float odom_sigma_theta_deg = 0.2f; ///< odometry edge heading std: this [deg] ...
  float odom_sigma_theta_per_m = 0.05f;  ///< ... plus this per metre driven [deg/m]
  float loop_sigma_xy_m = 0.05f;     ///< loop edge std [m]
  float loop_sigma_theta_deg = 0.5f; ///< loop edge heading std [deg]
  double max_loop_chi2 = 30.0;       ///< a new loop edge still above this after optimisation is dropped
  PoseGraphSettings graph;
};
/// Throws duet::Error(kInvalidArgument) naming the bad field.
void validate(const LoopClosureSettings& s);

}  // namespace duet
