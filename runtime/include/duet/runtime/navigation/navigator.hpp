#pragma once
/// @file navigator.hpp
/// The planning half of the explorer (paper §3, Fig. 6): the costmaps of the latest map, the
/// goal life cycle and the global path. The Controller (controller.hpp) follows what it
/// publishes (NavPlanView); the Explorer (explorer.hpp) composes the two on one thread, the
/// runtime (exploration_runtime.hpp) runs the Navigator as a background task and the
/// Controller on the control thread.
///
/// Costmaps (update_map(), at the map rate): the observation model of the map (Procedure 1's
/// reward) and two layered costmaps (costmap_layer.hpp): the planning costmap (the map with the
/// contact obstacles, inflated) and the dynamic window's (the planning costmap's grid with the
/// recent obstacles and the body's trail, inflated with unknown cells as obstacles); a goal
/// strategy may keep a grid of its own (the relaxed grid while a relaxed goal is active).
///
/// Goal life cycle (the paper: "a new goal when the last is reached or its time limit passes"):
///  - decide() takes a decision when there is no goal: it asks its goal strategies in order
///    (goal_strategy.hpp; by default Procedure 1 and the frontier search, the frontier search on
///    a relaxed grid, view goals); the first goal proposed is moved to a cell the dynamic window
///    can stand on (standoff), then a path is planned (A* on the planning grid);
///  - a frontier goal reached and looked at is blacklisted for good; a goal abandoned (time
///    limit, no path, stuck, blocked) for blacklist_ttl_s, for good once max_goal_failures goals
///    were abandoned at its place; a view goal's frontier cell is
///    never looked at again;
///  - update_map() re-checks the goal (moved again or abandoned when blocked) and re-plans;
///  - a decision that finds the robot blocked (no traversable cell around it) is taken again
///    at each map for blocked_recovery_s while the controller climbs the clearance;
///  - exploration ends with the decision's status after final_retries decisions without a
///    goal at later map updates; then, by ExplorerSettings::on_done, the robot stays, drives
///    home, or patrols: waypoints picked along its own trail (every cell it drove through was
///    free), visited in the order it first passed them, lap after lap; a waypoint that cannot
///    be reached (no path, time limit, stuck, blocked) is skipped for this lap, and the patrol
///    ends (kDone) only when a whole lap reaches none.
///
/// Frames: map frame (the grid given to update_map()). Thread safety: not thread-safe (one
/// thread at a time); the kernels run TBB-parallel in the caller's task arena, and the
/// results do not depend on the thread count.
#include <duet/kernels/dwa.hpp>
#include <duet/kernels/exploration.hpp>
#include <duet/kernels/grid.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/kernels/observation.hpp>
#include <duet/kernels/path.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/navigation/contact_layer.hpp>
#include <duet/runtime/navigation/costmap_layer.hpp>
#include <duet/runtime/navigation/explorer_settings.hpp>
#include <duet/runtime/navigation/footprint_layer.hpp>
#include <duet/runtime/navigation/goal_strategy.hpp>
#include <duet/runtime/navigation/recent_obstacle_layer.hpp>
#include <duet/runtime/navigation/trail_layer.hpp>
#include <duet/runtime/navigation/unexplored.hpp>
#include <duet/runtime/robot/latency.hpp>

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace duet {

/// The plain values of a plan, shared by its view and its snapshot.
struct NavPlanState {
  ExplorerState state = ExplorerState::kIdle;
  bool have_map = false;
  bool wait_for_map = false;          ///< the last decision found nothing: no new one before the next map
  /// The last decision found the robot blocked (no traversable cell within its radius) and it is
  /// recovering (ExplorerSettings::blocked_recovery_s): the controller climbs the clearance.
  bool blocked = false;
  /// The goal counts as reached within this distance, without facing its heading (a simulated
  /// goal with ExplorerSettings::simulated_goal_handoff_m); 0: reach it and face its heading.
  float handoff_m = 0.0f;
  std::uint64_t goal_id = 0;          ///< changes with every new goal (0: none yet)
  double deadline_s = 0.0;            ///< the goal's time limit (runtime clock)
  DwaSettings dwa;                    ///< the profile's, with the relaxed radius while a relaxed goal is active
};

/// What the controller follows: a read-only view of the navigator's goal and grids (valid
/// until the navigator is next changed) or of a snapshot of them (NavSnapshot).
struct NavPlanView : NavPlanState {
  const Pose2* goal = nullptr;        ///< nullptr: no goal
  std::span<const Eigen::Vector2f> path;
  const InflatedGrid* local = nullptr;     ///< the dynamic window's grid
  const InflatedGrid* planning = nullptr;  ///< the grid paths are planned on
  [[nodiscard]] bool has_goal() const noexcept { return goal != nullptr; }
};

/// A copy of a NavPlanView that owns its data (handed from a background task to the control thread).
struct NavSnapshot : NavPlanState {
  ExplorationStatus stop_status = ExplorationStatus::kNoFrontier;
  std::string stop_detail;
  std::vector<UnexploredRegion> left;  ///< Navigator::left_unexplored()
  std::optional<Pose2> goal;
  std::vector<Eigen::Vector2f> path;
  InflatedGrid local, planning;
  [[nodiscard]] NavPlanView view() const;
};

/// The Navigator's two costmaps.
enum class CostmapKind {
  kPlanning,  ///< paths are planned on it (and strategies see its grid as the latest map)
  kLocal,     ///< the dynamic window drives on it
};

/// Why the controller gave a goal up.
enum class AbandonReason { kTimeout, kStuck };

class Navigator {
 public:
  /// With the default goal strategies (make_goal_strategies()).
  explicit Navigator(const Profile& profile, const ExplorerSettings& settings = {});
  /// With an ordered list of goal strategies (at least one; asked in order at each decision).
  Navigator(const Profile& profile, const ExplorerSettings& settings, std::vector<std::unique_ptr<GoalStrategy>> strategies);

  /// The latest map: rebuilds the costmaps, re-checks and re-plans the current goal.
  void update_map(const OccupancyGrid& grid, const Pose2& robot, double now_s);
  /// A decision (when there is no goal and the last decision did not ask to wait for a map).
  void decide(const Pose2& robot, double now_s);
  /// The recent obstacle points (map frame), used from the next update_map() on.
  void set_recent_obstacles(std::span<const Eigen::Vector2f> points);
  /// A robot position (map frame): the body's trail (kept 0.05 m apart) is free in the local grid.
  void add_trail(const Eigen::Vector2f& p);
  /// Appends a caller's layer to one of the costmaps, after its default layers (e.g. keep-out
  /// zones); it applies from the next update_map() on and moves with shift().
  void add_layer(CostmapKind costmap, std::unique_ptr<CostmapLayer> layer);

  // Events from the controller; `goal_id` names the goal they are about (ignored if it is no longer the current one).
  void goal_reached(std::uint64_t goal_id, double now_s);
  void abandon(std::uint64_t goal_id, AbandonReason why, double now_s);
  /// A stall: a contact obstacle at `contact` (map frame); abandons the goal; no decision before the next map.
  void stall(const Eigen::Vector2f& contact, double now_s);

  // Requests of the robot's operator (the C API's duet_runtime_return_home / _stop).
  /// Stop exploring (or patrolling) and drive back to the start through the normal goal
  /// machinery; stop_detail() says the operator asked. kDone at once when there is no trail yet
  /// or no path home after the usual attempts. No effect when already done or returning.
  void return_home(const Pose2& robot, double now_s);
  /// Stop now: the goal is dropped and the state becomes kDone, stop_detail() = `why`.
  void stop(const std::string& why);

  /// The map frame moved (loop closure): goal, path, trail, contacts, recent obstacles, view target move by D.
  void shift(const Pose2& D);

  [[nodiscard]] NavPlanView view() const;
  [[nodiscard]] NavSnapshot snapshot() const;
  [[nodiscard]] NavPlanState plan_state() const;

  [[nodiscard]] ExplorerState state() const noexcept { return state_; }
  [[nodiscard]] ExplorationStatus stop_status() const noexcept { return stop_status_; }
  /// Why exploration stopped, in words: "explored: no frontier left", "explored: N frontier
  /// cells left, all unreachable ...", "gave up: ..." - and, with OnDone::kReturnHome, whether
  /// the robot got home. Empty while exploring.
  [[nodiscard]] const std::string& stop_detail() const noexcept { return stop_detail_; }
  /// What was left unexplored when exploration stopped, where and why (unexplored.hpp; largest
  /// first; the stop detail lists the largest). Empty while exploring and when nothing was left.
  [[nodiscard]] const std::vector<UnexploredRegion>& left_unexplored() const noexcept { return left_; }
  /// Goals abandoned while exploring, counted per place (within the blacklist radius).
  [[nodiscard]] const std::vector<GoalFailures>& goal_failures() const noexcept { return failures_; }
  [[nodiscard]] const ExplorerStats& stats() const noexcept { return stats_; }
  [[nodiscard]] const std::optional<Pose2>& goal() const noexcept { return goal_; }
  [[nodiscard]] const std::vector<Eigen::Vector2f>& path() const noexcept { return path_; }
  [[nodiscard]] const InflatedGrid& inflated() const noexcept { return planning_costmap_.inflated(); }
  /// The grid paths are planned on: the goal's strategy's own (a relaxed grid), else inflated().
  [[nodiscard]] const InflatedGrid& planning_grid() const noexcept;
  [[nodiscard]] const InflatedGrid& local_grid() const noexcept { return local_costmap_.inflated(); }
  [[nodiscard]] const LayeredCostmap& costmap(CostmapKind which) const noexcept {
    return which == CostmapKind::kPlanning ? planning_costmap_ : local_costmap_;
  }
  [[nodiscard]] const std::vector<Eigen::Vector2f>& contacts() const noexcept { return contacts_->points(); }
  [[nodiscard]] const std::vector<Eigen::Vector2f>& recent_obstacles() const noexcept { return recent_->points(); }
  [[nodiscard]] const ExplorationDecision& last_decision() const noexcept { return decision_; }
  [[nodiscard]] const std::vector<DecisionRecord>& decisions() const noexcept { return log_; }
  [[nodiscard]] const std::vector<Eigen::Vector2f>& frontier_points() const noexcept { return frontier_xy_; }
  [[nodiscard]] bool wait_for_map() const noexcept { return wait_for_map_; }
  [[nodiscard]] std::uint64_t goal_id() const noexcept { return goal_id_; }
  /// Wall time of each decide() that ran (all strategies, the standoff and the path) [s].
  [[nodiscard]] const LatencyStats& decide_latency() const noexcept { return decide_latency_; }

 private:
  bool plan(const Pose2& robot);
  void abandon_goal(int& counter, double now_s);
  [[nodiscard]] GridView latest_map() const;
  [[nodiscard]] GoalStrategy* active() const;
  void drop_goal();
  [[nodiscard]] float dwa_clearance() const;
  [[nodiscard]] DwaSettings dwa_settings() const;
  [[nodiscard]] bool can_stand_on(int x, int y) const;
  [[nodiscard]] std::optional<Eigen::Vector2f> standoff(const Eigen::Vector2f& target) const;
  bool recheck_goal();
  /// Nothing left to explore: stop, or (OnDone::kReturnHome) start driving home.
  void finish(const Pose2& robot, double now_s);
  /// A goal at the start position and a path to it; false if none.
  bool plan_home(const Pose2& robot, double now_s);
  /// The patrol round from the trail (OnDone::kPatrol).
  void start_patrol(const Pose2& robot, double now_s);
  /// A goal at the next reachable patrol waypoint (skipping those with no path); kDone when a
  /// whole lap has none.
  void next_patrol_goal(const Pose2& robot, double now_s);
  /// The current patrol goal ended: reached or skipped; on to the next waypoint.
  void patrol_goal_ended(bool reached);
  /// The goal and its path are set: its deadline (the time limit plus the path at the nominal
  /// speed) and a new goal id.
  void start_goal(double now_s);
  /// No frontier cell of the planning grid within frontier_seen_radius_m of goal_frontier_.
  [[nodiscard]] bool frontier_seen() const;
  /// A goal at `target` (already in map frame), its path, its deadline; false without a path.
  bool set_goal_to(const Eigen::Vector2f& target, const Pose2& robot, double now_s);

  Profile profile_;
  ExplorerSettings settings_;
  std::vector<SensorSector> sectors_;
  ObservationModel model_;
  LayeredCostmap planning_costmap_;
  LayeredCostmap local_costmap_;
  ContactLayer* contacts_ = nullptr;       ///< the default layers (owned by the costmaps)
  FootprintLayer* footprint_ = nullptr;
  RecentObstacleLayer* recent_ = nullptr;
  TrailLayer* trail_ = nullptr;
  GoalBlacklist blacklist_;
  std::vector<std::unique_ptr<GoalStrategy>> strategies_;
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  std::size_t active_ = kNone;  ///< the strategy whose goal is the current one (kNone: none, or home)
  PathWorkspace path_ws_;
  ExplorationDecision decision_;
  ExplorerState state_ = ExplorerState::kIdle;
  ExplorationStatus stop_status_ = ExplorationStatus::kNoFrontier;
  ExplorerStats stats_;
  bool have_map_ = false;
  bool model_geometry_valid_ = false;
  std::optional<Pose2> goal_;
  std::uint64_t goal_id_ = 0;
  Eigen::Vector2f goal_target_{0.0f, 0.0f};
  /// The frontier cell a frontier goal is for (frontier_seen()); empty for other goals.
  std::optional<Eigen::Vector2f> goal_frontier_;
  std::vector<Eigen::Vector2f> path_;
  double goal_deadline_s_ = 0.0;
  int no_goal_decisions_ = 0;
  double blocked_since_s_ = -1.0;  ///< the first decision of the current blocked spell (-1: not blocked)
  bool simulated_goal_ = false;    ///< the current goal is Procedure 1's X_g
  bool handoff_ = false;          ///< ... and was farther than simulated_goal_handoff_m when issued
  bool wait_for_map_ = false;
  std::vector<DecisionRecord> log_;
  std::vector<Eigen::Vector2f> frontier_xy_;
  LatencyStats decide_latency_;
  bool returning_ = false;       ///< driving home (OnDone::kReturnHome)
  int home_attempts_ = 0;        ///< paths home tried
  std::vector<Eigen::Vector2f> patrol_;  ///< the patrol round (map frame)
  std::size_t patrol_next_ = 0;  ///< the waypoint of the current / next patrol goal
  int patrol_misses_ = 0;        ///< waypoints skipped in a row (a whole lap: the patrol ends)
  std::string stop_detail_;
  std::vector<GoalFailures> failures_;
  std::vector<UnexploredRegion> left_;
};

}  // namespace duet
