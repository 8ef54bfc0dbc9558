// Frontier search (paper §3.2; the frontier cell itself: test_frontier_mask.cpp): clusters vs
// a reference flood fill; find_frontier vs a reference Dijkstra (heap of doubles) over the
// traversable cells: same goal path length, goal is a valid candidate, path valid, per-cluster
// reachability and distance; statuses on hand-made grids (closed room -> kNoFrontier, frontier only
// behind a wall -> kAllUnreachable, blacklist -> kAllBlacklisted, expiry, robot blocked, border
// frontiers not connected, small clusters ignored, min goal distance); GoalBlacklist; invalid
// settings; thread counts; the Willow Garage map with a path to the goal (plan_path).
#include "frontier_reference.hpp"
#include "frontier_test_grids.hpp"
#include "kernel_test_util.hpp"

#include <duet/kernels/error.hpp>
#include <duet/kernels/frontier.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/kernels/path.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <queue>
#include <random>
#include <span>
#include <vector>

namespace duet {
namespace {

using test::kNaN;
using namespace frontier_test;

// ---- find_frontier vs reference ------------------------------------------------------------------------

TEST(Frontier, MatchesReferenceOnRandomGrids) {
  int found = 0, trials = 0;
  for (std::uint32_t seed = 1; seed <= 24; ++seed) {
    const int w = 40 + int(seed % 5) * 30, h = 30 + int(seed % 3) * 40;
    const TestGrid tg = explored(w, h, seed * 31);
    InflationSettings is;
    is.robot_radius_m = seed % 2 ? 0.05f : 0.1f;
    InflatedGrid g;
    inflate(tg.view(), is, g);
    std::vector<std::size_t> trav;
    for (std::size_t i = 0; i < g.cell_count(); ++i)
      if (g.traversable[i]) trav.push_back(i);
    if (trav.empty()) continue;
    std::mt19937 rng(seed);
    std::uniform_int_distribution<std::size_t> pick(0, trav.size() - 1);
    FrontierWorkspace ws;
    for (int k = 0; k < 8; ++k) {  // k < 4: approach cells within 1 m; 4..7: none (0 m) or 0.3 m
      FrontierSettings s;
      s.min_cluster_cells = 1 + k % 4;
      s.min_goal_distance_m = k % 4 == 2 ? 0.0f : 0.5f;
      s.approach_radius_m = k < 4 ? 1.0f : k == 5 ? 0.3f : 0.0f;
      if (k % 3 == 1) s.min_unknown_region_m2 = seed % 2 ? 0.01f : 0.1f;  // 4 or 40 cells at 0.05 m
      GoalBlacklist bl;
      if (k % 4 == 3) bl.add(g.cell_center(trav[pick(rng)]), 0.0, 10.0);
      const Eigen::Vector2f robot = g.cell_center(trav[pick(rng)]);
      const FrontierResult r = find_frontier(g, robot, bl, 1.0, s, ws);
      SCOPED_TRACE(::testing::Message() << "seed " << seed << " k " << k);
      check_against_reference(g, robot, bl, 1.0, s, r);
      ++trials;
      found += r.status == FrontierStatus::kFound;
    }
  }
  EXPECT_GT(found, trials / 3);
}

// ---- statuses on hand-made grids -------------------------------------------------------------------------

// 60 x 40 cells of 0.05 m: known room [5, 30] x [5, 30] walled; unknown outside.
TestGrid closed_room() {
  TestGrid tg = blank(60, 40, kNaN);
  tg.rect(4, 4, 31, 31, kOcc);
  tg.rect(5, 5, 30, 30, kFree);
  return tg;
}

TEST(Frontier, ClosedRoomHasNoFrontier) {
  TestGrid tg = blank(40, 40, kFree);
  tg.rect(0, 0, 39, 0, kOcc);
  tg.rect(0, 39, 39, 39, kOcc);
  tg.rect(0, 0, 0, 39, kOcc);
  tg.rect(39, 0, 39, 39, kOcc);
  InflatedGrid g;
  inflate(tg.view(), InflationSettings{}, g);
  FrontierWorkspace ws;
  const FrontierResult r = find_frontier(g, g.cell_center(20, 20), GoalBlacklist{}, 0.0, FrontierSettings{}, ws);
  EXPECT_EQ(r.status, FrontierStatus::kNoFrontier);
  EXPECT_TRUE(r.clusters.empty());
  // Also with unknown space outside the walls: the walls separate free from unknown.
  const TestGrid room = closed_room();
  inflate(room.view(), InflationSettings{}, g);
  EXPECT_EQ(find_frontier(g, g.cell_center(15, 15), GoalBlacklist{}, 0.0, FrontierSettings{}, ws).status,
            FrontierStatus::kNoFrontier);
}

TEST(Frontier, FrontierBehindWallIsUnreachable) {
  TestGrid tg = closed_room();
  tg.rect(40, 10, 50, 20, kFree);  // a known free patch beyond the wall, bordering unknown space
  InflatedGrid g;
  inflate(tg.view(), InflationSettings{}, g);
  FrontierWorkspace ws;
  const FrontierResult r = find_frontier(g, g.cell_center(15, 15), GoalBlacklist{}, 0.0, FrontierSettings{}, ws);
  EXPECT_EQ(r.status, FrontierStatus::kAllUnreachable);
  ASSERT_EQ(r.clusters.size(), 1u);
  EXPECT_FALSE(r.clusters[0].reachable);
  EXPECT_EQ(r.clusters[0].cells, 40);  // the ring of the 11 x 11 patch
  EXPECT_TRUE(std::isinf(r.clusters[0].path_length_m));
  EXPECT_EQ(g.cell_of(r.clusters[0].nearest_xy), Eigen::Vector2i(40, 15));
}

TEST(Frontier, DoorwayBlacklistExpiryAndMinDistance) {
  TestGrid tg = closed_room();
  tg.rect(31, 16, 31, 21, kFree);  // a 6-cell (0.3 m) door in the right wall: beyond it, unknown
  InflationSettings is;
  is.robot_radius_m = 0.05f;
  InflatedGrid g;
  inflate(tg.view(), is, g);
  FrontierWorkspace ws;
  FrontierSettings s;
  const Eigen::Vector2f robot = g.cell_center(10, 18);
  GoalBlacklist bl;
  FrontierResult r = find_frontier(g, robot, bl, 0.0, s, ws);
  ASSERT_EQ(r.status, FrontierStatus::kFound);
  check_against_reference(g, robot, bl, 0.0, s, r);
  EXPECT_EQ(g.cell_of(r.goal_xy).x(), 31);
  EXPECT_NEAR(r.path_length_m, 21 * 0.05f, 1e-4f);
  // Blacklist the door for 10 s (t = 100): every candidate is blocked.
  bl.add(r.goal_xy, 100.0, 10.0);
  r = find_frontier(g, robot, bl, 105.0, s, ws);
  EXPECT_EQ(r.status, FrontierStatus::kAllBlacklisted);
  ASSERT_EQ(r.clusters.size(), 1u);
  EXPECT_TRUE(r.clusters[0].reachable);
  EXPECT_TRUE(r.clusters[0].blacklisted);
  check_against_reference(g, robot, bl, 105.0, s, r);
  // Expired at t = 110 (blocks while now < expiry), even before expire() removes it.
  EXPECT_EQ(find_frontier(g, robot, bl, 110.0, s, ws).status, FrontierStatus::kFound);
  EXPECT_EQ(bl.size(), 1u);
  bl.expire(110.0);
  EXPECT_EQ(bl.size(), 0u);
  // Too near: the robot stands 0.25 m from the door, min distance 0.5 m -> nothing to go to.
  const Eigen::Vector2f near_door = g.cell_center(26, 18);
  r = find_frontier(g, near_door, bl, 0.0, s, ws);
  EXPECT_EQ(r.status, FrontierStatus::kAllBlacklisted);
  FrontierSettings s0 = s;
  s0.min_goal_distance_m = 0.0f;
  r = find_frontier(g, near_door, bl, 0.0, s0, ws);
  EXPECT_EQ(r.status, FrontierStatus::kFound);
  EXPECT_NEAR(r.path_length_m, 5 * 0.05f, 1e-4f);
  // min_cluster_cells larger than the door's frontier (6 cells): ignored -> no frontier.
  FrontierSettings big = s;
  big.min_cluster_cells = 7;
  EXPECT_EQ(find_frontier(g, robot, bl, 0.0, big, ws).status, FrontierStatus::kNoFrontier);
}

// A gap seen from afar: beyond a 2-cell opening in the room's wall a walled 2-cell (0.1 m) passage,
// narrower than the robot, leads 0.7 m to the unknown. No frontier cell is traversable: without
// approach cells nothing is reachable; with them the goal is a room cell in front of the passage.
TEST(Frontier, NarrowFrontierIsReachedThroughApproachCells) {
  TestGrid tg = closed_room();
  tg.rect(31, 18, 31, 19, kFree);  // the opening
  tg.rect(32, 17, 45, 17, kOcc);   // the passage's walls
  tg.rect(32, 20, 45, 20, kOcc);
  tg.rect(32, 18, 45, 19, kFree);  // the passage; unknown beyond x = 45
  InflationSettings is;
  is.robot_radius_m = 0.1f;
  InflatedGrid g;
  inflate(tg.view(), is, g);
  FrontierWorkspace ws;
  FrontierSettings s;
  s.min_cluster_cells = 1;
  s.approach_radius_m = 0.0f;
  const Eigen::Vector2f robot = g.cell_center(10, 18);
  GoalBlacklist bl;
  FrontierResult r = find_frontier(g, robot, bl, 0.0, s, ws);
  ASSERT_EQ(r.clusters.size(), 1u);
  EXPECT_EQ(r.status, FrontierStatus::kAllUnreachable);
  check_against_reference(g, robot, bl, 0.0, s, r);
  s.approach_radius_m = 1.0f;
  r = find_frontier(g, robot, bl, 0.0, s, ws);
  ASSERT_EQ(r.status, FrontierStatus::kFound);
  check_against_reference(g, robot, bl, 0.0, s, r);
  const Eigen::Vector2i gc = g.cell_of(r.goal_xy), tc = g.cell_of(r.target_xy);
  EXPECT_TRUE(g.traversable[g.index(gc.x(), gc.y())]);
  EXPECT_FALSE(g.traversable[g.index(tc.x(), tc.y())]);
  EXPECT_EQ(tc.x(), 45);  // the target is a frontier cell at the passage's end
  EXPECT_LE(gc.x(), 30);  // the goal is in the room
  EXPECT_LE((r.target_xy - r.goal_xy).norm(), 1.0f + 1e-4f);
  EXPECT_TRUE(r.clusters[0].reachable);
  // The workspace is clean for the next call: the same search without approach cells again.
  s.approach_radius_m = 0.0f;
  EXPECT_EQ(find_frontier(g, robot, bl, 0.0, s, ws).status, FrontierStatus::kAllUnreachable);
  // Blacklisting the target blocks every approach cell of it.
  s.approach_radius_m = 1.0f;
  bl.add(r.target_xy, 0.0, 10.0);
  s.blacklist_radius_m = 1.0f;
  r = find_frontier(g, robot, bl, 1.0, s, ws);
  EXPECT_NE(r.status, FrontierStatus::kFound);
  check_against_reference(g, robot, bl, 1.0, s, r);
  FrontierSettings bad;
  bad.approach_radius_m = -1.0f;
  EXPECT_DUET_ERROR((void)find_frontier(g, robot, bl, 0.0, bad, ws), ErrorCode::kInvalidArgument, "approach_radius_m");
}

// Enclosed unknown pockets: a pillar's inside (never seen) in a known room, and a closet whose
// unknown inside is 5 x 5 cells, next to an open side of the room towards a large unknown area.
TEST(Frontier, EnclosedUnknownPocketsAreNotFrontiers) {
  TestGrid tg = blank(60, 40, kNaN);
  tg.rect(4, 4, 31, 31, kOcc);
  tg.rect(5, 5, 30, 30, kFree);
  tg.rect(31, 10, 31, 14, kFree);  // an opening to the unknown east (large region)
  tg.rect(14, 14, 16, 16, kNaN);   // a 3 x 3 unknown pocket (a pillar's inside seen all around)
  tg.rect(20, 20, 24, 24, kNaN);   // a 5 x 5 pocket
  InflationSettings is;
  is.robot_radius_m = 0.05f;
  InflatedGrid g;
  inflate(tg.view(), is, g);
  FrontierWorkspace ws;
  FrontierSettings s;
  s.min_cluster_cells = 1;
  const Eigen::Vector2f robot = g.cell_center(8, 8);
  FrontierResult r = find_frontier(g, robot, GoalBlacklist{}, 0.0, s, ws);
  EXPECT_EQ(r.clusters.size(), 3u);  // both pockets' rings and the opening
  check_against_reference(g, robot, GoalBlacklist{}, 0.0, s, r);
  s.min_unknown_region_m2 = 0.04f;  // 16 cells: the 3 x 3 pocket goes
  r = find_frontier(g, robot, GoalBlacklist{}, 0.0, s, ws);
  EXPECT_EQ(r.clusters.size(), 2u);
  check_against_reference(g, robot, GoalBlacklist{}, 0.0, s, r);
  s.min_unknown_region_m2 = 0.5f;  // 200 cells: both pockets go; the east region is open to the border
  r = find_frontier(g, robot, GoalBlacklist{}, 0.0, s, ws);
  ASSERT_EQ(r.clusters.size(), 1u);
  check_against_reference(g, robot, GoalBlacklist{}, 0.0, s, r);
  ASSERT_EQ(r.status, FrontierStatus::kFound);
  EXPECT_EQ(g.cell_of(r.goal_xy).x(), 31);
  // The workspace is clean for the next call (verdicts reset): the first result again.
  s.min_unknown_region_m2 = 0.0f;
  EXPECT_EQ(find_frontier(g, robot, GoalBlacklist{}, 0.0, s, ws).clusters.size(), 3u);
  FrontierSettings bad;
  bad.min_unknown_region_m2 = -1.0f;
  EXPECT_DUET_ERROR((void)find_frontier(g, robot, GoalBlacklist{}, 0.0, bad, ws), ErrorCode::kInvalidArgument, "min_unknown_region_m2");
}

TEST(Frontier, RobotBlockedAndBorderFrontiers) {
  TestGrid tg = closed_room();
  tg.rect(31, 16, 31, 21, kFree);
  InflatedGrid g;
  inflate(tg.view(), InflationSettings{}, g);
  FrontierWorkspace ws;
  EXPECT_EQ(find_frontier(g, g.cell_center(4, 15), GoalBlacklist{}, 0.0, FrontierSettings{}, ws).status,
            FrontierStatus::kRobotBlocked);  // in the wall, nothing traversable within 0.2 m
  EXPECT_EQ(find_frontier(g, Eigen::Vector2f(-100.0f, 0.0f), GoalBlacklist{}, 0.0, FrontierSettings{}, ws).status,
            FrontierStatus::kRobotBlocked);
  EXPECT_EQ(find_frontier(g, Eigen::Vector2f(kNaN, 0.0f), GoalBlacklist{}, 0.0, FrontierSettings{}, ws).status,
            FrontierStatus::kRobotBlocked);
  // A free strip touching the grid's top border; unknown only in the top row next to it: its
  // frontier cells are on the border row - 1 and border -> only the non-border ones are connected.
  TestGrid strip = blank(30, 10, kFree);
  strip.rect(0, 9, 29, 9, kNaN);  // unknown top row
  strip.rect(0, 0, 29, 7, kOcc);  // walls below: the free row y = 8 is a corridor
  InflationSettings is;
  is.robot_radius_m = 0.0f;
  inflate(strip.view(), is, g);
  FrontierSettings s;
  s.min_goal_distance_m = 0.0f;
  FrontierResult r = find_frontier(g, g.cell_center(5, 8), GoalBlacklist{}, 0.0, s, ws);
  ASSERT_EQ(r.status, FrontierStatus::kFound);
  const Eigen::Vector2i gc = g.cell_of(r.goal_xy);
  EXPECT_EQ(gc, Eigen::Vector2i(5, 8));
  // Frontier only on the left border column: not connected -> unreachable.
  TestGrid col = blank(10, 10, kFree);
  col.rect(0, 0, 0, 9, kNaN);
  inflate(col.view(), is, g);
  r = find_frontier(g, g.cell_center(5, 5), GoalBlacklist{}, 0.0, s, ws);
  ASSERT_EQ(r.clusters.size(), 1u);
  EXPECT_EQ(r.clusters[0].cells, 10);  // column x = 1
  EXPECT_EQ(r.status, FrontierStatus::kFound);  // x = 1, y in 1..8 are connected
  EXPECT_EQ(g.cell_of(r.goal_xy).x(), 1);
  TestGrid corner = blank(3, 3, kFree);
  corner.set(0, 0, kNaN);
  inflate(corner.view(), is, g);
  r = find_frontier(g, g.cell_center(2, 2), GoalBlacklist{}, 0.0, s, ws);
  EXPECT_EQ(r.status, FrontierStatus::kFound);  // (1, 1) is the one connected frontier cell
  EXPECT_EQ(g.cell_of(r.goal_xy), Eigen::Vector2i(1, 1));
  TestGrid tiny = blank(2, 2, kFree);
  tiny.set(0, 0, kNaN);
  inflate(tiny.view(), is, g);
  FrontierSettings s1 = s;
  s1.min_cluster_cells = 1;
  r = find_frontier(g, g.cell_center(1, 1), GoalBlacklist{}, 0.0, s1, ws);
  EXPECT_EQ(r.status, FrontierStatus::kAllUnreachable);  // 2x2: no cell has 8 neighbours
  EXPECT_TRUE(r.clusters[0].reachable);
}

TEST(Frontier, BlacklistClass) {
  GoalBlacklist bl;
  EXPECT_EQ(bl.size(), 0u);
  EXPECT_FALSE(bl.blocks({0, 0}, 1.0f, 0.0));
  bl.add({1.0f, 2.0f}, 10.0, 5.0);
  bl.add({-4.0f, 0.0f}, 10.0, std::numeric_limits<double>::infinity());
  EXPECT_TRUE(bl.blocks({1.5f, 2.0f}, 0.5f, 12.0));   // 0.5 away (exact in float): inclusive
  EXPECT_FALSE(bl.blocks({1.3f, 2.41f}, 0.5f, 12.0));
  EXPECT_FALSE(bl.blocks({1.0f, 2.0f}, 0.5f, 15.0));  // expired at 15
  EXPECT_TRUE(bl.blocks({-4.0f, 0.0f}, 0.0f, 1e12));
  bl.expire(15.0);
  EXPECT_EQ(bl.size(), 1u);
  bl.clear();
  EXPECT_EQ(bl.size(), 0u);
  EXPECT_DUET_ERROR(bl.add({kNaN, 0.0f}, 0.0, 1.0), ErrorCode::kInvalidArgument, "xy");
  EXPECT_DUET_ERROR(bl.add({0.0f, 0.0f}, kNaN, 1.0), ErrorCode::kInvalidArgument, "now_s");
  EXPECT_DUET_ERROR(bl.add({0.0f, 0.0f}, 0.0, 0.0), ErrorCode::kInvalidArgument, "ttl_s");
  EXPECT_DUET_ERROR(bl.add({0.0f, 0.0f}, 0.0, -1.0), ErrorCode::kInvalidArgument, "ttl_s");
}

TEST(Frontier, InvalidSettings) {
  const TestGrid tg = closed_room();
  InflatedGrid g;
  inflate(tg.view(), InflationSettings{}, g);
  FrontierWorkspace ws;
  FrontierSettings s;
  s.min_cluster_cells = 0;
  EXPECT_DUET_ERROR((void)find_frontier(g, {0, 0}, GoalBlacklist{}, 0.0, s, ws), ErrorCode::kInvalidArgument, "min_cluster_cells");
  s = FrontierSettings{};
  s.min_goal_distance_m = -1.0f;
  EXPECT_DUET_ERROR((void)find_frontier(g, {0, 0}, GoalBlacklist{}, 0.0, s, ws), ErrorCode::kInvalidArgument, "min_goal_distance_m");
  s = FrontierSettings{};
  s.blacklist_radius_m = kNaN;
  EXPECT_DUET_ERROR((void)find_frontier(g, {0, 0}, GoalBlacklist{}, 0.0, s, ws), ErrorCode::kInvalidArgument, "blacklist_radius_m");
  g.state.pop_back();
  EXPECT_DUET_ERROR((void)find_frontier(g, {0, 0}, GoalBlacklist{}, 0.0, FrontierSettings{}, ws), ErrorCode::kInvalidArgument,
                    "width*height");
  InflatedGrid empty;
  EXPECT_EQ(find_frontier(empty, {0, 0}, GoalBlacklist{}, 0.0, FrontierSettings{}, ws).status, FrontierStatus::kNoFrontier);
  for (auto st : {FrontierStatus::kFound, FrontierStatus::kNoFrontier, FrontierStatus::kAllUnreachable,
                  FrontierStatus::kAllBlacklisted, FrontierStatus::kRobotBlocked})
    EXPECT_GT(std::string(to_string(st)).size(), 3u);
}

TEST(Frontier, ThreadCountIndependentAndWorkspaceReuse) {
  const TestGrid tg = explored(500, 380, 2024);
  InflatedGrid g;
  inflate(tg.view(), InflationSettings{}, g);
  std::size_t start = 0;
  for (std::size_t i = g.cell_count() / 2; i < g.cell_count(); ++i)
    if (g.traversable[i]) {
      start = i;
      break;
    }
  FrontierWorkspace w1, w2;
  const FrontierResult a = test::in_arena(1, [&] { return find_frontier(g, g.cell_center(start), GoalBlacklist{}, 0.0, FrontierSettings{}, w1); });
  const FrontierResult b = test::in_arena(2, [&] { return find_frontier(g, g.cell_center(start), GoalBlacklist{}, 0.0, FrontierSettings{}, w2); });
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.goal_xy, b.goal_xy);
  EXPECT_EQ(a.path, b.path);
  ASSERT_EQ(a.clusters.size(), b.clusters.size());
  for (std::size_t k = 0; k < a.clusters.size(); ++k) {
    EXPECT_EQ(a.clusters[k].centroid, b.clusters[k].centroid);
    EXPECT_EQ(a.clusters[k].nearest_xy, b.clusters[k].nearest_xy);
    EXPECT_EQ(a.clusters[k].path_length_m, b.clusters[k].path_length_m);
  }
  // Reuse w1 on another grid, then on the first again.
  const TestGrid other = explored(90, 200, 5);
  InflatedGrid g2;
  inflate(other.view(), InflationSettings{}, g2);
  (void)find_frontier(g2, g2.cell_center(std::size_t{0}), GoalBlacklist{}, 0.0, FrontierSettings{}, w1);
  const FrontierResult c = find_frontier(g, g.cell_center(start), GoalBlacklist{}, 0.0, FrontierSettings{}, w1);
  EXPECT_EQ(c.goal_xy, a.goal_xy);
  EXPECT_EQ(c.path, a.path);
  check_against_reference(g, g.cell_center(start), GoalBlacklist{}, 0.0, FrontierSettings{}, a);
}

// A serpentine corridor of ~80000 cells: path lengths beyond the 32-bit fixed-point range
// (65535 cells), so the search reruns on 64-bit costs; the result must still match the reference.
TEST(Frontier, VeryLongPathsUse64BitCosts) {
  const int w = 400, h = 401;
  TestGrid tg = blank(w, h, kOcc, 0.05f);
  for (int y = 1; y <= h - 2; y += 2) tg.rect(1, y, w - 2, y, kFree);
  for (int y = 2; y <= h - 3; y += 2) tg.set((y / 2) % 2 ? w - 2 : 1, y, kFree);
  tg.rect(w / 2 - 1, h - 2, w / 2 + 1, h - 2, kNaN);  // unknown patch in the last corridor
  InflationSettings is;
  is.robot_radius_m = 0.0f;
  InflatedGrid g;
  inflate(tg.view(), is, g);
  FrontierSettings s;
  s.min_cluster_cells = 1;
  FrontierWorkspace ws;
  const Eigen::Vector2f robot = g.cell_center(1, 1);
  const FrontierResult r = find_frontier(g, robot, GoalBlacklist{}, 0.0, s, ws);
  ASSERT_EQ(r.status, FrontierStatus::kFound);
  EXPECT_GT(r.path_length_m, 70000 * 0.05f);
  EXPECT_EQ(r.clusters.size(), 2u);
  check_against_reference(g, robot, GoalBlacklist{}, 0.0, s, r);
}

// ---- real data: the Willow Garage map ----------------------------------------------------------------

constexpr const char* kWillow = test::kWillowMap;

// The Willow map (test::willow_trinary(): 205 = unknown, darker = occupied, lighter = free).
TestGrid load_willow() {
  test::WillowGrid m = test::willow_trinary(kOcc, kFree);
  TestGrid g;
  g.w = m.w;
  g.h = m.h;
  g.res = 0.10f;
  g.origin = {0.0f, 0.0f};
  g.l = std::move(m.logodds);
  return g;
}

TEST(Frontier, WillowMapFrontierAndPath) {
  DUET_REQUIRE_DATA(kWillow);
  const TestGrid tg = load_willow();
  ASSERT_GT(tg.w, 0) << "cannot decode " << kWillow;
  InflatedGrid g;
  inflate(tg.view(), InflationSettings{}, g);
  // Robot: the traversable cell with the largest clearance (deterministic; inside the building).
  std::size_t robot = 0;
  float best = -1.0f;
  for (std::size_t i = 0; i < g.cell_count(); ++i)
    if (g.traversable[i] && std::isfinite(g.clearance_m[i]) && g.clearance_m[i] > best) {
      best = g.clearance_m[i];
      robot = i;
    }
  ASSERT_TRUE(g.traversable[robot]);
  const Eigen::Vector2f robot_xy = g.cell_center(robot);
  FrontierWorkspace ws1, ws2;
  const FrontierSettings s;
  const FrontierResult a = test::in_arena(1, [&] { return find_frontier(g, robot_xy, GoalBlacklist{}, 0.0, s, ws1); });
  const FrontierResult b = test::in_arena(2, [&] { return find_frontier(g, robot_xy, GoalBlacklist{}, 0.0, s, ws2); });
  ASSERT_EQ(a.status, FrontierStatus::kFound) << to_string(a.status);
  EXPECT_EQ(a.goal_xy, b.goal_xy);
  EXPECT_EQ(a.path, b.path);
  EXPECT_EQ(a.clusters.size(), b.clusters.size());
  EXPECT_GT(a.clusters.size(), 5u);
  check_against_reference(g, robot_xy, GoalBlacklist{}, 0.0, s, a);
  // plan_path with no clearance cost runs on the same graph: same length to the goal.
  PathWorkspace pws;
  PathSettings ps;
  ps.clearance_weight = 0.0f;
  const PathResult p0 = plan_path(g, robot_xy, a.goal_xy, ps, pws);
  ASSERT_EQ(p0.status, PathStatus::kFound);
  EXPECT_NEAR(p0.length_m, a.path_length_m, 1e-3f);
  const PathResult p = plan_path(g, robot_xy, a.goal_xy, PathSettings{}, pws);
  ASSERT_EQ(p.status, PathStatus::kFound);
  EXPECT_GE(p.length_m, p0.length_m - 1e-4f);
  EXPECT_GE(p.cost, p.length_m);
  for (const auto& wp : p.waypoints) {
    const Eigen::Vector2i c = g.cell_of(wp);
    ASSERT_TRUE(g.traversable[g.index(c.x(), c.y())]);
  }
  // Blacklisting the goal moves the goal elsewhere (or reports why not).
  GoalBlacklist bl;
  bl.add(a.goal_xy, 0.0, 60.0);
  const FrontierResult c = find_frontier(g, robot_xy, bl, 1.0, s, ws1);
  check_against_reference(g, robot_xy, bl, 1.0, s, c);
  if (c.status == FrontierStatus::kFound) {
    EXPECT_GT((c.goal_xy - a.goal_xy).norm(), s.blacklist_radius_m);
  }
}

// FrontierSelection::kExploreLite: explore_lite's cost (potential_scale * distance - gain_scale *
// size) prefers a large frontier a little farther away over a small one next to the robot;
// kNearest takes the nearest; with gain_scale = 0 the cost is the distance alone.
TEST(Frontier, ExploreLiteCostPrefersLargeFrontiers) {
  TestGrid tg = blank(100, 40, kFree);
  tg.rect(0, 0, 99, 0, kOcc);
  tg.rect(0, 39, 99, 39, kOcc);
  tg.rect(0, 0, 0, 39, kOcc);
  tg.rect(99, 0, 99, 39, kOcc);
  tg.rect(15, 19, 16, 20, kNaN);  // small unknown pocket, ~10 cells from the robot
  tg.rect(60, 8, 90, 31, kNaN);   // large unknown region, ~35 cells away
  InflatedGrid g;
  inflate(tg.view(), InflationSettings{}, g);
  FrontierWorkspace ws;
  const Eigen::Vector2f robot = g.cell_center(25, 20);
  FrontierSettings s;
  s.min_goal_distance_m = 0.0f;
  const FrontierResult nearest = find_frontier(g, robot, GoalBlacklist{}, 0.0, s, ws);
  ASSERT_EQ(nearest.status, FrontierStatus::kFound);
  EXPECT_LT(g.cell_of(nearest.goal_xy).x(), 25);
  s.selection = FrontierSelection::kExploreLite;
  const FrontierResult lite = find_frontier(g, robot, GoalBlacklist{}, 0.0, s, ws);
  ASSERT_EQ(lite.status, FrontierStatus::kFound);
  EXPECT_GE(g.cell_of(lite.goal_xy).x(), 55);
  // The goal is that cluster's nearest cell by path, and the path leads there.
  ASSERT_FALSE(lite.path.empty());
  EXPECT_EQ(g.cell_of(lite.path.back()), g.cell_of(lite.goal_xy));
  EXPECT_NEAR(lite.path_length_m, (g.cell_of(lite.goal_xy) - Eigen::Vector2i(25, 20)).cast<float>().norm() * 0.05f, 0.5f);
  // The same clusters and statuses as the nearest selection (only the choice differs).
  ASSERT_EQ(lite.clusters.size(), nearest.clusters.size());
  for (std::size_t k = 0; k < lite.clusters.size(); ++k) {
    EXPECT_EQ(lite.clusters[k].cells, nearest.clusters[k].cells);
    EXPECT_EQ(lite.clusters[k].path_length_m, nearest.clusters[k].path_length_m);
  }
  s.gain_scale = 0.0f;  // distance only: the small pocket again
  EXPECT_LT(g.cell_of(find_frontier(g, robot, GoalBlacklist{}, 0.0, s, ws).goal_xy).x(), 25);
  // Blacklisting the large region's goal moves explore_lite's choice to the other cluster.
  s.gain_scale = 1.0f;
  GoalBlacklist bl;
  bl.add(lite.goal_xy, 0.0, 100.0);
  s.blacklist_radius_m = 20.0f * 0.05f;
  const FrontierResult second = find_frontier(g, robot, bl, 0.0, s, ws);
  ASSERT_EQ(second.status, FrontierStatus::kFound);
  EXPECT_GT((second.goal_xy - lite.goal_xy).norm(), s.blacklist_radius_m);
  // Bad weights are named.
  s.potential_scale = -1.0f;
  EXPECT_THROW(validate(s), Error);
  s.potential_scale = 3.0f;
  s.gain_scale = NAN;
  EXPECT_THROW(validate(s), Error);
}

}  // namespace
}  // namespace duet

