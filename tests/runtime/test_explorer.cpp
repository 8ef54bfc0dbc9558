// Explorer (runtime/explorer.hpp) on hand-made grids: goals next to unknown space are moved to
// a cell the dynamic window can stand on (global traversable, clear of unknown cells by the
// window's radius), re-checked at map updates, and abandoned when no such cell is near.
#include <duet/kernels/error.hpp>
#include <duet/runtime/navigation/explorer.hpp>
#include <duet/runtime/config/profile.hpp>

#include <gtest/gtest.h>

#include "half_known_room.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace {

constexpr float kRes = duet_test::kRoomRes;

using duet_test::frontier_only_profile;
using duet_test::half_known_room;

float needed_clearance(const duet::Profile& p) {
  return p.exploration.dwa.robot_radius_m + p.exploration.dwa.safety_margin_m;
}

bool fits(const duet::Explorer& e, const duet::Pose2& goal, float needed) {
  Eigen::Vector2i c;
  if (!e.inflated().cell_of(Eigen::Vector2f(goal.x, goal.y), c)) return false;
  const std::size_t i = e.inflated().index(c.x(), c.y());
  return e.inflated().traversable[i] != 0 && e.local_grid().clearance_m[i] > needed;
}

// The explorer's first decision in half_known_room(), from (1.0, 1.5) facing +x.
void decide_in_half_known_room(duet::Explorer& e) {
  const duet::Pose2 robot{1.0f, 1.5f, 0.0f};
  e.update_map(half_known_room(), robot, 0.0);
  (void)e.control(robot, duet::Twist{}, 0.0);
}

TEST(Explorer, FrontierGoalIsMovedOffTheUnknownCells) {
  const duet::Profile p = frontier_only_profile();
  duet::Explorer e(p);
  decide_in_half_known_room(e);
  ASSERT_TRUE(e.goal().has_value());
  const duet::Pose2 decided = e.last_decision().goal;
  const duet::Pose2 goal = *e.goal();
  // The decision's goal is a frontier cell (last known-free column, x in [3.95, 4.0)).
  EXPECT_GT(decided.x, 3.9f);
  EXPECT_LT(decided.x, 4.0f);
  // The goal the robot drives to is clear of the unknown cells (centres from x = 4.025) by the
  // dynamic window's radius, and is the nearest such cell: one more cell towards the frontier
  // would not be.
  const float needed = needed_clearance(p);
  EXPECT_TRUE(fits(e, goal, needed));
  EXPECT_GT(4.025f - goal.x, needed);
  EXPECT_LE(4.025f - goal.x, needed + kRes + 1e-4f);
  EXPECT_NEAR(goal.y, decided.y, 0.5f * kRes + 1e-4f);
  EXPECT_EQ(goal.theta, decided.theta);
  EXPECT_EQ(e.stats().goals_moved, 1);
  ASSERT_FALSE(e.path().empty());
  EXPECT_NEAR(e.path().back().x(), goal.x, 1e-4f);
  EXPECT_NEAR(e.path().back().y(), goal.y, 1e-4f);
}

// A room 3 x 5.4 m, known free, walled, with unknown space behind a gap in its east wall (x >
// 3.5 m, y in [4, 5]). The robot is below the gap, facing north, with paths not drawn to aisle
// centres (clearance_weight 0), so it drives straight north to the frontier goal and arrives
// with the frontier on its right: with look_with_any_sensor the paper's right sensor faces it
// (no turn); without it the robot turns to face it with the front sensor.
TEST(Explorer, AFrontierGoalIsLookedAtWithTheSensorThatTurnsTheLeast) {
  auto room = [] {
    duet::OccupancyGrid g(kRes, Eigen::Vector2f(0.0f, 0.0f), 80, 120);  // 4 x 6 m
    for (int y = 0; y < g.height(); ++y)
      for (int x = 0; x < g.width(); ++x) {
        const float cx = (x + 0.5f) * kRes, cy = (y + 0.5f) * kRes;
        const bool inside = cx > 0.5f && cx < 3.5f && cy > 0.1f && cy < 5.5f;
        const bool east_gap = cx >= 3.5f && cy > 4.0f && cy < 5.0f;
        g.logodds()[g.index(x, y)] = inside ? -2.0f : east_gap ? std::numeric_limits<float>::quiet_NaN() : 3.0f;
      }
    return g;
  };
  auto first_goal = [&](bool any_sensor, float start_x) {
    duet::Profile p = frontier_only_profile();
    p.exploration.path.clearance_weight = 0.0f;
    duet::ExplorerSettings s;
    s.look_with_any_sensor = any_sensor;
    duet::Explorer e(p, s);
    const duet::Pose2 robot{start_x, 0.6f, 1.5707964f};  // facing north
    e.update_map(room(), robot, 0.0);
    (void)e.control(robot, duet::Twist{}, 0.0);
    EXPECT_TRUE(e.goal().has_value());
    return std::make_pair(e.goal().value_or(duet::Pose2{}), std::vector<Eigen::Vector2f>(e.path().begin(), e.path().end()));
  };
  const float goal_x = first_goal(false, 2.0f).first.x;  // where the goal stands, off the unknown cells
  const auto [front_goal, front_path] = first_goal(false, goal_x);
  const auto [any_goal, any_path] = first_goal(true, goal_x);
  ASSERT_GE(any_path.size(), 2u);
  const Eigen::Vector2f in = any_path.back() - any_path[any_path.size() - 2];
  const float from = std::atan2(in.y(), in.x());
  // The same goal position either way, below the gap's far side.
  EXPECT_NEAR(any_goal.x, front_goal.x, 1e-5f);
  EXPECT_NEAR(any_goal.y, front_goal.y, 1e-5f);
  // The path arrives northwards.
  EXPECT_NEAR(from, 1.5707964f, 0.1f);
  // Without the option the front sensor faces the gap: the heading points east of north by more
  // than 45 deg. With it, the heading of heading_to_look() for that arrival: the right sensor's,
  // within 45 deg of north - a smaller turn.
  const float pi = 3.14159265f;
  EXPECT_GT(std::fabs(std::remainder(front_goal.theta - from, 2.0f * pi)), 0.7854f);
  EXPECT_NEAR(any_goal.theta, duet::heading_to_look(front_goal.theta, from, duet::paper_dual_sensors(30)), 1e-5f);
  EXPECT_LE(std::fabs(std::remainder(any_goal.theta - from, 2.0f * pi)), 0.7854f);
}

