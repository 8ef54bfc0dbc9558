#pragma once
/// @file motion_model.hpp
/// The robot's planar pose and the noise-free differential-drive motion model of the paper,
/// Eq. (4): X_{k+1} = f(X_k, U_k) with U_k = (v_k, omega_k) held for dt.
///
/// Frame: the map frame, x-y plane, theta counter-clockwise from +x [rad] (REP 103).
/// Thread safety: pure functions; call from any thread.
#include <Eigen/Core>

#include <cmath>

namespace duet {

/// Planar pose in the map frame.
struct Pose2 {
  float x = 0.0f;      ///< [m]
  float y = 0.0f;      ///< [m]
  float theta = 0.0f;  ///< heading [rad], counter-clockwise from +x
};

/// a * b: pose b, given in a's frame, in a's parent frame (heading wrapped to [-pi, pi]).
[[nodiscard]] inline Pose2 compose(const Pose2& a, const Pose2& b) noexcept {
  const float c = std::cos(a.theta), s = std::sin(a.theta);
  return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, std::remainder(a.theta + b.theta, 6.28318530717958647692f)};
}

/// a^-1: compose(a, inverse(a)) is the identity.
[[nodiscard]] inline Pose2 inverse(const Pose2& a) noexcept {
  const float c = std::cos(a.theta), s = std::sin(a.theta);
  return {-(c * a.x + s * a.y), -(-s * a.x + c * a.y), -a.theta};
}

/// T p: the point p, given in T's frame, in T's parent frame.
[[nodiscard]] inline Eigen::Vector2f transform_point(const Pose2& T, const Eigen::Vector2f& p) noexcept {
  const float c = std::cos(T.theta), s = std::sin(T.theta);
  return {T.x + c * p.x() - s * p.y(), T.y + s * p.x() + c * p.y()};
}

/// A velocity command of a differential-drive chassis.
struct Twist {
  float v = 0.0f;      ///< forward speed [m/s]
  float omega = 0.0f;  ///< yaw rate [rad/s], counter-clockwise positive
};

/// What the chassis can do (paper §4.1: Kobuki, 0.7 m/s, 180 deg/s) and what exploration allows
/// (DESIGN.md §7: max speed 0.5 m/s while exploring).
struct ChassisLimits {
  float max_v_mps = 0.5f;              ///< forward speed limit while exploring [m/s]
  float min_v_mps = -0.2f;             ///< reverse speed limit (<= 0) [m/s]
  float max_omega_rps = 3.1415927f;    ///< |omega| limit, 180 deg/s [rad/s]
  float max_accel_mps2 = 1.0f;         ///< |dv/dt| limit [m/s^2]
  float max_alpha_rps2 = 3.0f;         ///< |domega/dt| limit [rad/s^2]
};
void validate(const ChassisLimits& limits);

/// sin(x) / x, by its series below |x| = 1e-3 (where the series' error is below float rounding).
[[nodiscard]] inline float sinc(float x) noexcept {
  return std::fabs(x) < 1e-3f ? 1.0f - x * x * (1.0f / 6.0f) : std::sin(x) / x;
}

/// Eq. (4): the pose after holding (v, omega) for dt seconds from `p`.
///   x' = x - v/w sin(theta) + v/w sin(theta + w dt)
///   y' = y + v/w cos(theta) - v/w cos(theta + w dt)
///   theta' = theta + w dt          (wrapped to (-pi, pi])
/// evaluated in the equivalent chord form: the displacement is v dt sinc(w dt / 2) along the mean
/// heading theta + w dt / 2 (the same expression without the cancellation of two nearly equal
/// sines). Its omega -> 0 limit is the straight line x' = x + v dt cos(theta),
/// y' = y + v dt sin(theta), reached continuously (no threshold).
[[nodiscard]] inline Pose2 motion_step(const Pose2& p, const Twist& u, float dt) noexcept {
  const float half = 0.5f * u.omega * dt;
  const float chord = u.v * dt * sinc(half);
  const float mid = p.theta + half;
  float th = p.theta + 2.0f * half;
  constexpr float kPi = 3.14159265358979f;
  th = std::remainder(th, 2.0f * kPi);  // (-pi, pi]
  return {p.x + chord * std::cos(mid), p.y + chord * std::sin(mid), th};
}

/// Clamp a command to the chassis limits (speed only; acceleration is the caller's window).
[[nodiscard]] inline Twist clamp_twist(const Twist& u, const ChassisLimits& l) noexcept {
  Twist r = u;
  r.v = std::fmin(std::fmax(r.v, l.min_v_mps), l.max_v_mps);
  r.omega = std::fmin(std::fmax(r.omega, -l.max_omega_rps), l.max_omega_rps);
  return r;
}

}  // namespace duet
