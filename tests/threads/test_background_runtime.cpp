// The runtime's background mode (exploration_runtime.hpp, Execution::kBackground): control
// never waits for a map update or a decision, the robot stops when it has no path, results
// arrive, and the worker runs its jobs in order. Run under ThreadSanitizer in CI
// (scripts/test.sh): the tests run their TBB work in one-thread arenas so that every
// cross-thread hand-over is the runtime's own (mutexes, the worker's queue).
#include <duet/kernels/error.hpp>
#include <duet/runtime/robot/background_worker.hpp>
#include <duet/runtime/robot/exploration_runtime.hpp>

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include "runtime/scripted_robot.hpp"

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

namespace {

using duet_test::StandingRobot;

double wall_now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

duet::RuntimeSettings background(double decision_delay_s) {
  duet::RuntimeSettings rs;
  rs.sensor_rate_hz = 1.0;
  rs.execution = duet::Execution::kBackground;
  rs.background_threads = 1;
  rs.decision_delay_s = decision_delay_s;
  return rs;
}

}  // namespace

TEST(BackgroundWorker, RunsJobsInOrderAndReportsErrors) {
  duet::BackgroundWorker w(1);
  std::vector<int> order;  // written by the worker only; read after wait_idle()
  for (int i = 0; i < 50; ++i) w.submit([&order, i] { order.push_back(i); });
  w.wait_idle();
  ASSERT_EQ(order.size(), 50u);
  for (int i = 0; i < 50; ++i) EXPECT_EQ(order[static_cast<std::size_t>(i)], i);
  EXPECT_EQ(w.pending(), 0u);
  w.submit([] { throw std::runtime_error("job failed"); });
  w.submit([&order] { order.push_back(-1); });  // the worker goes on after a failed job
  w.wait_idle();
  EXPECT_THROW(w.rethrow_if_failed(), std::runtime_error);
  EXPECT_NO_THROW(w.rethrow_if_failed());  // reported once
  EXPECT_EQ(order.back(), -1);
}

TEST(BackgroundWorker, DestructionWithQueuedJobsDropsThem) {
  std::atomic<int> ran{0};
  std::atomic<bool> started{false};
  {
    duet::BackgroundWorker w(1);
    w.submit([&] {
      started = true;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      ++ran;
    });
    for (int i = 0; i < 10; ++i) w.submit([&] { ++ran; });
    while (!started) std::this_thread::yield();
  }  // waits for the running job, drops the queued ones
  EXPECT_EQ(ran.load(), 1);
}

// A robot standing between two walls, ticked at 20 Hz by the wall clock for 5 s, while every
// decision takes 2 s (RuntimeSettings::decision_delay_s). No tick may wait for it: each one
// returns in far less than the delay, the commands are zero while there is no goal (the robot
// stops safely), and the map updates due while the decision runs are skipped and counted.
TEST(BackgroundRuntime, ASlowDecisionNeverDelaysACommand) {
  tbb::task_arena arena(1);
  arena.execute([] {
    StandingRobot r(background(2.0));
    const double start = wall_now();
    double longest_tick = 0.0;
    for (int k = 0; k < 100; ++k) {
      const double due = start + 0.05 * k;
      while (wall_now() < due) std::this_thread::sleep_for(std::chrono::microseconds(500));
      const double t0 = wall_now();
      r.run(k, k + 1);
      longest_tick = std::max(longest_tick, wall_now() - t0);
    }
    EXPECT_LT(longest_tick, 1.0) << "a tick waited for the 2 s decision";
    const duet::RuntimeTiming tm = r.rt.timing();
    EXPECT_EQ(tm.command_latency.count, 100u);
    EXPECT_LT(tm.command_latency.max_s, 1.0);
    EXPECT_GE(r.rt.stats().decisions_requested, 1u);
    // The first decision was asked for after the first map (t >= 0) and took >= 2 s: no goal,
    // and so no motion, before t = 2 s.
    ASSERT_EQ(r.chassis.commands.size(), 100u);
    for (std::size_t k = 0; k < 40; ++k) {
      EXPECT_EQ(r.chassis.commands[k].v, 0.0f) << "tick " << k;
      EXPECT_EQ(r.chassis.commands[k].omega, 0.0f) << "tick " << k;
    }
    EXPECT_GT(r.rt.stats().map_sets_skipped, 0u);  // updates due while the decision ran
    r.rt.drain();
    EXPECT_GE(r.rt.stats().sets_integrated, 1u);
    EXPECT_EQ(r.rt.mapper().stats().observations, r.rt.stats().sets_integrated);
    EXPECT_GE(r.rt.explorer().navigator().stats().decisions, 1);
    EXPECT_EQ(r.rt.state(), duet::ExplorerState::kExploring);
    EXPECT_GT(r.rt.map_grid().known_cells(), 100u);  // the control side's copy of the map
  });
}

