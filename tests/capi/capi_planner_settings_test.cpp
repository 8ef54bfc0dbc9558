// The exploration planner's settings through the C API (duet.h, "Exploration planner"): the
// init functions give the built-in dual profile's values, and every status has its string.
#include "capi_planner_util.hpp"

using namespace duet_capi_test;

// The tests sit in the shared parts' namespace: a using-directive for it at file scope would
// reach the next file of a unity batch.
namespace duet_capi_planner_test {

// The C defaults are the built-in dual profile's (the values duet explore and duet_runtime run with).
TEST(CapiPlannerSettings, InitFunctionsMirrorTheBuiltInProfile) {
  duet_sensor_sector ss;
  duet_sensor_sector_init(&ss);
  const duet::SensorSector css;
  EXPECT_EQ(ss.x_m, css.x_m);
  EXPECT_EQ(ss.y_m, css.y_m);
  EXPECT_EQ(ss.yaw_rad, css.yaw_rad);
  EXPECT_EQ(ss.fov_rad, css.fov_rad);
  EXPECT_EQ(ss.min_range_m, css.min_range_m);
  EXPECT_EQ(ss.max_range_m, css.max_range_m);
  EXPECT_EQ(ss.rays, css.rays);

  duet_sensor_sector dual[2];
  duet_paper_dual_sensors(dual, 17);
  const auto cdual = duet::paper_dual_sensors(17);
  ASSERT_EQ(cdual.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(dual[i].x_m, cdual[i].x_m);
    EXPECT_EQ(dual[i].y_m, cdual[i].y_m);
    EXPECT_EQ(dual[i].yaw_rad, cdual[i].yaw_rad);
    EXPECT_EQ(dual[i].fov_rad, cdual[i].fov_rad);
    EXPECT_EQ(dual[i].min_range_m, cdual[i].min_range_m);
    EXPECT_EQ(dual[i].max_range_m, cdual[i].max_range_m);
    EXPECT_EQ(dual[i].rays, 17);
  }

  duet_observation_settings os;
  duet_observation_settings_init(&os);
  const duet::ObservationSettings& cos = dual_profile().exploration.observation;
  EXPECT_EQ(os.thresholds.occupied_logodds, cos.thresholds.occupied_logodds);
  EXPECT_EQ(os.thresholds.free_logodds, cos.thresholds.free_logodds);
  EXPECT_EQ(static_cast<int>(os.backend), static_cast<int>(cos.backend));  // same numbering
  EXPECT_EQ(os.tile_cells, cos.tile_cells);

  duet_inflation_settings is;
  duet_inflation_settings_init(&is);
  const duet::InflationSettings& cis = dual_profile().exploration.inflation;
  EXPECT_EQ(is.thresholds.occupied_logodds, cis.thresholds.occupied_logodds);
  EXPECT_EQ(is.thresholds.free_logodds, cis.thresholds.free_logodds);
  EXPECT_EQ(is.robot_radius_m, cis.robot_radius_m);
  EXPECT_EQ(is.unknown_is_obstacle, cis.unknown_is_obstacle ? 1 : 0);
  EXPECT_EQ(is.uncertain_is_obstacle, cis.uncertain_is_obstacle ? 1 : 0);
  EXPECT_EQ(is.uncertain_is_obstacle, 1);

  duet_path_settings ps;
  duet_path_settings_init(&ps);
  const duet::PathSettings& cps = dual_profile().exploration.path;
  EXPECT_EQ(ps.allow_diagonal, cps.allow_diagonal ? 1 : 0);
  EXPECT_EQ(ps.clearance_weight, cps.clearance_weight);
  EXPECT_EQ(ps.clearance_decay_m, cps.clearance_decay_m);
  EXPECT_EQ(ps.goal_tolerance_m, cps.goal_tolerance_m);

  duet_frontier_settings fs;
  duet_frontier_settings_init(&fs);
  const duet::FrontierSettings& cfs = dual_profile().exploration.strategy.frontier;
  EXPECT_EQ(fs.min_cluster_cells, cfs.min_cluster_cells);
  EXPECT_EQ(fs.min_goal_distance_m, cfs.min_goal_distance_m);
  EXPECT_EQ(fs.blacklist_radius_m, cfs.blacklist_radius_m);
  EXPECT_EQ(fs.approach_radius_m, cfs.approach_radius_m);
  EXPECT_EQ(fs.min_unknown_region_m2, cfs.min_unknown_region_m2);

  duet_partial_sim_settings sim;
  duet_partial_sim_settings_init(&sim);
  const duet::PartialSimSettings& csim = dual_profile().exploration.strategy.simulation;
  EXPECT_EQ(sim.iterations, csim.iterations);
  EXPECT_EQ(sim.particles, csim.particles);
  EXPECT_EQ(sim.phi_a, csim.phi_a);
  EXPECT_EQ(sim.phi_b, csim.phi_b);
  EXPECT_EQ(sim.stages, csim.stages);
  EXPECT_EQ(sim.stage_dt_s, csim.stage_dt_s);
  EXPECT_EQ(sim.v_min_mps, csim.v_min_mps);
  EXPECT_EQ(sim.v_max_mps, csim.v_max_mps);
  EXPECT_EQ(sim.omega_max_rps, csim.omega_max_rps);
  EXPECT_EQ(sim.sigma_v_mps, csim.sigma_v_mps);
  EXPECT_EQ(sim.sigma_omega_rps, csim.sigma_omega_rps);
  EXPECT_EQ(sim.resample_ess_fraction, csim.resample_ess_fraction);
  EXPECT_EQ(sim.gamma, csim.gamma);
  EXPECT_EQ(sim.unknown_hit_probability, csim.unknown_hit_probability);
  EXPECT_EQ(sim.hit_logodds, csim.hit_logodds);
  EXPECT_EQ(sim.miss_logodds, csim.miss_logodds);
  EXPECT_EQ(sim.ism_noise_logodds, csim.ism_noise_logodds);
  EXPECT_EQ(sim.min_logodds, csim.min_logodds);
  EXPECT_EQ(sim.max_logodds, csim.max_logodds);
  EXPECT_EQ(sim.min_goal_distance_m, csim.min_goal_distance_m);
  EXPECT_EQ(sim.max_goal_distance_m, csim.max_goal_distance_m);
  EXPECT_EQ(sim.collision_step_m, csim.collision_step_m);
  EXPECT_EQ(sim.seed, csim.seed);

  duet_exploration_settings es;
  duet_exploration_settings_init(&es);
  const duet::ExplorationSettings& ces = dual_profile().exploration.strategy;
  EXPECT_EQ(es.eps_r_bits, ces.eps_r_bits);
  EXPECT_EQ(es.use_simulation, ces.use_simulation ? 1 : 0);
  EXPECT_EQ(es.simulation.particles, ces.simulation.particles);
  EXPECT_EQ(es.simulation.seed, ces.simulation.seed);
  EXPECT_EQ(es.frontier.min_cluster_cells, ces.frontier.min_cluster_cells);
  EXPECT_EQ(es.frontier.blacklist_radius_m, ces.frontier.blacklist_radius_m);
  EXPECT_EQ(es.frontier.approach_radius_m, ces.frontier.approach_radius_m);

  duet_dwa_settings ds;
  duet_dwa_settings_init(&ds);
  const duet::DwaSettings& cds = dual_profile().exploration.dwa;
  EXPECT_EQ(ds.limits.max_v_mps, cds.limits.max_v_mps);
  EXPECT_EQ(ds.limits.min_v_mps, cds.limits.min_v_mps);
  EXPECT_EQ(ds.limits.max_omega_rps, cds.limits.max_omega_rps);
  EXPECT_EQ(ds.limits.max_accel_mps2, cds.limits.max_accel_mps2);
  EXPECT_EQ(ds.limits.max_alpha_rps2, cds.limits.max_alpha_rps2);
  EXPECT_EQ(ds.mapping_max_omega_rps, cds.mapping_max_omega_rps);
  EXPECT_EQ(ds.mapping_max_alpha_rps2, cds.mapping_max_alpha_rps2);
  EXPECT_EQ(ds.control_period_s, cds.control_period_s);
  EXPECT_EQ(ds.v_samples, cds.v_samples);
  EXPECT_EQ(ds.omega_samples, cds.omega_samples);
  EXPECT_EQ(ds.steps, cds.steps);
  EXPECT_EQ(ds.sim_time_s, cds.sim_time_s);
  EXPECT_EQ(ds.robot_radius_m, cds.robot_radius_m);
  EXPECT_EQ(ds.safety_margin_m, cds.safety_margin_m);
  EXPECT_EQ(ds.w_progress, cds.w_progress);
  EXPECT_EQ(ds.w_path, cds.w_path);
  EXPECT_EQ(ds.w_clearance, cds.w_clearance);
  EXPECT_EQ(ds.w_speed, cds.w_speed);
  EXPECT_EQ(ds.clearance_cap_m, cds.clearance_cap_m);
  EXPECT_EQ(ds.lookahead_m, cds.lookahead_m);
  EXPECT_EQ(ds.goal_tolerance_m, cds.goal_tolerance_m);
  EXPECT_EQ(ds.oscillation_window_calls, cds.oscillation_window_calls);
  EXPECT_EQ(ds.oscillation_min_progress_m, cds.oscillation_min_progress_m);
  EXPECT_EQ(ds.oscillation_min_turn_rad, cds.oscillation_min_turn_rad);
  EXPECT_EQ(ds.recovery_max_calls, cds.recovery_max_calls);
  EXPECT_EQ(ds.rotate_omega_rps, cds.rotate_omega_rps);
  EXPECT_EQ(ds.rotate_tolerance_rad, cds.rotate_tolerance_rad);
  EXPECT_EQ(ds.backoff_distance_m, cds.backoff_distance_m);
  EXPECT_EQ(ds.backoff_speed_mps, cds.backoff_speed_mps);

  // NULL is ignored.
  duet_sensor_sector_init(nullptr);
  duet_observation_settings_init(nullptr);
  duet_inflation_settings_init(nullptr);
  duet_path_settings_init(nullptr);
  duet_frontier_settings_init(nullptr);
  duet_partial_sim_settings_init(nullptr);
  duet_exploration_settings_init(nullptr);
  duet_dwa_settings_init(nullptr);
}

TEST(CapiPlannerSettings, StatusStrings) {
  EXPECT_STREQ(duet_path_status_string(DUET_PATH_FOUND), "DUET_PATH_FOUND");
  EXPECT_STREQ(duet_path_status_string(DUET_PATH_OUTSIDE_GRID), "DUET_PATH_OUTSIDE_GRID");
  EXPECT_STREQ(duet_frontier_status_string(DUET_FRONTIER_ALL_BLACKLISTED), "DUET_FRONTIER_ALL_BLACKLISTED");
  EXPECT_STREQ(duet_exploration_status_string(DUET_EXPLORATION_SIMULATED_GOAL), "DUET_EXPLORATION_SIMULATED_GOAL");
  EXPECT_STREQ(duet_exploration_status_string(DUET_EXPLORATION_ROBOT_BLOCKED), "DUET_EXPLORATION_ROBOT_BLOCKED");
  EXPECT_STREQ(duet_dwa_status_string(DUET_DWA_NO_PATH), "DUET_DWA_NO_PATH");
  // Values that are not enumerators. C code may pass any int; from C++ only values inside the
  // enums' value range (0..7 here: 3 bits) can be passed without undefined behaviour (and the
  // sanitizer build checks that), so the out-of-enumerator values tested are 5/6..7.
  for (int v = 5; v <= 7; ++v) {
    EXPECT_STREQ(duet_path_status_string(static_cast<duet_path_status>(v)), "DUET_PATH_?");
    EXPECT_STREQ(duet_frontier_status_string(static_cast<duet_frontier_status>(v)), "DUET_FRONTIER_?");
  }
  for (int v = 6; v <= 7; ++v) {
    EXPECT_STREQ(duet_exploration_status_string(static_cast<duet_exploration_status>(v)), "DUET_EXPLORATION_?");
    EXPECT_STREQ(duet_dwa_status_string(static_cast<duet_dwa_status>(v)), "DUET_DWA_?");
  }
  // Each enumerator has its own name.
  for (int v = 0; v <= 5; ++v) {
    EXPECT_STRNE(duet_exploration_status_string(static_cast<duet_exploration_status>(v)), "DUET_EXPLORATION_?");
    EXPECT_STRNE(duet_dwa_status_string(static_cast<duet_dwa_status>(v)), "DUET_DWA_?");
  }
  for (int v = 0; v <= 4; ++v) {
    EXPECT_STRNE(duet_path_status_string(static_cast<duet_path_status>(v)), "DUET_PATH_?");
    EXPECT_STRNE(duet_frontier_status_string(static_cast<duet_frontier_status>(v)), "DUET_FRONTIER_?");
  }
}

}  // namespace duet_capi_planner_test
