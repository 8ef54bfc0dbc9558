// OccupancyGrid, the value type: growth keeps cells at their world position (and its limits),
// probabilities and ROS trinary values, cell_of / cell_center / index. update_grid: test_grid.cpp.
#include "grid_test_util.hpp"
#include "kernel_test_util.hpp"

#include <duet/kernels/error.hpp>
#include <duet/kernels/grid.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace duet {
namespace test_occupancy_grid {

using test::kNaN;
using test::same_grid;

// ---- tests: OccupancyGrid --------------------------------------------------------------------------

TEST(Grid, GrowthKeepsCellsAtTheirWorldPosition) {
  OccupancyGrid g(0.05f, Eigen::Vector2f(1.3f, -0.7f), 30, 20);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-2.0f, 3.5f);
  std::vector<std::pair<Eigen::Vector2f, float>> marks;
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < g.width(); ++x) {
      const float v = (x * 7 + y * 3) % 5 == 0 ? kNaN : u(rng);
      g.logodds()[g.index(x, y)] = v;
      marks.emplace_back(g.cell_center(x, y), v);
    }
  const float before_res = g.resolution();
  const std::vector<std::pair<Eigen::Vector2f, Eigen::Vector2f>> boxes{
      {{-3.013f, -4.007f}, {-2.011f, -3.512f}}, {{10.017f, 0.013f}, {12.019f, 1.011f}}, {{0.012f, 5.009f}, {0.113f, 9.021f}},
      {{-20.007f, -20.013f}, {25.011f, 30.017f}}};
  for (const auto& [lo, hi] : boxes) {
    g.ensure_contains(lo, hi, 3);
    EXPECT_EQ(g.resolution(), before_res);
    EXPECT_EQ(g.cell_count(), static_cast<std::size_t>(g.width()) * static_cast<std::size_t>(g.height()));
    // The box plus the margin is inside.
    const Eigen::Vector2i a = g.cell_of(lo), b = g.cell_of(hi);
    EXPECT_TRUE(g.in_bounds(a.x() - 3, a.y() - 3) && g.in_bounds(b.x() + 3, b.y() + 3));
    // Every old cell holds its old value at its old world position.
    std::size_t known = 0;
    for (const auto& [xy, v] : marks) {
      const Eigen::Vector2i c = g.cell_of(xy);
      ASSERT_TRUE(g.in_bounds(c.x(), c.y()));
      const float now = g.at(c.x(), c.y());
      if (std::isnan(v)) {
        EXPECT_TRUE(std::isnan(now));
      } else {
        EXPECT_EQ(now, v);
        ++known;
      }
      EXPECT_LT((g.cell_center(c.x(), c.y()) - xy).norm(), 1e-4f);  // on the same lattice
    }
    EXPECT_EQ(g.known_cells(), known);  // new cells are unknown
  }
  // Already inside: no change.
  const auto w = g.width(), h = g.height();
  const Eigen::Vector2f o = g.origin();
  g.ensure_contains(Eigen::Vector2f(0, 0), Eigen::Vector2f(1, 1), 2);
  EXPECT_EQ(g.width(), w);
  EXPECT_EQ(g.height(), h);
  EXPECT_EQ(g.origin(), o);
}

TEST(Grid, GrowthFromEmptyAndLimits) {
  OccupancyGrid g(0.1f);
  EXPECT_EQ(g.cell_count(), 0u);
  EXPECT_EQ(g.known_cells(), 0u);
  g.ensure_contains(Eigen::Vector2f(-1.0f, 2.0f), Eigen::Vector2f(1.0f, 2.5f), 0);
  EXPECT_GE(g.width(), 20);
  EXPECT_GE(g.height(), 5);
  EXPECT_LE(g.width(), 22);
  EXPECT_LE(g.height(), 7);
  EXPECT_EQ(g.known_cells(), 0u);
  const auto kOut = ErrorCode::kOutOfRange;
  const OccupancyGrid before = g;
  EXPECT_DUET_ERROR(g.ensure_contains(Eigen::Vector2f(0, 0), Eigen::Vector2f(kNaN, 0), 0), kOut, "not finite");
  EXPECT_DUET_ERROR(g.ensure_contains(Eigen::Vector2f(-1e7f, 0), Eigen::Vector2f(1e7f, 1), 0), kOut, "limit");
  EXPECT_DUET_ERROR(g.ensure_contains(Eigen::Vector2f(0, 0), Eigen::Vector2f(100, 100), 0, 1000), kOut, "limit");
  EXPECT_TRUE(same_grid(g, before));  // a failed growth changes nothing
  EXPECT_DUET_ERROR(OccupancyGrid{0.0f}, ErrorCode::kInvalidArgument, "resolution");
  EXPECT_DUET_ERROR(OccupancyGrid{kNaN}, ErrorCode::kInvalidArgument, "resolution");
  EXPECT_DUET_ERROR(OccupancyGrid(0.1f, Eigen::Vector2f(0, 0), -1, 5), ErrorCode::kInvalidArgument, "size");
  EXPECT_DUET_ERROR(OccupancyGrid(0.1f, Eigen::Vector2f(0, 0), 100000, 100000), kOut, "too large");
}

