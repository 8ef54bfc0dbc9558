/// @file push_robot.cpp
/// A robot fed by pushes (see push_robot.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/robot/push_robot.hpp>

#include <string>
#include <utility>

namespace duet {

void validate(const PushRobotSettings& s) {
  if (s.frame_queue < 1 || s.frame_queue > 1024)
    fail(ErrorCode::kInvalidArgument, "PushRobotSettings::frame_queue must be in [1, 1024], got " + std::to_string(s.frame_queue));
  if (s.odometry_queue < 1 || s.odometry_queue > 1000000)
    fail(ErrorCode::kInvalidArgument, "PushRobotSettings::odometry_queue must be in [1, 1e6], got " + std::to_string(s.odometry_queue));
}

PushRobot::PushRobot(std::size_t sensors, const PushRobotSettings& settings)
    : settings_((validate(settings), settings)), chassis_(*this) {
  if (sensors < 1 || sensors > 16)
    fail(ErrorCode::kInvalidArgument, "PushRobot: the sensor count must be in [1, 16], got " + std::to_string(sensors));
  for (std::size_t i = 0; i < sensors; ++i) {
    sensor_objs_.push_back(std::unique_ptr<PushSensor>(new PushSensor(*this, i)));
    ifaces_.push_back(sensor_objs_.back().get());
  }
  frames_.resize(sensors);
}

void PushRobot::push_frame(std::size_t sensor, double stamp_s, RgbdImage&& image) {
  if (sensor >= frames_.size())
    fail(ErrorCode::kInvalidArgument, "PushRobot: sensor " + std::to_string(sensor) + " out of range (" +
                                          std::to_string(frames_.size()) + " sensors)");
  RgbdImage dropped;  // freed outside the lock
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.frames_pushed;
    auto& q = frames_[sensor];
    if (q.size() >= settings_.frame_queue) {
      dropped = std::move(q.front().image);
      q.pop_front();
      ++stats_.frames_overflowed;
    }
    q.push_back(StampedRgbd{stamp_s, std::move(image)});
  }
}

void PushRobot::push_odometry(const OdometryMsg& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.odometry_pushed;
  if (odometry_.size() >= settings_.odometry_queue) {
    odometry_.pop_front();
    ++stats_.odometry_overflowed;
  }
  odometry_.push_back(msg);
}

RgbdImage PushRobot::spare_image() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (spare_.empty()) return {};
  RgbdImage image = std::move(spare_.back());
  spare_.pop_back();
  return image;
}

Twist PushRobot::latest_command() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return command_;
}

PushStats PushRobot::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void PushChassis::command(const Twist& cmd) {
  std::lock_guard<std::mutex> lock(robot_.mutex_);
  robot_.command_ = cmd;
}

std::vector<OdometryMsg> PushChassis::take_odometry() {
  std::vector<OdometryMsg> out;
  {
    std::lock_guard<std::mutex> lock(robot_.mutex_);
    out.assign(robot_.odometry_.begin(), robot_.odometry_.end());
    robot_.odometry_.clear();
  }
  const double origin = robot_.time_origin();
  for (OdometryMsg& m : out) m.stamp_s -= origin;  // a non-finite stamp stays non-finite: the guard drops it
  return out;
}

std::vector<StampedRgbd> PushSensor::take_frames() {
  std::vector<StampedRgbd> out;
  {
    std::lock_guard<std::mutex> lock(robot_.mutex_);
    auto& q = robot_.frames_[index_];
    out.reserve(q.size());
    for (StampedRgbd& f : q) out.push_back(std::move(f));
    q.clear();
  }
  const double origin = robot_.time_origin();
  for (StampedRgbd& f : out) f.stamp_s -= origin;
  return out;
}

void PushSensor::recycle(RgbdImage&& image) {
  constexpr std::size_t kSpares = 8;  // enough for two sensors' frames in flight
  std::lock_guard<std::mutex> lock(robot_.mutex_);
  if (robot_.spare_.size() < kSpares) robot_.spare_.push_back(std::move(image));
}

}  // namespace duet
