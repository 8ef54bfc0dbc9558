#pragma once
/// @file explorer.hpp
/// The explorer and the controller of the runtime (paper §3, Fig. 6; DESIGN.md §3) on the
/// exploration kernels: it keeps the observation model and the inflated grid of the latest map,
/// decides goals (partial map simulation, then the global frontier search), plans the global
/// path to the goal (A* on the inflated grid) and follows it with the dynamic window.
///
/// Goal life cycle (the paper: "a new goal when the last is reached or its time limit passes"):
///  - a decision is taken when there is no goal (start, goal reached, goal abandoned);
///  - at a goal the robot turns to the goal's heading (Procedure 1's X_g, or facing the unknown
///    side of a frontier); a frontier goal, once reached and looked at, is blacklisted for good
///    (if it is still a frontier the unknown cells behind it cannot be seen from there);
///  - a goal is abandoned, and blacklisted for blacklist_ttl_s, when its time limit passes
///    (goal_timeout_s + path length / nominal speed), when no path to it exists, or when the
///    dynamic window finds no admissible trajectory (or keeps recovering) for too long;
///  - the path is re-planned from the robot at every map update (the grid changed), and
///    abandoned when the goal cell became occupied or non-traversable.
///  - the dynamic window sees UNKNOWN cells as obstacles (the global path does not, so that
///    frontiers stay reachable): an RGB-D sensor sees nothing nearer than its min range
///    (0.5 m), so an obstacle the robot did not see on its way in stays unknown once it is
///    close, and driving into unknown space near the robot is driving blind. The cells the
///    robot's body has covered (its trail) are free - costmap_2d's footprint clearing - so the
///    robot is never inside an unknown "obstacle" at its own position. When no trajectory is
///    admissible on that grid (the robot is hemmed in by unseen cells) the dynamic window falls
///    back to the global grid for that period (counted in stats().local_fallbacks); when nothing
///    is admissible there either (the robot is inside the margin: a map update brought an
///    obstacle nearer), it escapes forward - turn towards more clearance, creep at 0.1 m/s -
///    because both sensors look forward/right and reversing is blind (stats().escapes); so does a
///    robot the window keeps on one spot for cornered_after_s (stats().cornered_escapes).
///  - a goal is a place the dynamic window can stand on its own grid: a goal (simulated or
///    frontier) whose cell lies within the dynamic window's radius of an unknown cell is moved
///    to the nearest cell, at most goal_standoff_search_m away, that is traversable on the
///    global grid and clear of unknown cells by that radius (stats().goals_moved); no such cell
///    = no path. A frontier goal always borders unknown cells, and the unknown beside a goal
///    may be an obstacle face never seen (a Kinect returns nothing above ~80 deg incidence, so
///    a shelf's face seen along an aisle stays unknown): measured on the lab, a goal 3 cm from
///    such a face made the robot enter the local margin, fall back to the global grid and hit
///    the shelf. The goal is re-checked (and moved again) at every map update. Blacklisting
///    uses the decision's own goal, not the moved one.
///  - when no frontier can be gone to (all unreachable, or all reachable ones blacklisted) and
///    the relaxed grid offers none either, the robot looks at them from where it can stand:
///    view goals (ExplorerSettings::view_range_m), each frontier cell looked at once;
///  - exploration ends with the decision's status when it has no goal (no frontier left, all
///    unreachable, all blacklisted, robot blocked) - after `final_retries` further decisions
///    at later map updates, because one more map update often re-opens a frontier; with
///    stop_when_no_frontier, a simulated goal does not keep it going once no reachable frontier
///    is left (see ExplorerSettings).
///
/// Frames: all poses in the map frame (the frame of the grid given to update_map()).
/// Thread safety: one Explorer per robot; calls are not thread-safe (one at a time); the kernels
/// run TBB-parallel in the caller's task arena, and results do not depend on the thread count.
#include <duet/kernels/dwa.hpp>
#include <duet/kernels/exploration.hpp>
#include <duet/kernels/grid.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/kernels/observation.hpp>
#include <duet/kernels/path.hpp>
#include <duet/runtime/profile.hpp>

#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace duet {