TEST(Explorer, GoalIsMovedAgainWhenTheMapClosesAroundIt) {
  const duet::Profile p = frontier_only_profile();
  duet::Explorer e(p);
  const duet::Pose2 robot{1.0f, 1.5f, 0.0f};
  duet::OccupancyGrid g = half_known_room();
  e.update_map(g, robot, 0.0);
  (void)e.control(robot, duet::Twist{}, 0.0);
  ASSERT_TRUE(e.goal().has_value());
  const duet::Pose2 first = *e.goal();
  // A newly seen obstacle 0.1 m in front of the goal, across the whole room.
  const int wall_x = g.cell_of(Eigen::Vector2f(first.x + 0.1f, first.y)).x();
  for (int y = 0; y < g.height(); ++y) g.logodds()[g.index(wall_x, y)] = 3.5f;
  e.update_map(g, robot, 1.0);
  ASSERT_TRUE(e.goal().has_value());
  const float needed = needed_clearance(p);
  EXPECT_TRUE(fits(e, *e.goal(), needed));
  EXPECT_LT(e.goal()->x, first.x);
  EXPECT_EQ(e.stats().goals_moved, 2);
  EXPECT_EQ(e.stats().goals_abandoned_blocked, 0);
}

TEST(Explorer, GoalWithNoStandingRoomNearbyIsAbandoned) {
  const duet::Profile p = frontier_only_profile();
  duet::ExplorerSettings s;
  s.goal_standoff_search_m = 0.0f;  // never move a goal: a frontier goal cannot be stood on
  duet::Explorer e(p, s);
  const duet::Pose2 robot{1.0f, 1.5f, 0.0f};
  e.update_map(half_known_room(), robot, 0.0);
  const duet::Twist cmd = e.control(robot, duet::Twist{}, 0.0);
  EXPECT_FALSE(e.goal().has_value());
  EXPECT_GE(e.stats().goals_abandoned_no_path, 1);
  EXPECT_EQ(e.stats().goals_moved, 0);
  EXPECT_EQ(cmd.v, 0.0f);
  EXPECT_EQ(cmd.omega, 0.0f);
}

// The robot boxed in by a dotted ring of observed-but-uncertain cells (they block by default): the
// frontier search on the planning grid reaches nothing, the search on the relaxed grid (uncertain
// cells not blocking) finds the frontier, and the robot gets a goal and a path instead of stopping.
TEST(Explorer, BoxedInByUncertainCellsTakesARelaxedGoal) {
  duet::Profile p = frontier_only_profile();
  ASSERT_TRUE(p.exploration.inflation.uncertain_is_obstacle);
  p.exploration.strategy.frontier.min_unknown_region_m2 = 0.5f;  // the ring (~0.2 m^2) is no frontier
  duet::ExplorerSettings s;
  duet::Explorer e(p, s);
  const duet::Pose2 robot{1.0f, 1.5f, 0.0f};
  duet::OccupancyGrid g = half_known_room();
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < 80; ++x) {
      const float d = (g.cell_center(x, y) - Eigen::Vector2f(robot.x, robot.y)).norm();
      // A dotted ring of cells seen but neither free nor occupied (speckle at grazing angles).
      if (d > 0.6f && d < 0.66f && (x + y) % 2 == 0) g.logodds()[g.index(x, y)] = 0.0f;
    }
  e.update_map(g, robot, 0.0);
  (void)e.control(robot, duet::Twist{}, 0.0);
  ASSERT_FALSE(e.decisions().empty());
  EXPECT_TRUE(e.decisions().front().relaxed);
  EXPECT_EQ(e.decisions().front().status, duet::ExplorationStatus::kFrontierGoal);
  ASSERT_TRUE(e.goal().has_value());
  EXPECT_EQ(e.stats().relaxed_goals, 1);
  EXPECT_EQ(e.stats().boxed_in_goals, 1);  // the squeezed radius alone does not open the ring
  EXPECT_GT(e.goal()->x, 3.0f);  // towards the frontier at x = 4 m
  EXPECT_FALSE(e.path().empty());
  // The planning grid is the relaxed one while the goal is active: the ring does not block there.
  // The path leaves the ring through cells the planning grid blocks.
  std::size_t blocked = 0;
  for (const Eigen::Vector2f& w : e.path()) {
    const Eigen::Vector2i c = e.inflated().cell_of(w);
    blocked += e.inflated().traversable[e.inflated().index(c.x(), c.y())] == 0;
    EXPECT_NE(e.planning_grid().traversable[e.planning_grid().index(c.x(), c.y())], 0);
  }
  EXPECT_GT(blocked, 0u);
  EXPECT_EQ(e.state(), duet::ExplorerState::kExploring);
}

