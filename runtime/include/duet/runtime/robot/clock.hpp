#pragma once
/// @file clock.hpp
/// The runtime's one notion of time (DESIGN.md §3): a simulated lockstep clock (the default,
/// bit-for-bit repeatable) and a wall clock (`duet explore --realtime`).
///
/// Time is a double in seconds since the clock's origin (0 at construction, or the SimClock's
/// start). Every message stamp in the runtime (sensor frames, odometry, synchronised sets) is
/// on this time line.
///
/// Thread safety: now_s() may be called from any thread at any time on both clocks. SimClock's
/// advance_to()/advance_by()/sleep_until() are meant for one driving thread (the runtime loop);
/// they are atomic, so concurrent readers see either the old or the new time, never a torn
/// value. SteadyClock has no mutable state: every member is safe from any thread.
#include <atomic>
#include <chrono>

namespace duet {

/// Abstract clock. Implementations never run backwards: now_s() is non-decreasing.
class Clock {
 public:
  virtual ~Clock() = default;
  Clock() = default;
  Clock(const Clock&) = delete;
  Clock& operator=(const Clock&) = delete;

  /// The current time [s] since the clock's origin.
  [[nodiscard]] virtual double now_s() const = 0;
  /// Blocks (wall clock) or jumps (simulated clock) until now_s() >= t_s. A time at or before
  /// now_s() returns at once. Throws duet::Error(kInvalidArgument) for a non-finite t_s.
  virtual void sleep_until(double t_s) = 0;
  /// True for a clock whose time only moves when the runtime moves it (lockstep simulation).
  [[nodiscard]] virtual bool simulated() const = 0;
};

/// Lockstep simulated time: it moves only when the runtime calls advance_to()/advance_by()
/// or sleep_until() (which sets the time and never sleeps). Deterministic by construction.
class SimClock final : public Clock {
 public:
  /// `start_s`: the initial time [s], finite (default 0). Throws kInvalidArgument otherwise.
  explicit SimClock(double start_s = 0.0);

  [[nodiscard]] double now_s() const override { return now_.load(std::memory_order_acquire); }
  /// Sets the time to max(now_s(), t_s); never sleeps.
  void sleep_until(double t_s) override;
  [[nodiscard]] bool simulated() const override { return true; }

  /// Moves time to `t_s` [s]. Throws kInvalidArgument for a non-finite t_s or t_s < now_s()
  /// (simulated time never runs backwards; equal is a no-op).
  void advance_to(double t_s);
  /// advance_to(now_s() + dt_s); dt_s finite and >= 0 [s].
  void advance_by(double dt_s);

 private:
  std::atomic<double> now_;
};

/// Wall time from std::chrono::steady_clock: 0 at construction, scaled by `rate`
/// (rate = k: the clock runs k times faster than real time, so a simulation paced by it runs at
/// k x real time; rate = 1: real time). sleep_until() really sleeps (std::this_thread).
class SteadyClock final : public Clock {
 public:
  /// `rate`: simulated seconds per wall second, finite, in [1e-3, 1e6] (default 1 = real time).
  /// Throws duet::Error(kInvalidArgument) naming the range otherwise.
  explicit SteadyClock(double rate = 1.0);

  [[nodiscard]] double now_s() const override;
  /// Sleeps until the wall time at which now_s() reaches t_s (returns at once if already past).
  void sleep_until(double t_s) override;
  [[nodiscard]] bool simulated() const override { return false; }
  [[nodiscard]] double rate() const noexcept { return rate_; }

 private:
  std::chrono::steady_clock::time_point origin_;
  double rate_;
};

}  // namespace duet
