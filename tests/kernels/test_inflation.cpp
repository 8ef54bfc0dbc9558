// inflate(): classification, exact Euclidean distance transform vs a brute-force reference (min
// over every blocked cell of the integer squared distance, same float conversion so results are
// compared exactly), traversability at the radius boundary, unknown_is_obstacle and
// uncertain_is_obstacle (NaN vs observed-but-between-thresholds cells), empty / 1x1 /
// all-occupied / obstacle-free grids, buffer reuse, invalid settings, thread counts, and the
// Willow Garage map (sampled cells vs brute force).
#include "kernel_test_util.hpp"

#include <duet/kernels/error.hpp>
#include <duet/kernels/inflation.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace duet {
namespace test_inflation {

using test::kInf;
using test::kNaN;

constexpr float kFree = -2.0f, kOcc = 3.0f, kMid = 0.1f;  // kMid: observed but between thresholds = unknown

using TestGrid = test::LogOddsTestGrid;

TestGrid random_grid(int w, int h, double p_occ, double p_unk, std::uint32_t seed, float res = 0.05f) {
  TestGrid g;
  g.w = w;
  g.h = h;
  g.res = res;
  g.origin = {-1.25f, 3.5f};
  g.l.resize(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (float& v : g.l) {
    const double r = u(rng);
    v = r < p_occ ? kOcc : r < p_occ + p_unk ? (u(rng) < 0.5 ? kNaN : kMid) : kFree;
  }
  return g;
}

// Reference: brute force over all blocked cells.
struct RefInflation {
  std::vector<CellState> state;
  std::vector<float> clearance;
  std::vector<std::uint8_t> traversable;
};

RefInflation reference_inflate(const TestGrid& g, const InflationSettings& s) {
  RefInflation r;
  const std::size_t n = g.l.size();
  r.state.resize(n);
  std::vector<std::pair<int, int>> blocked;
  for (int y = 0; y < g.h; ++y)
    for (int x = 0; x < g.w; ++x) {
      const float l = g.l[static_cast<std::size_t>(y * g.w + x)];
      CellState c = CellState::kUnknown;
      if (l >= s.thresholds.occupied_logodds) c = CellState::kOccupied;
      else if (l <= s.thresholds.free_logodds) c = CellState::kFree;
      r.state[static_cast<std::size_t>(y * g.w + x)] = c;
      const bool never_seen = std::isnan(l);
      if (c == CellState::kOccupied || (c == CellState::kUnknown && (never_seen ? s.unknown_is_obstacle : s.uncertain_is_obstacle)))
        blocked.emplace_back(x, y);
    }
  r.clearance.resize(n);
  r.traversable.resize(n);
  for (int y = 0; y < g.h; ++y)
    for (int x = 0; x < g.w; ++x) {
      std::int64_t best = -1;
      for (const auto& [bx, by] : blocked) {
        const std::int64_t d2 = std::int64_t(bx - x) * (bx - x) + std::int64_t(by - y) * (by - y);
        if (best < 0 || d2 < best) best = d2;
      }
      const std::size_t i = static_cast<std::size_t>(y * g.w + x);
      r.clearance[i] = best < 0 ? kInf : static_cast<float>(static_cast<double>(g.res) * std::sqrt(static_cast<double>(best)));
      r.traversable[i] = r.state[i] == CellState::kFree && r.clearance[i] > s.robot_radius_m;
    }
  return r;
}

void expect_matches_reference(const TestGrid& g, const InflationSettings& s, const InflatedGrid& out) {
  const RefInflation r = reference_inflate(g, s);
  ASSERT_EQ(out.width, g.w);
  ASSERT_EQ(out.height, g.h);
  EXPECT_EQ(out.resolution_m, g.res);
  EXPECT_EQ(out.origin, g.origin);
  EXPECT_EQ(out.robot_radius_m, s.robot_radius_m);
  ASSERT_EQ(out.state.size(), r.state.size());
  std::size_t bad = 0;
  for (std::size_t i = 0; i < r.state.size(); ++i) {
    if (out.state[i] != r.state[i] || out.clearance_m[i] != r.clearance[i] || out.traversable[i] != r.traversable[i]) {
      if (++bad <= 5)
        ADD_FAILURE() << "cell " << i << " (" << i % static_cast<std::size_t>(g.w) << ", " << i / static_cast<std::size_t>(g.w)
                      << "): clearance " << out.clearance_m[i] << " vs " << r.clearance[i] << ", traversable "
                      << int(out.traversable[i]) << " vs " << int(r.traversable[i]);
    }
  }
  EXPECT_EQ(bad, 0u);
}

TEST(Inflation, MatchesBruteForceOnRandomGrids) {
  std::uint32_t seed = 7;
  for (const auto& [w, h] : std::vector<std::pair<int, int>>{{1, 1}, {1, 17}, {23, 1}, {37, 23}, {64, 64}, {130, 41}}) {
    for (const double p_occ : {0.002, 0.03, 0.3, 0.9}) {
      for (const int flags : {0, 1, 2, 3}) {
        const bool unk = (flags & 1) != 0, unc = (flags & 2) != 0;
        const TestGrid g = random_grid(w, h, p_occ, 0.15, ++seed);
        InflationSettings s;
        s.unknown_is_obstacle = unk;
        s.uncertain_is_obstacle = unc;
        s.robot_radius_m = 0.1f;
        InflatedGrid out;
        inflate(g.view(), s, out);
        SCOPED_TRACE(::testing::Message() << w << "x" << h << " p_occ=" << p_occ << " unknown_is_obstacle=" << unk
                                          << " uncertain_is_obstacle=" << unc);
        expect_matches_reference(g, s, out);
      }
    }
  }
}

// A grid whose squared distances in cells can pass 2^31 (50001 cells along one side) takes the
// int64 path instead of the int32 / SSE2 one; both give the brute force's bits. Also a row of
// blocked cells long enough for the runs inside it to be left out of the envelope.
TEST(Inflation, LongGridsTakeTheWidePathAndMatchBruteForce) {
  for (const auto& [w, h] : std::vector<std::pair<int, int>>{{50001, 1}, {1, 50001}, {46342, 2}, {300, 3}}) {
    TestGrid g;
    g.w = w;
    g.h = h;
    g.res = 0.05f;
    g.l.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), kFree);
    const std::size_t n = g.l.size();
    // Everything blocked lies near one end, so the far end is ~50000 cells away (2.5e9 squared).
    g.l[3] = kOcc;
    for (std::size_t i = 100; i < std::min<std::size_t>(n, 130); ++i) g.l[i] = kOcc;  // a run of blocked cells
    g.l[std::min<std::size_t>(n - 1, 160)] = kNaN;  // unknown: blocks only with unknown_is_obstacle
    for (const bool unk : {false, true}) {
      InflationSettings s;
      s.unknown_is_obstacle = unk;
      s.robot_radius_m = 0.12f;
      InflatedGrid out;
      inflate(g.view(), s, out);
      SCOPED_TRACE(::testing::Message() << w << "x" << h << " unknown_is_obstacle=" << unk);
      expect_matches_reference(g, s, out);
    }
  }
}

