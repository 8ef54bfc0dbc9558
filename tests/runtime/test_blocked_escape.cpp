// The way out for a blocked robot (blocked_escape.hpp): path_out() against a breadth-first
// reference on a niche, its empty cases (off the grid, NaN, already traversable, nothing in
// reach, an empty grid), and creep_along() - turns first, creeps at 0.1 m/s within the chassis'
// limits, stops at the end and short of a cell the body does not fit in. The Explorer's use of
// both: test_explorer_motion.cpp (Explorer.BlockedRobotClimbsOutInsteadOfGivingUp).
#include <duet/kernels/grid.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/runtime/navigation/blocked_escape.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace test_blocked_escape {

constexpr float kRes = 0.05f;
constexpr float kBody = 0.177f;

// A 2 m x 3 m room with a niche 0.4 m wide and 0.6 m deep in its south wall (x 11..18, y 1..11
// free), inflated with the 0.29 m planning radius: no cell of the niche is traversable.
duet::InflatedGrid niche(float radius = 0.29f) {
  duet::OccupancyGrid g(kRes, Eigen::Vector2f(0.0f, 0.0f), 40, 60);
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < g.width(); ++x)
      g.logodds()[g.index(x, y)] = (y < 12 && (x <= 10 || x >= 19)) || y == 0 ? 3.5f : -2.0f;
  duet::InflationSettings s;
  s.robot_radius_m = radius;
  duet::InflatedGrid out;
  duet::inflate(duet::GridView(g), s, out);
  return out;
}

TEST(BlockedEscape, PathOutOfANicheIsTheShortestToATraversableCell) {
  const duet::InflatedGrid g = niche();
  const Eigen::Vector2f robot(15.0f * kRes, 6.0f * kRes);
  Eigen::Vector2i rc;
  ASSERT_TRUE(g.cell_of(robot, rc));
  ASSERT_FALSE(g.traversable[g.index(rc.x(), rc.y())]);
  const std::vector<Eigen::Vector2f> path = duet::path_out(g, robot, kBody, 2.0f);
  ASSERT_GE(path.size(), 2u);
  // Starts at the robot's cell, ends on a traversable cell, steps between 8-neighbours, every
  // cell but the last one the body fits in (clearance above the chassis' radius).
  EXPECT_EQ(g.cell_of(path.front()), rc);
  const Eigen::Vector2i end = g.cell_of(path.back());
  EXPECT_TRUE(g.traversable[g.index(end.x(), end.y())]);
  float length = 0.0f;
  for (std::size_t i = 0; i < path.size(); ++i) {
    const Eigen::Vector2i c = g.cell_of(path[i]);
    EXPECT_GE(g.clearance_m[g.index(c.x(), c.y())], kBody) << i;
    if (i + 1 < path.size()) {
      EXPECT_FALSE(g.traversable[g.index(c.x(), c.y())]) << i;  // the first traversable cell ends it
    }
    if (i > 0) {
      const Eigen::Vector2i d = c - g.cell_of(path[i - 1]);
      EXPECT_LE(std::max(std::abs(d.x()), std::abs(d.y())), 1);
      length += (path[i] - path[i - 1]).norm();
    }
  }
  // Reference: the nearest traversable cell by 8-connected path length through cells the body
  // fits in, by brute force (Bellman-Ford relaxation to a fixed point).
  std::vector<float> dist(g.cell_count(), std::numeric_limits<float>::infinity());
  dist[g.index(rc.x(), rc.y())] = 0.0f;
  for (bool changed = true; changed;) {
    changed = false;
    for (int y = 0; y < g.height; ++y)
      for (int x = 0; x < g.width; ++x) {
        const std::size_t i = g.index(x, y);
        if (!std::isfinite(dist[i]) || g.traversable[i]) continue;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            if ((dx == 0 && dy == 0) || !g.in_bounds(x + dx, y + dy)) continue;
            const std::size_t j = g.index(x + dx, y + dy);
            if (!(g.clearance_m[j] >= kBody) && !g.traversable[j]) continue;
            const float nd = dist[i] + kRes * ((dx != 0 && dy != 0) ? std::sqrt(2.0f) : 1.0f);
            if (nd < dist[j] - 1e-6f) {
              dist[j] = nd;
              changed = true;
            }
          }
      }
  }
  float best = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i < g.cell_count(); ++i)
    if (g.traversable[i]) best = std::min(best, dist[i]);
  EXPECT_NEAR(length, best, 1e-3f);
  EXPECT_GT(path.back().y(), 0.6f);  // out of the niche's mouth
}

