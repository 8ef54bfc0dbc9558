// duet_runtime with its own control thread while drivers push from three threads and the
// application reads: its own test executable so that the ThreadSanitizer pass (scripts/test.sh)
// builds only libduet.so and this file.
#include "capi/capi_helpers.hpp"

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <string>
#include <chrono>
#include <thread>
#include <vector>

namespace {

using duet_capi_test::DeviceTest;

// Drivers push from their own threads while the runtime runs its own control thread and the
// application reads the status, the command and the grid and saves the maps (copied under the
// run lock, written outside it while control goes on): part of the ThreadSanitizer pass.
// One-thread arenas (device and background): Debian's TBB is not instrumented, so TSan would
// take its parallel loops for races (scripts/test.sh).
// One 640 x 480 depth frame (millimetres), stamped `stamp_s` (its capture time), to `sensor`.
// The two cameras' frames of one instant carry one stamp, as synchronised cameras' do: the
// runtime pairs frames whose stamps lie within 25 ms (SynchronizerSettings), and frames stamped
// when each push happened drifted apart under ThreadSanitizer on a loaded machine until no set
// was ever made (no set in 120 s in 2 of 21 runs here; CI stop 52: one save where three were due).
void push_depth(duet_runtime rt, size_t sensor, const std::vector<uint16_t>& depth, double stamp_s) {
  duet_rgbd_image im;
  duet_rgbd_image_init(&im);
  im.stamp_s = stamp_s;
  im.depth = depth.data();
  im.width = 640;
  im.height = 480;
  duet_runtime_push_rgbd(rt, sensor, &im);
}

class CapiRuntimeThreads : public DeviceTest {
 protected:
  void SetUp() override {
    (void)duet_device_get_error(nullptr);
    device_ = duet_device_new("threads=1");
    ASSERT_NE(device_, nullptr) << duet_device_get_error_message(nullptr);
  }
};

TEST_F(CapiRuntimeThreads, PushFromThreeThreadsWhileTheRuntimeRunsItsOwnThread) {
  const char* sets[] = {"runtime.background_threads=1", "runtime.sensor_rate_hz=5"};
  duet_runtime rt = duet_runtime_new(device_, DUET_PROFILE_NAME_OR_FILE, "dual", sets, 2, 1);
  ASSERT_NE(rt, nullptr) << message();
  std::atomic<int> events{0};
  duet_runtime_set_event_callback(rt, [](void* u, double, const char*) { ++*static_cast<std::atomic<int>*>(u); }, &events);
  duet_runtime_start(rt, nullptr, nullptr);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  duet_runtime_start(rt, nullptr, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
  duet_runtime_spin_once(rt, duet_time_now());
  EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
  std::atomic<bool> stop{false};
  // Each camera on its own thread, both capturing on one 5 Hz tick (their frames share a stamp).
  const double t0 = duet_time_now();
  auto camera = [&](size_t sensor) {
    std::vector<uint16_t> depth(640 * 480, static_cast<uint16_t>(1500 + 500 * sensor));
    for (int k = 0; !stop.load(); ++k) {
      const double tick = t0 + 0.2 * k;
      while (duet_time_now() < tick && !stop.load()) std::this_thread::sleep_for(std::chrono::milliseconds(2));
      push_depth(rt, sensor, depth, tick);
    }
  };
  auto wheels = [&] {
    while (!stop.load()) {
      duet_runtime_push_odometry(rt, duet_time_now(), duet_pose2{0, 0, 0}, duet_twist{0, 0});
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  };
  std::thread c0(camera, 0), c1(camera, 1), w(wheels);
  std::size_t reads = 0, saves = 0;
  const auto dir = std::filesystem::temp_directory_path() / ("duet_capi_threads_save_" + std::to_string(::getpid()));
  // At least 3 s of contention, then on until every count asserted below is reached: the
  // counts are what the test is about, not how fast a sanitizer build on a loaded CI machine
  // reaches them (CI stop 52 failed the like-shaped save test below on its 4 s clock). The
  // 120 s cap only keeps a hung runtime from hanging the test.
  const double t_start = duet_time_now();
  auto enough = [&](const duet_runtime_stats& now) {
    return saves == 2 && reads > 10 && now.control_periods > 20 && now.frames_pushed >= 20 &&
           now.odometry_pushed >= 100 && now.sets_integrated >= 1;
  };
  for (;;) {
    duet_runtime_stats now;
    duet_runtime_get_stats(rt, &now);
    const double elapsed = duet_time_now() - t_start;
    if (elapsed > 120.0 || (elapsed >= 3.0 && enough(now))) break;
    if (saves < 2 && now.control_periods >= 5 * (saves + 1)) {  // twice, once control has run
      duet_runtime_save(rt, dir.string().c_str());
      EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
      EXPECT_TRUE(std::filesystem::is_regular_file(dir / "summary.json"));
      EXPECT_TRUE(std::filesystem::is_regular_file(dir / "cloud.pcd"));
      ++saves;
    }
    duet_runtime_status s;
    duet_runtime_get_status(rt, &s);
    (void)duet_runtime_get_command(rt);
    duet_grid g = duet_runtime_get_grid(rt);
    duet_grid_release(g);
    ++reads;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  duet_runtime_pause(rt);
  duet_runtime_resume(rt);
  stop.store(true);
  c0.join();
  c1.join();
  w.join();
  duet_runtime_join(rt);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  duet_runtime_stats st;
  duet_runtime_get_stats(rt, &st);
  // 20 Hz over at least 3 s, with margin for a slow sanitizer build. Under TSan the two saves take 1-2 s
  // each (the map update in flight is waited for): 12 periods when a save held the run lock
  // for it, 71 now that it is waited for without the lock.
  EXPECT_GT(st.control_periods, 20u);
  EXPECT_GE(st.frames_pushed, 20u);
  EXPECT_GE(st.odometry_pushed, 100u);
  EXPECT_GE(st.sets_integrated, 1u);
  EXPECT_GT(reads, 10u);
  EXPECT_EQ(saves, 2u);
  std::filesystem::remove_all(dir);
  duet_cloud cloud = duet_runtime_get_cloud(rt);
  EXPECT_GT(duet_cloud_get_size(cloud), 0u);
  duet_cloud_release(cloud);
  duet_runtime_release(rt);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
}

// The ROS node's threads on a device of threads=1: one thread copies the grid (in the device's
// arena) while a service thread saves and the publishing thread reads the cloud. A save that
// finds the arena's one slot busy runs on the worker of its second slot (thread index 1): the
// voxel filter's per-thread tables once wrote past their end there (a SIGSEGV in the node under
// ThreadSanitizer, CI stop 50; VoxelFilter.RunsOnTheSecondSlotOfAOneThreadArena is the
// deterministic test). Two readers of the map at once: the map updates stay held until both are
// done.
TEST_F(CapiRuntimeThreads, SaveAndCloudWhileAnotherThreadCopiesTheGrid) {
  const char* sets[] = {"runtime.background_threads=1", "runtime.sensor_rate_hz=5"};
  duet_runtime rt = duet_runtime_new(device_, DUET_PROFILE_NAME_OR_FILE, "dual", sets, 2, 2);
  ASSERT_NE(rt, nullptr) << message();
  static std::atomic<int> errors{0};  // every error on the device, whichever thread met it
  errors = 0;
  duet_device_set_error_callback(device_, [](void*, duet_error, const char* m) {
    ++errors;
    ADD_FAILURE() << m;
  }, nullptr);
  duet_runtime_start(rt, nullptr, nullptr);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  std::atomic<bool> stop{false};
  std::atomic<std::size_t> copies{0}, clouds{0};
  std::thread feed([&] {
    std::vector<uint16_t> depth(640 * 480, 1500);  // a wall 1.5 m ahead
    int n = 0;
    while (!stop.load()) {
      const double stamp = duet_time_now();  // both frames of one instant
      for (size_t sensor = 0; sensor < 2 && n % 8 == 0; ++sensor) {
        push_depth(rt, sensor, depth, stamp);
      }
      duet_runtime_push_odometry(rt, duet_time_now(), duet_pose2{0, 0, 0}, duet_twist{0, 0});
      ++n;
      std::this_thread::sleep_for(std::chrono::milliseconds(25));
    }
  });
  duet_runtime_stats st0{};
  for (int i = 0; i < 400 && st0.control_periods == 0; ++i) {  // the grid and the cloud exist from the first period
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    duet_runtime_get_stats(rt, &st0);
  }
  ASSERT_GT(st0.control_periods, 0u);
  std::thread grids([&] {
    std::vector<float> p;
    while (!stop.load()) {
      duet_grid g = duet_runtime_get_grid(rt);
      if (g == nullptr) continue;
      p.resize(static_cast<std::size_t>(duet_grid_get_width(g)) * static_cast<std::size_t>(duet_grid_get_height(g)));
      for (int k = 0; k < 20 && !p.empty(); ++k) {
        duet_grid_copy_probabilities(g, p.data(), p.size());  // in the device's arena
        ++copies;
      }
      duet_grid_release(g);
    }
  });
  std::thread cloud_reader([&] {
    while (!stop.load()) {
      duet_cloud c = duet_runtime_get_cloud(rt);
      if (c != nullptr) ++clouds;
      duet_cloud_release(c);
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  });
  const auto dir = std::filesystem::temp_directory_path() / ("duet_capi_threads_save2_" + std::to_string(::getpid()));
  std::size_t saves = 0;
  // At least 4 s of contention, then on until 3 saves, 11 copies and 11 clouds have happened
  // beside each other. A 4 s clock alone failed on CI stop 52 under ThreadSanitizer: the first
  // set was integrated so late that one save fitted. The 120 s cap only stops a hung runtime.
  const double t_start = duet_time_now();
  for (;;) {
    const double elapsed = duet_time_now() - t_start;
    if (elapsed > 120.0 || (elapsed >= 4.0 && saves >= 3 && copies.load() > 10 && clouds.load() > 10)) break;
    duet_runtime_stats st;
    duet_runtime_get_stats(rt, &st);
    if (st.sets_integrated >= 1) {
      duet_runtime_save(rt, dir.string().c_str());
      ++saves;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  stop.store(true);
  feed.join();
  grids.join();
  cloud_reader.join();
  duet_runtime_join(rt);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
  EXPECT_EQ(errors.load(), 0);
  EXPECT_GE(saves, 3u);
  EXPECT_GT(copies.load(), 10u);
  EXPECT_GT(clouds.load(), 10u);
  EXPECT_TRUE(std::filesystem::is_regular_file(dir / "cloud.pcd"));
  duet_cloud last = duet_runtime_get_cloud(rt);
  EXPECT_GT(duet_cloud_get_size(last), 0u);
  duet_cloud_release(last);
  std::filesystem::remove_all(dir);
  duet_runtime_release(rt);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
  duet_device_set_error_callback(device_, nullptr, nullptr);
}

TEST_F(CapiRuntimeThreads, ReleasedFromItsOwnEventCallback) {
  // The last reference dropped on the runtime's own thread (its event callback): the thread
  // ends by itself and frees the runtime - no join of a thread by itself, no use after free.
  const char* sets[] = {"runtime.background_threads=1"};
  duet_runtime rt = duet_runtime_new(device_, DUET_PROFILE_NAME_OR_FILE, "single", sets, 1, 1);
  ASSERT_NE(rt, nullptr) << message();
  struct Ctx {
    duet_runtime rt;
    std::atomic<bool> released{false};
  } ctx{rt};
  duet_runtime_set_event_callback(
      rt,
      [](void* u, double, const char* m) {
        auto* c = static_cast<Ctx*>(u);
        if (std::string(m).find("-> done") != std::string::npos && !c->released.exchange(true)) duet_runtime_release(c->rt);
      },
      &ctx);
  duet_runtime_start(rt, nullptr, nullptr);
  duet_runtime_stop(rt);  // the next period reports "idle -> done"
  for (int i = 0; i < 400 && !ctx.released.load(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_TRUE(ctx.released.load());
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // the thread finishes and frees the runtime
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
  duet_runtime_spin_once(rt, 1.0);  // released: an error, never a crash
  EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
}

TEST_F(CapiRuntimeThreads, ReleaseWhileRunningStopsTheThreadFirst) {
  const char* sets[] = {"runtime.background_threads=1"};
  duet_runtime rt = duet_runtime_new(device_, DUET_PROFILE_NAME_OR_FILE, "single", sets, 1, 1);
  ASSERT_NE(rt, nullptr) << message();
  static std::atomic<int> after{0};
  static std::atomic<bool> gone{false};
  duet_runtime_set_event_callback(rt, [](void*, double, const char*) { if (gone.load()) ++after; }, nullptr);
  duet_runtime_start(rt, nullptr, nullptr);
  std::this_thread::sleep_for(std::chrono::milliseconds(150));
  duet_runtime_stop(rt);
  duet_runtime_release(rt);  // returns once the thread has ended
  gone.store(true);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_EQ(after.load(), 0);  // no callback after the release returned
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
}

}  // namespace
