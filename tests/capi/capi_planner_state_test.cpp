// The exploration planner's state through the C API: read-backs equal the kernels', strided rows
// equal packed rows, a duet_grid equals its copied cells, an incremental grid update equals a
// fresh planner, 1 and 2 device threads give identical results, the output capacity rule, and
// concurrent calls on one planner are serialised.
#include "capi_planner_util.hpp"

using namespace duet_capi_test;

// The tests sit in the shared parts' namespace: a using-directive for it at file scope would
// reach the next file of a unity batch.
namespace duet_capi_planner_test {

TEST_F(PlannerTest, ReadBacksEqualTheKernel) {
  const TestGrid g = random_grid(3);
  duet_inflation_settings is;
  duet_inflation_settings_init(&is);
  is.robot_radius_m = 0.25f;
  is.unknown_is_obstacle = 1;
  is.uncertain_is_obstacle = 0;
  set_grid(planner_, g, nullptr, &is);
  duet::InflationSettings cis = dual_profile().exploration.inflation;
  cis.robot_radius_m = 0.25f;
  cis.unknown_is_obstacle = true;
  cis.uncertain_is_obstacle = false;
  duet::InflatedGrid inflated;
  duet::inflate(g.view(), cis, inflated);
  int w = 0, h = 0;
  duet_planner_get_grid_size(planner_, &w, &h);
  EXPECT_EQ(w, g.w);
  EXPECT_EQ(h, g.h);
  std::vector<float> clearance(g.cells());
  std::vector<std::uint8_t> traversable(g.cells()), mask(g.cells()), expected_mask(g.cells());
  duet_planner_copy_clearance(planner_, clearance.data(), clearance.size());
  duet_planner_copy_traversable(planner_, traversable.data(), traversable.size());
  duet_planner_copy_frontier_mask(planner_, mask.data(), mask.size());
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  EXPECT_TRUE(same_vec(clearance, inflated.clearance_m, "clearance"));
  EXPECT_TRUE(same_vec(traversable, inflated.traversable, "traversable"));
  const std::size_t frontier = duet::frontier_mask(g.view(), duet::CellThresholds{}, expected_mask);
  EXPECT_GT(frontier, 0u);
  EXPECT_TRUE(same_vec(mask, expected_mask, "frontier mask"));
  EXPECT_GT(std::count(traversable.begin(), traversable.end(), 1), 100);
}

TEST_F(PlannerTest, StridedRowsEqualPackedRows) {
  const TestGrid g = random_grid(21);
  const std::size_t stride_floats = static_cast<std::size_t>(g.w) + 5;  // 20 bytes of padding per row
  std::vector<float> strided(stride_floats * static_cast<std::size_t>(g.h), 77.0f);
  for (int y = 0; y < g.h; ++y) {
    std::copy_n(g.l.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(g.w), g.w,
                strided.data() + static_cast<std::size_t>(y) * stride_floats);
  }
  duet_planner packed = duet_planner_new(device_);
  set_grid(packed, g);
  duet_planner_set_grid(planner_, strided.data(), stride_floats * sizeof(float), g.w, g.h, g.res, g.ox, g.oy, nullptr,
                        nullptr);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  // Explicit packed stride = 0.
  duet_planner explicit_packed = duet_planner_new(device_);
  duet_planner_set_grid(explicit_packed, g.l.data(), static_cast<std::size_t>(g.w) * sizeof(float), g.w, g.h, g.res,
                        g.ox, g.oy, nullptr, nullptr);
  const auto poses = random_poses(g, 8, 4);
  const Snapshot a = snapshot(device_, packed, poses, {1.0f, 1.0f, 0.5f}, {3.0f, 2.0f});
  const Snapshot b = snapshot(device_, planner_, poses, {1.0f, 1.0f, 0.5f}, {3.0f, 2.0f});
  const Snapshot c = snapshot(device_, explicit_packed, poses, {1.0f, 1.0f, 0.5f}, {3.0f, 2.0f});
  expect_same(a, b);
  expect_same(a, c);
  duet_planner_release(explicit_packed);
  duet_planner_release(packed);
}

TEST_F(PlannerTest, GridHandleEqualsItsCopiedCells) {
  duet_grid grid = duet_grid_new(device_, 0.05f);
  const std::vector<float> xyz = room_points(4000, 5);
  std::vector<std::uint8_t> labels(xyz.size() / 3);
  for (std::size_t i = 0; i < labels.size(); ++i) {
    labels[i] = xyz[3 * i + 2] > 0.1f ? DUET_LABEL_OBSTACLE : DUET_LABEL_FLOOR;
  }
  duet_grid_update(grid, 0.0f, 0.0f, xyz.data(), 0, labels.data(), 0, labels.size(), nullptr);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  const int w = duet_grid_get_width(grid), h = duet_grid_get_height(grid);
  float ox = 0, oy = 0;
  duet_grid_get_origin(grid, &ox, &oy);
  std::vector<float> cells(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  duet_grid_copy_logodds(grid, cells.data(), cells.size());

  duet_planner copied = duet_planner_new(device_);
  duet_planner_set_grid(copied, cells.data(), 0, w, h, 0.05f, ox, oy, nullptr, nullptr);
  duet_planner_set_grid_from(planner_, grid, nullptr, nullptr);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  // The planner owns a copy: changing the grid afterwards changes nothing.
  duet_grid_update(grid, 0.0f, 0.0f, xyz.data(), 0, labels.data(), 0, labels.size() / 2, nullptr);
  const std::vector<duet::Pose2> poses = {{0.5f, 0.0f, 0.0f}, {1.0f, 0.5f, -1.0f}, {0.2f, -0.5f, 2.0f}};
  const Snapshot a = snapshot(device_, copied, poses, {0.5f, 0.0f, 0.0f}, {1.5f, -0.5f});
  const Snapshot b = snapshot(device_, planner_, poses, {0.5f, 0.0f, 0.0f}, {1.5f, -0.5f});
  expect_same(a, b);
  EXPECT_GT(std::count(a.traversable.begin(), a.traversable.end(), 1), 10);
  duet_planner_release(copied);
  duet_grid_release(grid);
}

TEST_F(PlannerTest, IncrementalUpdateEqualsAFreshPlanner) {
  for (const duet_observation_backend backend : {DUET_OBSERVATION_EMBREE, DUET_OBSERVATION_DDA}) {
    SCOPED_TRACE(backend == DUET_OBSERVATION_DDA ? "dda" : "embree");
    const auto os = obs_settings(backend);
    TestGrid g = door_room();
    set_grid(planner_, g, &os);
    // The robot "explores" through the door: the corridor behind it becomes known, a wall closes.
    g.fill(101, 80, 160, 120, kFreeL);
    g.fill(101, 79, 160, 80, kOccL);
    g.fill(101, 120, 160, 121, kOccL);
    g.fill(40, 70, 45, 90, kOccL);  // a new obstacle inside the room
    set_grid(planner_, g, &os);     // same geometry and settings: incremental
    duet_planner fresh = duet_planner_new(device_);
    set_grid(fresh, g, &os);
    ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
    const auto poses = random_poses(g, 16, 8);
    const Snapshot a = snapshot(device_, fresh, poses, {2.0f, 5.0f, 0.3f}, {7.0f, 5.0f});
    const Snapshot b = snapshot(device_, planner_, poses, {2.0f, 5.0f, 0.3f}, {7.0f, 5.0f});
    expect_same(a, b);
    EXPECT_EQ(a.path.status, DUET_PATH_FOUND);  // through the door into the new corridor
    // And the C++ kernel on the final grid agrees.
    const Reference ref(g, backend == DUET_OBSERVATION_DDA ? duet::ObservationBackend::kDda
                                                            : duet::ObservationBackend::kEmbree);
    std::vector<duet::RayObservation> expected(poses.size() * 60);
    ref.model.observe(poses, ref.sensors, expected);
    for (std::size_t i = 0; i < expected.size(); ++i) {
      ASSERT_TRUE(same_float(b.rays[i].entropy_bits, expected[i].entropy_bits)) << i;
    }
    // A different geometry (origin moved by one cell) rebuilds: same as fresh too.
    TestGrid moved = g;
    moved.ox = -0.05f;
    set_grid(planner_, moved, &os);
    set_grid(fresh, moved, &os);
    expect_same(snapshot(device_, fresh, poses, {2.0f, 5.0f, 0.3f}, {7.0f, 5.0f}),
                snapshot(device_, planner_, poses, {2.0f, 5.0f, 0.3f}, {7.0f, 5.0f}));
    duet_planner_release(fresh);
  }
}

TEST(CapiPlanner, OneAndTwoThreadsGiveIdenticalResults) {
  (void)duet_device_get_error(nullptr);
  std::vector<Snapshot> snaps;
  for (const char* config : {"threads=1", "threads=2"}) {
    duet_device d = duet_device_new(config);
    ASSERT_NE(d, nullptr);
    duet_planner p = duet_planner_new(d);
    for (int which = 0; which < 2; ++which) {
      const TestGrid g = which ? random_grid(13) : door_room();
      for (const duet_observation_backend backend : {DUET_OBSERVATION_DDA, DUET_OBSERVATION_EMBREE}) {
        const auto os = obs_settings(backend);
        set_grid(p, g, &os);
        const auto poses = random_poses(g, 64, 2);
        snaps.push_back(snapshot(d, p, poses, which ? duet::Pose2{1.0f, 1.0f, 0.0f} : duet::Pose2{2.0f, 5.0f, 3.1f},
                                 which ? Eigen::Vector2f(4.0f, 3.0f) : Eigen::Vector2f(4.5f, 3.8f)));
      }
    }
    duet_planner_release(p);
    duet_device_release(d);
  }
  ASSERT_EQ(snaps.size(), 8u);
  for (std::size_t i = 0; i < 4; ++i) {
    SCOPED_TRACE(i);
    expect_same(snaps[i], snaps[i + 4]);
  }
  EXPECT_EQ(snaps[0].sim.found, 1);
  EXPECT_EQ(snaps[0].path.status, DUET_PATH_FOUND);
  EXPECT_FALSE(snaps[0].dwa.empty());
  EXPECT_EQ(duet_device_get_error(nullptr), DUET_ERROR_NONE);
}

TEST_F(PlannerTest, OutputCapacityRule) {
  const TestGrid g = door_room();
  set_grid(planner_, g);
  // Full counts first, with no buffers at all.
  duet_frontier_result full;
  duet_planner_find_frontier(planner_, 2.0f, 5.0f, 0.0, nullptr, &full, nullptr, 0, nullptr, 0);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  ASSERT_EQ(full.status, DUET_FRONTIER_FOUND);
  ASSERT_GT(full.path_count, 4u);
  ASSERT_GE(full.cluster_count, 1u);
  std::vector<float> all(2 * full.path_count);
  std::vector<duet_frontier_cluster> all_clusters(full.cluster_count);
  duet_frontier_result again;
  duet_planner_find_frontier(planner_, 2.0f, 5.0f, 0.0, nullptr, &again, all.data(), full.path_count,
                             all_clusters.data(), all_clusters.size());
  EXPECT_EQ(std::memcmp(&again, &full, sizeof full), 0);
  // Too small: the first 3 points / 0 clusters are written, nothing beyond; counts are full.
  std::vector<float> small(2 * 3 + 2, -9.0f);
  duet_frontier_cluster one_cluster;
  std::memset(&one_cluster, 0x5A, sizeof one_cluster);
  const duet_frontier_cluster untouched = one_cluster;
  duet_frontier_result part;
  duet_planner_find_frontier(planner_, 2.0f, 5.0f, 0.0, nullptr, &part, small.data(), 3, &one_cluster, 0);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  EXPECT_EQ(part.path_count, full.path_count);
  EXPECT_EQ(part.cluster_count, full.cluster_count);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(small[static_cast<std::size_t>(i)], all[static_cast<std::size_t>(i)]);
  EXPECT_EQ(small[6], -9.0f);
  EXPECT_EQ(small[7], -9.0f);
  EXPECT_EQ(std::memcmp(&one_cluster, &untouched, sizeof one_cluster), 0);

  // plan_path
  duet_path_result pr;
  duet_planner_plan_path(planner_, 2.0f, 5.0f, 4.5f, 3.8f, nullptr, &pr, nullptr, 0);
  ASSERT_EQ(pr.status, DUET_PATH_FOUND);
  std::vector<float> pall(2 * pr.waypoint_count);
  duet_planner_plan_path(planner_, 2.0f, 5.0f, 4.5f, 3.8f, nullptr, &pr, pall.data(), pr.waypoint_count);
  std::vector<float> psmall(6, -9.0f);
  duet_path_result pr2;
  duet_planner_plan_path(planner_, 2.0f, 5.0f, 4.5f, 3.8f, nullptr, &pr2, psmall.data(), 2);
  EXPECT_EQ(pr2.waypoint_count, pr.waypoint_count);
  EXPECT_EQ(psmall[0], pall[0]);
  EXPECT_EQ(psmall[3], pall[3]);
  EXPECT_EQ(psmall[4], -9.0f);

  // simulate
  duet_partial_sim_result sr;
  duet_pose2 traj[3];
  for (auto& t : traj) t = {-9.0f, -9.0f, -9.0f};
  duet_planner_simulate(planner_, {2.0f, 5.0f, 3.14159f}, nullptr, &sr, traj, 2);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  EXPECT_EQ(sr.trajectory_count, 4u);
  EXPECT_NE(traj[1].x, -9.0f);
  EXPECT_EQ(traj[2].x, -9.0f);

  // sensors
  duet_sensor_sector one;
  EXPECT_EQ(duet_planner_get_sensors(planner_, &one, 1), 2u);
  EXPECT_EQ(duet_planner_get_sensors(planner_, nullptr, 0), 2u);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
}

TEST_F(PlannerTest, ConcurrentCallsOnOnePlannerAreSerialized) {
  const TestGrid a = door_room();
  TestGrid b = door_room();
  b.fill(40, 70, 45, 90, kOccL);
  set_grid(planner_, a);
  const auto poses = to_c(random_poses(a, 8, 1));
  std::vector<std::thread> threads;
  for (int t = 0; t < 3; ++t) {
    threads.emplace_back([&, t] {
      std::vector<duet_ray_observation> out(poses.size() * 60);
      for (int i = 0; i < 20; ++i) {
        if (t == 0) {
          set_grid(planner_, (i % 2) ? a : b);
        } else if (t == 1) {
          duet_planner_observe(planner_, poses.data(), poses.size(), out.data(), out.size());
        } else {
          duet_path_result pr;
          duet_planner_plan_path(planner_, 2.0f, 5.0f, 4.5f, 3.8f, nullptr, &pr, nullptr, 0);
          EXPECT_EQ(pr.status, DUET_PATH_FOUND);
          duet_planner_blacklist_add(planner_, 1.0f, 1.0f, 0.0, 1.0);
        }
      }
    });
  }
  for (auto& th : threads) th.join();
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
  EXPECT_EQ(duet_planner_blacklist_get_size(planner_), 20u);
}

}  // namespace duet_capi_planner_test
