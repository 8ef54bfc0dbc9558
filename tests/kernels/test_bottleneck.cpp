// widest_passage(): against a brute-force reference (for every distinct clearance c, a BFS over
// the free cells with clearance >= c; a cell's value is the largest c that reaches it) on random
// grids with fixed seeds; a corridor narrowed to a known gap; the Willow Garage map (the reference
// on a window); empty, 1x1, start outside / blocked / NaN, mismatched buffers.
#include "kernel_test_util.hpp"

#include <duet/kernels/bottleneck.hpp>
#include <duet/kernels/error.hpp>
#include <duet/kernels/inflation.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <random>
#include <set>
#include <vector>

namespace duet {
namespace test_bottleneck {

using test::kNaN;
constexpr float kFreeL = -2.0f, kOccL = 3.0f;

InflatedGrid inflated(const std::vector<float>& l, int w, int h, float res = 0.05f) {
  InflatedGrid g;
  InflationSettings s;
  s.robot_radius_m = 0.2f;
  inflate(GridView(l, w, h, res, Eigen::Vector2f(0.0f, 0.0f)), s, g);
  return g;
}

// The reference: the largest threshold whose BFS (same connectivity as the kernel) reaches a cell.
std::vector<float> reference(const InflatedGrid& g, Eigen::Vector2i s) {
  std::vector<float> out(g.cell_count(), 0.0f);
  auto free = [&](int x, int y) { return g.in_bounds(x, y) && g.state[g.index(x, y)] == CellState::kFree; };
  if (!free(s.x(), s.y())) return out;
  std::set<float> levels;
  for (std::size_t i = 0; i < g.cell_count(); ++i)
    if (g.state[i] == CellState::kFree) levels.insert(g.clearance_m[i]);
  for (const float c : levels) {
    if (g.clearance_m[g.index(s.x(), s.y())] < c) break;
    std::vector<std::uint8_t> seen(g.cell_count(), 0);
    std::deque<Eigen::Vector2i> q{s};
    seen[g.index(s.x(), s.y())] = 1;
    auto ok = [&](int x, int y) { return free(x, y) && g.clearance_m[g.index(x, y)] >= c; };
    while (!q.empty()) {
      const Eigen::Vector2i p = q.front();
      q.pop_front();
      out[g.index(p.x(), p.y())] = c;  // levels ascend: the last one that reaches a cell wins
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (!dx && !dy) continue;
          const int nx = p.x() + dx, ny = p.y() + dy;
          if (!ok(nx, ny) || seen[g.index(nx, ny)]) continue;
          if (dx && dy && !(free(p.x() + dx, p.y()) && free(p.x(), p.y() + dy))) continue;
          seen[g.index(nx, ny)] = 1;
          q.push_back({nx, ny});
        }
    }
  }
  return out;
}

Eigen::Vector2f centre(const InflatedGrid& g, int x, int y) { return g.cell_center(g.index(x, y)); }

TEST(WidestPassage, MatchesTheReferenceOnRandomGrids) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 40; ++trial) {
    const int w = 5 + static_cast<int>(u(rng) * 40), h = 5 + static_cast<int>(u(rng) * 40);
    const double p_occ = 0.05 + 0.3 * u(rng);
    std::vector<float> l(static_cast<std::size_t>(w) * h);
    for (float& v : l) {
      const double r = u(rng);
      v = r < p_occ ? kOccL : r < p_occ + 0.05 ? kNaN : kFreeL;
    }
    const InflatedGrid g = inflated(l, w, h);
    const Eigen::Vector2i s(static_cast<int>(u(rng) * w), static_cast<int>(u(rng) * h));
    std::vector<float> got;
    widest_passage(g, centre(g, s.x(), s.y()), got);
    const std::vector<float> want = reference(g, s);
    ASSERT_EQ(got.size(), want.size());
    for (std::size_t i = 0; i < got.size(); ++i) ASSERT_EQ(got[i], want[i]) << "trial " << trial << " cell " << i;
  }
}