TEST(Inflation, SingleObstacleGivesEuclideanDistances) {
  TestGrid g;
  g.w = 41;
  g.h = 31;
  g.res = 0.1f;
  g.l.assign(static_cast<std::size_t>(g.w * g.h), kFree);
  g.l[static_cast<std::size_t>(10 * g.w + 20)] = kOcc;
  InflatedGrid out;
  inflate(g.view(), InflationSettings{}, out);
  // (20+3, 10+4) is 5 cells away: 0.5 m.
  EXPECT_NEAR(out.clearance_m[out.index(23, 14)], 0.5f, 1e-6f);
  EXPECT_NEAR(out.clearance_m[out.index(0, 0)], 0.1f * std::sqrt(400.0f + 100.0f), 1e-5f);
  EXPECT_EQ(out.clearance_m[out.index(20, 10)], 0.0f);
  EXPECT_EQ(out.state[out.index(20, 10)], CellState::kOccupied);
  // Radius 0.2 m: cells exactly 2 cells away (clearance == radius) are not traversable, 3 away are.
  EXPECT_EQ(out.traversable[out.index(22, 10)], 0);
  EXPECT_EQ(out.traversable[out.index(23, 10)], 1);
  EXPECT_EQ(out.traversable[out.index(21, 11)], 0);  // sqrt(2)*0.1 < 0.2
  expect_matches_reference(g, InflationSettings{}, out);
}

