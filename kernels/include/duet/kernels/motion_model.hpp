#pragma once
/// @file motion_model.hpp
/// The robot's planar pose and the noise-free differential-drive motion model of the paper,
/// Eq. (4): X_{k+1} = f(X_k, U_k) with U_k = (v_k, omega_k) held for dt.
///
/// Frame: the map frame, x-y plane, theta counter-clockwise from +x [rad] (REP 103).
/// Thread safety: pure functions; call from any thread.
#include <cmath>

namespace duet {

/// Planar pose in the map frame.
struct Pose2 {
  float x = 0.0f;      ///< [m]
  float y = 0.0f;      ///< [m]
  float theta = 0.0f;  ///< heading [rad], counter-clockwise from +x
};

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

/// Below this |omega| [rad/s] Eq. (4) is replaced by its omega -> 0 limit (straight line);
/// at 1e-4 rad/s the two differ by less than 1e-9 m over 1 s at 1 m/s.
inline constexpr float kStraightOmega = 1e-4f;

/// Eq. (4): the pose after holding (v, omega) for dt seconds from `p`.
///   x' = x - v/w sin(theta) + v/w sin(theta + w dt)
///   y' = y + v/w cos(theta) - v/w cos(theta + w dt)
///   theta' = theta + w dt          (wrapped to (-pi, pi])
/// and for |w| < kStraightOmega its limit x' = x + v dt cos(theta), y' = y + v dt sin(theta).
/// The arc form is evaluated as 2 v/w sin(w dt / 2) along the mean heading, which is the same
/// expression without the cancellation of two nearly equal sines.
[[nodiscard]] inline Pose2 motion_step(const Pose2& p, const Twist& u, float dt) noexcept {
  const float dth = u.omega * dt;
  float dx, dy;
  if (std::fabs(u.omega) < kStraightOmega) {
    dx = u.v * dt * std::cos(p.theta);
    dy = u.v * dt * std::sin(p.theta);
  } else {
    const float chord = 2.0f * u.v / u.omega * std::sin(0.5f * dth);
    const float mid = p.theta + 0.5f * dth;
    dx = chord * std::cos(mid);
    dy = chord * std::sin(mid);
  }
  float th = p.theta + dth;
  constexpr float kPi = 3.14159265358979f;
  th = std::remainder(th, 2.0f * kPi);  // (-pi, pi]
  return {p.x + dx, p.y + dy, th};
}

/// Clamp a command to the chassis limits (speed only; acceleration is the caller's window).
[[nodiscard]] inline Twist clamp_twist(const Twist& u, const ChassisLimits& l) noexcept {
  Twist r = u;
  r.v = std::fmin(std::fmax(r.v, l.min_v_mps), l.max_v_mps);
  r.omega = std::fmin(std::fmax(r.omega, -l.max_omega_rps), l.max_omega_rps);
  return r;
}

}  // namespace duet
