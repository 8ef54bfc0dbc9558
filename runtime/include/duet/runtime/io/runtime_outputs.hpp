#pragma once
/// @file runtime_outputs.hpp
/// The files a runtime's run leaves (the robot's side of what `duet explore` writes): grid.yaml +
/// grid.pgm (map_server), grid.png, cloud.pcd (binary compressed), trajectory.tum (the pose
/// estimate per control period, map frame) and summary.json (state, stop reason, counters,
/// timing, plus the caller's `extra` numbers). Written by the C API's duet_runtime_save and
/// `duet replay`. Each file is written under a temporary name and renamed (output.hpp).
#include <duet/kernels/motion_model.hpp>
#include <duet/runtime/robot/exploration_runtime.hpp>

#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace duet {

/// (time [s], pose) per control period.
using Trajectory = std::vector<std::pair<double, Pose2>>;

/// TUM text of a planar trajectory ("t x y 0 0 0 qz qw"), as `duet explore` writes it.
[[nodiscard]] std::string tum_text(const Trajectory& trajectory);

/// Writes the files above into `dir` (created if needed). The runtime must be drained (its
/// mapper is read). Throws duet::Error(kIo) naming the file that could not be written.
void write_runtime_outputs(ExplorationRuntime& runtime, const Trajectory& trajectory, const std::filesystem::path& dir,
                           const std::map<std::string, double>& extra = {});

}  // namespace duet
