/// @file controller.cpp
/// Controller: the dynamic window and its behaviours on the Navigator's plan (see controller.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/navigation/controller.hpp>

#include <algorithm>
#include <cmath>

namespace duet {

Controller::Controller(const Profile& profile, const ExplorerSettings& settings)
    : profile_(profile),
      settings_(settings),
      stall_(settings.stall_timeout_s, profile.chassis.radius_m + 0.5f * settings.contact_radius_m),
      slow_zone_(settings.slow_clearance_m, settings.slow_speed_mps),
      cornered_(settings.cornered_after_s),
      seek_(settings) {
  validate(settings_);
  validate(profile_.exploration.dwa);
}

void Controller::shift(const Pose2& D) { cornered_.shift(D); }

Twist Controller::control(const Pose2& robot, const Twist& current, double now_s, GoalLink& link) {
  // Stall: driving forward, the odometry measures no motion - a contact the sensors cannot see.
  if (const std::optional<Eigen::Vector2f> contact = stall_.update(last_cmd_, current, robot, now_s)) {
    ++stats_.stalls;
    link.stall(*contact, now_s);
    last_cmd_ = Twist{};
    return last_cmd_;
  }
  last_cmd_ = follow(robot, current, now_s, link);
  // Whatever a behaviour computed from the measured twist (a glitch of 100 m/s included), the
  // command never exceeds the chassis' speeds (the profile's chassis section).
  const float v_max = profile_.chassis.max_linear_speed_mps, w_max = profile_.chassis.max_angular_speed_radps();
  last_cmd_.v = std::clamp(last_cmd_.v, -v_max, v_max);
  last_cmd_.omega = std::clamp(last_cmd_.omega, -w_max, w_max);
  return last_cmd_;
}

Twist Controller::follow(const Pose2& robot, const Twist& current, double now_s, GoalLink& link) {
  const Eigen::Vector2f here(robot.x, robot.y);
  link.trail(here);
  NavPlanView plan = link.plan();
  if (!plan.have_map || plan.state == ExplorerState::kDone) return Twist{};
  if (!plan.has_goal()) {
    // After a decision without a goal, wait for the next map before deciding again - climbing
    // out meanwhile when the decision found no traversable cell around the robot.
    if (plan.wait_for_map) {
      if (plan.blocked && plan.planning != nullptr) {
        std::optional<Twist> out = creep_along(robot, current, plan.path, *plan.planning, profile_.chassis.radius_m, plan.dwa);
        if (!out) out = Escape::step(robot, current, *plan.planning, true, plan.dwa);
        if (out) {
          ++stats_.blocked_escapes;
          return *out;
        }
      }
      return Twist{};
    }
    link.decide(robot, now_s);
    plan = link.plan();
    if (!plan.has_goal()) return Twist{};
  }
  if (plan.goal_id != goal_id_) {  // a new goal: the window and the behaviours start afresh
    goal_id_ = plan.goal_id;
    dwa_state_.reset();
    stuck_since_s_ = -1.0;
    cornered_.reset();
  }
  if (now_s > plan.deadline_s) {
    link.abandon(plan.goal_id, AbandonReason::kTimeout, now_s);
    return Twist{};
  }
  DwaSettings ds = plan.dwa;
  // Few features in view: turn towards surfaces that may show some (the wheels carry the pose).
  if (const std::optional<Twist> turn = seek_.step(robot, current, *plan.planning, ds, now_s)) {
    stats_.feature_seeks = seek_.seeks();
    dwa_state_.reset();
    return *turn;
  }
  const float v_seen = seek_.speed_limit(ds.limits.max_v_mps);
  if (v_seen < ds.limits.max_v_mps) ++stats_.few_feature_periods;
  const float v_limit = slow_zone_.speed_limit(robot, ds, *plan.planning);
  if (v_limit < ds.limits.max_v_mps) ++stats_.slowed;
  ds.limits.max_v_mps = std::min(v_limit, v_seen);
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
  // A goal handed off on the move (a simulated goal within handoff_m): reached, and this
  // period's command keeps the robot going while the next goal is decided.
  if (plan.handoff_m > 0.0f && (r.status == DwaStatus::kOk || r.status == DwaStatus::kGoalReached) &&
      (Eigen::Vector2f(plan.goal->x, plan.goal->y) - here).norm() <= plan.handoff_m) {
    stuck_since_s_ = -1.0;
    const Twist cmd = r.cmd;
    link.goal_reached(plan.goal_id, now_s);  // invalidates `plan`
    return cmd;
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
      if (const auto esc = Escape::step(robot, current, *plan.planning, false, ds)) {
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
      // Cornered: kept near one spot for cornered_after_s (CorneredWatch).
      if (cornered_.update(here, ds.control_period_s)) {
        const InflatedGrid& g = fell_back ? *plan.planning : *plan.local;
        if (const auto esc = Escape::step(robot, current, g, true, ds)) {
          ++stats_.cornered_escapes;
          return *esc;
        }
      }
      return r.cmd;
    }
  }
}

}  // namespace duet