struct ExplorerSettings {
  float goal_timeout_s = 20.0f;       ///< fixed part of a goal's time limit [s], (0, inf)
  float nominal_speed_mps = 0.3f;     ///< path length / this is added to the time limit [m/s], (0, inf)
  float blacklist_ttl_s = 60.0f;      ///< how long an abandoned goal stays blacklisted [s], (0, inf]
  float stuck_timeout_s = 4.0f;       ///< no admissible trajectory for this long abandons the goal [s], (0, inf)
  /// Stall: commanded forward (>= 0.03 m/s) while the odometry measures no motion (< 0.01 m/s)
  /// for this long [s], (0, inf). The robot has run into something its sensors cannot see (a
  /// Kinect sees nothing nearer than 0.5 m): a contact obstacle is put just ahead of it, in every
  /// grid the explorer plans and drives on from the next map update on, and the goal is abandoned.
  float stall_timeout_s = 1.0f;
  float contact_radius_m = 0.10f;     ///< radius of a contact obstacle [m], (0, 1]
  int final_retries = 3;              ///< decisions at later map updates before giving up, [0, 1000]
  /// Exploration is complete when no reachable frontier is left, even if the partial map
  /// simulation still offers a goal: its reward (Eq. 5 entropy reduction) never reaches zero
  /// because known cells below the log-odds clamp keep gaining from re-observation (measured
  /// on the lab: 10-60 bits per goal at 99 % coverage), so R_g <= eps_R alone never ends a run.
  /// Costs one frontier search per simulated goal. false: the paper's rule only.
  bool stop_when_no_frontier = true;
  /// How far a goal may be moved off cells next to unknown space (see the goal life cycle) [m],
  /// [0, 5]; 0 = never move a goal (it is then abandoned when next to unknown cells).
  float goal_standoff_search_m = 0.75f;
  /// When the frontier search reaches no goal, it runs again on a relaxed grid: the robot's
  /// radius (planner and dynamic window) shrinks to the chassis' radius + this margin if that
  /// is smaller than the profile's [m], [0, 1]. A door whose jambs, once fully seen, narrow it
  /// under the inflation can so still be passed (the paper's footprint radius 0.23 m + 0.06 m
  /// leaves the Kobuki's 0.177 m body 0.11 m; Willow's doors close in the 0.29 m inflation).
  float squeeze_margin_m = 0.06f;
  /// Shrink the radius (above) whenever the search reaches no goal, from any area (true); or only
  /// when boxed in (false, the default; below). Observed-but-uncertain cells still block at
  /// this level. Off by default because it costs collisions: on Willow (5400 s) it reached
  /// 94.0 % with the true pose on seed 1 (0 collisions), but 93.1 % with 1 collision on seed 2,
  /// and 88.6 % with 2 collisions on the corrected odometry (seed 3): the squeezed margin
  /// (0.12 m around the body) is less than the pose's error or than what the sensors miss.
  bool squeeze_anywhere = false;
  /// With squeeze_anywhere, only towards frontiers of unknown regions at least this large [m^2],
  /// [0, inf) (FrontierSettings::min_unknown_region_m2 for that search): a room behind a door,
  /// not the pockets between clutter (no change on the runs above).
  float squeeze_min_unknown_m2 = 4.0f;
  /// When the robot is boxed in - the search reached less than this area of traversable cells
  /// from it (or none) [m^2], [0, inf); 0 = never - observed-but-uncertain cells stop blocking
  /// too (a door that grazing rays left uncertain). Not from large areas: at the end of an
  /// exploration that squeezes the robot against faces seen only at grazing incidence (lab,
  /// 10 seeds: 2 collisions with, 0 without).
  float boxed_in_area_m2 = 10.0f;
  /// View goals: when the frontier search offers no goal (every frontier unreachable, or every
  /// reachable one blacklisted) and the relaxed grid none either, the explorer looks at the
  /// frontier cells it cannot go to from cells it can stand on - a room seen through a gap too
  /// narrow for the robot, a cone of free cells through a doorway - before it stops. A view cell
  /// lies on a straight line of known-free cells from a frontier cell, view_min_range_m to
  /// view_range_m from it, is reachable and fits the dynamic window (can_stand_on); the goal is
  /// the view cell with the shortest path from the robot, facing its frontier cell (the front
  /// sensor looks along the line). Reached or abandoned, its frontier cell is never looked at
  /// again (cells within the frontier blacklist radius of it neither), so the robot works along
  /// a cone of free cells as far as each view reveals more. View goals are counted in
  /// ExplorerStats::view_goals and marked in the decision log.
  /// Range from the frontier cell [m], [0, 10]; 0 = no view goals (stop as the paper's rule says).
  float view_range_m = 4.0f;
  /// Nearest view cell to its frontier cell [m], [0, view_range_m] ([0, 10] with no view goals): beyond the sensors' minimum
  /// range (0.5 m) plus the sensor's offset behind the robot's centre.
  float view_min_range_m = 0.8f;
  int view_rays = 72;  ///< directions cast from each frontier cell (evenly over 360 deg), [4, 3600]
  /// Recent obstacles: every grid cell an obstacle point of the last recent_obstacles_s seconds
  /// of observations fell in blocks the dynamic window's grid (local_grid()), whatever the map's
  /// log-odds say; the planning grid keeps the map (a path the window cannot follow ends in the
  /// stuck timeout and the goal is abandoned) (set_recent_obstacles(); the runtime keeps the points in the odometry frame,
  /// which is exact relative to the robot over seconds, and places them with the current pose
  /// correction). Why: where the pose estimate has moved since a place was mapped, a cell the
  /// map has seen free many times (log-odds at the -2.0 clamp) needs three hits (3 s at 1 Hz)
  /// before it blocks, while the robot drives into what the sensors show there (Willow seed 6:
  /// the map 0.22 m off the pose, a wall corner seen as it approached, the cells still free).
  /// Cells within one cell of an obstacle of the map are not marked: the inflation's margin (a
  /// cell) holds them, and marking them would thicken walls by the sensors' noise (a narrow
  /// corridor closed so, Willow seed 6). The map itself is not changed (the observation model
  /// and the stored grid keep the log-odds); this is the obstacle layer of a robot's local
  /// costmap (nav2, move_base). [s], [0, 3600]; 0 = off (the default: on Willow it avoided
  /// some collisions and caused others, see bench/RESULTS.md; 20 s is the value measured).
  float recent_obstacles_s = 0.0f;
  /// ... only points within this distance of the robot when seen [m], (0, 10]: near points are
  /// precise (the Kinect's axial noise is 1 cm at 3 m, 4 cm at 5 m) and those are the ones to avoid.
  float recent_obstacle_range_m = 3.0f;
  /// ... only cells seen as an obstacle in at least this many of the window's scans, [1, 1000]:
  /// a single noisy return does not block (the runtime counts them, see remember_obstacles).
  int recent_obstacle_min_scans = 2;
  /// Cornered: the dynamic window has kept the robot within 0.1 m of one spot (turning in place,
  /// or creeping at a few mm/s while it spins) for this long [s], (0, inf): it escapes towards
  /// more clearance as when it is inside the margin (stats().cornered_escapes), until it is out of
  /// that spot. Without it a robot at the very edge of the traversable band spins for ever (every
  /// forward motion reachable from the spin leaves the band, and turning on keeps the score) until
  /// the goal times out, and the next goal the same - for 3300 s on Willow seed 4.
  /// [s], [0, inf); 0 = off (the default: measured on Willow it freed seed 4 but the runs of
  /// seeds 5 and 6 then ended early, see bench/RESULTS.md); 8 s, more than a whole turn at the
  /// mapping's angular speed (2 pi / 0.8 rad/s = 7.9 s), is the value measured.
  float cornered_after_s = 0.0f;
  /// Slow zone (nav2's speed filter, the collision monitor's slowdown zone): the dynamic
  /// window's top speed falls with the robot's clearance on the planning grid (distance from
  /// its centre to the nearest seen obstacle cell), linearly from the profile's max_v_mps at
  /// slow_clearance_m down to slow_speed_mps at the window's own margin (robot radius + safety
  /// margin) and below. Why: the map can lag behind the sensors where the pose estimate moved
  /// since a place was mapped (a cell seen free many times needs three hits, 3 s at 1 Hz, to
  /// block), and at 0.5 m/s a turn round a corner the map holds 0.2 m off is a collision (Willow
  /// seed 6); slower near obstacles the sensors' new hits reach the map before the robot does,
  /// while open space is still crossed at full speed. [m], [0, 10]; 0 = off. 0.8 m: half a metre
  /// beyond the margin, so a corridor 1.6 m wide is crossed at full speed and a doorway slowly
  /// (measured on Willow, seeds 1-8: 4 collisions against 7 without; see bench/RESULTS.md).
  float slow_clearance_m = 0.8f;
  /// ... the top speed at the margin [m/s], (0, inf) (above the profile's max_v_mps it changes
  /// nothing). 0.25 m/s: half the paper's exploration speed; 0.75 m (three map updates' worth of
  /// hits) takes 3 s.
  float slow_speed_mps = 0.25f;
};
void validate(const ExplorerSettings& s);

