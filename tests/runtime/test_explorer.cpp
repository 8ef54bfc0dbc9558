// Explorer (runtime/explorer.hpp) on hand-made grids: goals next to unknown space are moved to
// a cell the dynamic window can stand on (global traversable, clear of unknown cells by the
// window's radius), re-checked at map updates, and abandoned when no such cell is near.
// The motion side (recent obstacles, slow zone, corners, view goals, the frame shift, the
// command's limits): test_explorer_motion.cpp.
#include <duet/kernels/error.hpp>
#include <duet/runtime/navigation/explorer.hpp>
#include <duet/runtime/config/profile.hpp>

#include <gtest/gtest.h>

#include "explorer_test_util.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace {

constexpr float kRes = duet_test::kRoomRes;

using duet_test::decide_in_half_known_room;
using duet_test::fits;
using duet_test::frontier_only_profile;
using duet_test::half_known_room;
using duet_test::needed_clearance;

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

// A frontier goal whose frontier the sensors saw past before the robot got there ends at the
// next map update (frontier_seen_radius_m) and the next decision takes the new frontier; a map
// that still shows the frontier keeps the goal, and with the radius 0 the robot drives on to it.
TEST(Explorer, FrontierGoalEndsWhenItsFrontierIsSeenOnTheWay) {
  const duet::Profile p = frontier_only_profile();
  const duet::Pose2 robot{1.0f, 1.5f, 0.0f};
  duet::OccupancyGrid seen = half_known_room();  // 0.5 m more of the room seen: frontier at x = 4.5 m
  for (int y = 0; y < seen.height(); ++y)
    for (int x = 80; x < 90; ++x) seen.logodds()[seen.index(x, y)] = -2.0f;
  for (const float radius : {0.3f, 0.0f}) {
    SCOPED_TRACE(radius);
    duet::ExplorerSettings s;
    s.frontier_seen_radius_m = radius;
    duet::Explorer e(p, s);
    decide_in_half_known_room(e);
    ASSERT_TRUE(e.goal().has_value());
    const duet::Pose2 first = *e.goal();
    e.update_map(half_known_room(), robot, 1.0);  // nothing new: the goal stays
    ASSERT_TRUE(e.goal().has_value());
    EXPECT_EQ(e.goal()->x, first.x);
    EXPECT_EQ(e.stats().frontier_goals_seen, 0);
    e.update_map(seen, robot, 2.0);
    if (radius > 0.0f) {
      EXPECT_FALSE(e.goal().has_value());
      EXPECT_EQ(e.stats().frontier_goals_seen, 1);
      EXPECT_EQ(e.stats().goals_reached, 0);  // not reached: nothing is blacklisted for it
      (void)e.control(robot, duet::Twist{}, 2.0);
      ASSERT_TRUE(e.goal().has_value());  // decided at once, towards the new frontier
      EXPECT_GT(e.last_decision().goal.x, 4.4f);
      EXPECT_GT(e.goal()->x, first.x + 0.4f);
    } else {
      ASSERT_TRUE(e.goal().has_value());
      EXPECT_EQ(e.goal()->x, first.x);
      EXPECT_EQ(e.stats().frontier_goals_seen, 0);
    }
  }
  duet::ExplorerSettings bad;
  bad.frontier_seen_radius_m = -0.1f;
  EXPECT_THROW(duet::Explorer(p, bad), duet::Error);
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
