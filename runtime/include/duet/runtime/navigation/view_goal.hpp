#pragma once
/// @file view_goal.hpp
/// A view goal: when every frontier left is unreachable (or blacklisted), a cell the robot can
/// stand on and reach from which a frontier cell it cannot reach is seen - along a line of
/// sight through known-free cells, between view_min_range_m and view_range_m - the nearest by
/// path. The goal faces the frontier cell. A frontier cell whose view goal was reached or
/// abandoned is not looked for again.
#include <duet/runtime/navigation/goal_strategy.hpp>

namespace duet {

class ViewGoal final : public GoalStrategy {
 public:
  ViewGoal(const Profile& profile, const ExplorerSettings& settings);
  [[nodiscard]] std::string_view name() const override { return "view"; }
  std::optional<GoalProposal> propose(GoalQuery& q) override;
  void goal_ended(const GoalEnd& end) override;
  void shift(const Pose2& D) override;

 private:
  FrontierSettings frontier_;
  ExplorerSettings settings_;
  GoalBlacklist viewed_;  ///< frontier cells whose view goal ended
  Eigen::Vector2f target_{0.0f, 0.0f};
  FrontierWorkspace ws_;
};

}  // namespace duet
