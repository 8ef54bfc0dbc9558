// Goal selection as an ordered list of strategies (navigation/goal_strategy.hpp): the navigator
// asks its strategies in order and takes the first goal proposed; the strategy that proposed it
// hears how it ended; the default list is the exploration decision, the relaxed frontier search
// and view goals.
#include <duet/kernels/error.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/navigation/exploration_goal.hpp>
#include <duet/runtime/navigation/navigator.hpp>
#include <duet/runtime/navigation/relaxed_goal.hpp>
#include <duet/runtime/navigation/view_goal.hpp>

#include <gtest/gtest.h>

#include "half_known_room.hpp"

#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace {

using duet_test::frontier_only_profile;
using duet_test::half_known_room;

duet::ExplorerSettings ttl_30s() {
  duet::ExplorerSettings s;
  s.blacklist_ttl_s = 30.0f;
  return s;
}

/// A strategy that proposes a fixed goal (or nothing) and records what it is told.
class Scripted final : public duet::GoalStrategy {
 public:
  Scripted(std::optional<duet::Pose2> goal, std::vector<std::string>& calls, std::string name)
      : GoalStrategy(ttl_30s()), goal_(goal), calls_(calls), name_(std::move(name)) {}
  [[nodiscard]] std::string_view name() const override { return name_; }
  std::optional<duet::GoalProposal> propose(duet::GoalQuery& q) override {
    calls_.push_back(name_ + ".propose");
    q.log.push_back(duet::DecisionRecord{});  // the navigator writes the goal into the last record
    if (!goal_) return std::nullopt;
    return duet::GoalProposal{*goal_, duet::GoalKind::kFrontier};
  }
  void goal_ended(const duet::GoalEnd& end) override {
    calls_.push_back(name_ + (end.reached ? ".reached" : ".abandoned"));
    GoalStrategy::goal_ended(end);
  }

 private:
  std::optional<duet::Pose2> goal_;
  std::vector<std::string>& calls_;
  std::string name_;
};

}  // namespace

TEST(GoalStrategy, DefaultListIsExplorationRelaxedView) {
  const duet::Profile p = duet::builtin_profile("dual");
  const auto list = duet::make_goal_strategies(p, p.runtime.explorer);
  ASSERT_EQ(list.size(), 3u);
  EXPECT_EQ(list[0]->name(), "exploration");
  EXPECT_EQ(list[1]->name(), "relaxed_frontier");
  EXPECT_EQ(list[2]->name(), "view");
}

TEST(GoalStrategy, FirstProposalWinsAndItsStrategyHearsTheEnd) {
  const duet::Profile p = frontier_only_profile();
  std::vector<std::string> calls;
  std::vector<std::unique_ptr<duet::GoalStrategy>> list;
  list.push_back(std::make_unique<Scripted>(std::nullopt, calls, "none"));
  list.push_back(std::make_unique<Scripted>(duet::Pose2{2.5f, 1.5f, 0.0f}, calls, "fixed"));
  list.push_back(std::make_unique<Scripted>(duet::Pose2{1.5f, 0.8f, 0.0f}, calls, "never"));
  duet::Navigator nav(p, p.runtime.explorer, std::move(list));
  const duet::Pose2 robot{1.0f, 1.5f, 0.0f};
  nav.update_map(half_known_room(), robot, 0.0);
  nav.decide(robot, 0.0);
  ASSERT_TRUE(nav.goal().has_value());
  EXPECT_FLOAT_EQ(nav.goal()->x, 2.5f);
  EXPECT_FLOAT_EQ(nav.goal()->y, 1.5f);
  EXPECT_EQ(calls, (std::vector<std::string>{"none.propose", "fixed.propose"}));
  ASSERT_FALSE(nav.decisions().empty());
  EXPECT_TRUE(nav.decisions().back().planned);
  EXPECT_EQ(nav.stats().frontier_goals, 1);
  // Reached: the proposing strategy is told; the next decision asks the list again.
  nav.goal_reached(nav.goal_id(), 1.0);
  EXPECT_EQ(calls.back(), "fixed.reached");
  EXPECT_FALSE(nav.goal().has_value());
  nav.decide(robot, 1.0);
  ASSERT_TRUE(nav.goal().has_value());
  nav.abandon(nav.goal_id(), duet::AbandonReason::kTimeout, 2.0);
  EXPECT_EQ(calls.back(), "fixed.abandoned");
}

TEST(GoalStrategy, NoProposalWaitsForTheNextMapAndFinishesAfterTheRetries) {
  const duet::Profile p = frontier_only_profile();
  duet::ExplorerSettings s = p.runtime.explorer;
  s.final_retries = 1;
  std::vector<std::string> calls;
  std::vector<std::unique_ptr<duet::GoalStrategy>> list;
  list.push_back(std::make_unique<Scripted>(std::nullopt, calls, "none"));
  duet::Navigator nav(p, s, std::move(list));
  const duet::Pose2 robot{1.0f, 1.5f, 0.0f};
  nav.update_map(half_known_room(), robot, 0.0);
  nav.decide(robot, 0.0);
  EXPECT_FALSE(nav.goal().has_value());
  EXPECT_TRUE(nav.wait_for_map());
  nav.decide(robot, 0.1);  // waits for a map: not asked again
  EXPECT_EQ(calls.size(), 1u);
  nav.update_map(half_known_room(), robot, 1.0);
  nav.decide(robot, 1.0);
  EXPECT_EQ(calls.size(), 2u);
  EXPECT_EQ(nav.state(), duet::ExplorerState::kDone);
}