TEST(BlockedEscape, NoPathWhenNotNeededOrNotPossible) {
  const duet::InflatedGrid g = niche();
  EXPECT_TRUE(duet::path_out(g, Eigen::Vector2f(1.0f, 2.0f), kBody, 2.0f).empty());    // already traversable
  EXPECT_TRUE(duet::path_out(g, Eigen::Vector2f(-1.0f, 0.3f), kBody, 2.0f).empty());   // off the grid
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(duet::path_out(g, Eigen::Vector2f(nan, 0.3f), kBody, 2.0f).empty());
  EXPECT_TRUE(duet::path_out(g, Eigen::Vector2f(0.75f, 0.3f), kBody, 0.2f).empty());  // the mouth is farther
  EXPECT_TRUE(duet::path_out(duet::InflatedGrid{}, Eigen::Vector2f(0.0f, 0.0f), kBody, 2.0f).empty());
  // A body wider than the niche: the robot's own cell is the limit (never tighter than here), so
  // it still gets out along the middle.
  EXPECT_FALSE(duet::path_out(g, Eigen::Vector2f(0.75f, 0.3f), 0.3f, 2.0f).empty());
}

TEST(BlockedEscape, CreepTurnsFirstThenCreepsWithinTheLimitsAndStops) {
  const duet::InflatedGrid g = niche();
  duet::DwaSettings ds;
  const std::vector<Eigen::Vector2f> path = duet::path_out(g, Eigen::Vector2f(0.75f, 0.3f), kBody, 2.0f);
  ASSERT_FALSE(path.empty());
  // Facing east (the path goes north): a turn in place, left, within the mapping limits.
  duet::Twist t = *duet::creep_along(duet::Pose2{0.75f, 0.3f, 0.0f}, duet::Twist{}, path, g, kBody, ds);
  EXPECT_EQ(t.v, 0.0f);
  EXPECT_GT(t.omega, 0.0f);
  EXPECT_LE(t.omega, ds.mapping_max_alpha_rps2 * ds.control_period_s + 1e-6f);
  // Facing north: forward, ramping up to 0.1 m/s at most.
  t = *duet::creep_along(duet::Pose2{0.75f, 0.3f, 1.5708f}, duet::Twist{}, path, g, kBody, ds);
  EXPECT_GT(t.v, 0.0f);
  EXPECT_LE(t.v, ds.limits.max_accel_mps2 * ds.control_period_s + 1e-6f);
  t = *duet::creep_along(duet::Pose2{0.75f, 0.3f, 1.5708f}, duet::Twist{0.1f, 0.0f}, path, g, kBody, ds);
  EXPECT_NEAR(t.v, 0.1f, 1e-6f);
  // At the path's end: nothing more to do; no path: nothing.
  EXPECT_FALSE(duet::creep_along(duet::Pose2{path.back().x(), path.back().y(), 1.5708f}, duet::Twist{}, path, g, kBody, ds));
  EXPECT_FALSE(duet::creep_along(duet::Pose2{0.75f, 0.3f, 1.5708f}, duet::Twist{}, {}, g, kBody, ds));
  // Driving the whole way on a perfect chassis: out of the niche, never nearer a wall than the body.
  duet::Pose2 robot{0.75f, 0.3f, 0.0f};
  duet::Twist current;
  for (int k = 0; k < 400; ++k) {
    const std::optional<duet::Twist> cmd = duet::creep_along(robot, current, path, g, kBody, ds);
    if (!cmd) break;
    current = *cmd;
    robot.x += current.v * ds.control_period_s * std::cos(robot.theta);
    robot.y += current.v * ds.control_period_s * std::sin(robot.theta);
    robot.theta += current.omega * ds.control_period_s;
    const Eigen::Vector2i c = g.cell_of(Eigen::Vector2f(robot.x, robot.y));
    EXPECT_GE(g.clearance_m[g.index(c.x(), c.y())], std::min(kBody, 0.2f)) << k;
  }
  EXPECT_LE((Eigen::Vector2f(robot.x, robot.y) - path.back()).norm(), 0.06f);
}

}  // namespace test_blocked_escape
