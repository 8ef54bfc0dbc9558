// Misuse of the exploration planner through the C API: NULL, released and wrong-kind handles,
// a planner that outlives its device's handle, calls before set_grid, NULL buffers and wrong
// counts give the documented error codes without crashing (also run under AddressSanitizer).
#include "capi_planner_util.hpp"

using namespace duet_capi_test;

// The tests sit in the shared parts' namespace: a using-directive for it at file scope would
// reach the next file of a unity batch.
namespace duet_capi_planner_test {

/// Every planner entry point with otherwise valid arguments; `needs_grid` marks those that fail
/// with INVALID_OPERATION before a grid is set.
struct Call {
  std::string name;
  bool needs_grid;
  std::function<void(duet_planner)> call;
};

std::vector<Call> planner_calls(duet_grid grid) {
  static std::vector<float> cells(100, -2.0f);
  static float out_f[100];
  static std::uint8_t out_u8[100];
  static duet_ray_observation rays[60];
  static float path_xy[8] = {1.0f, 1.0f, 2.0f, 2.0f};
  static duet_sensor_sector sensors[2];
  duet_paper_dual_sensors(sensors, 30);
  return {
      {"duet_planner_retain", false, [](duet_planner p) { duet_planner_retain(p); }},
      {"duet_planner_release", false, [](duet_planner p) { duet_planner_release(p); }},
      {"duet_planner_set_sensors", false, [](duet_planner p) { duet_planner_set_sensors(p, sensors, 2); }},
      {"duet_planner_get_sensors", false, [](duet_planner p) { EXPECT_EQ(duet_planner_get_sensors(p, nullptr, 0), 0u); }},
      {"duet_planner_get_ray_count", false, [](duet_planner p) { EXPECT_EQ(duet_planner_get_ray_count(p), 0u); }},
      {"duet_planner_set_grid", false,
       [](duet_planner p) { duet_planner_set_grid(p, cells.data(), 0, 10, 10, 0.1f, 0, 0, nullptr, nullptr); }},
      {"duet_planner_set_grid_from", false, [grid](duet_planner p) { duet_planner_set_grid_from(p, grid, nullptr, nullptr); }},
      {"duet_planner_get_grid_size", false,
       [](duet_planner p) {
         int w = 5, h = 5;
         duet_planner_get_grid_size(p, &w, &h);
         EXPECT_EQ(w, 0);
         EXPECT_EQ(h, 0);
       }},
      {"duet_planner_copy_clearance", true, [](duet_planner p) { duet_planner_copy_clearance(p, out_f, 100); }},
      {"duet_planner_copy_traversable", true, [](duet_planner p) { duet_planner_copy_traversable(p, out_u8, 100); }},
      {"duet_planner_copy_frontier_mask", true, [](duet_planner p) { duet_planner_copy_frontier_mask(p, out_u8, 100); }},
      {"duet_planner_observe", true,
       [](duet_planner p) {
         const duet_pose2 pose{0.5f, 0.5f, 0.0f};
         duet_planner_observe(p, &pose, 1, rays, 60);
       }},
      {"duet_planner_information", true,
       [](duet_planner p) { EXPECT_EQ(duet_planner_information(p, {0.5f, 0.5f, 0.0f}), 0.0f); }},
      {"duet_planner_simulate", true,
       [](duet_planner p) {
         duet_partial_sim_result r;
         r.found = 77;
         duet_planner_simulate(p, {0.5f, 0.5f, 0.0f}, nullptr, &r, nullptr, 0);
         EXPECT_EQ(r.found, 77);  // unchanged
       }},
      {"duet_planner_find_frontier", true,
       [](duet_planner p) {
         duet_frontier_result r;
         r.path_count = 77;
         duet_planner_find_frontier(p, 0.5f, 0.5f, 0.0, nullptr, &r, nullptr, 0, nullptr, 0);
         EXPECT_EQ(r.path_count, 77u);
       }},
      {"duet_planner_blacklist_add", false, [](duet_planner p) { duet_planner_blacklist_add(p, 0, 0, 0.0, 1.0); }},
      {"duet_planner_blacklist_expire", false, [](duet_planner p) { duet_planner_blacklist_expire(p, 0.0); }},
      {"duet_planner_blacklist_clear", false, [](duet_planner p) { duet_planner_blacklist_clear(p); }},
      {"duet_planner_blacklist_get_size", false, [](duet_planner p) { EXPECT_EQ(duet_planner_blacklist_get_size(p), 0u); }},
      {"duet_planner_decide", true,
       [](duet_planner p) {
         duet_decision d;
         d.frontier_ran = 77;
         duet_planner_decide(p, {0.5f, 0.5f, 0.0f}, 0.0, nullptr, &d);
         EXPECT_EQ(d.frontier_ran, 77);
       }},
      {"duet_planner_plan_path", true,
       [](duet_planner p) {
         duet_path_result r;
         r.waypoint_count = 77;
         duet_planner_plan_path(p, 0.5f, 0.5f, 0.7f, 0.7f, nullptr, &r, nullptr, 0);
         EXPECT_EQ(r.waypoint_count, 77u);
       }},
      {"duet_planner_dwa_step", true,
       [](duet_planner p) {
         duet_dwa_result r;
         r.valid_trajectories = 77;
         duet_planner_dwa_step(p, {0.5f, 0.5f, 0.0f}, {0, 0}, path_xy, 0, 2, nullptr, &r);
         EXPECT_EQ(r.valid_trajectories, 77);
       }},
      {"duet_planner_dwa_reset", false, [](duet_planner p) { duet_planner_dwa_reset(p); }},
  };
}

TEST(CapiPlannerMisuse, NullReleasedAndWrongKindHandles) {
  (void)duet_device_get_error(nullptr);
  duet_device d = duet_device_new("threads=1");
  duet_grid g = duet_grid_new(d, 0.1f);
  duet_cloud c = duet_cloud_new(d);
  duet_planner dead = duet_planner_new(d);
  duet_planner_release(dead);
  ASSERT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);
  for (const Call& call : planner_calls(g)) {
    SCOPED_TRACE(call.name);
    call.call(nullptr);
    EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
    std::string msg = duet_device_get_error_message(nullptr);
    EXPECT_NE(msg.find(call.name), std::string::npos) << msg;
    EXPECT_NE(msg.find("NULL"), std::string::npos) << msg;

    // A released or wrong-kind handle: the error reaches the device it belongs to.
    call.call(dead);
    EXPECT_EQ(duet_device_get_error(d), DUET_ERROR_INVALID_OPERATION);
    msg = duet_device_get_error_message(d);
    EXPECT_NE(msg.find("not a live duet_planner"), std::string::npos) << msg;

    call.call(reinterpret_cast<duet_planner>(c));
    EXPECT_EQ(duet_device_get_error(d), DUET_ERROR_INVALID_OPERATION);
    msg = duet_device_get_error_message(d);
    EXPECT_NE(msg.find("is a duet_cloud, expected a duet_planner"), std::string::npos) << msg;
    EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);  // nothing in the no-device slot
  }
  // The device and the grid are still fine (the wrong-kind release dropped nothing).
  EXPECT_EQ(duet_grid_get_width(g), 0);
  EXPECT_EQ(duet_cloud_get_size(c), 0u);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);
  // A planner handle where a device or grid is expected.
  duet_planner p = duet_planner_new(d);
  EXPECT_EQ(duet_planner_new(reinterpret_cast<duet_device>(p)), nullptr);
  EXPECT_EQ(duet_device_get_error(d), DUET_ERROR_INVALID_OPERATION);
  EXPECT_NE(std::string(duet_device_get_error_message(d)).find("is a duet_planner, expected a duet_device"),
            std::string::npos);
  duet_planner_set_grid_from(p, reinterpret_cast<duet_grid>(p), nullptr, nullptr);
  EXPECT_EQ(duet_device_get_error(d), DUET_ERROR_INVALID_OPERATION);
  duet_planner_set_grid_from(p, nullptr, nullptr, nullptr);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_planner_new(nullptr), nullptr);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
  duet_planner_release(p);
  duet_cloud_release(c);
  duet_grid_release(g);
  duet_device_release(d);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);
}

