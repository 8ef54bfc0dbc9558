/// @file controller_behaviours.cpp
/// The controller's behaviours (stall_detector.hpp, slow_zone.hpp, escape.hpp).
#include <duet/runtime/navigation/escape.hpp>
#include <duet/runtime/navigation/slow_zone.hpp>
#include <duet/runtime/navigation/stall_detector.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace duet {

namespace {
constexpr float kPi = 3.14159265358979f;
}  // namespace

float wrap_angle(float a) {
  while (a > kPi) a -= 2.0f * kPi;
  while (a < -kPi) a += 2.0f * kPi;
  return a;
}

Twist turn_in_place(float err, const Twist& current, const DwaSettings& ds) {
  const float w = std::clamp(1.5f * err, -ds.mapping_max_omega_rps, ds.mapping_max_omega_rps);
  const float dw = ds.mapping_max_alpha_rps2 * ds.control_period_s;
  return Twist{0.0f, std::clamp(w, current.omega - dw, current.omega + dw)};
}

std::optional<Eigen::Vector2f> StallDetector::update(const Twist& last_command, const Twist& measured, const Pose2& robot,
                                                     double now_s) {
  if (!(last_command.v >= 0.03f && std::fabs(measured.v) < 0.01f && std::isfinite(robot.x) && std::isfinite(robot.y))) {
    since_s_ = -1.0;
    return std::nullopt;
  }
  if (since_s_ < 0.0) since_s_ = now_s;
  if (now_s - since_s_ < timeout_s_) return std::nullopt;
  since_s_ = -1.0;
  return Eigen::Vector2f(robot.x + ahead_m_ * std::cos(robot.theta), robot.y + ahead_m_ * std::sin(robot.theta));
}

float SlowZone::speed_limit(const Pose2& robot, const DwaSettings& ds, const InflatedGrid& g) const {
  const float v_max = ds.limits.max_v_mps;
  if (clearance_m_ <= 0.0f) return v_max;
  const float v_slow = std::min(speed_mps_, v_max);
  Eigen::Vector2i c;
  if (!g.cell_of(Eigen::Vector2f(robot.x, robot.y), c)) return v_slow;  // off the map: nothing known
  const float clear = g.clearance_m[g.index(c.x(), c.y())];
  const float margin = ds.robot_radius_m + ds.safety_margin_m;
  if (!(clear < clearance_m_)) return v_max;  // also +inf (no obstacle at all)
  if (!(clearance_m_ > margin) || clear <= margin) return v_slow;
  const float u = (clear - margin) / (clearance_m_ - margin);
  return v_slow + (v_max - v_slow) * u;
}

std::optional<Twist> Escape::step(const Pose2& robot, const Twist& current, const InflatedGrid& g, bool cornered,
                                  const DwaSettings& ds) {
  Eigen::Vector2i c;
  if (!g.cell_of(Eigen::Vector2f(robot.x, robot.y), c)) return std::nullopt;
  const float here = g.clearance_m[g.index(c.x(), c.y())];
  // Not hemmed in by seen obstacles (and not cornered): nothing to escape.
  if (!cornered && !(here < ds.robot_radius_m + ds.safety_margin_m)) return std::nullopt;
  // The direction of the largest clearance among the cells 2 cells away.
  Eigen::Vector2f best_dir(0.0f, 0.0f);
  float best = here;
  for (int dy = -2; dy <= 2; ++dy)
    for (int dx = -2; dx <= 2; ++dx) {
      if (std::max(std::abs(dx), std::abs(dy)) != 2 || !g.in_bounds(c.x() + dx, c.y() + dy)) continue;
      const float v = g.clearance_m[g.index(c.x() + dx, c.y() + dy)];
      if (v > best) {
        best = v;
        best_dir = Eigen::Vector2f(static_cast<float>(dx), static_cast<float>(dy)).normalized();
      }
    }
  if (best_dir.squaredNorm() == 0.0f) return std::nullopt;
  const float err = wrap_angle(std::atan2(best_dir.y(), best_dir.x()) - robot.theta);
  if (std::fabs(err) > 0.3f) return turn_in_place(err, current, ds);
  return Twist{std::min(0.1f, current.v + ds.limits.max_accel_mps2 * ds.control_period_s), 0.0f};
}

bool CorneredWatch::update(const Eigen::Vector2f& here, float dt_s) {
  if ((here - at_).norm() > kRadius) {
    at_ = here;
    seconds_ = 0.0f;
  }
  seconds_ += dt_s;
  return after_s_ > 0.0f && seconds_ >= after_s_;
}

void CorneredWatch::shift(const Pose2& D) {
  if (at_.allFinite()) at_ = transform_point(D, at_);
}

}  // namespace duet
