#pragma once
// The outputs of one simulated run (`duet explore`, `duet compare`): the maps, trajectories,
// curve, health, log and summary, each written to a temporary name and renamed into place.
#include <duet/runtime/io/plot.hpp>
#include <duet/sim/sim_explore.hpp>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace duet::app {

/// summary.json of a run.
[[nodiscard]] nlohmann::json to_json(const sim::ExploreSummary& s);
/// summary.json's "health": resident memory and per-cycle time over the run (issue 19's long
/// run: growth after the first hour, the first and the last hour's mean tick).
[[nodiscard]] nlohmann::json health_json(const std::vector<sim::HealthSample>& health);
/// The explored area over time, as a plot series.
[[nodiscard]] PlotSeries curve_series(const std::vector<sim::CurvePoint>& curve, std::string label, Rgb8 colour, int width);
/// The paper's two results (Fig. 10) as plot markers.
[[nodiscard]] std::vector<PlotMarker> paper_markers();
/// Writes every output of `run` into `out` (summary.json last: a summary means a complete folder).
void write_outputs(sim::SimExplore& run, const std::filesystem::path& out);

}  // namespace duet::app
