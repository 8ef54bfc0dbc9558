// The exploration planner through the C API: every result equals the C++ kernels' on the same
// inputs (a room with a door, a random grid with a fixed seed) - observation, information, the
// partial map simulation, frontier search and blacklist, the decision, A* and the dynamic window.
#include "capi_planner_util.hpp"

using namespace duet_capi_test;

// The tests sit in the shared parts' namespace: a using-directive for it at file scope would
// reach the next file of a unity batch.
namespace duet_capi_planner_test {

TEST_F(PlannerTest, DefaultsBeforeAnyGrid) {
  int w = 7, h = 7;
  duet_planner_get_grid_size(planner_, &w, &h);
  EXPECT_EQ(w, 0);
  EXPECT_EQ(h, 0);
  EXPECT_EQ(duet_planner_get_ray_count(planner_), 60u);
  duet_sensor_sector s[3];
  duet_sensor_sector expected[2];
  duet_paper_dual_sensors(expected, 30);
  EXPECT_EQ(duet_planner_get_sensors(planner_, s, 3), 2u);
  EXPECT_EQ(std::memcmp(s, expected, sizeof expected), 0);
  EXPECT_EQ(duet_planner_blacklist_get_size(planner_), 0u);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
}

TEST_F(PlannerTest, ObserveAndInformationEqualTheKernel) {
  for (const duet_observation_backend backend : {DUET_OBSERVATION_DDA, DUET_OBSERVATION_EMBREE}) {
    for (int which = 0; which < 2; ++which) {
      SCOPED_TRACE(std::string(backend == DUET_OBSERVATION_DDA ? "dda " : "embree ") + (which ? "random" : "door room"));
      const TestGrid g = which ? random_grid(7) : door_room();
      const Reference ref(g, backend == DUET_OBSERVATION_DDA ? duet::ObservationBackend::kDda
                                                              : duet::ObservationBackend::kEmbree);
      const auto os = obs_settings(backend);
      set_grid(planner_, g, &os);
      ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
      const auto poses = random_poses(g, 37, 11);
      std::vector<duet::RayObservation> expected(poses.size() * 60);
      ref.model.observe(poses, ref.sensors, expected);
      const auto cp = to_c(poses);
      std::vector<duet_ray_observation> got(expected.size());
      duet_planner_observe(planner_, cp.data(), cp.size(), got.data(), got.size());
      ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
      int hits = 0;
      for (std::size_t i = 0; i < got.size(); ++i) {
        ASSERT_TRUE(same_float(got[i].entropy_bits, expected[i].entropy_bits)) << i;
        ASSERT_TRUE(same_float(got[i].range_m, expected[i].range_m)) << i;
        ASSERT_EQ(got[i].hit, expected[i].hit ? 1 : 0) << i;
        ASSERT_EQ(got[i].cells, expected[i].cells) << i;
        hits += got[i].hit;
      }
      EXPECT_GT(hits, 0);
      EXPECT_LT(hits, static_cast<int>(got.size()));
      float total = 0.0f;  // a pose inside an occupied cell observes nothing: only the sum is > 0
      for (std::size_t i = 0; i < 8; ++i) {
        const float info = duet_planner_information(planner_, cp[i]);
        EXPECT_TRUE(same_float(info, ref.model.information_bits(poses[i], ref.sensors)));
        total += info;
      }
      EXPECT_GT(total, 0.0f);
      // count 0 is valid (NULL buffers allowed).
      duet_planner_observe(planner_, nullptr, 0, nullptr, 0);
      EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
    }
  }
}

TEST_F(PlannerTest, CustomSensorsAreUsed) {
  const TestGrid g = door_room();
  set_grid(planner_, g);
  duet_sensor_sector s[3];
  for (auto& x : s) duet_sensor_sector_init(&x);
  s[0].rays = 5;
  s[1].rays = 1;
  s[1].yaw_rad = 1.0f;
  s[2].rays = 9;
  s[2].fov_rad = 6.2831853f;
  s[2].max_range_m = 2.0f;
  duet_planner_set_sensors(planner_, s, 3);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  EXPECT_EQ(duet_planner_get_ray_count(planner_), 15u);
  duet_sensor_sector back[3];
  EXPECT_EQ(duet_planner_get_sensors(planner_, back, 3), 3u);
  EXPECT_EQ(std::memcmp(back, s, sizeof s), 0);

  Reference ref(g);
  ref.sensors.clear();
  for (const auto& x : s) {
    duet::SensorSector c;
    c.x_m = x.x_m;
    c.y_m = x.y_m;
    c.yaw_rad = x.yaw_rad;
    c.fov_rad = x.fov_rad;
    c.min_range_m = x.min_range_m;
    c.max_range_m = x.max_range_m;
    c.rays = x.rays;
    ref.sensors.push_back(c);
  }
  const std::vector<duet::Pose2> poses = {{2.0f, 5.0f, 0.3f}, {4.0f, 4.0f, -2.0f}};
  std::vector<duet::RayObservation> expected(2 * 15);
  ref.model.observe(poses, ref.sensors, expected);
  const auto cp = to_c(poses);
  std::vector<duet_ray_observation> got(30);
  duet_planner_observe(planner_, cp.data(), 2, got.data(), got.size());
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_TRUE(same_float(got[i].entropy_bits, expected[i].entropy_bits)) << i;
    EXPECT_TRUE(same_float(got[i].range_m, expected[i].range_m)) << i;
  }
  // The old row length is now wrong.
  std::vector<duet_ray_observation> wrong(120);
  duet_planner_observe(planner_, cp.data(), 2, wrong.data(), wrong.size());
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
}