TEST(Grid, ProbabilitiesAndRosTrinary) {
  OccupancyGrid g(0.1f, Eigen::Vector2f(0, 0), 8, 1);
  const std::vector<float> l{kNaN, 0.0f, 3.5f, -2.0f, 0.85f, -0.4f, 0.61f, -1.41f};
  std::copy(l.begin(), l.end(), g.logodds().begin());
  std::vector<float> p(8);
  g.to_probabilities(p);
  EXPECT_EQ(p[0], -1.0f);
  for (std::size_t i = 1; i < l.size(); ++i) EXPECT_NEAR(p[i], 1.0 / (1.0 + std::exp(-static_cast<double>(l[i]))), 1e-6) << i;
  EXPECT_FLOAT_EQ(p[1], 0.5f);
  std::vector<std::int8_t> t(8);
  g.to_ros_trinary(t);
  // Defaults 0.65 / 0.45. p: -, 0.5, 0.971, 0.119, 0.701, 0.401, 0.648 (< 0.65), 0.196
  EXPECT_EQ(t, (std::vector<std::int8_t>{-1, -1, 100, 0, 100, 0, -1, 0}));
  g.to_ros_trinary(t, 0.65f, 0.196f);  // map_server's thresholds: 0.19624 > 0.196
  EXPECT_EQ(t, (std::vector<std::int8_t>{-1, -1, 100, 0, 100, -1, -1, -1}));
  // Reference on random values away from the thresholds.
  OccupancyGrid r(0.1f, Eigen::Vector2f(0, 0), 100, 100);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-4.0f, 4.0f);
  for (auto& x : r.logodds()) x = rng() % 10 == 0 ? kNaN : u(rng);
  std::vector<float> rp(r.cell_count());
  std::vector<std::int8_t> rt(r.cell_count());
  r.to_probabilities(rp);
  r.to_ros_trinary(rt, 0.7f, 0.3f);
  for (std::size_t i = 0; i < rp.size(); ++i) {
    const float x = r.logodds()[i];
    if (std::isnan(x)) {
      EXPECT_EQ(rp[i], -1.0f);
      EXPECT_EQ(rt[i], -1);
      continue;
    }
    const double pr = 1.0 / (1.0 + std::exp(-static_cast<double>(x)));
    EXPECT_NEAR(rp[i], pr, 1e-6);
    if (std::abs(pr - 0.7) < 1e-5 || std::abs(pr - 0.3) < 1e-5) continue;
    EXPECT_EQ(rt[i], pr >= 0.7 ? 100 : pr <= 0.3 ? 0 : -1) << "log-odds " << x;
  }
  // Size and threshold errors.
  std::vector<float> small(3);
  std::vector<std::int8_t> small_t(3);
  const auto kInv = ErrorCode::kInvalidArgument;
  EXPECT_DUET_ERROR(g.to_probabilities(small), kInv, "entries");
  EXPECT_DUET_ERROR(g.to_ros_trinary(small_t), kInv, "entries");
  EXPECT_DUET_ERROR(g.to_ros_trinary(t, 0.3f, 0.6f), kInv, "threshold");
  EXPECT_DUET_ERROR(g.to_ros_trinary(t, 1.5f, 0.2f), kInv, "threshold");
  // free_threshold 0: nothing is free; occupied 1: only p = 1 (never reached from finite log-odds).
  g.to_ros_trinary(t, 1.0f, 0.0f);
  EXPECT_EQ(std::count(t.begin(), t.end(), 0), 0);
}

TEST(Grid, CellOfAndCenter) {
  const OccupancyGrid g(0.25f, Eigen::Vector2f(-1.0f, 2.0f), 10, 10);
  EXPECT_EQ(g.cell_of(Eigen::Vector2f(-1.0f, 2.0f)), Eigen::Vector2i(0, 0));
  EXPECT_EQ(g.cell_of(Eigen::Vector2f(-0.76f, 2.26f)), Eigen::Vector2i(0, 1));
  EXPECT_EQ(g.cell_of(Eigen::Vector2f(-1.01f, 1.99f)), Eigen::Vector2i(-1, -1));
  EXPECT_EQ(g.cell_center(0, 0), Eigen::Vector2f(-0.875f, 2.125f));
  EXPECT_EQ(g.index(3, 2), 23u);  // row-major, row 0 at the lowest y
  EXPECT_TRUE(g.in_bounds(9, 9));
  EXPECT_FALSE(g.in_bounds(10, 0));
  EXPECT_FALSE(g.in_bounds(0, -1));
  EXPECT_EQ(g.known_cells(), 0u);
  EXPECT_TRUE(std::isnan(g.at(4, 4)));
}

}  // namespace test_occupancy_grid
}  // namespace duet