TEST(Inflation, EmptyAllOccupiedNoObstacleAndOneCell) {
  InflatedGrid out;
  TestGrid empty;
  inflate(empty.view(), InflationSettings{}, out);
  EXPECT_EQ(out.width, 0);
  EXPECT_TRUE(out.state.empty());
  EXPECT_TRUE(out.clearance_m.empty());
  EXPECT_TRUE(out.traversable.empty());
  EXPECT_EQ(out.clearance().at(0.0f, 0.0f), 0.0f);

  TestGrid occ = random_grid(20, 13, 1.0, 0.0, 1);
  inflate(occ.view(), InflationSettings{}, out);
  for (std::size_t i = 0; i < occ.l.size(); ++i) {
    EXPECT_EQ(out.clearance_m[i], 0.0f);
    EXPECT_EQ(out.traversable[i], 0);
  }

  TestGrid freeg = random_grid(20, 13, 0.0, 0.0, 2);
  freeg.l[5] = kNaN;  // unknown: not blocked by default, never traversable
  inflate(freeg.view(), InflationSettings{}, out);
  for (std::size_t i = 0; i < freeg.l.size(); ++i) {
    EXPECT_EQ(out.clearance_m[i], kInf);
    EXPECT_EQ(out.traversable[i], i == 5 ? 0 : 1);
  }
  EXPECT_EQ(out.clearance().at(-1.25f + 0.01f, 3.5f + 0.01f), kInf);
  EXPECT_EQ(out.clearance().at(-1.25f - 0.01f, 3.5f + 0.01f), 0.0f);  // outside: 0 (ClearanceView rule)

  InflationSettings unk;
  unk.unknown_is_obstacle = true;
  inflate(freeg.view(), unk, out);
  EXPECT_EQ(out.clearance_m[5], 0.0f);
  EXPECT_EQ(out.clearance_m[6], 0.05f);
  expect_matches_reference(freeg, unk, out);

  for (const float v : {kFree, kOcc, kNaN}) {
    TestGrid one;
    one.w = one.h = 1;
    one.l = {v};
    inflate(one.view(), InflationSettings{}, out);
    EXPECT_EQ(out.clearance_m[0], v == kOcc ? 0.0f : kInf);
    EXPECT_EQ(out.traversable[0], v == kFree ? 1 : 0);
  }
}

TEST(Inflation, UncertainAndNeverSeenCellsAreDistinguished) {
  // A free corridor with one never-observed cell (NaN) and one observed-but-uncertain cell
  // (a hit and a miss: 0.85 - 0.4 = 0.45, between the thresholds): by default only the
  // uncertain one blocks; each flag switches its own kind.
  TestGrid g;
  g.w = 9;
  g.h = 1;
  g.l.assign(9, kFree);
  g.l[2] = kNaN;
  g.l[6] = 0.45f;
  InflatedGrid out;
  InflationSettings s;
  s.robot_radius_m = 0.0f;
  inflate(g.view(), s, out);
  EXPECT_EQ(out.state[2], CellState::kUnknown);
  EXPECT_EQ(out.state[6], CellState::kUnknown);
  EXPECT_FLOAT_EQ(out.clearance_m[2], 0.2f);
  EXPECT_EQ(out.clearance_m[6], 0.0f);
  EXPECT_FLOAT_EQ(out.clearance_m[8], 0.1f);
  s.uncertain_is_obstacle = false;
  inflate(g.view(), s, out);
  for (const float c : out.clearance_m) EXPECT_EQ(c, kInf);
  s.unknown_is_obstacle = true;
  inflate(g.view(), s, out);
  EXPECT_EQ(out.clearance_m[2], 0.0f);
  EXPECT_FLOAT_EQ(out.clearance_m[6], 0.2f);
  for (std::size_t i = 0; i < out.traversable.size(); ++i) EXPECT_EQ(out.traversable[i], (i == 2 || i == 6) ? 0 : 1);
}

TEST(Inflation, ZeroRadiusAllowsEveryUnblockedFreeCell) {
  const TestGrid g = random_grid(50, 40, 0.2, 0.1, 99);
  InflationSettings s;
  s.robot_radius_m = 0.0f;
  InflatedGrid out;
  inflate(g.view(), s, out);
  for (std::size_t i = 0; i < g.l.size(); ++i) EXPECT_EQ(out.traversable[i], out.state[i] == CellState::kFree ? 1 : 0);
}

TEST(Inflation, ReusesBuffers) {
  const TestGrid g = random_grid(80, 60, 0.05, 0.1, 3);
  InflatedGrid out;
  inflate(g.view(), InflationSettings{}, out);
  const float* p = out.clearance_m.data();
  const TestGrid g2 = random_grid(80, 60, 0.2, 0.1, 4);
  inflate(g2.view(), InflationSettings{}, out);
  EXPECT_EQ(out.clearance_m.data(), p);
  expect_matches_reference(g2, InflationSettings{}, out);
  // Different size after a larger one: still correct.
  const TestGrid g3 = random_grid(13, 90, 0.1, 0.1, 5);
  inflate(g3.view(), InflationSettings{}, out);
  expect_matches_reference(g3, InflationSettings{}, out);
}

