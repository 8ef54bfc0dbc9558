// plan_path(): A* on the inflated grid vs a plain Dijkstra written here (same graph and cost, heap
// of doubles, no heuristic): equal cost on randomised maze grids with fixed seeds; every path step
// is between traversable 8-neighbours without corner cutting; length and cost recomputed from the
// waypoints; statuses (outside grid, start blocked, goal blocked, no path), the start rule inside
// the inflation, goal tolerance, 4-connectivity, invalid settings, workspace reuse, thread counts,
// the tie rule among equal-cost paths on an open grid.
#include "kernel_test_util.hpp"

#include <duet/kernels/error.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/kernels/path.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <queue>
#include <random>
#include <vector>

namespace duet {
namespace test_path {

using test::kNaN;

constexpr float kFree = -2.0f, kOcc = 3.0f;

using TestGrid = test::LogOddsTestGrid;

TestGrid blank(int w, int h, float v = kFree, float res = 0.05f) {
  TestGrid g;
  g.w = w;
  g.h = h;
  g.res = res;
  g.origin = {2.0f, -1.0f};
  g.l.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), v);
  return g;
}

// A maze-like grid: random wall segments, scattered obstacles and unknown blobs.
TestGrid maze(int w, int h, std::uint32_t seed) {
  TestGrid g = blank(w, h);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> ux(0, w - 1), uy(0, h - 1), ulen(3, std::max(4, w / 2));
  for (int k = 0; k < (w * h) / 150; ++k) {
    const int x = ux(rng), y = uy(rng), len = ulen(rng);
    const bool horiz = rng() & 1;
    for (int i = 0; i < len; ++i) {
      const int cx = horiz ? x + i : x, cy = horiz ? y : y + i;
      if (cx < w && cy < h) g.set(cx, cy, kOcc);
    }
  }
  for (int k = 0; k < (w * h) / 80; ++k) g.set(ux(rng), uy(rng), (rng() % 3) ? kOcc : kNaN);
  return g;
}

// ---- reference --------------------------------------------------------------------------------

struct RefResult {
  bool reachable = false;
  double cost = 0.0;
};

// Dijkstra over traversable cells with the header's cost, from the start cell to any goal cell.
RefResult reference_dijkstra(const InflatedGrid& g, std::size_t start, const std::vector<std::size_t>& goals,
                             const PathSettings& s) {
  const std::size_t n = g.cell_count();
  std::vector<double> dist(n, std::numeric_limits<double>::infinity());
  std::vector<char> is_goal(n, 0);
  for (auto q : goals) is_goal[q] = 1;
  using Item = std::pair<double, std::size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> pq;
  auto pen = [&](std::size_t c) {
    return std::max(0.0, 1.0 - (double(g.clearance_m[c]) - g.robot_radius_m) / double(s.clearance_decay_m));
  };
  dist[start] = 0.0;
  pq.push({0.0, start});
  while (!pq.empty()) {
    const auto [d, c] = pq.top();
    pq.pop();
    if (d > dist[c]) continue;
    if (is_goal[c]) return {true, d};
    const int x = int(c % std::size_t(g.width)), y = int(c / std::size_t(g.width));
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0) continue;
        const bool diag = dx != 0 && dy != 0;
        if (diag && !s.allow_diagonal) continue;
        const int nx = x + dx, ny = y + dy;
        if (!g.in_bounds(nx, ny) || !g.traversable[g.index(nx, ny)]) continue;
        if (diag && (!g.traversable[g.index(nx, y)] || !g.traversable[g.index(x, ny)])) continue;
        const std::size_t ni = g.index(nx, ny);
        const double len = (diag ? std::numbers::sqrt2 : 1.0) * g.resolution_m;
        const double nd = d + len * (1.0 + s.clearance_weight * 0.5 * (pen(c) + pen(ni)));
        if (nd < dist[ni]) {
          dist[ni] = nd;
          pq.push({nd, ni});
        }
      }
  }
  return {};
}

