#pragma once
// Sub-commands of the `duet` program; each registers itself on the CLI11 app and runs from
// its callback, setting exit_code.
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/robot/exploration_runtime.hpp>
#include <duet/runtime/robot/faults.hpp>
#include <duet/runtime/robot/robot_source.hpp>

#include "io/run_json.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include <optional>
#include <string>
#include <vector>

namespace duet::app {

/// Standard error is a terminal (progress lines are drawn there).
[[nodiscard]] bool stderr_is_tty();

/// --config FILE and --set KEY=VALUE on a sub-command (profile_command.cpp), and the overlays they give.
void add_overlay_options(CLI::App* cmd, std::vector<std::string>& configs, std::vector<std::string>& sets);
[[nodiscard]] std::vector<ProfileOverlay> overlays(const std::vector<std::string>& configs, const std::vector<std::string>& sets);

void add_map_command(CLI::App& app, int& exit_code);
void add_profile_command(CLI::App& app, int& exit_code);
void add_explore_command(CLI::App& app, int& exit_code);
void add_compare_command(CLI::App& app, int& exit_code);
void add_run_command(CLI::App& app, int& exit_code);
void add_replay_command(CLI::App& app, int& exit_code);
void add_eval_traj_command(CLI::App& app, int& exit_code);
/// `duet map` on a folder (map_command.cpp), for `duet replay` of a TUM RGB-D folder.
/// `poses`: replaces the folder's (one per frame, nothing = not mapped), which is then read
/// without them; `extra` joins summary.json.
int run_map_folder(const std::string& input, const std::string& out, const std::string& profile, const std::string& layout, int threads,
                   bool quiet, const std::vector<std::optional<Eigen::Isometry3f>>* poses = nullptr,
                   const nlohmann::json& extra = nlohmann::json::object());

/// summary.json's timing and input blocks: the runtime's (io/run_json.hpp), shared with duet_runtime_save.
using detail::input_json;
using detail::timing_json;
using detail::left_json;

/// summary.json's "faults": each injected fault (faults.hpp) and how often it acted.
[[nodiscard]] nlohmann::json faults_json(const std::vector<FaultCount>& faults);

/// The robot sources `duet run` knows (robot_sources.cpp: one line each).
[[nodiscard]] const RobotSourceRegistry& robot_sources();

}  // namespace duet::app
