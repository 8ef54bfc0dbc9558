// Misuse of duet_runtime and duet_sim (duet_runtime.h, duet_sim.h): every call rejects NULL,
// released and foreign handles, and bad arguments are errors that name what was wrong, never a
// crash (also run under AddressSanitizer).
#include "capi_helpers.hpp"

#include <cstdio>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace capi_runtime_misuse {

using CapiRuntime = duet_capi_test::DeviceTest;

/// Every entry point of duet_runtime.h and duet_sim.h that takes a runtime or simulator handle,
/// called with the given handles and otherwise valid arguments.
std::vector<std::pair<std::string, std::function<void()>>> runtime_calls(duet_runtime r, duet_sim s) {
  static std::vector<uint16_t> depth(640 * 480, 1000);
  static duet_rgbd_image im = [] {
    duet_rgbd_image x;
    duet_rgbd_image_init(&x);
    x.stamp_s = 1.0;
    x.depth = depth.data();
    x.width = 640;
    x.height = 480;
    return x;
  }();
  static duet_runtime_sensor_info info;
  static duet_runtime_status status;
  static duet_runtime_stats stats;
  static float xy[8];
  static char text[8];
  static double stamps[4];
  static duet_pose2 poses[4];
  static duet_twist twists[4];
  const std::string dir = (std::filesystem::temp_directory_path() / "duet_capi_never_written").string();
  return {
      {"duet_runtime_retain", [=] { duet_runtime_retain(r); }},
      {"duet_runtime_release", [=] { duet_runtime_release(r); }},
      {"duet_runtime_get_sensor_count", [=] { EXPECT_EQ(duet_runtime_get_sensor_count(r), 0u); }},
      {"duet_runtime_get_sensor_info", [=] { duet_runtime_get_sensor_info(r, 0, &info); }},
      {"duet_runtime_get_control_period", [=] { EXPECT_EQ(duet_runtime_get_control_period(r), 0.0); }},
      {"duet_runtime_set_time_origin", [=] { duet_runtime_set_time_origin(r, 0.0); }},
      {"duet_runtime_push_rgbd", [=] { duet_runtime_push_rgbd(r, 0, &im); }},
      {"duet_runtime_push_odometry", [=] { duet_runtime_push_odometry(r, 1.0, duet_pose2{0, 0, 0}, duet_twist{0, 0}); }},
      {"duet_runtime_push_gyro", [=] { duet_runtime_push_gyro(r, 1.0, 0.0f); }},
      {"duet_runtime_spin_once", [=] { duet_runtime_spin_once(r, 1.0); }},
      {"duet_runtime_start", [=] { duet_runtime_start(r, nullptr, nullptr); }},
      {"duet_runtime_pause", [=] { duet_runtime_pause(r); }},
      {"duet_runtime_resume", [=] { duet_runtime_resume(r); }},
      {"duet_runtime_stop", [=] { duet_runtime_stop(r); }},
      {"duet_runtime_return_home", [=] { duet_runtime_return_home(r); }},
      {"duet_runtime_join", [=] { duet_runtime_join(r); }},
      {"duet_runtime_save", [=] { duet_runtime_save(r, dir.c_str()); }},
      {"duet_runtime_record", [=] { duet_runtime_record(r, dir.c_str()); }},
      {"duet_runtime_get_status", [=] { duet_runtime_get_status(r, &status); }},
      {"duet_runtime_get_command", [=] { (void)duet_runtime_get_command(r); }},
      {"duet_runtime_get_stop_detail", [=] { EXPECT_EQ(duet_runtime_get_stop_detail(r, text, sizeof text), 0u); }},
      {"duet_runtime_get_path", [=] { EXPECT_EQ(duet_runtime_get_path(r, xy, 0, 4), 0u); }},
      {"duet_runtime_get_grid", [=] { EXPECT_EQ(duet_runtime_get_grid(r), nullptr); }},
      {"duet_runtime_get_cloud", [=] { EXPECT_EQ(duet_runtime_get_cloud(r), nullptr); }},
      {"duet_runtime_get_stats", [=] { duet_runtime_get_stats(r, &stats); }},
      {"duet_runtime_set_event_callback", [=] { duet_runtime_set_event_callback(r, nullptr, nullptr); }},
      {"duet_sim_retain", [=] { duet_sim_retain(s); }},
      {"duet_sim_release", [=] { duet_sim_release(s); }},
      {"duet_sim_get_time", [=] { EXPECT_TRUE(std::isnan(duet_sim_get_time(s))); }},
      {"duet_sim_step", [=] { duet_sim_step(s, duet_twist{0, 0}, 0.05); }},
      {"duet_sim_get_sensor_count", [=] { EXPECT_EQ(duet_sim_get_sensor_count(s), 0u); }},
      {"duet_sim_get_sensor_info", [=] { duet_sim_get_sensor_info(s, 0, &info); }},
      {"duet_sim_get_frames_waiting", [=] { EXPECT_EQ(duet_sim_get_frames_waiting(s, 0), 0u); }},
      {"duet_sim_take_frame", [=] {
         double st = 0.0;
         EXPECT_EQ(duet_sim_take_frame(s, 0, &st, depth.data(), 0, nullptr, 0, 640, 480), 0);
       }},
      {"duet_sim_take_odometry", [=] { EXPECT_EQ(duet_sim_take_odometry(s, stamps, poses, twists, 4), 0u); }},
      {"duet_sim_get_true_pose", [=] { EXPECT_TRUE(std::isnan(duet_sim_get_true_pose(s).x)); }},
      {"duet_sim_get_collisions", [=] { EXPECT_EQ(duet_sim_get_collisions(s), 0u); }},
  };
}