TEST_F(PlannerTest, SimulateEqualsTheKernelBitwise) {
  const TestGrid g = door_room();
  const Reference ref(g);
  set_grid(planner_, g);
  for (const std::uint64_t seed : {1ull, 42ull}) {
    for (const float theta : {3.14159f, 0.3f}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + " theta " + std::to_string(theta));
      const duet::Pose2 robot{2.0f, 5.0f, theta};
      duet::PartialSimSettings cs = dual_profile().exploration.strategy.simulation;
      cs.seed = seed;
      duet::PartialSimWorkspace ws;
      const duet::PartialSimResult r = duet::partial_map_simulation(ref.model, ref.inflated, robot, ref.sensors, cs, ws);
      duet_partial_sim_settings s;
      duet_partial_sim_settings_init(&s);
      s.seed = seed;
      duet_partial_sim_result out;
      std::vector<duet_pose2> traj(10, duet_pose2{-9.0f, -9.0f, -9.0f});
      duet_planner_simulate(planner_, {robot.x, robot.y, robot.theta}, &s, &out, traj.data(), traj.size());
      ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
      ASSERT_TRUE(r.found);
      EXPECT_EQ(out.found, 1);
      EXPECT_TRUE(same_pose(out.goal, r.goal));
      EXPECT_TRUE(same_float(out.reward_bits, r.reward_bits));
      EXPECT_GT(out.reward_bits, 0.0f);
      EXPECT_EQ(out.best_particle, r.best_particle);
      EXPECT_EQ(out.valid_particles, r.valid_particles);
      EXPECT_EQ(out.resamples, r.resamples);
      EXPECT_EQ(out.cells_visited, r.cells_visited);
      ASSERT_EQ(out.trajectory_count, r.best_trajectory.size());
      ASSERT_EQ(out.trajectory_count, 4u);
      for (std::size_t i = 0; i < 4; ++i) EXPECT_TRUE(same_pose(traj[i], r.best_trajectory[i])) << i;
      for (std::size_t i = 4; i < traj.size(); ++i) EXPECT_EQ(traj[i].x, -9.0f) << "written past the count";
    }
  }
}