// Checks the waypoints form a valid path on g and recomputes its length and cost.
void check_path(const InflatedGrid& g, const PathResult& r, const PathSettings& s) {
  ASSERT_EQ(r.status, PathStatus::kFound);
  ASSERT_FALSE(r.waypoints.empty());
  double len = 0.0, cost = 0.0;
  auto pen = [&](std::size_t c) {
    return std::max(0.0, 1.0 - (double(g.clearance_m[c]) - g.robot_radius_m) / double(s.clearance_decay_m));
  };
  Eigen::Vector2i prev{0, 0};
  for (std::size_t k = 0; k < r.waypoints.size(); ++k) {
    const Eigen::Vector2i c = g.cell_of(r.waypoints[k]);
    ASSERT_TRUE(g.in_bounds(c.x(), c.y()));
    ASSERT_LT((g.cell_center(c.x(), c.y()) - r.waypoints[k]).norm(), 1e-4f) << "waypoint not at a cell centre";
    ASSERT_TRUE(g.traversable[g.index(c.x(), c.y())]) << "waypoint " << k << " on a non-traversable cell";
    if (k > 0) {
      const int dx = c.x() - prev.x(), dy = c.y() - prev.y();
      ASSERT_LE(std::abs(dx), 1);
      ASSERT_LE(std::abs(dy), 1);
      ASSERT_FALSE(dx == 0 && dy == 0);
      const bool diag = dx != 0 && dy != 0;
      if (diag) {
        ASSERT_TRUE(s.allow_diagonal);
        ASSERT_TRUE(g.traversable[g.index(c.x(), prev.y())] && g.traversable[g.index(prev.x(), c.y())]) << "corner cut";
      }
      const double l = (diag ? std::numbers::sqrt2 : 1.0) * g.resolution_m;
      len += l;
      cost += l * (1.0 + s.clearance_weight * 0.5 * (pen(g.index(c.x(), c.y())) + pen(g.index(prev.x(), prev.y()))));
    }
    prev = c;
  }
  EXPECT_NEAR(r.length_m, len, 1e-4 * (1.0 + len));
  EXPECT_NEAR(r.cost, cost, 1e-4 * (1.0 + cost));
  EXPECT_GE(r.cost + 1e-5f, r.length_m);
}

// ---- tests ----------------------------------------------------------------------------------------

TEST(PathSearch, OptimalAndValidOnRandomMazes) {
  std::uint32_t seed = 100;
  int found = 0, no_path = 0;
  for (const auto& [w, h] : std::vector<std::pair<int, int>>{{20, 20}, {64, 48}, {120, 90}}) {
    for (const float radius : {0.0f, 0.05f, 0.08f}) {
      const TestGrid tg = maze(w, h, ++seed);
      InflationSettings is;
      is.robot_radius_m = radius;
      InflatedGrid g;
      inflate(tg.view(), is, g);
      std::vector<std::size_t> trav;
      for (std::size_t i = 0; i < g.cell_count(); ++i)
        if (g.traversable[i]) trav.push_back(i);
      ASSERT_GT(trav.size(), 10u);
      std::mt19937 rng(seed);
      std::uniform_int_distribution<std::size_t> pick(0, trav.size() - 1);
      PathWorkspace ws;
      for (int trial = 0; trial < 12; ++trial) {
        PathSettings s;
        s.allow_diagonal = trial % 4 != 3;
        s.clearance_weight = trial % 3 == 0 ? 0.0f : 1.5f;
        const std::size_t a = trav[pick(rng)], b = trav[pick(rng)];
        const PathResult r = plan_path(g, g.cell_center(a), g.cell_center(b), s, ws);
        const RefResult ref = reference_dijkstra(g, a, {b}, s);
        SCOPED_TRACE(::testing::Message() << w << "x" << h << " r=" << radius << " trial " << trial);
        if (!ref.reachable) {
          EXPECT_EQ(r.status, PathStatus::kNoPath);
          ++no_path;
          continue;
        }
        ++found;
        check_path(g, r, s);
        EXPECT_NEAR(r.cost, ref.cost, 1e-5 * (1.0 + ref.cost));
        EXPECT_EQ(g.cell_of(r.waypoints.front()), g.cell_of(g.cell_center(a)));
        EXPECT_EQ(g.cell_of(r.waypoints.back()), g.cell_of(g.cell_center(b)));
        EXPECT_FALSE(r.start_moved);
      }
    }
  }
  EXPECT_GT(found, 25);
  EXPECT_GT(no_path, 0);  // the mazes do split into components
}