// A door of 0.5 m: the profile's radius (0.29 m) closes it, the relaxed radius (Kobuki 0.177 m +
// 0.06 m) does not. The frontier beyond it is reached with the relaxed grid and dynamic window.
TEST(Explorer, NarrowDoorIsPassedWithTheRelaxedRadius) {
  const duet::Profile p = frontier_only_profile();
  duet::Explorer e(p);
  duet::OccupancyGrid g = half_known_room();
  for (int y = 0; y < g.height(); ++y)
    if (y < 24 || y > 33) g.logodds()[g.index(40, y)] = 3.5f;  // the wall at x = 2 m, door y in [1.2, 1.7) m
  const duet::Pose2 robot{1.0f, 1.45f, 0.0f};
  e.update_map(g, robot, 0.0);
  (void)e.control(robot, duet::Twist{}, 0.0);
  ASSERT_FALSE(e.decisions().empty());
  EXPECT_TRUE(e.decisions().front().relaxed);
  ASSERT_TRUE(e.goal().has_value());
  EXPECT_GT(e.goal()->x, 2.5f);  // beyond the door
  EXPECT_EQ(e.stats().relaxed_goals, 1);
  const Eigen::Vector2i door = e.inflated().cell_of(Eigen::Vector2f(2.025f, 1.425f));
  EXPECT_EQ(e.inflated().traversable[e.inflated().index(door.x(), door.y())], 0);
  EXPECT_NE(e.planning_grid().traversable[e.planning_grid().index(door.x(), door.y())], 0);
  EXPECT_NEAR(e.planning_grid().robot_radius_m, p.chassis.radius_m + duet::ExplorerSettings{}.squeeze_margin_m, 1e-6f);
  // With no squeeze allowed (margin up to the profile's radius) the door stays shut: nothing to do.
  duet::ExplorerSettings s;
  s.squeeze_margin_m = 1.0f;
  duet::Explorer shut(p, s);
  shut.update_map(g, robot, 0.0);
  (void)shut.control(robot, duet::Twist{}, 0.0);
  EXPECT_FALSE(shut.goal().has_value());
  EXPECT_EQ(shut.stats().relaxed_goals, 0);
  // Not boxed in: the robot's side of the door (~4 m^2 of traversable cells) is more than 1 m^2.
  // With squeeze_anywhere the squeezed radius is still tried from there, uncertain cells still block.
  duet::ExplorerSettings big;
  big.boxed_in_area_m2 = 1.0f;
  big.squeeze_anywhere = true;
  duet::Explorer open_side(p, big);
  open_side.update_map(g, robot, 0.0);
  (void)open_side.control(robot, duet::Twist{}, 0.0);
  ASSERT_TRUE(open_side.goal().has_value());
  EXPECT_GT(open_side.goal()->x, 2.5f);
  EXPECT_EQ(open_side.stats().relaxed_goals, 1);
  EXPECT_EQ(open_side.stats().boxed_in_goals, 0);
  ASSERT_FALSE(open_side.decisions().empty());
  EXPECT_GT(open_side.decisions().front().reached_cells, 400u);  // 1 m^2 at 0.05 m
  // ... and not at all with squeeze_anywhere off (the default): the door stays shut from a large area.
  big.squeeze_anywhere = false;
  duet::Explorer only_boxed(p, big);
  only_boxed.update_map(g, robot, 0.0);
  (void)only_boxed.control(robot, duet::Twist{}, 0.0);
  EXPECT_FALSE(only_boxed.goal().has_value());
  EXPECT_EQ(only_boxed.stats().relaxed_goals, 0);
}

// From a large area the squeezed radius is only used towards frontiers of large unknown regions:
// a 1.5 m^2 enclosed pocket behind the 0.5 m door is left (clutter the robot would squeeze
// into), unless squeeze_min_unknown_m2 allows it.
TEST(Explorer, SqueezeOnlyTowardsLargeUnknownRegions) {
  const duet::Profile p = frontier_only_profile();
  duet::OccupancyGrid g(kRes, Eigen::Vector2f(0.0f, 0.0f), 100, 60);
  for (float& l : g.logodds()) l = -2.0f;  // all known free
  for (int y = 0; y < g.height(); ++y)
    if (y < 24 || y > 33) g.logodds()[g.index(40, y)] = 3.5f;  // the wall at x = 2 m, door y in [1.2, 1.7) m
  for (int y = 10; y < 40; ++y)
    for (int x = 50; x < 70; ++x) g.logodds()[g.index(x, y)] = std::numeric_limits<float>::quiet_NaN();  // 1.5 m^2 pocket
  const duet::Pose2 robot{1.0f, 1.45f, 0.0f};
  duet::ExplorerSettings large;
  large.boxed_in_area_m2 = 1.0f;  // the robot's side is "large"
  large.squeeze_anywhere = true;
  duet::Explorer stays(p, large);
  stays.update_map(g, robot, 0.0);
  (void)stays.control(robot, duet::Twist{}, 0.0);
  EXPECT_FALSE(stays.goal().has_value());
  EXPECT_EQ(stays.stats().relaxed_goals, 0);
  large.squeeze_min_unknown_m2 = 1.0f;
  duet::Explorer goes(p, large);
  goes.update_map(g, robot, 0.0);
  (void)goes.control(robot, duet::Twist{}, 0.0);
  ASSERT_TRUE(goes.goal().has_value());
  EXPECT_GT(goes.goal()->x, 2.2f);
  EXPECT_EQ(goes.stats().relaxed_goals, 1);
}

