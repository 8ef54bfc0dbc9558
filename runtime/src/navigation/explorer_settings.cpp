/// @file explorer_settings.cpp
/// validate(ExplorerSettings): the ranges written on each field in explorer_settings.hpp.
#include <duet/kernels/error.hpp>
#include <duet/runtime/navigation/explorer_settings.hpp>

#include <cmath>
#include <string>

namespace duet {

const char* to_string(OnDone d) {
  switch (d) {
    case OnDone::kStay: return "stay";
    case OnDone::kReturnHome: return "return_home";
    case OnDone::kPatrol: return "patrol";
  }
  return "unknown";
}

const char* to_string(ExplorerState s) {
  switch (s) {
    case ExplorerState::kIdle: return "idle";
    case ExplorerState::kExploring: return "exploring";
    case ExplorerState::kReturningHome: return "returning_home";
    case ExplorerState::kPatrolling: return "patrolling";
    case ExplorerState::kDone: return "done";
  }
  return "unknown";
}

void validate(const ExplorerSettings& s) {
  auto positive = [](float v, const char* name) {
    if (!(std::isfinite(v) && v > 0.0f))
      fail(ErrorCode::kInvalidArgument, std::string("ExplorerSettings::") + name + " must be in (0, inf), got " + std::to_string(v));
  };
  positive(s.goal_timeout_s, "goal_timeout_s");
  positive(s.nominal_speed_mps, "nominal_speed_mps");
  positive(s.stuck_timeout_s, "stuck_timeout_s");
  positive(s.stall_timeout_s, "stall_timeout_s");
  if (!(s.contact_radius_m > 0.0f && s.contact_radius_m <= 1.0f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::contact_radius_m must be in (0, 1] m, got " + std::to_string(s.contact_radius_m));
  if (!(s.blacklist_ttl_s > 0.0f))  // +inf allowed
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::blacklist_ttl_s must be in (0, inf], got " + std::to_string(s.blacklist_ttl_s));
  if (!(s.goal_standoff_search_m >= 0.0f && s.goal_standoff_search_m <= 5.0f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::goal_standoff_search_m must be in [0, 5] m, got " + std::to_string(s.goal_standoff_search_m));
  if (!(s.boxed_in_area_m2 >= 0.0f && std::isfinite(s.boxed_in_area_m2)))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::boxed_in_area_m2 must be in [0, inf) m^2, got " + std::to_string(s.boxed_in_area_m2));
  if (!(s.squeeze_min_unknown_m2 >= 0.0f && std::isfinite(s.squeeze_min_unknown_m2)))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::squeeze_min_unknown_m2 must be in [0, inf) m^2, got " + std::to_string(s.squeeze_min_unknown_m2));
  if (!(s.squeeze_margin_m >= 0.0f && s.squeeze_margin_m <= 1.0f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::squeeze_margin_m must be in [0, 1] m, got " + std::to_string(s.squeeze_margin_m));
  if (!(s.view_range_m >= 0.0f && s.view_range_m <= 10.0f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::view_range_m must be in [0, 10] m, got " + std::to_string(s.view_range_m));
  // At most view_range_m; with no view goals (view_range_m = 0) at most view_range_m's own bound.
  const float view_min_max = s.view_range_m > 0.0f ? s.view_range_m : 10.0f;
  if (!(s.view_min_range_m >= 0.0f && s.view_min_range_m <= view_min_max))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::view_min_range_m must be in [0, " + std::to_string(view_min_max) +
                                          "] m (view_range_m, or 10 with no view goals), got " + std::to_string(s.view_min_range_m));
  if (s.view_rays < 4 || s.view_rays > 3600)
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::view_rays must be in [4, 3600], got " + std::to_string(s.view_rays));
  if (!(s.view_frontier_weight >= 0.0f && s.view_frontier_weight <= 1000.0f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::view_frontier_weight must be in [0, 1000] m/m, got " + std::to_string(s.view_frontier_weight));
  if (s.view_looks < 1 || s.view_looks > 100)
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::view_looks must be in [1, 100], got " + std::to_string(s.view_looks));
  if (!(s.view_relook_after_s >= 0.0f && s.view_relook_after_s <= 1e5f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::view_relook_after_s must be in [0, 1e5] s, got " + std::to_string(s.view_relook_after_s));
  if (!(s.simulated_goal_handoff_m >= 0.0f && s.simulated_goal_handoff_m <= 5.0f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::simulated_goal_handoff_m must be in [0, 5] m, got " + std::to_string(s.simulated_goal_handoff_m));
  if (!(s.frontier_seen_radius_m >= 0.0f && s.frontier_seen_radius_m <= 5.0f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::frontier_seen_radius_m must be in [0, 5] m, got " + std::to_string(s.frontier_seen_radius_m));
  if (!(s.view_relook_dwell_s >= 0.0f && s.view_relook_dwell_s <= 600.0f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::view_relook_dwell_s must be in [0, 600] s, got " + std::to_string(s.view_relook_dwell_s));
  if (!(s.view_min_gain_m2 >= 0.0f && s.view_min_gain_m2 <= 1e6f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::view_min_gain_m2 must be in [0, 1e6] m^2, got " + std::to_string(s.view_min_gain_m2));
  if (!(s.view_gain_window_s > 0.0f && s.view_gain_window_s <= 1e5f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::view_gain_window_s must be in (0, 1e5] s, got " + std::to_string(s.view_gain_window_s));
  if (!(s.recent_obstacles_s >= 0.0f && s.recent_obstacles_s <= 3600.0f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::recent_obstacles_s must be in [0, 3600] s, got " + std::to_string(s.recent_obstacles_s));
  if (!(s.recent_obstacle_range_m > 0.0f && s.recent_obstacle_range_m <= 10.0f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::recent_obstacle_range_m must be in (0, 10] m, got " + std::to_string(s.recent_obstacle_range_m));
  if (s.recent_obstacle_min_scans < 1 || s.recent_obstacle_min_scans > 1000)
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::recent_obstacle_min_scans must be in [1, 1000], got " + std::to_string(s.recent_obstacle_min_scans));
  if (!(std::isfinite(s.cornered_after_s) && s.cornered_after_s >= 0.0f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::cornered_after_s must be in [0, inf) s (0 = off), got " + std::to_string(s.cornered_after_s));
  if (!(s.slow_clearance_m >= 0.0f && s.slow_clearance_m <= 10.0f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::slow_clearance_m must be in [0, 10] m (0 = off), got " + std::to_string(s.slow_clearance_m));
  if (!(std::isfinite(s.slow_speed_mps) && s.slow_speed_mps > 0.0f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::slow_speed_mps must be in (0, inf) m/s, got " + std::to_string(s.slow_speed_mps));
  const auto in = [](float v, float lo, float hi, const char* name, const char* unit) {
    if (!(v >= lo && v <= hi))
      fail(ErrorCode::kInvalidArgument, std::string("ExplorerSettings::") + name + " must be in [" + std::to_string(lo) + ", " +
                                            std::to_string(hi) + "] " + unit + ", got " + std::to_string(v));
  };
  in(s.few_features_speed_mps, 0.0f, 100.0f, "few_features_speed_mps", "m/s (0 = no cap)");
  in(s.seek_after_s, 0.0f, 3600.0f, "seek_after_s", "s (0 = never)");
  in(s.seek_cooldown_s, 0.0f, 3600.0f, "seek_cooldown_s", "s");
  in(s.seek_min_turn_rad, 0.0f, 3.1416f, "seek_min_turn_rad", "rad");
  in(s.seek_range_m, 0.1f, 20.0f, "seek_range_m", "m");
  in(s.seek_min_range_m, 0.0f, s.seek_range_m, "seek_min_range_m", "m (at most seek_range_m)");
  if (!(s.patrol_spacing_m >= 0.5f && s.patrol_spacing_m <= 100.0f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::patrol_spacing_m must be in [0.5, 100] m, got " + std::to_string(s.patrol_spacing_m));
  if (!(s.blocked_recovery_s >= 0.0f && s.blocked_recovery_s <= 3600.0f))
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::blocked_recovery_s must be in [0, 3600] s (0 = off), got " + std::to_string(s.blocked_recovery_s));
  if (s.max_goal_failures < 0 || s.max_goal_failures > 1000)
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::max_goal_failures must be in [0, 1000], got " + std::to_string(s.max_goal_failures));
  if (s.final_retries < 0 || s.final_retries > 1000)
    fail(ErrorCode::kInvalidArgument, "ExplorerSettings::final_retries must be in [0, 1000], got " + std::to_string(s.final_retries));
}

}  // namespace duet