TEST(PathSearch, StraightCorridorAndSameCell) {
  TestGrid tg = blank(30, 5);
  InflatedGrid g;
  InflationSettings is;
  is.robot_radius_m = 0.0f;
  inflate(tg.view(), is, g);
  PathWorkspace ws;
  PathSettings s;
  const PathResult r = plan_path(g, g.cell_center(1, 2), g.cell_center(28, 2), s, ws);
  check_path(g, r, s);
  EXPECT_EQ(r.waypoints.size(), 28u);
  EXPECT_NEAR(r.length_m, 27 * 0.05f, 1e-5f);
  EXPECT_FLOAT_EQ(r.cost, r.length_m);  // no obstacle: no clearance penalty
  const PathResult same = plan_path(g, g.cell_center(4, 2) + Eigen::Vector2f(0.01f, 0.0f), g.cell_center(4, 2), s, ws);
  ASSERT_EQ(same.status, PathStatus::kFound);
  EXPECT_EQ(same.waypoints.size(), 1u);
  EXPECT_EQ(same.length_m, 0.0f);
}

// Tie rule (header): smallest f, then smallest heuristic (= largest g), then smallest cell index.
// On an open grid without clearance cost every path of min(|dx|,|dy|) diagonal and the remaining
// straight steps is optimal; the rule makes the search take the step that lowers the octile distance
// most first, i.e. all diagonal steps first, then the straight ones. 4-connected, the cells of
// equal f and h are taken by smallest index (lower row first).
TEST(PathSearch, TieRuleOnOpenGrid) {
  TestGrid tg = blank(40, 30);
  InflatedGrid g;
  InflationSettings is;
  is.robot_radius_m = 0.0f;
  inflate(tg.view(), is, g);
  PathWorkspace ws;
  PathSettings s;
  s.clearance_weight = 0.0f;
  std::mt19937 rng(4242);
  std::uniform_int_distribution<int> ux(0, 39), uy(0, 29);
  for (int k = 0; k < 60; ++k) {
    const Eigen::Vector2i a(ux(rng), uy(rng)), b(ux(rng), uy(rng));
    const PathResult r = plan_path(g, g.cell_center(a.x(), a.y()), g.cell_center(b.x(), b.y()), s, ws);
    ASSERT_EQ(r.status, PathStatus::kFound);
    check_path(g, r, s);
    // Expected: diagonal steps first, then straight.
    std::vector<Eigen::Vector2f> expect;
    Eigen::Vector2i c = a;
    const int sx = b.x() > a.x() ? 1 : (b.x() < a.x() ? -1 : 0), sy = b.y() > a.y() ? 1 : (b.y() < a.y() ? -1 : 0);
    expect.push_back(g.cell_center(c.x(), c.y()));
    while (c != b) {
      if (c.x() != b.x()) c.x() += sx;
      if (c.y() != b.y()) c.y() += sy;
      expect.push_back(g.cell_center(c.x(), c.y()));
    }
    SCOPED_TRACE(::testing::Message() << "from " << a.transpose() << " to " << b.transpose());
    EXPECT_EQ(r.waypoints, expect);
  }
  // 4-connected, (2,2) -> (4,4): (3,2) and (2,3) tie on f and h: the smaller index (3,2) wins, and
  // so on: x first, then y.
  s.allow_diagonal = false;
  const PathResult r4 = plan_path(g, g.cell_center(2, 2), g.cell_center(4, 4), s, ws);
  const std::vector<Eigen::Vector2f> e4 = {g.cell_center(2, 2), g.cell_center(3, 2), g.cell_center(4, 2), g.cell_center(4, 3),
                                           g.cell_center(4, 4)};
  EXPECT_EQ(r4.waypoints, e4);
}

