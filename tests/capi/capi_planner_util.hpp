#pragma once
/// @file capi_planner_util.hpp
/// The planner tests' shared parts (capi_planner_*_test.cpp): test grids, the C++ reference
/// every C API result is compared with, whole-planner snapshots and the PlannerTest fixture.
#include "capi_helpers.hpp"

#include <duet/runtime/config/profile.hpp>

#include <duet/kernels/dwa.hpp>
#include <duet/kernels/exploration.hpp>
#include <duet/kernels/frontier.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/kernels/observation.hpp>
#include <duet/kernels/partial_sim.hpp>
#include <duet/kernels/path.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace duet_capi_planner_test {

using namespace duet_capi_test;

/// The built-in dual profile: where the C API's defaults come from.
inline const duet::Profile& dual_profile() {
  static const duet::Profile p = duet::builtin_profile("dual");
  return p;
}

inline constexpr float kFreeL = -2.0f;  // clamped free (GridUpdateSettings.min_logodds)
inline constexpr float kOccL = 3.5f;    // clamped occupied
inline const float kNaN = std::numeric_limits<float>::quiet_NaN();
inline const float kInf = std::numeric_limits<float>::infinity();

/// A w x h grid of log-odds, all unknown (as tests/kernels/test_partial_sim.cpp).
struct TestGrid {
  int w, h;
  float res = 0.05f;
  float ox = 0.0f, oy = 0.0f;
  std::vector<float> l;
  TestGrid(int w_, int h_) : w(w_), h(h_), l(static_cast<std::size_t>(w_) * static_cast<std::size_t>(h_), kNaN) {}
  float& at(int x, int y) { return l[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)]; }
  void fill(int x0, int y0, int x1, int y1, float v) {  // [x0, x1) x [y0, y1)
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) at(x, y) = v;
  }
  void room(int x0, int y0, int x1, int y1) {  // free interior, walls one cell thick
    fill(x0 - 1, y0 - 1, x1 + 1, y1 + 1, kOccL);
    fill(x0, y0, x1, y1, kFreeL);
  }
  [[nodiscard]] duet::GridView view() const { return duet::GridView(l, w, h, res, Eigen::Vector2f(ox, oy)); }
  [[nodiscard]] std::size_t cells() const { return l.size(); }
};

/// 10 m x 10 m: a 4 m x 4 m known room at [1, 5) x [3, 7) m with a 1 m door in its east wall
/// leading to the unknown (tests/kernels/test_partial_sim.cpp).
inline TestGrid door_room() {
  TestGrid g(200, 200);
  g.room(20, 60, 100, 140);
  for (int y = 90; y < 110; ++y) g.at(100, y) = kFreeL;
  return g;
}

/// 120 x 90 cells of 0.1 m at origin (-3, -2): unknown, free, occupied and in-between cells,
/// with a free corridor area so that paths and frontiers exist.
inline TestGrid random_grid(std::uint32_t seed) {
  TestGrid g(120, 90);
  g.res = 0.1f;
  g.ox = -3.0f;
  g.oy = -2.0f;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int y = 0; y < g.h; ++y) {
    for (int x = 0; x < g.w; ++x) {
      const float r = u(rng);
      const bool open = x > 10 && x < 90 && y > 10 && y < 70;
      float v;
      if (open) {
        v = r < 0.97f ? kFreeL : (r < 0.98f ? kOccL : -1.0f + 2.0f * u(rng));
      } else {
        v = r < 0.5f ? kNaN : (r < 0.75f ? kFreeL : (r < 0.9f ? kOccL : -1.0f + 2.0f * u(rng)));
      }
      g.at(x, y) = v;
    }
  }
  return g;
}

/// The C++ side of every comparison.
struct Reference {
  duet::ObservationModel model;
  duet::InflatedGrid inflated;
  std::vector<duet::SensorSector> sensors = duet::paper_dual_sensors(30);
  Reference(const TestGrid& g, duet::ObservationBackend backend = duet::ObservationBackend::kDda)
      : model([&] {
          duet::ObservationSettings os = dual_profile().exploration.observation;
          os.backend = backend;
          return os;
        }()) {
    model.set_grid(g.view());
    duet::inflate(g.view(), dual_profile().exploration.inflation, inflated);
  }
};

inline duet_observation_settings obs_settings(duet_observation_backend backend) {
  duet_observation_settings s;
  duet_observation_settings_init(&s);
  s.backend = backend;
  return s;
}

inline void set_grid(duet_planner p, const TestGrid& g, const duet_observation_settings* os = nullptr,
              const duet_inflation_settings* is = nullptr) {
  duet_planner_set_grid(p, g.l.data(), 0, g.w, g.h, g.res, g.ox, g.oy, os, is);
}

inline std::vector<duet::Pose2> random_poses(const TestGrid& g, std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> ux(g.ox, g.ox + static_cast<float>(g.w) * g.res);
  std::uniform_real_distribution<float> uy(g.oy, g.oy + static_cast<float>(g.h) * g.res);
  std::uniform_real_distribution<float> ut(-3.14159f, 3.14159f);
  std::vector<duet::Pose2> p(n);
  for (auto& x : p) x = {ux(rng), uy(rng), ut(rng)};
  return p;
}

inline std::vector<duet_pose2> to_c(const std::vector<duet::Pose2>& v) {
  std::vector<duet_pose2> out;
  for (const auto& p : v) out.push_back({p.x, p.y, p.theta});
  return out;
}

inline bool same_pose(const duet_pose2& a, const duet::Pose2& b) {
  return same_float(a.x, b.x) && same_float(a.y, b.y) && same_float(a.theta, b.theta);
}