TEST(CapiPlannerMisuse, PlannerKeepsItsDeviceAlive) {
  (void)duet_device_get_error(nullptr);
  duet_device d = duet_device_new("threads=1");
  duet_planner p = duet_planner_new(d);
  duet_device_release(d);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);
  const TestGrid g = door_room();
  set_grid(p, g);
  EXPECT_GT(duet_planner_information(p, {2.0f, 5.0f, 0.0f}), 0.0f);
  duet_planner_information(p, {kNaN, 5.0f, 0.0f});
  EXPECT_EQ(duet_device_get_error(d), DUET_ERROR_INVALID_ARGUMENT);  // still reachable
  duet_planner_retain(p);
  duet_planner_release(p);
  EXPECT_EQ(duet_device_get_thread_count(d), 1);
  duet_planner_release(p);
  EXPECT_EQ(duet_device_get_thread_count(d), 0);  // gone with the planner
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_OPERATION);
  duet_planner_release(p);  // double release
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_OPERATION);
}

TEST_F(PlannerTest, CallsBeforeSetGridAreInvalidOperations) {
  duet_grid g = duet_grid_new(device_, 0.1f);
  for (const Call& call : planner_calls(g)) {
    if (call.name == "duet_planner_release" || call.name == "duet_planner_set_grid" ||
        call.name == "duet_planner_set_grid_from" || call.name == "duet_planner_retain") {
      continue;
    }
    SCOPED_TRACE(call.name);
    if (!call.needs_grid) {
      if (call.name == "duet_planner_get_sensors" || call.name == "duet_planner_get_ray_count" ||
          call.name == "duet_planner_blacklist_get_size") {
        continue;  // they return non-zero values on a live planner (checked elsewhere)
      }
      call.call(planner_);  // get_grid_size: 0 x 0, no error
      EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
      duet_planner_blacklist_clear(planner_);
      continue;
    }
    call.call(planner_);
    EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
    const std::string msg = message();
    EXPECT_NE(msg.find(call.name), std::string::npos) << msg;
    EXPECT_NE(msg.find("no grid"), std::string::npos) << msg;
  }
  // set_grid_from an empty duet_grid fails and leaves the planner without a grid.
  duet_planner_set_grid_from(planner_, g, nullptr, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("empty"), std::string::npos) << message();
  duet_planner_copy_clearance(planner_, nullptr, 0);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
  duet_grid_release(g);
}