TEST_F(PlannerTest, FrontierSearchAndBlacklistEqualTheKernel) {
  for (int which = 0; which < 2; ++which) {
    SCOPED_TRACE(which ? "random" : "door room");
    const TestGrid g = which ? random_grid(5) : door_room();
    const Reference ref(g);
    set_grid(planner_, g);
    duet_planner_blacklist_clear(planner_);
    const Eigen::Vector2f robot = which ? Eigen::Vector2f(2.0f, 2.0f) : Eigen::Vector2f(2.0f, 5.0f);
    duet::GoalBlacklist bl;
    for (int round = 0; round < 3; ++round) {
      SCOPED_TRACE("round " + std::to_string(round));
      duet::FrontierWorkspace ws;
      const duet::FrontierResult r = duet::find_frontier(ref.inflated, robot, bl, 10.0, dual_profile().exploration.strategy.frontier, ws);
      duet_frontier_result out;
      std::vector<float> path(2 * (r.path.size() + 3), -9.0f);
      std::vector<duet_frontier_cluster> clusters(r.clusters.size() + 2);
      duet_planner_find_frontier(planner_, robot.x(), robot.y(), 10.0, nullptr, &out, path.data(), path.size() / 2,
                                 clusters.data(), clusters.size());
      ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
      EXPECT_EQ(static_cast<int>(out.status), static_cast<int>(r.status));
      EXPECT_TRUE(same_float(out.goal_x, r.goal_xy.x()));
      EXPECT_TRUE(same_float(out.goal_y, r.goal_xy.y()));
      EXPECT_TRUE(same_float(out.target_x, r.target_xy.x()));
      EXPECT_TRUE(same_float(out.target_y, r.target_xy.y()));
      EXPECT_TRUE(same_float(out.path_length_m, r.path_length_m));
      EXPECT_EQ(out.frontier_cells, r.frontier_cells);
      EXPECT_EQ(out.reached_cells, r.reached_cells);
      ASSERT_EQ(out.path_count, r.path.size());
      ASSERT_EQ(out.cluster_count, r.clusters.size());
      for (std::size_t i = 0; i < r.path.size(); ++i) {
        EXPECT_TRUE(same_float(path[2 * i], r.path[i].x())) << i;
        EXPECT_TRUE(same_float(path[2 * i + 1], r.path[i].y())) << i;
      }
      EXPECT_EQ(path[2 * r.path.size()], -9.0f);
      for (std::size_t i = 0; i < r.clusters.size(); ++i) {
        const auto& k = r.clusters[i];
        EXPECT_EQ(clusters[i].cells, k.cells);
        EXPECT_TRUE(same_float(clusters[i].centroid_x, k.centroid.x()));
        EXPECT_TRUE(same_float(clusters[i].centroid_y, k.centroid.y()));
        EXPECT_TRUE(same_float(clusters[i].nearest_x, k.nearest_xy.x()));
        EXPECT_TRUE(same_float(clusters[i].nearest_y, k.nearest_xy.y()));
        EXPECT_TRUE(same_float(clusters[i].path_length_m, k.path_length_m));
        EXPECT_EQ(clusters[i].reachable, k.reachable ? 1 : 0);
        EXPECT_EQ(clusters[i].blacklisted, k.blacklisted ? 1 : 0);
      }
      if (round == 0) {
        ASSERT_EQ(r.status, duet::FrontierStatus::kFound);
        EXPECT_GT(r.path.size(), 1u);
        EXPECT_GE(r.clusters.size(), 1u);
      }
      if (r.status != duet::FrontierStatus::kFound) break;
      // Blacklist the goal on both sides; the next round must pick another goal (or none).
      bl.add(r.goal_xy, 10.0, 100.0);
      duet_planner_blacklist_add(planner_, r.goal_xy.x(), r.goal_xy.y(), 10.0, 100.0);
      ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
      EXPECT_EQ(duet_planner_blacklist_get_size(planner_), bl.size());
    }
  }
  // Expiry: entries added at 10 s for 100 s expire at 110 s.
  const std::size_t n = duet_planner_blacklist_get_size(planner_);
  EXPECT_GT(n, 0u);
  duet_planner_blacklist_expire(planner_, 109.0);
  EXPECT_EQ(duet_planner_blacklist_get_size(planner_), n);
  duet_planner_blacklist_expire(planner_, 110.0);
  EXPECT_EQ(duet_planner_blacklist_get_size(planner_), 0u);
  duet_planner_blacklist_add(planner_, 1.0f, 1.0f, 0.0, kInf);  // forever
  EXPECT_EQ(duet_planner_blacklist_get_size(planner_), 1u);
  duet_planner_blacklist_clear(planner_);
  EXPECT_EQ(duet_planner_blacklist_get_size(planner_), 0u);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
}

