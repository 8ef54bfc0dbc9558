// duet_runtime and duet_sim (duet_runtime.h, duet_sim.h): the robot loop through the C API on
// the simulator, the operator's requests, counted drops, and pushes from several
// threads into a runtime running its own thread (also run under ThreadSanitizer).
// (Misuse of the same calls: capi_runtime_misuse_test.cpp.)
#include "capi_helpers.hpp"

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <fstream>
#include <sstream>
#include <thread>

namespace {

using duet_capi_test::DeviceTest;

/// The simulator and a runtime on it, stepped like bindings_c/examples/robot_loop.c.
class Loop {
 public:
  Loop(duet_device d, const char* world, std::vector<const char*> sets, std::uint64_t seed = 1, bool gyro = false)
      : gyro_(gyro) {
    sets.insert(sets.begin(), "runtime.sensor_rate_hz=1");
    sim_ = duet_sim_new(d, world, DUET_PROFILE_NAME_OR_FILE, "dual", sets.data(), sets.size(), seed);
    rt_ = duet_runtime_new(d, DUET_PROFILE_NAME_OR_FILE, "dual", sets.data(), sets.size(), seed);
    if (!rt_ || !sim_) return;
    duet_runtime_set_time_origin(rt_, 0.0);
    for (size_t i = 0; i < duet_runtime_get_sensor_count(rt_); ++i) {
      duet_runtime_sensor_info info;
      duet_runtime_get_sensor_info(rt_, i, &info);
      info_.push_back(info);
      depth_.emplace_back(static_cast<size_t>(info.width) * info.height);
      rgb_.emplace_back(static_cast<size_t>(info.width) * info.height * 3);
    }
    dt_ = duet_runtime_get_control_period(rt_);
  }
  ~Loop() {
    duet_runtime_release(rt_);
    duet_sim_release(sim_);
  }
  [[nodiscard]] bool ok() const { return rt_ && sim_; }
  /// One period: the simulator moves, its data is pushed, the runtime spins (unless `spin` is false).
  void step(bool spin = true) {
    duet_sim_step(sim_, command_, dt_);
    t_ += dt_;
    double st[64];
    duet_pose2 p[64];
    duet_twist tw[64];
    size_t n;
    while ((n = duet_sim_take_odometry(sim_, st, p, tw, 64)) > 0)
      for (size_t k = 0; k < n; ++k) {
        if (gyro_) duet_runtime_push_gyro(rt_, st[k], tw[k].omega);  // a gyro beside the wheels
        duet_runtime_push_odometry(rt_, st[k], p[k], tw[k]);
      }
    for (size_t i = 0; i < info_.size(); ++i) {
      double stamp;
      while (duet_sim_take_frame(sim_, i, &stamp, depth_[i].data(), 0, rgb_[i].data(), 0, info_[i].width, info_[i].height)) {
        duet_rgbd_image im;
        duet_rgbd_image_init(&im);
        im.stamp_s = stamp;
        im.depth = depth_[i].data();
        im.width = info_[i].width;
        im.height = info_[i].height;
        im.depth_units_per_m = info_[i].depth_units_per_m;
        im.color = rgb_[i].data();
        duet_runtime_push_rgbd(rt_, i, &im);
      }
    }
    if (spin) duet_runtime_spin_once(rt_, t_);
    command_ = duet_runtime_get_command(rt_);
  }
  void run_for(double seconds) {
    const double end = t_ + seconds;
    while (t_ + 1e-9 < end) step();
  }
  [[nodiscard]] duet_runtime_status status() const {
    duet_runtime_status s;
    duet_runtime_get_status(rt_, &s);
    return s;
  }
  [[nodiscard]] std::string stop_detail() const {
    std::string s(duet_runtime_get_stop_detail(rt_, nullptr, 0), '\0');
    std::vector<char> buf(s.size() + 1);
    duet_runtime_get_stop_detail(rt_, buf.data(), buf.size());
    return buf.data();
  }
  duet_runtime rt() const { return rt_; }
  duet_sim sim() const { return sim_; }
  double t() const { return t_; }

