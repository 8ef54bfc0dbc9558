// accumulate_grid (how a grid is rebuilt from submaps after loop closure) against a reference by
// forward reasoning; adding to what is there; observed_extent; bad input.
#include "kernel_test_util.hpp"

#include <duet/kernels/error.hpp>
#include <duet/kernels/grid.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace duet {
namespace test_accumulate_grid {

using test::kNaN;

// accumulate_grid: a reference by forward reasoning on a small grid - each observed src cell
// moved by T lands in the dst cell its centre maps to (exact for multiples of 90 deg and whole-
// cell shifts), log-odds summed and clamped; unknown stays unknown.
TEST(AccumulateGrid, WholeCellShiftsAndQuarterTurnsMatchTheReference) {
  const float res = 0.1f;
  OccupancyGrid src(res, {0.0f, 0.0f}, 7, 5);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-2.0f, 3.5f);
  for (float& l : src.logodds()) l = (rng() % 3 == 0) ? OccupancyGrid::kUnknown : u(rng);
  for (const Pose2 T : {Pose2{0.0f, 0.0f, 0.0f}, Pose2{0.3f, -0.5f, 0.0f}, Pose2{1.0f, 2.0f, std::numbers::pi_v<float> / 2},
                        Pose2{-0.4f, 0.2f, std::numbers::pi_v<float>}}) {
    OccupancyGrid dst(res);
    accumulate_grid(dst, src, T, -2.0f, 3.5f);
    accumulate_grid(dst, src, T, -2.0f, 3.5f);  // twice: sums clamp
    const float c = std::cos(T.theta), s = std::sin(T.theta);
    std::size_t seen = 0;
    for (int y = 0; y < src.height(); ++y)
      for (int x = 0; x < src.width(); ++x) {
        const Eigen::Vector2f p = src.cell_center(x, y);
        const Eigen::Vector2f q(T.x + c * p.x() - s * p.y(), T.y + s * p.x() + c * p.y());
        const Eigen::Vector2i d = dst.cell_of(q);
        ASSERT_TRUE(dst.in_bounds(d.x(), d.y()));
        const float l = src.at(x, y);
        if (std::isnan(l)) {
          EXPECT_TRUE(std::isnan(dst.at(d.x(), d.y())));
        } else {
          EXPECT_NEAR(dst.at(d.x(), d.y()), std::clamp(2.0f * l, -2.0f, 3.5f), 1e-6f);
          ++seen;
        }
      }
    EXPECT_EQ(dst.known_cells(), seen);
    // Alignment: the origin stays on whole cells.
    EXPECT_NEAR(std::remainder(dst.origin().x(), res), 0.0f, 1e-5f);
  }
}

TEST(AccumulateGrid, AddsToWhatIsThereAndAnEmptySourceDoesNothing) {
  OccupancyGrid dst(0.05f, {-1.0f, -1.0f}, 40, 40);
  dst.logodds()[dst.index(20, 20)] = 1.0f;
  OccupancyGrid src(0.05f, {-1.0f, -1.0f}, 40, 40);
  src.logodds()[src.index(20, 20)] = 0.85f;
  src.logodds()[src.index(21, 20)] = -0.4f;
  Eigen::Vector2f lo(7.0f, 7.0f), hi(7.0f, 7.0f);
  EXPECT_FALSE(observed_extent(OccupancyGrid(0.05f), lo, hi));
  EXPECT_FALSE(observed_extent(OccupancyGrid(0.05f, {0.0f, 0.0f}, 3, 3), lo, hi));
  EXPECT_EQ(lo.x(), 7.0f);
  ASSERT_TRUE(observed_extent(src, lo, hi));
  EXPECT_NEAR(lo.x(), 0.0f, 1e-5f);   // cell 20 starts at -1 + 20 * 0.05
  EXPECT_NEAR(lo.y(), 0.0f, 1e-5f);
  EXPECT_NEAR(hi.x(), 0.1f, 1e-5f);   // cell 21 ends at 0.1
  EXPECT_NEAR(hi.y(), 0.05f, 1e-5f);
  accumulate_grid(dst, src, Pose2{}, -2.0f, 3.5f);
  EXPECT_NEAR(dst.at(20, 20), 1.85f, 1e-6f);
  EXPECT_NEAR(dst.at(21, 20), -0.4f, 1e-6f);
  EXPECT_EQ(dst.known_cells(), 2u);
  const OccupancyGrid before = dst;
  accumulate_grid(dst, OccupancyGrid(0.05f), Pose2{1, 2, 3}, -2.0f, 3.5f);
  accumulate_grid(dst, OccupancyGrid(0.05f, {0.0f, 0.0f}, 10, 10), Pose2{}, -2.0f, 3.5f);  // all unknown
  EXPECT_EQ(dst.width(), before.width());
  EXPECT_EQ(dst.known_cells(), 2u);
}

TEST(AccumulateGrid, BadInputThrowsAndLeavesTheGrid) {
  OccupancyGrid dst(0.05f, {0.0f, 0.0f}, 4, 4);
  OccupancyGrid src(0.1f, {0.0f, 0.0f}, 4, 4);
  src.logodds()[0] = 1.0f;
  EXPECT_THROW(accumulate_grid(dst, src, Pose2{}, -2.0f, 3.5f), Error);
  OccupancyGrid src2(0.05f, {0.0f, 0.0f}, 4, 4);
  src2.logodds()[0] = 1.0f;
  EXPECT_THROW(accumulate_grid(dst, src2, Pose2{kNaN, 0.0f, 0.0f}, -2.0f, 3.5f), Error);
  EXPECT_THROW(accumulate_grid(dst, src2, Pose2{}, 1.0f, -1.0f), Error);
  EXPECT_EQ(dst.known_cells(), 0u);
  EXPECT_EQ(dst.width(), 4);
}

}  // namespace test_accumulate_grid
}  // namespace duet