/// Everything the planner can report for one robot pose, for whole-planner comparisons.
struct Snapshot {
  std::vector<duet_ray_observation> rays;
  float information = 0.0f;
  duet_partial_sim_result sim{};
  std::vector<duet_pose2> trajectory;
  duet_frontier_result frontier{};
  std::vector<float> frontier_path;
  std::vector<duet_frontier_cluster> clusters;
  duet_decision decision{};
  duet_path_result path{};
  std::vector<float> path_xy;
  std::vector<duet_dwa_result> dwa;
  std::vector<float> clearance;
  std::vector<std::uint8_t> traversable, frontier_mask;
};

inline ::testing::AssertionResult same_bytes(const void* a, const void* b, std::size_t n, const char* what) {
  if (std::memcmp(a, b, n) != 0) return ::testing::AssertionFailure() << what << " differ";
  return ::testing::AssertionSuccess();
}

template <class T>
inline ::testing::AssertionResult same_vec(const std::vector<T>& a, const std::vector<T>& b, const char* what) {
  if (a.size() != b.size()) return ::testing::AssertionFailure() << what << ": sizes " << a.size() << " vs " << b.size();
  if (a.empty()) return ::testing::AssertionSuccess();
  return same_bytes(a.data(), b.data(), a.size() * sizeof(T), what);
}

inline Snapshot snapshot(duet_device d, duet_planner p, const std::vector<duet::Pose2>& poses, const duet::Pose2& robot,
                  Eigen::Vector2f goal) {
  Snapshot s;
  const auto cp = to_c(poses);
  s.rays.resize(poses.size() * duet_planner_get_ray_count(p));
  duet_planner_observe(p, cp.data(), cp.size(), s.rays.data(), s.rays.size());
  const duet_pose2 r{robot.x, robot.y, robot.theta};
  s.information = duet_planner_information(p, r);
  s.trajectory.resize(16);
  duet_planner_simulate(p, r, nullptr, &s.sim, s.trajectory.data(), s.trajectory.size());
  s.frontier_path.resize(2 * 4096);
  s.clusters.resize(256);
  duet_planner_find_frontier(p, robot.x, robot.y, 0.0, nullptr, &s.frontier, s.frontier_path.data(), 4096,
                             s.clusters.data(), s.clusters.size());
  duet_planner_decide(p, r, 0.0, nullptr, &s.decision);
  s.path_xy.resize(2 * 4096);
  duet_planner_plan_path(p, robot.x, robot.y, goal.x(), goal.y(), nullptr, &s.path, s.path_xy.data(), 4096);
  duet_planner_dwa_reset(p);
  duet_pose2 x = r;
  duet_twist cur{0.0f, 0.0f};
  for (int i = 0; i < 10 && s.path.status == DUET_PATH_FOUND; ++i) {
    duet_dwa_result dr;
    duet_planner_dwa_step(p, x, cur, s.path_xy.data(), 0, s.path.waypoint_count, nullptr, &dr);
    s.dwa.push_back(dr);
    const duet::Pose2 nx = duet::motion_step({x.x, x.y, x.theta}, {dr.cmd.v, dr.cmd.omega}, 0.05f);
    x = {nx.x, nx.y, nx.theta};
    cur = dr.cmd;
  }
  int w = 0, h = 0;
  duet_planner_get_grid_size(p, &w, &h);
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  s.clearance.resize(n);
  s.traversable.resize(n);
  s.frontier_mask.resize(n);
  duet_planner_copy_clearance(p, s.clearance.data(), n);
  duet_planner_copy_traversable(p, s.traversable.data(), n);
  duet_planner_copy_frontier_mask(p, s.frontier_mask.data(), n);
  EXPECT_EQ(duet_device_get_error(d), DUET_ERROR_NONE) << duet_device_get_error_message(d);
  return s;
}

inline void expect_same(const Snapshot& a, const Snapshot& b) {
  EXPECT_TRUE(same_vec(a.rays, b.rays, "rays"));
  EXPECT_TRUE(same_float(a.information, b.information));
  EXPECT_TRUE(same_bytes(&a.sim, &b.sim, sizeof a.sim, "simulation"));
  EXPECT_TRUE(same_vec(a.trajectory, b.trajectory, "trajectory"));
  EXPECT_TRUE(same_bytes(&a.frontier, &b.frontier, sizeof a.frontier, "frontier"));
  EXPECT_TRUE(same_vec(a.frontier_path, b.frontier_path, "frontier path"));
  EXPECT_TRUE(same_vec(a.clusters, b.clusters, "clusters"));
  EXPECT_TRUE(same_bytes(&a.decision, &b.decision, sizeof a.decision, "decision"));
  EXPECT_TRUE(same_bytes(&a.path, &b.path, sizeof a.path, "path"));
  EXPECT_TRUE(same_vec(a.path_xy, b.path_xy, "path xy"));
  EXPECT_TRUE(same_vec(a.dwa, b.dwa, "dwa"));
  EXPECT_TRUE(same_vec(a.clearance, b.clearance, "clearance"));
  EXPECT_TRUE(same_vec(a.traversable, b.traversable, "traversable"));
  EXPECT_TRUE(same_vec(a.frontier_mask, b.frontier_mask, "frontier mask"));
}

class PlannerTest : public DeviceTest {
 protected:
  void SetUp() override {
    DeviceTest::SetUp();
    planner_ = duet_planner_new(device_);
    ASSERT_NE(planner_, nullptr) << duet_device_get_error_message(device_);
  }
  void TearDown() override {
    duet_planner_release(planner_);
    DeviceTest::TearDown();
  }
  duet_planner planner_ = nullptr;
};

}  // namespace duet_capi_planner_test
