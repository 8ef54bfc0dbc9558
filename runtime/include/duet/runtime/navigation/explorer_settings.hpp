#pragma once
/// @file explorer_settings.hpp
/// Settings, state and counters of the explorer (navigation room): the goal life cycle
/// (Navigator, navigator.hpp) and the controller that follows its goals (Controller,
/// controller.hpp). Measurement history of these values lives in bench/RESULTS.md.
#include <duet/kernels/exploration.hpp>
#include <duet/kernels/motion_model.hpp>

#include <Eigen/Core>

#include <cstddef>

namespace duet {

/// What the robot does once nothing reachable is left to explore (the paper: remain in place).
///  - kStay: stop where it is;
///  - kReturnHome: drive back to where it started and stop there;
///  - kPatrol: drive a round of waypoints along its own trail (patrol_spacing_m apart), lap
///    after lap, until stopped (a guard robot; and the long-run test of issue 19).
enum class OnDone { kStay, kReturnHome, kPatrol };
[[nodiscard]] const char* to_string(OnDone d);

struct ExplorerSettings {
  // ---- goal life cycle (Navigator)
  float goal_timeout_s = 20.0f;       ///< fixed part of a goal's time limit [s], (0, inf)
  float nominal_speed_mps = 0.3f;     ///< path length / this is added to the time limit [m/s], (0, inf)
  float blacklist_ttl_s = 60.0f;      ///< how long an abandoned goal stays blacklisted [s], (0, inf]
  /// A place (within the frontier search's blacklist_radius_m of the first goal abandoned there)
  /// whose goals were abandoned this many times is blacklisted for good, [0, 1000]; 0 = never.
  /// When every frontier is blacklisted the ones abandoned for a while are forgotten and tried
  /// again (a goal timed out behind a person is not a reason to stop), so without it a goal the
  /// robot cannot reach but the planner can is tried again and again (Willow seed 1, stop 48:
  /// 15 tries of one goal 2.3 m away, 450 s without moving on). The summary lists such a place
  /// as "abandoned after N failed goals" (unexplored.hpp).
  int max_goal_failures = 3;
  int final_retries = 3;              ///< decisions at later map updates before giving up, [0, 1000]
  /// Blocked: the decision finds no traversable cell within the robot's radius (it stands in an
  /// obstacle's inflation: a narrow niche, or a pose estimate moved next to a wall). For up to
  /// this long the controller creeps along the way out to a traversable cell (blocked_escape.hpp)
  /// and the navigator decides again at each map, before final_retries count and the run gives
  /// up "blocked" [s], [0, 3600];
  /// 0 = give up at once (issue 23: belgioioso, one sensor, gave up at 1598 s with 94 %).
  float blocked_recovery_s = 30.0f;
  /// Once explored: stay where the robot is, or drive back to where it started (the first
  /// position of its trail) and stop there.
  OnDone on_done = OnDone::kStay;
  /// Patrol waypoints: trail positions at least this far from each other [m], [0.5, 100].
  float patrol_spacing_m = 3.0f;
  /// Exploration is complete when no reachable frontier is left, even if the partial map
  /// simulation still offers a goal: its reward (Eq. 5) never reaches zero, because known cells
  /// below the log-odds clamp keep gaining from re-observation, so R_g <= eps_R alone never
  /// ends a run. Costs one frontier search per simulated goal. false: the paper's rule only.
  bool stop_when_no_frontier = true;
  /// How far a goal may be moved off cells next to unknown space to a cell the dynamic window
  /// can stand on [m], [0, 5]; 0 = never (such a goal is abandoned).
  float goal_standoff_search_m = 0.75f;
  /// Relaxed grid: when the frontier search reaches no goal, it runs again with the robot's
  /// radius shrunk to the chassis' radius + this margin [m], [0, 1] (a door whose jambs, once
  /// fully seen, close under the inflation).
  float squeeze_margin_m = 0.06f;
  /// Shrink the radius whenever the search reaches no goal (true), or only when boxed in (false).
  bool squeeze_anywhere = false;
  /// With squeeze_anywhere, only towards unknown regions at least this large [m^2], [0, inf).
  float squeeze_min_unknown_m2 = 4.0f;
  /// Boxed in: the search reached less than this traversable area from the robot [m^2],
  /// [0, inf); 0 = never. Then observed-but-uncertain cells stop blocking too (a door that
  /// grazing rays left uncertain).
  float boxed_in_area_m2 = 10.0f;
  /// View goals: when no frontier can be gone to, look at the unreachable frontier cells from a
  /// cell the robot can stand on, on a straight line of known-free cells, view_min_range_m to
  /// view_range_m from the frontier cell (the nearest by path; each frontier cell looked at
  /// once). [m], [0, 10]; 0 = no view goals.
  float view_range_m = 4.0f;
  /// Nearest view cell to its frontier cell [m], [0, view_range_m] ([0, 10] with no view goals):
  /// beyond the sensors' minimum range plus the sensor's offset behind the robot's centre.
  float view_min_range_m = 0.8f;
  int view_rays = 72;  ///< directions cast from each frontier cell (evenly over 360 deg), [4, 3600]
  /// Which place is looked at first: the least path length to its view cell minus this many
  /// metres per metre of the frontier the place belongs to (its cluster's cells x resolution)
  /// [m/m], [0, 1000]; 0 = the nearest by path. A long frontier behind a gap is a large unseen
  /// region; a cell of ragged wall is a pocket (Willow seed 1, stop 46: 17 m of frontier behind a
  /// 0.45 m gap waited 2200 s while the robot looked at the nearer pockets first).
  float view_frontier_weight = 3.0f;
  /// Looks at one place before it is given up for good, [1, 100]. After the first, a place is
  /// looked at again only when nothing else is left (no frontier to go to, no place not yet
  /// looked at) and view_relook_after_s [s], [0, 1e5] after the last look: a door closed then
  /// may be open now (issue 23). 1 = each place once (the run ends sooner).
  int view_looks = 2;
  float view_relook_after_s = 30.0f;
  /// After a look again the robot stays where it looked from while the map around what it looks
  /// at keeps changing (more free cells within 2 m at a map update than at the one before; at
  /// least 3 s), at most this long [s], [0, 600], unless a goal turns up: a door seen shut many
  /// times needs about ten looks through it before the map holds it free (mapping.grid_update:
  /// from max_logodds 3.5 to below the free threshold at -0.4 a miss). A place that does not
  /// change costs 3 s.
  float view_relook_dwell_s = 30.0f;
  /// The view goals' budget (view_budget.hpp): while every frontier left is unreachable (the
  /// robot only looks at them from view goals), the looking ends when the map's known area grew
  /// by less than view_min_gain_m2 over the last view_gain_window_s; the explorer then stops, and
  /// its stop reason says so: each view at a far gap shows a few cells and leaves new ragged
  /// frontier cells, so without it looking can go on for an hour adding little.
  /// [m^2], [0, 1e6]; 0 = off (look until no place is left to look at).
  float view_min_gain_m2 = 0.0f;
  float view_gain_window_s = 600.0f;  ///< [s], (0, 1e5]
  /// true: a frontier goal's heading points whichever sensor needs the least turn from the
  /// heading the robot arrives with (heading_to_look(), observation.hpp): with the paper's front
  /// and right sensors, a frontier on the robot's right is looked at without turning to it.
  /// false: the front sensor faces it (as with one sensor). Off: on the lab (seeds 1-5, 900 s)
  /// it changed nothing on four seeds and made seed 4 finish 149 s later (T_90 +6 s); it was
  /// worse still for view goals (a side sensor sits 0.12 m off their line of sight through a
  /// gap), which it never turns.
  bool look_with_any_sensor = false;
  /// Procedure 1's goal X_g counts as reached once the robot is within this distance of it [m],
  /// [0, 5]: the next decision is taken on the move, without stopping and turning to X_g's
  /// heading (the paper re-plans when a goal is reached; the simulation's later stages are its
  /// least certain). 0 = drive to X_g, stop, and face its heading. Frontier, view, home and
  /// patrol goals are always driven to and faced.
  float simulated_goal_handoff_m = 0.0f;
  /// A frontier goal ends as soon as the map shows no frontier cell within frontier_seen_radius_m
  /// of the frontier cell it was for: a sensor saw past that frontier on the way (the side sensor
  /// sweeps frontiers the robot drives by), so driving on to it and turning there would show
  /// nothing new, and the robot decides again at once (explore_lite re-plans the same way when
  /// its goal's frontier disappears). [m], [0, 5]; 0 = off: drive to every frontier goal and
  /// look from there. The struct's default is off; the two Kobuki profiles set 0.3 m, because a
  /// frontier goal gains far less per second than a simulated goal and most of its drive is
  /// spent after its frontier was already seen (figures: bench/RESULTS.md, stop 55).
  float frontier_seen_radius_m = 0.0f;
  /// The cells wholly under the robot's body at its estimated pose are not obstacles in the
  /// costmaps (footprint_layer.hpp; the map keeps them): a pose a few centimetres off must not
  /// pin the robot to an obstacle its map puts under it (belgioioso seed 2 with near obstacles
  /// kept: 2700 s beside a post, issue 23).
  bool clear_footprint = true;
  /// Recent obstacles (a local costmap's obstacle layer): cells an obstacle point of the last
  /// recent_obstacles_s seconds fell in block the dynamic window's grid, whatever the map's
  /// log-odds say (where the pose moved since a place was mapped, the map needs several hits to
  /// block a cell it saw free many times). [s], [0, 3600]; 0 = off.
  float recent_obstacles_s = 0.0f;
  /// ... only points within this distance of the robot when seen [m], (0, 10].
  float recent_obstacle_range_m = 3.0f;
  /// ... only cells seen as an obstacle in at least this many of the window's scans, [1, 1000].
  int recent_obstacle_min_scans = 2;

