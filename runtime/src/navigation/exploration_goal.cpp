/// @file exploration_goal.cpp
/// The kernel's decision as the first goal strategy (see exploration_goal.hpp).
#include <duet/runtime/navigation/exploration_goal.hpp>

#include <chrono>
#include <limits>

namespace duet {

ExplorationGoal::ExplorationGoal(const Profile& profile, const ExplorerSettings& settings)
    : GoalStrategy(settings),
      strategy_(profile.exploration.strategy),
      stop_when_no_frontier_(settings.stop_when_no_frontier) {}

std::optional<GoalProposal> ExplorationGoal::propose(GoalQuery& q) {
  ExplorationSettings s = strategy_;
  // A distinct random stream per decision, derived from the profile's seed (Procedure 1).
  s.simulation.seed = strategy_.simulation.seed * 0x9E3779B97F4A7C15ull + decision_seed_++;
  const auto t0 = std::chrono::steady_clock::now();
  ExplorationDecision& d = q.decision;
  d = decide_goal(q.model, q.planning, q.robot, q.sectors, q.blacklist, q.now_s, s, ws_);
  if (stop_when_no_frontier_ && d.status == ExplorationStatus::kSimulatedGoal) {
    // The search ran concurrently with the simulation (concurrent_frontier_search); else run it.
    if (!d.frontier_searched) {
      d.frontier = find_frontier(q.planning, Eigen::Vector2f(q.robot.x, q.robot.y), q.blacklist, q.now_s, s.frontier, ws_.frontier);
      d.frontier_searched = true;
    }
    if (d.frontier.status == FrontierStatus::kNoFrontier) d.status = ExplorationStatus::kNoFrontier;
    else if (d.frontier.status == FrontierStatus::kAllUnreachable) d.status = ExplorationStatus::kAllUnreachable;
    else if (d.frontier.status == FrontierStatus::kAllBlacklisted) d.status = ExplorationStatus::kAllBlacklisted;
  }
  const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ++q.stats.decisions;
  q.stats.decision_time_sum_s += dt;
  q.stats.decision_time_max_s = std::max(q.stats.decision_time_max_s, dt);

  DecisionRecord rec;
  rec.t_s = q.now_s;
  rec.status = d.status;
  rec.reward_bits = d.reward_bits;
  rec.unknown_reward_bits = d.simulation.unknown_reward_bits;
  rec.robot = q.robot;
  rec.goal = d.goal;
  rec.wall_time_s = dt;
  rec.frontier_cells = d.frontier.frontier_cells;
  rec.reached_cells = d.frontier.reached_cells;
  float best = std::numeric_limits<float>::infinity();
  for (const auto& c : d.frontier.clusters)
    if (c.reachable) {
      ++rec.reachable_clusters;
      if (c.path_length_m < best) {
        best = c.path_length_m;
        rec.nearest_frontier = c.nearest_xy;
      }
    }
  q.log.push_back(rec);
  if (!d.frontier.clusters.empty() || d.frontier.status != FrontierStatus::kNoFrontier) {
    q.frontier_points.clear();
    const FrontierWorkspace& fw = ws_.frontier;
    for (const std::uint32_t i : fw.frontier)
      if (i < q.planning.cell_count() && i < fw.mask.size() && fw.mask[i]) q.frontier_points.push_back(q.planning.cell_center(static_cast<std::size_t>(i)));
  }
  if (d.status == ExplorationStatus::kAllBlacklisted) {
    // Goals abandoned for a while (time limit, no path, an obstacle where the frontier was)
    // must not end the exploration: forget them and decide again. Only frontiers the robot
    // stood at and looked at (blacklisted for good) may end it.
    GoalBlacklist keep;
    for (const auto& e : q.blacklist.entries())
      if (std::isinf(e.expiry_s)) keep.add(e.xy, q.now_s, std::numeric_limits<double>::infinity());
    if (keep.size() < q.blacklist.size()) {
      q.blacklist = keep;
      q.retry = true;
      return std::nullopt;
    }
  }
  if (!d.has_goal()) return std::nullopt;
  return GoalProposal{d.goal, d.status == ExplorationStatus::kSimulatedGoal ? GoalKind::kSimulated : GoalKind::kFrontier};
}

}  // namespace duet
