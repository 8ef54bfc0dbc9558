#pragma once
/// @file loop_closure.hpp
/// Loop closure on submaps (DESIGN.md §1: "loop closure, pose-graph optimisation"), in the plane.
///
/// The front end (wheel odometry corrected by scan-to-map matching, exploration_runtime.hpp) is
/// accurate over seconds but drifts over minutes: on a long loop the robot comes back to a place
/// it mapped with its pose 0.5-2 m off, and the new map of the place lands beside the old one.
/// The loop closer
///  1. keeps the map as submaps (Mapper::keep_submaps(): each holds submap_duration_s or
///     submap_travel_m of observations), one pose-graph node per submap at the robot's pose when
///     it opened, joined to the previous node by the front end's relative pose (an odometry edge
///     whose std grows with the distance driven);
///  2. every check_period_s, matches the obstacle points of the last query_window_s (the front
///     end's poses are good over that window; many frames see more structure than one) against
///     the OLD map only - the submaps closed at least min_age_s ago, composed around the robot -
///     with a wide window (LoopClosureSettings::match: +-1.5 m, +-6 deg by default) around the
///     current estimate. The recent submaps share the current drift and would only confirm it;
///  3. accepts a match when its score reaches match.min_score, its best is not on the window's
///     edge, its points lie on old walls and not on the old map's free floor (min_hits,
///     max_conflict_ratio: the likelihood field alone rewards a new wall laid on an old one), and
///     the next check agrees with it
///     (the same offset within confirm_m / confirm_deg: a single match in a repetitive office can
///     be wrong), and adds an edge between the open submap's node and the old submap that holds
///     most of the matched points (robust, Huber);
///  4. when the loop disagrees with the graph by more than min_correction_m / min_correction_deg,
///     optimises the graph (pose_graph.hpp), moves every submap with its node (the grid and the
///     cloud are rebuilt: Mapper::place_submaps()), closes the open submap and returns the shift
///     of the map frame at the robot; an edge still inconsistent after optimisation
///     (chi2 > max_loop_chi2) is dropped and the graph restored.
///
/// Thread safety: one thread; the kernels run TBB-parallel in the caller's task arena and the
/// results do not depend on the thread count.
#include <duet/kernels/grid_view.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/kernels/pose_graph.hpp>
#include <duet/kernels/scan_match.hpp>
#include <duet/runtime/localization/loop_closure_settings.hpp>
#include <duet/runtime/mapping/mapper.hpp>

#include <deque>
#include <optional>
#include <vector>

namespace duet {



struct LoopClosureStats {
  std::size_t checks = 0;              ///< loop searches run
  std::size_t matches = 0;             ///< ... whose match reached min_score and passed the checks below
  std::size_t rejected_edge = 0;       ///< matches whose best lay on the window's edge (not a peak)
  std::size_t rejected_free_space = 0; ///< matches that put query points on the old map's free floor
  std::size_t rejected_unexplained = 0; ///< ... that would move the map while the old map does not contradict the prediction
  std::size_t confirmed = 0;           ///< ... confirmed by the next search (loop edges added)
  std::size_t closures = 0;            ///< optimisations that moved the map
  std::size_t rejected_inconsistent = 0;  ///< loop edges dropped after optimisation (chi2 > max_loop_chi2)
  float max_shift_m = 0.0f;            ///< largest shift of the robot's pose by a closure [m]
  double time_s = 0.0;                 ///< wall time in the loop closer [s] (all of it; of which:)
  double compose_time_s = 0.0;         ///< ... composing the old map and the query [s]
  double distance_time_s = 0.0;        ///< ... its distance field [s]
  double match_time_s = 0.0;           ///< ... the wide-window match [s]
  double frozen_at_s = -1.0;           ///< when the map was finished (freeze()) [s]; -1: not frozen
};

/// One closure that moved the map (LoopCloser::events()).
struct LoopClosureEvent {
  double t_s = 0.0;            ///< stamp of the frames that closed it [s]
  std::size_t old_node = 0;    ///< the old submap's node
  std::size_t open_node = 0;   ///< the open submap's node
  Pose2 shift;                 ///< the map frame's shift (new = shift * old)
  float robot_shift_m = 0.0f;  ///< how far it moved the robot's pose [m]
  float score = 0.0f;          ///< the match's score
  float prior_score = 0.0f;    ///< the score of the predicted pose against the same old map
};

/// One match that passed the window-edge and free-space checks (LoopCloser::matches()): what the
/// prediction check (LoopClosureSettings::min_prediction_conflict) saw, for diagnosis.
struct LoopMatchRecord {
  double t_s = 0.0;                ///< stamp of the search [s]
  Pose2 correction;                ///< the match relative to the prediction (robot frame)
  float score = 0.0f;              ///< the match's score
  float prior_score = 0.0f;        ///< the prediction's score against the same old map
  float prediction_conflict = 0.0f;  ///< the share of the query on old free floor at the prediction, [0, 1]
  float shift_m = 0.0f;            ///< the correction's mean shift of the query's points [m]
  bool moves_map = false;          ///< beyond min_correction_m / min_correction_deg
  bool accepted = false;           ///< passed the prediction check (a candidate for confirmation)
};

class LoopCloser {
 public:
  /// Puts `mapper` into submap mode (Mapper::keep_submaps(): call before its first integrate()).
  LoopCloser(const LoopClosureSettings& settings, const CellThresholds& cells, Mapper& mapper);