TEST(WidestPassage, ACorridorNarrowedToAGapIsItsBottleneck) {
  // Two rooms (x < 20 and x > 30 cells) joined by a corridor whose walls leave a gap of 7 cells
  // (0.35 m at 5 cm): beyond the gap every cell is limited by the gap's middle cell, 4 cells from
  // the nearer wall cell centre.
  const int w = 60, h = 40;
  std::vector<float> l(static_cast<std::size_t>(w) * h, kFreeL);
  for (int y = 0; y < h; ++y)
    for (int x = 20; x <= 30; ++x)
      if (y < 16 || y > 22) l[static_cast<std::size_t>(y) * w + x] = kOccL;  // free rows 16..22: 7 cells
  const InflatedGrid g = inflated(l, w, h);
  std::vector<float> out;
  widest_passage(g, centre(g, 5, 20), out);
  EXPECT_FLOAT_EQ(out[g.index(50, 30)], 0.20f);  // 4 cells * 5 cm
  EXPECT_GT(out[g.index(10, 20)], 0.20f);        // the start's room is wider
  EXPECT_EQ(out[g.index(25, 5)], 0.0f);          // a wall cell
  // The robot (radius 0.2 m) does not fit: traversable needs clearance > radius.
  EXPECT_LE(out[g.index(50, 30)], g.robot_radius_m);
}

TEST(WidestPassage, MatchesTheReferenceOnTheWillowMap) {
  if (!test::have_data(test::kWillowMap)) GTEST_SKIP() << "no Willow map";
  const test::WillowGrid wg = test::willow_trinary(kOccL, kFreeL);
  ASSERT_GT(wg.w, 0);
  // A 200 x 200 window keeps the O(levels * N) reference quick.
  const int x0 = wg.w / 2 - 100, y0 = wg.h / 2 - 100, w = 200, h = 200;
  std::vector<float> l(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) l[static_cast<std::size_t>(y) * w + x] = wg.logodds[static_cast<std::size_t>(y0 + y) * wg.w + x0 + x];
  const InflatedGrid g = inflated(l, w, h, 0.1f);
  int sx = -1, sy = -1;
  float best = 0.0f;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (g.state[g.index(x, y)] == CellState::kFree && g.clearance_m[g.index(x, y)] > best) {
        best = g.clearance_m[g.index(x, y)];
        sx = x;
        sy = y;
      }
  ASSERT_GE(sx, 0) << "no free cell in the window";
  std::vector<float> got;
  widest_passage(g, centre(g, sx, sy), got);
  const std::vector<float> want = reference(g, {sx, sy});
  std::size_t reached = 0;
  for (std::size_t i = 0; i < got.size(); ++i) {
    ASSERT_EQ(got[i], want[i]) << "cell " << i;
    reached += got[i] > 0.0f;
  }
  EXPECT_GT(reached, 1000u);
}

TEST(WidestPassage, EdgeCases) {
  std::vector<float> out{1.0f, 2.0f};
  widest_passage(InflatedGrid{}, Eigen::Vector2f(0.0f, 0.0f), out);  // empty grid
  EXPECT_TRUE(out.empty());
  const InflatedGrid one = inflated({kFreeL}, 1, 1);
  widest_passage(one, centre(one, 0, 0), out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_TRUE(std::isinf(out[0]));  // no blocked cell anywhere: +inf
  std::vector<float> l(100, kFreeL);
  l[55] = kOccL;
  const InflatedGrid g = inflated(l, 10, 10);
  for (const Eigen::Vector2f& p : {Eigen::Vector2f(-1.0f, 0.1f), Eigen::Vector2f(kNaN, 0.1f), centre(g, 5, 5)}) {
    widest_passage(g, p, out);  // outside, NaN, on the occupied cell
    ASSERT_EQ(out.size(), 100u);
    EXPECT_TRUE(std::all_of(out.begin(), out.end(), [](float v) { return v == 0.0f; }));
  }
  InflatedGrid bad = g;
  bad.clearance_m.pop_back();
  test::expect_error([&] { widest_passage(bad, centre(g, 0, 0), out); }, "do not match");
}

}  // namespace test_bottleneck
}  // namespace duet
