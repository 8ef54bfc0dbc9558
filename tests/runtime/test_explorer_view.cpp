// View goals (view_goal.hpp) on hand-made grids: the robot looks at frontiers it cannot reach
// (each place once, then it stops), a long frontier before a near pocket
// (view_frontier_weight), and an abandoned view goal is not tried again. The explorer in
// motion: test_explorer_motion.cpp.
#include <duet/kernels/error.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/navigation/explorer.hpp>

#include <gtest/gtest.h>

#include "explorer_test_util.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace test_explorer_view {

constexpr float kRes = duet_test::kRoomRes;

using duet_test::fits;
using duet_test::frontier_only_profile;
using duet_test::needed_clearance;

// A room whose east wall (x = 2 m) has a one-cell gap; through it the sensors saw a one-cell-wide
// line of free cells 1.2 m long (a room beyond, seen through a crack), unknown all around it: a
// frontier the robot can never stand on. View goals: the robot goes to a cell of the room with a
// straight line of free cells to a frontier cell and faces it; each frontier cell looked at is
// not looked at again (nor any within the frontier blacklist radius), so it takes at most one view
// per 0.5 m of the line and then stops. With view_range_m = 0 it stops at once.
duet::OccupancyGrid room_with_a_crack() {
  duet::OccupancyGrid g(kRes, Eigen::Vector2f(0.0f, 0.0f), 100, 60);
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < 40; ++x) g.logodds()[g.index(x, y)] = -2.0f;
  for (int y = 0; y < g.height(); ++y) g.logodds()[g.index(40, y)] = 3.5f;  // the wall
  for (int x = 40; x < 64; ++x) g.logodds()[g.index(x, 30)] = -2.0f;        // the gap and the line beyond
  return g;
}

TEST(Explorer, ViewGoalsLookAtFrontiersTheRobotCannotReach) {
  const duet::Profile p = frontier_only_profile();
  const duet::OccupancyGrid g = room_with_a_crack();
  const float line_y = 30.5f * kRes;
  const duet::Pose2 start{0.6f, 0.6f, 1.0f};
  duet::ExplorerSettings off;
  off.view_range_m = 0.0f;
  off.final_retries = 0;
  duet::Explorer stops(p, off);
  stops.update_map(g, start, 0.0);
  (void)stops.control(start, duet::Twist{}, 0.0);
  EXPECT_FALSE(stops.goal().has_value());
  EXPECT_EQ(stops.state(), duet::ExplorerState::kDone);
  EXPECT_EQ(stops.stop_status(), duet::ExplorationStatus::kAllUnreachable);
  EXPECT_EQ(stops.stats().view_goals, 0);

  duet::ExplorerSettings on;
  on.final_retries = 0;
  on.view_looks = 1;  // each place once (looks again: SimDoors.APlaceLookedAtWhileItsDoorWasShut...)
  duet::Explorer e(p, on);
  e.update_map(g, start, 0.0);
  const duet::InflatedGrid& ig = e.inflated();
  double t = 0.0;
  int views = 0;
  float far_target = 0.0f;
  std::vector<Eigen::Vector2f> targets;
  for (; views < 10; ++views) {
    (void)e.control(start, duet::Twist{}, t);
    if (!e.goal().has_value()) break;
    const duet::Pose2 goal = *e.goal();
    ASSERT_FALSE(e.decisions().empty());
    const duet::DecisionRecord& d = e.decisions().back();
    EXPECT_TRUE(d.view);
    EXPECT_EQ(d.status, duet::ExplorationStatus::kAllUnreachable);
    // The target is a frontier cell of the gap or the line beyond it, at least a blacklist
    // radius from every target before it.
    EXPECT_NEAR(d.view_target.y(), line_y, 1e-4f);
    EXPECT_GT(d.view_target.x(), 2.0f);
    for (const auto& prev : targets) EXPECT_GT((d.view_target - prev).norm(), p.exploration.strategy.frontier.blacklist_radius_m);
    targets.push_back(d.view_target);
    // The goal: in the room, where the robot fits, 0.8-4 m from the target, facing it, and the
    // straight line between them crosses known-free cells only.
    const Eigen::Vector2f at(goal.x, goal.y);
    EXPECT_LT(goal.x, 2.0f - needed_clearance(p));
    EXPECT_TRUE(fits(e, goal, needed_clearance(p)));
    EXPECT_GE((d.view_target - at).norm(), on.view_min_range_m - kRes);
    EXPECT_LE((d.view_target - at).norm(), on.view_range_m);
    EXPECT_NEAR(goal.theta, std::atan2(d.view_target.y() - goal.y, d.view_target.x() - goal.x), 1e-5f);
    for (float u = 0.0f; u <= 1.0f; u += 0.01f) {
      const Eigen::Vector2i c = ig.cell_of(at + u * (d.view_target - at));
      EXPECT_EQ(ig.state[ig.index(c.x(), c.y())], duet::CellState::kFree) << u;
    }
    far_target = std::max(far_target, d.view_target.x());
    ASSERT_FALSE(e.path().empty());
    EXPECT_NEAR(e.path().back().x(), goal.x, 1e-4f);
    EXPECT_NEAR(e.path().back().y(), goal.y, 1e-4f);
    // The robot stands at the goal, facing its target: reached.
    t += 1.0;
    (void)e.control(goal, duet::Twist{}, t);
    EXPECT_FALSE(e.goal().has_value());
    EXPECT_EQ(e.stats().view_goals_reached, views + 1);
    t += 1.0;
  }
  // The gap and the 1.2 m line (to x = 3.2 m): one view per 0.5 m at most, out to the line's far
  // part (a cell beyond x = 2.75 m is seen through the gap only within 5 deg of the line), then
  // nothing is left to look at.
  EXPECT_GE(views, 2);
  EXPECT_LE(views, 3);
  EXPECT_GT(far_target, 2.75f);
  EXPECT_EQ(e.stats().view_goals, views);
  EXPECT_EQ(e.state(), duet::ExplorerState::kDone);
  EXPECT_EQ(e.stop_status(), duet::ExplorationStatus::kAllUnreachable);
}

