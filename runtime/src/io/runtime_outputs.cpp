/// @file runtime_outputs.cpp
/// A runtime's output files (see runtime_outputs.hpp).
#include <duet/runtime/io/cloud_io.hpp>
#include <duet/runtime/io/grid_io.hpp>
#include <duet/runtime/io/output.hpp>
#include <duet/runtime/io/runtime_outputs.hpp>

#include "io/run_json.hpp"

#include <cmath>
#include <cstdio>

namespace duet {

std::string tum_text(const Trajectory& trajectory) {
  std::string out = "# timestamp tx ty tz qx qy qz qw\n";
  char line[160];
  for (const auto& [t, p] : trajectory) {
    const double h = 0.5 * p.theta;
    std::snprintf(line, sizeof line, "%.3f %.4f %.4f 0 0 0 %.6f %.6f\n", t, static_cast<double>(p.x), static_cast<double>(p.y), std::sin(h),
                  std::cos(h));
    out += line;
  }
  return out;
}

RuntimeOutputs snapshot_runtime_outputs(ExplorationRuntime& rt, const Trajectory& trajectory, const std::map<std::string, double>& extra) {
  RuntimeOutputs out;
  out.grid = rt.map_grid();
  out.cloud = rt.mapper().cloud();
  out.trajectory = trajectory;
  const RuntimeStats& st = rt.stats();
  nlohmann::json j;
  j["profile"] = rt.profile().name;
  j["time_s"] = trajectory.empty() ? nlohmann::json(nullptr) : nlohmann::json(trajectory.back().first);
  j["control_periods"] = trajectory.size();
  j["explorer_state"] = to_string(rt.state());
  j["stop_detail"] = rt.stop_detail();
  j["left_unexplored"] = detail::left_json(rt.left_unexplored());
  j["execution"] = to_string(rt.settings().execution);
  j["sets_integrated"] = st.sets_integrated;
  j["scan_matches"] = st.scan_matches;
  j["scan_match_rejected"] = st.scan_match_rejected;
  j["loop_closures"] = st.loop_closures;
  j["relocalizations"] = st.relocalizations;
  j["relocalizations_held"] = st.relocalizations_held;
  j["relocalizations_new_space"] = st.relocalizations_new_space;
  j["relocalizations_ambiguous"] = st.relocalizations_ambiguous;
  j["relocalizations_in_obstacle"] = st.relocalizations_in_obstacle;
  j["relocalizations_at_edge"] = st.relocalizations_at_edge;
  j["relocalizations_asked"] = st.relocalizations_asked;
  j["frames_received"] = st.frames_received;
  j["frame_drops"] = st.frame_drops;
  j["odometry_received"] = st.odometry_received;
  j["input"] = detail::input_json(st.input, st.sets_with_missing, st.blind_holds, st.relocalizations);
  j["runtime"] = detail::timing_json(rt.timing());
  for (const auto& [k, v] : extra) j[k] = v;
  out.summary_json = j.dump(2) + "\n";
  return out;
}

void write_runtime_outputs(const RuntimeOutputs& o, const std::filesystem::path& dir) {
  prepare_output_dir(dir);
  if (o.grid.width() > 0 && o.grid.height() > 0) {
    write_map_server(o.grid, dir / "grid.yaml");
    write_grid_png(o.grid, dir / "grid.png");
  }
  write_pcd(dir / "cloud.pcd", o.cloud, PcdEncoding::kBinaryCompressed);
  write_text_file(dir / "trajectory.tum", tum_text(o.trajectory));
  write_text_file(dir / "summary.json", o.summary_json);
}

void write_runtime_outputs(ExplorationRuntime& rt, const Trajectory& trajectory, const std::filesystem::path& dir,
                           const std::map<std::string, double>& extra) {
  prepare_output_dir(dir);  // before the snapshot: a directory that cannot be made fails first
  write_runtime_outputs(snapshot_runtime_outputs(rt, trajectory, extra), dir);
}

}  // namespace duet
