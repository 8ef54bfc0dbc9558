/// @file explore_outputs.cpp
/// The outputs of one simulated run (see explore_outputs.hpp).
#include "explore_outputs.hpp"

#include "commands.hpp"

#include <duet/runtime/io/cloud_io.hpp>
#include <duet/runtime/io/grid_io.hpp>
#include <duet/runtime/io/output.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace duet::app {

nlohmann::json to_json(const sim::ExploreSummary& s) {
  nlohmann::json j;
  j["world"] = s.world;
  j["start"] = {{"x_m", s.start.x}, {"y_m", s.start.y}, {"theta_rad", s.start.theta}};
  j["profile"] = s.profile;
  j["seed"] = s.seed;
  j["stop_reason"] = sim::to_string(s.stop_reason);
  j["explorer_status"] = s.explorer_status;
  j["stop_detail"] = s.stop_detail;
  j["left_unexplored"] = left_json(s.left);
  j["explorer_state"] = s.explorer_state;
  j["sim_time_s"] = s.sim_time_s;
  j["wall_time_s"] = s.wall_time_s;
  j["speed_vs_real_time"] = s.wall_time_s > 0.0 ? s.sim_time_s / s.wall_time_s : 0.0;
  j["explored_area_m2"] = s.explored_area_m2;
  j["reachable_free_area_m2"] = s.reachable_free_area_m2;
  j["coverage"] = s.coverage;
  auto opt_time = [](double t) { return t >= 0.0 ? nlohmann::json(t) : nlohmann::json(nullptr); };
  j["t90_s"] = opt_time(s.t90_s);
  j["t_31m2_s"] = opt_time(s.t_paper_area_s);
  j["target_region_entered_s"] = opt_time(s.target_entered_s);
  j["path_length_m"] = s.path_length_m;
  j["collisions"] = s.collisions;
  const auto& e = s.explorer;
  j["decisions"] = {{"count", e.decisions},
                    {"simulated_goals", e.simulated_goals},
                    {"frontier_fallback_goals", e.frontier_goals},
                    {"mean_time_ms", e.decisions ? 1e3 * e.decision_time_sum_s / e.decisions : 0.0},
                    {"max_time_ms", 1e3 * e.decision_time_max_s}};
  j["goals"] = {{"reached", e.goals_reached},
                {"abandoned_timeout", e.goals_abandoned_timeout},
                {"abandoned_no_path", e.goals_abandoned_no_path},
                {"abandoned_stuck", e.goals_abandoned_stuck},
                {"abandoned_blocked", e.goals_abandoned_blocked},
                {"replans", e.replans},
                {"dwa_local_fallbacks", e.local_fallbacks},
                {"escapes", e.escapes},
                {"cornered_escapes", e.cornered_escapes},
                {"blocked_recoveries", e.blocked_recoveries},
                {"blocked_escapes", e.blocked_escapes},
                {"slowed_periods", e.slowed},
                {"few_feature_periods", e.few_feature_periods},
                {"feature_seeks", e.feature_seeks},
                {"goals_moved", e.goals_moved},
                {"relaxed_goals", e.relaxed_goals},
                {"boxed_in_goals", e.boxed_in_goals},
                {"stalls", e.stalls},
                {"view_goals", e.view_goals},
                {"view_goals_reached", e.view_goals_reached},
                {"frontier_goals_seen", e.frontier_goals_seen},
                {"patrol_waypoints", e.patrol_waypoints},
                {"patrol_reached", e.patrol_reached},
                {"patrol_skipped", e.patrol_skipped},
                {"patrol_laps", e.patrol_laps},
                {"recent_obstacle_cells", e.recent_obstacle_cells},
                {"footprint_clearings", e.footprint_clearings}};
  j["frames_rendered"] = s.frames_rendered;
  j["sets_integrated"] = s.sets_integrated;
  j["sets_not_integrated"] = s.sets_not_integrated;
  j["frame_drops"] = s.frame_drops;
  j["odometry_unmatched"] = s.odometry_unmatched;
  j["odometry_error_end_m"] = s.odometry_error_m;
  const std::string odom_source = s.visual_odometry ? "wheels + vision (EKF)" : "odometry";
  j["pose"] = {{"source", s.scan_matches + s.scan_match_rejected > 0 ? odom_source + " + scan matching" : odom_source},
               {"error_end_m", s.pose_error_m},
               {"error_max_m", s.pose_error_max_m},
               {"heading_error_end_deg", s.heading_error_deg},
               {"heading_rate_end_radps", s.heading_rate_radps},
               {"gyro_bias_true_radps", s.gyro_bias_radps},
               {"scan_matches", s.scan_matches},
               {"scan_match_rejected", s.scan_match_rejected},
               {"relocalizations_held", s.relocalizations_held},
               {"relocalizations_new_space", s.relocalizations_new_space},
               {"relocalizations_ambiguous", s.relocalizations_ambiguous},
               {"relocalizations_in_obstacle", s.relocalizations_in_obstacle},
               {"relocalizations_at_edge", s.relocalizations_at_edge},
               {"relocalizations_asked", s.relocalizations_asked},
               {"scan_match_time_s", s.scan_match_time_s}};
  if (s.visual_odometry)
    j["pose"]["visual_odometry"] = {{"health_end", s.localization_health},
                                    {"sets", s.visual.sets},
                                    {"accepted", s.visual.accepted},
                                    {"tracked_not_fused", s.visual.tracked_not_fused},
                                    {"gated", s.visual.gated},
                                    {"failed", s.visual.failed},
                                    {"failed_features", s.visual.too_few_features},
                                    {"failed_matches", s.visual.too_few_matches},
                                    {"failed_inliers", s.visual.too_few_inliers},
                                    {"incomplete_sets", s.visual_sets_incomplete},
                                    {"busy_sets", s.visual_sets_busy},
                                    {"location_points", s.visual.location_points},
                                    {"resets", s.visual.resets},
                                    {"time_s", s.visual.time_s},
                                    {"wheel_scale", s.visual.wheel_scale},
                                    {"wheel_scale_min", s.visual.wheel_scale_min},
                                    {"wheel_scale_max", s.visual.wheel_scale_max},
                                    {"wheel_yaw_bias_radps", s.visual.wheel_bias},
                                    {"mean_nis", s.visual.mean_nis}};
  j["faults"] = faults_json(s.faults);
  j["input"] = input_json(s.input, s.sets_with_missing, s.blind_holds, s.relocalizations);
  j["occupied_cells_on_obstacles"] = s.occupied_on_obstacles >= 0.0 ? nlohmann::json(s.occupied_on_obstacles) : nlohmann::json(nullptr);
  j["runtime"] = timing_json(s.timing);
  j["runtime"]["execution"] = to_string(s.execution);
  j["runtime"]["paced_by_wall_clock"] = s.realtime;
  j["runtime"]["map_sets_skipped"] = s.map_sets_skipped;
  j["loop_closure"] = {{"enabled", s.loop_closure},
                       {"checks", s.loops.checks},
                       {"matches", s.loops.matches},
                       {"rejected_edge", s.loops.rejected_edge},
                       {"rejected_free_space", s.loops.rejected_free_space},
                       {"rejected_unexplained", s.loops.rejected_unexplained},
                       {"confirmed", s.loops.confirmed},
                       {"closures", s.loops.closures},
                       {"rejected_inconsistent", s.loops.rejected_inconsistent},
                       {"max_shift_m", s.loops.max_shift_m},
                       {"frozen_at_s", s.loops.frozen_at_s >= 0.0 ? nlohmann::json(s.loops.frozen_at_s) : nlohmann::json(nullptr)},
                       {"time_s", s.loops.time_s},
                       {"compose_time_s", s.loops.compose_time_s},
                       {"distance_time_s", s.loops.distance_time_s},
                       {"match_time_s", s.loops.match_time_s}};
  return j;
}

