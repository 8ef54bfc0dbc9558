// The exploration planner through the C API (duet.h, "Exploration planner"): every result equals
// the C++ kernels' on the same inputs (a room with a door, a random grid with a fixed seed),
// strided rows equal packed rows, a duet_grid equals its copied cells, an incremental grid
// update equals a fresh planner, 1 and 2 device threads give identical results, the output
// capacity rule, and misuse (NULL / released / wrong-kind handles, NULL buffers, wrong counts,
// bad settings and enum values, calls before set_grid, NaN poses) gives the documented error
// codes without crashing (also run under AddressSanitizer).
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

using namespace duet_capi_test;

namespace {

/// The built-in dual profile: where the C API's defaults come from.
const duet::Profile& dual_profile() {
  static const duet::Profile p = duet::builtin_profile("dual");
  return p;
}

}  // namespace

namespace {

constexpr float kFreeL = -2.0f;  // clamped free (GridUpdateSettings.min_logodds)
constexpr float kOccL = 3.5f;    // clamped occupied
const float kNaN = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();

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
TestGrid door_room() {
  TestGrid g(200, 200);
  g.room(20, 60, 100, 140);
  for (int y = 90; y < 110; ++y) g.at(100, y) = kFreeL;
  return g;
}

/// 120 x 90 cells of 0.1 m at origin (-3, -2): unknown, free, occupied and in-between cells,
/// with a free corridor area so that paths and frontiers exist.
TestGrid random_grid(std::uint32_t seed) {
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

duet_observation_settings obs_settings(duet_observation_backend backend) {
  duet_observation_settings s;
  duet_observation_settings_init(&s);
  s.backend = backend;
  return s;
}

void set_grid(duet_planner p, const TestGrid& g, const duet_observation_settings* os = nullptr,
              const duet_inflation_settings* is = nullptr) {
  duet_planner_set_grid(p, g.l.data(), 0, g.w, g.h, g.res, g.ox, g.oy, os, is);
}

std::vector<duet::Pose2> random_poses(const TestGrid& g, std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> ux(g.ox, g.ox + static_cast<float>(g.w) * g.res);
  std::uniform_real_distribution<float> uy(g.oy, g.oy + static_cast<float>(g.h) * g.res);
  std::uniform_real_distribution<float> ut(-3.14159f, 3.14159f);
  std::vector<duet::Pose2> p(n);
  for (auto& x : p) x = {ux(rng), uy(rng), ut(rng)};
  return p;
}

std::vector<duet_pose2> to_c(const std::vector<duet::Pose2>& v) {
  std::vector<duet_pose2> out;
  for (const auto& p : v) out.push_back({p.x, p.y, p.theta});
  return out;
}

bool same_pose(const duet_pose2& a, const duet::Pose2& b) {
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

::testing::AssertionResult same_bytes(const void* a, const void* b, std::size_t n, const char* what) {
  if (std::memcmp(a, b, n) != 0) return ::testing::AssertionFailure() << what << " differ";
  return ::testing::AssertionSuccess();
}

template <class T>
::testing::AssertionResult same_vec(const std::vector<T>& a, const std::vector<T>& b, const char* what) {
  if (a.size() != b.size()) return ::testing::AssertionFailure() << what << ": sizes " << a.size() << " vs " << b.size();
  if (a.empty()) return ::testing::AssertionSuccess();
  return same_bytes(a.data(), b.data(), a.size() * sizeof(T), what);
}

Snapshot snapshot(duet_device d, duet_planner p, const std::vector<duet::Pose2>& poses, const duet::Pose2& robot,
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

void expect_same(const Snapshot& a, const Snapshot& b) {
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

// ---- settings -------------------------------------------------------------------------------

// The C defaults are the built-in dual profile's (the values duet explore and duet_runtime run with).
TEST(CapiPlannerSettings, InitFunctionsMirrorTheBuiltInProfile) {
  duet_sensor_sector ss;
  duet_sensor_sector_init(&ss);
  const duet::SensorSector css;
  EXPECT_EQ(ss.x_m, css.x_m);
  EXPECT_EQ(ss.y_m, css.y_m);
  EXPECT_EQ(ss.yaw_rad, css.yaw_rad);
  EXPECT_EQ(ss.fov_rad, css.fov_rad);
  EXPECT_EQ(ss.min_range_m, css.min_range_m);
  EXPECT_EQ(ss.max_range_m, css.max_range_m);
  EXPECT_EQ(ss.rays, css.rays);

  duet_sensor_sector dual[2];
  duet_paper_dual_sensors(dual, 17);
  const auto cdual = duet::paper_dual_sensors(17);
  ASSERT_EQ(cdual.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(dual[i].x_m, cdual[i].x_m);
    EXPECT_EQ(dual[i].y_m, cdual[i].y_m);
    EXPECT_EQ(dual[i].yaw_rad, cdual[i].yaw_rad);
    EXPECT_EQ(dual[i].fov_rad, cdual[i].fov_rad);
    EXPECT_EQ(dual[i].min_range_m, cdual[i].min_range_m);
    EXPECT_EQ(dual[i].max_range_m, cdual[i].max_range_m);
    EXPECT_EQ(dual[i].rays, 17);
  }

  duet_observation_settings os;
  duet_observation_settings_init(&os);
  const duet::ObservationSettings& cos = dual_profile().exploration.observation;
  EXPECT_EQ(os.thresholds.occupied_logodds, cos.thresholds.occupied_logodds);
  EXPECT_EQ(os.thresholds.free_logodds, cos.thresholds.free_logodds);
  EXPECT_EQ(static_cast<int>(os.backend), static_cast<int>(cos.backend));  // same numbering
  EXPECT_EQ(os.tile_cells, cos.tile_cells);

  duet_inflation_settings is;
  duet_inflation_settings_init(&is);
  const duet::InflationSettings& cis = dual_profile().exploration.inflation;
  EXPECT_EQ(is.thresholds.occupied_logodds, cis.thresholds.occupied_logodds);
  EXPECT_EQ(is.thresholds.free_logodds, cis.thresholds.free_logodds);
  EXPECT_EQ(is.robot_radius_m, cis.robot_radius_m);
  EXPECT_EQ(is.unknown_is_obstacle, cis.unknown_is_obstacle ? 1 : 0);
  EXPECT_EQ(is.uncertain_is_obstacle, cis.uncertain_is_obstacle ? 1 : 0);
  EXPECT_EQ(is.uncertain_is_obstacle, 1);

  duet_path_settings ps;
  duet_path_settings_init(&ps);
  const duet::PathSettings& cps = dual_profile().exploration.path;
  EXPECT_EQ(ps.allow_diagonal, cps.allow_diagonal ? 1 : 0);
  EXPECT_EQ(ps.clearance_weight, cps.clearance_weight);
  EXPECT_EQ(ps.clearance_decay_m, cps.clearance_decay_m);
  EXPECT_EQ(ps.goal_tolerance_m, cps.goal_tolerance_m);

  duet_frontier_settings fs;
  duet_frontier_settings_init(&fs);
  const duet::FrontierSettings& cfs = dual_profile().exploration.strategy.frontier;
  EXPECT_EQ(fs.min_cluster_cells, cfs.min_cluster_cells);
  EXPECT_EQ(fs.min_goal_distance_m, cfs.min_goal_distance_m);
  EXPECT_EQ(fs.blacklist_radius_m, cfs.blacklist_radius_m);
  EXPECT_EQ(fs.approach_radius_m, cfs.approach_radius_m);
  EXPECT_EQ(fs.min_unknown_region_m2, cfs.min_unknown_region_m2);

  duet_partial_sim_settings sim;
  duet_partial_sim_settings_init(&sim);
  const duet::PartialSimSettings& csim = dual_profile().exploration.strategy.simulation;
  EXPECT_EQ(sim.iterations, csim.iterations);
  EXPECT_EQ(sim.particles, csim.particles);
  EXPECT_EQ(sim.phi_a, csim.phi_a);
  EXPECT_EQ(sim.phi_b, csim.phi_b);
  EXPECT_EQ(sim.stages, csim.stages);
  EXPECT_EQ(sim.stage_dt_s, csim.stage_dt_s);
  EXPECT_EQ(sim.v_min_mps, csim.v_min_mps);
  EXPECT_EQ(sim.v_max_mps, csim.v_max_mps);
  EXPECT_EQ(sim.omega_max_rps, csim.omega_max_rps);
  EXPECT_EQ(sim.sigma_v_mps, csim.sigma_v_mps);
  EXPECT_EQ(sim.sigma_omega_rps, csim.sigma_omega_rps);
  EXPECT_EQ(sim.resample_ess_fraction, csim.resample_ess_fraction);
  EXPECT_EQ(sim.gamma, csim.gamma);
  EXPECT_EQ(sim.unknown_hit_probability, csim.unknown_hit_probability);
  EXPECT_EQ(sim.hit_logodds, csim.hit_logodds);
  EXPECT_EQ(sim.miss_logodds, csim.miss_logodds);
  EXPECT_EQ(sim.ism_noise_logodds, csim.ism_noise_logodds);
  EXPECT_EQ(sim.min_logodds, csim.min_logodds);
  EXPECT_EQ(sim.max_logodds, csim.max_logodds);
  EXPECT_EQ(sim.min_goal_distance_m, csim.min_goal_distance_m);
  EXPECT_EQ(sim.max_goal_distance_m, csim.max_goal_distance_m);
  EXPECT_EQ(sim.collision_step_m, csim.collision_step_m);
  EXPECT_EQ(sim.seed, csim.seed);

  duet_exploration_settings es;
  duet_exploration_settings_init(&es);
  const duet::ExplorationSettings& ces = dual_profile().exploration.strategy;
  EXPECT_EQ(es.eps_r_bits, ces.eps_r_bits);
  EXPECT_EQ(es.use_simulation, ces.use_simulation ? 1 : 0);
  EXPECT_EQ(es.simulation.particles, ces.simulation.particles);
  EXPECT_EQ(es.simulation.seed, ces.simulation.seed);
  EXPECT_EQ(es.frontier.min_cluster_cells, ces.frontier.min_cluster_cells);
  EXPECT_EQ(es.frontier.blacklist_radius_m, ces.frontier.blacklist_radius_m);
  EXPECT_EQ(es.frontier.approach_radius_m, ces.frontier.approach_radius_m);

  duet_dwa_settings ds;
  duet_dwa_settings_init(&ds);
  const duet::DwaSettings& cds = dual_profile().exploration.dwa;
  EXPECT_EQ(ds.limits.max_v_mps, cds.limits.max_v_mps);
  EXPECT_EQ(ds.limits.min_v_mps, cds.limits.min_v_mps);
  EXPECT_EQ(ds.limits.max_omega_rps, cds.limits.max_omega_rps);
  EXPECT_EQ(ds.limits.max_accel_mps2, cds.limits.max_accel_mps2);
  EXPECT_EQ(ds.limits.max_alpha_rps2, cds.limits.max_alpha_rps2);
  EXPECT_EQ(ds.mapping_max_omega_rps, cds.mapping_max_omega_rps);
  EXPECT_EQ(ds.mapping_max_alpha_rps2, cds.mapping_max_alpha_rps2);
  EXPECT_EQ(ds.control_period_s, cds.control_period_s);
  EXPECT_EQ(ds.v_samples, cds.v_samples);
  EXPECT_EQ(ds.omega_samples, cds.omega_samples);
  EXPECT_EQ(ds.steps, cds.steps);
  EXPECT_EQ(ds.sim_time_s, cds.sim_time_s);
  EXPECT_EQ(ds.robot_radius_m, cds.robot_radius_m);
  EXPECT_EQ(ds.safety_margin_m, cds.safety_margin_m);
  EXPECT_EQ(ds.w_progress, cds.w_progress);
  EXPECT_EQ(ds.w_path, cds.w_path);
  EXPECT_EQ(ds.w_clearance, cds.w_clearance);
  EXPECT_EQ(ds.w_speed, cds.w_speed);
  EXPECT_EQ(ds.clearance_cap_m, cds.clearance_cap_m);
  EXPECT_EQ(ds.lookahead_m, cds.lookahead_m);
  EXPECT_EQ(ds.goal_tolerance_m, cds.goal_tolerance_m);
  EXPECT_EQ(ds.oscillation_window_calls, cds.oscillation_window_calls);
  EXPECT_EQ(ds.oscillation_min_progress_m, cds.oscillation_min_progress_m);
  EXPECT_EQ(ds.oscillation_min_turn_rad, cds.oscillation_min_turn_rad);
  EXPECT_EQ(ds.recovery_max_calls, cds.recovery_max_calls);
  EXPECT_EQ(ds.rotate_omega_rps, cds.rotate_omega_rps);
  EXPECT_EQ(ds.rotate_tolerance_rad, cds.rotate_tolerance_rad);
  EXPECT_EQ(ds.backoff_distance_m, cds.backoff_distance_m);
  EXPECT_EQ(ds.backoff_speed_mps, cds.backoff_speed_mps);

  // NULL is ignored.
  duet_sensor_sector_init(nullptr);
  duet_observation_settings_init(nullptr);
  duet_inflation_settings_init(nullptr);
  duet_path_settings_init(nullptr);
  duet_frontier_settings_init(nullptr);
  duet_partial_sim_settings_init(nullptr);
  duet_exploration_settings_init(nullptr);
  duet_dwa_settings_init(nullptr);
}

TEST(CapiPlannerSettings, StatusStrings) {
  EXPECT_STREQ(duet_path_status_string(DUET_PATH_FOUND), "DUET_PATH_FOUND");
  EXPECT_STREQ(duet_path_status_string(DUET_PATH_OUTSIDE_GRID), "DUET_PATH_OUTSIDE_GRID");
  EXPECT_STREQ(duet_frontier_status_string(DUET_FRONTIER_ALL_BLACKLISTED), "DUET_FRONTIER_ALL_BLACKLISTED");
  EXPECT_STREQ(duet_exploration_status_string(DUET_EXPLORATION_SIMULATED_GOAL), "DUET_EXPLORATION_SIMULATED_GOAL");
  EXPECT_STREQ(duet_exploration_status_string(DUET_EXPLORATION_ROBOT_BLOCKED), "DUET_EXPLORATION_ROBOT_BLOCKED");
  EXPECT_STREQ(duet_dwa_status_string(DUET_DWA_NO_PATH), "DUET_DWA_NO_PATH");
  // Values that are not enumerators. C code may pass any int; from C++ only values inside the
  // enums' value range (0..7 here: 3 bits) can be passed without undefined behaviour (and the
  // sanitizer build checks that), so the out-of-enumerator values tested are 5/6..7.
  for (int v = 5; v <= 7; ++v) {
    EXPECT_STREQ(duet_path_status_string(static_cast<duet_path_status>(v)), "DUET_PATH_?");
    EXPECT_STREQ(duet_frontier_status_string(static_cast<duet_frontier_status>(v)), "DUET_FRONTIER_?");
  }
  for (int v = 6; v <= 7; ++v) {
    EXPECT_STREQ(duet_exploration_status_string(static_cast<duet_exploration_status>(v)), "DUET_EXPLORATION_?");
    EXPECT_STREQ(duet_dwa_status_string(static_cast<duet_dwa_status>(v)), "DUET_DWA_?");
  }
  // Each enumerator has its own name.
  for (int v = 0; v <= 5; ++v) {
    EXPECT_STRNE(duet_exploration_status_string(static_cast<duet_exploration_status>(v)), "DUET_EXPLORATION_?");
    EXPECT_STRNE(duet_dwa_status_string(static_cast<duet_dwa_status>(v)), "DUET_DWA_?");
  }
  for (int v = 0; v <= 4; ++v) {
    EXPECT_STRNE(duet_path_status_string(static_cast<duet_path_status>(v)), "DUET_PATH_?");
    EXPECT_STRNE(duet_frontier_status_string(static_cast<duet_frontier_status>(v)), "DUET_FRONTIER_?");
  }
}

// ---- equivalence with the C++ kernels -------------------------------------------------------

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

// ---- misuse ---------------------------------------------------------------------------------

namespace {

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

}  // namespace

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

}  // namespace
