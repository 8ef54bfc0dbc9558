#pragma once
// Scripted robot interfaces for runtime tests (no simulator): a chassis that records commands
// and hands out queued odometry, sensors that hand out queued frames, and a robot standing at
// the odometry origin between two walls.
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/robot/exploration_runtime.hpp>
#include <duet/runtime/robot/robot_io.hpp>

#include <algorithm>
#include <cstdint>
#include <mutex>
#include <vector>

namespace duet_test {

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
inline duet::StampedRgbd wall_frame(const duet::SensorProfile& s, double stamp) {
  duet::StampedRgbd f;
  f.stamp_s = stamp;
  f.image.width = s.intrinsics.width;
  f.image.height = s.intrinsics.height;
  f.image.depth.assign(static_cast<std::size_t>(f.image.width) * f.image.height,
                       static_cast<std::uint16_t>(2.0f * s.depth_units_per_m));
  return f;
}

// Paints `f` with a fixed pattern of 8 x 8 px grey blocks (a textured wall: corners for ORB).
inline void texture(duet::StampedRgbd& f, std::uint32_t seed) {
  f.image.rgb.resize(static_cast<std::size_t>(f.image.width) * f.image.height * 3);
  for (int v = 0; v < f.image.height; ++v)
    for (int u = 0; u < f.image.width; ++u) {
      std::uint32_t h = seed ^ (static_cast<std::uint32_t>(u / 8) * 73856093u) ^ (static_cast<std::uint32_t>(v / 8) * 19349663u);
      h = (h ^ (h >> 13)) * 0x5bd1e995u;
      const auto g = static_cast<std::uint8_t>((h >> 16) & 0xff);
      const std::size_t i = (static_cast<std::size_t>(v) * f.image.width + u) * 3;
      f.image.rgb[i] = f.image.rgb[i + 1] = f.image.rgb[i + 2] = g;
    }
}

// A robot standing at the odometry origin, ticked at 20 Hz with odometry at every tick and a
// frame pair once a second: the front Kinect sees a wall front_depth ahead, the right one a
// wall 2 m to the right.
struct StandingRobot {
  duet::Profile profile = duet::builtin_profile("dual");
  ScriptedChassis chassis;
  ScriptedSensor front, right;
  duet::RgbdSensorInterface* sensors[2] = {&front, &right};
  duet::ExplorationRuntime rt;
  float front_depth = 2.0f;
  bool textured = false;  ///< the walls painted (texture()): vision tracks them
  explicit StandingRobot(const duet::RuntimeSettings& rs) : rt(profile, chassis, sensors, rs) {}
  void run(int from, int to) {  // ticks [from, to) at t = 0.05 k
    for (int k = from; k < to; ++k) {
      const double t = 0.05 * k;
      chassis.pending.push_back({t, {}, {}});
      if (k % 20 == 0) {
        duet::StampedRgbd f = wall_frame(profile.sensors[0], t);
        std::fill(f.image.depth.begin(), f.image.depth.end(), static_cast<std::uint16_t>(front_depth * 1000.0f));
        duet::StampedRgbd g = wall_frame(profile.sensors[1], t);
        if (textured) {
          texture(f, 1);
          texture(g, 2);
        }
        front.pending.push_back(std::move(f));
        right.pending.push_back(std::move(g));
      }
      rt.tick(t);
    }
  }
};

}  // namespace duet_test
