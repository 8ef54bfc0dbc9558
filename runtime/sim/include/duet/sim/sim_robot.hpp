#pragma once
/// @file sim_robot.hpp
/// The simulated robot as a RobotSource (robot_source.hpp): a SimChassis in a World and one
/// SimRgbdSensor per profile sensor, rendering from the chassis' true pose. advance(t) moves the
/// chassis on to t, stopping at every instant a sensor is due (30 Hz frames fall between 20 Hz
/// control ticks), where that sensor renders. SimExplore runs it with scoring; `duet run
/// --robot sim:WORLD` runs it as any other source.
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/robot/robot_io.hpp>
#include <duet/runtime/robot/robot_source.hpp>
#include <duet/sim/chassis.hpp>
#include <duet/sim/renderer.hpp>
#include <duet/sim/world.hpp>

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace duet::sim {

/// A simulated RGB-D sensor on a SimChassis: renders the world from the chassis' true pose
/// when its period is due (capture()), and publishes the frame through the
/// RgbdSensorInterface. Frame noise is seeded from (seed, frame index).
class SimRgbdSensor final : public RgbdSensorInterface {
 public:
  /// `renderer` and `chassis` must outlive the sensor; rate_hz in (0, 1000].
  SimRgbdSensor(const RgbdRenderer& renderer, const SimChassis& chassis, SensorProfile sensor, double rate_hz,
                std::uint64_t seed);
  /// Renders a frame stamped now_s if one is due (the first at t = 0). Returns true if it rendered.
  bool capture(double now_s);
  [[nodiscard]] std::vector<StampedRgbd> take_frames() override;
  void recycle(RgbdImage&& image) override;
  [[nodiscard]] std::size_t frames_rendered() const noexcept { return rendered_; }
  /// When the next frame is due [s].
  [[nodiscard]] double next_due_s() const noexcept { return next_t_; }
  /// FAULT INJECTION (extrinsics): the sensor's true mount is yawed by this about its own
  /// position [rad] (the runtime still uses the profile's). 0 = as the profile says.
  void set_mount_error(float yaw_rad) noexcept { mount_error_rad_ = yaw_rad; }

 private:
  const RgbdRenderer& renderer_;
  const SimChassis& chassis_;
  SensorProfile sensor_;
  double period_s_;
  double next_t_ = 0.0;
  std::uint64_t seed_;
  float mount_error_rad_ = 0.0f;
  std::size_t rendered_ = 0;
  std::vector<StampedRgbd> out_;
  std::vector<RgbdImage> spare_;
};

struct SimRobotSettings {
  std::uint64_t seed = 1;        ///< seeds the chassis noise and each sensor's frame noise
  double sensor_rate_hz = 1.0;   ///< render rate of every sensor [Hz], (0, 1000]
  RenderSettings render;
  /// Chassis simulation: from the profile's chassis (limits, odometry rate) with the gyro
  /// heading of a Kobuki when unset; its seed is replaced by a value derived from `seed`.
  std::optional<ChassisSimSettings> chassis;
};

class SimRobot final : public RobotSource {
 public:
  /// `world`: validated by the caller (sim::validate), shared with the renderer and the chassis.
  /// Throws duet::Error(kInvalidArgument) for invalid settings or a start pose that collides.
  SimRobot(std::shared_ptr<const World> world, const Profile& profile, const SimRobotSettings& settings);
  SimRobot(const SimRobot&) = delete;
  SimRobot& operator=(const SimRobot&) = delete;

  [[nodiscard]] ChassisInterface& chassis() override { return chassis_; }
  [[nodiscard]] std::span<RgbdSensorInterface* const> sensors() override { return ifaces_; }
  /// Moves on to now_s (>= the last call's time): physics, odometry and due frames.
  void advance(double now_s) override;

  [[nodiscard]] const SimChassis& sim_chassis() const noexcept { return chassis_; }
  /// FAULT INJECTION: the simulated parts themselves (kidnap, extrinsics).
  [[nodiscard]] SimChassis& sim_chassis() noexcept { return chassis_; }
  [[nodiscard]] SimRgbdSensor& sim_sensor(std::size_t i) { return *sensors_.at(i); }
  [[nodiscard]] std::size_t frames_rendered() const;
  [[nodiscard]] double now_s() const noexcept { return t_; }
  /// Opens the closed door (Solid::door) called `name` now: it is gone from the frames and the
  /// chassis' collisions (the renderer's scene is rebuilt). Doors with an opening time open by
  /// themselves in advance(). Returns false if no closed door has that name.
  bool open_door(const std::string& name);
  /// The world as it stands now (doors opened so far removed).
  [[nodiscard]] const World& world() const noexcept { return *world_; }

 private:
  void rebuild(std::shared_ptr<const World> world);

  std::shared_ptr<const World> world_;
  RenderSettings render_;
  RgbdRenderer renderer_;
  SimChassis chassis_;
  std::vector<std::unique_ptr<SimRgbdSensor>> sensors_;
  std::vector<RgbdSensorInterface*> ifaces_;
  double t_ = 0.0;
};

/// A "sim" source for a registry: its argument is a world (a built-in name, a world YAML or a
/// map_server map YAML; empty: the lab), rendered at the profile's map rate.
[[nodiscard]] RobotSourceKind sim_robot_source();

}  // namespace duet::sim
