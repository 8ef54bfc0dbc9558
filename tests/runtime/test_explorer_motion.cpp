// Explorer (runtime/explorer.hpp) in motion on hand-made grids: recent obstacles stop the dynamic
// window where the map sees free, the slow zone near obstacles, a cornered robot escapes, a robot
// found blocked climbs out instead of giving up, Procedure 1's goals handed off on the move, a
// loop closure's frame shift moves the goal, path and recent obstacles, and the command never
// exceeds the chassis. Goals and their standing room: test_explorer.cpp; view goals:
// test_explorer_view.cpp.
#include <duet/kernels/error.hpp>
#include <duet/runtime/navigation/explorer.hpp>
#include <duet/runtime/config/profile.hpp>

#include <gtest/gtest.h>

#include "explorer_test_util.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace test_explorer_motion {

constexpr float kRes = duet_test::kRoomRes;

using duet_test::decide_in_half_known_room;
using duet_test::fits;
using duet_test::frontier_only_profile;
using duet_test::half_known_room;
using duet_test::needed_clearance;

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
  {  // Without the escape (0 = off): 60 s on the spot.
    duet::ExplorerSettings off;
    off.cornered_after_s = 0.0f;
    duet::Explorer e(p, off);
    const duet::Pose2 end = drive_from_the_corner(e, g, 60.0, &min_clearance);
    EXPECT_LT((Eigen::Vector2f(end.x, end.y) - start).norm(), 0.1f);
    EXPECT_EQ(e.stats().goals_reached, 0);
    EXPECT_EQ(e.stats().cornered_escapes, 0);
  }
  // With it (the default, 8 s): out after the first 8 s, then on to the frontier.
  duet::ExplorerSettings s;
  EXPECT_EQ(s.cornered_after_s, 8.0f);
  duet::Explorer e(p, s);
  const duet::Pose2 end = drive_from_the_corner(e, g, 60.0, &min_clearance);
  EXPECT_GT(e.stats().cornered_escapes, 0);
  EXPECT_GE(e.stats().goals_reached, 1);
  EXPECT_GT((Eigen::Vector2f(end.x, end.y) - start).norm(), 0.3f);
  EXPECT_GT(min_clearance, p.chassis.radius_m);  // never touched anything on the way
}

// A room 2 m x 3 m (the unknown beyond its north side: a frontier), with a niche 0.4 m wide and
// 0.6 m deep in its south wall. The robot stands at the back of the niche: its body fits (0.2 m
// and more to each side wall for a 0.177 m radius) but no cell within the planning radius
// (0.29 m) is traversable, nor on the relaxed grid (0.237 m) - the frontier search finds it
// blocked, as after a pose estimate moved next to a wall.
duet::OccupancyGrid room_with_a_niche() {
  duet::OccupancyGrid g(kRes, Eigen::Vector2f(0.0f, 0.0f), 40, 100);
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < g.width(); ++x)
      g.logodds()[g.index(x, y)] = y >= 72 ? std::numeric_limits<float>::quiet_NaN() : y < 12 && (x <= 10 || x >= 19) ? 3.5f : -2.0f;
  for (int x = 11; x < 19; ++x) g.logodds()[g.index(x, 0)] = 3.5f;  // the niche's back wall
  return g;
}

