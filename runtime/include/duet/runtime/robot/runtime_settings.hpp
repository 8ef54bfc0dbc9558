#pragma once
/// @file runtime_settings.hpp
/// Settings of the exploration runtime (exploration_runtime.hpp): rates, execution, and the
/// settings of its parts - the synchronizer, the pose correction, loop closure and the
/// explorer. Every one of them is reachable from the profile YAML (config/profile.hpp:
/// runtime, localization, exploration and control sections).
#include <duet/runtime/localization/loop_closure_settings.hpp>
#include <duet/runtime/localization/pose_correction_settings.hpp>
#include <duet/runtime/localization/visual_localization_settings.hpp>
#include <duet/runtime/navigation/explorer_settings.hpp>
#include <duet/runtime/robot/input_guard_settings.hpp>
#include <duet/runtime/robot/synchronizer.hpp>

namespace duet {

enum class Execution { kLockstep, kBackground };
[[nodiscard]] const char* to_string(Execution e);

struct RuntimeSettings {
  double control_rate_hz = 20.0;   ///< control and pose rate [Hz] (paper §4.2), (0, 1000]
  double map_rate_hz = 1.0;        ///< map update rate [Hz] (paper §4.2), (0, control_rate_hz]
  /// The rate the sensors deliver frames at [Hz], (0, 1000]: sizes the synchronizer's
  /// odometry queue and gives its inter-message lower bounds (0.9 / rate).
  double sensor_rate_hz = 30.0;
  Execution execution = Execution::kLockstep;  ///< see the file comment
  int background_threads = 0;      ///< kBackground: threads of the background arena, [0, 256]; 0 = all cores
  /// FAULT INJECTION (tests): in kBackground every decision takes at least this long [s], [0, 60].
  double decision_delay_s = 0.0;
  ExplorerSettings explorer;
  ApproximateTimeSettings sync;    ///< queue_size raised to hold two sensor periods of odometry
  InputGuardSettings input;        ///< what counts as a bad input, a jump, a clock step, a silent sensor
  PoseCorrectionSettings pose_correction;
  /// Submaps, loop search and pose-graph optimisation (loop_closure.hpp); needs the pose correction.
  LoopClosureSettings loop_closure;
  /// Visual odometry fused with the wheels by an EKF (visual_localization.hpp); off by default.
  VisualLocalizationSettings visual_odometry;
};
void validate(const RuntimeSettings& s);

}  // namespace duet
