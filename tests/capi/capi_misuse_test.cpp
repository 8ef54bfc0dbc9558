// C API misuse: NULL / released / foreign / wrong-type handles, bad buffers and settings, bad
// configuration strings, error callbacks and get-and-clear semantics. None of it may crash
// (this file is also run under AddressSanitizer: -DDUET_SANITIZE=ON).
#include "capi_helpers.hpp"

#include <tbb/info.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

using namespace duet_capi_test;

namespace {

/// Every entry point that takes a cloud, grid or device handle, called with the given handles
/// and otherwise valid arguments. Each call must record exactly one error.
std::vector<std::pair<std::string, std::function<void()>>> all_calls(duet_device d, duet_cloud c,
                                                                     duet_grid g) {
  static float xyz[6] = {0, 0, 0, 1, 1, 1};
  static float nrm[6] = {0, 0, 1, 0, 0, 1};
  static float out_f[64];
  static uint8_t lab[2] = {DUET_LABEL_OBSTACLE, DUET_LABEL_FLOOR};
  static uint32_t lab32[2];
  static int8_t out_i8[64];
  static uint8_t rgb[6] = {};
  static uint16_t depth[4] = {1000, 1000, 1000, 1000};
  static duet_sensor_frame frame;
  duet_sensor_frame_init(&frame);
  frame.depth = depth;
  frame.width = 2;
  frame.height = 2;
  return {
      {"duet_device_retain", [=] { duet_device_retain(d); }},
      {"duet_device_release", [=] { duet_device_release(d); }},
      {"duet_device_get_thread_count", [=] { EXPECT_EQ(duet_device_get_thread_count(d), 0); }},
      {"duet_device_set_error_callback", [=] { duet_device_set_error_callback(d, nullptr, nullptr); }},
      {"duet_cloud_new", [=] { EXPECT_EQ(duet_cloud_new(d), nullptr); }},
      {"duet_grid_new", [=] { EXPECT_EQ(duet_grid_new(d, 0.05f), nullptr); }},
      {"duet_estimate_normals", [=] { duet_estimate_normals(d, xyz, 0, 2, nullptr, out_f, 0, nullptr, 0); }},
      {"duet_euclidean_clusters", [=] {
         size_t n = 7;
         duet_euclidean_clusters(d, xyz, 0, 2, nullptr, lab32, 0, &n);
         EXPECT_EQ(n, 0u);
       }},
      {"duet_segment", [=] { duet_segment(d, xyz, 0, nrm, 0, 2, nullptr, lab, 0); }},
      {"duet_cloud_retain", [=] { duet_cloud_retain(c); }},
      {"duet_cloud_release", [=] { duet_cloud_release(c); }},
      {"duet_cloud_set_points", [=] { duet_cloud_set_points(c, xyz, 0, rgb, 0, 2); }},
      {"duet_cloud_clear", [=] { duet_cloud_clear(c); }},
      {"duet_cloud_get_size", [=] { EXPECT_EQ(duet_cloud_get_size(c), 0u); }},
      {"duet_cloud_has_colors", [=] { EXPECT_EQ(duet_cloud_has_colors(c), 0); }},
      {"duet_cloud_has_normals", [=] { EXPECT_EQ(duet_cloud_has_normals(c), 0); }},
      {"duet_cloud_get_points", [=] {
         const float* p = xyz;
         size_t s = 99;
         duet_cloud_get_points(c, &p, &s);
         EXPECT_EQ(p, nullptr);
         EXPECT_EQ(s, 0u);
       }},
      {"duet_cloud_get_colors", [=] {
         const uint8_t* p = rgb;
         duet_cloud_get_colors(c, &p, nullptr);
         EXPECT_EQ(p, nullptr);
       }},
      {"duet_cloud_get_normals", [=] {
         const float* p = xyz;
         duet_cloud_get_normals(c, &p, nullptr);
         EXPECT_EQ(p, nullptr);
       }},
      {"duet_cloud_get_curvature", [=] {
         const float* p = xyz;
         duet_cloud_get_curvature(c, &p, nullptr);
         EXPECT_EQ(p, nullptr);
       }},
      {"duet_cloud_copy_points", [=] { duet_cloud_copy_points(c, out_f, 0, 0); }},
      {"duet_cloud_copy_colors", [=] { duet_cloud_copy_colors(c, rgb, 0, 0); }},
      {"duet_cloud_copy_normals", [=] { duet_cloud_copy_normals(c, out_f, 0, 0); }},
      {"duet_cloud_copy_curvature", [=] { duet_cloud_copy_curvature(c, out_f, 0, 0); }},
      {"duet_back_project", [=] { duet_back_project(c, &frame, 1, nullptr, nullptr); }},
      {"duet_voxel_filter", [=] { duet_voxel_filter(c, xyz, 0, nullptr, 0, 2, nullptr); }},
      {"duet_cloud_estimate_normals", [=] { duet_cloud_estimate_normals(c, nullptr); }},
      {"duet_grid_retain", [=] { duet_grid_retain(g); }},
      {"duet_grid_release", [=] { duet_grid_release(g); }},
      {"duet_grid_update", [=] { duet_grid_update(g, 0, 0, xyz, 0, lab, 0, 2, nullptr); }},
      {"duet_grid_get_width", [=] { EXPECT_EQ(duet_grid_get_width(g), 0); }},
      {"duet_grid_get_height", [=] { EXPECT_EQ(duet_grid_get_height(g), 0); }},
      {"duet_grid_get_resolution", [=] { EXPECT_EQ(duet_grid_get_resolution(g), 0.0f); }},
      {"duet_grid_get_origin", [=] {
         float x = 5, y = 6;
         duet_grid_get_origin(g, &x, &y);
         EXPECT_EQ(x, 5.0f);
         EXPECT_EQ(y, 6.0f);
       }},
      {"duet_grid_get_known_cells", [=] { EXPECT_EQ(duet_grid_get_known_cells(g), 0u); }},
      {"duet_grid_copy_logodds", [=] { duet_grid_copy_logodds(g, out_f, 0); }},
      {"duet_grid_copy_probabilities", [=] { duet_grid_copy_probabilities(g, out_f, 0); }},
      {"duet_grid_copy_ros", [=] { duet_grid_copy_ros(g, out_i8, 0, 0.65f, 0.196f); }},
      {"duet_grid_scan_match", [=] {
         duet_scan_match_result r{};
         r.candidates = 9;
         duet_grid_scan_match(g, out_f, 0, 0, duet_pose2{0, 0, 0}, nullptr, &r);
         EXPECT_EQ(r.candidates, 9u);
       }},
  };
}

bool uses(const std::string& name, const char* prefix) { return name.rfind(prefix, 0) == 0; }

/// Which handle a call validates first: "device", "cloud" or "grid".
std::string handle_of(const std::string& name) {
  if (uses(name, "duet_cloud_new") || uses(name, "duet_grid_new")) return "device";
  if (uses(name, "duet_cloud") || name == "duet_back_project" || name == "duet_voxel_filter") return "cloud";
  if (uses(name, "duet_grid")) return "grid";
  return "device";
}

}  // namespace

