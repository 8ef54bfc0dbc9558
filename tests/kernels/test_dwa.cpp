// The dynamic window (dwa.hpp) in scenarios - corridor, corner, boxed in, dead end, oscillation,
// goal, no path - and closed-loop runs, the paper's motion constraint, errors and workspace reuse.
// Against the brute-force reference on random grids, and thread counts: test_dwa_reference.cpp.
#include "dwa_test_util.hpp"

#include <duet/kernels/dwa.hpp>
#include <duet/kernels/error.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <vector>

namespace duet {
namespace test_dwa {

using namespace dwa_test;

// ---- scenarios -----------------------------------------------------------------------------------

struct LoopStats {
  bool reached = false;
  int steps = 0;
  float min_clearance = kInf;
  float max_abs_omega = 0.0f, max_domega = 0.0f, max_dv = 0.0f;
  int oscillations = 0;
  float max_omega_seen = -kInf;
  Pose2 final_pose;
};

/// Closed loop: the chassis follows each command exactly for one control period (motion_step).
LoopStats closed_loop(const ClearanceView& view, Pose2 pose, const std::vector<V2>& path, const DwaSettings& s,
                      int max_steps) {
  LoopStats st;
  DwaState state;
  DwaWorkspace ws;
  Twist cur;
  for (int k = 0; k < max_steps; ++k) {
    const DwaResult r = dwa_step(view, pose, cur, path, s, state, ws);
    if (r.status == DwaStatus::kGoalReached) {
      st.reached = true;
      break;
    }
    if (r.oscillation) ++st.oscillations;
    st.max_abs_omega = std::max(st.max_abs_omega, std::fabs(r.cmd.omega));
    st.max_omega_seen = std::max(st.max_omega_seen, r.cmd.omega);
    st.max_domega = std::max(st.max_domega, std::fabs(r.cmd.omega - cur.omega));
    st.max_dv = std::max(st.max_dv, std::fabs(r.cmd.v - cur.v));
    pose = motion_step(pose, r.cmd, s.control_period_s);
    cur = r.cmd;
    st.min_clearance = std::min(st.min_clearance, view.at(pose.x, pose.y));
    st.steps = k + 1;
  }
  st.final_pose = pose;
  return st;
}

TEST(Dwa, FreeCorridorDrivesForwardAlongThePath) {
  const TestGrid g = corridor(4.0f, 1.0f, true, true);
  const ClearanceView view = g.view();
  const DwaSettings s;
  const std::vector<V2> path{V2(0.5f, 0.5f), V2(2.0f, 0.5f), V2(3.5f, 0.5f)};
  DwaState state;
  DwaWorkspace ws;
  const DwaResult r = dwa_step(view, Pose2{0.5f, 0.5f, 0.0f}, Twist{}, path, s, state, ws);
  ASSERT_EQ(r.status, DwaStatus::kOk);
  EXPECT_GT(r.cmd.v, 0.04f);  // top of the window [-0.05, 0.05]
  EXPECT_LT(std::fabs(r.cmd.omega), 0.01f);
  EXPECT_EQ(r.valid_trajectories, r.evaluated_trajectories);  // nothing near
  // Moving already: keeps accelerating to the speed limit.
  const DwaResult r2 = dwa_step(view, Pose2{1.0f, 0.5f, 0.0f}, Twist{0.48f, 0.0f}, path, s, state, ws);
  ASSERT_EQ(r2.status, DwaStatus::kOk);
  EXPECT_FLOAT_EQ(r2.cmd.v, 0.5f);

  const LoopStats st = closed_loop(view, Pose2{0.5f, 0.5f, 0.0f}, path, s, 400);
  EXPECT_TRUE(st.reached);
  EXPECT_LT(st.steps, 200);  // 3 m at up to 0.5 m/s: well under 10 s
  EXPECT_GT(st.min_clearance, s.robot_radius_m + s.safety_margin_m);
  EXPECT_LE(st.max_abs_omega, s.mapping_max_omega_rps + 1e-6f);
  EXPECT_LE(st.max_domega, s.mapping_max_alpha_rps2 * s.control_period_s + 1e-5f);
  EXPECT_LE(st.max_dv, s.limits.max_accel_mps2 * s.control_period_s + 1e-5f);
  EXPECT_EQ(st.oscillations, 0);
  EXPECT_LT(std::fabs(st.final_pose.y - 0.5f), 0.1f);
}

/// L-shaped corridor: along +x from (0, 0)-(2, 1), then up along x in [1, 2] to y = 4.
TestGrid l_corridor() {
  TestGrid g(50, 90, 0.05f, V2(-0.25f, -0.25f));
  g.block_rect(-1.0f, -1.0f, 100.0f, -0.001f);   // floor wall
  g.block_rect(-1.0f, -1.0f, -0.001f, 100.0f);   // left end
  g.block_rect(2.001f, -1.0f, 100.0f, 100.0f);   // right wall (ahead of the robot)
  g.block_rect(-1.0f, 1.001f, 0.999f, 100.0f);   // top of the horizontal leg, left of the vertical leg
  g.block_rect(-1.0f, 4.001f, 100.0f, 100.0f);   // far end
  g.build();
  return g;
}

TEST(Dwa, WallAheadAndPathTurningTurns) {
  const TestGrid g = l_corridor();
  const ClearanceView view = g.view();
  const DwaSettings s;
  const std::vector<V2> path{V2(0.3f, 0.5f), V2(1.5f, 0.5f), V2(1.5f, 3.6f)};
  // One step: 0.65 m from the wall ahead at 0.3 m/s, the path turning left.
  DwaState state;
  DwaWorkspace ws;
  const Twist cur{0.3f, 0.0f};
  const DwaResult r = dwa_step(view, Pose2{1.35f, 0.5f, 0.0f}, cur, path, s, state, ws);
  ASSERT_EQ(r.status, DwaStatus::kOk);
  EXPECT_LT(r.valid_trajectories, r.evaluated_trajectories);  // straight on at 0.35 m/s is inadmissible
  EXPECT_FALSE(ref_collision_free(view, Pose2{1.35f, 0.5f, 0.0f}, Twist{0.35f, 0.0f}, s));
  EXPECT_GT(r.cmd.omega, 0.04f);  // turns left as hard as the window allows (0.05)
  EXPECT_TRUE(in_window(s, cur, r.cmd));

  const LoopStats st = closed_loop(view, Pose2{0.3f, 0.5f, 0.0f}, path, s, 600);
  EXPECT_TRUE(st.reached);
  EXPECT_GT(st.min_clearance, s.robot_radius_m + s.safety_margin_m);
  EXPECT_GT(st.max_omega_seen, 0.3f);  // it really turned
  EXPECT_LE(st.max_abs_omega, s.mapping_max_omega_rps + 1e-6f);
  EXPECT_NEAR(st.final_pose.x, 1.5f, 0.15f);
}

TEST(Dwa, MappingConstraintBoundsOmegaAndAlpha) {
  const TestGrid g = corridor(4.0f, 3.0f, false, false);
  const ClearanceView view = g.view();
  // Path straight behind the robot: the best command turns as fast as allowed.
  const std::vector<V2> path{V2(1.0f, 1.5f), V2(1.0f, 2.5f)};
  DwaSettings s;
  DwaState state;
  DwaWorkspace ws;
  const DwaResult r = dwa_step(view, Pose2{1.0f, 1.0f, 0.0f}, Twist{0.0f, 0.78f}, path, s, state, ws);
  ASSERT_EQ(r.status, DwaStatus::kOk);
  EXPECT_FLOAT_EQ(r.cmd.omega, 0.8f);  // capped by mapping_max_omega_rps, not by the chassis' pi
  // Above the mapping bound (e.g. a command of another controller): decelerate by A*T only.
  const DwaResult r2 = dwa_step(view, Pose2{1.0f, 1.0f, 0.0f}, Twist{0.0f, 2.0f}, path, s, state, ws);
  ASSERT_EQ(r2.status, DwaStatus::kOk);
  EXPECT_FLOAT_EQ(r2.cmd.omega, 2.0f - 1.0f * 0.05f);
  // Without the mapping constraint the chassis' alpha gives a wider window.
  s.mapping_max_alpha_rps2 = 100.0f;
  s.mapping_max_omega_rps = 100.0f;
  const DwaResult r3 = dwa_step(view, Pose2{1.0f, 1.0f, 0.0f}, Twist{0.0f, 0.78f}, path, s, state, ws);
  EXPECT_FLOAT_EQ(r3.cmd.omega, 0.78f + 3.0f * 0.05f);
}

TEST(Dwa, CommandStaysWithinTheLimitsWhenTheMeasuredTwistIsBeyondThem) {
  // An odometry glitch of 100 m/s and 100 rad/s (or a push): the window follows the measured
  // twist, the command must not (it gave 99.95 m/s with status OK before).
  const TestGrid g = corridor(4.0f, 3.0f, false, false);
  const ClearanceView view = g.view();
  const std::vector<V2> path{V2(1.0f, 1.5f), V2(3.5f, 1.5f)};
  const DwaSettings s;
  for (const Twist glitch : {Twist{100.0f, 0.0f}, Twist{-100.0f, 0.0f}, Twist{0.0f, 100.0f}, Twist{0.3f, -100.0f}, Twist{1e30f, 1e30f}}) {
    DwaState state;
    DwaWorkspace ws;
    for (const V2& at : {V2(1.0f, 1.5f), V2(1.0f, 0.2f)}) {  // free, and near the wall (recovery)
      const DwaResult r = dwa_step(view, Pose2{at.x(), at.y(), 0.0f}, glitch, path, s, state, ws);
      EXPECT_GE(r.cmd.v, s.limits.min_v_mps) << glitch.v << " " << glitch.omega;
      EXPECT_LE(r.cmd.v, s.limits.max_v_mps) << glitch.v << " " << glitch.omega;
      EXPECT_LE(std::fabs(r.cmd.omega), s.limits.max_omega_rps) << glitch.v << " " << glitch.omega;
    }
  }
}

TEST(Dwa, BoxedInWithoutRoomGivesNoValidTrajectory) {
  // A ring of blocked cells 0.15 m around the robot: the footprint already touches.
  TestGrid g(40, 40, 0.05f, V2(-1.0f, -1.0f));
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x) {
      const float r = g.center(x, y).norm();
      if (r > 0.15f && r < 0.25f) g.block(x, y);
    }
  g.build();
  const ClearanceView view = g.view();
  const DwaSettings s;
  DwaState state;
  DwaWorkspace ws;
  const std::vector<V2> path{V2(0.0f, 0.0f), V2(0.8f, 0.0f)};
  const DwaResult r = dwa_step(view, Pose2{0.025f, 0.025f, 0.0f}, Twist{0.2f, 0.1f}, path, s, state, ws);
  EXPECT_EQ(r.status, DwaStatus::kNoValidTrajectory);
  EXPECT_EQ(r.cmd.v, 0.0f);
  EXPECT_EQ(r.cmd.omega, 0.0f);
  EXPECT_EQ(r.valid_trajectories, 0);
  EXPECT_EQ(r.evaluated_trajectories, 800);
}

TEST(Dwa, DeadEndBacksOffThenRotates) {
  // 0.56 m wide dead end closed at x = 2: the robot is inside the safety margin of the end wall.
  const TestGrid g = corridor(2.0f, 0.56f, true, true);
  const ClearanceView view = g.view();
  DwaSettings s;
  s.safety_margin_m = 0.06f;  // clearance of the pose's cell: 0.25 m (cell centres 0.25 m from the end wall)
  const Pose2 pose{1.78f, 0.28f, 0.0f};
  const float c0 = view.at(pose.x, pose.y);
  ASSERT_GT(c0, s.robot_radius_m);
  ASSERT_LE(c0, s.robot_radius_m + s.safety_margin_m);
  {  // Stale path straight through the end wall: aligned, so back off.
    const std::vector<V2> path{V2(1.0f, 0.28f), V2(3.0f, 0.28f)};
    DwaState state;
    DwaWorkspace ws;
    Pose2 p = pose;
    Twist cur;
    DwaResult r = dwa_step(view, p, cur, path, s, state, ws);
    ASSERT_EQ(r.status, DwaStatus::kBackOff);
    EXPECT_EQ(r.valid_trajectories, 0);
    EXPECT_FALSE(r.oscillation);
    EXPECT_FLOAT_EQ(r.cmd.v, -0.05f);  // ramps at max_accel * T toward -backoff_speed
    // The phase continues while the robot reverses, and ends after backoff_distance_m.
    int calls = 1;
    while (r.status == DwaStatus::kBackOff && calls < 200) {
      p = motion_step(p, r.cmd, s.control_period_s);
      cur = r.cmd;
      r = dwa_step(view, p, cur, path, s, state, ws);
      ++calls;
      if (r.status == DwaStatus::kBackOff) {
        EXPECT_GE(r.cmd.v, -s.backoff_speed_mps - 1e-6f);
      }
    }
    EXPECT_GE(pose.x - p.x, s.backoff_distance_m - 0.01f);
    EXPECT_LE(pose.x - p.x, s.backoff_distance_m + 0.01f);
    EXPECT_LE(calls, s.recovery_max_calls + 1);
    EXPECT_EQ(r.status, DwaStatus::kOk);  // out of the margin: the window works again
  }
  {  // Path behind: rotate toward it in place.
    const std::vector<V2> path{V2(1.8f, 0.28f), V2(0.3f, 0.28f)};
    DwaState state;
    DwaWorkspace ws;
    const DwaResult r = dwa_step(view, pose, Twist{}, path, s, state, ws);
    ASSERT_EQ(r.status, DwaStatus::kRotateInPlace);
    EXPECT_EQ(r.cmd.v, 0.0f);
    EXPECT_NE(r.cmd.omega, 0.0f);
    EXPECT_LE(std::fabs(r.cmd.omega), s.mapping_max_alpha_rps2 * s.control_period_s + 1e-6f);
  }
  {  // Closed behind too (a 0.5 m long pocket): no room to back off, aligned -> no valid trajectory.
    TestGrid pocket(60, 30, 0.05f, V2(-0.1f, -0.1f));
    pocket.block_rect(-1.0f, -1.0f, 100.0f, -0.001f);
    pocket.block_rect(-1.0f, 0.561f, 100.0f, 100.0f);
    pocket.block_rect(-1.0f, -1.0f, 1.499f, 100.0f);
    pocket.block_rect(2.001f, -1.0f, 100.0f, 100.0f);
    pocket.build();
    const ClearanceView pv = pocket.view();
    ASSERT_GT(pv.at(pose.x, pose.y), s.robot_radius_m);
    const std::vector<V2> path{V2(1.6f, 0.28f), V2(3.0f, 0.28f)};
    DwaState state;
    DwaWorkspace ws;
    const DwaResult r = dwa_step(pv, pose, Twist{}, path, s, state, ws);
    EXPECT_EQ(r.status, DwaStatus::kNoValidTrajectory);
    EXPECT_EQ(r.cmd.v, 0.0f);
    EXPECT_EQ(r.cmd.omega, 0.0f);
  }
}

/// Alternating poses A, B (no progress) while the controller commands motion: recovery after
/// exactly oscillation_window_calls counted calls, for at most recovery_max_calls calls.
void oscillation_scenario(const Pose2& a, const Pose2& b, DwaStatus expected_recovery) {
  const TestGrid g = corridor(4.0f, 1.0f, true, true);
  const ClearanceView view = g.view();
  DwaSettings s;
  s.oscillation_window_calls = 10;
  s.recovery_max_calls = 8;
  const std::vector<V2> path{V2(0.5f, 0.5f), V2(3.5f, 0.5f)};
  DwaState state;
  DwaWorkspace ws;
  int first_trigger = -1, recovery_calls = 0, triggers = 0;
  int back_to_ok = -1;
  for (int k = 0; k < 60; ++k) {
    const Pose2& p = (k % 2 == 0) ? a : b;
    const DwaResult r = dwa_step(view, p, Twist{0.1f, 0.0f}, path, s, state, ws);
    if (r.oscillation) {
      ++triggers;
      if (first_trigger < 0) first_trigger = k;
    }
    if (first_trigger >= 0 && back_to_ok < 0) {
      if (r.status == DwaStatus::kOk) back_to_ok = k;
      else {
        EXPECT_EQ(r.status, expected_recovery);
        ++recovery_calls;
      }
    }
    if (first_trigger < 0) {
      EXPECT_EQ(r.status, DwaStatus::kOk) << "call " << k;
    }
  }
  // Call 0 sets the anchor; calls 1..10 count: the 10th counted call triggers.
  EXPECT_EQ(first_trigger, s.oscillation_window_calls);
  EXPECT_EQ(recovery_calls, s.recovery_max_calls);  // the robot never moves: the time bound ends it
  EXPECT_EQ(back_to_ok, first_trigger + s.recovery_max_calls);
  EXPECT_GE(triggers, 2);  // and it re-arms after the window
}

TEST(Dwa, OscillationTriggersBoundedBackOff) {
  oscillation_scenario(Pose2{1.0f, 0.5f, 0.0f}, Pose2{1.03f, 0.5f, 0.02f}, DwaStatus::kBackOff);
}

TEST(Dwa, OscillationTriggersBoundedRotation) {
  oscillation_scenario(Pose2{1.0f, 0.5f, 0.8f}, Pose2{1.03f, 0.5f, 0.75f}, DwaStatus::kRotateInPlace);
}

TEST(Dwa, ProgressDoesNotTriggerOscillation) {
  const TestGrid g = corridor(4.0f, 1.0f, true, true);
  const ClearanceView view = g.view();
  DwaSettings s;
  s.oscillation_window_calls = 5;
  const std::vector<V2> path{V2(0.5f, 0.5f), V2(3.5f, 0.5f)};
  DwaState state;
  DwaWorkspace ws;
  for (int k = 0; k < 100; ++k) {  // 2.5 cm per call: progress of 0.1 m every 4 calls
    const DwaResult r = dwa_step(view, Pose2{0.5f + 0.025f * k, 0.5f, 0.0f}, Twist{0.5f, 0.0f}, path, s, state, ws);
    EXPECT_EQ(r.status, DwaStatus::kOk) << k;
    EXPECT_FALSE(r.oscillation);
  }
}

TEST(Dwa, GoalReachedAndNoPath) {
  const TestGrid g = corridor(4.0f, 1.0f, true, true);
  const ClearanceView view = g.view();
  const DwaSettings s;
  DwaState state;
  DwaWorkspace ws;
  const std::vector<V2> path{V2(0.5f, 0.5f), V2(2.0f, 0.5f)};
  DwaResult r = dwa_step(view, Pose2{1.9f, 0.45f, 1.0f}, Twist{0.3f, 0.2f}, path, s, state, ws);
  EXPECT_EQ(r.status, DwaStatus::kGoalReached);
  EXPECT_EQ(r.cmd.v, 0.0f);
  EXPECT_EQ(r.cmd.omega, 0.0f);
  r = dwa_step(view, Pose2{1.8f, 0.5f, 0.0f}, Twist{}, path, s, state, ws);  // 0.2 m: not yet
  EXPECT_EQ(r.status, DwaStatus::kOk);
  r = dwa_step(view, Pose2{1.0f, 0.5f, 0.0f}, Twist{0.3f, 0.2f}, {}, s, state, ws);
  EXPECT_EQ(r.status, DwaStatus::kNoPath);
  EXPECT_EQ(r.cmd.v, 0.0f);
  EXPECT_EQ(r.cmd.omega, 0.0f);
  // One-point path: the goal is the lookahead.
  const std::vector<V2> one{V2(3.0f, 0.5f)};
  r = dwa_step(view, Pose2{1.0f, 0.5f, 0.0f}, Twist{}, one, s, state, ws);
  EXPECT_EQ(r.status, DwaStatus::kOk);
  EXPECT_EQ(r.lookahead, one[0]);
  EXPECT_STREQ(to_string(DwaStatus::kBackOff), "back_off");
  EXPECT_STREQ(to_string(DwaStatus::kNoValidTrajectory), "no_valid_trajectory");
}

TEST(Dwa, EmptyGridAndHugeCoordinates) {
  const DwaSettings s;
  DwaState state;
  DwaWorkspace ws;
  const std::vector<V2> path{V2(0.0f, 0.0f), V2(5.0f, 0.0f)};
  ClearanceView empty;  // 0 x 0: everything is outside, clearance 0
  DwaResult r = dwa_step(empty, Pose2{}, Twist{}, path, s, state, ws);
  EXPECT_EQ(r.status, DwaStatus::kNoValidTrajectory);
  EXPECT_EQ(r.valid_trajectories, 0);
  const TestGrid g = corridor(4.0f, 1.0f, true, true);
  const std::vector<V2> far{V2(1e7f, 1e7f), V2(2e7f, 1e7f)};
  state.reset();
  r = dwa_step(g.view(), Pose2{1e7f, 1e7f, 0.3f}, Twist{}, far, s, state, ws);
  EXPECT_EQ(r.status, DwaStatus::kNoValidTrajectory);
  EXPECT_EQ(r.cmd.v, 0.0f);
}

TEST(Dwa, InvalidInputsThrow) {
  const TestGrid g = corridor(4.0f, 1.0f, true, true);
  const ClearanceView view = g.view();
  const std::vector<V2> path{V2(0.5f, 0.5f), V2(2.0f, 0.5f)};
  DwaState st;
  DwaWorkspace ws;
  const DwaSettings ok;
  const auto inv = ErrorCode::kInvalidArgument;
  EXPECT_DUET_ERROR(dwa_step(view, Pose2{kNaN, 0.5f, 0.0f}, Twist{}, path, ok, st, ws), inv, "pose");
  DwaSettings heavy;  // each count within its range, the product over the work budget
  heavy.v_samples = heavy.omega_samples = 1000;
  EXPECT_DUET_ERROR(dwa_step(view, Pose2{1.0f, 0.5f, 0.0f}, Twist{}, path, heavy, st, ws), inv, "rollout steps per call");
  heavy.steps = 1;  // 1e6: exactly the budget
  EXPECT_NO_THROW(dwa_step(view, Pose2{1.0f, 0.5f, 0.0f}, Twist{}, path, heavy, st, ws));
  EXPECT_DUET_ERROR(dwa_step(view, Pose2{1.0f, 0.5f, kInf}, Twist{}, path, ok, st, ws), inv, "pose");
  EXPECT_DUET_ERROR(dwa_step(view, Pose2{1.0f, 0.5f, 0.0f}, Twist{kNaN, 0.0f}, path, ok, st, ws), inv, "twist");
  const std::vector<V2> bad_path{V2(0.5f, 0.5f), V2(kNaN, 0.5f)};
  EXPECT_DUET_ERROR(dwa_step(view, Pose2{1.0f, 0.5f, 0.0f}, Twist{}, bad_path, ok, st, ws), inv, "waypoint 1");
  ClearanceView bad_view = view;
  bad_view.width += 1;
  EXPECT_DUET_ERROR(dwa_step(bad_view, Pose2{1.0f, 0.5f, 0.0f}, Twist{}, path, ok, st, ws), inv, "width * height");
  bad_view = view;
  bad_view.resolution_m = 0.0f;
  EXPECT_DUET_ERROR(dwa_step(bad_view, Pose2{1.0f, 0.5f, 0.0f}, Twist{}, path, ok, st, ws), inv, "resolution_m");

  auto expect_bad = [&](auto mutate, const char* field) {
    DwaSettings s;
    mutate(s);
    EXPECT_DUET_ERROR(validate(s), inv, field);
    EXPECT_DUET_ERROR(dwa_step(view, Pose2{1.0f, 0.5f, 0.0f}, Twist{}, path, s, st, ws), inv, field);
  };
  expect_bad([](DwaSettings& s) { s.mapping_max_omega_rps = 0.0f; }, "mapping_max_omega_rps");
  expect_bad([](DwaSettings& s) { s.mapping_max_alpha_rps2 = kNaN; }, "mapping_max_alpha_rps2");
  expect_bad([](DwaSettings& s) { s.control_period_s = -0.05f; }, "control_period_s");
  expect_bad([](DwaSettings& s) { s.v_samples = 0; }, "v_samples");
  expect_bad([](DwaSettings& s) { s.omega_samples = 1001; }, "omega_samples");
  expect_bad([](DwaSettings& s) { s.steps = 0; }, "steps");
  expect_bad([](DwaSettings& s) { s.sim_time_s = 0.0f; }, "sim_time_s");
  expect_bad([](DwaSettings& s) { s.robot_radius_m = -0.1f; }, "robot_radius_m");
  expect_bad([](DwaSettings& s) { s.safety_margin_m = kInf; }, "safety_margin_m");
  expect_bad([](DwaSettings& s) { s.w_progress = -1.0f; }, "w_progress");
  expect_bad([](DwaSettings& s) { s.w_path = kNaN; }, "w_path");
  expect_bad([](DwaSettings& s) { s.w_clearance = -1.0f; }, "w_clearance");
  expect_bad([](DwaSettings& s) { s.w_speed = kInf; }, "w_speed");
  expect_bad([](DwaSettings& s) { s.lookahead_m = 0.0f; }, "lookahead_m");
  expect_bad([](DwaSettings& s) { s.goal_tolerance_m = -0.1f; }, "goal_tolerance_m");
  expect_bad([](DwaSettings& s) { s.oscillation_window_calls = 0; }, "oscillation_window_calls");
  expect_bad([](DwaSettings& s) { s.oscillation_min_turn_rad = 4.0f; }, "oscillation_min_turn_rad");
  expect_bad([](DwaSettings& s) { s.recovery_max_calls = 0; }, "recovery_max_calls");
  expect_bad([](DwaSettings& s) { s.rotate_omega_rps = 0.0f; }, "rotate_omega_rps");
  expect_bad([](DwaSettings& s) { s.backoff_distance_m = 11.0f; }, "backoff_distance_m");
  expect_bad([](DwaSettings& s) { s.backoff_speed_mps = 0.0f; }, "backoff_speed_mps");
  expect_bad([](DwaSettings& s) { s.limits.max_v_mps = 0.0f; }, "max_v_mps");
  EXPECT_NO_THROW(validate(ok));
}

TEST(Dwa, WorkspaceIsReusedWithoutReallocation) {
  const TestGrid g = corridor(4.0f, 1.0f, true, true);
  const ClearanceView view = g.view();
  const DwaSettings s;
  const std::vector<V2> path{V2(0.5f, 0.5f), V2(2.0f, 0.5f), V2(3.5f, 0.5f)};
  DwaState state;
  DwaWorkspace ws;
  const DwaResult r1 = dwa_step(view, Pose2{0.6f, 0.5f, 0.0f}, Twist{0.2f, 0.0f}, path, s, state, ws);
  const float* ox = ws.off_x.data();
  const auto* rows = ws.rows.data();
  const auto* lp = ws.local_path.data();
  const DwaResult r2 = dwa_step(view, Pose2{0.7f, 0.5f, 0.0f}, Twist{0.2f, 0.0f}, path, s, state, ws);
  EXPECT_EQ(ox, ws.off_x.data());
  EXPECT_EQ(rows, ws.rows.data());
  EXPECT_EQ(lp, ws.local_path.data());
  EXPECT_EQ(r1.status, DwaStatus::kOk);
  EXPECT_EQ(r2.status, DwaStatus::kOk);
  // A dirty workspace (other sizes before) gives the same result as a fresh one.
  DwaSettings big = s;
  big.v_samples = 33;
  big.steps = 50;
  DwaState st2, st3;
  DwaWorkspace dirty, fresh;
  (void)dwa_step(view, Pose2{0.6f, 0.5f, 0.0f}, Twist{}, path, big, st2, dirty);
  st2.reset();
  EXPECT_TRUE(same_result(dwa_step(view, Pose2{0.7f, 0.5f, 0.0f}, Twist{0.2f, 0.0f}, path, s, st2, dirty),
                          dwa_step(view, Pose2{0.7f, 0.5f, 0.0f}, Twist{0.2f, 0.0f}, path, s, st3, fresh)));
}

}  // namespace test_dwa
}  // namespace duet