namespace {

void write_tum(const std::filesystem::path& path, const std::vector<sim::StampedPose>& traj) {
  std::string text = "# timestamp tx ty tz qx qy qz qw\n";
  char buf[256];
  for (const auto& p : traj) {
    const double h = 0.5 * p.pose.theta;
    std::snprintf(buf, sizeof buf, "%.3f %.4f %.4f 0 0 0 %.6f %.6f\n", p.t_s, static_cast<double>(p.pose.x),
                  static_cast<double>(p.pose.y), std::sin(h), std::cos(h));
    text += buf;
  }
  write_text_file(path, text);
}

void write_curve_csv(const std::filesystem::path& path, const std::vector<sim::CurvePoint>& curve) {
  std::string text = "time_s,explored_area_m2,coverage\n";
  char buf[128];
  for (const auto& c : curve) {
    std::snprintf(buf, sizeof buf, "%.2f,%.3f,%.4f\n", c.t_s, c.area_m2, c.coverage);
    text += buf;
  }
  write_text_file(path, text);
}

}  // namespace

PlotSeries curve_series(const std::vector<sim::CurvePoint>& curve, std::string label, Rgb8 colour, int width) {
  PlotSeries s;
  s.label = std::move(label);
  s.colour = colour;
  s.width_px = width;
  for (const auto& c : curve) {
    s.x.push_back(c.t_s);
    s.y.push_back(c.area_m2);
  }
  return s;
}