// ---- NULL handles ---------------------------------------------------------------------------

TEST(CapiMisuse, NullHandlesEverywhere) {
  (void)duet_device_get_error(nullptr);
  duet_device live = duet_device_new("threads=1");
  ASSERT_NE(live, nullptr);
  duet_cloud live_cloud = duet_cloud_new(live);
  duet_grid live_grid = duet_grid_new(live, 0.05f);
  for (auto& [name, call] : all_calls(nullptr, nullptr, nullptr)) {
    if (name == "duet_device_set_error_callback") continue;  // NULL = the no-device callback
    SCOPED_TRACE(name);
    call();
    EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
    const std::string msg = duet_device_get_error_message(nullptr);
    EXPECT_NE(msg.find(name), std::string::npos) << msg;
    EXPECT_NE(msg.find("NULL"), std::string::npos) << msg;
    EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);  // cleared
    EXPECT_EQ(duet_device_get_error(live), DUET_ERROR_NONE);     // nothing leaks to devices
  }
  duet_grid_release(live_grid);
  duet_cloud_release(live_cloud);
  duet_device_release(live);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);
}

// ---- released (dead) handles ------------------------------------------------------------------

TEST(CapiMisuse, ReleasedHandlesAreDetectedWithoutCrashing) {
  (void)duet_device_get_error(nullptr);
  duet_device d = duet_device_new("threads=2");
  ASSERT_NE(d, nullptr);
  duet_cloud c = duet_cloud_new(d);
  duet_grid g = duet_grid_new(d, 0.1f);
  ASSERT_NE(c, nullptr);
  ASSERT_NE(g, nullptr);
  duet_grid_release(g);
  duet_cloud_release(c);
  duet_device_release(d);
  ASSERT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);

  for (auto& [name, call] : all_calls(d, c, g)) {
    SCOPED_TRACE(name);
    call();
    EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_OPERATION);
    const std::string msg = duet_device_get_error_message(nullptr);
    EXPECT_NE(msg.find("not a live duet_" + handle_of(name)), std::string::npos) << msg;
  }
  // A dead device's own error query reports the misuse directly.
  EXPECT_EQ(duet_device_get_error(d), DUET_ERROR_INVALID_OPERATION);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);
  EXPECT_NE(std::string(duet_device_get_error_message(d)).find("not a live duet_device"),
            std::string::npos);
}

TEST(CapiMisuse, ForeignPointersAreRejectedWithoutDereferencing) {
  (void)duet_device_get_error(nullptr);
  // Not handles duet ever made: a stack address, an odd value, all bits set.
  int local = 0;
  const std::uintptr_t bogus[] = {reinterpret_cast<std::uintptr_t>(&local), 0x1,
                                  0x1234, ~std::uintptr_t{0}};
  for (std::uintptr_t b : bogus) {
    duet_cloud_get_size(reinterpret_cast<duet_cloud>(b));
    EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_OPERATION);
    duet_grid_update(reinterpret_cast<duet_grid>(b), 0, 0, nullptr, 0, nullptr, 0, 0, nullptr);
    EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_OPERATION);
    EXPECT_EQ(duet_cloud_new(reinterpret_cast<duet_device>(b)), nullptr);
    EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_OPERATION);
  }
}

