// The controller's behaviours as separate pieces (stall_detector.hpp, slow_zone.hpp, escape.hpp),
// each against its rule on small hand-made inputs.
#include <duet/kernels/inflation.hpp>
#include <duet/runtime/navigation/escape.hpp>
#include <duet/runtime/navigation/slow_zone.hpp>
#include <duet/runtime/navigation/stall_detector.hpp>

#include <gtest/gtest.h>

#include <cmath>

namespace {

/// A 2 x 2 m planning grid (0.05 m cells) whose clearance is `clear` everywhere.
duet::InflatedGrid grid_with_clearance(float clear) {
  duet::InflatedGrid g;
  g.resolution_m = 0.05f;
  g.origin = Eigen::Vector2f(0.0f, 0.0f);
  g.width = g.height = 40;
  g.clearance_m.assign(40 * 40, clear);
  g.traversable.assign(40 * 40, 1);
  g.state.assign(40 * 40, duet::CellState::kFree);
  return g;
}

duet::DwaSettings dwa() {
  duet::DwaSettings ds;
  ds.robot_radius_m = 0.2f;
  ds.safety_margin_m = 0.05f;
  ds.limits.max_v_mps = 0.5f;
  return ds;
}

}  // namespace

TEST(StallDetector, ReportsAContactAheadAfterTheTimeoutOnly) {
  duet::StallDetector stall(1.0, 0.3f);
  const duet::Pose2 robot{1.0f, 2.0f, static_cast<float>(M_PI / 2)};
  const duet::Twist forward{0.2f, 0.0f}, still{0.0f, 0.0f};
  EXPECT_FALSE(stall.update(forward, still, robot, 0.0));
  EXPECT_FALSE(stall.update(forward, still, robot, 0.95));
  const auto contact = stall.update(forward, still, robot, 1.0);
  ASSERT_TRUE(contact);
  EXPECT_NEAR(contact->x(), 1.0f, 1e-5f);
  EXPECT_NEAR(contact->y(), 2.3f, 1e-5f);
  // Starts over after a report, and whenever the robot moves or is not commanded forward.
  EXPECT_FALSE(stall.update(forward, still, robot, 1.5));
  EXPECT_FALSE(stall.update(forward, duet::Twist{0.1f, 0.0f}, robot, 2.6));
  EXPECT_FALSE(stall.update(forward, still, robot, 3.0));
  EXPECT_FALSE(stall.update(duet::Twist{0.01f, 0.0f}, still, robot, 3.5));
  EXPECT_FALSE(stall.update(forward, still, robot, 4.0));
  EXPECT_FALSE(stall.update(forward, still, duet::Pose2{NAN, 0.0f, 0.0f}, 5.5));  // no pose: no contact
}

TEST(SlowZone, SpeedFallsWithTheClearance) {
  const duet::SlowZone zone(0.6f, 0.1f);
  const duet::DwaSettings ds = dwa();  // margin 0.25 m
  const duet::Pose2 at{1.0f, 1.0f, 0.0f};
  EXPECT_FLOAT_EQ(zone.speed_limit(at, ds, grid_with_clearance(1.0f)), 0.5f);       // beyond the zone
  EXPECT_FLOAT_EQ(zone.speed_limit(at, ds, grid_with_clearance(INFINITY)), 0.5f);  // no obstacle at all
  EXPECT_FLOAT_EQ(zone.speed_limit(at, ds, grid_with_clearance(0.2f)), 0.1f);      // inside the margin
  EXPECT_NEAR(zone.speed_limit(at, ds, grid_with_clearance(0.425f)), 0.3f, 1e-5f); // halfway: linear
  EXPECT_FLOAT_EQ(zone.speed_limit(duet::Pose2{-5.0f, 1.0f, 0.0f}, ds, grid_with_clearance(1.0f)), 0.1f);  // off the map
  EXPECT_FLOAT_EQ(duet::SlowZone(0.0f, 0.1f).speed_limit(at, ds, grid_with_clearance(0.2f)), 0.5f);      // off
}

TEST(Escape, TurnsTowardsTheLargestClearanceThenCreeps) {
  duet::InflatedGrid g = grid_with_clearance(0.1f);  // inside the margin everywhere ...
  const Eigen::Vector2i c(20, 20);
  g.clearance_m[static_cast<std::size_t>(c.y()) * 40 + static_cast<std::size_t>(c.x() + 2)] = 0.5f;  // ... but 2 cells east
  const duet::DwaSettings ds = dwa();
  const duet::Pose2 facing_north{1.025f, 1.025f, static_cast<float>(M_PI / 2)};
  const auto turn = duet::Escape::step(facing_north, duet::Twist{}, g, false, ds);
  ASSERT_TRUE(turn);
  EXPECT_EQ(turn->v, 0.0f);
  EXPECT_LT(turn->omega, 0.0f);  // clockwise, towards east
  const auto creep = duet::Escape::step(duet::Pose2{1.025f, 1.025f, 0.0f}, duet::Twist{}, g, false, ds);
  ASSERT_TRUE(creep);
  EXPECT_GT(creep->v, 0.0f);
  EXPECT_LE(creep->v, 0.1f);
  // Outside the margin and not cornered: nothing to escape.
  EXPECT_FALSE(duet::Escape::step(facing_north, duet::Twist{}, grid_with_clearance(1.0f), false, ds));
}

TEST(CorneredWatch, CorneredAfterStayingNearOneSpot) {
  duet::CorneredWatch watch(1.0f);
  const Eigen::Vector2f spot(1.0f, 1.0f);
  bool cornered = false;
  for (int i = 0; i < 19; ++i) cornered = watch.update(spot + Eigen::Vector2f(0.004f * static_cast<float>(i), 0.0f), 0.05f);
  EXPECT_FALSE(cornered);
  EXPECT_TRUE(watch.update(spot, 0.05f));  // 20 periods of 0.05 s within 0.1 m
  EXPECT_FALSE(watch.update(spot + Eigen::Vector2f(0.2f, 0.0f), 0.05f));  // left the spot: starts over
  watch.reset();
  EXPECT_FALSE(duet::CorneredWatch(0.0f).update(spot, 100.0f));  // off
}