// The same door, its opening dotted with observed-but-uncertain cells (a face seen at grazing
// incidence): the squeezed radius alone does not open it. From a large area (not boxed in) the
// robot stays; boxed in, the uncertain cells stop blocking and it passes.
TEST(Explorer, UncertainCellsBlockUnlessBoxedIn) {
  const duet::Profile p = frontier_only_profile();
  duet::OccupancyGrid g = half_known_room();
  for (int y = 0; y < g.height(); ++y)
    if (y < 24 || y > 33) g.logodds()[g.index(40, y)] = 3.5f;
    else if (y % 3 == 0) g.logodds()[g.index(40, y)] = 0.0f;  // uncertain speckle in the opening
  const duet::Pose2 robot{1.0f, 1.45f, 0.0f};
  duet::ExplorerSettings large;
  large.boxed_in_area_m2 = 1.0f;  // the robot's side (~4 m^2) is not "boxed in"
  large.squeeze_anywhere = true;  // even then the uncertain cells block
  duet::Explorer stays(p, large);
  stays.update_map(g, robot, 0.0);
  (void)stays.control(robot, duet::Twist{}, 0.0);
  EXPECT_FALSE(stays.goal().has_value());
  EXPECT_EQ(stays.stats().relaxed_goals, 0);
  duet::Explorer passes(p);  // default 10 m^2: boxed in
  passes.update_map(g, robot, 0.0);
  (void)passes.control(robot, duet::Twist{}, 0.0);
  ASSERT_TRUE(passes.goal().has_value());
  EXPECT_GT(passes.goal()->x, 2.5f);
  EXPECT_EQ(passes.stats().relaxed_goals, 1);
  EXPECT_EQ(passes.stats().boxed_in_goals, 1);
}

// Driving forward while the odometry measures no motion (a contact the sensors cannot see): after
// stall_timeout_s a contact obstacle goes just ahead of the robot, the goal is abandoned, and from
// the next map update on every grid the explorer plans and drives on holds the obstacle.
TEST(Explorer, StallPutsAContactObstacleAheadAndAbandonsTheGoal) {
  const duet::Profile p = frontier_only_profile();
  duet::Explorer e(p);
  const duet::Pose2 robot{1.0f, 1.5f, 0.0f};
  const duet::OccupancyGrid g = half_known_room();
  e.update_map(g, robot, 0.0);
  // Moving: no stall however long.
  double t = 0.0;
  duet::Twist cmd = e.control(robot, duet::Twist{}, t);
  ASSERT_TRUE(e.goal().has_value());
  for (int i = 0; i < 40; ++i) cmd = e.control(robot, duet::Twist{0.2f, 0.0f}, t += 0.05);
  EXPECT_EQ(e.stats().stalls, 0);
  ASSERT_GE(cmd.v, 0.03f);  // it drives forward, towards the frontier at x = 4 m
  // Stalled: commanded forward, measured still, for more than 1 s.
  for (int i = 0; i < 25 && e.stats().stalls == 0; ++i) cmd = e.control(robot, duet::Twist{}, t += 0.05);
  EXPECT_EQ(e.stats().stalls, 1);
  EXPECT_GE(t, 1.0);
  EXPECT_EQ(cmd.v, 0.0f);
  EXPECT_FALSE(e.goal().has_value());
  ASSERT_EQ(e.contacts().size(), 1u);
  const Eigen::Vector2f c = e.contacts().front();
  EXPECT_NEAR(c.x(), robot.x + p.chassis.radius_m + 0.05f, 1e-4f);
  EXPECT_NEAR(c.y(), robot.y, 1e-4f);
  // Waits for the next map, then the contact blocks the planning and the driving grids.
  EXPECT_EQ(e.control(robot, duet::Twist{}, t += 0.05).v, 0.0f);
  e.update_map(g, robot, t);
  const Eigen::Vector2i cc = e.inflated().cell_of(c);
  EXPECT_EQ(e.inflated().state[e.inflated().index(cc.x(), cc.y())], duet::CellState::kOccupied);
  EXPECT_EQ(e.local_grid().state[e.local_grid().index(cc.x(), cc.y())], duet::CellState::kOccupied);
  EXPECT_LT(e.local_grid().clearance_m[e.local_grid().index(e.local_grid().cell_of(Eigen::Vector2f(robot.x, robot.y)).x(),
                                                            e.local_grid().cell_of(Eigen::Vector2f(robot.x, robot.y)).y())],
            0.3f);
}

// One 20 Hz control period on a perfect chassis (the command becomes the twist), the map given
// again once a second (period k % 20 == 0).
void perfect_step(duet::Explorer& e, const duet::OccupancyGrid& g, duet::Pose2& robot, duet::Twist& current, int k, double t) {
  if (k % 20 == 0) e.update_map(g, robot, t);
  const duet::Twist cmd = e.control(robot, current, t);
  robot.x += cmd.v * 0.05f * std::cos(robot.theta);
  robot.y += cmd.v * 0.05f * std::sin(robot.theta);
  robot.theta = std::remainder(robot.theta + cmd.omega * 0.05f, 2.0f * 3.14159265f);
  current = cmd;
}