TEST(CapiMisuse, WrongHandleTypeIsAnInvalidOperation) {
  (void)duet_device_get_error(nullptr);
  duet_device d = duet_device_new(nullptr);
  duet_cloud c = duet_cloud_new(d);
  duet_grid g = duet_grid_new(d, 0.05f);

  // The errors reach the device the bad handle belongs to (issue 20); the no-device slot stays clean.
  duet_cloud_get_size(reinterpret_cast<duet_cloud>(g));
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);
  EXPECT_EQ(duet_device_get_error(d), DUET_ERROR_INVALID_OPERATION);
  std::string msg = duet_device_get_error_message(d);
  EXPECT_NE(msg.find("is a duet_grid, expected a duet_cloud"), std::string::npos) << msg;

  EXPECT_EQ(duet_grid_get_width(reinterpret_cast<duet_grid>(c)), 0);
  EXPECT_EQ(duet_device_get_error(d), DUET_ERROR_INVALID_OPERATION);

  EXPECT_EQ(duet_cloud_new(reinterpret_cast<duet_device>(c)), nullptr);
  EXPECT_EQ(duet_device_get_error(d), DUET_ERROR_INVALID_OPERATION);
  msg = duet_device_get_error_message(d);
  EXPECT_NE(msg.find("is a duet_cloud, expected a duet_device"), std::string::npos) << msg;

  // Releasing through the wrong type must not drop a reference.
  duet_cloud_release(reinterpret_cast<duet_cloud>(g));
  EXPECT_EQ(duet_device_get_error(d), DUET_ERROR_INVALID_OPERATION);
  EXPECT_EQ(duet_grid_get_width(g), 0);
  EXPECT_EQ(duet_device_get_error(d), DUET_ERROR_NONE);

  duet_grid_release(g);
  duet_cloud_release(c);
  duet_device_release(d);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);
}

TEST(CapiMisuse, HandlesAreNeverRecycled) {
  (void)duet_device_get_error(nullptr);
  duet_device d = duet_device_new(nullptr);
  duet_cloud first = duet_cloud_new(d);
  duet_cloud_release(first);
  for (int i = 0; i < 100; ++i) {
    duet_cloud c = duet_cloud_new(d);
    EXPECT_NE(c, first);
    duet_cloud_release(c);
  }
  duet_cloud_get_size(first);
  EXPECT_EQ(duet_device_get_error(d), DUET_ERROR_INVALID_OPERATION);  // a released handle's device hears of it
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);
  duet_device_release(d);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);
}

// ---- reference counting ---------------------------------------------------------------------

TEST(CapiMisuse, RetainReleaseCounts) {
  (void)duet_device_get_error(nullptr);
  duet_device d = duet_device_new(nullptr);
  duet_cloud c = duet_cloud_new(d);
  duet_cloud_retain(c);
  duet_cloud_release(c);
  EXPECT_EQ(duet_cloud_get_size(c), 0u);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);
  duet_cloud_release(c);
  duet_cloud_get_size(c);
  EXPECT_EQ(duet_device_get_error(d), DUET_ERROR_INVALID_OPERATION);
  duet_cloud_release(c);  // double release
  EXPECT_EQ(duet_device_get_error(d), DUET_ERROR_INVALID_OPERATION);
  duet_device_release(d);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);
}

TEST(CapiMisuse, ObjectsKeepTheirDeviceAlive) {
  (void)duet_device_get_error(nullptr);
  duet_device d = duet_device_new("threads=1");
  duet_cloud c = duet_cloud_new(d);
  duet_grid g = duet_grid_new(d, 0.05f);
  duet_device_release(d);  // the user's reference is gone; c and g still hold one each
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);

  const float xyz[3] = {0.1f, 0.2f, 0.3f};
  duet_voxel_filter(c, xyz, 0, nullptr, 0, 1, nullptr);
  EXPECT_EQ(duet_cloud_get_size(c), 1u);
  duet_voxel_filter_settings vf;
  duet_voxel_filter_settings_init(&vf);
  vf.leaf_size_m = -1.0f;
  duet_voxel_filter(c, xyz, 0, nullptr, 0, 1, &vf);
  EXPECT_EQ(duet_device_get_error(d), DUET_ERROR_INVALID_ARGUMENT);  // still reachable

  duet_cloud_release(c);
  EXPECT_EQ(duet_device_get_thread_count(d), 1);  // g still holds it
  duet_grid_release(g);
  EXPECT_EQ(duet_device_get_thread_count(d), 0);  // now it is gone
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_OPERATION);
}

// ---- configuration --------------------------------------------------------------------------

TEST(CapiDevice, GoodConfigurations) {
  (void)duet_device_get_error(nullptr);
  const char* good[] = {nullptr, "", "threads=1", "threads=2,verbose=0", " threads = 3 , verbose=1 ",
                        "verbose=0", "threads=2,", ",threads=2"};
  const int cores = tbb::info::default_concurrency();  // larger requests are clamped to it
  const int threads[] = {-1, -1, 1, std::min(2, cores), std::min(3, cores), -1, std::min(2, cores),
                         std::min(2, cores)};
  for (std::size_t i = 0; i < std::size(good); ++i) {
    SCOPED_TRACE(good[i] ? good[i] : "NULL");
    duet_device d = duet_device_new(good[i]);
    ASSERT_NE(d, nullptr) << duet_device_get_error_message(nullptr);
    if (threads[i] > 0) {
      EXPECT_EQ(duet_device_get_thread_count(d), threads[i]);
    } else {
      EXPECT_GE(duet_device_get_thread_count(d), 1);
    }
    duet_device_release(d);
    EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);
  }
  // threads=0 means all cores: the same as the default.
  duet_device all = duet_device_new("threads=0");
  duet_device dflt = duet_device_new(nullptr);
  EXPECT_EQ(duet_device_get_thread_count(all), duet_device_get_thread_count(dflt));
  EXPECT_EQ(duet_device_get_thread_count(all), cores);
  duet_device many = duet_device_new("threads=1024");
  EXPECT_EQ(duet_device_get_thread_count(many), cores);
  duet_device_release(many);
  duet_device_release(all);
  duet_device_release(dflt);
}