TEST_F(CapiRuntime, EveryCallRejectsNullReleasedAndForeignHandles) {
  // NULL: INVALID_ARGUMENT in the no-device slot, naming the function and NULL.
  for (auto& [name, call] : runtime_calls(nullptr, nullptr)) {
    SCOPED_TRACE(name);
    call();
    EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
    const std::string msg = duet_device_get_error_message(nullptr);
    EXPECT_NE(msg.find(name), std::string::npos) << msg;
    EXPECT_NE(msg.find("NULL"), std::string::npos) << msg;
    EXPECT_EQ(take(), DUET_ERROR_NONE);
  }
  // Released: INVALID_OPERATION on the device they belonged to.
  const char* sets[] = {"runtime.sensor_rate_hz=1"};
  duet_runtime rt = duet_runtime_new(device_, DUET_PROFILE_NAME_OR_FILE, "dual", sets, 1, 1);
  duet_sim sim = duet_sim_new(device_, "lab", DUET_PROFILE_NAME_OR_FILE, "dual", sets, 1, 1);
  ASSERT_NE(rt, nullptr) << message();
  ASSERT_NE(sim, nullptr) << message();
  duet_runtime_release(rt);
  duet_sim_release(sim);
  for (auto& [name, call] : runtime_calls(rt, sim)) {
    SCOPED_TRACE(name);
    call();
    EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
    const bool is_sim = name.rfind("duet_sim", 0) == 0;
    EXPECT_NE(message().find(is_sim ? "not a live duet_sim" : "not a live duet_runtime"), std::string::npos) << message();
    EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);
  }
  // Foreign pointers (never made by duet) and handles of another kind.
  int local = 0;
  duet_grid grid = duet_grid_new(device_, 0.05f);
  for (const std::uintptr_t b : {reinterpret_cast<std::uintptr_t>(&local), std::uintptr_t{0x1234}, ~std::uintptr_t{0}}) {
    for (auto& [name, call] : runtime_calls(reinterpret_cast<duet_runtime>(b), reinterpret_cast<duet_sim>(b))) {
      SCOPED_TRACE(name);
      call();
      EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_OPERATION);
    }
  }
  for (auto& [name, call] : runtime_calls(reinterpret_cast<duet_runtime>(grid), reinterpret_cast<duet_sim>(grid))) {
    SCOPED_TRACE(name);
    call();
    EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);  // on the grid's device
    EXPECT_NE(message().find("is a duet_grid"), std::string::npos) << message();
  }
  EXPECT_EQ(duet_grid_get_width(grid), 0);  // the wrong-kind release dropped nothing
  duet_grid_release(grid);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
  // The creators and loaders with a NULL device.
  EXPECT_EQ(duet_runtime_new(nullptr, DUET_PROFILE_NAME_OR_FILE, "dual", nullptr, 0, 1), nullptr);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_sim_new(nullptr, "lab", DUET_PROFILE_NAME_OR_FILE, "dual", nullptr, 0, 1), nullptr);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
  duet_profile_settings ps;
  duet_profile_settings_load(nullptr, DUET_PROFILE_NAME_OR_FILE, "dual", nullptr, 0, &ps);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_grid_load_map_server(nullptr, "x.yaml"), nullptr);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
  duet_grid_save_map_server(nullptr, "x.yaml");
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
  duet_sim_score(nullptr, nullptr, nullptr, nullptr);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_FALSE(std::filesystem::exists(std::filesystem::temp_directory_path() / "duet_capi_never_written"));
}