TEST(Explorer, BlockedRobotClimbsOutInsteadOfGivingUp) {
  const duet::Profile p = frontier_only_profile();
  const duet::OccupancyGrid g = room_with_a_niche();
  const duet::Pose2 start{15.0f * kRes, 6.0f * kRes, 0.0f};
  const auto run = [&](const duet::ExplorerSettings& s, double seconds, float* min_clearance) {
    auto e = std::make_unique<duet::Explorer>(p, s);
    duet::Pose2 robot = start;
    duet::Twist current;
    *min_clearance = std::numeric_limits<float>::infinity();
    double t = 0.0;
    for (int k = 0; t < seconds && e->state() != duet::ExplorerState::kDone; ++k) {
      perfect_step(*e, g, robot, current, k, t);
      t += 0.05;
      // Distance from the body's centre to the nearest wall cell (the map's own obstacles).
      for (int y = 0; y < g.height(); ++y)
        for (int x = 0; x < g.width(); ++x)
          if (g.logodds()[g.index(x, y)] > 1.0f)
            *min_clearance = std::min(*min_clearance, (g.cell_center(x, y) - Eigen::Vector2f(robot.x, robot.y)).norm());
    }
    return std::make_pair(std::move(e), robot);
  };
  float min_clearance = 0.0f;
  {  // Off: the run ends at once, blocked, where it started.
    duet::ExplorerSettings off;
    off.blocked_recovery_s = 0.0f;
    auto [e, end] = run(off, 30.0, &min_clearance);
    EXPECT_EQ(e->state(), duet::ExplorerState::kDone);
    EXPECT_EQ(e->stop_status(), duet::ExplorationStatus::kRobotBlocked);
    EXPECT_NE(e->stop_detail().find("blocked"), std::string::npos) << e->stop_detail();
    EXPECT_LT(std::hypot(end.x - start.x, end.y - start.y), 0.05f);
    EXPECT_EQ(e->stats().blocked_recoveries, 0);
    EXPECT_EQ(e->stats().blocked_escapes, 0);
  }
  // The default (30 s): out of the niche, then on to the frontier, never touching a wall.
  duet::ExplorerSettings s;
  EXPECT_EQ(s.blocked_recovery_s, 30.0f);
  auto [e, end] = run(s, 60.0, &min_clearance);
  EXPECT_EQ(e->stats().blocked_recoveries, 1);
  EXPECT_GT(e->stats().blocked_escapes, 0);
  EXPECT_GE(e->stats().frontier_goals, 1);
  EXPECT_GE(e->stats().goals_reached, 1);
  EXPECT_NE(e->stop_status(), duet::ExplorationStatus::kRobotBlocked) << e->stop_detail();
  EXPECT_GT(end.y, 1.0f);  // out of the niche (0.6 m deep) and into the room
  EXPECT_GT(min_clearance, p.chassis.radius_m);
}

// One simulated goal reached while driving: the goal, the robot where it was reached, the
// command of that period, the time and how far the goal was from the robot when it was issued.
struct SimulatedGoalReached {
  duet::Pose2 goal, robot;
  duet::Twist cmd;
  double t_s = 0.0;
  float issued_at_m = 0.0f;
};

// 30 s of the explorer in the half-known room (a static map, updated each second: the unknown
// side keeps offering reward) on a perfect chassis from (1, 1.5); `reached` is called for each
// simulated goal reached.
template <typename OnReached>
void drive_simulated_goals(duet::Explorer& e, OnReached&& reached) {
  const duet::OccupancyGrid g = half_known_room();
  duet::Pose2 robot{1.0f, 1.5f, 0.0f};
  duet::Twist current;
  std::optional<duet::Pose2> last_goal;
  float issued_at_m = 0.0f;
  double t = 0.0;
  for (int k = 0; k < 600; ++k, t += 0.05) {
    if (k % 20 == 0) e.update_map(g, robot, t);
    const std::optional<duet::Pose2> goal = e.goal();
    const bool simulated = !e.decisions().empty() && e.decisions().back().status == duet::ExplorationStatus::kSimulatedGoal;
    const int before = e.stats().goals_reached;
    const duet::Twist cmd = e.control(robot, current, t);
    if (goal && simulated && e.stats().goals_reached > before) reached(SimulatedGoalReached{*goal, robot, cmd, t, issued_at_m});
    // control() may decide: the goal it works on next is the one after the call.
    const std::optional<duet::Pose2> now_goal = e.goal();
    if (now_goal && (!last_goal || now_goal->x != last_goal->x || now_goal->y != last_goal->y || now_goal->theta != last_goal->theta))
      issued_at_m = std::hypot(now_goal->x - robot.x, now_goal->y - robot.y);
    last_goal = now_goal;
    robot.x += cmd.v * 0.05f * std::cos(robot.theta);
    robot.y += cmd.v * 0.05f * std::sin(robot.theta);
    robot.theta = std::remainder(robot.theta + cmd.omega * 0.05f, 2.0f * 3.14159265f);
    current = cmd;
  }
}