enum class ExplorerState {
  kIdle,        ///< no map yet
  kExploring,   ///< following a goal
  kDone,        ///< stopped; see stop_reason()
};

/// Counters and timings of one run (decision time is wall time of decide()).
struct ExplorerStats {
  int decisions = 0;              ///< decide_goal() calls
  int simulated_goals = 0;        ///< goals from the partial map simulation
  int frontier_goals = 0;         ///< goals from the frontier fallback (R_g <= eps_R)
  int goals_reached = 0;
  int goals_abandoned_timeout = 0;
  int goals_abandoned_no_path = 0;
  int goals_abandoned_stuck = 0;
  int goals_abandoned_blocked = 0;   ///< goal cell became occupied or non-traversable
  int replans = 0;
  int local_fallbacks = 0;          ///< control periods the dynamic window fell back to the global grid
  int escapes = 0;                  ///< control periods spent escaping the dynamic window's margin
  int cornered_escapes = 0;         ///< control periods spent escaping a spot (ExplorerSettings::cornered_after_s)
  int slowed = 0;                   ///< control periods the slow zone lowered the top speed (ExplorerSettings::slow_clearance_m)
  int goals_moved = 0;              ///< goals moved off cells next to unknown space (decisions and re-checks)
  /// Frontier goals found on a relaxed grid (the squeezed radius; when boxed in, observed-but-
  /// uncertain cells not blocking either) after the search on the planning grid reached none.
  int relaxed_goals = 0;
  int boxed_in_goals = 0;           ///< of relaxed_goals, those with uncertain cells not blocking
  int stalls = 0;                   ///< stalls detected (ExplorerSettings::stall_timeout_s): contact obstacles placed
  int view_goals = 0;               ///< view goals taken (ExplorerSettings::view_range_m)
  int view_goals_reached = 0;       ///< of view_goals, those reached and looked from
  /// Sum over map updates of the cells the recent obstacles made blocking: cells with no
  /// obstacle of the map within one cell (ExplorerSettings::recent_obstacles_s) - how far the
  /// map lagged behind what the sensors showed.
  std::size_t recent_obstacle_cells = 0;
  double decision_time_sum_s = 0.0;
  double decision_time_max_s = 0.0;
};