// Every goal abandoned at once (a goal the planner finds a path to and the robot cannot reach):
// once every frontier is blacklisted the ones abandoned for a while are forgotten and tried
// again - but a place abandoned max_goal_failures times stays blacklisted, so the decisions end
// instead of trying one goal for ever (Willow seed 1, stop 48: 15 tries in 450 s).
TEST(GoalStrategy, APlaceAbandonedMaxGoalFailuresTimesIsBlacklistedForGood) {
  const duet::Profile p = frontier_only_profile();
  const duet::Pose2 robot{1.0f, 1.5f, 0.0f};
  // Abandons each goal at once; returns the goals taken before the decisions found none (or
  // `cap` when they did not end).
  auto abandon_all = [&](int max_failures, int cap) {
    duet::ExplorerSettings s = p.runtime.explorer;
    s.max_goal_failures = max_failures;
    s.blacklist_ttl_s = 1000.0f;  // only the forgetting brings a goal back within the test
    std::vector<std::unique_ptr<duet::GoalStrategy>> list;
    list.push_back(std::make_unique<duet::ExplorationGoal>(p, s));
    auto nav = std::make_unique<duet::Navigator>(p, s, std::move(list));
    nav->update_map(half_known_room(), robot, 0.0);
    int goals = 0;
    for (double t = 0.0; goals < cap; t += 1.0) {
      nav->decide(robot, t);
      if (!nav->goal()) break;
      ++goals;
      nav->abandon(nav->goal_id(), duet::AbandonReason::kTimeout, t + 0.5);
    }
    return std::make_pair(goals, nav->goal_failures());
  };
  const auto [goals, failures] = abandon_all(3, 200);
  ASSERT_FALSE(failures.empty());
  EXPECT_LT(goals, 200);  // the decisions ended
  int total = 0;
  for (const duet::GoalFailures& f : failures) {
    EXPECT_EQ(f.count, 3) << "at " << f.xy.transpose();  // each place tried three times, not more
    total += f.count;
  }
  EXPECT_EQ(total, goals);
  // A place is tried again after the forgetting: more than one goal per place.
  EXPECT_GT(goals, static_cast<int>(failures.size()));
  // 0 = never for good: the same goals come back as long as the decisions go on.
  EXPECT_EQ(abandon_all(0, 3 * goals + 5).first, 3 * goals + 5);
  duet::ExplorerSettings bad = p.runtime.explorer;
  bad.max_goal_failures = -1;
  EXPECT_THROW(duet::validate(bad), duet::Error);
}

TEST(GoalStrategy, EmptyOrNullListIsRejected) {
  const duet::Profile p = frontier_only_profile();
  EXPECT_THROW(duet::Navigator(p, p.runtime.explorer, {}), duet::Error);
  std::vector<std::unique_ptr<duet::GoalStrategy>> list;
  list.push_back(nullptr);
  EXPECT_THROW(duet::Navigator(p, p.runtime.explorer, std::move(list)), duet::Error);
}

// Each default strategy alone: the exploration decision finds the frontier of the half-known
// room; the relaxed search and the view goal propose nothing there (a frontier is reachable).
TEST(GoalStrategy, DefaultStrategiesAlone) {
  const duet::Profile p = frontier_only_profile();
  const duet::Pose2 robot{1.0f, 1.5f, 0.0f};
  auto alone = [&](std::unique_ptr<duet::GoalStrategy> s) {
    std::vector<std::unique_ptr<duet::GoalStrategy>> list;
    list.push_back(std::move(s));
    auto nav = std::make_unique<duet::Navigator>(p, p.runtime.explorer, std::move(list));
    nav->update_map(half_known_room(), robot, 0.0);
    nav->decide(robot, 0.0);
    return nav;
  };
  const auto exploration = alone(std::make_unique<duet::ExplorationGoal>(p, p.runtime.explorer));
  ASSERT_TRUE(exploration->goal().has_value());
  EXPECT_GT(exploration->goal()->x, 3.0f);  // towards the frontier at x = 4 m
  EXPECT_EQ(exploration->last_decision().status, duet::ExplorationStatus::kFrontierGoal);
  EXPECT_FALSE(exploration->frontier_points().empty());
  // Without the exploration decision there is no decision status to fall back from.
  EXPECT_FALSE(alone(std::make_unique<duet::RelaxedFrontierGoal>(p, p.runtime.explorer))->goal().has_value());
  EXPECT_FALSE(alone(std::make_unique<duet::ViewGoal>(p, p.runtime.explorer))->goal().has_value());
}