std::vector<PlotMarker> paper_markers() {
  return {{"paper, dual: 31.0 m^2 in 196 s", 196.0, 31.0, {30, 90, 200}},
          {"paper, single: 27.6 m^2 in 297 s", 297.0, 27.6, {220, 120, 20}}};
}

namespace {

nlohmann::json run_log(const sim::SimExplore& run) {
  nlohmann::json j;
  j["decisions"] = nlohmann::json::array();
  for (const auto& d : run.explorer().decisions())
    j["decisions"].push_back({{"t_s", d.t_s},
                              {"status", duet::to_string(d.status)},
                              {"reward_bits", d.reward_bits},
                              {"unknown_reward_bits", d.unknown_reward_bits},
                              {"robot", {d.robot.x, d.robot.y, d.robot.theta}},
                              {"goal", {d.goal.x, d.goal.y, d.goal.theta}},
                              {"planned", d.planned},
                              {"frontier_cells", d.frontier_cells},
                              {"reachable_frontier_clusters", d.reachable_clusters},
                              {"frontier_reached_cells", d.reached_cells},
                              {"relaxed", d.relaxed},
                              {"view", d.view},
                              {"view_target", d.view ? nlohmann::json::array({d.view_target.x(), d.view_target.y()}) : nlohmann::json()},
                              {"nearest_frontier", {d.nearest_frontier.x(), d.nearest_frontier.y()}},
                              {"wall_time_ms", 1e3 * d.wall_time_s}});
  j["loop_closures"] = nlohmann::json::array();
  if (const LoopCloser* lc = run.runtime().loop_closer())
    for (const auto& e : lc->events())
      j["loop_closures"].push_back({{"t_s", e.t_s},
                                    {"old_node", e.old_node},
                                    {"open_node", e.open_node},
                                    {"shift", {e.shift.x, e.shift.y, e.shift.theta}},
                                    {"robot_shift_m", e.robot_shift_m},
                                    {"score", e.score},
                                    {"prior_score", e.prior_score}});
  j["loop_matches"] = nlohmann::json::array();
  if (const LoopCloser* lc = run.runtime().loop_closer())
    for (const auto& m : lc->matches())
      j["loop_matches"].push_back({{"t_s", m.t_s},
                                   {"correction", {m.correction.x, m.correction.y, m.correction.theta}},
                                   {"score", m.score},
                                   {"prior_score", m.prior_score},
                                   {"prediction_conflict", m.prediction_conflict},
                                   {"shift_m", m.shift_m},
                                   {"moves_map", m.moves_map},
                                   {"accepted", m.accepted}});
  j["collisions"] = nlohmann::json::array();
  for (const auto& c : run.collision_log())
    j["collisions"].push_back({{"t_s", c.t_s},
                               {"true_pose", {c.true_pose.x, c.true_pose.y, c.true_pose.theta}},
                               {"command", {c.command.v, c.command.omega}},
                               {"estimated_pose", {c.estimated_pose.x, c.estimated_pose.y, c.estimated_pose.theta}},
                               {"map_clearance_m", std::isfinite(c.map_clearance_m) ? nlohmann::json(c.map_clearance_m) : nlohmann::json(nullptr)}});
  j["runtime_events"] = nlohmann::json::array();  // what the runtime noticed about its inputs and did
  for (const auto& e : run.runtime().events()) j["runtime_events"].push_back({{"t_s", e.t_s}, {"what", e.what}});
  return j;
}

void write_health_csv(const std::filesystem::path& path, const std::vector<sim::HealthSample>& health) {
  std::string text = "time_s,rss_mb,tick_mean_ms,tick_max_ms,step_mean_ms,grid_cells,submaps,explorer_state,heading_rate_radps\n";
  char buf[256];
  for (const auto& h : health) {
    std::snprintf(buf, sizeof buf, "%.1f,%.2f,%.4f,%.3f,%.4f,%zu,%ld,%s,%.4e\n", h.t_s, h.rss_mb, h.tick_mean_ms, h.tick_max_ms,
                  h.step_mean_ms, h.grid_cells, h.submaps, h.explorer_state.c_str(), h.heading_rate_radps);
    text += buf;
  }
  write_text_file(path, text);
}

}  // namespace

