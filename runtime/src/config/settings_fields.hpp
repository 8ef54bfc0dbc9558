#pragma once
/// @file settings_fields.hpp
/// The settings tree's field lists: every field of every settings struct a profile holds, by
/// its YAML key, in the order the profile YAML writes it. One list serves the reader of the
/// runtime's sections, the writer of the whole tree (to_yaml()) and `--set` (config/profile.hpp);
/// the ranges stay in each struct's validate(). A visitor V has:
///   v(key, field)                 a scalar: float, double, int, bool, sizes, strings, Vector3f
///   v.choice(key, field, names)   an enum by name ({{"a", E::kA}, ...})
///   v.section(key, fn)            a nested mapping; fn(v) visits its fields
/// `mapping` and the kernels' part of `exploration` are read through these lists too; only the
/// chassis (required keys) and the sensors (focal lengths or fields of view) have hand-written
/// readers in profile.cpp with the same keys, and the round-trip test checks they agree.
#include <duet/runtime/config/profile.hpp>

#include <cmath>
#include <initializer_list>
#include <utility>

namespace duet::detail {

template <class E>
using Names = std::initializer_list<std::pair<const char*, E>>;

inline constexpr Names<Execution> kExecutionNames = {{"lockstep", Execution::kLockstep}, {"background", Execution::kBackground}};
inline constexpr Names<OnDone> kOnDoneNames = {{"stay", OnDone::kStay}, {"return_home", OnDone::kReturnHome}, {"patrol", OnDone::kPatrol}};
inline constexpr Names<FrontierSelection> kSelectionNames = {{"nearest", FrontierSelection::kNearest},
                                                            {"explore_lite", FrontierSelection::kExploreLite}};
inline constexpr Names<ObservationBackend> kBackendNames = {{"dda", ObservationBackend::kDda}, {"embree", ObservationBackend::kEmbree}};

// ---- the runtime's sections (read and written through these lists)

template <class V>
void fields(V& v, ApproximateTimeSettings& s) {
  v("queue_size", s.queue_size);
  v("max_interval_duration_s", s.max_interval_duration_s);
  v("age_penalty", s.age_penalty);
}

template <class V>
void fields(V& v, InputGuardSettings& s) {
  v("clock_step_messages", s.clock_step_messages);
  v("jump_speed_factor", s.jump_speed_factor);
  v("jump_margin_m", s.jump_margin_m);
  v("jump_margin_rad", s.jump_margin_rad);
  v("garbled_step_m", s.garbled_step_m);
  v("garbled_fraction", s.garbled_fraction);
  v("sensor_timeout_periods", s.sensor_timeout_periods);
}

template <class V>
void fields(V& v, ScanMatchSettings& s) {
  v("linear_window_m", s.linear_window_m);
  v("angular_window_deg", s.angular_window_deg);
  v("linear_step_m", s.linear_step_m);
  v("angular_step_deg", s.angular_step_deg);
  v("sigma_m", s.sigma_m);
  v("max_distance_m", s.max_distance_m);
  v("prior_sigma_m", s.prior_sigma_m);
  v("prior_sigma_deg", s.prior_sigma_deg);
  v("min_points", s.min_points);
  v("min_score", s.min_score);
  v("runner_up_distance_m", s.runner_up_distance_m);
}

template <class V>
void fields(V& v, PoseCorrectionSettings& s) {
  v("enabled", s.enabled);
  v("gain", s.gain);
  v("rate_gain", s.rate_gain);
  v("rate_gain_initial", s.rate_gain_initial);
  v("reference_age_s", s.reference_age_s);
  v("min_height_m", s.min_height_m);
  v("max_height_m", s.max_height_m);
  v("pixel_step", s.pixel_step);
  v("max_points", s.max_points);
  v("relocalize_after", s.relocalize_after);
  v("relocalize_window_m", s.relocalize_window_m);
  v("relocalize_window_deg", s.relocalize_window_deg);
  v("relocalize_step_m", s.relocalize_step_m);
  v("relocalize_step_deg", s.relocalize_step_deg);
  v("relocalize_min_gain", s.relocalize_min_gain);
  v("relocalize_min_conflict", s.relocalize_min_conflict);
  v("relocalize_min_margin", s.relocalize_min_margin);
  v("relocalize_distinct_m", s.relocalize_distinct_m);
  v("relocalize_min_clearance_m", s.relocalize_min_clearance_m);
  v("relocalize_edge_steps", s.relocalize_edge_steps);
  v.section("match", [&](auto& w) { fields(w, s.match); });
}

template <class V>
void fields(V& v, PoseGraphSettings& s) {
  v("max_iterations", s.max_iterations);
  v("min_relative_decrease", s.min_relative_decrease);
  v("huber_delta", s.huber_delta);
  v("fixed_node", s.fixed_node);
}

template <class V>
void fields(V& v, LoopClosureSettings& s) {
  v("enabled", s.enabled);
  v("submap_duration_s", s.submap_duration_s);
  v("submap_travel_m", s.submap_travel_m);
  v("check_period_s", s.check_period_s);
  v("query_window_s", s.query_window_s);
  v("min_age_s", s.min_age_s);
  v("search_radius_m", s.search_radius_m);
  v("max_query_points", s.max_query_points);
  v("verify_hit_m", s.verify_hit_m);
  v("verify_free_m", s.verify_free_m);
  v("min_hits", s.min_hits);
  v("max_conflict_ratio", s.max_conflict_ratio);
  v("min_prediction_conflict", s.min_prediction_conflict);
  v("prediction_check_min_shift_m", s.prediction_check_min_shift_m);
  v("confirm_m", s.confirm_m);
  v("confirm_deg", s.confirm_deg);
  v("min_correction_m", s.min_correction_m);
  v("min_correction_deg", s.min_correction_deg);
  v("odom_sigma_xy_m", s.odom_sigma_xy_m);
  v("odom_sigma_xy_per_m", s.odom_sigma_xy_per_m);
  v("odom_sigma_theta_deg", s.odom_sigma_theta_deg);
  v("odom_sigma_theta_per_m", s.odom_sigma_theta_per_m);
  v("loop_sigma_xy_m", s.loop_sigma_xy_m);
  v("loop_sigma_theta_deg", s.loop_sigma_theta_deg);
  v("max_loop_chi2", s.max_loop_chi2);
  v.section("match", [&](auto& w) { fields(w, s.match); });
  v.section("graph", [&](auto& w) { fields(w, s.graph); });
}

/// The explorer's goal life cycle (Navigator): keys of the `exploration` section.
template <class V>
void goal_fields(V& v, ExplorerSettings& s) {
  v("goal_timeout_s", s.goal_timeout_s);
  v("nominal_speed_mps", s.nominal_speed_mps);
  v("blacklist_ttl_s", s.blacklist_ttl_s);
  v("final_retries", s.final_retries);
  v("max_goal_failures", s.max_goal_failures);
  v("blocked_recovery_s", s.blocked_recovery_s);
  v.choice("on_done", s.on_done, kOnDoneNames);
  v("patrol_spacing_m", s.patrol_spacing_m);
  v("stop_when_no_frontier", s.stop_when_no_frontier);
  v("goal_standoff_search_m", s.goal_standoff_search_m);
  v("squeeze_margin_m", s.squeeze_margin_m);
  v("squeeze_anywhere", s.squeeze_anywhere);
  v("squeeze_min_unknown_m2", s.squeeze_min_unknown_m2);
  v("boxed_in_area_m2", s.boxed_in_area_m2);
  v("view_range_m", s.view_range_m);
  v("view_min_range_m", s.view_min_range_m);
  v("view_rays", s.view_rays);
  v("view_frontier_weight", s.view_frontier_weight);
  v("simulated_goal_handoff_m", s.simulated_goal_handoff_m);
  v("view_looks", s.view_looks);
  v("view_relook_after_s", s.view_relook_after_s);
  v("view_relook_dwell_s", s.view_relook_dwell_s);
  v("view_min_gain_m2", s.view_min_gain_m2);
  v("view_gain_window_s", s.view_gain_window_s);
  v("look_with_any_sensor", s.look_with_any_sensor);
  v("frontier_seen_radius_m", s.frontier_seen_radius_m);
  v("clear_footprint", s.clear_footprint);
  v("recent_obstacles_s", s.recent_obstacles_s);
  v("recent_obstacle_range_m", s.recent_obstacle_range_m);
  v("recent_obstacle_min_scans", s.recent_obstacle_min_scans);
}

/// The controller's behaviours (Controller): the `control` section.
template <class V>
void control_fields(V& v, ExplorerSettings& s) {
  v("stuck_timeout_s", s.stuck_timeout_s);
  v("stall_timeout_s", s.stall_timeout_s);
  v("contact_radius_m", s.contact_radius_m);
  v("cornered_after_s", s.cornered_after_s);
  v("slow_clearance_m", s.slow_clearance_m);
  v("slow_speed_mps", s.slow_speed_mps);
  v("few_features_speed_mps", s.few_features_speed_mps);
  v("seek_after_s", s.seek_after_s);
  v("seek_cooldown_s", s.seek_cooldown_s);
  v("seek_min_turn_rad", s.seek_min_turn_rad);
  v("seek_min_range_m", s.seek_min_range_m);
  v("seek_range_m", s.seek_range_m);
}

/// The `runtime` section.
template <class V>
void runtime_fields(V& v, RuntimeSettings& s) {
  v("control_rate_hz", s.control_rate_hz);
  v("map_rate_hz", s.map_rate_hz);
  v("sensor_rate_hz", s.sensor_rate_hz);
  v.choice("execution", s.execution, kExecutionNames);
  v("background_threads", s.background_threads);
  v.section("synchronizer", [&](auto& w) { fields(w, s.sync); });
  v.section("input", [&](auto& w) { fields(w, s.input); });
}

/// The `localization` section.
template <class V>
void fields(V& v, PoseEkfSettings& s) {
  v("wheel_speed_sigma", s.wheel_speed_sigma);
  v("wheel_yaw_rate_sigma", s.wheel_yaw_rate_sigma);
  v("gyro_sigma", s.gyro_sigma);
  v("wheel_scale_sigma", s.wheel_scale_sigma);
  v("wheel_bias_sigma", s.wheel_bias_sigma);
  v("wheel_scale_walk", s.wheel_scale_walk);
  v("wheel_bias_walk", s.wheel_bias_walk);
  v("visual_min_sigma_m", s.visual_min_sigma_m);
  v("visual_min_sigma_deg", s.visual_min_sigma_deg);
  v("gate_chi2", s.gate_chi2);
}

template <class V>
void fields(V& v, VisualLocalizationSettings& s) {
  v("enabled", s.enabled);
  v("rate_hz", s.rate_hz);
  v("fuse_every_set", s.fuse_every_set);
  v("good_min_inliers", s.good_min_inliers);
  v("fuse_min_inliers", s.fuse_min_inliers);
  v("learn_wheels_min_inliers", s.learn_wheels_min_inliers);
  v("degraded_after_s", s.degraded_after_s);
  v("lost_after_s", s.lost_after_s);
  v("keyframe_translation_m", s.odometer.keyframe_translation_m);
  v("keyframe_rotation_deg", s.odometer.keyframe_rotation_deg);
  v("keyframe_inlier_ratio", s.odometer.keyframe_inlier_ratio);
  v("reset_after_failures", s.odometer.reset_after_failures);
  v("odometry_heading_from_gyro", s.odometry_heading_from_gyro);
  v.section("features", [&](auto& w) {
    w("max_features", s.odometer.frame.orb.max_features);
    w("scale_factor", s.odometer.frame.orb.scale_factor);
    w("levels", s.odometer.frame.orb.levels);
    w("fast_threshold", s.odometer.frame.orb.fast_threshold);
    w("min_fast_threshold", s.odometer.frame.orb.min_fast_threshold);
    w("grid_cols", s.odometer.frame.orb.grid_cols);
    w("grid_rows", s.odometer.frame.orb.grid_rows);
    w("min_depth_m", s.odometer.frame.min_depth_m);
    w("max_depth_m", s.odometer.frame.max_depth_m);
  });
  v.section("motion", [&](auto& w) {
    w("max_hamming", s.odometer.odometry.match.max_distance);
    w("ratio", s.odometer.odometry.match.ratio);
    w("cross_check", s.odometer.odometry.match.cross_check);
    w("guided_radius_px", s.odometer.odometry.guided_radius_px);
    w("fundamental_filter", s.odometer.odometry.fundamental_filter);
    w("fundamental_threshold_px", s.odometer.odometry.fundamental_threshold_px);
    w("inlier_threshold_px", s.odometer.odometry.inlier_threshold_px);
    w("max_hypotheses", s.odometer.odometry.max_hypotheses);
    w("refine_iterations", s.odometer.odometry.refine_iterations);
    w("rematch_radius_px", s.odometer.odometry.rematch_radius_px);
    w("min_inliers", s.odometer.odometry.min_inliers);
  });
  v.section("ekf", [&](auto& w) { fields(w, s.ekf); });
}

template <class V>
void localization_fields(V& v, RuntimeSettings& s) {
  v.section("pose_correction", [&](auto& w) { fields(w, s.pose_correction); });
  v.section("loop_closure", [&](auto& w) { fields(w, s.loop_closure); });
  v.section("visual_odometry", [&](auto& w) { fields(w, s.visual_odometry); });
}

// ---- the robot's and the kernels' sections

/// The sensor's focal lengths are what profile.cpp derives from its fields of view.
inline bool fov_form(const SensorProfile& s) {
  constexpr double kDeg = 0.017453292519943295;
  const double w = s.intrinsics.width, h = s.intrinsics.height;
  return s.intrinsics.fx == static_cast<float>(0.5 * w / std::tan(0.5 * s.fov_h_deg * kDeg)) &&
         s.intrinsics.fy == static_cast<float>(0.5 * h / std::tan(0.5 * s.fov_v_deg * kDeg));
}

template <class V>
void fields(V& v, ChassisProfile& c) {
  v("type", c.type);
  v("radius_m", c.radius_m);
  v("footprint_diameter_m", c.footprint_diameter_m);
  v("wheel_base_m", c.wheel_base_m);
  v("wheel_diameter_m", c.wheel_diameter_m);
  v("max_linear_speed_mps", c.max_linear_speed_mps);
  v("max_angular_speed_dps", c.max_angular_speed_dps);
  v("odometry_rate_hz", c.odometry_rate_hz);
}

template <class V>
void fields(V& v, SensorProfile& s) {
  v("name", s.name);
  v.section("intrinsics", [&](auto& w) {
    w("width", s.intrinsics.width);
    w("height", s.intrinsics.height);
    if (fov_form(s)) {  // the focal lengths are the fields of view's (as the profile gave them): those read back exactly
      w("fov_h_deg", s.fov_h_deg);
      w("fov_v_deg", s.fov_v_deg);
    } else {
      w("fx", s.intrinsics.fx);
      w("fy", s.intrinsics.fy);
    }
    w("cx", s.intrinsics.cx);
    w("cy", s.intrinsics.cy);
  });
  v("rate_hz", s.rate_hz);
  v("min_depth_m", s.min_depth_m);
  v("max_depth_m", s.max_depth_m);
  v("depth_units_per_m", s.depth_units_per_m);
  v.section("extrinsics", [&](auto& w) {
    w("xyz_m", s.extrinsics.xyz_m);
    w("zyx_euler_deg", s.extrinsics.zyx_euler_deg);
  });
}

template <class V>
void fields(V& v, MappingSettings& m) {
  v.section("back_projection", [&](auto& w) {
    w("min_depth_m", m.back_projection.min_depth_m);
    w("max_depth_m", m.back_projection.max_depth_m);
    w("pixel_step", m.back_projection.pixel_step);
  });
  v.section("voxel_filter", [&](auto& w) {
    w("leaf_size_m", m.voxel_filter.leaf_size_m);
    w("min_points_per_voxel", m.voxel_filter.min_points_per_voxel);
  });
  v.section("normals", [&](auto& w) {
    w("k", m.normals.k);
    w("viewpoint_m", m.normals.viewpoint);
  });
  v.section("segmentation", [&](auto& w) {
    SegmentationSettings& g = m.segmentation;
    w("floor_z_m", g.floor_z_m);
    w("max_floor_tilt_deg", g.max_floor_tilt_deg);
    w("floor_height_threshold_m", g.floor_height_threshold_m);
    w("min_height_m", g.min_height_m);
    w("max_height_m", g.max_height_m);
    w.section("clustering", [&](auto& x) {
      x("tolerance_m", g.clustering.tolerance_m);
      x("min_size", g.clustering.min_size);
      x("max_size", g.clustering.max_size);
    });
  });
  v.section("grid_update", [&](auto& w) {
    GridUpdateSettings& g = m.grid_update;
    w("hit_logodds", g.hit_logodds);
    w("miss_logodds", g.miss_logodds);
    w("min_logodds", g.min_logodds);
    w("max_logodds", g.max_logodds);
    w("clear_along_rays", g.clear_along_rays);
    w.up_to_inf("clear_max_height_m", g.clear_max_height_m);  // .inf (the default): every ray clears
    w("keep_occupied_within_m", g.keep_occupied_within_m);
    w("keep_occupied_logodds", g.keep_occupied_logodds);
    w("max_ray_length_m", g.max_ray_length_m);
    w("grow_margin_cells", g.grow_margin_cells);
  });
  v("grid_resolution_m", m.grid_resolution_m);
}

/// The kernels' part of the `exploration` section.
template <class V>
void fields(V& v, ExplorationProfile& e) {
  v("rays_per_sensor", e.rays_per_sensor);
  v.section("cells", [&](auto& w) {
    w("occupied_logodds", e.cells.occupied_logodds);
    w("free_logodds", e.cells.free_logodds);
  });
  v.section("observation", [&](auto& w) {
    w.choice("backend", e.observation.backend, kBackendNames);
    w("tile_cells", e.observation.tile_cells);
  });
  v.section("inflation", [&](auto& w) {
    w("robot_radius_m", e.inflation.robot_radius_m);
    w("unknown_is_obstacle", e.inflation.unknown_is_obstacle);
    w("uncertain_is_obstacle", e.inflation.uncertain_is_obstacle);
  });
  v.section("path", [&](auto& w) {
    w("allow_diagonal", e.path.allow_diagonal);
    w("clearance_weight", e.path.clearance_weight);
    w("clearance_decay_m", e.path.clearance_decay_m);
    w("goal_tolerance_m", e.path.goal_tolerance_m);
  });
  v.section("frontier", [&](auto& w) {
    FrontierSettings& f = e.strategy.frontier;
    w("min_cluster_cells", f.min_cluster_cells);
    w("min_goal_distance_m", f.min_goal_distance_m);
    w("blacklist_radius_m", f.blacklist_radius_m);
    w("approach_radius_m", f.approach_radius_m);
    w("min_unknown_region_m2", f.min_unknown_region_m2);
    w.choice("selection", f.selection, kSelectionNames);
    w("potential_scale", f.potential_scale);
    w("gain_scale", f.gain_scale);
  });
  v.section("simulation", [&](auto& w) {
    PartialSimSettings& p = e.strategy.simulation;
    w("iterations", p.iterations);
    w("particles", p.particles);
    w("phi_a", p.phi_a);
    w("phi_b", p.phi_b);
    w("stages", p.stages);
    w("stage_dt_s", p.stage_dt_s);
    w("v_min_mps", p.v_min_mps);
    w("v_max_mps", p.v_max_mps);
    w("omega_max_rps", p.omega_max_rps);
    w("sigma_v_mps", p.sigma_v_mps);
    w("sigma_omega_rps", p.sigma_omega_rps);
    w("resample_ess_fraction", p.resample_ess_fraction);
    w("gamma", p.gamma);
    w("unknown_hit_probability", p.unknown_hit_probability);
    w("hit_logodds", p.hit_logodds);
    w("miss_logodds", p.miss_logodds);
    w("ism_noise_logodds", p.ism_noise_logodds);
    w("min_logodds", p.min_logodds);
    w("max_logodds", p.max_logodds);
    w("min_goal_distance_m", p.min_goal_distance_m);
    w("max_goal_distance_m", p.max_goal_distance_m);
    w("collision_step_m", p.collision_step_m);
    w("seed", p.seed);
  });
  v("eps_r_bits", e.strategy.eps_r_bits);
  v("eps_r_unknown_only", e.strategy.eps_r_unknown_only);
  v("use_simulation", e.strategy.use_simulation);
  v.section("dwa", [&](auto& w) {
    DwaSettings& d = e.dwa;
    w("max_v_mps", d.limits.max_v_mps);
    w("min_v_mps", d.limits.min_v_mps);
    w("max_omega_rps", d.limits.max_omega_rps);
    w("max_accel_mps2", d.limits.max_accel_mps2);
    w("max_alpha_rps2", d.limits.max_alpha_rps2);
    w("mapping_max_omega_rps", d.mapping_max_omega_rps);
    w("mapping_max_alpha_rps2", d.mapping_max_alpha_rps2);
    w("control_period_s", d.control_period_s);
    w("v_samples", d.v_samples);
    w("omega_samples", d.omega_samples);
    w("steps", d.steps);
    w("sim_time_s", d.sim_time_s);
    w("safety_margin_m", d.safety_margin_m);
    w("w_progress", d.w_progress);
    w("w_path", d.w_path);
    w("w_clearance", d.w_clearance);
    w("w_speed", d.w_speed);
    w("clearance_cap_m", d.clearance_cap_m);
    w("lookahead_m", d.lookahead_m);
    w("goal_tolerance_m", d.goal_tolerance_m);
    w("oscillation_window_calls", d.oscillation_window_calls);
    w("oscillation_min_progress_m", d.oscillation_min_progress_m);
    w("oscillation_min_turn_rad", d.oscillation_min_turn_rad);
    w("recovery_max_calls", d.recovery_max_calls);
    w("rotate_omega_rps", d.rotate_omega_rps);
    w("rotate_tolerance_rad", d.rotate_tolerance_rad);
    w("backoff_distance_m", d.backoff_distance_m);
    w("backoff_speed_mps", d.backoff_speed_mps);
  });
}

}  // namespace duet::detail
