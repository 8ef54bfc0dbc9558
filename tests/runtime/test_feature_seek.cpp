// The controller's feature seeking (feature_seek.hpp): the speed cap and the turn towards
// surfaces, against their rules on hand-made grids; and in the loop, a corridor of plain walls
// (profiles/worlds/blank_corridor.yaml): health falls, the robot slows and turns, the wheels carry
// the pose with no jump, nothing collides, and the far room is explored.
#include <duet/kernels/error.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/navigation/feature_seek.hpp>
#include <duet/sim/sim_explore.hpp>
#include <duet/sim/world.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <string>
#include <vector>

namespace duet {
namespace test_feature_seek {

/// A 10 x 10 m free planning grid (0.05 m cells) with the robot at its centre, and an occupied
/// wall cell run at (x, y0..y1) when asked.
InflatedGrid free_grid() {
  InflatedGrid g;
  g.resolution_m = 0.05f;
  g.width = g.height = 200;
  g.clearance_m.assign(200 * 200, INFINITY);
  g.traversable.assign(200 * 200, 1);
  g.state.assign(200 * 200, CellState::kFree);
  return g;
}

void wall(InflatedGrid& g, float x0, float y0, float x1, float y1) {
  for (float t = 0.0f; t <= 1.0f; t += 0.002f) {
    const Eigen::Vector2i c = g.cell_of(Eigen::Vector2f(x0 + t * (x1 - x0), y0 + t * (y1 - y0)));
    if (g.in_bounds(c.x(), c.y())) g.state[g.index(c.x(), c.y())] = CellState::kOccupied;
  }
}

DwaSettings dwa() {
  DwaSettings ds;
  ds.limits.max_v_mps = 0.5f;
  ds.mapping_max_omega_rps = 0.6f;
  ds.mapping_max_alpha_rps2 = 2.0f;
  ds.control_period_s = 0.05f;
  return ds;
}

constexpr float kPi = std::numbers::pi_v<float>;

TEST(FeatureSeek, NothingWithoutVisionOrWhileHealthIsGood) {
  FeatureSeek seek{ExplorerSettings{}};
  const InflatedGrid g = free_grid();
  const Pose2 robot{5.0f, 5.0f, 0.0f};
  for (double t = 0.0; t < 30.0; t += 0.05) {
    seek.set_health(t < 15.0 ? std::nullopt : std::optional(LocalizationHealth::kGood), t);
    EXPECT_FALSE(seek.step(robot, Twist{}, g, dwa(), t));
    EXPECT_EQ(seek.speed_limit(0.5f), 0.5f);
  }
  EXPECT_EQ(seek.seeks(), 0);
}

TEST(FeatureSeek, SlowsAtOnceThenTurnsTowardsTheNearestSurface) {
  ExplorerSettings s;  // few_features_speed_mps 0.15, seek_after_s 1, range [0.6, 3.5] m
  FeatureSeek seek{s};
  InflatedGrid g = free_grid();
  wall(g, 2.0f, 7.0f, 9.0f, 7.0f);  // 2 m to the left (north) of a robot facing east
  wall(g, 2.0f, 1.0f, 9.0f, 1.0f);  // 4 m to the right: beyond seek_range_m
  Pose2 robot{5.0f, 5.0f, 0.0f};
  seek.set_health(LocalizationHealth::kDegraded, 10.0);
  EXPECT_FLOAT_EQ(seek.speed_limit(0.5f), 0.15f);
  EXPECT_FLOAT_EQ(seek.speed_limit(0.1f), 0.1f);  // never raises a lower limit
  EXPECT_FALSE(seek.step(robot, Twist{}, g, dwa(), 10.5));  // not yet seek_after_s
  // The nearest turn that looks at the wall within range: 30 deg left reaches y = 7 at 4 m (too
  // far), 45 deg at 2.8 m.
  EXPECT_NEAR(seek.seek_heading(robot, g), kPi / 4, 1e-5f);
  Twist cmd;
  int periods = 0;
  for (double t = 11.0; periods < 200; t += 0.05, ++periods) {
    seek.set_health(LocalizationHealth::kDegraded, t);
    const auto turn = seek.step(robot, cmd, g, dwa(), t);
    if (!turn) break;
    EXPECT_EQ(turn->v, 0.0f);  // in place
    EXPECT_GT(turn->omega, 0.0f);
    EXPECT_LE(turn->omega, 0.6f + 1e-6f);
    cmd = *turn;
    robot.theta += cmd.omega * 0.05f;
  }
  EXPECT_LT(periods, 200) << "the turn never ended";
  EXPECT_NEAR(robot.theta, kPi / 4, 0.1f);
  EXPECT_EQ(seek.seeks(), 1);
  // The cooldown (15 s): no second turn at once, though the health is still degraded.
  EXPECT_FALSE(seek.step(robot, Twist{}, g, dwa(), 20.0));
  EXPECT_TRUE(seek.step(robot, Twist{}, g, dwa(), 11.0 + 0.05 * periods + 15.1));
  EXPECT_EQ(seek.seeks(), 2);
}

TEST(FeatureSeek, TheTurnEndsWhenFeaturesAreBack) {
  FeatureSeek seek{ExplorerSettings{}};
  const InflatedGrid g = free_grid();  // nothing in range: a quarter turn left
  const Pose2 robot{5.0f, 5.0f, 1.0f};
  EXPECT_NEAR(seek.seek_heading(robot, g), 1.0f + kPi / 2, 1e-5f);
  seek.set_health(LocalizationHealth::kLost, 0.0);
  ASSERT_TRUE(seek.step(robot, Twist{}, g, dwa(), 1.5));
  EXPECT_TRUE(seek.turning());
  seek.set_health(LocalizationHealth::kGood, 1.6);
  EXPECT_FALSE(seek.turning());
  EXPECT_FALSE(seek.step(robot, Twist{}, g, dwa(), 1.6));
  EXPECT_EQ(seek.speed_limit(0.5f), 0.5f);
}

TEST(FeatureSeek, SettingsOutOfRangeAreNamed) {
  ExplorerSettings s;
  s.seek_min_range_m = 5.0f;  // beyond seek_range_m
  try {
    validate(s);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("seek_min_range_m"), std::string::npos) << e.what();
  }
  s = {};
  s.few_features_speed_mps = -1.0f;
  EXPECT_THROW(validate(s), Error);
  s = {};
  s.seek_after_s = NAN;
  EXPECT_THROW(validate(s), Error);
}

// In the loop: vision on, scan matching off (the odometry alone is measured), the corridor world.
TEST(FeatureSeek, ABlankCorridorSlowsAndTurnsTheRobotAndTheWheelsCarryThePose) {
  sim::ExploreSettings st;
  st.runtime = builtin_profile("dual_kinect_kobuki").runtime;
  st.seed = 5;
  st.max_time_s = 150.0;
  st.sensor_rate_hz = 5.0;
  st.runtime.pose_correction.enabled = false;
  st.runtime.visual_odometry.enabled = true;
  sim::SimExplore run(sim::resolve_world(DUET_SOURCE_DIR "/profiles/worlds/blank_corridor.yaml"),
                      builtin_profile("dual_kinect_kobuki"), st);
  std::map<std::string, int> health_in_corridor;
  double max_speed_not_good = 0.0;
  bool reached_east_room = false;
  double reached_at = 0.0;
  std::vector<bool> good_at;  // per estimated pose: vision was good when it was taken
  while (run.step()) {
    const auto h = run.runtime().localization_health();
    good_at.resize(run.estimated_trajectory().size(), h && *h == LocalizationHealth::kGood);
    const Pose2 truth = run.chassis().true_pose();
    if (h && truth.x > 5.0f && truth.x < 9.0f) ++health_in_corridor[to_string(*h)];
    if (!reached_east_room && truth.x > 10.5f) reached_east_room = true, reached_at = run.now_s();
    if (h && *h != LocalizationHealth::kGood) max_speed_not_good = std::max(max_speed_not_good, std::fabs(double(run.runtime().last_command().v)));
    // Through the corridor and 10 s into the room beyond it: what this test is about is over.
    if (reached_east_room && run.now_s() > reached_at + 10.0) run.interrupt("through the corridor");
  }
  const auto s = run.summary();
  std::printf("corridor: the east room reached at %.1f s, the run stopped at %.1f s\n", reached_at, s.sim_time_s);
  std::printf("corridor: health in the corridor good %d degraded %d lost %d; seeks %d, capped periods %d; "
              "pose error max %.3f m; coverage %.1f %%\n",
              health_in_corridor["good"], health_in_corridor["degraded"], health_in_corridor["lost"], s.explorer.feature_seeks,
              s.explorer.few_feature_periods, s.pose_error_max_m, 100.0 * s.coverage);
  EXPECT_GT(health_in_corridor["degraded"] + health_in_corridor["lost"], 0) << "health never fell in the corridor";
  EXPECT_GT(s.explorer.feature_seeks, 0);
  EXPECT_GT(s.explorer.few_feature_periods, 0);
  EXPECT_LE(max_speed_not_good, 0.15 + 1e-6);
  EXPECT_TRUE(reached_east_room) << "the robot never got through the corridor";
  // The wheels carry the pose: no jump between control periods. A step beyond what the chassis'
  // top speed allows is a correction; with few features (health degraded, fewer than
  // good_min_inliers) vision still corrects the wheels' drift by a centimetre or so, through the
  // EKF's gate (an injected 1 m jump is rejected: PoseEkf tests). 2 cm bounds both.
  const auto& traj = run.estimated_trajectory();
  ASSERT_GE(good_at.size() + 1, traj.size());  // the run's end adds the last pose
  good_at.resize(traj.size(), false);
  double worst_not_good = 0.0, worst = 0.0;
  for (std::size_t k = 1; k < traj.size(); ++k) {
    const double d = std::hypot(traj[k].pose.x - traj[k - 1].pose.x, traj[k].pose.y - traj[k - 1].pose.y);
    const double excess = d - 0.7 * (traj[k].t_s - traj[k - 1].t_s);
    worst = std::max(worst, excess);
    if (!good_at[k]) worst_not_good = std::max(worst_not_good, excess);
  }
  std::printf("corridor: largest step beyond the top speed %.4f m while vision was not good, %.4f m overall\n", worst_not_good, worst);
  EXPECT_LT(worst, 0.02);
  EXPECT_LT(s.pose_error_max_m, 0.3);
  EXPECT_EQ(s.collisions, 0u);
}

}  // namespace test_feature_seek
}  // namespace duet
