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

/// What the files hold, copied out of a runtime: taken while the runtime is held (a few
/// milliseconds of copying), written after it is let go (the PNG, the compressed PCD and the
/// renames take a second or more on a big map - which would otherwise hold control).
struct RuntimeOutputs {
  OccupancyGrid grid;
  PointCloud cloud;
  Trajectory trajectory;
  std::string summary_json;  ///< summary.json's text
};

/// Copies what write_runtime_outputs writes. The runtime must be drained (its mapper is read).
[[nodiscard]] RuntimeOutputs snapshot_runtime_outputs(ExplorationRuntime& runtime, const Trajectory& trajectory,
                                                      const std::map<std::string, double>& extra = {});

/// Writes the files above into `dir` (created if needed). Throws duet::Error(kIo) naming the
/// file that could not be written.
void write_runtime_outputs(const RuntimeOutputs& outputs, const std::filesystem::path& dir);

/// snapshot_runtime_outputs, then write_runtime_outputs.
void write_runtime_outputs(ExplorationRuntime& runtime, const Trajectory& trajectory, const std::filesystem::path& dir,
                           const std::map<std::string, double>& extra = {});

}  // namespace duet