TEST(Inflation, InvalidInputThrows) {
  const TestGrid g = random_grid(4, 4, 0.1, 0.1, 6);
  InflatedGrid out;
  InflationSettings s;
  s.robot_radius_m = -0.1f;
  EXPECT_DUET_ERROR(inflate(g.view(), s, out), ErrorCode::kInvalidArgument, "robot_radius_m");
  s.robot_radius_m = kNaN;
  EXPECT_DUET_ERROR(inflate(g.view(), s, out), ErrorCode::kInvalidArgument, "robot_radius_m");
  s = InflationSettings{};
  s.thresholds.free_logodds = 1.0f;
  EXPECT_DUET_ERROR(inflate(g.view(), s, out), ErrorCode::kInvalidArgument, "free_logodds");
  GridView bad = g.view();
  bad.width = 5;
  EXPECT_DUET_ERROR(inflate(bad, InflationSettings{}, out), ErrorCode::kInvalidArgument, "log-odds");
  bad = g.view();
  bad.resolution_m = 0.0f;
  EXPECT_DUET_ERROR(inflate(bad, InflationSettings{}, out), ErrorCode::kInvalidArgument, "resolution_m");
  inflate(g.view(), InflationSettings{}, out);
  out.traversable.pop_back();
  EXPECT_DUET_ERROR(validate(out), ErrorCode::kInvalidArgument, "width*height");
}

TEST(Inflation, ThreadCountIndependent) {
  const TestGrid g = random_grid(701, 333, 0.01, 0.2, 11);
  InflatedGrid a, b;
  InflationSettings s;
  test::in_arena(1, [&] { inflate(g.view(), s, a); });
  test::in_arena(2, [&] { inflate(g.view(), s, b); });
  EXPECT_TRUE(test::bitwise_equal(a.clearance_m, b.clearance_m));
  EXPECT_TRUE(test::bitwise_equal(a.traversable, b.traversable));
  EXPECT_TRUE(test::bitwise_equal(a.state, b.state));
}

// ---- real data: the Willow Garage map --------------------------------------------------------------

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

TEST(Inflation, WillowMapSampledCellsMatchBruteForce) {
  DUET_REQUIRE_DATA(kWillow);
  const TestGrid g = load_willow();
  ASSERT_GT(g.w, 0) << "cannot decode " << kWillow;
  InflatedGrid a, b;
  test::in_arena(2, [&] { inflate(g.view(), InflationSettings{}, a); });
  test::in_arena(1, [&] { inflate(g.view(), InflationSettings{}, b); });
  EXPECT_TRUE(test::bitwise_equal(a.clearance_m, b.clearance_m));
  std::vector<std::pair<int, int>> occ;
  std::size_t n_free = 0, n_trav = 0;
  for (int y = 0; y < g.h; ++y)
    for (int x = 0; x < g.w; ++x) {
      const float l = g.l[static_cast<std::size_t>(y * g.w + x)];
      if (l == kOcc) occ.emplace_back(x, y);
      n_free += l == kFree;
      n_trav += a.traversable[a.index(x, y)];
    }
  ASSERT_GT(occ.size(), 1000u);
  EXPECT_GT(n_trav, n_free / 3);
  EXPECT_LT(n_trav, n_free);
  std::mt19937 rng(2010);
  std::uniform_int_distribution<int> ux(0, g.w - 1), uy(0, g.h - 1);
  const int samples = test::full_or(3000, 300);
  for (int k = 0; k < samples; ++k) {
    const int x = ux(rng), y = uy(rng);
    std::int64_t best = -1;
    for (const auto& [bx, by] : occ) {
      const std::int64_t d2 = std::int64_t(bx - x) * (bx - x) + std::int64_t(by - y) * (by - y);
      if (best < 0 || d2 < best) best = d2;
    }
    const float want = static_cast<float>(static_cast<double>(g.res) * std::sqrt(static_cast<double>(best)));
    ASSERT_EQ(a.clearance_m[a.index(x, y)], want) << "cell (" << x << ", " << y << ")";
  }
}

}  // namespace test_inflation
}  // namespace duet
