// ExplorationRuntime on scripted robot interfaces (no simulator): synchronisation, map rate,
// counted drops when a sensor stops, idle without a map, and bad wiring.
#include <duet/kernels/error.hpp>
#include <duet/runtime/robot/exploration_runtime.hpp>
#include <duet/runtime/config/profile.hpp>

#include <gtest/gtest.h>

#include "scripted_robot.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace {
using duet_test::ScriptedChassis;
using duet_test::ScriptedSensor;
using duet_test::StandingRobot;
using duet_test::wall_frame;

duet::RuntimeSettings one_hertz(float recent_obstacles_s) {
  duet::RuntimeSettings rs;
  rs.sensor_rate_hz = 1.0;
  rs.pose_correction.enabled = false;
  rs.explorer.recent_obstacles_s = recent_obstacles_s;
  return rs;
}
}  // namespace

TEST(ExplorationRuntime, IntegratesSynchronizedSetsAtTheMapRate) {
  const duet::Profile profile = duet::builtin_profile("dual");
  ScriptedChassis chassis;
  ScriptedSensor front, right;
  duet::RgbdSensorInterface* sensors[] = {&front, &right};
  duet::RuntimeSettings rs;
  rs.sensor_rate_hz = 5.0;  // frames at 5 Hz, map at 1 Hz
  duet::ExplorationRuntime rt(profile, chassis, sensors, rs);
  for (int k = 0; k <= 200; ++k) {  // 10 s at 20 Hz
    const double t = 0.05 * k;
    // Odometry at 50 Hz, ending at t (the robot stands still at the origin).
    for (int j = 0; j < (k == 0 ? 1 : 5); ++j) chassis.pending.push_back({t - 0.02 * (k == 0 ? 0 : 4 - j), {}, {}});
    if (k % 4 == 0) {
      front.pending.push_back(wall_frame(profile.sensors[0], t));
      right.pending.push_back(wall_frame(profile.sensors[1], t));
    }
    rt.tick(t);
  }
  const auto& st = rt.stats();
  EXPECT_EQ(st.frames_received, 2u * 51u);
  EXPECT_EQ(st.frame_drops, 0u);
  // Sets at 5 Hz: one per map second integrated (t = 0, 1, ..., 9; the set at t = 10 may wait
  // for its successor), the rest counted as not integrated.
  EXPECT_GE(st.sets_integrated, 10u);
  EXPECT_LE(st.sets_integrated, 11u);
  EXPECT_GE(st.sets_integrated + st.sets_not_integrated, 50u);
  EXPECT_EQ(rt.mapper().stats().observations, st.sets_integrated);
  EXPECT_GT(rt.mapper().grid().known_cells(), 100u);  // the walls and the floor rays
  EXPECT_GT(front.recycled, 40);                      // buffers went back to the sensor
  EXPECT_EQ(chassis.commands.size(), 201u);           // one command per tick
  for (const auto& c : chassis.commands) EXPECT_TRUE(std::isfinite(c.v) && std::isfinite(c.omega));
}


// Recent obstacles (ExplorerSettings::recent_obstacles_s): the mapper's obstacle cells within
// recent_obstacle_range_m of the robot, kept in the odometry frame and placed in the map frame
// with the latest correction, one point per cell seen in at least two scans of the window. The
// robot stands still; the front wall is at x = 1.882 m in the robot frame (the Kinect sits
// 0.118 m behind the centre), the right one at y = -2 m. Then the pose is moved 1 m forward in
// the map frame (a correction: the odometry did not move): the remembered walls move with it,
// where the new frames put them too, while the map keeps the first copy. Then the front wall
// goes out of range (4 m): after the window, none of it is remembered.
TEST(ExplorationRuntime, RecentObstaclesMoveWithTheCorrectionAndAreForgotten) {
  StandingRobot r(one_hertz(3.0f));
  const duet::ExplorationRuntime& rt = r.rt;
  auto count = [&](float x_lo, float x_hi) {  // remembered points of the front wall (|y| < 0.5 m) in [x_lo, x_hi]
    int n = 0;
    for (const Eigen::Vector2f& q : rt.explorer().recent_obstacles()) n += std::fabs(q.y()) < 0.5f && q.x() >= x_lo && q.x() <= x_hi;
    return n;
  };
  r.run(0, 20);  // up to t = 0.95: the integration at t = 0 only - a cell needs two scans
  EXPECT_EQ(rt.stats().sets_integrated, 1u);
  EXPECT_TRUE(rt.explorer().recent_obstacles().empty());
  r.run(20, 61);  // integrations at t = 1, 2, 3
  ASSERT_GE(rt.stats().sets_integrated, 3u);
  const auto& recent = rt.explorer().recent_obstacles();
  ASSERT_FALSE(recent.empty());
  for (const Eigen::Vector2f& q : recent) EXPECT_LE(q.norm(), 3.0f + 0.05f);  // within range (cell centres)
  EXPECT_GT(count(1.80f, 1.95f), 10);
  EXPECT_EQ(count(0.0f, 1.80f) + count(1.95f, 10.0f), 0);
  int right_wall = 0;
  for (const Eigen::Vector2f& q : recent) right_wall += std::fabs(q.y() + 2.0f) < 0.08f;
  EXPECT_GT(right_wall, 10);
  // One point per cell, at its centre.
  std::vector<std::pair<int, int>> cells;
  for (const Eigen::Vector2f& q : recent) {
    const int cx = static_cast<int>(std::floor(q.x() / 0.05f)), cy = static_cast<int>(std::floor(q.y() / 0.05f));
    EXPECT_NEAR(q.x(), (cx + 0.5f) * 0.05f, 1e-4f);
    EXPECT_NEAR(q.y(), (cy + 0.5f) * 0.05f, 1e-4f);
    cells.emplace_back(cx, cy);
  }
  std::sort(cells.begin(), cells.end());
  EXPECT_EQ(std::unique(cells.begin(), cells.end()), cells.end());
  // The correction moves the pose 1 m forward: old and new points agree at x = 2.882 m.
  r.rt.override_pose(duet::Pose2{1.0f, 0.0f, 0.0f});
  r.run(61, 81);  // one more integration at t = 4
  EXPECT_GT(count(2.80f, 2.95f), 10);
  EXPECT_EQ(count(0.0f, 2.80f) + count(2.95f, 10.0f), 0);
  // The map still holds the wall where it was first seen.
  const duet::OccupancyGrid& g = r.rt.mapper().grid();
  const Eigen::Vector2i first = g.cell_of(Eigen::Vector2f(1.875f, 0.0f));
  EXPECT_GE(g.logodds()[g.index(first.x(), first.y())], r.profile.exploration.cells.occupied_logodds);
  // The front wall moves out of range: remembered for 3 s, then forgotten.
  r.front_depth = 4.0f;
  r.run(81, 101);  // t = 5: the scans of t = 2..4 are still within 3 s
  EXPECT_GT(count(2.80f, 2.95f), 10);
  r.run(101, 181);  // t = 9: only scans of t = 6..9 (front wall beyond 3 m)
  EXPECT_EQ(count(-10.0f, 10.0f), 0);
  EXPECT_FALSE(rt.explorer().recent_obstacles().empty());  // the right wall, still near
}