/// One decision, for the run's log.
struct DecisionRecord {
  double t_s = 0.0;                 ///< runtime clock
  ExplorationStatus status = ExplorationStatus::kNoFrontier;
  float reward_bits = 0.0f;         ///< R_g of the partial map simulation
  Pose2 robot;                      ///< where the robot was
  Pose2 goal;                       ///< the goal (if any)
  bool planned = false;             ///< a path to the goal was found
  std::size_t frontier_cells = 0;   ///< frontier cells in kept clusters (when the search ran)
  int reachable_clusters = 0;       ///< frontier clusters the robot can reach (when the search ran)
  std::size_t reached_cells = 0;    ///< cells the frontier search reached from the robot (when it ran)
  bool relaxed = false;             ///< the goal came from the search on the relaxed grid
  bool view = false;                ///< the goal is a view goal (ExplorerSettings::view_range_m)
  Eigen::Vector2f view_target{0.0f, 0.0f};  ///< for a view goal: the frontier cell it looks at
  Eigen::Vector2f nearest_frontier{0.0f, 0.0f};  ///< the nearest reachable cluster's nearest cell
  double wall_time_s = 0.0;         ///< how long decide_goal() took
};

class Explorer {
 public:
  /// `profile.exploration` configures the kernels; its sensors give the observation sectors.
  explicit Explorer(const Profile& profile, const ExplorerSettings& settings = {});

  /// The latest map (1 Hz): rebuilds the observation model and the inflated grid, re-plans the
  /// current goal's path. `now_s` is the runtime clock.
  void update_map(const OccupancyGrid& grid, const Pose2& robot, double now_s);

