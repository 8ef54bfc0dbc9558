/// @file push_robot.cpp
/// A robot fed by pushes (see push_robot.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/robot/push_robot.hpp>

#include <cmath>
#include <string>
#include <utility>

namespace duet {

void validate(const PushRobotSettings& s) {
  if (s.frame_queue < 1 || s.frame_queue > 1024)
    fail(ErrorCode::kInvalidArgument, "PushRobotSettings::frame_queue must be in [1, 1024], got " + std::to_string(s.frame_queue));
  if (s.gyro_queue < 1 || s.gyro_queue > 1000000)
    fail(ErrorCode::kInvalidArgument, "PushRobotSettings::gyro_queue must be in [1, 1e6], got " + std::to_string(s.gyro_queue));
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

void PushRobot::push_gyro(double stamp_s, float yaw_rate_rps) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.gyro_pushed;
  if (!std::isfinite(stamp_s) || !std::isfinite(yaw_rate_rps)) {
    ++stats_.gyro_invalid;
    return;
  }
  if (gyro_.size() >= settings_.gyro_queue) {
    gyro_.pop_front();
    ++stats_.gyro_overflowed;
  }
  gyro_.emplace_back(stamp_s, yaw_rate_rps);
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
  std::deque<std::pair<double, float>> gyro;
  {
    std::lock_guard<std::mutex> lock(robot_.mutex_);
    out.assign(robot_.odometry_.begin(), robot_.odometry_.end());
    robot_.odometry_.clear();
    gyro.swap(robot_.gyro_);
  }
  const double origin = robot_.time_origin();
  for (OdometryMsg& m : out) m.stamp_s -= origin;  // a non-finite stamp stays non-finite: the guard drops it
  for (auto& g : gyro) g.first -= origin;
  robot_.fuse(out, std::move(gyro));
  return out;
}

void PushRobot::fuse(std::vector<OdometryMsg>& msgs, std::deque<std::pair<double, float>>&& gyro) {
  std::uint64_t invalid = 0, gaps = 0;
  for (const auto& g : gyro) {
    if (!(g.first > last_gyro_t_)) {
      ++invalid;
      continue;
    }
    last_gyro_t_ = g.first;
    gyro_hist_.push_back(g);
    gyro_on_ = true;
  }
  // The gyro's heading change over (t0, t1]: each sample's rate holds back to the sample before
  // it; nullopt when the samples do not cover the interval.
  // A gyro that lags the wheels by up to kHold has its last rate held to t1.
  constexpr double kHold = 0.05;
  auto integral = [&](double t0, double t1) -> std::optional<double> {
    if (gyro_hist_.size() < 2 || gyro_hist_.front().first > t0 || gyro_hist_.back().first < t1 - kHold) return std::nullopt;
    double sum = 0.0;
    for (std::size_t i = 1; i < gyro_hist_.size(); ++i) {
      const double a = std::max(t0, gyro_hist_[i - 1].first), b = std::min(t1, gyro_hist_[i].first);
      if (b > a) sum += static_cast<double>(gyro_hist_[i].second) * (b - a);
    }
    const double held_from = std::max(t0, gyro_hist_.back().first);
    if (t1 > held_from) sum += static_cast<double>(gyro_hist_.back().second) * (t1 - held_from);
    return sum;
  };
  if (gyro_on_) {
    for (OdometryMsg& m : msgs) {
      const bool valid = std::isfinite(m.stamp_s) && std::isfinite(m.pose.x) && std::isfinite(m.pose.y) && std::isfinite(m.pose.theta);
      if (!valid || (last_wheel_ && !(m.stamp_s > last_wheel_->stamp_s))) continue;  // the input guard drops it
      const OdometryMsg raw = m;
      if (!last_wheel_) {
        fused_ = m.pose;
      } else {
        const Pose2& p = last_wheel_->pose;
        const float c = std::cos(p.theta), sn = std::sin(p.theta);
        const float dx = c * (m.pose.x - p.x) + sn * (m.pose.y - p.y);    // the wheels' step, in their frame
        const float dy = -sn * (m.pose.x - p.x) + c * (m.pose.y - p.y);
        const float dtheta_wheels = std::remainder(m.pose.theta - p.theta, 6.28318530717958647692f);
        const std::optional<double> g = integral(last_wheel_->stamp_s, m.stamp_s);
        if (!g) ++gaps;
        const float dtheta = g ? static_cast<float>(*g) : dtheta_wheels;
        // The step's distance along the chord, turned by the gyro's half change instead of the wheels'.
        const float along = dx * std::cos(0.5f * dtheta_wheels) + dy * std::sin(0.5f * dtheta_wheels);
        const float h = fused_.theta + 0.5f * dtheta;
        fused_ = Pose2{fused_.x + along * std::cos(h), fused_.y + along * std::sin(h),
                       std::remainder(fused_.theta + dtheta, 6.28318530717958647692f)};
        const double dt = m.stamp_s - last_wheel_->stamp_s;
        if (g && dt > 0.0) m.twist.omega = static_cast<float>(*g / dt);
      }
      m.pose = fused_;
      last_wheel_ = raw;
    }
    // Samples before the last wheel message (but the one that bounds it) are no longer needed.
    const double keep_from = last_wheel_ ? last_wheel_->stamp_s : -1e300;
    while (gyro_hist_.size() > 1 && gyro_hist_[1].first <= keep_from) gyro_hist_.pop_front();
    while (gyro_hist_.size() > settings_.gyro_queue) gyro_hist_.pop_front();
  }
  if (invalid || gaps) {
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.gyro_invalid += invalid;
    stats_.gyro_gaps += gaps;
  }
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
