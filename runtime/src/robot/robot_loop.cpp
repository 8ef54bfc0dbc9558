/// @file robot_loop.cpp
/// The runtime on any robot source (see robot_loop.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/robot/clock.hpp>
#include <duet/runtime/robot/robot_loop.hpp>

#include <cmath>

namespace duet {

void validate(const RobotRunSettings& s) {
  if (!(std::isfinite(s.max_time_s) && s.max_time_s > 0.0 && s.max_time_s <= 1e6))
    fail(ErrorCode::kInvalidArgument, "RobotRunSettings.max_time_s must be in (0, 1e6] s, got " + std::to_string(s.max_time_s));
}

RobotRunResult run_robot(RobotSource& source, ExplorationRuntime& runtime, const RobotRunSettings& settings,
                         const std::function<bool(double now_s)>& keep_going) {
  validate(settings);
  const double dt = 1.0 / runtime.settings().control_rate_hz;
  SteadyClock wall;
  RobotRunResult r;
  for (long k = 1;; ++k) {
    const double t = static_cast<double>(k) * dt;  // no accumulated rounding over long runs
    if (t > settings.max_time_s + 1e-9) break;
    source.advance(t);
    if (settings.realtime) wall.sleep_until(t);
    runtime.tick(t);
    r.time_s = t;
    if (runtime.state() == ExplorerState::kDone) {
      r.done = true;
      break;
    }
    if (keep_going && !keep_going(t)) break;
  }
  runtime.drain();
  r.stop_detail = runtime.stop_detail();
  r.timing = runtime.timing();
  r.stats = runtime.stats();
  return r;
}

}  // namespace duet