// Recent obstacles: the map has seen a corridor free many times (log-odds at the -2.0 clamp) but
// the latest observations put a wall across it - as when the pose estimate has moved since the
// corridor was mapped. The dynamic window's grid blocks the recent obstacle cells at once, except
// cells within one cell of an obstacle of the map (the inflation's margin holds them); the
// planning grid and the stored map are not changed; the counter counts the cells marked, bad
// points are skipped. The robot (a perfect chassis) drives towards the frontier beyond and stops
// short of the wall (the goal stays: its path is on the planning grid); with no recent obstacles
// any more it goes on through.
TEST(Explorer, RecentObstaclesStopTheDynamicWindowWhereTheMapSeesFree) {
  const duet::Profile p = frontier_only_profile();
  duet::Explorer e(p);
  duet::OccupancyGrid g = half_known_room();
  g.logodds()[g.index(40, 0)] = 3.5f;  // one cell the map already holds as an obstacle
  duet::Pose2 robot{1.0f, 1.5f, 0.0f};
  std::vector<Eigen::Vector2f> wall;
  for (int y = 0; y < g.height(); ++y) wall.push_back(g.cell_center(40, y));  // x = 2.025 m, the whole width
  wall.emplace_back(std::numeric_limits<float>::quiet_NaN(), 1.0f);  // skipped
  wall.emplace_back(50.0f, 50.0f);                                   // outside the grid: ignored
  e.set_recent_obstacles(wall);
  EXPECT_EQ(e.recent_obstacles().size(), wall.size() - 1);
  e.update_map(g, robot, 0.0);
  for (int y = 0; y < g.height(); ++y) {
    const std::size_t i = e.local_grid().index(40, y);
    // (40, 0) is the map's own obstacle; (40, 1) is next to it: not marked, blocked by inflation.
    const auto expected = y == 1 ? duet::CellState::kFree : duet::CellState::kOccupied;
    EXPECT_EQ(e.local_grid().state[i], expected) << y;
    EXPECT_EQ(e.local_grid().traversable[i], 0) << y;
    EXPECT_EQ(e.local_grid().traversable[e.local_grid().index(38, y)], 0) << y;  // inflated
    if (y > 0) {
      EXPECT_EQ(e.inflated().state[i], duet::CellState::kFree) << y;  // planning: the map
    }
  }
  EXPECT_EQ(e.stats().recent_obstacle_cells, static_cast<std::size_t>(g.height() - 2));  // per update
  EXPECT_EQ(g.logodds()[g.index(40, 30)], -2.0f);  // the map itself is the caller's, unchanged
  // Drive for 10 s (perfect chassis, map updates at 1 Hz with the same recent wall).
  auto drive = [&](double t0, double seconds, bool wall_there) {
    duet::Twist current{};
    for (int k = 0; k < static_cast<int>(seconds * 20.0); ++k) {
      const double t = t0 + 0.05 * k;
      perfect_step(e, g, robot, current, k, t);
      if (wall_there) {
        EXPECT_LT(robot.x, 2.0f - p.chassis.radius_m) << t;  // never into the wall cells (x >= 2.0)
      }
    }
  };
  drive(0.0, 10.0, true);
  EXPECT_GT(robot.x, 1.3f);  // it did drive towards the frontier
  EXPECT_LE(robot.x, 2.0f - p.exploration.dwa.robot_radius_m + 0.05f);  // and stopped at the margin
  // Nothing recent any more: the corridor is free again from the next map update on.
  e.set_recent_obstacles({});
  e.update_map(g, robot, 10.0);
  EXPECT_EQ(e.local_grid().state[e.local_grid().index(40, 30)], duet::CellState::kFree);
  EXPECT_EQ(e.stats().recent_obstacle_cells, 11u * static_cast<std::size_t>(g.height() - 2));  // 1 + 10 updates with the wall
  drive(10.0, 20.0, false);
  EXPECT_GT(robot.x, 2.5f);
}

// Slow zone (ExplorerSettings::slow_clearance_m): along a corridor 1.1 m wide (walls 0.5 m from
// the robot's centre line) the dynamic window's top speed is the linear interpolation between
// slow_speed_mps at its margin and the profile's max_v_mps at slow_clearance_m; in the open (the
// half-known room, no obstacle seen) and with the slow zone off it drives at the profile's speed.
duet::OccupancyGrid corridor() {
  duet::OccupancyGrid g(kRes, Eigen::Vector2f(0.0f, 0.0f), 200, 22);
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < 160; ++x) g.logodds()[g.index(x, y)] = (y == 0 || y == 21) ? 3.5f : -2.0f;
  return g;
}

float top_speed(const duet::ExplorerSettings& s, const duet::OccupancyGrid& g, float y0, float& x_end, int& slowed) {
  duet::Explorer e(frontier_only_profile(), s);
  duet::Pose2 robot{0.6f, y0, 0.0f};
  duet::Twist current{};
  float top = 0.0f;
  for (int k = 0; k < 200; ++k) {  // 10 s
    perfect_step(e, g, robot, current, k, 0.05 * k);
    top = std::max(top, current.v);
  }
  x_end = robot.x;
  slowed = e.stats().slowed;
  return top;
}