// Two cracks in the east wall of a 2 m x 5 m room: a near one (y = 0.5 m) with 0.5 m of line seen
// beyond it, and a far one (y = 4 m) with 2 m of line - a small pocket and a long frontier, both
// unreachable. View goals rank by path length less view_frontier_weight x the frontier's length:
// with 0 the robot (at the south end) looks through the near crack first, by default (3 m/m)
// through the far one.
duet::OccupancyGrid room_with_two_cracks() {
  duet::OccupancyGrid g(kRes, Eigen::Vector2f(0.0f, 0.0f), 100, 100);
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < 40; ++x) g.logodds()[g.index(x, y)] = -2.0f;
  for (int y = 0; y < g.height(); ++y) g.logodds()[g.index(40, y)] = 3.5f;  // the wall
  for (int x = 40; x < 51; ++x) g.logodds()[g.index(x, 10)] = -2.0f;        // near: the gap and 0.5 m beyond
  for (int x = 40; x < 81; ++x) g.logodds()[g.index(x, 80)] = -2.0f;        // far: the gap and 2 m beyond
  return g;
}

TEST(Explorer, ViewGoalsLookAtTheLongerFrontierFirst) {
  const duet::Profile p = frontier_only_profile();
  const duet::OccupancyGrid g = room_with_two_cracks();
  const duet::Pose2 start{0.6f, 0.3f, 1.0f};
  const auto first_target = [&](float weight) {
    duet::ExplorerSettings s;
    s.final_retries = 0;
    s.view_frontier_weight = weight;
    duet::Explorer e(p, s);
    e.update_map(g, start, 0.0);
    (void)e.control(start, duet::Twist{}, 0.0);
    EXPECT_TRUE(e.goal().has_value());
    EXPECT_FALSE(e.decisions().empty());
    if (e.decisions().empty() || !e.decisions().back().view) return Eigen::Vector2f(-1.0f, -1.0f);
    return e.decisions().back().view_target;
  };
  EXPECT_NEAR(first_target(0.0f).y(), 10.5f * kRes, 1e-4f);  // the nearest by path
  duet::ExplorerSettings defaults;
  EXPECT_EQ(defaults.view_frontier_weight, 3.0f);
  EXPECT_NEAR(first_target(defaults.view_frontier_weight).y(), 80.5f * kRes, 1e-4f);
  duet::ExplorerSettings bad;
  bad.view_frontier_weight = -1.0f;
  EXPECT_THROW(duet::validate(bad), duet::Error);
  bad.view_frontier_weight = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(duet::validate(bad), duet::Error);
}

// A view goal the robot cannot get to is abandoned like any goal; its frontier cell is then not
// looked at again either.
TEST(Explorer, AbandonedViewGoalIsNotTriedAgain) {
  const duet::Profile p = frontier_only_profile();
  duet::ExplorerSettings s;
  s.final_retries = 0;
  s.goal_timeout_s = 1.0f;
  duet::Explorer e(p, s);
  const duet::OccupancyGrid g = room_with_a_crack();
  const duet::Pose2 start{0.6f, 0.6f, 1.0f};
  e.update_map(g, start, 0.0);
  (void)e.control(start, duet::Twist{}, 0.0);
  ASSERT_TRUE(e.goal().has_value());
  ASSERT_TRUE(e.decisions().back().view);
  const Eigen::Vector2f first_target = e.decisions().back().view_target;
  // The time limit passes with the robot not moving.
  (void)e.control(start, duet::Twist{}, 100.0);
  EXPECT_FALSE(e.goal().has_value());
  EXPECT_EQ(e.stats().goals_abandoned_timeout, 1);
  (void)e.control(start, duet::Twist{}, 100.05);
  // Another view goal, for another frontier cell, or none.
  if (e.goal().has_value()) {
    EXPECT_TRUE(e.decisions().back().view);
    EXPECT_GT((e.decisions().back().view_target - first_target).norm(), p.exploration.strategy.frontier.blacklist_radius_m);
  }
  EXPECT_EQ(e.stats().view_goals_reached, 0);
}

}  // namespace test_explorer_view
