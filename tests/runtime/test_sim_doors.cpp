// Doors and gaps end to end (issue 23): a world's doors (a box with `door: true` or
// `opens_at_s`) open in the renderer and the chassis; a room seen only through a gap narrower
// than the robot gets a view goal and the stop names it with the gap's width; a door half open
// (a gap too narrow) that opens once the robot has given its frontier up and driven away is
// gone back to and explored behind.
#include <duet/kernels/error.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/sim/sim_explore.hpp>
#include <duet/sim/sim_robot.hpp>
#include <duet/sim/world.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

namespace {

using duet::sim::World;

// Room A (4 m x 4.1 m) and room B (2.85 m x 4.1 m) behind a wall with a 0.4 m slot (y 1.9-2.3).
const char* kGapRoom = R"(name: gap_room
floor: {min: [0, 0], max: [7.0, 4.2]}
start: [1.0, 2.0, 0.0]
walls:
  - {name: outer, points: [[0.05, 0.05], [6.95, 0.05], [6.95, 4.15], [0.05, 4.15]], closed: true}
  - {name: slot south, points: [[4.0, 0.1], [4.0, 1.85]]}
  - {name: slot north, points: [[4.0, 2.35], [4.0, 4.1]]}
)";

// Room A (7 m x 4.1 m, two crates) and room B (3.1 m x 4.1 m) joined by a 1 m doorway
// (y 1.5-2.5) whose door stands half open: it leaves a 0.3 m gap (y 2.2-2.5) until it opens.
const char* kDoorRooms = R"(name: door_rooms
floor: {min: [0, 0], max: [10.2, 4.2]}
start: [6.3, 2.0, 0.0]
walls:
  - {name: outer, points: [[0.05, 0.05], [10.15, 0.05], [10.15, 4.15], [0.05, 4.15]], closed: true}
  - {name: east south, points: [[7.0, 0.1], [7.0, 1.45]]}
  - {name: east north, points: [[7.0, 2.55], [7.0, 4.1]]}
boxes:
  - {name: door, min: [6.95, 1.5], max: [7.05, 2.2], height_m: 2.0, door: true}
  - {name: crate, centre: [2.5, 2.8], size: [0.6, 0.6], height_m: 0.8}
  - {name: shelf, min: [4.0, 0.1], max: [4.4, 1.2], height_m: 1.5}
)";

duet::sim::ExploreSettings door_settings(std::uint64_t seed, double max_time) {
  duet::sim::ExploreSettings s;
  s.seed = seed;
  s.max_time_s = max_time;
  return s;
}

}  // namespace

