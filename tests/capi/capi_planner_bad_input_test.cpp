// Bad input to the exploration planner through the C API: grid arguments (the planner stays as it
// was), settings fields (named in the message), non-finite poses, and the device-less paper
// sensors' errors - documented error codes, no crash (also run under AddressSanitizer).
#include "capi_planner_util.hpp"

using namespace duet_capi_test;

// The tests sit in the shared parts' namespace: a using-directive for it at file scope would
// reach the next file of a unity batch.
namespace duet_capi_planner_test {

TEST_F(PlannerTest, BadGridArgumentsLeaveThePlannerUnchanged) {
  const TestGrid g = door_room();
  set_grid(planner_, g);
  ASSERT_EQ(take(), DUET_ERROR_NONE);
  const float info = duet_planner_information(planner_, {2.0f, 5.0f, 0.0f});
  std::vector<float> small(16, -2.0f);
  struct Case {
    const char* what;
    std::function<void()> call;
    duet_error code;
    const char* expected;
  };
  duet_observation_settings bad_backend;
  duet_observation_settings_init(&bad_backend);
  const int seven = 7;
  std::memcpy(&bad_backend.backend, &seven, sizeof seven);
  duet_observation_settings bad_tile;
  duet_observation_settings_init(&bad_tile);
  bad_tile.tile_cells = 0;
  duet_observation_settings bad_thresholds;
  duet_observation_settings_init(&bad_thresholds);
  bad_thresholds.thresholds.free_logodds = 1.0f;
  duet_inflation_settings bad_radius;
  duet_inflation_settings_init(&bad_radius);
  bad_radius.robot_radius_m = -0.1f;
  duet_inflation_settings bad_flag;
  duet_inflation_settings_init(&bad_flag);
  bad_flag.unknown_is_obstacle = 2;
  duet_inflation_settings bad_flag2;
  duet_inflation_settings_init(&bad_flag2);
  bad_flag2.uncertain_is_obstacle = -1;
  const std::vector<Case> cases = {
      {"NULL cells", [&] { duet_planner_set_grid(planner_, nullptr, 0, 4, 4, 0.1f, 0, 0, nullptr, nullptr); },
       DUET_ERROR_INVALID_ARGUMENT, "logodds is NULL"},
      {"zero width", [&] { duet_planner_set_grid(planner_, small.data(), 0, 0, 4, 0.1f, 0, 0, nullptr, nullptr); },
       DUET_ERROR_INVALID_ARGUMENT, "width x height is 0 x 4"},
      {"negative height", [&] { duet_planner_set_grid(planner_, small.data(), 0, 4, -1, 0.1f, 0, 0, nullptr, nullptr); },
       DUET_ERROR_INVALID_ARGUMENT, "width x height"},
      {"huge", [&] { duet_planner_set_grid(planner_, small.data(), 0, 1 << 15, 1 << 15, 0.1f, 0, 0, nullptr, nullptr); },
       DUET_ERROR_OUT_OF_RANGE, "2^30"},
      {"NaN resolution", [&] { duet_planner_set_grid(planner_, small.data(), 0, 4, 4, kNaN, 0, 0, nullptr, nullptr); },
       DUET_ERROR_INVALID_ARGUMENT, "resolution_m"},
      {"zero resolution", [&] { duet_planner_set_grid(planner_, small.data(), 0, 4, 4, 0.0f, 0, 0, nullptr, nullptr); },
       DUET_ERROR_INVALID_ARGUMENT, "resolution_m"},
      {"inf origin", [&] { duet_planner_set_grid(planner_, small.data(), 0, 4, 4, 0.1f, kInf, 0, nullptr, nullptr); },
       DUET_ERROR_INVALID_ARGUMENT, "origin_x"},
      {"NaN origin", [&] { duet_planner_set_grid(planner_, small.data(), 0, 4, 4, 0.1f, 0, kNaN, nullptr, nullptr); },
       DUET_ERROR_INVALID_ARGUMENT, "origin_y"},
      // The map frame's limits (found by fuzz_capi: a resolution of 1e-30 made Procedure 1's
      // ray buffers' size overflow).
      {"tiny resolution", [&] { duet_planner_set_grid(planner_, small.data(), 0, 4, 4, 1e-30f, 0, 0, nullptr, nullptr); },
       DUET_ERROR_INVALID_ARGUMENT, "resolution_m"},
      {"huge resolution", [&] { duet_planner_set_grid(planner_, small.data(), 0, 4, 4, 1e3f, 0, 0, nullptr, nullptr); },
       DUET_ERROR_INVALID_ARGUMENT, "resolution_m"},
      {"far origin", [&] { duet_planner_set_grid(planner_, small.data(), 0, 4, 4, 0.1f, 0, -3e4f, nullptr, nullptr); },
       DUET_ERROR_OUT_OF_RANGE, "origin"},
      {"stride < row", [&] { duet_planner_set_grid(planner_, small.data(), 12, 4, 4, 0.1f, 0, 0, nullptr, nullptr); },
       DUET_ERROR_INVALID_ARGUMENT, "logodds stride 12 bytes is smaller"},
      {"stride % 4", [&] { duet_planner_set_grid(planner_, small.data(), 17, 4, 2, 0.1f, 0, 0, nullptr, nullptr); },
       DUET_ERROR_INVALID_ARGUMENT, "not a multiple of 4"},
      {"misaligned",
       [&] {
         duet_planner_set_grid(planner_, reinterpret_cast<const float*>(reinterpret_cast<const char*>(small.data()) + 2), 0,
                               2, 2, 0.1f, 0, 0, nullptr, nullptr);
       },
       DUET_ERROR_INVALID_ARGUMENT, "aligned"},
      {"bad backend enum",
       [&] { duet_planner_set_grid(planner_, small.data(), 0, 4, 4, 0.1f, 0, 0, &bad_backend, nullptr); },
       DUET_ERROR_INVALID_ARGUMENT, "observation_settings.backend is 7"},
      {"bad tile",
       [&] { duet_planner_set_grid(planner_, small.data(), 0, 4, 4, 0.1f, 0, 0, &bad_tile, nullptr); },
       DUET_ERROR_INVALID_ARGUMENT, "observation_settings: ObservationSettings.tile_cells"},
      {"bad thresholds",
       [&] { duet_planner_set_grid(planner_, small.data(), 0, 4, 4, 0.1f, 0, 0, &bad_thresholds, nullptr); },
       DUET_ERROR_INVALID_ARGUMENT, "free_logodds"},
      {"bad radius",
       [&] { duet_planner_set_grid(planner_, small.data(), 0, 4, 4, 0.1f, 0, 0, nullptr, &bad_radius); },
       DUET_ERROR_INVALID_ARGUMENT, "inflation_settings: InflationSettings.robot_radius_m"},
      {"bad flag",
       [&] { duet_planner_set_grid(planner_, small.data(), 0, 4, 4, 0.1f, 0, 0, nullptr, &bad_flag); },
       DUET_ERROR_INVALID_ARGUMENT, "inflation_settings.unknown_is_obstacle is 2"},
      {"bad flag 2",
       [&] { duet_planner_set_grid(planner_, small.data(), 0, 4, 4, 0.1f, 0, 0, nullptr, &bad_flag2); },
       DUET_ERROR_INVALID_ARGUMENT, "inflation_settings.uncertain_is_obstacle is -1"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    c.call();
    EXPECT_EQ(take(), c.code);
    const std::string msg = message();
    EXPECT_NE(msg.find(c.expected), std::string::npos) << msg;
    EXPECT_NE(msg.find("duet_planner_set_grid"), std::string::npos) << msg;
    int w = 0, h = 0;
    duet_planner_get_grid_size(planner_, &w, &h);
    EXPECT_EQ(w, 200);
    EXPECT_EQ(h, 200);
    EXPECT_TRUE(same_float(duet_planner_information(planner_, {2.0f, 5.0f, 0.0f}), info));
  }
  EXPECT_EQ(take(), DUET_ERROR_NONE);
  // A grid of another device.
  duet_device other = duet_device_new("threads=1");
  duet_grid foreign = duet_grid_new(other, 0.1f);
  duet_planner_set_grid_from(planner_, foreign, nullptr, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_OPERATION);
  EXPECT_NE(message().find("another device"), std::string::npos) << message();
  duet_grid_release(foreign);
  duet_device_release(other);
}

TEST_F(PlannerTest, BadSettingsFieldsAreNamed) {
  const TestGrid g = door_room();
  set_grid(planner_, g);
  const duet_pose2 robot{2.0f, 5.0f, 0.0f};
  struct Case {
    const char* what;
    std::function<void()> call;
    const char* expected;
  };
  std::vector<Case> cases;
  auto sim_case = [&](const char* field, std::function<void(duet_partial_sim_settings&)> change) {
    cases.push_back({field,
                     [this, robot, change] {
                       duet_partial_sim_settings s;
                       duet_partial_sim_settings_init(&s);
                       change(s);
                       duet_partial_sim_result r;
                       duet_planner_simulate(planner_, robot, &s, &r, nullptr, 0);
                     },
                     field});
  };
  sim_case("iterations", [](auto& s) { s.iterations = 0; });
  sim_case("particles", [](auto& s) { s.particles = -3; });
  sim_case("stages", [](auto& s) { s.stages = 101; });
  sim_case("phi_a", [](auto& s) { s.phi_a = -5; });
  sim_case("stage_dt_s", [](auto& s) { s.stage_dt_s = kNaN; });
  sim_case("gamma", [](auto& s) { s.gamma = 0.0f; });
  sim_case("unknown_hit_probability", [](auto& s) { s.unknown_hit_probability = 1.0f; });
  auto frontier_case = [&](const char* field, std::function<void(duet_frontier_settings&)> change) {
    cases.push_back({field,
                     [this, change] {
                       duet_frontier_settings s;
                       duet_frontier_settings_init(&s);
                       change(s);
                       duet_frontier_result r;
                       duet_planner_find_frontier(planner_, 2, 5, 0, &s, &r, nullptr, 0, nullptr, 0);
                     },
                     field});
  };
  frontier_case("min_cluster_cells", [](auto& s) { s.min_cluster_cells = 0; });
  frontier_case("min_goal_distance_m", [](auto& s) { s.min_goal_distance_m = -1.0f; });
  frontier_case("blacklist_radius_m", [](auto& s) { s.blacklist_radius_m = kNaN; });
  frontier_case("approach_radius_m", [](auto& s) { s.approach_radius_m = -0.5f; });
  frontier_case("min_unknown_region_m2", [](auto& s) { s.min_unknown_region_m2 = kNaN; });
  auto exploration_case = [&](const char* field, std::function<void(duet_exploration_settings&)> change) {
    cases.push_back({field,
                     [this, robot, change] {
                       duet_exploration_settings s;
                       duet_exploration_settings_init(&s);
                       change(s);
                       duet_decision d;
                       duet_planner_decide(planner_, robot, 0.0, &s, &d);
                     },
                     field});
  };
  exploration_case("eps_r_bits", [](auto& s) { s.eps_r_bits = -1.0f; });
  exploration_case("use_simulation", [](auto& s) { s.use_simulation = 5; });
  exploration_case("particles", [](auto& s) { s.simulation.particles = 0; });
  exploration_case("min_cluster_cells", [](auto& s) { s.frontier.min_cluster_cells = -2; });
  auto path_case = [&](const char* field, std::function<void(duet_path_settings&)> change) {
    cases.push_back({field,
                     [this, change] {
                       duet_path_settings s;
                       duet_path_settings_init(&s);
                       change(s);
                       duet_path_result r;
                       duet_planner_plan_path(planner_, 2, 5, 4, 4, &s, &r, nullptr, 0);
                     },
                     field});
  };
  path_case("allow_diagonal", [](auto& s) { s.allow_diagonal = -1; });
  path_case("clearance_weight", [](auto& s) { s.clearance_weight = -1.0f; });
  path_case("clearance_decay_m", [](auto& s) { s.clearance_decay_m = 0.0f; });
  path_case("goal_tolerance_m", [](auto& s) { s.goal_tolerance_m = kInf; });
  auto dwa_case = [&](const char* field, std::function<void(duet_dwa_settings&)> change) {
    cases.push_back({field,
                     [this, robot, change] {
                       duet_dwa_settings s;
                       duet_dwa_settings_init(&s);
                       change(s);
                       const float path[4] = {2.0f, 5.0f, 3.0f, 5.0f};
                       duet_dwa_result r;
                       duet_planner_dwa_step(planner_, robot, {0, 0}, path, 0, 2, &s, &r);
                     },
                     field});
  };
  dwa_case("v_samples", [](auto& s) { s.v_samples = 0; });
  dwa_case("steps", [](auto& s) { s.steps = 1001; });
  dwa_case("control_period_s", [](auto& s) { s.control_period_s = 0.0f; });
  dwa_case("w_path", [](auto& s) { s.w_path = -1.0f; });
  dwa_case("max_v_mps", [](auto& s) { s.limits.max_v_mps = 0.0f; });
  dwa_case("min_v_mps", [](auto& s) { s.limits.min_v_mps = 0.5f; });
  dwa_case("mapping_max_omega_rps", [](auto& s) { s.mapping_max_omega_rps = kNaN; });
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    c.call();
    EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
    const std::string msg = message();
    EXPECT_NE(msg.find(c.expected), std::string::npos) << msg;
    EXPECT_NE(msg.find("settings"), std::string::npos) << msg;
  }
  // The DWA state was not touched by the failing steps: the next valid step equals a fresh one.
  duet_planner fresh = duet_planner_new(device_);
  set_grid(fresh, g);
  const float path[4] = {2.0f, 5.0f, 3.0f, 5.0f};
  duet_dwa_result a, b;
  duet_planner_dwa_step(planner_, robot, {0, 0}, path, 0, 2, nullptr, &a);
  duet_planner_dwa_step(fresh, robot, {0, 0}, path, 0, 2, nullptr, &b);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
  EXPECT_EQ(std::memcmp(&a, &b, sizeof a), 0);
  duet_planner_release(fresh);
}

TEST_F(PlannerTest, NonFinitePosesAreInvalidArguments) {
  const TestGrid g = door_room();
  set_grid(planner_, g);
  const float bad_values[] = {kNaN, kInf, -kInf};
  for (const float bad : bad_values) {
    SCOPED_TRACE(bad);
    const duet_pose2 poses[3] = {{bad, 5.0f, 0.0f}, {2.0f, bad, 0.0f}, {2.0f, 5.0f, bad}};
    for (const duet_pose2& p : poses) {
      const duet_pose2 two[2] = {{2.0f, 5.0f, 0.0f}, p};
      std::vector<duet_ray_observation> rays(120);
      rays[0].cells = -77;
      duet_planner_observe(planner_, two, 2, rays.data(), rays.size());
      EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
      EXPECT_NE(message().find("poses[1]"), std::string::npos) << message();
      EXPECT_EQ(rays[0].cells, -77);  // outputs unchanged

      EXPECT_EQ(duet_planner_information(planner_, p), 0.0f);
      EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
      EXPECT_NE(message().find("pose"), std::string::npos) << message();

      duet_partial_sim_result sr;
      sr.found = 77;
      duet_planner_simulate(planner_, p, nullptr, &sr, nullptr, 0);
      EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
      EXPECT_NE(message().find("robot"), std::string::npos) << message();
      EXPECT_EQ(sr.found, 77);

      duet_decision d;
      d.frontier_ran = 77;
      duet_planner_decide(planner_, p, 0.0, nullptr, &d);
      EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
      EXPECT_EQ(d.frontier_ran, 77);

      const float path[4] = {2.0f, 5.0f, 3.0f, 5.0f};
      duet_dwa_result dr;
      dr.valid_trajectories = 77;
      duet_planner_dwa_step(planner_, p, {0, 0}, path, 0, 2, nullptr, &dr);
      EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
      EXPECT_EQ(dr.valid_trajectories, 77);
    }
    const float path[4] = {2.0f, 5.0f, 3.0f, 5.0f};
    duet_dwa_result dr;
    duet_planner_dwa_step(planner_, {2.0f, 5.0f, 0.0f}, {bad, 0}, path, 0, 2, nullptr, &dr);
    EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(message().find("current"), std::string::npos) << message();

    duet_frontier_result fr;
    duet_planner_find_frontier(planner_, bad, 5.0f, 0.0, nullptr, &fr, nullptr, 0, nullptr, 0);
    EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(message().find("x is not finite"), std::string::npos) << message();
    duet_planner_find_frontier(planner_, 2.0f, 5.0f, static_cast<double>(bad), nullptr, &fr, nullptr, 0, nullptr, 0);
    EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(message().find("now_s"), std::string::npos) << message();

    duet_path_result pr;
    duet_planner_plan_path(planner_, 2.0f, 5.0f, 4.0f, bad, nullptr, &pr, nullptr, 0);
    EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(message().find("goal_y"), std::string::npos) << message();

    duet_planner_blacklist_add(planner_, bad, 1.0f, 0.0, 1.0);
    EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
    duet_planner_blacklist_add(planner_, 1.0f, 1.0f, static_cast<double>(bad), 1.0);
    EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
    duet_planner_blacklist_expire(planner_, static_cast<double>(bad));
    EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  }
  EXPECT_EQ(duet_planner_blacklist_get_size(planner_), 0u);
  // A pose outside the grid is not an error: the kernels say so in their status.
  duet_path_result pr;
  duet_planner_plan_path(planner_, -5.0f, 5.0f, 4.0f, 4.0f, nullptr, &pr, nullptr, 0);
  EXPECT_EQ(pr.status, DUET_PATH_OUTSIDE_GRID);
  duet_frontier_result fr;
  duet_planner_find_frontier(planner_, -5.0f, 5.0f, 0.0, nullptr, &fr, nullptr, 0, nullptr, 0);
  EXPECT_EQ(fr.status, DUET_FRONTIER_ROBOT_BLOCKED);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
}

TEST(CapiPlannerMisuse, PaperDualSensorsErrorsGoToTheNoDeviceSlot) {
  (void)duet_device_get_error(nullptr);
  duet_sensor_sector s[2];
  duet_paper_dual_sensors(s, 30);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);
  const duet_sensor_sector before[2] = {s[0], s[1]};
  duet_paper_dual_sensors(s, 0);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(duet_device_get_error_message(nullptr)).find("rays_per_sensor"), std::string::npos);
  EXPECT_EQ(std::memcmp(s, before, sizeof before), 0);
  duet_paper_dual_sensors(s, 100001);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
  duet_paper_dual_sensors(nullptr, 30);
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(duet_device_get_error_message(nullptr)).find("out is NULL"), std::string::npos);
}

}  // namespace duet_capi_planner_test
