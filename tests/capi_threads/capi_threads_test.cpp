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
  auto camera = [&](size_t sensor) {
    std::vector<uint16_t> depth(640 * 480, static_cast<uint16_t>(1500 + 500 * sensor));
    while (!stop.load()) {
      duet_rgbd_image im;
      duet_rgbd_image_init(&im);
      im.stamp_s = duet_time_now();
      im.depth = depth.data();
      im.width = 640;
      im.height = 480;
      duet_runtime_push_rgbd(rt, sensor, &im);
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
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
  const double t_end = duet_time_now() + 3.0;
  while (duet_time_now() < t_end) {
    duet_runtime_stats now;
    duet_runtime_get_stats(rt, &now);
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
  // 20 Hz over 3 s, with margin for a slow sanitizer build. Under TSan the two saves take 1-2 s
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