// Fixed-point costs (header): still optimal for a heavy clearance weight (fewer fractional bits)
// and for coarse and fine resolutions.
TEST(PathSearch, OptimalWithHeavyWeightAndOtherResolutions) {
  std::uint32_t seed = 900;
  for (const auto& [res, weight] : std::vector<std::pair<float, float>>{{0.05f, 1000.0f}, {1.0f, 3.0f}, {0.002f, 1.0f}}) {
    TestGrid tg = maze(70, 50, ++seed);
    tg.res = res;
    InflatedGrid g;
    InflationSettings is;
    is.robot_radius_m = res;
    inflate(tg.view(), is, g);
    std::vector<std::size_t> trav;
    for (std::size_t i = 0; i < g.cell_count(); ++i)
      if (g.traversable[i]) trav.push_back(i);
    ASSERT_GT(trav.size(), 10u);
    std::mt19937 rng(seed);
    std::uniform_int_distribution<std::size_t> pick(0, trav.size() - 1);
    PathWorkspace ws;
    PathSettings s;
    s.clearance_weight = weight;
    s.clearance_decay_m = 6.0f * res;
    int found = 0;
    for (int trial = 0; trial < 15; ++trial) {
      const std::size_t a = trav[pick(rng)], b = trav[pick(rng)];
      const PathResult r = plan_path(g, g.cell_center(a), g.cell_center(b), s, ws);
      const RefResult ref = reference_dijkstra(g, a, {b}, s);
      SCOPED_TRACE(::testing::Message() << "res " << res << " weight " << weight << " trial " << trial);
      if (!ref.reachable) {
        EXPECT_EQ(r.status, PathStatus::kNoPath);
        continue;
      }
      ++found;
      check_path(g, r, s);
      EXPECT_NEAR(r.cost, ref.cost, 1e-5 * (1.0 + ref.cost));
    }
    EXPECT_GT(found, 3);
  }
}

TEST(PathSearch, Statuses) {
  // Two rooms split by a wall at x = 20; a block of wall in room A at x = 5..9.
  TestGrid tg = blank(40, 20);
  for (int y = 0; y < 20; ++y) tg.set(20, y, kOcc);
  for (int y = 8; y < 13; ++y)
    for (int x = 5; x < 10; ++x) tg.set(x, y, kOcc);
  InflatedGrid g;
  InflationSettings is;
  is.robot_radius_m = 0.05f;  // one cell
  inflate(tg.view(), is, g);
  PathWorkspace ws;
  const PathSettings s;
  const Eigen::Vector2f a = g.cell_center(2, 2), a2 = g.cell_center(15, 15), b = g.cell_center(30, 10);
  EXPECT_EQ(plan_path(g, a, a2, s, ws).status, PathStatus::kFound);
  EXPECT_EQ(plan_path(g, a, b, s, ws).status, PathStatus::kNoPath);
  EXPECT_EQ(plan_path(g, a, g.cell_center(7, 10), s, ws).status, PathStatus::kGoalBlocked);
  EXPECT_EQ(plan_path(g, g.cell_center(7, 10), a, s, ws).status, PathStatus::kStartBlocked);
  EXPECT_EQ(plan_path(g, a, Eigen::Vector2f(-5.0f, 0.0f), s, ws).status, PathStatus::kOutsideGrid);
  EXPECT_EQ(plan_path(g, Eigen::Vector2f(kNaN, 0.0f), a, s, ws).status, PathStatus::kOutsideGrid);
  EXPECT_EQ(plan_path(g, g.cell_center(40, 0), a, s, ws).status, PathStatus::kOutsideGrid);
  // Start inside the inflation (next to the block, one cell): moved to the nearest traversable cell.
  const PathResult moved = plan_path(g, g.cell_center(4, 10), a, s, ws);
  ASSERT_EQ(moved.status, PathStatus::kFound);
  EXPECT_TRUE(moved.start_moved);
  EXPECT_EQ(g.cell_of(moved.waypoints.front()), Eigen::Vector2i(3, 10));
  check_path(g, moved, s);
  // Goal inside the inflation: blocked without tolerance, found with it.
  EXPECT_EQ(plan_path(g, a, g.cell_center(4, 10), s, ws).status, PathStatus::kGoalBlocked);
  PathSettings tol = s;
  tol.goal_tolerance_m = 0.06f;
  const PathResult rt = plan_path(g, a, g.cell_center(4, 10), tol, ws);
  ASSERT_EQ(rt.status, PathStatus::kFound);
  EXPECT_LE((rt.waypoints.back() - g.cell_center(4, 10)).norm(), 0.06f);
  check_path(g, rt, tol);
  std::vector<std::size_t> goals;
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x)
      if (g.traversable[g.index(x, y)] && (g.cell_center(x, y) - g.cell_center(4, 10)).norm() <= 0.06f) goals.push_back(g.index(x, y));
  const RefResult ref = reference_dijkstra(g, g.index(2, 2), goals, tol);
  ASSERT_TRUE(ref.reachable);
  EXPECT_NEAR(rt.cost, ref.cost, 1e-5 * (1 + ref.cost));
  const char* names[] = {to_string(PathStatus::kFound), to_string(PathStatus::kStartBlocked), to_string(PathStatus::kGoalBlocked),
                         to_string(PathStatus::kNoPath), to_string(PathStatus::kOutsideGrid)};
  for (const char* nm : names) EXPECT_GT(std::string(nm).size(), 3u);
}