nlohmann::json health_json(const std::vector<sim::HealthSample>& health) {
  nlohmann::json j;
  j["samples"] = health.size();
  if (health.empty()) return j;
  double peak = -1.0;
  for (const auto& h : health) peak = std::max(peak, h.rss_mb);
  j["rss_first_mb"] = health.front().rss_mb;
  j["rss_peak_mb"] = peak;
  j["rss_end_mb"] = health.back().rss_mb;
  // After the first hour: the sample at 1 h (the first at or after it) against the last one.
  constexpr double kHour = 3600.0;
  const auto at_hour = std::find_if(health.begin(), health.end(), [](const auto& h) { return h.t_s >= kHour; });
  if (at_hour != health.end() && at_hour->rss_mb > 0.0 && health.back().t_s > at_hour->t_s) {
    j["rss_at_1h_mb"] = at_hour->rss_mb;
    j["rss_growth_after_1h"] = (health.back().rss_mb - at_hour->rss_mb) / at_hour->rss_mb;
  }
  // The mean tick of the first and of the last hour (by samples in each).
  auto mean_tick = [&](double from, double to) {
    double sum = 0.0;
    int n = 0;
    for (const auto& h : health)
      if (h.t_s > from && h.t_s <= to) {
        sum += h.tick_mean_ms;
        ++n;
      }
    return n ? nlohmann::json(sum / n) : nlohmann::json(nullptr);
  };
  const double end = health.back().t_s;
  j["tick_mean_first_hour_ms"] = mean_tick(0.0, kHour);
  if (end > 2.0 * kHour) j["tick_mean_last_hour_ms"] = mean_tick(end - kHour, end);
  return j;
}

void write_outputs(sim::SimExplore& run, const std::filesystem::path& out) {
  prepare_output_dir(out);
  const PointCloud& cloud = run.mapper().cloud();
  write_pcd(out / "cloud.pcd", cloud, PcdEncoding::kBinaryCompressed);
  write_ply(out / "cloud.ply", cloud, PlyEncoding::kBinaryLittleEndian);
  const OccupancyGrid& grid = run.mapper().grid();
  write_map_server(grid, out / "grid.yaml");
  GridPngOptions png;
  png.scale = std::max(1, 800 / std::max(1, std::max(grid.width(), grid.height())));
  for (const auto& p : run.estimated_trajectory()) png.polyline.emplace_back(p.pose.x, p.pose.y);
  png.dots = run.explorer().frontier_points();
  write_grid_png(grid, out / "grid.png", png);
  write_tum(out / "trajectory.tum", run.estimated_trajectory());
  write_tum(out / "trajectory_true.tum", run.true_trajectory());
  write_curve_csv(out / "curve.csv", run.curve());
  const auto sum = run.summary();
  PlotOptions po;
  po.title = "Explored area over time: " + sum.profile + " on " + sum.world + " (seed " + std::to_string(sum.seed) + ")";
  po.x_label = "time [s]";
  po.y_label = "explored area [m^2]";
  po.markers = paper_markers();
  write_plot_png(out / "curve.png", {curve_series(run.curve(), sum.profile, {30, 90, 200}, 2)}, po);
  write_text_file(out / "log.json", run_log(run).dump(1) + "\n");
  write_health_csv(out / "health.csv", run.health());
  nlohmann::json summary = to_json(sum);
  summary["health"] = health_json(run.health());
  write_text_file(out / "summary.json", summary.dump(2) + "\n");  // last: a summary means a complete folder
}

}  // namespace duet::app