// Procedure 1's goals handed off on the move (simulated_goal_handoff_m): in the half-known room
// the robot takes simulated goals for 30 s on a perfect chassis. By default each one is reached
// within the window's goal tolerance and faced (the command of that period is zero); with a
// 0.4 m handoff each is reached within 0.4 m, and at most periods the robot is still moving when
// it is - no stop, no turn at X_g.
TEST(Explorer, SimulatedGoalsAreHandedOffOnTheMove) {
  const duet::Profile p = duet::builtin_profile("dual_kinect_kobuki");
  for (const float handoff : {0.0f, 0.4f}) {
    duet::ExplorerSettings s;
    EXPECT_EQ(s.simulated_goal_handoff_m, 0.0f);
    s.simulated_goal_handoff_m = handoff;
    duet::Explorer e(p, s);
    int reached = 0, moving = 0;
    drive_simulated_goals(e, [&](const SimulatedGoalReached& r) {
      ++reached;
      const float d = std::hypot(r.goal.x - r.robot.x, r.goal.y - r.robot.y);
      if (handoff > 0.0f) {
        EXPECT_LE(d, handoff + 1e-4f) << r.t_s;
        moving += r.cmd.v > 0.0f ? 1 : 0;
      } else {
        EXPECT_LE(d, p.exploration.dwa.goal_tolerance_m + kRes) << r.t_s;  // the path ends at the goal cell's centre
        EXPECT_LE(std::fabs(std::remainder(r.goal.theta - r.robot.theta, 6.2831853f)), 0.2f) << r.t_s;
        EXPECT_EQ(r.cmd.v, 0.0f);
        EXPECT_EQ(r.cmd.omega, 0.0f);
      }
    });
    EXPECT_GE(reached, 3) << "handoff " << handoff;
    if (handoff > 0.0f) {
      EXPECT_GT(2 * moving, reached) << moving << " of " << reached;
    }
  }
  duet::ExplorerSettings bad;
  bad.simulated_goal_handoff_m = -0.1f;
  EXPECT_THROW(duet::validate(bad), duet::Error);
  bad.simulated_goal_handoff_m = 6.0f;
  EXPECT_THROW(duet::validate(bad), duet::Error);
}

// A simulated goal issued within the handoff distance of the robot is a turn to look, not a
// waypoint: it is reached facing its heading (handing it off would end it at once, unturned).
// With the largest handoff (5 m) every X_g of the half-known room is issued within it.
TEST(Explorer, ASimulatedGoalIssuedWithinTheHandoffIsFaced) {
  const duet::Profile p = duet::builtin_profile("dual_kinect_kobuki");
  duet::ExplorerSettings s;
  s.simulated_goal_handoff_m = 5.0f;
  duet::Explorer e(p, s);
  int reached = 0;
  drive_simulated_goals(e, [&](const SimulatedGoalReached& r) {
    ++reached;
    ASSERT_LE(r.issued_at_m, s.simulated_goal_handoff_m) << r.t_s;
    EXPECT_LE(std::fabs(std::remainder(r.goal.theta - r.robot.theta, 6.2831853f)), 0.2f) << r.t_s;
    EXPECT_EQ(r.cmd.v, 0.0f) << r.t_s;
    EXPECT_EQ(r.cmd.omega, 0.0f) << r.t_s;
  });
  EXPECT_GE(reached, 3);
}

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
}  // namespace test_explorer_motion
