#pragma once
/// @file goal_strategy.hpp
/// Goal selection as an ordered list of strategies (paper Fig. 6 and the fallbacks a real
/// building needs). At each decision the Navigator asks its strategies in order; the first that
/// proposes a goal wins, and its goal is the one the navigator moves to a cell the robot can
/// stand on and plans a path to. The default list (make_goal_strategies()):
///   1. ExplorationGoal   - the kernel's decision: Procedure 1's simulated goal, below eps_R the
///                          frontier search (nearest frontier or explore_lite's cost);
///   2. RelaxedFrontierGoal - the frontier search on a grid inflated by a smaller radius, when
///                          every frontier is unreachable on the planning grid (a narrow door);
///   3. ViewGoal          - a cell from which an unreachable frontier cell is seen.
///
/// Life cycle of a strategy (all calls on the navigator's thread):
///   propose()       - once per decision attempt, in list order, until one proposes;
///   map_updated()   - at every map update (a strategy with grids of its own rebuilds them);
///   goal_ended()    - its goal was reached or abandoned;
///   shift()         - the map frame moved (loop closure);
/// and, while its goal is the navigator's, planning_grid() / robot_radius_m() may replace the
/// navigator's planning grid and the dynamic window's radius.
#include <duet/kernels/exploration.hpp>
#include <duet/kernels/frontier.hpp>
#include <duet/kernels/grid.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/kernels/observation.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/navigation/explorer_settings.hpp>

#include <functional>
#include <string>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

namespace duet {

/// What a goal came from (the navigator's statistics count them apart).
enum class GoalKind { kSimulated, kFrontier, kRelaxedFrontier, kView };

/// One decision attempt as the strategies see it. `decision` is shared: the first strategy
/// fills it, later ones read its status (why it found nothing) and may replace it.
struct GoalQuery {
  Pose2 robot;
  double now_s = 0.0;
  const ObservationModel& model;     ///< the latest map's observation model
  GridView latest;                   ///< the latest map with the contact obstacles
  const InflatedGrid& planning;      ///< the latest map, inflated by the robot's radius
  std::span<const SensorSector> sectors;
  GoalBlacklist& blacklist;          ///< frontier goals not to take (reached, or abandoned for a while)
  ExplorationDecision& decision;
  std::vector<DecisionRecord>& log;  ///< the run's decisions (a strategy that decides appends its record)
  std::vector<Eigen::Vector2f>& frontier_points;  ///< the frontier cells of the last search (map frame, for plots)
  ExplorerStats& stats;
  std::function<bool(int, int)> can_stand_on;  ///< the dynamic window fits on cell (x, y) of the planning grid
  bool retry = false;                ///< set by a strategy that changed what decisions depend on: decide again
  /// Set by a strategy that has no goal now but will have one at a later decision (a place to
  /// look at again once enough time has passed): the navigator waits for it instead of counting
  /// the decision towards ExplorerSettings::final_retries.
  bool later = false;
};

struct GoalProposal {
  Pose2 goal;
  GoalKind kind = GoalKind::kFrontier;
  Eigen::Vector2f target{0.0f, 0.0f};  ///< the frontier cell a view goal looks at
};

/// How a goal ended, for the strategy that proposed it.
struct GoalEnd {
  bool reached = false;              ///< false: abandoned (time limit, no path, stuck, blocked)
  double now_s = 0.0;
  Eigen::Vector2f target{0.0f, 0.0f};  ///< where the goal was meant to be (before any standoff)
  const ExplorationDecision& decision;  ///< the decision the goal came from
  GoalBlacklist& blacklist;
  ExplorerStats& stats;
  /// Abandoned: the goals abandoned at this place so far, this one included (Navigator counts
  /// them per place, within the blacklist radius); 0 when reached.
  int failures = 0;
};

class GoalStrategy {
 public:
  virtual ~GoalStrategy() = default;
  [[nodiscard]] virtual std::string_view name() const = 0;
  /// A goal, or nothing (the next strategy is asked).
  virtual std::optional<GoalProposal> propose(GoalQuery& query) = 0;
  /// The map was updated; `active`: this strategy's goal is the navigator's.
  virtual void map_updated(const GridView& latest, bool active) {
    (void)latest;
    (void)active;
  }
  /// Its goal ended. The default: a goal reached at a frontier is blacklisted for good (it was
  /// looked at from there), one abandoned for blacklist_ttl_s - for good once its place was
  /// abandoned max_goal_failures times (ExplorerSettings).
  virtual void goal_ended(const GoalEnd& end);
  /// The map frame moved by D (loop closure).
  virtual void shift(const Pose2& D) { (void)D; }
  /// Frontier cells this strategy looked at and will not look for again (map frame), for the
  /// report of what was left (unexplored.hpp).
  [[nodiscard]] virtual std::vector<Eigen::Vector2f> looked_at() const { return {}; }
  /// Why this strategy has stopped proposing goals, for the stop reason ("" = it has not).
  [[nodiscard]] virtual std::string stop_note() const { return {}; }
  /// While its goal is active: the grid to plan on instead of the navigator's (nullptr: that one).
  [[nodiscard]] virtual const InflatedGrid* planning_grid() const { return nullptr; }
  /// While its goal is active: the dynamic window's robot radius, if it differs [m].
  [[nodiscard]] virtual std::optional<float> robot_radius_m() const { return std::nullopt; }

 protected:
  /// The default goal_ended()'s blacklisting: ExplorerSettings::blacklist_ttl_s and
  /// max_goal_failures.
  explicit GoalStrategy(const ExplorerSettings& settings)
      : blacklist_ttl_s_(settings.blacklist_ttl_s), max_goal_failures_(settings.max_goal_failures) {}
  float blacklist_ttl_s_;
  int max_goal_failures_;
};

/// The default ordered list for a profile (see the file comment).
[[nodiscard]] std::vector<std::unique_ptr<GoalStrategy>> make_goal_strategies(const Profile& profile,
                                                                            const ExplorerSettings& settings);

}  // namespace duet