TEST(PathSearch, GoalToleranceMatchesReferenceOnMazes) {
  const TestGrid tg = maze(80, 60, 5);
  InflatedGrid g;
  InflationSettings is;
  is.robot_radius_m = 0.05f;
  inflate(tg.view(), is, g);
  PathWorkspace ws;
  PathSettings s;
  s.goal_tolerance_m = 0.23f;
  std::mt19937 rng(55);
  std::uniform_real_distribution<float> ux(2.0f, 2.0f + 80 * 0.05f), uy(-1.0f, -1.0f + 60 * 0.05f);
  int found = 0;
  for (int k = 0; k < 80; ++k) {
    const Eigen::Vector2f a(ux(rng), uy(rng)), b(ux(rng), uy(rng));
    const PathResult r = plan_path(g, a, b, s, ws);
    const Eigen::Vector2i ac = g.cell_of(a);
    if (!g.traversable[g.index(ac.x(), ac.y())]) continue;
    std::vector<std::size_t> goals;
    const Eigen::Vector2i bc = g.cell_of(b);
    for (int y = 0; y < g.height; ++y)
      for (int x = 0; x < g.width; ++x)
        if (g.traversable[g.index(x, y)] && ((g.cell_center(x, y) - b).norm() <= s.goal_tolerance_m || Eigen::Vector2i(x, y) == bc))
          goals.push_back(g.index(x, y));
    if (goals.empty()) {
      EXPECT_EQ(r.status, PathStatus::kGoalBlocked);
      continue;
    }
    const RefResult ref = reference_dijkstra(g, g.index(ac.x(), ac.y()), goals, s);
    if (!ref.reachable) {
      EXPECT_EQ(r.status, PathStatus::kNoPath);
      continue;
    }
    ++found;
    check_path(g, r, s);
    EXPECT_NEAR(r.cost, ref.cost, 1e-5 * (1 + ref.cost));
  }
  EXPECT_GT(found, 5);
}

