// summary.json's shared blocks (see run_json.hpp).
#include "io/run_json.hpp"

#include <cmath>

namespace duet::detail {

nlohmann::json timing_json(const RuntimeTiming& tm) {
  auto latency = [](const LatencySummary& l) {
    return nlohmann::json{{"count", l.count}, {"p50_ms", 1e3 * l.p50_s}, {"p99_ms", 1e3 * l.p99_s}, {"max_ms", 1e3 * l.max_s},
                          {"mean_ms", 1e3 * l.mean_s}};
  };
  return {{"nominal_period_ms", 1e3 * tm.nominal_period_s},
          {"control_period", latency(tm.control_period)},
          {"command_latency", latency(tm.command_latency)},
          {"frame_to_map", latency(tm.frame_to_map)},
          {"decision", latency(tm.decision)},
          {"late_periods", tm.late_periods},
          {"missed_periods", tm.missed_periods}};
}

nlohmann::json input_json(const InputStats& in, std::uint64_t sets_with_missing, std::uint64_t blind_holds, std::size_t relocalizations) {
  return {{"odometry_invalid", in.odometry_invalid},
          {"odometry_out_of_order", in.odometry_out_of_order},
          {"odometry_jumps_absorbed", in.odometry_jumps},
          {"frames_invalid", in.frames_invalid},
          {"frames_out_of_order", in.frames_out_of_order},
          {"frames_empty", in.frames_empty},
          {"frames_garbled", in.frames_garbled},
          {"clock_restarts", in.clock_restarts},
          {"sensor_silences", in.sensor_silences},
          {"missing_frames_added", in.missing_frames},
          {"sets_with_missing_frames", sets_with_missing},
          {"blind_hold_periods", blind_holds},
          {"relocalizations", relocalizations}};
}

nlohmann::json left_json(const std::vector<UnexploredRegion>& left) {
  nlohmann::json a = nlohmann::json::array();
  for (const UnexploredRegion& r : left) {
    nlohmann::json o{{"x_m", r.centroid.x()},
                     {"y_m", r.centroid.y()},
                     {"nearest_x_m", r.nearest.x()},
                     {"nearest_y_m", r.nearest.y()},
                     {"frontier_cells", r.cells},
                     {"length_m", r.length_m},
                     {"why", to_string(r.why)},
                     {"failed_goals", r.failures},
                     {"looked_at", r.looked_at},
                     {"needed_m", r.needed_m}};
    o["gap_m"] = std::isfinite(r.gap_m) ? nlohmann::json(r.gap_m) : nlohmann::json(nullptr);  // null: no obstacle at all
    a.push_back(std::move(o));
  }
  return a;
}

}  // namespace duet::detail