TEST(Explorer, SlowZoneLimitsTheSpeedNearObstacles) {
  const duet::Profile p = frontier_only_profile();
  const float v_max = p.exploration.dwa.limits.max_v_mps;
  const float margin = needed_clearance(p);
  duet::ExplorerSettings slow;
  slow.slow_clearance_m = 0.8f;
  slow.slow_speed_mps = 0.25f;
  ASSERT_LT(margin, 0.5f);
  // The centre line's cells are 0.5 m from the nearer wall's cell centres.
  const float limit = slow.slow_speed_mps + (v_max - slow.slow_speed_mps) * (0.5f - margin) / (slow.slow_clearance_m - margin);
  const duet::OccupancyGrid g = corridor();
  float x_slow = 0.0f, x_fast = 0.0f, x_open = 0.0f;
  int n_slow = 0, n_fast = 0, n_open = 0;
  const float v_slow = top_speed(slow, g, 0.55f, x_slow, n_slow);
  EXPECT_LE(v_slow, limit + 1e-4f);
  EXPECT_GT(v_slow, limit - 0.03f);  // it did speed up to the limit
  EXPECT_GT(x_slow, 2.5f);           // and drove down the corridor
  duet::ExplorerSettings off;
  off.slow_clearance_m = 0.0f;
  const float v_fast = top_speed(off, g, 0.55f, x_fast, n_fast);
  EXPECT_GT(v_fast, v_max - 0.03f);
  EXPECT_GT(x_fast, x_slow + 0.5f);
  const float v_open = top_speed(slow, half_known_room(), 1.5f, x_open, n_open);
  EXPECT_GT(v_open, v_max - 0.03f);
  EXPECT_GT(n_slow, 100);  // of 200 periods: every period it drove down the corridor
  EXPECT_EQ(n_fast, 0);
  EXPECT_EQ(n_open, 0);
  // The default is on, with these values.
  EXPECT_EQ(duet::ExplorerSettings{}.slow_clearance_m, slow.slow_clearance_m);
  EXPECT_EQ(duet::ExplorerSettings{}.slow_speed_mps, slow.slow_speed_mps);
  // Bad settings name the field.
  for (const float bad : {-0.1f, 10.5f, std::numeric_limits<float>::quiet_NaN()}) {
    duet::ExplorerSettings s;
    s.slow_clearance_m = bad;
    EXPECT_THROW(duet::Explorer(p, s), duet::Error) << bad;
  }
  for (const float bad : {0.0f, -0.2f, std::numeric_limits<float>::infinity()}) {
    duet::ExplorerSettings s;
    s.slow_speed_mps = bad;
    try {
      duet::Explorer e(p, s);
      ADD_FAILURE() << bad;
    } catch (const duet::Error& err) {
      EXPECT_NE(std::string(err.what()).find("slow_speed_mps"), std::string::npos) << err.what();
    }
  }
}

// Cornered (ExplorerSettings::cornered_after_s). The map around the robot on Willow seed 4 at
// 400 s, where it spun for 3300 s (from a debugging dump of the run, 2 m x 2 m, north up,
// 'M' occupied, 'U' not seen (here: occupied), 'u' uncertain, else free; '@' the robot, '*' its
// path, ',' free cells the dynamic window's radius does not fit on). The robot stands on a bump
// of the band it fits in (0.292 m of clearance for 0.29 m needed) with its path going south from
// the cell west of it; spinning, every forward motion the window can reach leaves the band, so it
// turns on (creeping at 3 mm/s) for ever. Below the map a strip never seen: the frontier.
duet::OccupancyGrid willow_corner() {
  static const char* const kRows[41] = {
      "UUUUUUUUUUUUUU,,,,,,..............,,,,,,,",
      "UUUUUUUUUUUUUUU,,,,,,,...........,,,,,,,,",
      "UUUUUUUUUUUUUUU,,,,,,,.........,,,,,,,,,U",
      "UUUUUUUUUUUUUUU,,,,,,,,.......,,,,,,,,,UU",
      "UUUUUUUUUUUUUUUU,M,,,,,......,,,,,,,,,UUU",
      "UUUUUUUUUUUUUUUU,M,,,,,....,,,,,,,,,,UUUU",
      "UUUUUUUUUUUUUUUU,M,,,,,..,,,,,,,,,,UUUUUU",
      "UUUUUUUUUUUUMMMMMM,,,,,,,,,,,,,,,,UUUUUUU",
      "UUUUUUUUUUUUMMMMMM,,,,,,,,,,,,,,,UUUUUUUU",
      "UUUUUUUUUUUUMMMMMM,,,,,,,,,,,,,UUUUUUUUUU",
      "UUUUUUUUUUUUMM,,,,,,,,,,,,,,,,UUUUUUUUUUU",
      "UUUUUUUUUUUMMM,,,,,,,,,,,,,M,UUUUUUUUUUUU",
      "UUUUUUUUUUMMMM,,,,,,,,,,,,,MUUUUUUUUUUUUU",
      "UUUUUUUUUUMMMM,,,,,,,,,,,,,MUUUUUUUUUUUUU",
      "UUUUUUUUUUMM,,,,,,,,..,,,,,MUUUUUUUUUUUUU",
      "UUUUUUUUUUMM,,,,,,,...,,,,,MMMUUUUUUUUUUU",
      "UUUUUUUUMMMM,,,,,,....,,,,,,,MUUUUUUUUUUU",
      "UUUUUUUUMMMM,,,,,,....,,,,,,,MUUUUUUUUUUU",
      "UUUUUUUUMM,,,,,,,.....,,,,,MUUUUUUUUUUUUU",
      "UUUUUUUUMM,,,,,,,....,,,,,,MUUUUUUUUUUUUU",
      "UUUUUUUUMM,,,,,,...*@,,,,,,MUUUUUUUUUUUUU",
      "UUUUUUUUMM,,,,,,...*,,,,,,,MUUUUUUUUUUUUU",
      "UUUUUUUMMM,,,,,....*,,,,,,,MUUUUUUUUUUUUU",
      "UUUUUUMM,M,,,,,....*,,,,,MuMMUMMUUUUMMMMU",
      "UUUUUUMM,,,,,,,....*,,,,,uMMMMMMMMMMMMMMM",
      "UUUUUUMM,,,,,,,....*,,,,,,MMMMMMMMMMMMMMM",
      "UUUUUM,M,,,,,,.....*,,,,,,MMMMMMMMMMMMMMM",
      "UUUUMM,M,,,,,,.....*.,,,,M,MMMMMMMMMMMMMM",
      "UUUUMM,,,,,,,......*.,,,,,,,,,,,,,,,,,,,,",
      "UUUUMM,,,,,,,......*..,,,,,,,,,,,,,,,,,,,",
      "UUUUMM,,,,,,........*.,,,,,,,,,,,,,,,,,,,",
      "UUMM,M,,,,,,,,.......*.,,,,,,,,,,,,,,,,,,",
      "UUMM,,,,,,,,,,,,......*..,,,,,,,,,,,,,,,,",
      "UUMM,,,,,,,,,,,,,,.....*.................",
      "UUUM,,,,,,,,,,,,,,,,....*................",
      "UUUM,MMMMM,,,,,,,,,,,,...*...............",
      "UU,MM,UUUM,,,,,,,,,,,,....**.............",
      "U,MM,UUUUMMMMM,,,,,,,,,,....**...........",
      "UuMM,UUUUUUUUM,,,M,,,,,,......**.........",
      "UMM,UUUUUUUUUMMMMM,,,,,,,,......*********",
      "UMMUUUUUUUUUUUUUU,,,,,,,,,...............",
  };
  constexpr int kExtra = 4;  // unknown rows below
  duet::OccupancyGrid g(kRes, Eigen::Vector2f(0.0f, 0.0f), 41, 41 + kExtra);
  for (int r = 0; r < 41; ++r)
    for (int c = 0; c < 41; ++c) {
      const char ch = kRows[r][c];
      g.logodds()[g.index(c, 40 - r + kExtra)] = ch == 'M' || ch == 'U' ? 3.5f : ch == 'u' ? 0.0f : -2.0f;
    }
  for (int y = 0; y < kExtra; ++y)
    for (int x = 0; x < 41; ++x) g.logodds()[g.index(x, y)] = std::numeric_limits<float>::quiet_NaN();
  return g;
}

