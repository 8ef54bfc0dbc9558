#pragma once
/// @file exploration_goal.hpp
/// The kernel's decision (exploration.hpp, decide_goal()): Procedure 1's simulated goal and,
/// below eps_R, the frontier search - as ExplorationSettings selects (the paper's strategy, the
/// nearest frontier, explore_lite's cost). With stop_when_no_frontier a simulated goal is not
/// taken once the frontier search finds no frontier left (the map is complete). Every call is
/// one decision: a fresh random stream for Procedure 1, a record in the run's log.
#include <duet/runtime/navigation/goal_strategy.hpp>

namespace duet {

class ExplorationGoal final : public GoalStrategy {
 public:
  ExplorationGoal(const Profile& profile, const ExplorerSettings& settings);
  [[nodiscard]] std::string_view name() const override { return "exploration"; }
  std::optional<GoalProposal> propose(GoalQuery& q) override;

 private:
  ExplorationSettings strategy_;
  bool stop_when_no_frontier_;
  ExplorationWorkspace ws_;
  std::uint64_t decision_seed_ = 0;
};

}  // namespace duet