  /// The recent obstacle points (map frame xy; ExplorerSettings::recent_obstacles_s), used from
  /// the next update_map() on until replaced. Non-finite points are skipped; points outside the
  /// map's grid are ignored. The runtime calls it before every update_map().
  void set_recent_obstacles(std::span<const Eigen::Vector2f> points);
  [[nodiscard]] const std::vector<Eigen::Vector2f>& recent_obstacles() const noexcept { return recent_; }

  /// The map frame moved (a loop closure): what the explorer keeps in it - the goal, its path,
  /// the body's trail, the contacts, the recent obstacles, the view target - is moved by D
  /// (new = D * old). The trail's and contacts' older parts were mapped with other corrections
  /// and are moved by the same D (an approximation: they only free unknown cells under the
  /// body and block cells the bumper hit). Call before the next update_map().
  void shift_frame(const Pose2& D);

  /// One control period (20 Hz): takes a decision if needed, then the dynamic window's command.
  /// `current` is the chassis' twist (odometry). Returns a zero twist when idle or done.
  Twist control(const Pose2& robot, const Twist& current, double now_s);

  [[nodiscard]] ExplorerState state() const noexcept { return state_; }
  /// Why exploration stopped (kDone): the last decision's status.
  [[nodiscard]] ExplorationStatus stop_status() const noexcept { return stop_status_; }
  [[nodiscard]] const ExplorerStats& stats() const noexcept { return stats_; }
  [[nodiscard]] const std::optional<Pose2>& goal() const noexcept { return goal_; }
  [[nodiscard]] const std::vector<Eigen::Vector2f>& path() const noexcept { return path_; }
  [[nodiscard]] const InflatedGrid& inflated() const noexcept { return inflated_; }
  /// The grid paths are planned on: inflated(), or while a relaxed goal is active the same map
  /// inflated with the relaxed radius (and, when boxed in, observed-but-uncertain cells not
  /// blocking; see ExplorerSettings::squeeze_margin_m, ExplorerStats::relaxed_goals).
  [[nodiscard]] const InflatedGrid& planning_grid() const noexcept { return relaxed_active_ ? relaxed_ : inflated_; }
  /// Contact obstacles placed at stalls (world xy), in every planning and driving grid.
  [[nodiscard]] const std::vector<Eigen::Vector2f>& contacts() const noexcept { return contacts_; }
  /// The dynamic window's grid: unknown cells are obstacles, the trail is free.
  [[nodiscard]] const InflatedGrid& local_grid() const noexcept { return local_; }
  [[nodiscard]] const ExplorationDecision& last_decision() const noexcept { return decision_; }
  /// Every decision so far.
  [[nodiscard]] const std::vector<DecisionRecord>& decisions() const noexcept { return log_; }
  /// Frontier cells (kept clusters) found by the last decision that ran the frontier search
  /// (world xy, for pictures).
  [[nodiscard]] const std::vector<Eigen::Vector2f>& frontier_points() const noexcept { return frontier_xy_; }

 private:
  void decide(const Pose2& robot, double now_s);
  Twist control_step(const Pose2& robot, const Twist& current, double now_s);
  /// Sets the cells within contact_radius_m of every contact to occupied.
  void mark_contacts(OccupancyGrid& g) const;
  void mark_recent(OccupancyGrid& g);  // counts the cells it marks (stats)
  bool plan(const Pose2& robot);
  void abandon(int& counter, double now_s);
  /// Forgets the current goal, its path and its modes (relaxed, view) and resets the dynamic window.
  void drop_goal();
  /// Turn towards the largest clearance of `g` 2 cells away, then creep at 0.1 m/s; nullopt when
  /// no such cell has more clearance than the robot's, or (not cornered) the robot is outside
  /// the dynamic window's margin.
  [[nodiscard]] std::optional<Twist> escape(const Pose2& robot, const Twist& current, const InflatedGrid& g, bool cornered) const;
  /// The dynamic window's radius + safety margin [m] (of dwa_settings()).
  [[nodiscard]] float dwa_clearance() const;
  /// The dynamic window's top speed at `robot` (ExplorerSettings::slow_clearance_m): `ds`'s max_v_mps
  /// in open space, down to slow_speed_mps at the window's margin.
  [[nodiscard]] float speed_limit(const Pose2& robot, const DwaSettings& ds) const;
  /// The profile's dynamic window settings, with the relaxed radius while a relaxed goal is active.
  [[nodiscard]] DwaSettings dwa_settings() const;
  /// min(profile's inflation radius, chassis radius + squeeze_margin_m) [m].
  [[nodiscard]] float relaxed_radius() const;
  /// Cell (x, y) is traversable globally and clear of unknown cells by dwa_clearance() on the
  /// dynamic window's grid (false outside either grid).
  [[nodiscard]] bool can_stand_on(int x, int y) const;
  /// The nearest cell to `target` (within goal_standoff_search_m) the dynamic window can stand
  /// on: traversable globally, and clear of unknown cells by the window's radius on its grid.
  [[nodiscard]] std::optional<Eigen::Vector2f> standoff(const Eigen::Vector2f& target) const;
  /// Moves goal_ to standoff(goal_target_) if it is no longer such a cell; false if none.
  bool recheck_goal();
  /// The map inflated with the relaxed radius (and uncertain cells not blocking if
  /// relaxed_boxed_in_), into relaxed_.
  void build_relaxed();
  /// After a decision whose frontier search found no goal (all unreachable or blacklisted or too
  /// near, robot blocked): the search again on the relaxed grid (squeeze_anywhere,
  /// boxed_in_area_m2); true (and decision_ set to its frontier goal, relaxed_active_) if it
  /// found one.
  bool try_relaxed(const Pose2& robot, double now_s);
  /// A view goal (see ExplorerSettings::view_range_m) from the latest map, or none; sets
  /// view_target_ to the frontier cell it looks at.
  [[nodiscard]] std::optional<Pose2> find_view(const Pose2& robot, double now_s);

