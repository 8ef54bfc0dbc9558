// Clocks: the simulated clock moves only when told and never backwards; the steady clock follows
// the wall clock scaled by its rate and really sleeps. No upper bound on any duration is asserted
// (the machine is shared); lower bounds follow from the sleep's contract.
#include <duet/kernels/error.hpp>
#include <duet/runtime/robot/clock.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>
#include <vector>

using duet::Clock;
using duet::SimClock;
using duet::SteadyClock;

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

void expect_invalid(auto&& f) {
  try {
    f();
    ADD_FAILURE() << "no error";
  } catch (const duet::Error& e) {
    EXPECT_EQ(e.code(), duet::ErrorCode::kInvalidArgument);
  }
}
}  // namespace

TEST(Clock, SimClockMovesOnlyWhenToldAndNeverBackwards) {
  SimClock clock;
  const Clock& base = clock;
  EXPECT_TRUE(base.simulated());
  EXPECT_EQ(base.now_s(), 0.0);
  EXPECT_EQ(clock.now_s(), 0.0);  // nothing moves it by itself
  clock.advance_to(1.5);
  EXPECT_EQ(clock.now_s(), 1.5);
  clock.advance_to(1.5);  // equal: no-op
  EXPECT_EQ(clock.now_s(), 1.5);
  expect_invalid([&] { clock.advance_to(1.0); });
  EXPECT_EQ(clock.now_s(), 1.5);
  clock.sleep_until(1.0);  // in the past: returns at once, time unchanged
  EXPECT_EQ(clock.now_s(), 1.5);
  clock.sleep_until(2.25);  // sets the time, never sleeps
  EXPECT_EQ(clock.now_s(), 2.25);
  clock.advance_by(0.25);
  EXPECT_EQ(clock.now_s(), 2.5);
  clock.advance_by(0.0);
  EXPECT_EQ(clock.now_s(), 2.5);
  expect_invalid([&] { clock.advance_by(-0.1); });
  expect_invalid([&] { clock.advance_by(kNaN); });
  expect_invalid([&] { clock.advance_to(kNaN); });
  expect_invalid([&] { clock.advance_to(kInf); });
  expect_invalid([&] { clock.sleep_until(kNaN); });
  EXPECT_EQ(clock.now_s(), 2.5);

  SimClock late(100.0);
  EXPECT_EQ(late.now_s(), 100.0);
  expect_invalid([] { SimClock c(kNaN); });
  // A simulated sleep of a simulated hour takes no wall time worth waiting for: it just sets it.
  late.sleep_until(3700.0);
  EXPECT_EQ(late.now_s(), 3700.0);
}

TEST(Clock, SimClockReadersSeeMonotoneTimeWhileItAdvances) {
  SimClock clock;
  std::atomic<bool> done{false};
  std::atomic<int> regressions{0};
  std::atomic<long> reads{0};
  std::thread reader([&] {
    double last = clock.now_s();
    while (!done.load()) {
      const double t = clock.now_s();
      if (t < last) ++regressions;
      last = t;
      ++reads;
    }
  });
  while (reads.load() == 0) std::this_thread::yield();  // the reader runs before time moves
  for (int k = 1; k <= 200000; ++k) clock.advance_to(k * 1e-3);
  const long before_end = reads.load();
  while (reads.load() < before_end + 100) std::this_thread::yield();  // and reads the end too
  done = true;
  reader.join();
  EXPECT_EQ(regressions.load(), 0);
  EXPECT_GT(reads.load(), 100);
  EXPECT_EQ(clock.now_s(), 200.0);
}

TEST(Clock, SteadyClockFollowsTheWallClockAndReallySleeps) {
  SteadyClock clock;
  const Clock& base = clock;
  EXPECT_FALSE(base.simulated());
  EXPECT_EQ(clock.rate(), 1.0);
  double last = clock.now_s();
  EXPECT_GE(last, 0.0);
  for (int k = 0; k < 1000; ++k) {
    const double t = clock.now_s();
    EXPECT_GE(t, last);
    last = t;
  }
  const double target = clock.now_s() + 0.02;
  const auto w0 = std::chrono::steady_clock::now();
  clock.sleep_until(target);
  const std::chrono::duration<double> waited = std::chrono::steady_clock::now() - w0;
  EXPECT_GE(clock.now_s(), target);
  EXPECT_GE(waited.count(), 0.0195);  // it slept (lower bound only)
  clock.sleep_until(0.0);             // the past: returns at once
  expect_invalid([&] { clock.sleep_until(kNaN); });
}

TEST(Clock, SteadyClockRateScalesTime) {
  SteadyClock fast(100.0);
  EXPECT_EQ(fast.rate(), 100.0);
  const auto w0 = std::chrono::steady_clock::now();
  fast.sleep_until(2.0);  // 2 s of clock time = 20 ms of wall time at 100 x
  const std::chrono::duration<double> waited = std::chrono::steady_clock::now() - w0;
  EXPECT_GE(fast.now_s(), 2.0);
  EXPECT_GE(waited.count(), 0.0195);
  // Clock time runs 100 x faster than the wall: over >= 20 ms of wall time it gained >= 2 s.
  SteadyClock slow(0.5);
  const auto w1 = std::chrono::steady_clock::now();  // the wall interval encloses the clock's
  const double s0 = slow.now_s();
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  const double gained = slow.now_s() - s0;
  const std::chrono::duration<double> wall = std::chrono::steady_clock::now() - w1;
  EXPECT_GE(gained, 0.5 * 0.02 * 0.999);
  EXPECT_LE(gained, 0.5 * wall.count() + 1e-9);  // same measurement, not a timing assumption
  for (double bad : {0.0, -1.0, 1e-4, 2e6, kNaN, kInf}) expect_invalid([bad] { SteadyClock c(bad); });
}
