/// @file input_guard.cpp
/// The runtime's checks of its inputs (see input_guard.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/robot/input_guard.hpp>

#include <cmath>
#include <cstdio>
#include <numbers>

namespace duet {
namespace {

constexpr std::size_t kMaxEvents = 1000;

bool finite(const Pose2& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.theta); }
bool finite(const Twist& t) { return std::isfinite(t.v) && std::isfinite(t.omega); }

std::string fmt(const char* f, double a, double b = 0.0) {
  char buf[160];
  std::snprintf(buf, sizeof buf, f, a, b);
  return buf;
}

}  // namespace

void validate(const InputGuardSettings& s) {
  auto bad = [](const std::string& what) { fail(ErrorCode::kInvalidArgument, "InputGuardSettings::" + what); };
  if (s.clock_step_messages < 2 || s.clock_step_messages > 1000) bad("clock_step_messages must be in [2, 1000]");
  if (!(s.jump_speed_factor >= 1.0 && std::isfinite(s.jump_speed_factor))) bad("jump_speed_factor must be finite and >= 1");
  if (!(s.jump_margin_m >= 0.0f && std::isfinite(s.jump_margin_m))) bad("jump_margin_m must be finite and >= 0");
  if (!(s.jump_margin_rad >= 0.0f && std::isfinite(s.jump_margin_rad))) bad("jump_margin_rad must be finite and >= 0");
  if (!(s.garbled_step_m > 0.0f && std::isfinite(s.garbled_step_m))) bad("garbled_step_m must be finite and > 0");
  if (!(s.garbled_fraction > 0.0 && s.garbled_fraction <= 1.0)) bad("garbled_fraction must be in (0, 1]");
  if (!(s.sensor_timeout_periods >= 1.0 && std::isfinite(s.sensor_timeout_periods))) bad("sensor_timeout_periods must be finite and >= 1");
}

InputGuard::InputGuard(const Profile& profile, double sensor_rate_hz, const InputGuardSettings& settings)
    : settings_((validate(settings), settings)),
      sensors_(profile.sensors),
      max_v_(profile.chassis.max_linear_speed_mps),
      max_w_(profile.chassis.max_angular_speed_radps()),
      sensor_period_s_(1.0 / sensor_rate_hz),
      have_frame_(profile.sensors.size(), false),
      silent_(profile.sensors.size(), false),
      last_frame_t_(profile.sensors.size(), 0.0) {}

void InputGuard::log(double t, std::string what) {
  if (events_.size() < kMaxEvents) {
    events_.push_back({t, std::move(what)});
  } else {
    ++events_dropped_;
  }
}

void InputGuard::restart(double now_s, const std::string& why) {
  ++stats_.clock_restarts;
  log(now_s, why + ": synchronizer and odometry history restarted on the new time base");
  have_odom_ = false;
  have_any_frame_ = false;
  std::fill(have_frame_.begin(), have_frame_.end(), false);
  std::fill(silent_.begin(), silent_.end(), false);
}

InputGuard::Verdict InputGuard::odometry(OdometryMsg& m, double now_s) {
  if (!std::isfinite(m.stamp_s) || !finite(m.pose) || !finite(m.twist)) {
    if (stats_.odometry_invalid++ == 0) log(now_s, "odometry with a non-finite stamp, pose or twist: dropped (and every later one, counted)");
    return Verdict::kDrop;
  }
  if (have_odom_) {
    if (!(m.stamp_s > last_odom_t_)) {
      // Behind the last accepted stamp: a message out of order (dropped), unless the clock
      // stepped back - then every message is behind, in order among themselves: after
      // clock_step_messages such in a row, a new time base.
      const bool in_order = behind_ == 0 || m.stamp_s > last_behind_t_;
      behind_ = in_order && m.stamp_s < last_odom_t_ ? behind_ + 1 : 0;
      last_behind_t_ = m.stamp_s;
      if (behind_ >= settings_.clock_step_messages) {
        behind_ = 0;
        restart(now_s, fmt("odometry stamps stepped back %.3f s", last_odom_t_ - m.stamp_s));
        return Verdict::kRestart;
      }
      if (stats_.odometry_out_of_order++ == 0) log(now_s, "odometry out of order or repeated: dropped (and every later one, counted)");
      return Verdict::kDrop;
    }
    behind_ = 0;
  }
  Pose2 fixed = compose(odom_fix_, m.pose);
  if (have_odom_) {
    // Farther than the chassis can go in the time since the last message: a jump, not motion.
    const double dt = m.stamp_s - last_odom_t_;
    const Pose2 step = compose(inverse(last_odom_), fixed);
    const double reach = settings_.jump_speed_factor * max_v_ * dt + settings_.jump_margin_m;
    const double turn = settings_.jump_speed_factor * max_w_ * dt + settings_.jump_margin_rad;
    const double d = std::hypot(step.x, step.y);
    if (d > reach || std::fabs(std::remainder(step.theta, 2.0 * std::numbers::pi)) > turn) {
      odom_fix_ = compose(last_odom_, inverse(m.pose));  // this message now continues the last one
      fixed = last_odom_;
      ++stats_.odometry_jumps;
      log(now_s, fmt("odometry jumped %.3f m / %.1f deg in one message: absorbed (the pose continues; scan matching corrects it)", d,
                     std::fabs(std::remainder(step.theta, 2.0 * std::numbers::pi)) * 180.0 / std::numbers::pi));
    }
  }
  m.pose = fixed;
  last_odom_ = fixed;
  last_odom_t_ = m.stamp_s;
  have_odom_ = true;
  return Verdict::kAccept;
}

