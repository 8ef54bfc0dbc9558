// The simulated differential-drive chassis (see chassis.hpp for the model).
#include <duet/kernels/error.hpp>
#include <duet/sim/chassis.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

namespace duet::sim {
namespace {

/// A standard normal draw: Box-Muller on 53-bit uniforms (portable across libraries).
double standard_normal(std::mt19937_64& g) {
  const double u1 = (static_cast<double>(g() >> 11) + 1.0) * 0x1p-53;  // (0, 1]
  const double u2 = static_cast<double>(g() >> 11) * 0x1p-53;          // [0, 1)
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

void bad(const char* type, const char* key, double v, const char* range) {
  fail(ErrorCode::kInvalidArgument,
       std::string(type) + "." + key + " = " + std::to_string(v) + " is outside " + range);
}

// v in [lo, hi] and finite (lo_open / hi_open: exclusive ends).
bool in_range(double v, double lo, double hi, bool lo_open = false, bool hi_open = false) {
  if (!std::isfinite(v)) return false;
  if (lo_open ? !(v > lo) : !(v >= lo)) return false;
  if (hi_open ? !(v < hi) : !(v <= hi)) return false;
  return true;
}

float clampf(float x, float lo, float hi) { return std::min(std::max(x, lo), hi); }

// Moves `from` toward `to` by at most `max_step`.
float approach(float from, float to, float max_step) { return from + clampf(to - from, -max_step, max_step); }

}  // namespace

ChassisSimSettings ChassisSimSettings::from_profile(const ChassisProfile& profile) {
  ChassisSimSettings s;
  s.max_linear_speed_mps = profile.max_linear_speed_mps;
  s.max_angular_speed_radps = profile.max_angular_speed_radps();
  s.wheel_base_m = profile.wheel_base_m;
  s.odometry_rate_hz = profile.odometry_rate_hz;
  if (std::isfinite(profile.odometry_rate_hz) && profile.odometry_rate_hz > 0.0f) {
    const double period = 1.0 / static_cast<double>(profile.odometry_rate_hz);
    const double n = std::max(1.0, std::ceil(period / 0.005 - 1e-9));
    s.physics_step_s = period / n;
  }
  return s;
}

void validate(const ChassisSimSettings& s) {
  constexpr const char* k = "ChassisSimSettings";
  if (!in_range(s.max_linear_speed_mps, 0.0, 10.0, true)) bad(k, "max_linear_speed_mps", s.max_linear_speed_mps, "(0, 10]");
  if (!in_range(s.max_angular_speed_radps, 0.0, 100.0, true))
    bad(k, "max_angular_speed_radps", s.max_angular_speed_radps, "(0, 100]");
  if (!in_range(s.max_linear_accel_mps2, 0.0, 1e4, true))
    bad(k, "max_linear_accel_mps2", s.max_linear_accel_mps2, "(0, 1e4]");
  if (!in_range(s.max_angular_accel_radps2, 0.0, 1e4, true))
    bad(k, "max_angular_accel_radps2", s.max_angular_accel_radps2, "(0, 1e4]");
  if (!in_range(s.physics_step_s, 1e-5, 0.1)) bad(k, "physics_step_s", s.physics_step_s, "[1e-5, 0.1]");
  if (!in_range(s.odometry_rate_hz, 0.0, 1000.0, true)) bad(k, "odometry_rate_hz", s.odometry_rate_hz, "(0, 1000]");
  const double ratio = 1.0 / static_cast<double>(s.odometry_rate_hz) / s.physics_step_s;
  const double n = std::round(ratio);
  if (n < 1.0 || std::fabs(ratio - n) > 1e-6 * ratio)
    fail(ErrorCode::kInvalidArgument,
         "ChassisSimSettings.odometry_rate_hz = " + std::to_string(s.odometry_rate_hz) +
             ": the odometry period must be an integer multiple (>= 1) of physics_step_s = " +
             std::to_string(s.physics_step_s) + " s");
  if (!in_range(s.wheel_base_m, 0.0, 5.0, true)) bad(k, "wheel_base_m", s.wheel_base_m, "(0, 5]");
  if (!in_range(s.wheel_slip_std, 0.0, 0.5)) bad(k, "wheel_slip_std", s.wheel_slip_std, "[0, 0.5]");
  if (!in_range(s.wheel_slip_correlation_s, 0.0, 100.0))
    bad(k, "wheel_slip_correlation_s", s.wheel_slip_correlation_s, "[0, 100]");
  if (!in_range(s.wheel_base_bias, -0.2, 0.2)) bad(k, "wheel_base_bias", s.wheel_base_bias, "[-0.2, 0.2]");
  if (!in_range(s.encoder_noise_m, 0.0, 0.01)) bad(k, "encoder_noise_m", s.encoder_noise_m, "[0, 0.01]");
  if (!in_range(s.gyro_noise_density, 0.0, 0.01)) bad(k, "gyro_noise_density", s.gyro_noise_density, "[0, 0.01]");
  if (!in_range(s.gyro_bias_std_radps, 0.0, 0.1)) bad(k, "gyro_bias_std_radps", s.gyro_bias_std_radps, "[0, 0.1]");
  if (!in_range(s.contact_release_m, 0.0, 1.0)) bad(k, "contact_release_m", s.contact_release_m, "[0, 1]");
}

ChassisBody ChassisBody::from_profile(const ChassisProfile& profile) {
  ChassisBody b;
  b.radius_m = profile.radius_m;
  return b;
}

void validate(const ChassisBody& b) {
  constexpr const char* k = "ChassisBody";
  if (!in_range(b.radius_m, 0.0, 5.0, true)) bad(k, "radius_m", b.radius_m, "(0, 5]");
  if (!in_range(b.z_low_m, 0.0, 10.0, false, true)) bad(k, "z_low_m", b.z_low_m, "[0, 10)");
  if (!in_range(b.z_high_m, b.z_low_m, 10.0, true)) bad(k, "z_high_m", b.z_high_m, "(z_low_m, 10]");
}

SimChassis::SimChassis(std::shared_ptr<const World> world, const ChassisSimSettings& settings, const Pose2& start,
                       const ChassisBody& body)
    : world_(std::move(world)), settings_(settings), body_(body), rng_(settings.seed) {
  if (!world_) fail(ErrorCode::kInvalidArgument, "SimChassis: world is null");
  solids_ = SolidIndex(*world_);
  validate(settings_);
  validate(body_);
  if (!std::isfinite(start.x) || !std::isfinite(start.y) || !std::isfinite(start.theta))
    fail(ErrorCode::kInvalidArgument, "SimChassis: the start pose is not finite");
  h_ = settings_.physics_step_s;
  steps_per_odom_ =
      static_cast<std::uint64_t>(std::llround(1.0 / static_cast<double>(settings_.odometry_rate_hz) / h_));
  true_pose_ = start;
  true_pose_.theta = std::remainder(start.theta, 6.283185307179586f);
  odom_pose_ = true_pose_;
  if (collides_at(true_pose_, 0.0f))
    fail(ErrorCode::kInvalidArgument,
         "SimChassis: the start pose (" + std::to_string(start.x) + ", " + std::to_string(start.y) +
             ") collides with " + world_->name + " (or is off its floor) for a robot of radius " +
             std::to_string(body_.radius_m) + " m");
  // The slip process starts in its stationary distribution.
  slip_l_ = settings_.wheel_slip_std * normal();
  slip_r_ = settings_.wheel_slip_std * normal();
  odometry_.push_back(OdometryMsg{0.0, odom_pose_, Twist{}});
  if (settings_.gyro_heading) {
    // The gyro's bias: its own generator, so enabling the gyro does not shift the wheel noise.
    std::mt19937_64 g(settings_.seed ^ 0x9E3779B97F4A7C15ull);
    gyro_bias_ = static_cast<float>(settings_.gyro_bias_std_radps * standard_normal(g));
    gyro_rng_.seed(settings_.seed ^ 0xD1B54A32D192ED03ull);
    gyro_step_std_ = static_cast<float>(static_cast<double>(settings_.gyro_noise_density) / std::sqrt(h_));
  }
}

void SimChassis::set_world(std::shared_ptr<const World> world) {
  if (!world) fail(ErrorCode::kInvalidArgument, "SimChassis::set_world: world is null");
  world_ = std::move(world);
  solids_ = SolidIndex(*world_);
}

double SimChassis::normal() { return standard_normal(rng_); }

bool SimChassis::collides_at(const Pose2& p, float extra_radius) const {
  return solids_.collides(*world_, Eigen::Vector2f(p.x, p.y), body_.radius_m + extra_radius, body_.z_low_m, body_.z_high_m);
}

void SimChassis::command(const Twist& cmd) {
  if (std::isfinite(cmd.v) && std::isfinite(cmd.omega)) {
    command_ = cmd;
  } else {
    command_ = Twist{};
    ++invalid_commands_;
  }
  blocked_ = false;
}

void SimChassis::advance(double dt_s) {
  if (!std::isfinite(dt_s) || dt_s < 0.0 || dt_s > 3600.0)
    fail(ErrorCode::kInvalidArgument, "SimChassis::advance: dt_s = " + std::to_string(dt_s) + " is outside [0, 3600]");
  now_s_ += dt_s;
  // Every step that ends at or before now_s_ (a tolerance for the rounding of summed dt).
  while (static_cast<double>(steps_ + 1) * h_ <= now_s_ + 1e-9 * h_) step();
}

void SimChassis::step() {
  const auto& s = settings_;
  const float h = static_cast<float>(h_);
  // 1.-2. Clamp the held command to the velocity limits; follow it within the acceleration limits.
  Twist target;
  if (!blocked_) {
    target.v = clampf(command_.v, -s.max_linear_speed_mps, s.max_linear_speed_mps);
    target.omega = clampf(command_.omega, -s.max_angular_speed_radps, s.max_angular_speed_radps);
  }
  actual_.v = approach(actual_.v, target.v, s.max_linear_accel_mps2 * h);
  actual_.omega = approach(actual_.omega, target.omega, s.max_angular_accel_radps2 * h);

  // Random draws: always four per step, in this order, so the stream never depends on the path.
  const double n_slip_l = normal(), n_slip_r = normal();
  const double n_enc_l = normal(), n_enc_r = normal();
  if (s.wheel_slip_correlation_s > 0.0f) {
    const double phi = std::exp(-h_ / static_cast<double>(s.wheel_slip_correlation_s));
    const double q = std::sqrt(std::max(0.0, 1.0 - phi * phi)) * s.wheel_slip_std;
    slip_l_ = phi * slip_l_ + q * n_slip_l;
    slip_r_ = phi * slip_r_ + q * n_slip_r;
  } else {
    slip_l_ = s.wheel_slip_std * n_slip_l;
    slip_r_ = s.wheel_slip_std * n_slip_r;
  }
  // Encoder noise with the given std per odometry period: per step std / sqrt(steps per period).
  const double enc_std = s.encoder_noise_m / std::sqrt(static_cast<double>(steps_per_odom_));

  // 3. Nominal wheel rim speeds (what the wheel controller drives and the encoders count).
  const float b = s.wheel_base_m;
  const float u_l = actual_.v - actual_.omega * (0.5f * b);
  const float u_r = actual_.v + actual_.omega * (0.5f * b);
  // 4. Ground speeds with slip; effective wheel base with its bias.
  const float g_l = u_l * static_cast<float>(1.0 + slip_l_);
  const float g_r = u_r * static_cast<float>(1.0 + slip_r_);
  const Twist truth{0.5f * (g_l + g_r), (g_r - g_l) / (b * (1.0f + s.wheel_base_bias))};
  // Measured wheel speeds and the nominal kinematics (what the robot's odometry computes).
  const float m_l = u_l + static_cast<float>(enc_std * n_enc_l / h_);
  const float m_r = u_r + static_cast<float>(enc_std * n_enc_r / h_);
  const float gyro_noise = gyro_step_std_ > 0.0f ? gyro_step_std_ * static_cast<float>(standard_normal(gyro_rng_)) : 0.0f;
  const Twist measured{0.5f * (m_l + m_r), s.gyro_heading ? truth.omega + gyro_bias_ + gyro_noise : (m_r - m_l) / b};

  // 5. Paper Eq. (4) for the truth and for the odometry.
  const Pose2 next = motion_step(true_pose_, truth, h);
  const bool moved = next.x != true_pose_.x || next.y != true_pose_.y;
  if (moved && collides_at(next, 0.0f)) {
    // 6. Collision: undo the step (the wheels did not turn), stop, wait for a new command.
    if (!in_contact_) ++collisions_;
    in_contact_ = true;
    blocked_ = true;
    actual_ = Twist{};
    true_twist_ = Twist{};
  } else {
    true_pose_ = next;
    true_twist_ = truth;
    odom_pose_ = motion_step(odom_pose_, measured, h);
    odom_dist_l_ += static_cast<double>(m_l) * h_;
    odom_dist_r_ += static_cast<double>(m_r) * h_;
    if (in_contact_ && !collides_at(true_pose_, s.contact_release_m)) in_contact_ = false;
  }
  ++steps_;
  if (steps_ % steps_per_odom_ == 0) {
    const double period = static_cast<double>(steps_per_odom_) * h_;
    OdometryMsg msg;
    msg.stamp_s = static_cast<double>(steps_) * h_;
    msg.pose = odom_pose_;
    msg.twist.v = static_cast<float>(0.5 * (odom_dist_l_ + odom_dist_r_) / period);
    msg.twist.omega = static_cast<float>((odom_dist_r_ - odom_dist_l_) / (static_cast<double>(b) * period));
    odometry_.push_back(msg);
    odom_dist_l_ = odom_dist_r_ = 0.0;
  }
}

bool SimChassis::displace(const Eigen::Vector2f& d) {
  const Pose2 moved{true_pose_.x + d.x(), true_pose_.y + d.y(), true_pose_.theta};
  if (!d.allFinite() || collides_at(moved, 0.0f)) return false;
  true_pose_ = moved;
  return true;
}

Pose2 SimChassis::true_pose() const noexcept {
  const double rem = now_s_ - static_cast<double>(steps_) * h_;
  if (!(rem > 0.0)) return true_pose_;
  return motion_step(true_pose_, true_twist_, static_cast<float>(rem));
}

std::vector<OdometryMsg> SimChassis::take_odometry() {
  std::vector<OdometryMsg> out;
  out.swap(odometry_);
  return out;
}

}  // namespace duet::sim