 private:
  duet_sim sim_ = nullptr;
  duet_runtime rt_ = nullptr;
  std::vector<duet_runtime_sensor_info> info_;
  std::vector<std::vector<uint16_t>> depth_;
  std::vector<std::vector<uint8_t>> rgb_;
  double dt_ = 0.05, t_ = 0.0;
  duet_twist command_{0.0f, 0.0f};
  bool gyro_ = false;
};

using CapiRuntime = DeviceTest;

TEST_F(CapiRuntime, ExploresTheLabThroughTheCApi) {
  Loop loop(device_, "lab", {});
  ASSERT_TRUE(loop.ok()) << message();
  EXPECT_TRUE(std::isnan(loop.status().time_s));  // before the first period
  loop.run_for(30.0);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  const duet_runtime_status s = loop.status();
  EXPECT_DOUBLE_EQ(s.time_s, loop.t());
  EXPECT_EQ(s.state, DUET_EXPLORER_EXPLORING);
  EXPECT_EQ(s.map_updates, 31u);  // 1 Hz: the frames of t = 0, 1, ..., 30 s
  EXPECT_EQ(s.health, DUET_POSE_GOOD);
  // The pose estimate follows the truth (the correction keeps it within a few cm here).
  const duet_pose2 truth = duet_sim_get_true_pose(loop.sim());
  EXPECT_LT(std::hypot(s.pose.x - truth.x, s.pose.y - truth.y), 0.15f);
  // A goal with a path that ends at it.
  ASSERT_EQ(s.has_goal, 1);
  std::vector<float> path(2 * s.path_points);
  ASSERT_EQ(duet_runtime_get_path(loop.rt(), path.data(), 0, s.path_points), s.path_points);
  ASSERT_GE(s.path_points, 1u);
  EXPECT_LT(std::hypot(path[path.size() - 2] - s.goal.x, path.back() - s.goal.y), 0.2f);
  // The grid covers a good part of the lab already, and scores as duet explore scores it.
  duet_grid grid = duet_runtime_get_grid(loop.rt());
  double coverage = 0.0, area = 0.0;
  duet_sim_score(loop.sim(), grid, &coverage, &area);
  EXPECT_GT(coverage, 0.1);  // the first 30 s of the lab: ~0.18 of its reachable area, ~15 m^2
  EXPECT_GT(area, 10.0);
  EXPECT_GT(duet_grid_get_known_cells(grid), 1000u);
  duet_grid_release(grid);
  duet_cloud cloud = duet_runtime_get_cloud(loop.rt());
  EXPECT_GT(duet_cloud_get_size(cloud), 1000u);
  EXPECT_EQ(duet_cloud_has_colors(cloud), 1);
  duet_cloud_release(cloud);
  EXPECT_EQ(duet_sim_get_collisions(loop.sim()), 0u);
  duet_runtime_stats st;
  duet_runtime_get_stats(loop.rt(), &st);
  EXPECT_EQ(st.control_periods, 600u);
  EXPECT_EQ(st.frames_pushed, 2u * 31u);  // two sensors at 1 Hz, t = 0 ... 30 s
  EXPECT_EQ(st.frames_invalid + st.frames_out_of_order + st.frames_queue_overflow, 0u);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
}

TEST_F(CapiRuntime, SavesTheFilesDuetExploreWrites) {
  Loop loop(device_, "lab", {});
  ASSERT_TRUE(loop.ok()) << message();
  loop.run_for(5.0);
  const auto dir = std::filesystem::temp_directory_path() / ("duet_capi_save_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  duet_runtime_save(loop.rt(), dir.c_str());
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  for (const char* f : {"grid.yaml", "grid.pgm", "grid.png", "cloud.pcd", "trajectory.tum", "summary.json"})
    EXPECT_TRUE(std::filesystem::is_regular_file(dir / f)) << f;
  std::ifstream tum(dir / "trajectory.tum");
  std::string line;
  std::size_t poses = 0;
  while (std::getline(tum, line)) poses += !line.empty() && line[0] != '#';
  EXPECT_EQ(poses, 100u);  // one per control period
  std::filesystem::remove_all(dir);
  // A folder that cannot be written: an IO error naming it.
  duet_runtime_save(loop.rt(), "/proc/duet_cannot_write_here");
  EXPECT_EQ(take(), DUET_ERROR_IO);
  EXPECT_NE(message().find("/proc/duet_cannot_write_here"), std::string::npos) << message();
}

TEST_F(CapiRuntime, RecordsWhatItTakesForAReplay) {
  const auto dir = std::filesystem::temp_directory_path() / ("duet_capi_rec_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  Loop loop(device_, "lab", {});
  ASSERT_TRUE(loop.ok()) << message();
  duet_runtime_record(loop.rt(), dir.c_str());
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  duet_runtime_record(loop.rt(), dir.c_str());  // once
  EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
  loop.run_for(5.0);
  duet_runtime_record(loop.rt(), (dir.string() + "_late").c_str());  // after the first period
  EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
  duet_runtime_join(loop.rt());
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  duet_runtime_stats st;
  duet_runtime_get_stats(loop.rt(), &st);
  EXPECT_EQ(st.frames_recorded, 12u);  // 2 sensors x t = 0 ... 5 s
  EXPECT_EQ(st.frames_record_dropped, 0u);
  std::ifstream meta(dir / "recording.yaml");
  std::stringstream text;
  text << meta.rdbuf();
  EXPECT_NE(text.str().find("frames_recorded: 12"), std::string::npos) << text.str();
  EXPECT_TRUE(std::filesystem::is_regular_file(dir / "kinect_front" / "depth" / "000005.png"));
  // A folder in use is refused.
  Loop other(device_, "lab", {});
  duet_runtime_record(other.rt(), dir.c_str());
  EXPECT_EQ(take(), DUET_ERROR_IO);
  EXPECT_NE(message().find("empty or new folder"), std::string::npos) << message();
  std::filesystem::remove_all(dir);
}

TEST_F(CapiRuntime, StopEndsExplorationAndHoldsStill) {
  Loop loop(device_, "lab", {});
  ASSERT_TRUE(loop.ok()) << message();
  loop.run_for(10.0);
  duet_runtime_stop(loop.rt());
  loop.run_for(2.0);
  const duet_runtime_status s = loop.status();
  EXPECT_EQ(s.state, DUET_EXPLORER_DONE);
  EXPECT_EQ(s.command.v, 0.0f);
  EXPECT_EQ(s.command.omega, 0.0f);
  EXPECT_EQ(loop.stop_detail(), "stopped by the operator");
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
}

TEST_F(CapiRuntime, ReturnHomeDrivesBackToTheStart) {
  Loop loop(device_, "lab", {});
  ASSERT_TRUE(loop.ok()) << message();
  const duet_pose2 start = duet_sim_get_true_pose(loop.sim());
  loop.run_for(25.0);
  const duet_pose2 away = duet_sim_get_true_pose(loop.sim());
  ASSERT_GT(std::hypot(away.x - start.x, away.y - start.y), 0.5f) << "the robot should have left the start";
  duet_runtime_return_home(loop.rt());
  loop.step();
  EXPECT_EQ(loop.status().state, DUET_EXPLORER_RETURNING_HOME);
  for (int i = 0; i < 20 * 120 && loop.status().state != DUET_EXPLORER_DONE; ++i) loop.step();
  EXPECT_EQ(loop.status().state, DUET_EXPLORER_DONE);
  EXPECT_NE(loop.stop_detail().find("the operator asked to return home"), std::string::npos) << loop.stop_detail();
  const duet_pose2 end = duet_sim_get_true_pose(loop.sim());
  EXPECT_LT(std::hypot(end.x - start.x, end.y - start.y), 0.5f);
  EXPECT_EQ(duet_sim_get_collisions(loop.sim()), 0u);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
}

TEST_F(CapiRuntime, PauseStopsTheTimeLineAndDropsInput) {
  Loop loop(device_, "lab", {});
  ASSERT_TRUE(loop.ok()) << message();
  loop.run_for(10.0);
  const duet_runtime_status before = loop.status();
  duet_runtime_pause(loop.rt());
  duet_runtime_pause(loop.rt());  // idempotent
  loop.run_for(5.0);              // the robot's drivers keep delivering; the runtime is spun
  duet_runtime_status paused = loop.status();
  EXPECT_EQ(paused.paused, 1);
  EXPECT_EQ(paused.command.v, 0.0f);
  EXPECT_EQ(paused.map_updates, before.map_updates);  // no mapping while paused
  duet_runtime_stats st;
  duet_runtime_get_stats(loop.rt(), &st);
  EXPECT_EQ(st.frames_paused, 2u * 5u);
  EXPECT_GT(st.odometry_paused, 200u);  // 50 Hz
  duet_runtime_resume(loop.rt());
  loop.run_for(10.0);
  const duet_runtime_status after = loop.status();
  EXPECT_EQ(after.paused, 0);
  EXPECT_EQ(after.state, DUET_EXPLORER_EXPLORING);
  EXPECT_GE(after.map_updates, before.map_updates + 9);
  duet_runtime_get_stats(loop.rt(), &st);
  // The pause was skipped by the time line: nothing after it looks out of order or stepped back.
  EXPECT_EQ(st.odometry_out_of_order + st.frames_out_of_order + st.clock_restarts, 0u);
  EXPECT_EQ(duet_sim_get_collisions(loop.sim()), 0u);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
}

TEST_F(CapiRuntime, AGyroGivesTheHeading) {
  // A gyro beside the simulated Kobuki's wheels (its measured yaw rate at each odometry stamp):
  // every step is covered and the robot explores as with the odometry alone, the heading now
  // integrated from the gyro's rates.
  Loop plain(device_, "lab", {});
  Loop gyro(device_, "lab", {}, 1, true);
  ASSERT_TRUE(plain.ok() && gyro.ok()) << message();
  plain.run_for(10.0);
  gyro.run_for(10.0);
  duet_runtime_stats st;
  duet_runtime_get_stats(gyro.rt(), &st);
  EXPECT_EQ(st.gyro_pushed, 501u);  // 50 Hz, t = 0 ... 10 s
  EXPECT_EQ(st.gyro_gaps, 0u);
  EXPECT_EQ(st.gyro_invalid, 0u);
  // Each estimate against its own run's truth (the two runs' paths part after a few goals: a
  // decision taken on the move - the profile's handoff - turns on millimetres).
  const duet_runtime_status a = plain.status(), b = gyro.status();
  const duet_pose2 truth = duet_sim_get_true_pose(gyro.sim()), truth_a = duet_sim_get_true_pose(plain.sim());
  EXPECT_LT(std::hypot(a.pose.x - truth_a.x, a.pose.y - truth_a.y), 0.15f);
  EXPECT_LT(std::abs(std::remainder(a.pose.theta - truth_a.theta, 6.2831853f)), 0.05f);
  EXPECT_LT(std::abs(std::remainder(b.pose.theta - truth.theta, 6.2831853f)), 0.05f);
  EXPECT_LT(std::hypot(b.pose.x - truth.x, b.pose.y - truth.y), 0.15f);
  EXPECT_EQ(b.state, DUET_EXPLORER_EXPLORING);
  EXPECT_EQ(duet_sim_get_collisions(gyro.sim()), 0u);
  duet_runtime_push_gyro(gyro.rt(), std::nan(""), 1.0f);
  duet_runtime_push_gyro(gyro.rt(), 100.0, INFINITY);
  duet_runtime_push_gyro(gyro.rt(), 1.0, 0.5f);  // before the last sample
  gyro.step();
  duet_runtime_get_stats(gyro.rt(), &st);
  EXPECT_EQ(st.gyro_invalid, 3u);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
  duet_runtime_push_gyro(nullptr, 1.0, 0.0f);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
}

TEST_F(CapiRuntime, BadStampsAreCountedDropsNotErrors) {
  Loop loop(device_, "lab", {});
  ASSERT_TRUE(loop.ok()) << message();
  loop.run_for(2.0);
  const double t = loop.t();
  const duet_pose2 p{0.0f, 0.0f, 0.0f};
  const duet_twist z{0.0f, 0.0f};
  duet_runtime_push_odometry(loop.rt(), std::nan(""), p, z);   // invalid
  duet_runtime_push_odometry(loop.rt(), t - 1.0, p, z);        // out of order
  duet_runtime_push_odometry(loop.rt(), t - 1.0, p, z);        // duplicate
  const duet_pose2 inf_pose{INFINITY, 0.0f, 0.0f};
  duet_runtime_push_odometry(loop.rt(), t + 0.001, inf_pose, z);  // invalid pose
  std::vector<uint16_t> depth(640 * 480, 1500);
  duet_rgbd_image im;
  duet_rgbd_image_init(&im);
  im.depth = depth.data();
  im.width = 640;
  im.height = 480;
  duet_runtime_push_rgbd(loop.rt(), 0, &im);  // stamp NaN (init's): a counted drop
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
  loop.step();
  duet_runtime_stats st;
  duet_runtime_get_stats(loop.rt(), &st);
  EXPECT_EQ(st.odometry_invalid, 2u);
  EXPECT_EQ(st.odometry_out_of_order, 2u);
  EXPECT_EQ(st.frames_invalid, 1u);
  loop.run_for(3.0);
  EXPECT_EQ(loop.status().state, DUET_EXPLORER_EXPLORING);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
}

TEST_F(CapiRuntime, DepthInOtherUnitsAndFloatMetresMapsTheSame) {
  // One frame of a flat wall 2 m ahead, pushed as uint16 mm, uint16 at 5000 units/m and float
  // metres into three runtimes: the same grid.
  std::vector<uint16_t> mm(640 * 480, 2000), tum(640 * 480, 10000);
  std::vector<float> metres(640 * 480, 2.0f);
  metres[0] = std::nanf("");  // no return
  mm[0] = 0;
  tum[0] = 0;
  std::vector<size_t> known;
  for (int variant = 0; variant < 3; ++variant) {
    const char* sets[] = {"runtime.sensor_rate_hz=1"};
    duet_runtime rt = duet_runtime_new(device_, DUET_PROFILE_NAME_OR_FILE, "single", sets, 1, 1);
    ASSERT_NE(rt, nullptr) << message();
    duet_runtime_set_time_origin(rt, 0.0);
    for (int k = 0; k <= 50; ++k) duet_runtime_push_odometry(rt, 0.02 * k, duet_pose2{0, 0, 0}, duet_twist{0, 0});
    duet_rgbd_image im;
    duet_rgbd_image_init(&im);
    im.stamp_s = 0.5;
    im.width = 640;
    im.height = 480;
    if (variant == 0) im.depth = mm.data();
    if (variant == 1) {
      im.depth = tum.data();
      im.depth_units_per_m = 5000.0f;
    }
    if (variant == 2) {
      im.depth = metres.data();
      im.depth_format = DUET_DEPTH_F32;
    }
    duet_runtime_push_rgbd(rt, 0, &im);
    for (int k = 1; k <= 20; ++k) duet_runtime_spin_once(rt, 0.05 * k);
    duet_grid g = duet_runtime_get_grid(rt);
    known.push_back(duet_grid_get_known_cells(g));
    duet_grid_release(g);
    duet_runtime_release(rt);
  }
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  EXPECT_GT(known[0], 100u);
  EXPECT_EQ(known[1], known[0]);
  EXPECT_EQ(known[2], known[0]);
}

TEST_F(CapiRuntime, PerFrameIntrinsicsBackProjectThatFrame) {
  // A wall 2 m ahead seen through the profile's intrinsics and through twice its focal length:
  // the same pixels span half the width.
  std::vector<uint16_t> mm(640 * 480, 2000);
  auto spread = [&](const float* intrinsics) {
    const char* sets[] = {"runtime.sensor_rate_hz=1"};
    duet_runtime rt = duet_runtime_new(device_, DUET_PROFILE_NAME_OR_FILE, "single", sets, 1, 1);
    duet_runtime_set_time_origin(rt, 0.0);
    for (int k = 0; k <= 50; ++k) duet_runtime_push_odometry(rt, 0.02 * k, duet_pose2{0, 0, 0}, duet_twist{0, 0});
    duet_rgbd_image im;
    duet_rgbd_image_init(&im);
    EXPECT_EQ(im.intrinsics, nullptr);
    im.stamp_s = 0.5;
    im.width = 640;
    im.height = 480;
    im.depth = mm.data();
    im.intrinsics = intrinsics;
    duet_runtime_push_rgbd(rt, 0, &im);
    for (int k = 1; k <= 20; ++k) duet_runtime_spin_once(rt, 0.05 * k);
    duet_cloud c = duet_runtime_get_cloud(rt);
    const size_t n = duet_cloud_get_size(c);
    std::vector<float> xyz(3 * n);
    duet_cloud_copy_points(c, xyz.data(), 0, n);
    float lo = 1e9f, hi = -1e9f;
    for (size_t i = 0; i < n; ++i) {
      lo = std::min(lo, xyz[3 * i + 1]);
      hi = std::max(hi, xyz[3 * i + 1]);
    }
    duet_cloud_release(c);
    duet_runtime_release(rt);
    return n ? hi - lo : 0.0f;
  };
  duet_runtime_sensor_info info;
  {
    duet_runtime rt = duet_runtime_new(device_, DUET_PROFILE_NAME_OR_FILE, "single", nullptr, 0, 1);
    duet_runtime_get_sensor_info(rt, 0, &info);
    duet_runtime_release(rt);
  }
  const float own = spread(nullptr);
  const float twice[4] = {2.0f * info.fx, 2.0f * info.fy, info.cx, info.cy};
  const float narrow = spread(twice);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  EXPECT_GT(own, 1.5f);
  EXPECT_NEAR(narrow, own / 2.0f, 0.1f * own);
  // Invalid intrinsics: an error naming them.
  duet_runtime rt = duet_runtime_new(device_, DUET_PROFILE_NAME_OR_FILE, "single", nullptr, 0, 1);
  duet_rgbd_image im;
  duet_rgbd_image_init(&im);
  im.stamp_s = 1.0;
  im.width = 640;
  im.height = 480;
  im.depth = mm.data();
  const float bad[4] = {-1.0f, 500.0f, 320.0f, 240.0f};
  im.intrinsics = bad;
  duet_runtime_push_rgbd(rt, 0, &im);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("intrinsics"), std::string::npos) << message();
  duet_runtime_release(rt);
}

TEST_F(CapiRuntime, EventsReachTheCallback) {
  Loop loop(device_, "lab", {});
  ASSERT_TRUE(loop.ok()) << message();
  std::vector<std::string> lines;
  duet_runtime_set_event_callback(loop.rt(), [](void* u, double, const char* m) { static_cast<std::vector<std::string>*>(u)->push_back(m); }, &lines);
  loop.run_for(3.0);
  duet_runtime_stop(loop.rt());
  loop.step();
  bool exploring = false, done = false;
  for (const auto& l : lines) {
    exploring |= l.find("-> exploring") != std::string::npos;
    done |= l.find("-> done (stopped by the operator)") != std::string::npos;
  }
  EXPECT_TRUE(exploring && done) << ::testing::PrintToString(lines);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
}

}  // namespace
