// What exploration left, where and why (navigation/unexplored.hpp): on a hand-made map - the
// robot's room, a wall with a gap narrower than the robot into a second room whose far side is
// unknown, a frontier in the robot's room where goals failed, one that was looked at, one seen
// across unknown space - each region gets its reason, the gap its width; describe() names them;
// empty, NaN and off-grid input; and a Navigator that gives up reports them in its stop detail.
#include <duet/kernels/frontier.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/runtime/navigation/unexplored.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace duet {
namespace test_unexplored {

constexpr float kFreeL = -2.0f, kOccL = 3.0f, kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr int kW = 120, kH = 60;  // 6 m x 3 m at 5 cm

struct Map {
  std::vector<float> l = std::vector<float>(static_cast<std::size_t>(kW) * kH, kFreeL);
  void set(int x0, int x1, int y0, int y1, float v) {
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) l[static_cast<std::size_t>(y) * kW + x] = v;
  }
  [[nodiscard]] InflatedGrid inflated() const {
    InflatedGrid g;
    InflationSettings s;
    s.robot_radius_m = 0.2f;
    inflate(GridView(l, kW, kH, 0.05f, Eigen::Vector2f(0.0f, 0.0f)), s, g);
    return g;
  }
};

// The frontier cells of g (free cells with an unknown 8-neighbour), as cell centres.
std::vector<Eigen::Vector2f> frontier_points(const InflatedGrid& g) {
  std::vector<std::uint8_t> mask(g.cell_count());
  (void)frontier_mask(g.state, g.width, g.height, mask);
  std::vector<Eigen::Vector2f> p;
  for (std::size_t i = 0; i < mask.size(); ++i)
    if (mask[i]) p.push_back(g.cell_center(i));
  return p;
}

// Room A: x < 2.5 m. Wall at x 2.5-2.65 m with a gap of 7 cells (0.35 m) at y 1.5-1.85 m.
// Room B: x 2.65-4.0 m known free, unknown beyond x = 4 m.
Map gap_map() {
  Map m;
  m.set(50, 52, 0, kH - 1, kOccL);
  m.set(50, 52, 30, 36, kFreeL);
  m.set(80, kW - 1, 0, kH - 1, kNaN);
  return m;
}

const UnexploredRegion* region_near(const std::vector<UnexploredRegion>& r, Eigen::Vector2f xy, float within) {
  for (const UnexploredRegion& x : r)
    if ((x.centroid - xy).norm() < within) return &x;
  return nullptr;
}

TEST(Unexplored, ARoomBehindAGapNarrowerThanTheRobotIsNamedWithTheGap) {
  const InflatedGrid g = gap_map().inflated();
  const std::vector<Eigen::Vector2f> f = frontier_points(g);
  ASSERT_FALSE(f.empty());
  const std::vector<Eigen::Vector2f> looked{{3.975f, 1.6f}};  // a view goal looked through the gap
  const auto left = find_unexplored(g, Eigen::Vector2f(1.0f, 1.5f), f, {}, looked);
  ASSERT_EQ(left.size(), 1u);
  EXPECT_EQ(left[0].why, LeftWhy::kNarrowGap);  // unreachable first, looked at second
  EXPECT_TRUE(left[0].looked_at);
  EXPECT_NEAR(left[0].gap_m, 0.35f, 0.051f);  // exact to one cell
  EXPECT_FLOAT_EQ(left[0].needed_m, 0.4f);
  EXPECT_NEAR(left[0].centroid.x(), 3.975f, 0.03f);
  EXPECT_EQ(left[0].cells, kH);
  const std::string d = describe(left);
  EXPECT_NE(d.find("1 region left"), std::string::npos) << d;
  EXPECT_NE(d.find("unreachable through a gap of 0.3"), std::string::npos) << d;
  EXPECT_NE(d.find("the robot needs 0.40 m"), std::string::npos) << d;
  EXPECT_NE(d.find("looked at from a view goal"), std::string::npos) << d;
}

TEST(Unexplored, AWideEnoughGapLeavesTheRoomReachableAndFailedGoalsAreCounted) {
  Map m = gap_map();
  m.set(50, 52, 20, 45, kFreeL);  // 1.3 m
  const InflatedGrid g = m.inflated();
  const std::vector<Eigen::Vector2f> f = frontier_points(g);
  auto left = find_unexplored(g, Eigen::Vector2f(1.0f, 1.5f), f, {}, {});
  ASSERT_EQ(left.size(), 1u);
  EXPECT_EQ(left[0].why, LeftWhy::kReachable);
  EXPECT_GT(left[0].gap_m, 0.4f);
  const std::vector<GoalFailures> failures{{Eigen::Vector2f(3.975f, 1.0f), 3}, {Eigen::Vector2f(1.0f, 1.0f), 5}};
  left = find_unexplored(g, Eigen::Vector2f(1.0f, 1.5f), f, failures, {});
  ASSERT_EQ(left.size(), 1u);
  EXPECT_EQ(left[0].why, LeftWhy::kAbandoned);
  EXPECT_EQ(left[0].failures, 3);  // the one 3 m away is not this region's
  EXPECT_NE(describe(left).find("abandoned after 3 failed goals"), std::string::npos) << describe(left);
  const std::vector<Eigen::Vector2f> looked{{3.975f, 2.0f}};
  left = find_unexplored(g, Eigen::Vector2f(1.0f, 1.5f), f, failures, looked);
  ASSERT_EQ(left.size(), 1u);
  EXPECT_EQ(left[0].why, LeftWhy::kLookedAt);
  EXPECT_TRUE(left[0].looked_at);
  EXPECT_NE(describe(left).find("looked at"), std::string::npos);
  EXPECT_NE(describe(left).find("3 failed goals there"), std::string::npos) << describe(left);
  const std::vector<Eigen::Vector2f> elsewhere{{1.0f, 2.0f}};  // 3 m from the region
  EXPECT_EQ(find_unexplored(g, Eigen::Vector2f(1.0f, 1.5f), f, {}, elsewhere)[0].why, LeftWhy::kReachable);
}