TEST(CapiDevice, BadConfigurationsReturnNullWithAMessage) {
  (void)duet_device_get_error(nullptr);
  const std::pair<const char*, const char*> bad[] = {
      {"thread=2", "unknown configuration key 'thread'"},
      {"threads=2,colour=1", "unknown configuration key 'colour'"},
      {"threads=-1", "'threads'"},
      {"threads=abc", "bad value 'abc' for key 'threads'"},
      {"threads=2x", "bad value '2x'"},
      {"threads=", "bad value ''"},
      {"threads=99999999999999999999", "'threads'"},
      {"threads=1025", "[0, 1024]"},
      {"verbose=2", "'verbose'"},
      {"threads", "not key=value"},
      {"threads=1,threads=2", "given twice"},
      {"=3", "unknown configuration key ''"},
  };
  for (const auto& [config, expected] : bad) {
    SCOPED_TRACE(config);
    EXPECT_EQ(duet_device_new(config), nullptr);
    EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
    const std::string msg = duet_device_get_error_message(nullptr);
    EXPECT_NE(msg.find("duet_device_new"), std::string::npos) << msg;
    EXPECT_NE(msg.find(expected), std::string::npos) << msg;
  }
}

// ---- error state: get-and-clear, messages, callbacks ------------------------------------------

TEST_F(DeviceTest, GetErrorReturnsTheFirstErrorAndClears) {
  EXPECT_EQ(take(), DUET_ERROR_NONE);
  EXPECT_STREQ(duet_device_get_error_message(device_), "");
  duet_cloud c = duet_cloud_new(device_);
  duet_cloud_copy_points(c, nullptr, 0, 5);  // INVALID_ARGUMENT (count 0 expected)
  duet_cloud_set_points(c, nullptr, 0, nullptr, 0, 1);  // INVALID_ARGUMENT
  duet_cloud_copy_normals(c, nullptr, 0, 0);            // fine: empty
  duet_voxel_filter_settings vf;
  duet_voxel_filter_settings_init(&vf);
  const float huge[3] = {3e38f, 3e38f, 3e38f};
  const float tiny[3] = {-3e38f, -3e38f, -3e38f};
  float both[6];
  std::memcpy(both, huge, sizeof huge);
  std::memcpy(both + 3, tiny, sizeof tiny);
  duet_voxel_filter(c, both, 0, nullptr, 0, 2, &vf);  // OUT_OF_RANGE: voxel index overflow
  // The code and the message are the first error's (issue 20: they were the first code with
  // the last message).
  const std::string first = message();
  EXPECT_NE(first.find("duet_cloud_copy_points"), std::string::npos) << first;
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);  // the first one
  EXPECT_EQ(message(), first);                     // still the message of the error just taken
  EXPECT_EQ(take(), DUET_ERROR_NONE);              // cleared
  EXPECT_EQ(message(), first);                     // the message is not cleared
  duet_voxel_filter(c, both, 0, nullptr, 0, 2, &vf);
  EXPECT_NE(message().find("duet_voxel_filter"), std::string::npos) << message();  // the next first error
  EXPECT_EQ(take(), DUET_ERROR_OUT_OF_RANGE);
  duet_cloud_release(c);
}

TEST_F(DeviceTest, ErrorCallbackFiresWithCodeMessageAndUserPointer) {
  struct Seen {
    int calls = 0;
    duet_error code = DUET_ERROR_NONE;
    std::string message;
  } seen;
  duet_device_set_error_callback(
      device_,
      [](void* user, duet_error code, const char* msg) {
        auto* s = static_cast<Seen*>(user);
        ++s->calls;
        s->code = code;
        s->message = msg;
      },
      &seen);
  duet_grid g = duet_grid_new(device_, 0.05f);
  std::vector<float> out(3);
  duet_grid_copy_logodds(g, out.data(), out.size());
  EXPECT_EQ(seen.calls, 1);
  EXPECT_EQ(seen.code, DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(seen.message.find("duet_grid_copy_logodds"), std::string::npos) << seen.message;
  EXPECT_NE(seen.message.find("expected 0"), std::string::npos) << seen.message;
  EXPECT_NE(seen.message.find("given 3"), std::string::npos) << seen.message;
  EXPECT_EQ(message(), seen.message);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);  // the callback does not consume the code

  // Every error fires, even while one is pending.
  duet_grid_copy_logodds(g, out.data(), 1);
  duet_grid_copy_logodds(g, out.data(), 2);
  EXPECT_EQ(seen.calls, 3);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);

  // Removing the callback.
  duet_device_set_error_callback(device_, nullptr, &seen);
  duet_grid_copy_logodds(g, out.data(), 1);
  EXPECT_EQ(seen.calls, 3);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_grid_release(g);
}