TEST_F(PlannerTest, DecideEqualsTheKernel) {
  const TestGrid g = door_room();
  const Reference ref(g);
  set_grid(planner_, g);
  for (int use_sim = 1; use_sim >= 0; --use_sim) {
    for (const float eps : {1.0f, 1e6f}) {  // 1e6: the frontier search decides
      SCOPED_TRACE("use_simulation " + std::to_string(use_sim) + " eps " + std::to_string(eps));
      duet::ExplorationSettings cs = dual_profile().exploration.strategy;
      cs.use_simulation = use_sim != 0;
      cs.eps_r_bits = eps;
      const duet::Pose2 robot{2.0f, 5.0f, 3.14159f};
      duet::ExplorationWorkspace ws;
      duet::GoalBlacklist bl;
      const duet::ExplorationDecision d = duet::decide_goal(ref.model, ref.inflated, robot, ref.sensors, bl, 0.0, cs, ws);
      duet_exploration_settings s;
      duet_exploration_settings_init(&s);
      s.use_simulation = use_sim;
      s.eps_r_bits = eps;
      duet_decision out;
      duet_planner_decide(planner_, {robot.x, robot.y, robot.theta}, 0.0, &s, &out);
      ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
      EXPECT_EQ(static_cast<int>(out.status), static_cast<int>(d.status));
      EXPECT_TRUE(same_pose(out.goal, d.goal));
      EXPECT_TRUE(same_float(out.reward_bits, d.reward_bits));
      EXPECT_EQ(out.simulated_goal_blacklisted, d.simulated_goal_blacklisted ? 1 : 0);
      EXPECT_EQ(out.simulation_ran, use_sim);
      EXPECT_EQ(out.simulation.found, d.simulation.found ? 1 : 0);
      EXPECT_TRUE(same_pose(out.simulation.goal, d.simulation.goal));
      EXPECT_EQ(out.simulation.best_particle, d.simulation.best_particle);
      EXPECT_EQ(out.simulation.cells_visited, d.simulation.cells_visited);
      EXPECT_EQ(static_cast<int>(out.frontier.status), static_cast<int>(d.frontier.status));
      EXPECT_EQ(out.frontier.path_count, d.frontier.path.size());
      if (use_sim && eps == 1.0f) {
        EXPECT_EQ(out.status, DUET_EXPLORATION_SIMULATED_GOAL);
        EXPECT_EQ(out.frontier_ran, 0);
      } else {
        EXPECT_EQ(out.status, DUET_EXPLORATION_FRONTIER_GOAL);
        EXPECT_EQ(out.frontier_ran, 1);
        EXPECT_EQ(out.frontier.status, DUET_FRONTIER_FOUND);
      }
    }
  }
}

TEST_F(PlannerTest, PlanPathEqualsTheKernel) {
  for (int which = 0; which < 2; ++which) {
    SCOPED_TRACE(which ? "random" : "door room");
    const TestGrid g = which ? random_grid(9) : door_room();
    const Reference ref(g);
    set_grid(planner_, g);
    const std::vector<std::pair<Eigen::Vector2f, Eigen::Vector2f>> queries =
        which ? std::vector<std::pair<Eigen::Vector2f, Eigen::Vector2f>>{{{-1.5f, -0.5f}, {4.5f, 4.5f}},
                                                                          {{0.0f, 0.0f}, {2.0f, 3.0f}},
                                                                          {{-2.9f, -1.9f}, {8.0f, 6.0f}}}
              : std::vector<std::pair<Eigen::Vector2f, Eigen::Vector2f>>{{{2.0f, 5.0f}, {4.5f, 5.0f}},
                                                                          {{1.5f, 3.5f}, {4.6f, 6.6f}},
                                                                          {{2.0f, 5.0f}, {7.0f, 5.0f}},
                                                                          {{2.0f, 5.0f}, {20.0f, 5.0f}}};
    for (const float tolerance : {0.0f, 0.3f}) {
      duet::PathSettings cs = dual_profile().exploration.path;
      cs.goal_tolerance_m = tolerance;
      duet_path_settings s;
      duet_path_settings_init(&s);
      s.goal_tolerance_m = tolerance;
      int found = 0;
      for (const auto& [a, b] : queries) {
        duet::PathWorkspace ws;
        const duet::PathResult r = duet::plan_path(ref.inflated, a, b, cs, ws);
        duet_path_result out;
        std::vector<float> xy(2 * (r.waypoints.size() + 1), -9.0f);
        duet_planner_plan_path(planner_, a.x(), a.y(), b.x(), b.y(), &s, &out, xy.data(), xy.size() / 2);
        ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
        EXPECT_EQ(static_cast<int>(out.status), static_cast<int>(r.status));
        ASSERT_EQ(out.waypoint_count, r.waypoints.size());
        EXPECT_TRUE(same_float(out.length_m, r.length_m));
        EXPECT_TRUE(same_float(out.cost, r.cost));
        EXPECT_EQ(out.start_moved, r.start_moved ? 1 : 0);
        EXPECT_EQ(out.expanded, r.expanded);
        for (std::size_t i = 0; i < r.waypoints.size(); ++i) {
          EXPECT_TRUE(same_float(xy[2 * i], r.waypoints[i].x()));
          EXPECT_TRUE(same_float(xy[2 * i + 1], r.waypoints[i].y()));
        }
        EXPECT_EQ(xy[2 * r.waypoints.size()], -9.0f);
        found += out.status == DUET_PATH_FOUND;
      }
      EXPECT_GE(found, 1);
    }
  }
}