  /// After every Mapper::integrate(): the frames at time t [s] were integrated at pose `at` (map
  /// frame). Returns the shift D of the map frame when a closure moved the map (the new pose of
  /// anything the old map frame held is D * old; the robot's pose estimate must be moved by it),
  /// nullopt otherwise. The mapper must be the constructor's.
  std::optional<Pose2> update(Mapper& mapper, const Pose2& at, double t);

  /// The map is finished (exploration is over; the runtime also freezes the mapper's cloud,
  /// Mapper::freeze_cloud()): from now on no submap opens - the open one takes every later
  /// observation into its grid, so the map keeps up with changes while its memory stays
  /// bounded by the building's area - and no loop search runs (a closure would move that
  /// submap, built over the whole patrol, as one rigid piece). The front end's scan-to-map
  /// matching against the finished map keeps the pose, as in a SLAM system's localisation
  /// mode. Idempotent; `t` is recorded (stats().frozen_at_s).
  void freeze(double t);
  [[nodiscard]] bool frozen() const noexcept { return frozen_; }

  [[nodiscard]] const LoopClosureStats& stats() const noexcept { return stats_; }
  /// Pose-graph nodes (one per submap: the robot's pose when it opened, as now estimated).
  [[nodiscard]] const std::vector<Pose2>& nodes() const noexcept { return nodes_; }
  [[nodiscard]] const std::vector<PoseGraphEdge>& edges() const noexcept { return edges_; }
  /// Every closure that moved the map, in order.
  [[nodiscard]] const std::vector<LoopClosureEvent>& events() const noexcept { return events_; }
  /// Every match that reached the prediction check, in order (one per loop search at most).
  [[nodiscard]] const std::vector<LoopMatchRecord>& matches() const noexcept { return matches_; }

 private:
  bool check(Mapper& mapper, const Pose2& at, double t, Pose2& match, std::size_t& old_node);
  std::optional<Pose2> close(Mapper& mapper, const Pose2& at, double t, const Pose2& match, std::size_t old_node);
  /// Whether `match` is off the prediction `at` by more than min_correction_m or min_correction_deg
  /// (a closure that would move the map).
  [[nodiscard]] bool beyond_min_correction(const Pose2& at, const Pose2& match) const;

  LoopClosureSettings settings_;
  CellThresholds cells_;
  std::vector<Pose2> nodes_;        ///< X_k (current estimate)
  std::vector<Pose2> anchors_;      ///< A_k: X_k when submap k opened (the frame its content was integrated in)
  std::vector<double> closed_t_;    ///< when submap k closed [s] (+inf while open)
  std::vector<PoseGraphEdge> edges_;
  double opened_t_ = 0.0;           ///< when the open submap opened [s]
  float travel_m_ = 0.0f;           ///< driven since the last node [m]
  std::optional<Pose2> last_at_;
  double last_check_t_ = -1e300;
  struct Pending {
    Pose2 offset;                   ///< match * at^-1 of the unconfirmed match
    std::size_t node = 0;
  };
  std::optional<Pending> pending_;
  struct QueryScan {
    double t = 0.0;
    std::vector<Eigen::Vector2f> points;  ///< map frame
  };
  std::deque<QueryScan> ring_;
  OccupancyGrid reference_;
  InflatedGrid distance_;
  std::vector<Eigen::Vector2f> query_;
  std::vector<std::pair<std::uint64_t, Eigen::Vector2f>> cells_scratch_;  ///< (cell, point) scratch
  LoopClosureStats stats_;
  std::vector<LoopClosureEvent> events_;
  std::vector<LoopMatchRecord> matches_;
  struct Extent {
    bool observed = false;
    Eigen::Vector2f lo{0.0f, 0.0f}, hi{0.0f, 0.0f};  ///< observed cells' bounds, integration frame [m]
  };
  std::vector<Extent> extents_;     ///< of the closed submaps, by index
  float last_score_ = 0.0f;
  float last_prior_score_ = 0.0f;
  float last_prior_conflict_ = 0.0f;
  bool frozen_ = false;
};

}  // namespace duet