TEST_F(DeviceTest, CallbackMayCallBackIntoDuetAndAThrowingCallbackIsContained) {
  static duet_device dev;
  dev = device_;
  duet_device_set_error_callback(
      device_,
      [](void*, duet_error, const char*) {
        // Re-entrant use of the same device from inside the callback must not deadlock.
        (void)duet_device_get_error_message(dev);
        (void)duet_device_get_thread_count(dev);
      },
      nullptr);
  duet_segment(device_, nullptr, 0, nullptr, 0, 3, nullptr, nullptr, 0);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);

  duet_device_set_error_callback(
      device_, [](void*, duet_error, const char*) { throw std::runtime_error("from a callback"); },
      nullptr);
  duet_segment(device_, nullptr, 0, nullptr, 0, 3, nullptr, nullptr, 0);  // must not propagate
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_device_set_error_callback(device_, nullptr, nullptr);
}

TEST(CapiDevice, NoDeviceCallbackAndThreadLocalSlot) {
  (void)duet_device_get_error(nullptr);
  static std::atomic<int> calls;
  static duet_error last_code;
  calls = 0;
  last_code = DUET_ERROR_NONE;
  duet_device_set_error_callback(
      nullptr, [](void*, duet_error code, const char*) {
        ++calls;
        last_code = code;
      },
      nullptr);
  EXPECT_EQ(duet_device_new("bogus=1"), nullptr);
  EXPECT_EQ(calls.load(), 1);
  EXPECT_EQ(last_code, DUET_ERROR_INVALID_ARGUMENT);
  duet_device_set_error_callback(nullptr, nullptr, nullptr);
  EXPECT_EQ(duet_device_new("bogus=1"), nullptr);
  EXPECT_EQ(calls.load(), 1);

  // The no-device slot is per thread: another thread sees nothing pending.
  duet_error other = DUET_ERROR_UNKNOWN;
  std::thread t([&] { other = duet_device_get_error(nullptr); });
  t.join();
  EXPECT_EQ(other, DUET_ERROR_NONE);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
}

// A callback whose own duet call fails is not called again for that error (found by
// fuzz_capi: it recursed until the stack overflowed); the inner error is still recorded.
TEST(CapiDevice, ACallbackIsNotReenteredByItsOwnFailingCall) {
  (void)duet_device_get_error(nullptr);
  static std::atomic<int> calls;
  calls = 0;
  duet_device_set_error_callback(
      nullptr, [](void*, duet_error, const char*) {
        ++calls;
        (void)duet_device_get_thread_count(nullptr);  // fails: NULL device
      },
      nullptr);
  EXPECT_EQ(duet_device_get_thread_count(nullptr), 0);
  EXPECT_EQ(calls.load(), 1);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_device_get_thread_count(nullptr), 0);  // the guard was released
  EXPECT_EQ(calls.load(), 2);
  duet_device_set_error_callback(nullptr, nullptr, nullptr);
  (void)duet_device_get_error(nullptr);
}

TEST(CapiDevice, VersionAndErrorStrings) {
  EXPECT_EQ(duet_get_version(), DUET_VERSION);
  EXPECT_STREQ(duet_get_version_string(), DUET_VERSION_STRING);
  EXPECT_STREQ(duet_error_string(DUET_ERROR_NONE), "DUET_ERROR_NONE");
  EXPECT_STREQ(duet_error_string(DUET_ERROR_OUT_OF_MEMORY), "DUET_ERROR_OUT_OF_MEMORY");
  // Not an enumerator. 15 is the largest value the C++ enum can hold (its range is that of a
  // 4-bit field): a larger one would be undefined behaviour on the C++ (test) side, where UBSan
  // flags the load; C code may pass any int, which the library reads as int (enum_value()).
  duet_error bogus;
  const int fifteen = 15;
  std::memcpy(&bogus, &fifteen, sizeof bogus);
  EXPECT_STREQ(duet_error_string(bogus), "DUET_ERROR_?");
}

// ---- buffers --------------------------------------------------------------------------------