TEST(ExplorationRuntime, NoRecentObstaclesWhenTheWindowIsZero) {
  StandingRobot r(one_hertz(0.0f));
  r.run(0, 61);
  EXPECT_GE(r.rt.stats().sets_integrated, 3u);
  EXPECT_FALSE(r.rt.mapper().last_obstacles().empty());
  EXPECT_TRUE(r.rt.explorer().recent_obstacles().empty());
  EXPECT_EQ(r.rt.explorer().stats().recent_obstacle_cells, 0u);
}

TEST(ExplorationRuntime, ASilentSensorIsMappedAroundAndCounted) {
  const duet::Profile profile = duet::builtin_profile("dual");
  ScriptedChassis chassis;
  ScriptedSensor front, right;
  duet::RgbdSensorInterface* sensors[] = {&front, &right};
  duet::RuntimeSettings rs;
  rs.sensor_rate_hz = 30.0;
  duet::ExplorationRuntime rt(profile, chassis, sensors, rs);
  for (int k = 0; k <= 100; ++k) {
    const double t = 0.05 * k;
    chassis.pending.push_back({t, {}, {}});
    front.pending.push_back(wall_frame(profile.sensors[0], t));  // the right sensor never sends
    rt.tick(t);
  }
  const auto& st = rt.stats();
  // After 2.5 frame periods without a frame from it, the right sensor is silent: the runtime
  // adds a missing frame beside each front frame and maps with the front sensor alone (it
  // stalled the synchronizer for good before the input guard).
  EXPECT_EQ(st.input.sensor_silences, 1u);
  EXPECT_GT(st.input.missing_frames, 90u);
  EXPECT_GT(st.sets_integrated, 3u);
  EXPECT_EQ(st.sets_with_missing, st.sets_integrated + st.sets_not_integrated);
  EXPECT_GT(rt.mapper().stats().observations, 0u);
  EXPECT_FALSE(rt.events().empty());
  // Non-finite and out-of-order stamps are dropped and counted by the input guard, never integrated.
  chassis.pending.push_back({NAN, {}, {}});
  chassis.pending.push_back({1.0, {}, {}});
  rt.tick(5.1);
  EXPECT_EQ(rt.stats().input.odometry_invalid, 1u);
  EXPECT_EQ(rt.stats().input.odometry_out_of_order, 1u);
}

TEST(ExplorationRuntime, WiringErrors) {
  const duet::Profile profile = duet::builtin_profile("dual");
  ScriptedChassis chassis;
  ScriptedSensor one;
  duet::RgbdSensorInterface* too_few[] = {&one};
  EXPECT_THROW(duet::ExplorationRuntime(profile, chassis, too_few), duet::Error);
  duet::RgbdSensorInterface* with_null[] = {&one, nullptr};
  EXPECT_THROW(duet::ExplorationRuntime(profile, chassis, with_null), duet::Error);
  duet::RgbdSensorInterface* ok[] = {&one, &one};
  duet::RuntimeSettings bad;
  bad.map_rate_hz = 100.0;
  EXPECT_THROW(duet::ExplorationRuntime(profile, chassis, ok, bad), duet::Error);
}