// Drives the explorer on the map for `seconds` with a perfect chassis (the command is the next
// twist), from the spot and the spin of the Willow run; returns the final pose.
duet::Pose2 drive_from_the_corner(duet::Explorer& e, const duet::OccupancyGrid& g, double seconds, float* min_clearance) {
  duet::Pose2 robot{g.cell_center(20, 24).x(), g.cell_center(20, 24).y(), -0.16f};
  duet::Twist current{0.0f, -0.8f};
  *min_clearance = std::numeric_limits<float>::infinity();
  double t = 0.0;
  for (int k = 0; t < seconds; ++k) {
    perfect_step(e, g, robot, current, k, t);
    t += 0.05;
    const Eigen::Vector2i c = e.inflated().cell_of(Eigen::Vector2f(robot.x, robot.y));
    *min_clearance = std::min(*min_clearance, e.inflated().clearance_m[e.inflated().index(c.x(), c.y())]);
  }
  return robot;
}

TEST(Explorer, CorneredRobotEscapesTowardsMoreClearance) {
  const duet::Profile p = frontier_only_profile();
  const duet::OccupancyGrid g = willow_corner();
  const Eigen::Vector2f start = g.cell_center(20, 24);
  float min_clearance = 0.0f;
  {  // Without the escape (the default, 0 = off): 60 s on the spot.
    duet::Explorer e(p);
    const duet::Pose2 end = drive_from_the_corner(e, g, 60.0, &min_clearance);
    EXPECT_LT((Eigen::Vector2f(end.x, end.y) - start).norm(), 0.1f);
    EXPECT_EQ(e.stats().goals_reached, 0);
    EXPECT_EQ(e.stats().cornered_escapes, 0);
  }
  // With it (8 s): out after the first 8 s, then on to the frontier.
  duet::ExplorerSettings s;
  s.cornered_after_s = 8.0f;
  duet::Explorer e(p, s);
  const duet::Pose2 end = drive_from_the_corner(e, g, 60.0, &min_clearance);
  EXPECT_GT(e.stats().cornered_escapes, 0);
  EXPECT_GE(e.stats().goals_reached, 1);
  EXPECT_GT((Eigen::Vector2f(end.x, end.y) - start).norm(), 0.3f);
  EXPECT_GT(min_clearance, p.chassis.radius_m);  // never touched anything on the way
}

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