// Without a delay the background mode integrates every map update a standing robot offers and
// delivers decisions; after drain() the control side's view agrees with the pipeline's.
TEST(BackgroundRuntime, MapUpdatesAndDecisionsArrive) {
  tbb::task_arena arena(1);
  arena.execute([] {
    StandingRobot r(background(0.0));
    for (int k = 0; k < 120; ++k) {  // 6 s of runtime clock, as fast as the loop goes
      r.run(k, k + 1);
      if (k % 20 == 19) r.rt.drain();  // let each map update finish before the next is due
    }
    r.rt.drain();
    EXPECT_EQ(r.rt.stats().map_sets_skipped, 0u);
    EXPECT_EQ(r.rt.stats().sets_integrated, 6u);
    EXPECT_EQ(r.rt.mapper().stats().observations, 6u);
    EXPECT_EQ(r.rt.map_grid().known_cells(), r.rt.mapper().grid().known_cells());
    EXPECT_EQ(r.rt.explorer_stats().decisions, r.rt.explorer().stats().decisions);
    EXPECT_EQ(r.rt.state(), r.rt.explorer().state());
    EXPECT_EQ(r.front.recycled + r.right.recycled, 12);  // every frame's buffers came back
  });
}

// Visual odometry in the background mode: the front end runs on its own worker on copies of
// the frames (the sets' buffers go back to the sensors as before), and the EKF fuses each result
// on the control thread. A robot standing before textured walls: every set is tracked, the
// location point's views match (identity motion), the EKF takes them and the pose stays put.
TEST(BackgroundRuntime, VisualOdometryRunsOffTheControlThread) {
  tbb::task_arena arena(1);
  arena.execute([] {
    duet::RuntimeSettings rs = background(0.0);
    rs.visual_odometry.enabled = true;
    rs.pose_correction.enabled = false;
    StandingRobot r(rs);
    r.textured = true;
    for (int k = 0; k < 120; ++k) {  // 6 sets
      r.run(k, k + 1);
      if (k % 20 == 19) r.rt.drain();
    }
    r.rt.drain();
    const duet::RuntimeStats& s = r.rt.stats();
    EXPECT_EQ(s.visual_sets_busy, 0u);
    EXPECT_EQ(s.visual.sets, 6u);
    EXPECT_EQ(s.visual.failed, 0u) << "features " << s.visual.too_few_features << " matches " << s.visual.too_few_matches;
    EXPECT_GE(s.visual.accepted + s.visual.tracked_not_fused, 5u);  // every set after the first location point
    EXPECT_GT(s.visual.last_inliers, 100u);
    EXPECT_EQ(s.visual.gated, 0u);
    ASSERT_TRUE(r.rt.localization_health().has_value());
    EXPECT_EQ(*r.rt.localization_health(), duet::LocalizationHealth::kGood);
    EXPECT_NEAR(r.rt.pose().x, 0.0f, 0.01f);
    EXPECT_NEAR(r.rt.pose().y, 0.0f, 0.01f);
    EXPECT_EQ(r.front.recycled + r.right.recycled, 12);  // the runtime's copies are its own
  });
}

// Without drains the control thread never waits for the front end: sets due while it still
// runs are skipped and counted, and every set is either tracked or skipped.
TEST(BackgroundRuntime, VisualSetsDueWhileTheFrontEndRunsAreCounted) {
  tbb::task_arena arena(1);
  arena.execute([] {
    duet::RuntimeSettings rs = background(0.0);
    rs.visual_odometry.enabled = true;
    rs.pose_correction.enabled = false;
    StandingRobot r(rs);
    r.textured = true;
    r.run(0, 200);  // 10 sets, as fast as the loop goes
    r.rt.drain();
    const duet::RuntimeStats& s = r.rt.stats();
    EXPECT_EQ(s.visual.sets + s.visual_sets_busy, 10u);
    EXPECT_GE(s.visual.sets, 1u);
  });
}

TEST(BackgroundRuntime, BadSettingsAreNamed) {
  duet::Profile profile = duet::builtin_profile("dual");
  duet_test::ScriptedChassis chassis;
  duet_test::ScriptedSensor a, b;
  duet::RgbdSensorInterface* sensors[] = {&a, &b};
  auto message = [&](const duet::RuntimeSettings& rs) {
    try {
      duet::ExplorationRuntime rt(profile, chassis, sensors, rs);
    } catch (const duet::Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  duet::RuntimeSettings rs = background(-1.0);
  EXPECT_NE(message(rs).find("decision_delay_s"), std::string::npos);
  rs = background(0.0);
  rs.background_threads = -2;
  EXPECT_NE(message(rs).find("background_threads"), std::string::npos);
}
