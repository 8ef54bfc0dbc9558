#include <duet/kernels/error.hpp>
#include <duet/runtime/robot/clock.hpp>

#include <cmath>
#include <string>
#include <thread>

namespace duet {
namespace {

void require_finite(double t, const char* what) {
  if (!std::isfinite(t)) fail(ErrorCode::kInvalidArgument, std::string(what) + " = " + std::to_string(t) + " is not finite");
}

}  // namespace

SimClock::SimClock(double start_s) : now_(start_s) { require_finite(start_s, "SimClock start_s"); }

void SimClock::sleep_until(double t_s) {
  require_finite(t_s, "SimClock::sleep_until t_s");
  if (t_s > now_.load(std::memory_order_relaxed)) now_.store(t_s, std::memory_order_release);
}

void SimClock::advance_to(double t_s) {
  require_finite(t_s, "SimClock::advance_to t_s");
  const double now = now_.load(std::memory_order_relaxed);
  if (t_s < now)
    fail(ErrorCode::kInvalidArgument, "SimClock::advance_to t_s = " + std::to_string(t_s) +
                                          " is before now_s() = " + std::to_string(now) +
                                          " (simulated time never runs backwards)");
  now_.store(t_s, std::memory_order_release);
}

void SimClock::advance_by(double dt_s) {
  require_finite(dt_s, "SimClock::advance_by dt_s");
  if (dt_s < 0.0)
    fail(ErrorCode::kInvalidArgument, "SimClock::advance_by dt_s = " + std::to_string(dt_s) + " is outside [0, inf)");
  advance_to(now_.load(std::memory_order_relaxed) + dt_s);
}

SteadyClock::SteadyClock(double rate) : origin_(std::chrono::steady_clock::now()), rate_(rate) {
  if (!std::isfinite(rate) || !(rate >= 1e-3 && rate <= 1e6))
    fail(ErrorCode::kInvalidArgument, "SteadyClock rate = " + std::to_string(rate) + " is outside [1e-3, 1e6]");
}

double SteadyClock::now_s() const {
  const std::chrono::duration<double> wall = std::chrono::steady_clock::now() - origin_;
  return wall.count() * rate_;
}

void SteadyClock::sleep_until(double t_s) {
  require_finite(t_s, "SteadyClock::sleep_until t_s");
  const double wall_s = t_s / rate_;
  if (wall_s <= 0.0) return;
  // Clamp to a century so the conversion to the clock's integer ticks cannot overflow.
  const double clamped = wall_s < 3.15e9 ? wall_s : 3.15e9;
  const auto deadline =
      origin_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(clamped));
  std::this_thread::sleep_until(deadline);
  // sleep_until on steady_clock returns at or after the deadline; guard against an early
  // wake-up from the double -> tick rounding so that now_s() >= t_s holds on return.
  while (now_s() < t_s) std::this_thread::sleep_for(std::chrono::microseconds(10));
}

}  // namespace duet
