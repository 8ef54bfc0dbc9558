#pragma once
/// @file robot_loop.hpp
/// The runtime on any robot source (robot_source.hpp): once per control period the source moves
/// on to the period's time and the runtime ticks, until the explorer is done, the time limit
/// passes or the caller stops it. On the wall clock (realtime) the loop sleeps to each period's
/// time; on the simulated clock it runs as fast as the source allows (lockstep sources only).
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/robot/exploration_runtime.hpp>
#include <duet/runtime/robot/robot_source.hpp>

#include <functional>
#include <string>

namespace duet {

struct RobotRunSettings {
  double max_time_s = 600.0;  ///< stop after this much runtime-clock time [s], (0, 1e6]
  bool realtime = false;      ///< pace the loop by the wall clock (a real robot, or a simulator in real time)
};
void validate(const RobotRunSettings& s);

struct RobotRunResult {
  double time_s = 0.0;                    ///< runtime clock at the end [s]
  bool done = false;                      ///< the explorer finished (else the time limit or the caller stopped it)
  std::string stop_detail;                ///< why the explorer stopped, in words (empty when not done)
  RuntimeTiming timing;                   ///< control period and latencies (wall clock)
  RuntimeStats stats;
};

/// Runs `runtime` on `source` (the runtime was built on the source's chassis and sensors).
/// `keep_going` (optional) is asked once per period; false stops the run.
RobotRunResult run_robot(RobotSource& source, ExplorationRuntime& runtime, const RobotRunSettings& settings,
                         const std::function<bool(double now_s)>& keep_going = {});

}  // namespace duet
