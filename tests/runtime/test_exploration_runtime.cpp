// ExplorationRuntime on scripted robot interfaces (no simulator): synchronisation, map rate,
// counted drops when a sensor stops, idle without a map, and bad wiring.
#include <duet/kernels/error.hpp>
#include <duet/runtime/exploration_runtime.hpp>
#include <duet/runtime/profile.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace {

struct ScriptedChassis : duet::ChassisInterface {
  std::vector<duet::OdometryMsg> pending;
  std::vector<duet::Twist> commands;
  void command(const duet::Twist& cmd) override { commands.push_back(cmd); }
  std::vector<duet::OdometryMsg> take_odometry() override {
    std::vector<duet::OdometryMsg> out;
    out.swap(pending);
    return out;
  }
};

struct ScriptedSensor : duet::RgbdSensorInterface {
  std::vector<duet::StampedRgbd> pending;
  int recycled = 0;
  std::vector<duet::StampedRgbd> take_frames() override {
    std::vector<duet::StampedRgbd> out;
    out.swap(pending);
    return out;
  }
  void recycle(duet::RgbdImage&&) override { ++recycled; }
};

// A frame of a wall 2 m ahead (depth only), the profile's image size.
duet::StampedRgbd wall_frame(const duet::SensorProfile& s, double stamp) {
  duet::StampedRgbd f;
  f.stamp_s = stamp;
  f.image.width = s.intrinsics.width;
  f.image.height = s.intrinsics.height;
  f.image.depth.assign(static_cast<std::size_t>(f.image.width) * f.image.height,
                       static_cast<std::uint16_t>(2.0f * s.depth_units_per_m));
  return f;
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

TEST(ExplorationRuntime, ASilentSensorIsCountedNotFatal) {
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
  EXPECT_EQ(st.sets_integrated, 0u);
  EXPECT_GT(st.frame_drops, 50u);  // queue overflow of the front stream, counted
  EXPECT_EQ(rt.mapper().stats().observations, 0u);
  // No map: the explorer is idle and commands a stop.
  EXPECT_EQ(rt.explorer().state(), duet::ExplorerState::kIdle);
  for (const auto& c : chassis.commands) {
    EXPECT_EQ(c.v, 0.0f);
    EXPECT_EQ(c.omega, 0.0f);
  }
  // Non-finite and out-of-order stamps are dropped and counted, never integrated.
  chassis.pending.push_back({NAN, {}, {}});
  chassis.pending.push_back({1.0, {}, {}});
  rt.tick(5.1);
  EXPECT_GE(rt.synchronizer().stats(2).dropped_total(), 2u);
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