TEST_F(CapiRuntime, MisuseIsAnErrorNeverACrash) {
  const char* sets[] = {"runtime.sensor_rate_hz=1"};
  // Creation.
  EXPECT_EQ(duet_runtime_new(nullptr, DUET_PROFILE_NAME_OR_FILE, "dual", nullptr, 0, 1), nullptr);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_runtime_new(device_, DUET_PROFILE_NAME_OR_FILE, nullptr, nullptr, 0, 1), nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_runtime_new(device_, DUET_PROFILE_NAME_OR_FILE, "dual", nullptr, 2, 1), nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_runtime_new(device_, DUET_PROFILE_NAME_OR_FILE, "no_such_profile", nullptr, 0, 1), nullptr);
  EXPECT_NE(take(), DUET_ERROR_NONE);
  EXPECT_EQ(duet_runtime_new(device_, DUET_PROFILE_YAML_TEXT, "name: x\nno_such_key: 1\n", nullptr, 0, 1), nullptr);
  EXPECT_NE(take(), DUET_ERROR_NONE);
  EXPECT_NE(message().find("no_such_key"), std::string::npos) << message();
  const char* bad_set[] = {"runtime.control_rate_hz=-5"};
  EXPECT_EQ(duet_runtime_new(device_, DUET_PROFILE_NAME_OR_FILE, "dual", bad_set, 1, 1), nullptr);
  EXPECT_NE(take(), DUET_ERROR_NONE);
  EXPECT_NE(message().find("control_rate_hz"), std::string::npos) << message();
  EXPECT_EQ(duet_runtime_new(device_, static_cast<duet_profile_kind>(7), "dual", nullptr, 0, 1), nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_sim_new(device_, "/nonexistent/world.yaml", DUET_PROFILE_NAME_OR_FILE, "dual", nullptr, 0, 1), nullptr);
  EXPECT_NE(take(), DUET_ERROR_NONE);
  EXPECT_NE(message().find("/nonexistent/world.yaml"), std::string::npos) << message();

  duet_runtime rt = duet_runtime_new(device_, DUET_PROFILE_NAME_OR_FILE, "dual", sets, 1, 1);
  duet_sim sim = duet_sim_new(device_, "lab", DUET_PROFILE_NAME_OR_FILE, "dual", sets, 1, 1);
  ASSERT_NE(rt, nullptr) << message();
  ASSERT_NE(sim, nullptr) << message();
  // Arguments.
  duet_runtime_sensor_info info;
  duet_runtime_get_sensor_info(rt, 2, &info);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_runtime_get_sensor_info(rt, 0, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  std::vector<uint16_t> depth(640 * 480, 1000);
  duet_rgbd_image im;
  duet_rgbd_image_init(&im);
  im.stamp_s = 1.0;
  im.depth = depth.data();
  duet_runtime_push_rgbd(rt, 0, &im);  // size 0 x 0 (init's): an error, never an over-read
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("640 x 480"), std::string::npos) << message();
  im.width = 320;
  im.height = 240;
  duet_runtime_push_rgbd(rt, 0, &im);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  im.width = 640;
  im.height = 480;
  duet_runtime_push_rgbd(rt, 5, &im);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_runtime_push_rgbd(rt, 0, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  im.depth_row_stride = 100;  // shorter than a row
  duet_runtime_push_rgbd(rt, 0, &im);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  im.depth_row_stride = 0;
  im.depth_units_per_m = 0.0f;
  duet_runtime_push_rgbd(rt, 0, &im);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  im.depth_units_per_m = 1000.0f;
  std::vector<uint8_t> color(640 * 480 * 3);
  im.color = color.data();
  im.color_channels = 2;
  duet_runtime_push_rgbd(rt, 0, &im);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  im.depth_format = static_cast<duet_depth_format>(9);
  duet_runtime_push_rgbd(rt, 0, &im);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_runtime_stats st;
  duet_runtime_get_stats(rt, &st);
  EXPECT_EQ(st.frames_pushed, 0u);  // nothing invalid was queued
  duet_runtime_spin_once(rt, std::nan(""));
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_runtime_get_path(rt, nullptr, 0, 4), 0u);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_runtime_get_stop_detail(rt, nullptr, 0), 0u);  // sizing call: fine
  EXPECT_EQ(take(), DUET_ERROR_NONE);
  duet_runtime_return_home(rt);  // no period yet
  EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
  duet_runtime_spin_once(rt, 10.0);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
  duet_runtime_set_time_origin(rt, 0.0);  // too late
  EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
  duet_runtime_spin_once(rt, 9.0);  // backwards
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_runtime_start(rt, nullptr, nullptr);  // spun by its caller already
  EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
  duet_runtime_save(rt, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  // The simulator.
  duet_sim_step(sim, duet_twist{NAN, 0.0f}, 0.05);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_sim_step(sim, duet_twist{0.0f, 0.0f}, 0.0);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_sim_step(sim, duet_twist{0.0f, 0.0f}, 0.05);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
  double stamp = 0.0;
  EXPECT_EQ(duet_sim_take_frame(sim, 0, &stamp, depth.data(), 0, nullptr, 0, 320, 240), 0);  // wrong size
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_sim_take_frame(sim, 3, &stamp, depth.data(), 0, nullptr, 0, 640, 480), 0);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_sim_take_frame(sim, 0, &stamp, depth.data(), 0, nullptr, 0, 640, 480), 1);  // the frame at t = 0
  EXPECT_EQ(stamp, 0.0);
  EXPECT_EQ(duet_sim_take_frame(sim, 0, &stamp, depth.data(), 0, nullptr, 0, 640, 480), 0);  // none left
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
  duet_sim_score(sim, nullptr, nullptr, nullptr);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
  // Handles: NULL, wrong kind, released.
  duet_runtime_spin_once(nullptr, 1.0);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
  // Wrong kind and released handles: the error reaches their device.
  duet_runtime_spin_once(reinterpret_cast<duet_runtime>(sim), 1.0);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
  duet_sim_step(reinterpret_cast<duet_sim>(rt), duet_twist{0, 0}, 0.05);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
  duet_runtime_release(rt);
  duet_sim_release(sim);
  duet_runtime_push_odometry(rt, 1.0, duet_pose2{0, 0, 0}, duet_twist{0, 0});
  EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
  EXPECT_NE(message().find("not a live duet_runtime"), std::string::npos) << message();
  EXPECT_EQ(duet_sim_get_collisions(sim), 0u);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);
  EXPECT_STREQ(duet_explorer_state_string(static_cast<duet_explorer_state>(42)), "?");
  EXPECT_STREQ(duet_pose_health_string(DUET_POSE_LOST), "lost");
}

}  // namespace capi_runtime_misuse
