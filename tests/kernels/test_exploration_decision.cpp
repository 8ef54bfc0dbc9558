// The combined strategy of Fig. 6 (decide_goal: Procedure 1, then the frontier search when its
// reward is too small) on hand-made grids (partial_sim_test_util.hpp).
#include <duet/kernels/exploration.hpp>
#include <duet/kernels/partial_sim.hpp>

#include "partial_sim_test_util.hpp"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <vector>

namespace duet {
namespace test_partial_sim {

// The frontier search run concurrently with the simulation (the default) gives the very decision
// of the sequential order, in both branches of Fig. 6 and with 1 and 2 threads.
TEST(Exploration, ConcurrentFrontierSearchGivesTheSequentialDecision) {
  const TestGrid g = door_room();
  Prepared p(g);
  const auto sensors = paper_dual_sensors(30);
  GoalBlacklist bl;
  for (const float eps_r : {1.0f, 1e9f}) {  // simulated goal taken / frontier fall-back
    ExplorationDecision ref;
    bool have_ref = false;
    for (const bool concurrent : {false, true})
      for (const int threads : {1, 2}) {
        ExplorationSettings s;
        s.eps_r_bits = eps_r;
        s.concurrent_frontier_search = concurrent;
        ExplorationDecision d;
        tbb::task_arena(threads).execute([&] {
          ExplorationWorkspace ws;
          d = decide_goal(p.model, p.inflated, Pose2{2.0f, 5.0f, 0.3f}, sensors, bl, 0.0, s, ws);
        });
        if (!have_ref) {
          ref = d;
          have_ref = true;
          EXPECT_EQ(ref.status, eps_r > 1e8f ? ExplorationStatus::kFrontierGoal : ExplorationStatus::kSimulatedGoal)
              << to_string(ref.status);
          continue;
        }
        EXPECT_EQ(d.status, ref.status);
        EXPECT_EQ(d.goal.x, ref.goal.x);
        EXPECT_EQ(d.goal.y, ref.goal.y);
        EXPECT_EQ(d.goal.theta, ref.goal.theta);
        EXPECT_EQ(d.reward_bits, ref.reward_bits);
        EXPECT_EQ(d.simulation.weights, ref.simulation.weights);
        if (eps_r > 1e8f) {  // the frontier branch: the search is the decision's, either way
          EXPECT_TRUE(d.frontier_searched);
          EXPECT_EQ(d.frontier.status, ref.frontier.status);
          EXPECT_EQ(d.frontier.path.size(), ref.frontier.path.size());
          EXPECT_EQ(d.frontier.goal_xy, ref.frontier.goal_xy);
        } else {  // the simulated goal: the concurrent search is kept, the sequential one never ran
          EXPECT_EQ(d.frontier_searched, concurrent);
          if (concurrent) {
            FrontierWorkspace fw;
            const FrontierResult direct = find_frontier(p.inflated, Eigen::Vector2f(2.0f, 5.0f), bl, 0.0, s.frontier, fw);
            EXPECT_EQ(d.frontier.status, direct.status);
            EXPECT_EQ(d.frontier.goal_xy, direct.goal_xy);
            EXPECT_EQ(d.frontier.path.size(), direct.path.size());
            EXPECT_EQ(d.frontier.clusters.size(), direct.clusters.size());
          }
        }
      }
  }
}

// A fully known closed room: nothing to learn (cells at the clamps), so R_g <= eps_R and the
// frontier search runs and finds no frontier.
TEST(Exploration, ClosedKnownRoomSaysNoFrontier) {
  TestGrid g(120, 120);
  g.room(10, 10, 110, 110);
  Prepared p(g);
  const auto sensors = paper_dual_sensors(30);
  ExplorationWorkspace ws;
  ExplorationSettings s;
  GoalBlacklist bl;
  const ExplorationDecision d = decide_goal(p.model, p.inflated, Pose2{3.0f, 3.0f, 0.0f}, sensors, bl, 0.0, s, ws);
  EXPECT_LE(d.reward_bits, s.eps_r_bits);
  EXPECT_EQ(d.status, ExplorationStatus::kNoFrontier) << to_string(d.status);
  EXPECT_FALSE(d.has_goal());
}

TEST(Exploration, DoorRoomTakesTheSimulatedGoal) {
  const TestGrid g = door_room();
  Prepared p(g);
  const auto sensors = paper_dual_sensors(30);
  ExplorationWorkspace ws;
  ExplorationSettings s;
  GoalBlacklist bl;
  const ExplorationDecision d = decide_goal(p.model, p.inflated, Pose2{2.0f, 5.0f, 3.14159f}, sensors, bl, 0.0, s, ws);
  EXPECT_EQ(d.status, ExplorationStatus::kSimulatedGoal) << to_string(d.status);
  EXPECT_GT(d.reward_bits, s.eps_r_bits);
  EXPECT_EQ(d.goal.x, d.simulation.goal.x);
}

// R_g <= eps_R (a threshold no simulation reaches): the frontier goal, at the door.
TEST(Exploration, LowRewardFallsBackToTheFrontier) {
  const TestGrid g = door_room();
  Prepared p(g);
  const auto sensors = paper_dual_sensors(30);
  ExplorationWorkspace ws;
  ExplorationSettings s;
  s.eps_r_bits = 1e9f;
  GoalBlacklist bl;
  const ExplorationDecision d = decide_goal(p.model, p.inflated, Pose2{2.0f, 5.0f, 3.14159f}, sensors, bl, 0.0, s, ws);
  ASSERT_EQ(d.status, ExplorationStatus::kFrontierGoal) << to_string(d.status);
  EXPECT_NEAR(d.goal.x, 5.0f, 0.2f);  // the door is the east wall, x = 5.0 .. 5.05 m
  EXPECT_GT(d.goal.y, 4.4f);
  EXPECT_LT(d.goal.y, 5.6f);
  // Blacklisting the door leaves nothing reachable but blacklisted.
  bl.add(Eigen::Vector2f(5.0f, 5.0f), 0.0, 60.0);
  s.frontier.blacklist_radius_m = 1.0f;
  const ExplorationDecision d2 = decide_goal(p.model, p.inflated, Pose2{2.0f, 5.0f, 3.14159f}, sensors, bl, 1.0, s, ws);
  EXPECT_EQ(d2.status, ExplorationStatus::kAllBlacklisted) << to_string(d2.status);
  // After expiry the door is a goal again.
  const ExplorationDecision d3 = decide_goal(p.model, p.inflated, Pose2{2.0f, 5.0f, 3.14159f}, sensors, bl, 61.0, s, ws);
  EXPECT_EQ(d3.status, ExplorationStatus::kFrontierGoal) << to_string(d3.status);
}

// A closed room whose floor was seen free only once (l = -0.4, free but not certain): the paper's
// test takes a goal inside it (seeing the floor again removes ~0.08 bits a cell, far above eps_R);
// counting only unknown cells (eps_r_unknown_only), nothing is left to see and the frontier search
// says so.
TEST(Exploration, AGoalThatOnlyConfirmsKnownCellsIsNotTakenWhenOnlyUnknownCellsCount) {
  TestGrid g(120, 120);
  g.room(10, 10, 110, 110);
  g.fill(10, 10, 110, 110, -0.4f);
  Prepared p(g);
  const auto sensors = paper_dual_sensors(30);
  ExplorationWorkspace ws;
  ExplorationSettings s;
  GoalBlacklist bl;
  const Pose2 robot{3.0f, 3.0f, 0.0f};
  const ExplorationDecision paper = decide_goal(p.model, p.inflated, robot, sensors, bl, 0.0, s, ws);
  EXPECT_EQ(paper.status, ExplorationStatus::kSimulatedGoal) << to_string(paper.status);
  EXPECT_GT(paper.reward_bits, s.eps_r_bits);
  EXPECT_EQ(paper.simulation.unknown_reward_bits, 0.0f);
  s.eps_r_unknown_only = true;
  const ExplorationDecision unknown_only = decide_goal(p.model, p.inflated, robot, sensors, bl, 0.0, s, ws);
  EXPECT_EQ(unknown_only.status, ExplorationStatus::kNoFrontier) << to_string(unknown_only.status);
  EXPECT_FALSE(unknown_only.has_goal());
  EXPECT_EQ(unknown_only.reward_bits, paper.reward_bits) << "the same simulation; only the test differs";
  // With the door of door_room() the unknown beyond it is worth the trip under either test.
  const TestGrid dg = door_room();
  Prepared dp(dg);
  const ExplorationDecision door = decide_goal(dp.model, dp.inflated, Pose2{4.0f, 5.0f, 0.0f}, sensors, bl, 0.0, s, ws);
  EXPECT_EQ(door.status, ExplorationStatus::kSimulatedGoal) << to_string(door.status);
  EXPECT_GT(door.simulation.unknown_reward_bits, s.eps_r_bits);
}

// The door of door_room() replaced by a walled passage of 0.2 m (narrower than the robot) that
// ends in the unknown 0.5 m beyond the wall: the frontier goal is an approach cell in the room,
// facing the passage's end (the frontier cell it is for).
TEST(Exploration, NarrowFrontierGoalFacesItsTarget) {
  TestGrid g(200, 200);
  g.room(20, 60, 100, 140);
  for (int x = 100; x <= 110; ++x) {
    g.at(x, 97) = kOccL;
    g.at(x, 102) = kOccL;
    for (int y = 98; y <= 101; ++y) g.at(x, y) = kFreeL;
  }
  Prepared p(g);
  const auto sensors = paper_dual_sensors(30);
  ExplorationWorkspace ws;
  ExplorationSettings s;
  s.eps_r_bits = 1e9f;  // the frontier search decides
  s.frontier.approach_radius_m = 1.0f;
  GoalBlacklist bl;
  const Pose2 robot{2.0f, 5.0f, 3.14159f};
  const ExplorationDecision d = decide_goal(p.model, p.inflated, robot, sensors, bl, 0.0, s, ws);
  ASSERT_EQ(d.status, ExplorationStatus::kFrontierGoal) << to_string(d.status);
  const Eigen::Vector2f look = d.frontier.target_xy - d.frontier.goal_xy;
  ASSERT_GT(look.norm(), 0.0f);  // an approach cell
  EXPECT_LT(d.goal.x, 5.0f);     // in the room
  EXPECT_GT(d.frontier.target_xy.x(), 5.0f);  // the passage's end
  EXPECT_NEAR(d.goal.theta, std::atan2(look.y(), look.x()), 1e-5f);
  s.frontier.approach_radius_m = 0.0f;  // without approach cells the passage is unreachable
  EXPECT_EQ(decide_goal(p.model, p.inflated, robot, sensors, bl, 0.0, s, ws).status, ExplorationStatus::kAllUnreachable);
}

}  // namespace test_partial_sim
}  // namespace duet
