// The planner's settings (duet.h, "Exploration planner"): duet_*_settings_init(), the conversion
// of the C settings structs to the C++ ones (validated), the C mirrors of the kernel results and
// the status strings. The defaults are the built-in dual profile's (default_profile()): the same
// values `duet explore` and duet_runtime run with.
#include "capi_internal.hpp"

#include <cmath>
#include <limits>
#include <string>

namespace duet::capi {
namespace {

/// Runs the kernel's validate(c); its duet::Error (which names the C++ struct and field, the
/// same field names as the C mirror) is rethrown prefixed with the C argument name.
template <class C>
void validate_as(const C& c, const char* name) {
  try {
    validate(c);
  } catch (const Error& e) {
    if (e.code() != ErrorCode::kInvalidArgument) throw;
    invalid_argument(std::string(name) + ": " + e.what());
  }
}

/// A C int used as a bool must be 0 or 1.
bool flag(int v, const char* name, const char* field) {
  if (v != 0 && v != 1) {
    invalid_argument(std::string(name) + "." + field + " is " + std::to_string(v) + " (allowed: 0 or 1)");
  }
  return v != 0;
}

duet_cell_thresholds to_c(const CellThresholds& t) {
  duet_cell_thresholds c;
  c.occupied_logodds = t.occupied_logodds;
  c.free_logodds = t.free_logodds;
  return c;
}

CellThresholds from_c(const duet_cell_thresholds& c) {
  CellThresholds t;
  t.occupied_logodds = c.occupied_logodds;
  t.free_logodds = c.free_logodds;
  return t;
}

duet_frontier_settings to_c(const FrontierSettings& f) {
  duet_frontier_settings c;
  c.min_cluster_cells = f.min_cluster_cells;
  c.min_goal_distance_m = f.min_goal_distance_m;
  c.blacklist_radius_m = f.blacklist_radius_m;
  c.approach_radius_m = f.approach_radius_m;
  c.min_unknown_region_m2 = f.min_unknown_region_m2;
  return c;
}

FrontierSettings from_c(const duet_frontier_settings& c) {
  FrontierSettings f;
  f.min_cluster_cells = c.min_cluster_cells;
  f.min_goal_distance_m = c.min_goal_distance_m;
  f.blacklist_radius_m = c.blacklist_radius_m;
  f.approach_radius_m = c.approach_radius_m;
  f.min_unknown_region_m2 = c.min_unknown_region_m2;
  return f;
}

duet_partial_sim_settings to_c(const PartialSimSettings& p) {
  duet_partial_sim_settings c;
  c.iterations = p.iterations;
  c.particles = p.particles;
  c.phi_a = p.phi_a;
  c.phi_b = p.phi_b;
  c.stages = p.stages;
  c.stage_dt_s = p.stage_dt_s;
  c.v_min_mps = p.v_min_mps;
  c.v_max_mps = p.v_max_mps;
  c.omega_max_rps = p.omega_max_rps;
  c.sigma_v_mps = p.sigma_v_mps;
  c.sigma_omega_rps = p.sigma_omega_rps;
  c.resample_ess_fraction = p.resample_ess_fraction;
  c.gamma = p.gamma;
  c.unknown_hit_probability = p.unknown_hit_probability;
  c.hit_logodds = p.hit_logodds;
  c.miss_logodds = p.miss_logodds;
  c.ism_noise_logodds = p.ism_noise_logodds;
  c.min_logodds = p.min_logodds;
  c.max_logodds = p.max_logodds;
  c.min_goal_distance_m = p.min_goal_distance_m;
  c.max_goal_distance_m = p.max_goal_distance_m;
  c.collision_step_m = p.collision_step_m;
  c.seed = p.seed;
  return c;
}

PartialSimSettings from_c(const duet_partial_sim_settings& c) {
  PartialSimSettings p;
  p.iterations = c.iterations;
  p.particles = c.particles;
  p.phi_a = c.phi_a;
  p.phi_b = c.phi_b;
  p.stages = c.stages;
  p.stage_dt_s = c.stage_dt_s;
  p.v_min_mps = c.v_min_mps;
  p.v_max_mps = c.v_max_mps;
  p.omega_max_rps = c.omega_max_rps;
  p.sigma_v_mps = c.sigma_v_mps;
  p.sigma_omega_rps = c.sigma_omega_rps;
  p.resample_ess_fraction = c.resample_ess_fraction;
  p.gamma = c.gamma;
  p.unknown_hit_probability = c.unknown_hit_probability;
  p.hit_logodds = c.hit_logodds;
  p.miss_logodds = c.miss_logodds;
  p.ism_noise_logodds = c.ism_noise_logodds;
  p.min_logodds = c.min_logodds;
  p.max_logodds = c.max_logodds;
  p.min_goal_distance_m = c.min_goal_distance_m;
  p.max_goal_distance_m = c.max_goal_distance_m;
  p.collision_step_m = c.collision_step_m;
  p.seed = c.seed;
  return p;
}

}  // namespace

// ---- C -> C++ settings --------------------------------------------------------------------

SensorSector to_cpp(const duet_sensor_sector& c) {
  SensorSector s;
  s.x_m = c.x_m;
  s.y_m = c.y_m;
  s.yaw_rad = c.yaw_rad;
  s.fov_rad = c.fov_rad;
  s.min_range_m = c.min_range_m;
  s.max_range_m = c.max_range_m;
  s.rays = c.rays;
  return s;
}

ObservationSettings to_cpp(const duet_observation_settings* s, const char* name) {
  ObservationSettings c = default_profile().exploration.observation;
  if (s != nullptr) {
    const int backend = enum_value(s->backend);
    if (backend != DUET_OBSERVATION_EMBREE && backend != DUET_OBSERVATION_DDA) {
      invalid_argument(std::string(name) + ".backend is " + std::to_string(backend) +
                       " (allowed: DUET_OBSERVATION_EMBREE, DUET_OBSERVATION_DDA)");
    }
    c.thresholds = from_c(s->thresholds);
    c.backend = backend == DUET_OBSERVATION_EMBREE ? ObservationBackend::kEmbree : ObservationBackend::kDda;
    c.tile_cells = s->tile_cells;
  }
  validate_as(c, name);
  return c;
}

InflationSettings to_cpp(const duet_inflation_settings* s, const char* name) {
  InflationSettings c = default_profile().exploration.inflation;
  if (s != nullptr) {
    c.thresholds = from_c(s->thresholds);
    c.robot_radius_m = s->robot_radius_m;
    c.unknown_is_obstacle = flag(s->unknown_is_obstacle, name, "unknown_is_obstacle");
    c.uncertain_is_obstacle = flag(s->uncertain_is_obstacle, name, "uncertain_is_obstacle");
  }
  validate_as(c, name);
  return c;
}

PathSettings to_cpp(const duet_path_settings* s, const char* name) {
  PathSettings c = default_profile().exploration.path;
  if (s != nullptr) {
    c.allow_diagonal = flag(s->allow_diagonal, name, "allow_diagonal");
    c.clearance_weight = s->clearance_weight;
    c.clearance_decay_m = s->clearance_decay_m;
    c.goal_tolerance_m = s->goal_tolerance_m;
  }
  validate_as(c, name);
  return c;
}

FrontierSettings to_cpp(const duet_frontier_settings* s, const char* name) {
  FrontierSettings c = s != nullptr ? from_c(*s) : default_profile().exploration.strategy.frontier;
  validate_as(c, name);
  return c;
}

PartialSimSettings to_cpp(const duet_partial_sim_settings* s, const char* name) {
  PartialSimSettings c = s != nullptr ? from_c(*s) : default_profile().exploration.strategy.simulation;
  validate_as(c, name);
  return c;
}

ExplorationSettings to_cpp(const duet_exploration_settings* s, const char* name) {
  ExplorationSettings c = default_profile().exploration.strategy;
  if (s != nullptr) {
    c.simulation = from_c(s->simulation);
    c.frontier = from_c(s->frontier);
    c.eps_r_bits = s->eps_r_bits;
    c.use_simulation = flag(s->use_simulation, name, "use_simulation");
  }
  validate_as(c, name);
  return c;
}

DwaSettings to_cpp(const duet_dwa_settings* s, const char* name) {
  DwaSettings c = default_profile().exploration.dwa;
  if (s != nullptr) {
    c.limits.max_v_mps = s->limits.max_v_mps;
    c.limits.min_v_mps = s->limits.min_v_mps;
    c.limits.max_omega_rps = s->limits.max_omega_rps;
    c.limits.max_accel_mps2 = s->limits.max_accel_mps2;
    c.limits.max_alpha_rps2 = s->limits.max_alpha_rps2;
    c.mapping_max_omega_rps = s->mapping_max_omega_rps;
    c.mapping_max_alpha_rps2 = s->mapping_max_alpha_rps2;
    c.control_period_s = s->control_period_s;
    c.v_samples = s->v_samples;
    c.omega_samples = s->omega_samples;
    c.steps = s->steps;
    c.sim_time_s = s->sim_time_s;
    c.robot_radius_m = s->robot_radius_m;
    c.safety_margin_m = s->safety_margin_m;
    c.w_progress = s->w_progress;
    c.w_path = s->w_path;
    c.w_clearance = s->w_clearance;
    c.w_speed = s->w_speed;
    c.clearance_cap_m = s->clearance_cap_m;
    c.lookahead_m = s->lookahead_m;
    c.goal_tolerance_m = s->goal_tolerance_m;
    c.oscillation_window_calls = s->oscillation_window_calls;
    c.oscillation_min_progress_m = s->oscillation_min_progress_m;
    c.oscillation_min_turn_rad = s->oscillation_min_turn_rad;
    c.recovery_max_calls = s->recovery_max_calls;
    c.rotate_omega_rps = s->rotate_omega_rps;
    c.rotate_tolerance_rad = s->rotate_tolerance_rad;
    c.backoff_distance_m = s->backoff_distance_m;
    c.backoff_speed_mps = s->backoff_speed_mps;
  }
  validate_as(c, name);
  return c;
}

// ---- C++ -> C results ---------------------------------------------------------------------

duet_sensor_sector to_c(const SensorSector& s) {
  duet_sensor_sector c;
  c.x_m = s.x_m;
  c.y_m = s.y_m;
  c.yaw_rad = s.yaw_rad;
  c.fov_rad = s.fov_rad;
  c.min_range_m = s.min_range_m;
  c.max_range_m = s.max_range_m;
  c.rays = s.rays;
  return c;
}

duet_pose2 to_c(const Pose2& p) { return duet_pose2{p.x, p.y, p.theta}; }

duet_partial_sim_result to_c(const PartialSimResult& r) {
  auto c = blank<duet_partial_sim_result>();
  c.found = r.found ? 1 : 0;
  c.goal = to_c(r.goal);
  c.reward_bits = r.reward_bits;
  c.best_particle = r.best_particle;
  c.valid_particles = r.valid_particles;
  c.resamples = r.resamples;
  c.cells_visited = r.cells_visited;
  c.trajectory_count = r.best_trajectory.size();
  return c;
}

duet_frontier_result to_c(const FrontierResult& r) {
  auto c = blank<duet_frontier_result>();
  switch (r.status) {
    case FrontierStatus::kFound: c.status = DUET_FRONTIER_FOUND; break;
    case FrontierStatus::kNoFrontier: c.status = DUET_FRONTIER_NO_FRONTIER; break;
    case FrontierStatus::kAllUnreachable: c.status = DUET_FRONTIER_ALL_UNREACHABLE; break;
    case FrontierStatus::kAllBlacklisted: c.status = DUET_FRONTIER_ALL_BLACKLISTED; break;
    case FrontierStatus::kRobotBlocked: c.status = DUET_FRONTIER_ROBOT_BLOCKED; break;
    default: api_fail(DUET_ERROR_UNKNOWN, "unknown FrontierStatus (internal error)");
  }
  c.goal_x = r.goal_xy.x();
  c.goal_y = r.goal_xy.y();
  c.target_x = r.target_xy.x();
  c.target_y = r.target_xy.y();
  c.path_length_m = r.path_length_m;
  c.path_count = r.path.size();
  c.cluster_count = r.clusters.size();
  c.frontier_cells = r.frontier_cells;
  c.reached_cells = r.reached_cells;
  return c;
}

void fill(const duet::ObservationSettings& c, duet_observation_settings* settings) {
  settings->thresholds = to_c(c.thresholds);
  settings->backend = c.backend == duet::ObservationBackend::kEmbree ? DUET_OBSERVATION_EMBREE : DUET_OBSERVATION_DDA;
  settings->tile_cells = c.tile_cells;
}

void fill(const duet::InflationSettings& c, duet_inflation_settings* settings) {
  settings->thresholds = to_c(c.thresholds);
  settings->robot_radius_m = c.robot_radius_m;
  settings->unknown_is_obstacle = c.unknown_is_obstacle ? 1 : 0;
  settings->uncertain_is_obstacle = c.uncertain_is_obstacle ? 1 : 0;
}

void fill(const duet::PathSettings& c, duet_path_settings* settings) {
  settings->allow_diagonal = c.allow_diagonal ? 1 : 0;
  settings->clearance_weight = c.clearance_weight;
  settings->clearance_decay_m = c.clearance_decay_m;
  settings->goal_tolerance_m = c.goal_tolerance_m;
}

void fill(const duet::ExplorationSettings& c, duet_exploration_settings* settings) {
  settings->simulation = to_c(c.simulation);
  settings->frontier = to_c(c.frontier);
  settings->eps_r_bits = c.eps_r_bits;
  settings->use_simulation = c.use_simulation ? 1 : 0;
}

void fill(const duet::DwaSettings& c, duet_dwa_settings* settings) {
  settings->limits.max_v_mps = c.limits.max_v_mps;
  settings->limits.min_v_mps = c.limits.min_v_mps;
  settings->limits.max_omega_rps = c.limits.max_omega_rps;
  settings->limits.max_accel_mps2 = c.limits.max_accel_mps2;
  settings->limits.max_alpha_rps2 = c.limits.max_alpha_rps2;
  settings->mapping_max_omega_rps = c.mapping_max_omega_rps;
  settings->mapping_max_alpha_rps2 = c.mapping_max_alpha_rps2;
  settings->control_period_s = c.control_period_s;
  settings->v_samples = c.v_samples;
  settings->omega_samples = c.omega_samples;
  settings->steps = c.steps;
  settings->sim_time_s = c.sim_time_s;
  settings->robot_radius_m = c.robot_radius_m;
  settings->safety_margin_m = c.safety_margin_m;
  settings->w_progress = c.w_progress;
  settings->w_path = c.w_path;
  settings->w_clearance = c.w_clearance;
  settings->w_speed = c.w_speed;
  settings->clearance_cap_m = c.clearance_cap_m;
  settings->lookahead_m = c.lookahead_m;
  settings->goal_tolerance_m = c.goal_tolerance_m;
  settings->oscillation_window_calls = c.oscillation_window_calls;
  settings->oscillation_min_progress_m = c.oscillation_min_progress_m;
  settings->oscillation_min_turn_rad = c.oscillation_min_turn_rad;
  settings->recovery_max_calls = c.recovery_max_calls;
  settings->rotate_omega_rps = c.rotate_omega_rps;
  settings->rotate_tolerance_rad = c.rotate_tolerance_rad;
  settings->backoff_distance_m = c.backoff_distance_m;
  settings->backoff_speed_mps = c.backoff_speed_mps;
}

}  // namespace duet::capi