TEST_F(PlannerTest, DwaStepsEqualTheKernelAndKeepState) {
  const TestGrid g = door_room();
  const Reference ref(g);
  set_grid(planner_, g);
  duet::PathWorkspace pws;
  const duet::PathResult path = duet::plan_path(ref.inflated, {2.0f, 5.0f}, {4.5f, 3.8f}, dual_profile().exploration.path, pws);
  ASSERT_EQ(path.status, duet::PathStatus::kFound);
  // The path as a strided record array (x, y, something else).
  struct Waypoint {
    float x, y, z;
  };
  std::vector<Waypoint> rec;
  for (const auto& p : path.waypoints) rec.push_back({p.x(), p.y(), 1234.0f});

  duet::DwaSettings cs = dual_profile().exploration.dwa;
  cs.oscillation_window_calls = 5;  // exercise the state between calls
  duet_dwa_settings s;
  duet_dwa_settings_init(&s);
  s.oscillation_window_calls = 5;
  duet::DwaState state;
  duet::DwaWorkspace ws;
  duet::Pose2 x{2.0f, 5.0f, 2.5f};  // facing away from the path: recovery first
  duet::Twist cur{};
  std::vector<int> statuses;
  for (int step = 0; step < 80; ++step) {
    SCOPED_TRACE("step " + std::to_string(step));
    const duet::DwaResult r = duet::dwa_step(ref.inflated.clearance(), x, cur, path.waypoints, cs, state, ws);
    duet_dwa_result out;
    duet_planner_dwa_step(planner_, {x.x, x.y, x.theta}, {cur.v, cur.omega}, &rec[0].x, sizeof(Waypoint), rec.size(),
                          &s, &out);
    ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
    ASSERT_EQ(static_cast<int>(out.status), static_cast<int>(r.status));
    ASSERT_TRUE(same_float(out.cmd.v, r.cmd.v));
    ASSERT_TRUE(same_float(out.cmd.omega, r.cmd.omega));
    ASSERT_TRUE(same_float(out.score, r.score));
    EXPECT_EQ(out.valid_trajectories, r.valid_trajectories);
    EXPECT_EQ(out.evaluated_trajectories, r.evaluated_trajectories);
    EXPECT_EQ(out.oscillation, r.oscillation ? 1 : 0);
    EXPECT_TRUE(same_float(out.lookahead_x, r.lookahead.x()));
    EXPECT_TRUE(same_float(out.lookahead_y, r.lookahead.y()));
    statuses.push_back(out.status);
    x = duet::motion_step(x, r.cmd, cs.control_period_s);
    cur = r.cmd;
  }
  EXPECT_NE(std::find(statuses.begin(), statuses.end(), DUET_DWA_OK), statuses.end());
  // Reset = a fresh state.
  duet_planner_dwa_reset(planner_);
  state.reset();
  const duet::DwaResult r = duet::dwa_step(ref.inflated.clearance(), x, cur, path.waypoints, cs, state, ws);
  duet_dwa_result out;
  duet_planner_dwa_step(planner_, {x.x, x.y, x.theta}, {cur.v, cur.omega}, &rec[0].x, sizeof(Waypoint), rec.size(), &s,
                        &out);
  EXPECT_EQ(static_cast<int>(out.status), static_cast<int>(r.status));
  EXPECT_TRUE(same_float(out.cmd.v, r.cmd.v));
  // An empty path: NO_PATH, NULL allowed.
  duet_planner_dwa_step(planner_, {x.x, x.y, x.theta}, {0, 0}, nullptr, 0, 0, nullptr, &out);
  EXPECT_EQ(out.status, DUET_DWA_NO_PATH);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
}

}  // namespace duet_capi_planner_test