  // ---- controller behaviours (Controller)
  float stuck_timeout_s = 4.0f;       ///< no admissible trajectory for this long abandons the goal [s], (0, inf)
  /// Stall: commanded forward (>= 0.03 m/s) while the odometry measures no motion (< 0.01 m/s)
  /// for this long [s], (0, inf): the robot touches something its sensors cannot see (nearer
  /// than their minimum range). A contact obstacle goes just ahead of it in every grid the
  /// explorer plans and drives on, and the goal is abandoned.
  float stall_timeout_s = 1.0f;
  float contact_radius_m = 0.10f;     ///< radius of a contact obstacle [m], (0, 1]
  /// Cornered: the dynamic window kept the robot within 0.1 m of one spot this long [s],
  /// [0, inf); 0 = off. It then creeps towards more clearance until out of that spot. At the
  /// edge of the band its radius fits in (a door jamb, a bump of the band), spinning, every
  /// forward motion the window can reach from the spin leaves the band: without this the robot
  /// turns on until the goal's time limit (a full turn at the mapping limit takes 8 s).
  float cornered_after_s = 8.0f;
  /// Slow zone (nav2's speed filter): the top speed falls with the clearance on the planning
  /// grid, linearly from the profile's max_v_mps at slow_clearance_m to slow_speed_mps at the
  /// window's margin, so the sensors' new hits reach the map before the robot does.
  /// [m], [0, 10]; 0 = off.
  float slow_clearance_m = 0.8f;
  float slow_speed_mps = 0.25f;       ///< the top speed at the margin [m/s], (0, inf)
  /// Feature seeking (feature_seek.hpp; only with localization.visual_odometry on): where vision
  /// sees too few features (health degraded or lost) the top speed is capped at
  /// few_features_speed_mps [m/s], [0, 100] (0 = no cap) ...
  float few_features_speed_mps = 0.15f;
  /// ... and after seek_after_s [s], [0, 3600] (0 = never) of it the robot turns in place towards
  /// surfaces the planning grid shows between seek_min_range_m [m], [0, seek_range_m] and
  /// seek_range_m [m], [0.1, 20] (at least seek_min_turn_rad [rad], [0, pi] away from its
  /// heading), at most once per seek_cooldown_s [s], [0, 3600].
  float seek_after_s = 1.0f;
  float seek_cooldown_s = 15.0f;
  float seek_min_turn_rad = 0.5f;
  float seek_min_range_m = 0.6f;
  float seek_range_m = 3.5f;
};
void validate(const ExplorerSettings& s);

enum class ExplorerState {
  kIdle,           ///< no map yet
  kExploring,      ///< following a goal
  kReturningHome,  ///< explored; driving back to the start (OnDone::kReturnHome)
  kPatrolling,     ///< explored; driving the patrol round (OnDone::kPatrol)
  kDone,           ///< stopped; see stop_status() and stop_detail()
};
[[nodiscard]] const char* to_string(ExplorerState s);

/// Counters and timings of one run (decision time is the wall time of a decision).
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
  int cornered_escapes = 0;         ///< control periods spent escaping a spot (cornered_after_s)
  int blocked_recoveries = 0;       ///< times the robot was found blocked and climbed out (blocked_recovery_s)
  int blocked_escapes = 0;          ///< control periods spent climbing out while blocked
  int slowed = 0;                   ///< control periods the slow zone lowered the top speed
  int few_feature_periods = 0;      ///< control periods the top speed was capped for vision (feature_seek.hpp)
  int feature_seeks = 0;            ///< turns towards surfaces with features (feature_seek.hpp)
  int goals_moved = 0;              ///< goals moved off cells next to unknown space (decisions and re-checks)
  int relaxed_goals = 0;            ///< frontier goals found on a relaxed grid
  int boxed_in_goals = 0;           ///< of relaxed_goals, those with uncertain cells not blocking
  int stalls = 0;                   ///< stalls detected: contact obstacles placed
  int view_goals = 0;               ///< view goals taken
  int view_goals_reached = 0;       ///< of view_goals, those reached and looked from
  int frontier_goals_seen = 0;      ///< frontier goals ended on the way: their frontier was seen (frontier_seen_radius_m)
  int patrol_waypoints = 0;         ///< waypoints of the patrol round (OnDone::kPatrol)
  int patrol_reached = 0;           ///< patrol waypoints reached
  int patrol_skipped = 0;           ///< patrol waypoints given up (no path, time limit, stuck, blocked)
  int patrol_laps = 0;              ///< patrol rounds completed
  /// Sum over map updates of the cells the recent obstacles made blocking.
  std::size_t recent_obstacle_cells = 0;
  /// Map updates at which an occupied cell lay under the estimated body (clear_footprint).
  int footprint_clearings = 0;
  double decision_time_sum_s = 0.0;
  double decision_time_max_s = 0.0;
};

/// One decision, for the run's log.
struct DecisionRecord {
  double t_s = 0.0;                 ///< runtime clock
  ExplorationStatus status = ExplorationStatus::kNoFrontier;
  float reward_bits = 0.0f;         ///< R_g of the partial map simulation
  float unknown_reward_bits = 0.0f; ///< R_g's part from unknown cells (PartialSimResult)
  Pose2 robot;                      ///< where the robot was
  Pose2 goal;                       ///< the goal (if any)
  bool planned = false;             ///< a path to the goal was found
  std::size_t frontier_cells = 0;   ///< frontier cells in kept clusters (when the search ran)
  int reachable_clusters = 0;       ///< frontier clusters the robot can reach (when the search ran)
  std::size_t reached_cells = 0;    ///< cells the frontier search reached from the robot (when it ran)
  bool relaxed = false;             ///< the goal came from the search on the relaxed grid
  bool view = false;                ///< the goal is a view goal
  Eigen::Vector2f view_target{0.0f, 0.0f};       ///< for a view goal: the frontier cell it looks at
  Eigen::Vector2f nearest_frontier{0.0f, 0.0f};  ///< the nearest reachable cluster's nearest cell
  double wall_time_s = 0.0;         ///< how long the decision took
};

}  // namespace duet