  Profile profile_;
  ExplorerSettings settings_;
  std::vector<SensorSector> sectors_;
  ObservationModel model_;
  InflatedGrid inflated_;
  InflatedGrid relaxed_;        ///< see planning_grid(); built only when needed
  bool relaxed_active_ = false; ///< the current goal was found on relaxed_
  bool relaxed_boxed_in_ = false; ///< relaxed_ lets uncertain cells through (boxed in)
  InflatedGrid local_;
  OccupancyGrid local_grid_{0.05f};
  std::vector<Eigen::Vector2f> trail_;  ///< robot positions, 0.05 m apart
  std::vector<Eigen::Vector2f> contacts_;  ///< see contacts()
  std::vector<Eigen::Vector2f> recent_;    ///< see recent_obstacles()
  std::vector<std::size_t> recent_cells_;  ///< scratch of mark_recent()
  OccupancyGrid contact_grid_{0.05f};      ///< the latest map with the contacts marked (when there are any)
  bool marked_ = false;
  float cornered_s_ = 0.0f;                ///< how long the window has kept the robot near cornered_at_ (cornered_after_s)
  Eigen::Vector2f cornered_at_{std::numeric_limits<float>::infinity(), 0.0f};                    ///< contact_grid_ is the grid of the latest update_map()
  Twist last_cmd_;                         ///< the last command control() returned
  double stall_since_s_ = -1.0;
  GoalBlacklist blacklist_;
  GoalBlacklist viewed_;             ///< frontier cells looked at from a view goal (never again)
  bool view_active_ = false;         ///< the current goal is a view goal
  Eigen::Vector2f view_target_{0.0f, 0.0f};  ///< the frontier cell the current view goal looks at
  FrontierWorkspace view_ws_;        ///< the view search's frontier search
  ExplorationWorkspace ws_;
  PathWorkspace path_ws_;
  DwaState dwa_state_;
  DwaWorkspace dwa_ws_;
  ExplorationDecision decision_;
  ExplorerState state_ = ExplorerState::kIdle;
  ExplorationStatus stop_status_ = ExplorationStatus::kNoFrontier;
  ExplorerStats stats_;
  bool have_map_ = false;
  bool model_geometry_valid_ = false;
  std::optional<Pose2> goal_;
  Eigen::Vector2f goal_target_{0.0f, 0.0f};  ///< the decision's goal before standoff() (blacklisting)
  std::vector<Eigen::Vector2f> path_;
  double goal_deadline_s_ = 0.0;
  double stuck_since_s_ = -1.0;
  int no_goal_decisions_ = 0;  ///< consecutive decisions without a goal
  bool wait_for_map_ = false;   ///< the last decision found nothing: wait for the next map
  std::uint64_t decision_seed_ = 0;
  std::vector<DecisionRecord> log_;
  std::vector<Eigen::Vector2f> frontier_xy_;
};

}  // namespace duet