bool InputGuard::garbled(const RgbdImage& im, float units_per_m, bool& empty) const {
  // Neighbouring pixels along every 8th row: in a real scene most valid neighbours lie on one
  // surface (a few cm apart at 5 m), edges are a small share.
  const double step = static_cast<double>(settings_.garbled_step_m) * units_per_m;
  std::size_t pairs = 0, edges = 0, valid = 0;
  for (int y = 0; y < im.height; y += 8) {
    const std::uint16_t* row = im.depth.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(im.width);
    for (int x = 0; x + 1 < im.width; ++x) {
      if (row[x] != 0) ++valid;
      if (row[x] == 0 || row[x + 1] == 0) continue;
      ++pairs;
      if (std::fabs(static_cast<double>(row[x]) - static_cast<double>(row[x + 1])) > step) ++edges;
    }
  }
  empty = valid == 0;
  return pairs > 0 && static_cast<double>(edges) > settings_.garbled_fraction * static_cast<double>(pairs);
}

InputGuard::Verdict InputGuard::frame(std::size_t i, const StampedRgbd& f, double now_s, bool& missing) {
  missing = false;
  const SensorProfile& s = sensors_.at(i);
  const RgbdImage& im = f.image;
  const std::size_t px = static_cast<std::size_t>(s.intrinsics.width) * static_cast<std::size_t>(s.intrinsics.height);
  if (!std::isfinite(f.stamp_s) || im.width != s.intrinsics.width || im.height != s.intrinsics.height || im.depth.size() != px ||
      (!im.rgb.empty() && im.rgb.size() != 3 * px)) {
    if (stats_.frames_invalid++ == 0)
      log(now_s, "sensor " + std::to_string(i + 1) + ": a frame with a non-finite stamp or the wrong size: dropped (and every later one, counted)");
    return Verdict::kDrop;
  }
  if (have_frame_[i]) {
    if (!(f.stamp_s > last_frame_t_[i])) {  // a clock step back restarts on the odometry (above)
      if (stats_.frames_out_of_order++ == 0)
        log(now_s, "sensor " + std::to_string(i + 1) + ": a frame out of order or repeated: dropped (and every later one, counted)");
      return Verdict::kDrop;
    }
  }
  if (silent_[i]) {
    silent_[i] = false;
    log(now_s, "sensor " + std::to_string(i + 1) + " delivers again");
  }
  if (!have_any_frame_) first_frame_t_ = f.stamp_s;
  have_any_frame_ = true;
  have_frame_[i] = true;
  last_frame_t_[i] = f.stamp_s;
  bool empty = false;
  if (garbled(im, s.depth_units_per_m, empty)) {
    if (stats_.frames_garbled++ == 0)
      log(now_s, "sensor " + std::to_string(i + 1) + ": depth that is noise, not a scene: mapped as a missing frame (and every later one, counted)");
    missing = true;
  } else if (empty) {
    if (stats_.frames_empty++ == 0) log(now_s, "sensor " + std::to_string(i + 1) + ": a frame with no depth return (and every later one, counted)");
  }
  return Verdict::kAccept;
}

std::vector<std::size_t> InputGuard::silent_sensors(std::size_t from_sensor, double stamp, double now_s) {
  std::vector<std::size_t> out;
  const double timeout = settings_.sensor_timeout_periods * sensor_period_s_;
  for (std::size_t j = 0; j < sensors_.size(); ++j) {
    if (j == from_sensor) continue;
    // Not heard from yet: silent only once the others have delivered for the timeout.
    const double last = have_frame_[j] ? last_frame_t_[j] : first_frame_t_;
    if (!silent_[j] && stamp - last <= timeout) continue;
    if (!silent_[j]) {
      silent_[j] = true;
      ++stats_.sensor_silences;
      log(now_s, "sensor " + std::to_string(j + 1) + fmt(" silent for %.2f s: mapping with the others", stamp - last));
    }
    if (have_frame_[j] && !(stamp > last_frame_t_[j])) continue;
    have_frame_[j] = true;
    last_frame_t_[j] = stamp;
    ++stats_.missing_frames;
    out.push_back(j);
  }
  return out;
}

}  // namespace duet