TEST(SimDoors, DoorsAreReadAndCheckedFromYaml) {
  const World w = duet::sim::parse_world(kDoorRooms, "door_rooms.yaml");
  int doors = 0;
  for (const auto& s : w.solids)
    if (s.door) {
      ++doors;
      EXPECT_EQ(s.name, "boxes[0] 'door'");
      EXPECT_TRUE(std::isinf(s.opens_at_s));
    }
  EXPECT_EQ(doors, 1);
  const World timed = duet::sim::parse_world(std::string(kDoorRooms) + "  - {name: flap, min: [1, 3], max: [1.5, 3.5], opens_at_s: 12.5}\n", "t.yaml");
  EXPECT_EQ(timed.solids.back().name, "boxes[3] 'flap'");
  EXPECT_TRUE(timed.solids.back().door);
  EXPECT_DOUBLE_EQ(timed.solids.back().opens_at_s, 12.5);
  EXPECT_EQ(duet::sim::with_doors_open(timed).solids.size(), timed.solids.size() - 2);
  const std::string names[] = {"boxes[3] 'flap'"};
  EXPECT_EQ(duet::sim::with_doors_open(timed, names).solids.size(), timed.solids.size() - 1);
  auto error_of = [](const std::string& extra) {
    try {
      (void)duet::sim::parse_world(std::string(kDoorRooms) + extra, "bad.yaml");
    } catch (const duet::Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of("  - {min: [1, 3], max: [1.5, 3.5], opens_at_s: -1}\n").find("boxes[3].opens_at_s"), std::string::npos);
  EXPECT_NE(error_of("  - {min: [1, 3], max: [1.5, 3.5], opens_at_s: .nan}\n").find("opens_at_s"), std::string::npos);
  EXPECT_NE(error_of("  - {min: [1, 3], max: [1.5, 3.5], door: false, opens_at_s: 3}\n").find("goes with a door"), std::string::npos);
  EXPECT_NE(error_of("  - {min: [1, 3], max: [1.5, 3.5], door: maybe}\n").find("boxes[3].door"), std::string::npos);
  World code = w;  // a world built in code
  code.solids.front().opens_at_s = 3.0;
  EXPECT_THROW(duet::sim::validate(code), duet::Error);  // not a door
}

TEST(SimDoors, AnOpenedDoorIsGoneFromTheFramesAndTheChassis) {
  // The robot faces the door from 1 m: its front camera sees the door at ~0.9 m, then the far
  // wall of room B (3 m further) once the door has opened - by time, or by the caller.
  for (const bool timed : {false, true}) {
    World w = duet::sim::parse_world(kDoorRooms, "door_rooms.yaml");
    w.start = duet::Pose2{6.0f, 1.85f, 0.0f};
    if (timed)
      for (auto& solid : w.solids)
        if (solid.door) solid.opens_at_s = 0.5;
    const auto world = std::make_shared<const World>(w);
    duet::sim::SimRobotSettings rs;
    rs.sensor_rate_hz = 10.0;
    duet::sim::SimRobot robot(world, duet::builtin_profile("dual_kinect_kobuki"), rs);
    const float units = duet::builtin_profile("dual_kinect_kobuki").sensors[0].depth_units_per_m;
    auto centre_depth = [&] {  // [m]
      const auto frames = robot.sensors()[0]->take_frames();
      if (frames.empty()) return -1.0;
      const auto& img = frames.back().image;
      return img.depth[static_cast<std::size_t>(img.height / 2) * img.width + img.width / 2] / static_cast<double>(units);
    };
    robot.advance(0.0);
    const double before = centre_depth();
    EXPECT_TRUE(duet::sim::collides(robot.world(), Eigen::Vector2f(7.0f, 1.85f), 0.1f));
    if (!timed) {
      EXPECT_FALSE(robot.open_door("no such door"));
      EXPECT_TRUE(robot.open_door("boxes[0] 'door'"));
      EXPECT_FALSE(robot.open_door("boxes[0] 'door'"));  // open already
    }
    robot.advance(1.0);
    const double after = centre_depth();
    EXPECT_LT(before, 1.5) << "the door";
    EXPECT_GT(after, 3.0) << "room B's far wall";
    EXPECT_FALSE(duet::sim::collides(robot.world(), Eigen::Vector2f(7.0f, 1.85f), 0.1f));
    EXPECT_FALSE(duet::sim::collides(robot.sim_chassis().world(), Eigen::Vector2f(7.0f, 1.85f), 0.1f));
  }
}

TEST(SimDoors, ARoomSeenOnlyThroughANarrowGapGetsAViewGoalAndTheStopNamesIt) {
  auto es = door_settings(1, 400.0);
  es.runtime.explorer.view_looks = 1;  // the stop's report is the subject here, not looking again (below)
  duet::sim::SimExplore run(duet::sim::parse_world(kGapRoom, "gap_room.yaml"), duet::builtin_profile("dual_kinect_kobuki"), es);
  run.run();
  const auto s = run.summary();
  EXPECT_EQ(s.stop_reason, duet::sim::StopReason::kExplorerDone) << s.stop_detail;
  EXPECT_EQ(s.collisions, 0u);
  EXPECT_GE(s.explorer.view_goals, 1) << s.stop_detail;
  // Everything left is behind the slot, unreachable through it, and was looked at. The slot is
  // 0.4 m; the map's is its ragged copy (wall ends seen at grazing angles).
  ASSERT_FALSE(s.left.empty()) << "nothing left behind the gap: " << s.stop_detail;
  for (const auto& r : s.left) {
    EXPECT_GT(r.centroid.x(), 4.05f) << s.stop_detail;
    EXPECT_EQ(r.why, duet::LeftWhy::kNarrowGap) << s.stop_detail;
    EXPECT_GT(r.gap_m, 0.15f) << s.stop_detail;
    EXPECT_LE(r.gap_m, 0.5f) << s.stop_detail;
    EXPECT_LT(r.gap_m, r.needed_m) << s.stop_detail;
  }
  EXPECT_TRUE(s.left.front().looked_at) << s.stop_detail;
  EXPECT_NE(s.stop_detail.find("unreachable through a gap of"), std::string::npos) << s.stop_detail;
}

TEST(SimDoors, ADoorThatOpensAfterItsFrontierWasGivenUpIsGoneBackToAndExploredBehind) {
  // The robot starts facing the door: it sees room B through the gap first, and room A is left
  // to explore once it gives B up. The door opens once the robot is 2 m from the doorway after
  // that: with view goals nearest first (view_frontier_weight 0) it drives off to look at room
  // A's corners; ranked by frontier length (the default) it looks at room B's long frontier from
  // beside the doorway until it stops, and the door would open in front of it - the default's
  // look again at a door opened later is APlaceLookedAtWhileItsDoorWasShut... below.
  auto es = door_settings(1, 600.0);
  es.runtime.explorer.view_frontier_weight = 0.0f;
  duet::sim::SimExplore run(duet::sim::parse_world(kDoorRooms, "door_rooms.yaml"), duet::builtin_profile("dual_kinect_kobuki"), es);
  const Eigen::Vector2f doorway(7.0f, 2.0f);
  double opened_at = -1.0;
  bool given_up = false;
  double entered_b = -1.0;
  while (run.step()) {
    const auto& nav = run.explorer().navigator();
    if (!given_up) {
      // Room B's frontier (seen through the 0.3 m gap) given up: a view goal looked at it, or a
      // goal for it failed.
      given_up = run.explorer().stats().view_goals_reached > 0;
      for (const auto& f : nav.goal_failures()) given_up = given_up || f.xy.x() > 6.8f;
    }
    const duet::Pose2 p = run.chassis().true_pose();
    if (given_up && opened_at < 0.0 && (Eigen::Vector2f(p.x, p.y) - doorway).norm() > 2.0f) {
      ASSERT_TRUE(run.open_door("boxes[0] 'door'"));
      opened_at = run.now_s();
    }
    if (opened_at >= 0.0 && entered_b < 0.0 && p.x > 7.4f) entered_b = run.now_s();
  }
  const auto s = run.summary();
  std::printf("door: given up, opened at %.1f s, robot through at %.1f s; stopped at %.1f s, coverage %.3f: %s\n", opened_at, entered_b,
              s.sim_time_s, s.coverage, s.stop_detail.c_str());
  ASSERT_TRUE(given_up) << "room B's frontier was never given up: " << s.stop_detail;
  ASSERT_GE(opened_at, 0.0) << "the robot never drove 2 m away from the doorway after giving room B up: " << s.stop_detail;
  EXPECT_GT(entered_b, opened_at) << "the robot did not go back through the opened door: " << s.stop_detail;
  EXPECT_EQ(s.stop_reason, duet::sim::StopReason::kExplorerDone) << s.stop_detail;
  EXPECT_GE(s.coverage, 0.95) << "room B was not explored: " << s.stop_detail;
  EXPECT_EQ(s.collisions, 0u);
}

TEST(SimDoors, APlaceLookedAtWhileItsDoorWasShutIsLookedAtAgainBeforeTheRobotStops) {
  // A robot that looks at each place once (view_looks = 1) stops at T1 with room B behind a
  // half-open door. The same run with the default (view_looks = 2; identical until T1), with the
  // door opened 5 s after T1: the robot looks through the gap again, sees the door open and goes in.
  World w = duet::sim::parse_world(kDoorRooms, "door_rooms.yaml");
  w.start = duet::Pose2{1.0f, 2.0f, 0.0f};
  double t1 = -1.0;
  for (const int looks : {1, 2}) {
    auto es = door_settings(1, 900.0);
    es.runtime.explorer.view_looks = looks;
    duet::sim::SimExplore run(w, duet::builtin_profile("dual_kinect_kobuki"), es);
    double opened_at = -1.0, entered_b = -1.0;
    while (run.step()) {
      if (t1 >= 0.0 && opened_at < 0.0 && run.now_s() >= t1 + 5.0) {
        ASSERT_TRUE(run.open_door("boxes[0] 'door'"));
        opened_at = run.now_s();
      }
      if (opened_at >= 0.0 && entered_b < 0.0 && run.chassis().true_pose().x > 7.4f) entered_b = run.now_s();
    }
    const auto s = run.summary();
    std::printf("view_looks %d: door opened at %.1f s, robot through at %.1f s; stopped at %.1f s, coverage %.3f, %d view goals: %s\n",
                looks, opened_at, entered_b, s.sim_time_s, s.coverage, s.explorer.view_goals, s.stop_detail.c_str());
    EXPECT_EQ(s.stop_reason, duet::sim::StopReason::kExplorerDone) << s.stop_detail;
    EXPECT_EQ(s.collisions, 0u);
    if (looks == 1) {
      t1 = s.sim_time_s;
      EXPECT_GE(s.explorer.view_goals, 1) << "no view goal through the gap: " << s.stop_detail;
      EXPECT_LT(s.coverage, 0.9) << "room B was explored through a shut door?";
    } else {
      EXPECT_GT(entered_b, opened_at) << "the robot did not look again and go through the opened door: " << s.stop_detail;
      EXPECT_GE(s.coverage, 0.95) << s.stop_detail;
    }
  }
}

TEST(SimDoors, TheViewGoalsStopWhenLookingNoLongerAddsToTheMap) {
  // The gap room looked at with the default number of looks: without a budget the robot looks
  // until no place is left to look at; with a budget no window can meet (1e6 m^2 in 5 s) it
  // looks once (the window begins at the first decision with every frontier unreachable) and
  // stops at the first check, saying why.
  double t_off = -1.0;
  int views_off = -1;
  for (const float min_gain : {0.0f, 1e6f}) {
    auto es = door_settings(1, 600.0);
    es.runtime.explorer.view_min_gain_m2 = min_gain;
    es.runtime.explorer.view_gain_window_s = 5.0f;
    duet::sim::SimExplore run(duet::sim::parse_world(kGapRoom, "gap_room.yaml"), duet::builtin_profile("dual_kinect_kobuki"), es);
    run.run();
    const auto s = run.summary();
    std::printf("view_min_gain_m2 %g: stopped at %.1f s, %d view goals, coverage %.3f: %s\n", static_cast<double>(min_gain), s.sim_time_s,
                s.explorer.view_goals, s.coverage, s.stop_detail.c_str());
    EXPECT_EQ(s.stop_reason, duet::sim::StopReason::kExplorerDone) << s.stop_detail;
    EXPECT_EQ(s.collisions, 0u);
    EXPECT_GE(s.explorer.view_goals, 1) << s.stop_detail;
    const bool noted = s.stop_detail.find("looking at them from view goals added") != std::string::npos;
    if (min_gain == 0.0f) {
      EXPECT_FALSE(noted) << s.stop_detail;
      t_off = s.sim_time_s;
      views_off = s.explorer.view_goals;
    } else {
      EXPECT_TRUE(noted) << s.stop_detail;
      EXPECT_NE(s.stop_detail.find("unreachable through a gap of"), std::string::npos) << "the report of what is left is kept: " << s.stop_detail;
      EXPECT_LT(s.explorer.view_goals, views_off) << "the budget ended no view goal";
      EXPECT_LT(s.sim_time_s, t_off);
    }
  }
}

TEST(SimDoors, TheViewGoalBudgetIsChecked) {
  duet::ExplorerSettings s;
  s.view_min_gain_m2 = -1.0f;
  EXPECT_THROW(duet::validate(s), duet::Error);
  s.view_min_gain_m2 = 5.0f;
  s.view_gain_window_s = 0.0f;
  EXPECT_THROW(duet::validate(s), duet::Error);
  s.view_gain_window_s = 600.0f;
  EXPECT_NO_THROW(duet::validate(s));
}