using namespace duet::capi;

extern "C" {

DUET_API void duet_sensor_sector_init(duet_sensor_sector* sector) {
  if (sector == nullptr) return;
  *sector = to_c(duet::SensorSector{});
}

DUET_API void duet_paper_dual_sensors(duet_sensor_sector out[2], int rays_per_sensor) {
  guarded(nullptr, "duet_paper_dual_sensors", [&] {
    check_not_null(out, "out");
    if (rays_per_sensor < 1 || rays_per_sensor > 100000) {
      invalid_argument("rays_per_sensor is " + std::to_string(rays_per_sensor) + " (allowed: [1, 100000])");
    }
    const auto s = duet::paper_dual_sensors(rays_per_sensor);
    if (s.size() != 2) api_fail(DUET_ERROR_UNKNOWN, "paper_dual_sensors did not return 2 sensors (internal error)");
    out[0] = to_c(s[0]);
    out[1] = to_c(s[1]);
  });
}

DUET_API void duet_observation_settings_init(duet_observation_settings* settings) {
  if (settings == nullptr) return;
  fill(default_profile().exploration.observation, settings);
}

DUET_API void duet_inflation_settings_init(duet_inflation_settings* settings) {
  if (settings == nullptr) return;
  fill(default_profile().exploration.inflation, settings);
}

DUET_API void duet_path_settings_init(duet_path_settings* settings) {
  if (settings == nullptr) return;
  fill(default_profile().exploration.path, settings);
}

DUET_API void duet_frontier_settings_init(duet_frontier_settings* settings) {
  if (settings == nullptr) return;
  *settings = to_c(default_profile().exploration.strategy.frontier);
}

DUET_API void duet_partial_sim_settings_init(duet_partial_sim_settings* settings) {
  if (settings == nullptr) return;
  *settings = to_c(default_profile().exploration.strategy.simulation);
}

DUET_API void duet_exploration_settings_init(duet_exploration_settings* settings) {
  if (settings == nullptr) return;
  fill(default_profile().exploration.strategy, settings);
}

DUET_API void duet_dwa_settings_init(duet_dwa_settings* settings) {
  if (settings == nullptr) return;
  fill(default_profile().exploration.dwa, settings);
}

DUET_API const char* duet_path_status_string(enum duet_path_status status) {
  switch (enum_value(status)) {
    case DUET_PATH_FOUND: return "DUET_PATH_FOUND";
    case DUET_PATH_START_BLOCKED: return "DUET_PATH_START_BLOCKED";
    case DUET_PATH_GOAL_BLOCKED: return "DUET_PATH_GOAL_BLOCKED";
    case DUET_PATH_NO_PATH: return "DUET_PATH_NO_PATH";
    case DUET_PATH_OUTSIDE_GRID: return "DUET_PATH_OUTSIDE_GRID";
  }
  return "DUET_PATH_?";
}

DUET_API const char* duet_frontier_status_string(enum duet_frontier_status status) {
  switch (enum_value(status)) {
    case DUET_FRONTIER_FOUND: return "DUET_FRONTIER_FOUND";
    case DUET_FRONTIER_NO_FRONTIER: return "DUET_FRONTIER_NO_FRONTIER";
    case DUET_FRONTIER_ALL_UNREACHABLE: return "DUET_FRONTIER_ALL_UNREACHABLE";
    case DUET_FRONTIER_ALL_BLACKLISTED: return "DUET_FRONTIER_ALL_BLACKLISTED";
    case DUET_FRONTIER_ROBOT_BLOCKED: return "DUET_FRONTIER_ROBOT_BLOCKED";
  }
  return "DUET_FRONTIER_?";
}

DUET_API const char* duet_exploration_status_string(enum duet_exploration_status status) {
  switch (enum_value(status)) {
    case DUET_EXPLORATION_SIMULATED_GOAL: return "DUET_EXPLORATION_SIMULATED_GOAL";
    case DUET_EXPLORATION_FRONTIER_GOAL: return "DUET_EXPLORATION_FRONTIER_GOAL";
    case DUET_EXPLORATION_NO_FRONTIER: return "DUET_EXPLORATION_NO_FRONTIER";
    case DUET_EXPLORATION_ALL_UNREACHABLE: return "DUET_EXPLORATION_ALL_UNREACHABLE";
    case DUET_EXPLORATION_ALL_BLACKLISTED: return "DUET_EXPLORATION_ALL_BLACKLISTED";
    case DUET_EXPLORATION_ROBOT_BLOCKED: return "DUET_EXPLORATION_ROBOT_BLOCKED";
  }
  return "DUET_EXPLORATION_?";
}

DUET_API const char* duet_dwa_status_string(enum duet_dwa_status status) {
  switch (enum_value(status)) {
    case DUET_DWA_OK: return "DUET_DWA_OK";
    case DUET_DWA_GOAL_REACHED: return "DUET_DWA_GOAL_REACHED";
    case DUET_DWA_ROTATE_IN_PLACE: return "DUET_DWA_ROTATE_IN_PLACE";
    case DUET_DWA_BACK_OFF: return "DUET_DWA_BACK_OFF";
    case DUET_DWA_NO_VALID_TRAJECTORY: return "DUET_DWA_NO_VALID_TRAJECTORY";
    case DUET_DWA_NO_PATH: return "DUET_DWA_NO_PATH";
  }
  return "DUET_DWA_?";
}

}  // extern "C"
