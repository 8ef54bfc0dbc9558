// The frontier cell (paper §3.2; kernels/frontier.hpp): frontier_mask() against a per-cell
// reference (both overloads, the SSE2 and the AVX2 paths, thread counts) and
// any_frontier_cell_within() against a brute force over the mask. find_frontier: test_frontier.cpp.
#include "frontier_test_grids.hpp"
#include "kernel_test_util.hpp"

#include <duet/kernels/error.hpp>
#include <duet/kernels/frontier.hpp>
#include <duet/kernels/inflation.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

namespace duet {
namespace test_frontier_mask {

using namespace frontier_test;

// ---- frontier_mask ---------------------------------------------------------------------------------

TEST(Frontier, MaskMatchesReference) {
  std::uint32_t seed = 1;
  for (const auto& [w, h] : std::vector<std::pair<int, int>>{{1, 1}, {1, 9}, {9, 1}, {2, 2}, {33, 17}, {100, 70}, {257, 40}, {31, 5}, {32, 6}, {64, 64}, {1100, 9}}) {
    const TestGrid tg = explored(w, h, ++seed);
    CellThresholds t;
    std::vector<CellState> st(tg.l.size());
    classify_grid(tg.view(), t, st);
    const std::vector<std::uint8_t> ref = reference_mask(st, w, h);
    std::vector<std::uint8_t> m(tg.l.size(), 7), m2(tg.l.size(), 9);
    const std::size_t n = frontier_mask(tg.view(), t, m);
    const std::size_t n2 = frontier_mask(st, w, h, m2);
    EXPECT_EQ(m, ref) << w << "x" << h;
    EXPECT_EQ(m2, ref) << w << "x" << h;
    std::size_t cnt = 0;
    for (auto v : ref) cnt += v;
    EXPECT_EQ(n, cnt);
    EXPECT_EQ(n2, cnt);
    // The baseline (SSE2) path gives the same bytes as the AVX2 one used on this CPU.
    std::vector<std::uint8_t> m3(tg.l.size(), 5), m4(tg.l.size(), 6);
    EXPECT_EQ(detail::frontier_mask_isa(tg.view(), t, m3, false), cnt);
    EXPECT_EQ(detail::frontier_mask_isa(st, w, h, m4, false), cnt);
    EXPECT_EQ(m3, ref) << w << "x" << h;
    EXPECT_EQ(m4, ref) << w << "x" << h;
  }
  // Hand-made: a free cell next to an unknown one; the grid border is not unknown.
  TestGrid tg = blank(4, 3, kFree);
  tg.set(3, 2, kNaN);
  std::vector<std::uint8_t> m(12);
  EXPECT_EQ(frontier_mask(tg.view(), CellThresholds{}, m), 3u);
  EXPECT_EQ(m, (std::vector<std::uint8_t>{0, 0, 0, 0, 0, 0, 1, 1, 0, 0, 1, 0}));
  TestGrid empty;
  std::vector<std::uint8_t> none;
  EXPECT_EQ(frontier_mask(empty.view(), CellThresholds{}, none), 0u);
  EXPECT_DUET_ERROR(frontier_mask(tg.view(), CellThresholds{}, none), ErrorCode::kInvalidArgument, "mask");
}

TEST(Frontier, MaskThreadCountIndependent) {
  const TestGrid tg = explored(613, 411, 42);
  std::vector<std::uint8_t> a(tg.l.size()), b(tg.l.size());
  const std::size_t na = test::in_arena(1, [&] { return frontier_mask(tg.view(), CellThresholds{}, a); });
  const std::size_t nb = test::in_arena(2, [&] { return frontier_mask(tg.view(), CellThresholds{}, b); });
  EXPECT_EQ(na, nb);
  EXPECT_EQ(a, b);
  EXPECT_GT(na, 100u);
}

TEST(Frontier, AnyFrontierCellWithinMatchesTheMask) {
  // Against a brute force over frontier_mask(): every cell's centre tested against the disc.
  int hits = 0, misses = 0;
  for (std::uint32_t seed = 1; seed <= 12; ++seed) {
    const int w = 20 + int(seed % 4) * 25, h = 15 + int(seed % 3) * 20;
    const TestGrid tg = explored(w, h, seed * 17);
    InflatedGrid g;
    inflate(tg.view(), InflationSettings{}, g);
    std::vector<std::uint8_t> mask(g.cell_count());
    frontier_mask(g.state, w, h, mask);
    std::mt19937 rng(seed);
    // Points inside and up to 1 m outside the grid; radii from 0 (one cell centre or none) to 2 m.
    std::uniform_real_distribution<float> px(g.origin.x() - 1.0f, g.origin.x() + w * g.resolution_m + 1.0f);
    std::uniform_real_distribution<float> py(g.origin.y() - 1.0f, g.origin.y() + h * g.resolution_m + 1.0f);
    std::uniform_real_distribution<float> pr(0.0f, 2.0f);
    for (int k = 0; k < 200; ++k) {
      Eigen::Vector2f xy{px(rng), py(rng)};
      float r = k % 10 == 0 ? 0.0f : pr(rng);
      if (k % 10 == 1) {  // exactly on a cell centre, radius 0: that cell alone
        xy = g.cell_center(static_cast<std::size_t>(rng() % g.cell_count()));
        r = 0.0f;
      }
      bool ref = false;
      for (std::size_t i = 0; i < g.cell_count() && !ref; ++i)
        ref = mask[i] && (g.cell_center(i) - xy).norm() <= r;
      EXPECT_EQ(any_frontier_cell_within(g, xy, r), ref) << "seed " << seed << " k " << k << " xy " << xy.transpose() << " r " << r;
      (ref ? hits : misses) += 1;
    }
  }
  EXPECT_GT(hits, 300);  // both answers are exercised
  EXPECT_GT(misses, 300);
  // Hand-made: the frontier cells of MaskMatchesReference's 4 x 3 grid are (2,1), (3,1), (2,2).
  TestGrid tg = blank(4, 3, kFree);
  tg.set(3, 2, kNaN);
  InflatedGrid g;
  inflate(tg.view(), InflationSettings{}, g);
  EXPECT_TRUE(any_frontier_cell_within(g, g.cell_center(2, 1), 0.0f));
  EXPECT_FALSE(any_frontier_cell_within(g, g.cell_center(0, 0), 0.0f));
  EXPECT_FALSE(any_frontier_cell_within(g, g.cell_center(0, 0), 0.09f));  // (2,1) is 0.112 m away
  EXPECT_TRUE(any_frontier_cell_within(g, g.cell_center(0, 0), 0.12f));
  EXPECT_FALSE(any_frontier_cell_within(g, {1e6f, -1e6f}, 1.0f));  // far outside
  EXPECT_TRUE(any_frontier_cell_within(g, {1e6f, -1e6f}, 3e6f));   // a huge radius covers the grid
  // Empty grid, bad arguments.
  EXPECT_FALSE(any_frontier_cell_within(InflatedGrid{}, {0.0f, 0.0f}, 1.0f));
  EXPECT_DUET_ERROR((void)any_frontier_cell_within(g, {NAN, 0.0f}, 1.0f), ErrorCode::kInvalidArgument, "xy");
  EXPECT_DUET_ERROR((void)any_frontier_cell_within(g, {0.0f, 0.0f}, -1.0f), ErrorCode::kInvalidArgument, "radius_m");
  EXPECT_DUET_ERROR((void)any_frontier_cell_within(g, {0.0f, 0.0f}, INFINITY), ErrorCode::kInvalidArgument, "radius_m");
  InflatedGrid bad = g;
  bad.state.pop_back();
  EXPECT_DUET_ERROR((void)any_frontier_cell_within(bad, {0.0f, 0.0f}, 1.0f), ErrorCode::kInvalidArgument, "state");
}

}  // namespace test_frontier_mask
}  // namespace duet