TEST_F(DeviceTest, PointBufferValidation) {
  duet_cloud c = duet_cloud_new(device_);
  alignas(16) float xyz[32] = {};
  struct Case {
    const float* ptr;
    size_t stride;
    size_t count;
    const char* expected;
  };
  const Case cases[] = {
      {nullptr, 0, 4, "xyz is NULL but count is 4"},
      {xyz, 8, 2, "xyz stride 8 bytes is smaller than its element (12 bytes)"},
      {xyz, 4, 2, "smaller than its element"},
      {xyz, 14, 2, "not a multiple of 4"},
      {reinterpret_cast<const float*>(reinterpret_cast<const char*>(xyz) + 2), 12, 2,
       "not 4-byte aligned"},
      {xyz, (SIZE_MAX / 8) & ~size_t{3}, 16, "exceed the address space"},
  };
  for (const Case& k : cases) {
    SCOPED_TRACE(k.expected);
    duet_voxel_filter(c, k.ptr, k.stride, nullptr, 0, k.count, nullptr);
    EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(message().find(k.expected), std::string::npos) << message();
    std::vector<uint32_t> labels(k.count);
    duet_euclidean_clusters(device_, k.ptr, k.stride, k.count, nullptr, labels.data(), 0, nullptr);
    EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
    std::vector<float> normals(3 * k.count);
    duet_estimate_normals(device_, k.ptr, k.stride, k.count, nullptr, normals.data(), 0, nullptr, 0);
    EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  }
  // count 0 with NULL pointers is fine everywhere.
  duet_voxel_filter(c, nullptr, 0, nullptr, 0, 0, nullptr);
  duet_euclidean_clusters(device_, nullptr, 0, 0, nullptr, nullptr, 0, nullptr);
  duet_estimate_normals(device_, nullptr, 0, 0, nullptr, nullptr, 0, nullptr, 0);
  duet_segment(device_, nullptr, 0, nullptr, 0, 0, nullptr, nullptr, 0);
  duet_cloud_set_points(c, nullptr, 0, nullptr, 0, 0);
  duet_cloud_estimate_normals(c, nullptr);
  duet_back_project(c, nullptr, 0, nullptr, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
  EXPECT_EQ(duet_cloud_get_size(c), 0u);
  duet_cloud_release(c);
}

TEST_F(DeviceTest, OutputBufferValidation) {
  const std::vector<float> xyz = random_points(50, 1, 1.0f);
  std::vector<float> normals(150);
  std::vector<uint32_t> labels(50);
  std::vector<uint8_t> seg(50);
  duet_estimate_normals(device_, xyz.data(), 0, 50, nullptr, nullptr, 0, nullptr, 0);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("normals is NULL but count is 50"), std::string::npos) << message();
  duet_estimate_normals(device_, xyz.data(), 0, 50, nullptr, normals.data(), 8, nullptr, 0);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_euclidean_clusters(device_, xyz.data(), 0, 50, nullptr, nullptr, 0, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_euclidean_clusters(device_, xyz.data(), 0, 50, nullptr, labels.data(), 2, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_segment(device_, xyz.data(), 0, normals.data(), 0, 50, nullptr, nullptr, 0);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_segment(device_, xyz.data(), 0, nullptr, 0, 50, nullptr, seg.data(), 0);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("normals is NULL"), std::string::npos) << message();
  duet_segment(device_, xyz.data(), 0, normals.data(), 6, 50, nullptr, seg.data(), 0);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
}

TEST_F(DeviceTest, CloudCopyAndBorrowValidation) {
  duet_cloud c = duet_cloud_new(device_);
  const std::vector<float> xyz = random_points(10, 2, 1.0f);
  duet_cloud_set_points(c, xyz.data(), 0, nullptr, 0, 10);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  std::vector<float> out(30);
  duet_cloud_copy_points(c, out.data(), 0, 9);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("expected 10 elements, given 9"), std::string::npos) << message();
  duet_cloud_copy_points(c, out.data(), 0, 10);
  EXPECT_EQ(take(), DUET_ERROR_NONE);
  EXPECT_EQ(out, xyz);
  duet_cloud_copy_normals(c, out.data(), 0, 10);  // no normals yet
  EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
  EXPECT_NE(message().find("has no normals"), std::string::npos) << message();
  std::vector<uint8_t> rgb(30);
  duet_cloud_copy_colors(c, rgb.data(), 0, 10);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
  duet_cloud_get_points(c, nullptr, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  const uint8_t* colors = rgb.data();
  size_t stride = 7;
  duet_cloud_get_colors(c, &colors, &stride);  // absent attribute: NULL, no error
  EXPECT_EQ(take(), DUET_ERROR_NONE);
  EXPECT_EQ(colors, nullptr);
  EXPECT_EQ(stride, 3u);
  duet_cloud_release(c);
}

TEST_F(DeviceTest, GridCopyRequiresTheExactSize) {
  duet_grid g = duet_grid_new(device_, 0.1f);
  const float xyz[6] = {1.0f, 0.0f, 0.5f, 0.5f, 0.5f, 0.0f};
  const uint8_t labels[2] = {DUET_LABEL_OBSTACLE, DUET_LABEL_FLOOR};
  duet_grid_update(g, 0.0f, 0.0f, xyz, 0, labels, 0, 2, nullptr);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  const size_t n = static_cast<size_t>(duet_grid_get_width(g)) * duet_grid_get_height(g);
  ASSERT_GT(n, 0u);
  std::vector<float> f(n + 1);
  std::vector<int8_t> i8(n + 1);
  for (size_t wrong : {size_t{0}, n - 1, n + 1}) {
    duet_grid_copy_logodds(g, f.data(), wrong);
    EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(message().find("expected " + std::to_string(n) + " elements, given " + std::to_string(wrong)),
              std::string::npos)
        << message();
    duet_grid_copy_probabilities(g, f.data(), wrong);
    EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
    duet_grid_copy_ros(g, i8.data(), wrong, 0.65f, 0.196f);
    EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  }
  duet_grid_copy_logodds(g, nullptr, n);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_grid_copy_ros(g, i8.data(), n, 0.2f, 0.6f);  // free > occupied
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_grid_copy_ros(g, i8.data(), n, NAN, 0.1f);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_grid_copy_ros(g, i8.data(), n, 0.65f, 0.196f);
  duet_grid_copy_probabilities(g, f.data(), n);
  duet_grid_copy_logodds(g, f.data(), n);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
  duet_grid_release(g);
}

TEST_F(DeviceTest, GridArgumentValidation) {
  EXPECT_EQ(duet_grid_new(device_, 0.0f), nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_grid_new(device_, -0.05f), nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_grid_new(device_, NAN), nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_grid_new(device_, INFINITY), nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  // A huge resolution overflowed the grid's origin and crashed the next update: refused now
  // (cells of 1 mm to 100 m).
  EXPECT_EQ(duet_grid_new(device_, 3e38f), nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("resolution must be in"), std::string::npos) << message();
  EXPECT_EQ(duet_grid_new(device_, 1e-9f), nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  {
    // A sensor or points ~1e17 m from the origin: an error or dropped points, never a 0-wide grid
    // that the next update reads out of bounds.
    duet_grid far = duet_grid_new(device_, 0.05f);
    const float pts[6] = {1e17f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f};
    const uint8_t lab[2] = {DUET_LABEL_OBSTACLE, DUET_LABEL_OBSTACLE};
    duet_grid_update(far, 1e17f, 0.0f, pts, 0, lab, 0, 2, nullptr);
    EXPECT_EQ(take(), DUET_ERROR_OUT_OF_RANGE);
    EXPECT_NE(message().find("limit"), std::string::npos) << message();
    duet_grid_update(far, 0.0f, 0.0f, pts, 0, lab, 0, 2, nullptr);  // the far point dropped, the near one kept
    EXPECT_EQ(take(), DUET_ERROR_NONE);
    EXPECT_GT(duet_grid_get_width(far), 0);
    EXPECT_GE(duet_grid_get_known_cells(far), 1u);
    duet_grid_update(far, 0.0f, 0.0f, pts, 0, lab, 0, 2, nullptr);
    EXPECT_EQ(take(), DUET_ERROR_NONE);
    duet_grid_release(far);
  }

  duet_grid g = duet_grid_new(device_, 0.05f);
  const float xyz[6] = {1.0f, 0.0f, 0.5f, 0.5f, 0.5f, 0.0f};
  uint8_t labels[2] = {DUET_LABEL_OBSTACLE, 7};
  duet_grid_update(g, 0.0f, 0.0f, xyz, 0, labels, 0, 2, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("labels[1] is 7"), std::string::npos) << message();
  labels[1] = DUET_LABEL_FLOOR;
  duet_grid_update(g, NAN, 0.0f, xyz, 0, labels, 0, 2, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_grid_update(g, 0.0f, 0.0f, xyz, 0, nullptr, 0, 2, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_grid_update_settings gs;
  duet_grid_update_settings_init(&gs);
  gs.clear_along_rays = 2;
  duet_grid_update(g, 0.0f, 0.0f, xyz, 0, labels, 0, 2, &gs);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("clear_along_rays"), std::string::npos) << message();
  // Scan matching: NULL out, a NULL buffer with points, a misaligned stride, a non-finite prior,
  // invalid settings (named) - errors that leave *out unchanged; NULL grid.
  duet_scan_match_result res{};
  res.candidates = 77;
  const float pts[4] = {1.0f, 0.0f, 0.0f, 1.0f};
  duet_grid_scan_match(g, pts, 0, 2, duet_pose2{0, 0, 0}, nullptr, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_grid_scan_match(g, nullptr, 0, 2, duet_pose2{0, 0, 0}, nullptr, &res);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_grid_scan_match(g, pts, 3, 2, duet_pose2{0, 0, 0}, nullptr, &res);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_grid_scan_match(g, pts, 0, 2, duet_pose2{NAN, 0, 0}, nullptr, &res);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("prior"), std::string::npos) << message();
  duet_scan_match_settings ss;
  duet_scan_match_settings_init(&ss);
  ss.sigma_m = -1.0f;
  duet_grid_scan_match(g, pts, 0, 2, duet_pose2{0, 0, 0}, &ss, &res);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("sigma_m"), std::string::npos) << message();
  EXPECT_EQ(res.candidates, 77u);
  // On an empty grid (0 x 0) there is nothing to match: the prior, NOT_CONFIDENT or TOO_FEW_POINTS.
  duet_grid_scan_match(g, pts, 0, 2, duet_pose2{0.5f, 0, 0}, nullptr, &res);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
  EXPECT_EQ(res.status, DUET_SCAN_MATCH_TOO_FEW_POINTS);
  EXPECT_EQ(res.pose.x, 0.5f);
  // None of that touched the grid.
  EXPECT_EQ(duet_grid_get_width(g), 0);
  EXPECT_EQ(duet_grid_get_known_cells(g), 0u);
  float x = 1, y = 1;
  duet_grid_get_origin(g, nullptr, &y);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_grid_get_origin(g, &x, &y);
  EXPECT_EQ(take(), DUET_ERROR_NONE);
  duet_grid_release(g);
}

TEST_F(DeviceTest, InvalidSettingsAreRejectedAndLeaveTheOutputUnchanged) {
  duet_cloud c = duet_cloud_new(device_);
  const std::vector<float> xyz = random_points(100, 3, 1.0f);
  duet_voxel_filter(c, xyz.data(), 0, nullptr, 0, 100, nullptr);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  const size_t before = duet_cloud_get_size(c);
  ASSERT_GT(before, 0u);

  duet_voxel_filter_settings vf;
  duet_voxel_filter_settings_init(&vf);
  for (float leaf : {0.0f, -1.0f, NAN, INFINITY}) {
    vf.leaf_size_m = leaf;
    duet_voxel_filter(c, xyz.data(), 0, nullptr, 0, 100, &vf);
    EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT) << leaf;
    EXPECT_EQ(duet_cloud_get_size(c), before);
  }
  duet_normal_settings ns;
  duet_normal_settings_init(&ns);
  ns.k = 2;
  duet_cloud_estimate_normals(c, &ns);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_cloud_has_normals(c), 0);

  duet_clustering_settings cs;
  duet_clustering_settings_init(&cs);
  cs.tolerance_m = 0.0f;
  std::vector<uint32_t> labels(100, 123);
  size_t n = 99;
  duet_euclidean_clusters(device_, xyz.data(), 0, 100, &cs, labels.data(), 0, &n);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(n, 0u);
  EXPECT_EQ(labels[0], 123u);  // output untouched

  duet_back_projection_settings bp;
  duet_back_projection_settings_init(&bp);
  bp.pixel_step = 0;
  duet_back_project(c, nullptr, 0, &bp, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_cloud_get_size(c), before);
  duet_cloud_release(c);
}

TEST_F(DeviceTest, SensorFrameValidation) {
  duet_cloud c = duet_cloud_new(device_);
  std::vector<uint16_t> depth(16 * 12, 1500);
  std::vector<uint8_t> rgb(16 * 12 * 3, 200);
  auto good = [&] {
    duet_sensor_frame f;
    duet_sensor_frame_init(&f);
    f.depth = depth.data();
    f.width = 16;
    f.height = 12;
    f.fx = f.fy = 20.0f;
    f.cx = 7.5f;
    f.cy = 5.5f;
    return f;
  };
  duet_sensor_frame f = good();
  duet_back_project(c, &f, 1, nullptr, nullptr);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  const size_t before = duet_cloud_get_size(c);
  EXPECT_EQ(before, 16u * 12u);

  struct Case {
    std::function<void(duet_sensor_frame&)> spoil;
    const char* expected;
  };
  const Case cases[] = {
      {[](duet_sensor_frame& x) { x.depth = nullptr; }, "frames[0].depth is NULL"},
      {[](duet_sensor_frame& x) { x.width = 0; }, "width x height"},
      {[](duet_sensor_frame& x) { x.height = -3; }, "width x height"},
      {[](duet_sensor_frame& x) {  // what C code can do; a static_cast would be UB in C++
         const int nine = 9;
         std::memcpy(&x.depth_format, &nine, sizeof nine);
       },
       "depth_format"},
      {[](duet_sensor_frame& x) { x.depth_row_stride = 30; }, "depth_row_stride"},
      {[](duet_sensor_frame& x) { x.depth_row_stride = 33; }, "aligned"},
      {[](duet_sensor_frame& x) { x.depth_units_per_m = 0.0f; }, "depth_units_per_m"},
      {[](duet_sensor_frame& x) { x.fx = 0.0f; }, "fx/fy"},
      {[](duet_sensor_frame& x) { x.cy = NAN; }, "cy"},
      {[&](duet_sensor_frame& x) { x.color = rgb.data(); x.color_channels = 2; }, "color_channels"},
      {[&](duet_sensor_frame& x) { x.color = rgb.data(); x.color_bgr = 3; }, "color_bgr"},
      {[&](duet_sensor_frame& x) { x.color = rgb.data(); x.color_row_stride = 47; }, "color_row_stride"},
      {[](duet_sensor_frame& x) { x.T_robot_camera[0] = 2.0f; }, "orthonormal"},
      {[](duet_sensor_frame& x) { x.T_robot_camera[0] = -1.0f; }, "orthonormal"},  // reflection
      {[](duet_sensor_frame& x) { x.T_robot_camera[3] = 0.5f; }, "last row"},
      {[](duet_sensor_frame& x) { x.T_robot_camera[12] = NAN; }, "not finite"},
  };
  for (const Case& k : cases) {
    SCOPED_TRACE(k.expected);
    duet_sensor_frame frames[2] = {good(), good()};
    k.spoil(frames[1]);
    duet_back_project(c, frames, 2, nullptr, nullptr);
    EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
    std::string expected = k.expected;
    if (expected.rfind("frames[0]", 0) == 0) expected.replace(7, 1, "1");
    EXPECT_NE(message().find(expected), std::string::npos) << message();
    EXPECT_EQ(duet_cloud_get_size(c), before);  // unchanged
  }
  duet_back_project(c, nullptr, 2, nullptr, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_cloud_release(c);
}

// ---- concurrency ----------------------------------------------------------------------------

TEST_F(DeviceTest, ConcurrentUseAndReleaseNeverCrash) {
  const std::vector<float> xyz = random_points(2000, 4, 1.0f);
  duet_cloud shared = duet_cloud_new(device_);
  std::atomic<bool> stop{false};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (int i = 0; i < 40; ++i) {
        if (t % 2 == 0) {
          duet_voxel_filter(shared, xyz.data(), 0, nullptr, 0, xyz.size() / 3, nullptr);
        } else {
          const size_t n = duet_cloud_get_size(shared);
          std::vector<float> out(3 * n);
          duet_cloud_copy_points(shared, out.data(), 0, n);  // may race with a resize: size error ok
        }
        // Short-lived objects created and released concurrently.
        duet_grid g = duet_grid_new(device_, 0.05f);
        duet_grid_release(g);
      }
    });
  }
  // One thread releases a cloud the others keep using: they must get INVALID_OPERATION.
  duet_cloud doomed = duet_cloud_new(device_);
  std::thread user([&] {
    while (!stop.load()) (void)duet_cloud_get_size(doomed);
  });
  duet_cloud_release(doomed);
  for (auto& t : threads) t.join();
  stop = true;
  user.join();
  (void)take();  // size races of the copy threads are allowed
  duet_cloud_release(shared);
}