TEST_F(PlannerTest, BadBuffersAndCounts) {
  const TestGrid g = door_room();
  set_grid(planner_, g);
  ASSERT_EQ(take(), DUET_ERROR_NONE);
  const duet_pose2 pose{2.0f, 5.0f, 0.0f};
  std::vector<duet_ray_observation> rays(60);
  std::vector<float> f(g.cells());
  std::vector<std::uint8_t> u8(g.cells());
  struct Case {
    const char* what;
    std::function<void()> call;
    duet_error code;
    const char* expected;  // in the message
  };
  const std::vector<Case> cases = {
      {"observe NULL poses", [&] { duet_planner_observe(planner_, nullptr, 1, rays.data(), 60); },
       DUET_ERROR_INVALID_ARGUMENT, "poses is NULL"},
      {"observe NULL out", [&] { duet_planner_observe(planner_, &pose, 1, nullptr, 60); }, DUET_ERROR_INVALID_ARGUMENT,
       "out is NULL"},
      {"observe wrong out_count", [&] { duet_planner_observe(planner_, &pose, 1, rays.data(), 59); },
       DUET_ERROR_INVALID_ARGUMENT, "expected 60 elements, given 59"},
      {"observe out_count for 0 poses", [&] { duet_planner_observe(planner_, &pose, 0, rays.data(), 60); },
       DUET_ERROR_INVALID_ARGUMENT, "expected 0 elements"},
      {"copy_clearance NULL", [&] { duet_planner_copy_clearance(planner_, nullptr, f.size()); },
       DUET_ERROR_INVALID_ARGUMENT, "out is NULL"},
      {"copy_clearance count", [&] { duet_planner_copy_clearance(planner_, f.data(), f.size() - 1); },
       DUET_ERROR_INVALID_ARGUMENT, "expected 40000 elements"},
      {"copy_traversable count", [&] { duet_planner_copy_traversable(planner_, u8.data(), 5); },
       DUET_ERROR_INVALID_ARGUMENT, "expected 40000"},
      {"copy_frontier_mask count", [&] { duet_planner_copy_frontier_mask(planner_, u8.data(), 0); },
       DUET_ERROR_INVALID_ARGUMENT, "expected 40000"},
      {"copy_frontier_mask NULL", [&] { duet_planner_copy_frontier_mask(planner_, nullptr, u8.size()); },
       DUET_ERROR_INVALID_ARGUMENT, "out is NULL"},
      {"simulate NULL out", [&] { duet_planner_simulate(planner_, pose, nullptr, nullptr, nullptr, 0); },
       DUET_ERROR_INVALID_ARGUMENT, "out is NULL"},
      {"simulate NULL trajectory",
       [&] {
         duet_partial_sim_result r;
         duet_planner_simulate(planner_, pose, nullptr, &r, nullptr, 4);
       },
       DUET_ERROR_INVALID_ARGUMENT, "trajectory is NULL but trajectory_capacity is 4"},
      {"find_frontier NULL out",
       [&] { duet_planner_find_frontier(planner_, 2, 5, 0, nullptr, nullptr, nullptr, 0, nullptr, 0); },
       DUET_ERROR_INVALID_ARGUMENT, "out is NULL"},
      {"find_frontier NULL path",
       [&] {
         duet_frontier_result r;
         duet_planner_find_frontier(planner_, 2, 5, 0, nullptr, &r, nullptr, 3, nullptr, 0);
       },
       DUET_ERROR_INVALID_ARGUMENT, "path_xy is NULL but path_capacity is 3"},
      {"find_frontier NULL clusters",
       [&] {
         duet_frontier_result r;
         duet_planner_find_frontier(planner_, 2, 5, 0, nullptr, &r, nullptr, 0, nullptr, 2);
       },
       DUET_ERROR_INVALID_ARGUMENT, "clusters is NULL but cluster_capacity is 2"},
      {"decide NULL out", [&] { duet_planner_decide(planner_, pose, 0.0, nullptr, nullptr); },
       DUET_ERROR_INVALID_ARGUMENT, "out is NULL"},
      {"plan_path NULL xy",
       [&] {
         duet_path_result r;
         duet_planner_plan_path(planner_, 2, 5, 4, 4, nullptr, &r, nullptr, 1);
       },
       DUET_ERROR_INVALID_ARGUMENT, "xy is NULL but capacity is 1"},
      {"plan_path NULL out", [&] { duet_planner_plan_path(planner_, 2, 5, 4, 4, nullptr, nullptr, nullptr, 0); },
       DUET_ERROR_INVALID_ARGUMENT, "out is NULL"},
      {"dwa NULL path",
       [&] {
         duet_dwa_result r;
         duet_planner_dwa_step(planner_, pose, {0, 0}, nullptr, 0, 2, nullptr, &r);
       },
       DUET_ERROR_INVALID_ARGUMENT, "path_xy is NULL but count is 2"},
      {"dwa small stride",
       [&] {
         duet_dwa_result r;
         duet_planner_dwa_step(planner_, pose, {0, 0}, f.data(), 4, 2, nullptr, &r);
       },
       DUET_ERROR_INVALID_ARGUMENT, "path_xy stride 4 bytes is smaller"},
      {"dwa NaN waypoint",
       [&] {
         const float bad[4] = {2.0f, 5.0f, kNaN, 5.0f};
         duet_dwa_result r;
         duet_planner_dwa_step(planner_, pose, {0, 0}, bad, 0, 2, nullptr, &r);
       },
       DUET_ERROR_INVALID_ARGUMENT, "path_xy[1] is not finite"},
      {"dwa NULL out",
       [&] { duet_planner_dwa_step(planner_, pose, {0, 0}, f.data(), 0, 1, nullptr, nullptr); },
       DUET_ERROR_INVALID_ARGUMENT, "out is NULL"},
      {"get_sensors NULL", [&] { duet_planner_get_sensors(planner_, nullptr, 2); }, DUET_ERROR_INVALID_ARGUMENT,
       "out is NULL but capacity is 2"},
      {"set_sensors NULL", [&] { duet_planner_set_sensors(planner_, nullptr, 2); }, DUET_ERROR_INVALID_ARGUMENT,
       "sensors is NULL"},
      {"set_sensors 0",
       [&] {
         duet_sensor_sector s;
         duet_sensor_sector_init(&s);
         duet_planner_set_sensors(planner_, &s, 0);
       },
       DUET_ERROR_INVALID_ARGUMENT, "count is 0"},
      {"set_sensors bad field",
       [&] {
         duet_sensor_sector s[2];
         duet_paper_dual_sensors(s, 30);
         s[1].fov_rad = 7.0f;
         duet_planner_set_sensors(planner_, s, 2);
       },
       DUET_ERROR_INVALID_ARGUMENT, "sensors[1]: SensorSector.fov_rad"},
      {"set_sensors bad rays",
       [&] {
         duet_sensor_sector s;
         duet_sensor_sector_init(&s);
         s.rays = 0;
         duet_planner_set_sensors(planner_, &s, 1);
       },
       DUET_ERROR_INVALID_ARGUMENT, "sensors[0]: SensorSector.rays"},
      {"blacklist ttl 0", [&] { duet_planner_blacklist_add(planner_, 1, 1, 0.0, 0.0); }, DUET_ERROR_INVALID_ARGUMENT,
       "ttl_s"},
      {"blacklist ttl NaN", [&] { duet_planner_blacklist_add(planner_, 1, 1, 0.0, std::nan("")); },
       DUET_ERROR_INVALID_ARGUMENT, "ttl_s"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    c.call();
    EXPECT_EQ(take(), c.code);
    const std::string msg = message();
    EXPECT_NE(msg.find(c.expected), std::string::npos) << msg;
  }
  // Nothing changed: sensors, blacklist, grid.
  EXPECT_EQ(duet_planner_get_ray_count(planner_), 60u);
  EXPECT_EQ(duet_planner_blacklist_get_size(planner_), 0u);
  int w = 0, h = 0;
  duet_planner_get_grid_size(planner_, &w, &h);
  EXPECT_EQ(w, 200);
  EXPECT_EQ(take(), DUET_ERROR_NONE);
}

}  // namespace duet_capi_planner_test