TEST(Unexplored, AFrontierSeenAcrossUnknownSpaceHasNoKnownWay) {
  Map m = gap_map();
  m.set(50, 52, 30, 36, kOccL);  // the gap closed: room B only seen over the wall
  const InflatedGrid g = m.inflated();
  const auto left = find_unexplored(g, Eigen::Vector2f(1.0f, 1.5f), frontier_points(g), {}, {});
  ASSERT_EQ(left.size(), 1u);
  EXPECT_EQ(left[0].why, LeftWhy::kNoKnownWay);
  EXPECT_EQ(left[0].gap_m, 0.0f);
  EXPECT_NE(describe(left).find("no known free way"), std::string::npos);
  // Right behind the wall (room B known only 3 cells deep): the region's approach does not
  // reach across the wall into room A.
  m.set(56, kW - 1, 0, kH - 1, kNaN);
  const InflatedGrid thin = m.inflated();
  const auto behind = find_unexplored(thin, Eigen::Vector2f(1.0f, 1.5f), frontier_points(thin), {}, {});
  ASSERT_EQ(behind.size(), 1u);
  EXPECT_EQ(behind[0].why, LeftWhy::kNoKnownWay);
  UnexploredSettings approach;  // approach cells spread through free cells only
  approach.approach_radius_m = 0.5f;
  EXPECT_EQ(find_unexplored(thin, Eigen::Vector2f(1.0f, 1.5f), frontier_points(thin), {}, {}, approach)[0].why, LeftWhy::kNoKnownWay);
}

TEST(Unexplored, RegionsAreSeparatedAndListedLargestFirst) {
  Map m = gap_map();
  m.set(10, 14, 10, 14, kNaN);  // a small unknown patch in room A: its own reachable region (20 cells)
  const InflatedGrid g = m.inflated();
  const auto left = find_unexplored(g, Eigen::Vector2f(1.0f, 2.5f), frontier_points(g), {}, {});
  ASSERT_EQ(left.size(), 2u);
  EXPECT_GT(left[0].cells, left[1].cells);
  EXPECT_EQ(left[0].why, LeftWhy::kNarrowGap);
  const UnexploredRegion* patch = region_near(left, Eigen::Vector2f(0.625f, 0.625f), 0.2f);
  ASSERT_NE(patch, nullptr);
  EXPECT_EQ(patch->why, LeftWhy::kReachable);
  EXPECT_EQ(patch->cells, 24);  // the 7 x 7 ring around the 5 x 5 patch
  UnexploredSettings s;
  s.min_cells = 30;
  EXPECT_EQ(find_unexplored(g, Eigen::Vector2f(1.0f, 2.5f), frontier_points(g), {}, {}, s).size(), 1u);
  EXPECT_NE(describe(left, 1).find("and 1 more"), std::string::npos) << describe(left, 1);
}

TEST(Unexplored, EmptyNaNAndOffGridInput) {
  const InflatedGrid g = gap_map().inflated();
  EXPECT_TRUE(find_unexplored(g, Eigen::Vector2f(1.0f, 1.5f), {}, {}, {}).empty());
  EXPECT_TRUE(describe({}).empty());
  const std::vector<Eigen::Vector2f> odd{{kNaN, 1.0f}, {-5.0f, 1.0f}, {100.0f, 100.0f}};
  EXPECT_TRUE(find_unexplored(g, Eigen::Vector2f(1.0f, 1.5f), odd, {}, {}).empty());
  EXPECT_TRUE(find_unexplored(InflatedGrid{}, Eigen::Vector2f(1.0f, 1.5f), frontier_points(g), {}, {}).empty());
  // A robot off the grid (or NaN) reaches nothing: every region has no known way.
  for (const Eigen::Vector2f& robot : {Eigen::Vector2f(-3.0f, 1.0f), Eigen::Vector2f(kNaN, kNaN)}) {
    const auto left = find_unexplored(g, robot, frontier_points(g), {}, {});
    ASSERT_EQ(left.size(), 1u);
    EXPECT_EQ(left[0].why, LeftWhy::kNoKnownWay);
  }
}

}  // namespace test_unexplored
}  // namespace duet
