/// @file goal_strategy.cpp
/// The strategies' default goal end and the default list (see goal_strategy.hpp).
#include <duet/runtime/navigation/exploration_goal.hpp>
#include <duet/runtime/navigation/goal_strategy.hpp>
#include <duet/runtime/navigation/relaxed_goal.hpp>
#include <duet/runtime/navigation/view_goal.hpp>

#include <limits>

namespace duet {

void GoalStrategy::goal_ended(const GoalEnd& end) {
  constexpr double kForever = std::numeric_limits<double>::infinity();
  if (!end.reached) {
    const bool for_good = max_goal_failures_ > 0 && end.failures >= max_goal_failures_;
    end.blacklist.add(end.target, end.now_s, for_good ? kForever : static_cast<double>(blacklist_ttl_s_));
    return;
  }
  // A frontier that is still a frontier after the robot stood at it and looked at it cannot be
  // observed from there (the inside of an obstacle behind a gap in its outline): never again.
  // For a goal on an approach cell the frontier cell it was for is the one looked at.
  if (end.decision.status != ExplorationStatus::kFrontierGoal) return;
  end.blacklist.add(end.target, end.now_s, kForever);
  if (end.decision.frontier.target_xy != end.target) end.blacklist.add(end.decision.frontier.target_xy, end.now_s, kForever);
}

std::vector<std::unique_ptr<GoalStrategy>> make_goal_strategies(const Profile& profile, const ExplorerSettings& settings) {
  std::vector<std::unique_ptr<GoalStrategy>> list;
  list.push_back(std::make_unique<ExplorationGoal>(profile, settings));
  list.push_back(std::make_unique<RelaxedFrontierGoal>(profile, settings));
  list.push_back(std::make_unique<ViewGoal>(profile, settings));
  return list;
}

}  // namespace duet