TEST(Explorer, InvalidStandoffSearchThrows) {
  const duet::Profile p = frontier_only_profile();
  for (const float bad : {-0.1f, 5.5f, std::numeric_limits<float>::quiet_NaN()}) {
    duet::ExplorerSettings s;
    s.goal_standoff_search_m = bad;
    EXPECT_THROW(duet::Explorer(p, s), duet::Error) << bad;
    duet::ExplorerSettings m;
    m.squeeze_margin_m = bad * 10.0f;  // -1, 55, NaN
    EXPECT_THROW(duet::Explorer(p, m), duet::Error) << bad;
    duet::ExplorerSettings a;
    a.boxed_in_area_m2 = bad < 0.0f || std::isnan(bad) ? bad : std::numeric_limits<float>::infinity();
    EXPECT_THROW(duet::Explorer(p, a), duet::Error) << bad;
    duet::ExplorerSettings u;
    u.squeeze_min_unknown_m2 = a.boxed_in_area_m2;
    EXPECT_THROW(duet::Explorer(p, u), duet::Error) << bad;
    duet::ExplorerSettings st;
    st.stall_timeout_s = bad < 0.0f || std::isnan(bad) ? bad : 0.0f;
    EXPECT_THROW(duet::Explorer(p, st), duet::Error) << bad;
    duet::ExplorerSettings cr;
    cr.contact_radius_m = bad;
    EXPECT_THROW(duet::Explorer(p, cr), duet::Error) << bad;
    duet::ExplorerSettings vr;
    vr.view_range_m = bad * 2.0f;  // -0.2, 11, NaN
    EXPECT_THROW(duet::Explorer(p, vr), duet::Error) << bad;
    duet::ExplorerSettings vm;
    vm.view_min_range_m = bad;  // -0.1, 5.5 > view_range_m = 4, NaN
    EXPECT_THROW(duet::Explorer(p, vm), duet::Error) << bad;
    duet::ExplorerSettings ro;
    ro.recent_obstacles_s = bad < 0.0f || std::isnan(bad) ? bad : 3601.0f;
    EXPECT_THROW(duet::Explorer(p, ro), duet::Error) << bad;
    duet::ExplorerSettings rr;
    rr.recent_obstacle_range_m = bad < 0.0f || std::isnan(bad) ? bad : 0.0f;
    EXPECT_THROW(duet::Explorer(p, rr), duet::Error) << bad;
    duet::ExplorerSettings co;
    co.cornered_after_s = bad < 0.0f || std::isnan(bad) ? bad : std::numeric_limits<float>::infinity();  // 0 = off is valid
    EXPECT_THROW(duet::Explorer(p, co), duet::Error) << bad;
  }
  // Integer settings out of range: the error names the field.
  auto expect_error_naming = [&](const duet::ExplorerSettings& bad, const char* name) {
    try {
      duet::Explorer e(p, bad);
      ADD_FAILURE() << name;
    } catch (const duet::Error& err) {
      EXPECT_NE(std::string(err.what()).find(name), std::string::npos) << err.what();
    }
  };
  for (const int scans : {0, 1001}) {
    duet::ExplorerSettings rs;
    rs.recent_obstacle_min_scans = scans;
    expect_error_naming(rs, "recent_obstacle_min_scans");
  }
  for (const int rays : {3, 3601}) {
    duet::ExplorerSettings v;
    v.view_rays = rays;
    expect_error_naming(v, "view_rays");
  }
}

}  // namespace

namespace {

// A loop closure moves the map frame: the goal, its path and the recent obstacles move by the
// same shift (new = D * old); a non-finite shift is refused and moves nothing.
TEST(Explorer, ShiftFrameMovesTheGoalThePathAndTheRecentObstacles) {
  const duet::Profile p = frontier_only_profile();
  duet::Explorer e(p);
  decide_in_half_known_room(e);
  ASSERT_TRUE(e.goal().has_value());
  ASSERT_FALSE(e.path().empty());
  const std::vector<Eigen::Vector2f> recent{{2.0f, 2.0f}};
  e.set_recent_obstacles(recent);
  ASSERT_EQ(e.recent_obstacles().size(), 1u);
  const duet::Pose2 goal = *e.goal();
  const std::vector<Eigen::Vector2f> path = e.path();
  const duet::Pose2 D{0.3f, -0.2f, 0.05f};
  EXPECT_THROW(e.shift_frame(duet::Pose2{std::nanf(""), 0.0f, 0.0f}), duet::Error);
  EXPECT_EQ(e.goal()->x, goal.x);
  e.shift_frame(D);
  const duet::Pose2 want = duet::compose(D, goal);
  EXPECT_NEAR(e.goal()->x, want.x, 1e-5f);
  EXPECT_NEAR(e.goal()->y, want.y, 1e-5f);
  EXPECT_NEAR(e.goal()->theta, want.theta, 1e-5f);
  ASSERT_EQ(e.path().size(), path.size());
  for (std::size_t k = 0; k < path.size(); ++k) {
    const duet::Pose2 q = duet::compose(D, duet::Pose2{path[k].x(), path[k].y(), 0.0f});
    EXPECT_NEAR(e.path()[k].x(), q.x, 1e-5f);
    EXPECT_NEAR(e.path()[k].y(), q.y, 1e-5f);
  }
  const duet::Pose2 r = duet::compose(D, duet::Pose2{2.0f, 2.0f, 0.0f});
  EXPECT_NEAR(e.recent_obstacles()[0].x(), r.x, 1e-5f);
  EXPECT_NEAR(e.recent_obstacles()[0].y(), r.y, 1e-5f);
}

}  // namespace

TEST(Explorer, CommandNeverExceedsTheChassisWhateverTheOdometrySays) {
  // A glitched measured twist (100 m/s, 100 rad/s) reaches every behaviour that works from it -
  // the window, the turn to a goal's heading, the escapes: the command stays within the chassis.
  const duet::Profile p = frontier_only_profile();
  duet::Explorer e(p);
  decide_in_half_known_room(e);
  ASSERT_TRUE(e.goal().has_value());
  const float v_max = p.chassis.max_linear_speed_mps, w_max = p.chassis.max_angular_speed_radps();
  double t = 0.1;
  for (const duet::Twist glitch : {duet::Twist{100.0f, 0.0f}, duet::Twist{-100.0f, 3.0f}, duet::Twist{0.2f, 100.0f},
                                   duet::Twist{0.0f, -100.0f}}) {
    for (const duet::Pose2 at : {duet::Pose2{1.0f, 1.5f, 0.0f}, duet::Pose2{e.goal()->x, e.goal()->y, e.goal()->theta + 1.0f}}) {
      const duet::Twist cmd = e.control(at, glitch, t);
      t += 0.05;
      EXPECT_LE(std::fabs(cmd.v), v_max) << glitch.v << " " << glitch.omega;
      EXPECT_LE(std::fabs(cmd.omega), w_max) << glitch.v << " " << glitch.omega;
    }
  }
}
