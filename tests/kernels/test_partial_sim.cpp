// Procedure 1 (partial map simulation) on hand-made grids (partial_sim_test_util.hpp); the
// combined strategy of Fig. 6 is tested in test_exploration_decision.cpp.
#include <duet/kernels/entropy.hpp>
#include <duet/kernels/error.hpp>
#include <duet/kernels/exploration.hpp>
#include <duet/kernels/partial_sim.hpp>

#include "partial_sim_test_util.hpp"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <random>
#include <set>
#include <span>
#include <string>
#include <vector>

namespace duet {
namespace detail {
enum class PartialSimSamples { kAuto, kOneAtATime, kLanes };  // partial_sim_samples.hpp
extern PartialSimSamples partial_sim_samples;
bool partial_sim_lanes_available();
}  // namespace detail
namespace test_partial_sim {

TEST(PartialSim, DoorRoomGoalPointsToTheUnknownSide) {
  const TestGrid g = door_room();
  Prepared p(g);
  const Pose2 robot{2.0f, 5.0f, 3.14159f};
  const auto sensors = paper_dual_sensors(30);
  PartialSimWorkspace ws;
  PartialSimSettings s;
  const PartialSimResult r = partial_map_simulation(p.model, p.inflated, robot, sensors, s, ws);
  ASSERT_TRUE(r.found);
  EXPECT_GT(r.reward_bits, ExplorationSettings{}.eps_r_bits);
  // The robot starts facing west (away from the door, both sensors see known walls); at the goal
  // one of the two sensors faces the door (east) and sees more entropy than at the start.
  float best_cos = -1.0f;
  for (const SensorSector& sec : sensors) best_cos = std::max(best_cos, std::cos(r.goal.theta + sec.yaw_rad));
  EXPECT_GT(best_cos, 0.7f) << "goal " << r.goal.x << " " << r.goal.y << " " << r.goal.theta;
  EXPECT_GT(p.model.information_bits(r.goal, sensors), p.model.information_bits(robot, sensors));
  // Goal distance band (issue 3: 0.5-10 m).
  const float d = std::hypot(r.goal.x - robot.x, r.goal.y - robot.y);
  EXPECT_GE(d, s.min_goal_distance_m);
  EXPECT_LE(d, s.max_goal_distance_m);
  // The best rollout stays on traversable cells (re-simulated here with plain Eq. 4 steps).
  ASSERT_EQ(r.best_motions.size(), static_cast<std::size_t>(s.stages));
  Pose2 x = robot;
  const Eigen::Vector2i start = p.inflated.cell_of(Eigen::Vector2f(robot.x, robot.y));
  for (const Twist& u : r.best_motions) {
    for (int q = 0; q < 200; ++q) {
      x = motion_step(x, u, s.stage_dt_s / 200.0f);
      Eigen::Vector2i c;
      ASSERT_TRUE(p.inflated.cell_of(Eigen::Vector2f(x.x, x.y), c));
      if (c == start) continue;
      EXPECT_TRUE(p.inflated.traversable[p.inflated.index(c.x(), c.y())]) << "rollout crosses a blocked cell at " << x.x << "," << x.y;
    }
  }
  EXPECT_NEAR(x.x, r.goal.x, 1e-3f);
  EXPECT_NEAR(x.y, r.goal.y, 1e-3f);
  // Weights: normalised, and n_m has the largest.
  double sum = 0.0;
  for (float w : r.weights) sum += w;
  EXPECT_NEAR(sum, 1.0, 1e-6);
  ASSERT_GE(r.best_particle, 0);
  for (float w : r.weights) EXPECT_LE(w, r.weights[static_cast<std::size_t>(r.best_particle)]);
  EXPECT_GT(r.cells_visited, 0);
  EXPECT_GT(r.valid_particles, 0);
}

// The same decision, bit for bit: goal, particle, rewards, weights, resamples and visits.
void expect_same_result(const PartialSimResult& a, const PartialSimResult& b) {
  EXPECT_EQ(a.found, b.found);
  EXPECT_EQ(a.best_particle, b.best_particle);
  EXPECT_EQ(a.goal.x, b.goal.x);
  EXPECT_EQ(a.goal.y, b.goal.y);
  EXPECT_EQ(a.goal.theta, b.goal.theta);
  EXPECT_EQ(a.reward_bits, b.reward_bits);
  EXPECT_EQ(a.unknown_reward_bits, b.unknown_reward_bits);
  EXPECT_EQ(a.weights, b.weights);
  EXPECT_EQ(a.resamples, b.resamples);
  EXPECT_EQ(a.cells_visited, b.cells_visited);
}

TEST(PartialSim, SameResultWithOneAndTwoThreads) {
  const TestGrid g = door_room();
  Prepared p(g);
  const Pose2 robot{2.0f, 5.0f, 0.3f};
  const auto sensors = paper_dual_sensors(30);
  PartialSimSettings s;
  s.seed = 42;
  PartialSimResult r1, r2;
  tbb::task_arena(1).execute([&] {
    PartialSimWorkspace ws;
    r1 = partial_map_simulation(p.model, p.inflated, robot, sensors, s, ws);
  });
  tbb::task_arena(2).execute([&] {
    PartialSimWorkspace ws;
    r2 = partial_map_simulation(p.model, p.inflated, robot, sensors, s, ws);
    // and again with the same (warm) workspace
    const PartialSimResult r3 = partial_map_simulation(p.model, p.inflated, robot, sensors, s, ws);
    EXPECT_EQ(r3.weights, r2.weights);
  });
  expect_same_result(r1, r2);
  // A different seed gives a different (valid) answer.
  s.seed = 43;
  PartialSimWorkspace ws;
  const PartialSimResult r4 = partial_map_simulation(p.model, p.inflated, robot, sensors, s, ws);
  EXPECT_NE(r4.weights, r1.weights);
}

// The reference for the hand computations: f(ix, iy) for every cell each ray of the sensors'
// fans at pose x crosses, ray by ray (walk_cells, the reference DDA; cells outside the grid too).
template <class F>
void walk_fans(const TestGrid& g, const Pose2& x, std::span<const SensorSector> sensors, F f) {
  for (const SensorSector& sec : sensors) {
    std::vector<Eigen::Vector2f> o(static_cast<std::size_t>(sec.rays)), d(static_cast<std::size_t>(sec.rays));
    sector_rays(x, sec, o, d);
    for (std::size_t i = 0; i < o.size(); ++i)
      walk_cells(g.view(), o[i], d[i], sec.min_range_m, sec.max_range_m, [&](int ix, int iy, float, float) {
        f(ix, iy);
        return true;
      });
  }
}

// n 2 x 2 islands at random places of g (fixed seed); island i gets value(i).
template <class V>
void scatter_islands(TestGrid& g, unsigned seed, int n, V value) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> pos(0, 398);
  for (int i = 0; i < n; ++i) {
    const int x = pos(rng), y = pos(rng);
    g.fill(x, y, x + 2, y + 2, value(i));
  }
}

// One iteration, one particle, one observation sample, one 1 s stage straight ahead at 1 m/s,
// no l_ISM noise: the settings of the hand computations below.
PartialSimSettings one_straight_sample() {
  PartialSimSettings s;
  s.iterations = 1;
  s.particles = 1;
  s.phi_a = 0;
  s.phi_b = 1;
  s.stages = 1;
  s.v_min_mps = s.v_max_mps = 1.0f;
  s.omega_max_rps = 0.0f;
  s.ism_noise_logodds = 0.0f;
  return s;
}
// Lines 10-17 against a hand computation: one particle, one deterministic straight motion, one
// sample, no noise, every cell within sensor range known free at l = -0.4: the reward is the
// number of distinct cells the fans cross times E(-0.4) - E(-0.8).
TEST(PartialSim, RewardMatchesHandComputationOnKnownFreeCells) {
  TestGrid g(400, 400);
  g.fill(0, 0, 400, 400, -0.4f);
  Prepared p(g);
  const PartialSimSettings s = one_straight_sample();
  const Pose2 robot{10.0f, 10.0f, 0.7f};
  const auto sensors = paper_dual_sensors(30);
  PartialSimWorkspace ws;
  const PartialSimResult r = partial_map_simulation(p.model, p.inflated, robot, sensors, s, ws);
  ASSERT_TRUE(r.found);
  const Pose2 x1 = motion_step(robot, Twist{1.0f, 0.0f}, 1.0f);
  EXPECT_NEAR(r.goal.x, x1.x, 1e-5f);
  EXPECT_NEAR(r.goal.y, x1.y, 1e-5f);
  std::set<std::pair<int, int>> cells;
  walk_fans(g, x1, sensors, [&](int ix, int iy) { cells.insert({ix, iy}); });
  const double per_cell = static_cast<double>(entropy_bits(-0.4f)) - static_cast<double>(entropy_bits(-0.8f));
  EXPECT_NEAR(r.reward_bits, per_cell * static_cast<double>(cells.size()), 1e-3 * per_cell * static_cast<double>(cells.size()));
  EXPECT_EQ(r.unknown_reward_bits, 0.0f) << "every cell is known free: nothing new to see";
}

// R_g split by the cells' state against a hand computation: clamped free space with 2 x 2 islands
// of known-free cells at l = -0.4 and of never-observed cells (NaN) scattered over it (fixed seed,
// none within 1.5 m of the robot's path). With chi tiny every unknown cell is sampled free, so a
// crossed island cell adds E(-0.4) - E(-0.8) (known) or 1 - E(-0.4) (unknown); only the unknown
// ones count in unknown_reward_bits.
TEST(PartialSim, UnknownRewardCountsOnlyTheCellsOfUnknownState) {
  TestGrid g(400, 400);
  g.fill(0, 0, 400, 400, kFreeL);
  scatter_islands(g, 11, 800, [](int i) { return i % 2 == 0 ? -0.4f : kUnknown; });
  const Pose2 robot{10.02f, 9.97f, 0.7f};
  for (int y = 0; y < 400; ++y)
    for (int x = 0; x < 400; ++x)
      if (std::hypot((x + 0.5f) * 0.05f - 10.4f, (y + 0.5f) * 0.05f - 10.3f) < 2.0f) g.at(x, y) = kFreeL;
  Prepared p(g);
  PartialSimSettings s = one_straight_sample();
  s.unknown_hit_probability = 1e-9f;
  const auto sensors = paper_dual_sensors(30);
  PartialSimWorkspace ws;
  const PartialSimResult r = partial_map_simulation(p.model, p.inflated, robot, sensors, s, ws);
  ASSERT_TRUE(r.found);
  const Pose2 x1 = motion_step(robot, Twist{1.0f, 0.0f}, 1.0f);
  std::set<std::pair<int, int>> known, unknown;
  walk_fans(g, x1, sensors, [&](int ix, int iy) {
    if (!g.view().in_bounds(ix, iy)) return;
    const float l = g.at(ix, iy);
    if (std::isnan(l)) unknown.insert({ix, iy});
    else if (l == -0.4f) known.insert({ix, iy});
  });
  ASSERT_GT(known.size(), 10u) << "the fans must cross both kinds of island for this test to mean anything";
  ASSERT_GT(unknown.size(), 10u);
  const double per_known = static_cast<double>(entropy_bits(-0.4f)) - static_cast<double>(entropy_bits(-0.8f));
  const double per_unknown = 1.0 - static_cast<double>(entropy_bits(-0.4f));
  const double want_unknown = per_unknown * static_cast<double>(unknown.size());
  const double want_all = want_unknown + per_known * static_cast<double>(known.size());
  EXPECT_NEAR(r.unknown_reward_bits, want_unknown, 1e-3 * want_all);
  EXPECT_NEAR(r.reward_bits, want_all, 1e-3 * want_all);
  EXPECT_LT(r.unknown_reward_bits, r.reward_bits);
}

// The same hand computation where the walks jump: known free space at the clamp (reward exactly
// 0, skipped by the walks in block-sized jumps) with 2 x 2 islands of cells at l = -0.4 scattered
// over it (fixed seed). A jump must land exactly where the cell-by-cell walk would be: the reward
// counts every island cell the fans cross (walk_cells, the reference DDA), no more, no fewer.
TEST(PartialSim, JumpsOverClampedFreeSpaceMissNoCell) {
  for (const float theta : {0.7f, 0.0f, -1.1f, 2.6f}) {  // diagonal and axis-parallel fans
    TestGrid g(400, 400);
    g.fill(0, 0, 400, 400, kFreeL);
    scatter_islands(g, 5, 600, [](int) { return -0.4f; });
    Prepared p(g);
    const PartialSimSettings s = one_straight_sample();
    const Pose2 robot{10.02f, 9.97f, theta};
    const auto sensors = paper_dual_sensors(30);
    PartialSimWorkspace ws;
    const PartialSimResult r = partial_map_simulation(p.model, p.inflated, robot, sensors, s, ws);
    const Pose2 x1 = motion_step(robot, Twist{1.0f, 0.0f}, 1.0f);
    std::set<std::pair<int, int>> cells;  // distinct island cells crossed (the reward)
    std::int64_t crossings = 0;           // island cells crossed, ray by ray (the walks' visits)
    walk_fans(g, x1, sensors, [&](int ix, int iy) {
      if (g.view().in_bounds(ix, iy) && g.at(ix, iy) == -0.4f) {
        cells.insert({ix, iy});
        ++crossings;
      }
    });
    ASSERT_GT(cells.size(), 20u) << "the fans must cross islands for this test to mean anything";
    ASSERT_TRUE(r.found);
    EXPECT_EQ(r.cells_visited, crossings) << "theta " << theta;
    const double per_cell = static_cast<double>(entropy_bits(-0.4f)) - static_cast<double>(entropy_bits(-0.8f));
    EXPECT_NEAR(r.reward_bits, per_cell * static_cast<double>(cells.size()), 1e-3 * per_cell) << "theta " << theta;
  }
}

// The samples in AVX2 lanes (up to 8 at once) give the bits of one sample at a time: on the mixed
// grid of the test above and on a grid smaller than the rays (cells outside it), with
// more samples than lanes (groups), without l_ISM noise, and with hits so frequent that rays stop
// on cells other rays sampled occupied; 1 and 2 threads.
TEST(PartialSim, LanesGiveTheBitsOfOneSampleAtATime) {
  if (!detail::partial_sim_lanes_available()) GTEST_SKIP() << "no AVX2 on this CPU or build: the lanes are not used";
  struct Restore {
    ~Restore() { detail::partial_sim_samples = detail::PartialSimSamples::kAuto; }
  } restore;
  TestGrid mixed(400, 400);
  mixed.room(20, 20, 380, 380);
  scatter_islands(mixed, 5, 2500, [](int i) { return -0.4f * static_cast<float>(1 + i % 4); });
  scatter_islands(mixed, 6, 300, [](int i) { return i % 3 == 0 ? 0.2f : kUnknown; });
  scatter_islands(mixed, 7, 60, [](int) { return kOccL; });
  mixed.fill(110, 110, 130, 130, -1.2f);
  TestGrid small(120, 120);  // 6 m x 6 m: the 5 m rays from its middle leave it
  small.fill(10, 10, 110, 110, -1.2f);
  for (int i = 0; i < 12; ++i) small.fill(15 + 8 * i, 20 + 7 * (i % 5), 17 + 8 * i, 22 + 7 * (i % 5), i % 2 == 0 ? kUnknown : kOccL);
  struct Case {
    const char* name;
    const TestGrid grid;
    Pose2 robot;
  };
  const Case cases[] = {{"mixed", mixed, Pose2{6.0f, 6.0f, 0.4f}}, {"small grid, rays leave it", small, Pose2{3.0f, 3.0f, 0.5f}}};
  PartialSimSettings groups;  // phi_i = 5 i + 4: up to 29 samples, four groups of lanes
  groups.phi_a = 5;
  groups.phi_b = 4;
  PartialSimSettings no_noise;
  no_noise.ism_noise_logodds = 0.0f;
  PartialSimSettings hits;
  hits.unknown_hit_probability = 0.3f;
  const PartialSimSettings settings[] = {PartialSimSettings{}, groups, no_noise, hits};
  for (const Case& c : cases) {
    Prepared p(c.grid);
    for (std::size_t si = 0; si < std::size(settings); ++si)
      for (int threads : {1, 2}) {
        PartialSimSettings s = settings[si];
        s.seed = 7 + si;
        PartialSimResult one, lanes;
        tbb::task_arena(threads).execute([&] {
          PartialSimWorkspace ws;
          detail::partial_sim_samples = detail::PartialSimSamples::kOneAtATime;
          one = partial_map_simulation(p.model, p.inflated, c.robot, paper_dual_sensors(30), s, ws);
          detail::partial_sim_samples = detail::PartialSimSamples::kLanes;
          lanes = partial_map_simulation(p.model, p.inflated, c.robot, paper_dual_sensors(30), s, ws);  // same (warm) workspace
          detail::partial_sim_samples = detail::PartialSimSamples::kAuto;
        });
        SCOPED_TRACE(std::string(c.name) + ", settings " + std::to_string(si) + ", " + std::to_string(threads) + " threads");
        ASSERT_GT(one.valid_particles, 10) << "the rollouts must be valid for the test to mean anything";
        ASSERT_GT(one.reward_bits, 0.0f);
        expect_same_result(one, lanes);
        EXPECT_EQ(one.cells_stored, lanes.cells_stored);
      }
  }
}

TEST(PartialSim, EmbreeAndDdaModelsGiveTheSameDecision) {
  const TestGrid g = door_room();
  Prepared pd(g, ObservationBackend::kDda), pe(g, ObservationBackend::kEmbree);
  const auto sensors = paper_dual_sensors(30);
  PartialSimWorkspace w1, w2;
  const Pose2 robot{2.0f, 5.0f, 1.0f};
  const PartialSimResult a = partial_map_simulation(pd.model, pd.inflated, robot, sensors, PartialSimSettings{}, w1);
  const PartialSimResult b = partial_map_simulation(pe.model, pe.inflated, robot, sensors, PartialSimSettings{}, w2);
  EXPECT_EQ(a.weights, b.weights);
  EXPECT_EQ(a.goal.x, b.goal.x);
}

// Robot boxed in by obstacles: every rollout is rejected, nothing found, R_g = 0.
TEST(PartialSim, AllRolloutsRejectedGivesNoGoal) {
  TestGrid g(100, 100);
  g.room(40, 40, 52, 52);  // 0.6 m square: the inflated radius 0.2 m leaves ~no room to move 0.5 m
  Prepared p(g);
  PartialSimWorkspace ws;
  const PartialSimResult r =
      partial_map_simulation(p.model, p.inflated, Pose2{2.3f, 2.3f, 0.0f}, paper_dual_sensors(30), PartialSimSettings{}, ws);
  EXPECT_FALSE(r.found);
  EXPECT_EQ(r.reward_bits, 0.0f);
  EXPECT_EQ(r.valid_particles, 0);
  EXPECT_EQ(r.goal.x, 2.3f);
}

TEST(PartialSim, SettingsThatWouldTakeMinutesAreRefusedByTheBudgets) {
  // Each passed validation and made one call take minutes (issue 19): a tiny collision step, a
  // huge particle count. The budgets name the product they bound.
  auto message = [](const PartialSimSettings& s) {
    try {
      validate(s);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  PartialSimSettings s;
  EXPECT_EQ(message(s), "");
  s.collision_step_m = 1e-9f;
  EXPECT_NE(message(s).find("rollout sub-steps per stage, more than the budget"), std::string::npos) << message(s);
  s.collision_step_m = 0.0001f;  // 5000 sub-steps: within the budget
  EXPECT_EQ(message(s), "");
  s = {};
  s.particles = 100000;
  s.iterations = 10;
  EXPECT_NE(message(s).find("simulated observations per decision"), std::string::npos) << message(s);
  s = {};
  s.particles = 12500;  // 12500 * 20 * 4 = 1e6: exactly the budget
  EXPECT_EQ(message(s), "");
  // Speeds within a robot's (fuzz_capi: speeds near 3e38 made the rollouts' poses NaN).
  s = {};
  s.v_max_mps = 3e38f;
  EXPECT_NE(message(s).find("v_min_mps/v_max_mps"), std::string::npos) << message(s);
  s = {};
  s.v_min_mps = -3e38f;
  EXPECT_NE(message(s).find("v_min_mps/v_max_mps"), std::string::npos) << message(s);
  s = {};
  s.omega_max_rps = 1e30f;
  EXPECT_NE(message(s).find("omega_max_rps"), std::string::npos) << message(s);
  s = {};
  s.sigma_omega_rps = 1e30f;
  EXPECT_NE(message(s).find("sigma_omega_rps"), std::string::npos) << message(s);
  s = {};
  s.v_min_mps = -5.0f;  // backwards at 5 m/s: within the speeds, 200 sub-steps at 2.5 cm
  EXPECT_EQ(message(s), "");
}

TEST(PartialSim, TheCellBudgetIsCheckedWithTheSensorsAndTheGrid) {
  // 12500 particles pass validate() (1e6 simulated observations), but with 60 rays of 5 m on a
  // 5 cm grid they would walk 1.2e10 cells: refused at the call, naming the budget.
  const TestGrid g = door_room();
  Prepared p(g);
  const auto sensors = paper_dual_sensors(30);
  PartialSimWorkspace ws;
  PartialSimSettings s;
  s.particles = 12500;
  EXPECT_NO_THROW(validate(s));
  try {
    (void)partial_map_simulation(p.model, p.inflated, Pose2{2.0f, 5.0f, 0.0f}, sensors, s, ws);
    ADD_FAILURE() << "1.2e10 cell visits accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("cell visits per call"), std::string::npos) << e.what();
  }
  s.particles = 1000;  // 9.7e8 cells: within it
  EXPECT_NO_THROW((void)partial_map_simulation(p.model, p.inflated, Pose2{2.0f, 5.0f, 0.0f}, sensors, s, ws));
}

TEST(PartialSim, InvalidInputsThrow) {
  const TestGrid g = door_room();
  Prepared p(g);
  const auto sensors = paper_dual_sensors(30);
  PartialSimWorkspace ws;
  const Pose2 robot{2.0f, 5.0f, 0.0f};
  auto expect_throw = [&](PartialSimSettings s) {
    EXPECT_THROW((void)partial_map_simulation(p.model, p.inflated, robot, sensors, s, ws), Error);
  };
  PartialSimSettings s;
  s.iterations = 0;
  expect_throw(s);
  s = {};
  s.particles = 0;
  expect_throw(s);
  s = {};
  s.phi_a = -1;  // phi_1 = 0
  s.phi_b = 1;
  expect_throw(s);
  s = {};
  s.gamma = std::nanf("");
  expect_throw(s);
  s = {};
  s.unknown_hit_probability = 1.0f;
  expect_throw(s);
  s = {};
  s.ism_noise_logodds = 0.5f;  // would flip a miss (-0.4) into a hit
  expect_throw(s);
  s = {};
  s.max_goal_distance_m = 0.1f;
  expect_throw(s);
  EXPECT_THROW((void)partial_map_simulation(p.model, p.inflated, Pose2{std::nanf(""), 0.0f, 0.0f}, sensors, {}, ws), Error);
  EXPECT_THROW((void)partial_map_simulation(p.model, p.inflated, robot, std::span<const SensorSector>{}, {}, ws), Error);
  InflatedGrid other;
  TestGrid small(10, 10);
  inflate(small.view(), InflationSettings{}, other);
  EXPECT_THROW((void)partial_map_simulation(p.model, other, robot, sensors, {}, ws), Error);
  ExplorationSettings es;
  es.eps_r_bits = -1.0f;
  EXPECT_THROW(validate(es), Error);
}

}  // namespace test_partial_sim
}  // namespace duet