TEST(PathSearch, KeepsClearFromWallsWhenWeighted) {
  // A 1.5 m wide corridor along x: with the clearance cost the path runs near the centre line.
  TestGrid tg = blank(100, 30);
  for (int x = 0; x < 100; ++x) {
    tg.set(x, 0, kOcc);
    tg.set(x, 29, kOcc);
  }
  InflatedGrid g;
  inflate(tg.view(), InflationSettings{}, g);
  PathWorkspace ws;
  PathSettings s;
  const PathResult r = plan_path(g, g.cell_center(2, 6), g.cell_center(97, 6), s, ws);
  check_path(g, r, s);
  float max_clear = 0.0f;
  for (const auto& p : r.waypoints) max_clear = std::max(max_clear, g.clearance().at(p.x(), p.y()));
  EXPECT_GE(max_clear, 0.2f + 0.3f);  // reaches the zero-penalty band
  PathSettings plain = s;
  plain.clearance_weight = 0.0f;
  const PathResult r0 = plan_path(g, g.cell_center(2, 6), g.cell_center(97, 6), plain, ws);
  check_path(g, r0, plain);
  EXPECT_NEAR(r0.length_m, 95 * 0.05f, 1e-4f);
  EXPECT_GT(r.length_m, r0.length_m);
}

TEST(PathSearch, InvalidSettingsAndGrid) {
  const TestGrid tg = blank(5, 5);
  InflatedGrid g;
  inflate(tg.view(), InflationSettings{}, g);
  PathWorkspace ws;
  const Eigen::Vector2f a = g.cell_center(1, 1);
  PathSettings s;
  s.clearance_weight = -1.0f;
  EXPECT_DUET_ERROR((void)plan_path(g, a, a, s, ws), ErrorCode::kInvalidArgument, "clearance_weight");
  s = PathSettings{};
  s.clearance_decay_m = 0.0f;
  EXPECT_DUET_ERROR((void)plan_path(g, a, a, s, ws), ErrorCode::kInvalidArgument, "clearance_decay_m");
  s = PathSettings{};
  s.goal_tolerance_m = kNaN;
  EXPECT_DUET_ERROR((void)plan_path(g, a, a, s, ws), ErrorCode::kInvalidArgument, "goal_tolerance_m");
  s = PathSettings{};
  s.clearance_weight = 1e30f;  // finite, but beyond the fixed-point range of the search
  EXPECT_DUET_ERROR((void)plan_path(g, a, a, s, ws), ErrorCode::kInvalidArgument, "clearance_weight");
  InflatedGrid bad = g;
  bad.clearance_m.resize(3);
  EXPECT_DUET_ERROR((void)plan_path(bad, a, a, PathSettings{}, ws), ErrorCode::kInvalidArgument, "width*height");
  InflatedGrid empty;
  EXPECT_EQ(plan_path(empty, a, a, PathSettings{}, ws).status, PathStatus::kOutsideGrid);
}

TEST(PathSearch, WorkspaceReuseAcrossGridsAndThreadCounts) {
  const TestGrid t1 = maze(150, 100, 9), t2 = maze(40, 70, 10);
  InflatedGrid g1a, g1b, g2;
  InflationSettings is;
  is.robot_radius_m = 0.05f;
  test::in_arena(1, [&] { inflate(t1.view(), is, g1a); });
  test::in_arena(2, [&] { inflate(t1.view(), is, g1b); });
  inflate(t2.view(), is, g2);
  PathWorkspace ws, ws2;
  int found = 0;
  std::mt19937 rng(77);
  for (int k = 0; k < 20; ++k) {
    const InflatedGrid& g = k % 2 ? g2 : g1a;
    std::uniform_int_distribution<std::size_t> pick(0, g.cell_count() - 1);
    const std::size_t a = pick(rng), b = pick(rng);
    const PathResult r = plan_path(g, g.cell_center(a), g.cell_center(b), PathSettings{}, ws);
    PathWorkspace fresh;
    const PathResult f = plan_path(g, g.cell_center(a), g.cell_center(b), PathSettings{}, fresh);
    EXPECT_EQ(r.status, f.status);
    EXPECT_EQ(r.cost, f.cost);
    EXPECT_EQ(r.waypoints, f.waypoints);
    found += r.status == PathStatus::kFound;
    if (k % 2 == 0) {
      const PathResult o = plan_path(g1b, g.cell_center(a), g.cell_center(b), PathSettings{}, ws2);
      EXPECT_EQ(o.waypoints, r.waypoints);
      EXPECT_EQ(o.cost, r.cost);
    }
  }
  EXPECT_GT(found, 3);
}

}  // namespace test_path
}  // namespace duet
