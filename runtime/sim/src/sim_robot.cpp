/// @file sim_robot.cpp
/// The simulated robot as a RobotSource (see sim_robot.hpp).
#include <duet/kernels/error.hpp>
#include <duet/sim/sim_robot.hpp>

#include <duet/runtime/config/seed_mix.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace duet::sim {
namespace {

ChassisSimSettings chassis_settings(const Profile& profile, const SimRobotSettings& s) {
  ChassisSimSettings c = s.chassis ? *s.chassis : ChassisSimSettings::from_profile(profile.chassis);
  // The Kobuki's odometry takes its heading from the gyro (kobuki_node's default).
  if (!s.chassis) c.gyro_heading = true;
  c.seed = mix(s.seed ^ 0xC4A551ull);
  return c;
}

}  // namespace

SimRgbdSensor::SimRgbdSensor(const RgbdRenderer& renderer, const SimChassis& chassis, SensorProfile sensor, double rate_hz,
                             std::uint64_t seed)
    : renderer_(renderer), chassis_(chassis), sensor_(std::move(sensor)), period_s_(0.0), seed_(seed) {
  if (!(std::isfinite(rate_hz) && rate_hz > 0.0 && rate_hz <= 1000.0))
    fail(ErrorCode::kInvalidArgument, "SimRgbdSensor '" + sensor_.name + "': rate_hz must be in (0, 1000], got " + std::to_string(rate_hz));
  period_s_ = 1.0 / rate_hz;
}

bool SimRgbdSensor::capture(double now_s) {
  if (now_s + 1e-9 < next_t_) return false;
  StampedRgbd f;
  f.stamp_s = now_s;
  if (!spare_.empty()) {
    f.image = std::move(spare_.back());
    spare_.pop_back();
  }
  Eigen::Isometry3f mount = sensor_.T_robot_optical();
  if (mount_error_rad_ != 0.0f) mount.linear() = Eigen::AngleAxisf(mount_error_rad_, Eigen::Vector3f::UnitZ()) * mount.linear();
  renderer_.render(sensor_, to_isometry(chassis_.true_pose()) * mount, mix(seed_ + 0x100000001B3ull * rendered_), f.image);
  ++rendered_;
  out_.push_back(std::move(f));
  while (next_t_ <= now_s + 1e-9) next_t_ += period_s_;
  return true;
}

std::vector<StampedRgbd> SimRgbdSensor::take_frames() {
  std::vector<StampedRgbd> out;
  out.swap(out_);
  return out;
}

void SimRgbdSensor::recycle(RgbdImage&& image) {
  if (spare_.size() < 4) spare_.push_back(std::move(image));
}

SimRobot::SimRobot(std::shared_ptr<const World> world, const Profile& profile, const SimRobotSettings& settings)
    : world_((world ? void() : fail(ErrorCode::kInvalidArgument, "SimRobot: no world"), world)),
      render_(settings.render),
      renderer_(*world_, settings.render),
      chassis_(world, chassis_settings(profile, settings), world->start, ChassisBody::from_profile(profile.chassis)) {
  for (std::size_t i = 0; i < profile.sensors.size(); ++i) {
    sensors_.push_back(std::make_unique<SimRgbdSensor>(renderer_, chassis_, profile.sensors[i], settings.sensor_rate_hz,
                                                       mix(settings.seed * 0x9E3779B97F4A7C15ull + i)));
    ifaces_.push_back(sensors_.back().get());
  }
}

bool SimRobot::open_door(const std::string& name) {
  const bool closed = std::any_of(world_->solids.begin(), world_->solids.end(), [&](const Solid& s) { return s.door && s.name == name; });
  if (!closed) return false;
  const std::string names[] = {name};
  rebuild(std::make_shared<const World>(with_doors_open(*world_, names)));
  return true;
}

void SimRobot::rebuild(std::shared_ptr<const World> world) {
  renderer_ = RgbdRenderer(*world, render_);  // the sensors keep their reference to renderer_
  chassis_.set_world(world);
  world_ = std::move(world);
}

void SimRobot::advance(double now_s) {
  if (!(now_s >= t_)) fail(ErrorCode::kInvalidArgument, "SimRobot::advance: time " + std::to_string(now_s) + " s is before " + std::to_string(t_) + " s");
  // Doors whose time has come open before the period (at most one rebuild per period).
  std::vector<std::string> due;
  for (const Solid& s : world_->solids)
    if (s.door && s.opens_at_s <= now_s) due.push_back(s.name);
  if (!due.empty()) rebuild(std::make_shared<const World>(with_doors_open(*world_, due)));
  double t_chassis = t_;
  for (;;) {
    double next = now_s;
    for (const auto& s : sensors_) next = std::min(next, s->next_due_s());
    if (next > t_chassis) {
      chassis_.advance(next - t_chassis);
      t_chassis = next;
    }
    for (auto& s : sensors_) (void)s->capture(t_chassis);
    if (t_chassis + 1e-9 >= now_s) break;
  }
  t_ = now_s;
}

std::size_t SimRobot::frames_rendered() const {
  std::size_t n = 0;
  for (const auto& s : sensors_) n += s->frames_rendered();
  return n;
}

RobotSourceKind sim_robot_source() {
  RobotSourceKind k;
  k.name = "sim";
  k.help = "the simulator: sim:WORLD - a built-in world (lab), a world YAML or a map_server map YAML (default: lab)";
  k.make = [](const Profile& profile, const RobotSourceRequest& request) -> std::unique_ptr<RobotSource> {
    World world = resolve_world(request.argument.empty() ? "lab" : request.argument);
    validate(world, world.source.empty() ? "world" : world.source);
    SimRobotSettings s;
    s.seed = request.seed;
    s.sensor_rate_hz = profile.runtime.map_rate_hz;
    return std::make_unique<SimRobot>(std::make_shared<const World>(std::move(world)), profile, s);
  };
  return k;
}

}  // namespace duet::sim
