/// @file relaxed_goal.cpp
/// The frontier search on a relaxed grid (see relaxed_goal.hpp).
#include <duet/runtime/navigation/relaxed_goal.hpp>

#include <algorithm>

namespace duet {

RelaxedFrontierGoal::RelaxedFrontierGoal(const Profile& profile, const ExplorerSettings& settings)
    : GoalStrategy(settings),
      inflation_(profile.exploration.inflation),
      frontier_(profile.exploration.strategy.frontier),
      settings_(settings),
      radius_m_(std::min(profile.exploration.inflation.robot_radius_m, profile.chassis.radius_m + settings.squeeze_margin_m)) {}

void RelaxedFrontierGoal::build(const GridView& latest) {
  InflationSettings relaxed = inflation_;
  if (boxed_in_) relaxed.uncertain_is_obstacle = false;
  relaxed.robot_radius_m = radius_m_;
  inflate(latest, relaxed, relaxed_);
}

void RelaxedFrontierGoal::map_updated(const GridView& latest, bool active) {
  if (active) build(latest);
}

std::optional<GoalProposal> RelaxedFrontierGoal::propose(GoalQuery& q) {
  ExplorationDecision& d = q.decision;
  if (!d.frontier_searched) return std::nullopt;
  if (d.status != ExplorationStatus::kAllUnreachable && d.status != ExplorationStatus::kRobotBlocked &&
      d.status != ExplorationStatus::kAllBlacklisted)
    return std::nullopt;
  // Boxed in: the search reached a small area from the robot (none if it is blocked).
  const double cell_m2 = static_cast<double>(q.planning.resolution_m) * static_cast<double>(q.planning.resolution_m);
  const bool boxed_in = static_cast<double>(d.frontier.reached_cells) * cell_m2 < static_cast<double>(settings_.boxed_in_area_m2);
  FrontierResult f;
  bool found = false;
  // First the squeezed radius alone, then (boxed in) with uncertain cells not blocking as well.
  for (const bool level_boxed : {false, true}) {
    if (level_boxed ? !boxed_in : !(settings_.squeeze_anywhere || boxed_in)) continue;
    if (!level_boxed && !(radius_m_ < inflation_.robot_radius_m)) continue;  // the planning grid itself
    boxed_in_ = level_boxed;
    build(q.latest);
    // From a large area only frontiers of large unknown regions (a room behind a door), not
    // the pockets between furniture and clutter the robot would squeeze into.
    FrontierSettings fs = frontier_;
    if (!boxed_in) fs.min_unknown_region_m2 = std::max(fs.min_unknown_region_m2, settings_.squeeze_min_unknown_m2);
    f = find_frontier(relaxed_, Eigen::Vector2f(q.robot.x, q.robot.y), q.blacklist, q.now_s, fs, ws_);
    if (f.status == FrontierStatus::kFound) {
      found = true;
      break;
    }
  }
  if (!found) return std::nullopt;
  d.status = ExplorationStatus::kFrontierGoal;
  d.goal = frontier_goal_pose(f, q.robot);
  d.frontier = std::move(f);
  d.frontier_searched = true;
  ++q.stats.relaxed_goals;
  q.stats.boxed_in_goals += boxed_in_;
  if (!q.log.empty()) {
    q.log.back().status = d.status;
    q.log.back().relaxed = true;
  }
  return GoalProposal{d.goal, GoalKind::kRelaxedFrontier};
}

}  // namespace duet
