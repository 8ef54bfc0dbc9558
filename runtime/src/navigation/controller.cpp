/// @file controller.cpp
/// Controller: the dynamic window and its behaviours on the Navigator's plan (see controller.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/navigation/controller.hpp>

#include <algorithm>
#include <cmath>

namespace duet {

namespace {
constexpr float kPi = 3.14159265358979f;

float wrap_angle(float a) {
  while (a > kPi) a -= 2.0f * kPi;
  while (a < -kPi) a += 2.0f * kPi;
  return a;
}

/// Rotation in place towards a heading error `err` [rad], within the paper's motion constraint
/// (|omega| and |domega/dt| bounds of the dynamic window settings).
Twist turn_in_place(float err, const Twist& current, const DwaSettings& ds) {
  const float w = std::clamp(1.5f * err, -ds.mapping_max_omega_rps, ds.mapping_max_omega_rps);
  const float dw = ds.mapping_max_alpha_rps2 * ds.control_period_s;
  return Twist{0.0f, std::clamp(w, current.omega - dw, current.omega + dw)};
}
}  // namespace

Controller::Controller(const Profile& profile, const ExplorerSettings& settings) : profile_(profile), settings_(settings) {
  validate(settings_);
  validate(profile_.exploration.dwa);
}

void Controller::shift(const Pose2& D) {
  if (cornered_at_.allFinite()) cornered_at_ = transform_point(D, cornered_at_);
}

float Controller::speed_limit(const Pose2& robot, const DwaSettings& ds, const InflatedGrid& g) const {
  const float v_max = ds.limits.max_v_mps;
  if (settings_.slow_clearance_m <= 0.0f) return v_max;
  const float v_slow = std::min(settings_.slow_speed_mps, v_max);
  Eigen::Vector2i c;
  if (!g.cell_of(Eigen::Vector2f(robot.x, robot.y), c)) return v_slow;  // off the map: nothing known
  const float clear = g.clearance_m[g.index(c.x(), c.y())];
  const float margin = ds.robot_radius_m + ds.safety_margin_m;
  if (!(clear < settings_.slow_clearance_m)) return v_max;  // also +inf (no obstacle at all)
  if (!(settings_.slow_clearance_m > margin) || clear <= margin) return v_slow;
  const float u = (clear - margin) / (settings_.slow_clearance_m - margin);
  return v_slow + (v_max - v_slow) * u;
}

std::optional<Twist> Controller::escape(const Pose2& robot, const Twist& current, const InflatedGrid& g, bool cornered,
                                        const DwaSettings& ds) const {
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

Twist Controller::control(const Pose2& robot, const Twist& current, double now_s, GoalLink& link) {
  // Stall: driving forward, the odometry measures no motion - a contact the sensors cannot see.
  if (last_cmd_.v >= 0.03f && std::fabs(current.v) < 0.01f && std::isfinite(robot.x) && std::isfinite(robot.y)) {
    if (stall_since_s_ < 0.0) stall_since_s_ = now_s;
    if (now_s - stall_since_s_ >= settings_.stall_timeout_s) {
      const float ahead = profile_.chassis.radius_m + 0.5f * settings_.contact_radius_m;
      link.stall(Eigen::Vector2f(robot.x + ahead * std::cos(robot.theta), robot.y + ahead * std::sin(robot.theta)), now_s);
      stall_since_s_ = -1.0;
      last_cmd_ = Twist{};
      return last_cmd_;
    }
  } else {
    stall_since_s_ = -1.0;
  }
  last_cmd_ = follow(robot, current, now_s, link);
  return last_cmd_;
}

Twist Controller::follow(const Pose2& robot, const Twist& current, double now_s, GoalLink& link) {
  const Eigen::Vector2f here(robot.x, robot.y);
  link.trail(here);
  NavPlanView plan = link.plan();
  if (!plan.have_map || plan.state == ExplorerState::kDone) return Twist{};
  if (!plan.has_goal()) {
    // After a decision without a goal, wait for the next map before deciding again.
    if (plan.wait_for_map) return Twist{};
    link.decide(robot, now_s);
    plan = link.plan();
    if (!plan.has_goal()) return Twist{};
  }
  if (plan.goal_id != goal_id_) {  // a new goal: the window and the behaviours start afresh
    goal_id_ = plan.goal_id;
    dwa_state_.reset();
    stuck_since_s_ = -1.0;
    cornered_s_ = 0.0f;
  }
  if (now_s > plan.deadline_s) {
    link.abandon(plan.goal_id, AbandonReason::kTimeout, now_s);
    return Twist{};
  }
  DwaSettings ds = plan.dwa;
  const float v_limit = speed_limit(robot, ds, *plan.planning);
  if (v_limit < ds.limits.max_v_mps) ++stats_.slowed;
  ds.limits.max_v_mps = v_limit;
  const DwaState before = dwa_state_;
  DwaResult r = dwa_step(plan.local->clearance(), robot, current, plan.path, ds, dwa_state_, dwa_ws_);
  bool fell_back = false;
  if (r.status == DwaStatus::kNoValidTrajectory) {
    // Hemmed in by cells nobody has seen (nearer than the sensors' min range, they stay
    // unknown): fall back to the planning grid, where only seen obstacles count.
    dwa_state_ = before;
    r = dwa_step(plan.planning->clearance(), robot, current, plan.path, ds, dwa_state_, dwa_ws_);
    ++stats_.local_fallbacks;
    fell_back = true;
  }
  switch (r.status) {
    case DwaStatus::kGoalReached: {
      // A goal is a pose: Procedure 1's X_g, or a frontier goal facing the unknown side. Turn to
      // its heading, within the paper's bounded angular speed - the sensors must look at what
      // the goal was chosen for.
      const float err = wrap_angle(plan.goal->theta - robot.theta);
      if (std::fabs(err) > 0.2f) return turn_in_place(err, current, ds);
      link.goal_reached(plan.goal_id, now_s);
      return Twist{};
    }
    case DwaStatus::kNoValidTrajectory:
      // Nothing admissible even on the planning grid: the robot sits inside the window's margin
      // (a map update moved an obstacle nearer). Reversing is blind: escape forward.
      if (const auto esc = escape(robot, current, *plan.planning, false, ds)) {
        ++stats_.escapes;
        return *esc;
      }
      [[fallthrough]];
    case DwaStatus::kNoPath:
      if (stuck_since_s_ < 0.0) stuck_since_s_ = now_s;
      if (now_s - stuck_since_s_ > settings_.stuck_timeout_s) {
        link.abandon(plan.goal_id, AbandonReason::kStuck, now_s);
        stuck_since_s_ = -1.0;
      }
      return r.cmd;
    default: {
      stuck_since_s_ = -1.0;
      // Cornered: kept within kCorneredRadius of one spot for cornered_after_s - at the edge of
      // the traversable band every forward motion reachable from the spin leaves it.
      constexpr float kCorneredRadius = 0.10f;
      if ((here - cornered_at_).norm() > kCorneredRadius) {
        cornered_at_ = here;
        cornered_s_ = 0.0f;
      }
      cornered_s_ += ds.control_period_s;
      if (settings_.cornered_after_s > 0.0f && cornered_s_ >= settings_.cornered_after_s) {
        const InflatedGrid& g = fell_back ? *plan.planning : *plan.local;
        if (const auto esc = escape(robot, current, g, true, ds)) {
          ++stats_.cornered_escapes;
          return *esc;
        }
      }
      return r.cmd;
    }
  }
}

}  // namespace duet
