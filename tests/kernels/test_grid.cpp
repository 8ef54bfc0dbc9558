// update_grid vs a serial reference written from the header (one update per cell
// per call: hit if any obstacle point, else miss if any floor point's cell or any cell crossed by a
// ray from the sensor to an end cell's centre; exact DDA in double); rays to high points, obstacles
// kept near the sensor, clamping, ignored labels, max_ray_length, errors, thread counts. The
// OccupancyGrid type: test_occupancy_grid.cpp; accumulate_grid: test_accumulate_grid.cpp.
#include "grid_test_util.hpp"
#include "kernel_test_util.hpp"

#include <duet/kernels/error.hpp>
#include <duet/kernels/grid.hpp>

#include <gtest/gtest.h>

#include <limits>

#include <algorithm>
#include <random>
#include <set>
#include <utility>
#include <vector>

namespace duet {
namespace test_grid {

using test::kInf;
using test::kNaN;
using Cell = std::pair<int, int>;
using test::same_grid;

// ---- reference -----------------------------------------------------------------------------------

// Cells crossed by the segment from `from` to the centre of `end`, starting in `start`, excluding
// `end` (exact Amanatides-Woo in double, crossing times recomputed from the boundaries each step).
// Returns false if the walk does not reach `end` in |dx| + |dy| steps.
bool reference_ray(const OccupancyGrid& g, const Eigen::Vector2f& from, Cell start, Cell end, std::set<Cell>& out) {
  const double res = g.resolution();
  const Eigen::Vector2d org = g.origin().cast<double>();
  const Eigen::Vector2d s = from.cast<double>();
  const Eigen::Vector2d t = g.cell_center(end.first, end.second).cast<double>();
  const Eigen::Vector2d d = t - s;
  const int sx = d.x() > 0 ? 1 : -1, sy = d.y() > 0 ? 1 : -1;
  Cell c = start;
  const int steps = std::abs(end.first - start.first) + std::abs(end.second - start.second);
  for (int k = 0; k < steps + 1; ++k) {
    if (c == end) return true;
    out.insert(c);
    const double bx = org.x() + (c.first + (sx > 0 ? 1 : 0)) * res, by = org.y() + (c.second + (sy > 0 ? 1 : 0)) * res;
    const double tx = d.x() != 0.0 ? (bx - s.x()) / d.x() : std::numeric_limits<double>::infinity();
    const double ty = d.y() != 0.0 ? (by - s.y()) / d.y() : std::numeric_limits<double>::infinity();
    if (tx < ty) c.first += sx;
    else c.second += sy;
  }
  return c == end;
}

struct RefStats {
  std::size_t rays = 0, ray_failures = 0;
};

// The header's semantics on a copy of the grid (growth through the same ensure_contains, which is
// tested on its own below).
RefStats reference_update(OccupancyGrid& g, const Eigen::Vector2f& sensor, const std::vector<Eigen::Vector3f>& pts,
                          const std::vector<PointLabel>& labels, const GridUpdateSettings& s) {
  RefStats st;
  const double max_r = s.max_ray_length_m;
  std::vector<std::size_t> used;
  Eigen::Vector2f lo = sensor, hi = sensor;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (labels[i] == PointLabel::kIgnored) continue;
    const Eigen::Vector2f xy = pts[i].head<2>();
    if (!xy.allFinite()) continue;
    if ((xy - sensor).squaredNorm() > static_cast<float>(max_r * max_r)) continue;
    used.push_back(i);
    lo = lo.cwiseMin(xy);
    hi = hi.cwiseMax(xy);
  }
  g.ensure_contains(lo, hi, s.grow_margin_cells);
  std::set<Cell> hit, end_free, ray_free;
  for (const auto i : used) {
    const Eigen::Vector2i c = g.cell_of(pts[i].head<2>());
    (labels[i] == PointLabel::kObstacle ? hit : end_free).insert({c.x(), c.y()});
  }
  if (s.clear_along_rays) {
    const Eigen::Vector2i sc = g.cell_of(sensor);
    std::set<Cell> ends = hit;
    ends.insert(end_free.begin(), end_free.end());
    for (const Cell& e : ends) {
      ++st.rays;
      if (!reference_ray(g, sensor, {sc.x(), sc.y()}, e, ray_free)) ++st.ray_failures;
    }
  }
  auto apply = [&](const Cell& c, float delta) {
    float& l = g.logodds()[g.index(c.first, c.second)];
    l = std::clamp((std::isnan(l) ? 0.0f : l) + delta, s.min_logodds, s.max_logodds);
  };
  for (const Cell& c : hit) apply(c, s.hit_logodds);
  std::set<Cell> miss = end_free;
  miss.insert(ray_free.begin(), ray_free.end());
  for (const Cell& c : miss)
    if (!hit.count(c)) apply(c, s.miss_logodds);
  return st;
}

struct Scan {
  Eigen::Vector2f sensor;
  std::vector<Eigen::Vector3f> pts;
  std::vector<PointLabel> labels;
};

Scan random_scan(std::uint32_t seed, std::size_t n, float spread, Eigen::Vector2f centre = {0, 0}) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::uniform_int_distribution<int> lab(0, 9);
  Scan s;
  s.sensor = centre + Eigen::Vector2f(u(rng), u(rng)) * 0.5f;
  for (std::size_t i = 0; i < n; ++i) {
    // Points on a few "walls" (many points per cell) and scattered ones.
    Eigen::Vector2f xy;
    if (i % 3 == 0) {
      const float a = u(rng);
      xy = centre + Eigen::Vector2f(spread * 0.8f, spread * a);
      if (i % 2) xy = centre + Eigen::Vector2f(spread * a, -spread * 0.6f);
    } else {
      xy = centre + Eigen::Vector2f(u(rng), u(rng)) * spread;
    }
    s.pts.emplace_back(xy.x(), xy.y(), u(rng));
    const int l = lab(rng);
    s.labels.push_back(l < 4 ? PointLabel::kObstacle : l < 9 ? PointLabel::kFloor : PointLabel::kIgnored);
    if (i % 37 == 0) s.pts.back().x() = kNaN;
    if (i % 41 == 0) s.pts.back().z() = kNaN;  // z is not used by the 2D grid
  }
  return s;
}

// ---- tests: update_grid vs reference ---------------------------------------------------------------

TEST(Grid, UpdateMatchesReferenceOnRandomScenes) {
  GridUpdateWorkspace ws;
  for (const float res : {0.05f, 0.1f, 0.037f}) {
    OccupancyGrid g(res), ref(res);
    GridUpdateSettings s;
    s.grow_margin_cells = 7;
    std::size_t rays = 0, failures = 0;
    for (std::uint32_t call = 0; call < 12; ++call) {
      // The robot moves; scans overlap; later scans make the grid grow in every direction.
      const Eigen::Vector2f centre(1.5f * std::cos(0.7f * static_cast<float>(call)), 1.2f * std::sin(0.9f * static_cast<float>(call)));
      const Scan sc = random_scan(1000 * static_cast<std::uint32_t>(res * 1000) + call, 1500, 3.0f + 0.3f * static_cast<float>(call), centre);
      update_grid(g, sc.sensor, sc.pts, sc.labels, s, ws);
      const RefStats st = reference_update(ref, sc.sensor, sc.pts, sc.labels, s);
      rays += st.rays;
      failures += st.ray_failures;
      ASSERT_TRUE(same_grid(g, ref)) << "resolution " << res << ", call " << call;
    }
    EXPECT_EQ(failures, 0u);
    EXPECT_GT(rays, 1000u);
    EXPECT_GT(g.known_cells(), 1000u);
  }
}

TEST(Grid, UpdateMatchesReferenceWithoutRaysAndWithShortRays) {
  GridUpdateWorkspace ws;
  GridUpdateSettings s;
  s.clear_along_rays = false;
  OccupancyGrid g(0.05f), ref(0.05f);
  for (std::uint32_t call = 0; call < 4; ++call) {
    const Scan sc = random_scan(77 + call, 3000, 4.0f);
    update_grid(g, sc.sensor, sc.pts, sc.labels, s, ws);
    reference_update(ref, sc.sensor, sc.pts, sc.labels, s);
    ASSERT_TRUE(same_grid(g, ref)) << "call " << call;
  }
  s.clear_along_rays = true;
  s.max_ray_length_m = 1.5f;
  for (std::uint32_t call = 0; call < 4; ++call) {
    const Scan sc = random_scan(88 + call, 3000, 4.0f);
    update_grid(g, sc.sensor, sc.pts, sc.labels, s, ws);
    reference_update(ref, sc.sensor, sc.pts, sc.labels, s);
    ASSERT_TRUE(same_grid(g, ref)) << "call " << call;
  }
}

TEST(Grid, UpdateOnPresizedGridAndAxisAlignedRays) {
  // Sensor and points on cell centres along rows / columns / diagonals (exact ties in the DDA).
  OccupancyGrid g(0.1f, Eigen::Vector2f(-5.0f, -5.0f), 100, 100), ref = g;
  std::vector<Eigen::Vector3f> pts;
  std::vector<PointLabel> labels;
  for (int k = -30; k <= 30; k += 3) {
    const float f = 0.1f * static_cast<float>(k) + 0.05f;
    for (const Eigen::Vector2f& xy : {Eigen::Vector2f(f, 0.05f), Eigen::Vector2f(0.05f, f), Eigen::Vector2f(f, f)}) {
      pts.emplace_back(xy.x(), xy.y(), 0.0f);
      labels.push_back(k % 2 ? PointLabel::kObstacle : PointLabel::kFloor);
    }
  }
  GridUpdateSettings s;
  s.grow_margin_cells = 0;
  GridUpdateWorkspace ws;
  const Eigen::Vector2f sensor(0.05f, 0.05f);
  update_grid(g, sensor, pts, labels, s, ws);
  const RefStats st = reference_update(ref, sensor, pts, labels, s);
  EXPECT_EQ(st.ray_failures, 0u);
  EXPECT_EQ(g.width(), 100);  // everything was inside: no growth
  EXPECT_EQ(g.origin(), Eigen::Vector2f(-5.0f, -5.0f));
  EXPECT_TRUE(same_grid(g, ref));
}

// ---- tests: semantics by hand ------------------------------------------------------------------------

TEST(Grid, SingleObstacleHitAndRay) {
  OccupancyGrid g(0.1f, Eigen::Vector2f(0, 0), 20, 10);
  GridUpdateSettings s;
  s.grow_margin_cells = 0;
  GridUpdateWorkspace ws;
  const std::vector<Eigen::Vector3f> p{{1.55f, 0.55f, 0.3f}};
  const std::vector<PointLabel> l{PointLabel::kObstacle};
  update_grid(g, Eigen::Vector2f(0.25f, 0.55f), p, l, s, ws);
  EXPECT_FLOAT_EQ(g.at(15, 5), 0.85f);
  for (int x = 2; x < 15; ++x) EXPECT_FLOAT_EQ(g.at(x, 5), -0.4f) << x;  // the ray, sensor cell included
  EXPECT_TRUE(std::isnan(g.at(1, 5)));
  EXPECT_TRUE(std::isnan(g.at(16, 5)));
  EXPECT_TRUE(std::isnan(g.at(8, 4)));
  EXPECT_EQ(g.known_cells(), 14u);
}

TEST(Grid, RaysToHighObstaclePointsDoNotClear) {
  // A wall point 1.5 m high beyond a low bench: the 2D ray to it passes over the bench in 3D,
  // so with clear_max_height_m = 0.6 it must not clear anything; a low point and a floor point
  // still clear their rays. The default (+inf) clears every ray.
  GridUpdateSettings s;
  s.grow_margin_cells = 0;
  s.clear_max_height_m = 0.6f;
  GridUpdateWorkspace ws;
  const std::vector<Eigen::Vector3f> high{{1.55f, 0.55f, 1.5f}};
  const std::vector<PointLabel> obstacle{PointLabel::kObstacle};
  OccupancyGrid g(0.1f, Eigen::Vector2f(0, 0), 20, 10);
  update_grid(g, Eigen::Vector2f(0.25f, 0.55f), high, obstacle, s, ws);
  EXPECT_FLOAT_EQ(g.at(15, 5), 0.85f);  // the hit is still marked
  for (int x = 2; x < 15; ++x) EXPECT_TRUE(std::isnan(g.at(x, 5))) << x;
  EXPECT_EQ(g.known_cells(), 1u);
  const std::vector<Eigen::Vector3f> low{{1.55f, 0.55f, 0.6f}};  // at the limit: clears
  OccupancyGrid g2(0.1f, Eigen::Vector2f(0, 0), 20, 10);
  update_grid(g2, Eigen::Vector2f(0.25f, 0.55f), low, obstacle, s, ws);
  for (int x = 2; x < 15; ++x) EXPECT_FLOAT_EQ(g2.at(x, 5), -0.4f) << x;
  const std::vector<Eigen::Vector3f> floor_pt{{1.55f, 0.55f, 3.0f}};  // floor label: always clears
  OccupancyGrid g3(0.1f, Eigen::Vector2f(0, 0), 20, 10);
  update_grid(g3, Eigen::Vector2f(0.25f, 0.55f), floor_pt, std::vector<PointLabel>{PointLabel::kFloor}, s, ws);
  for (int x = 2; x <= 15; ++x) EXPECT_FLOAT_EQ(g3.at(x, 5), -0.4f) << x;
  s.clear_max_height_m = std::numeric_limits<float>::infinity();
  OccupancyGrid g4(0.1f, Eigen::Vector2f(0, 0), 20, 10);
  update_grid(g4, Eigen::Vector2f(0.25f, 0.55f), high, obstacle, s, ws);
  for (int x = 2; x < 15; ++x) EXPECT_FLOAT_EQ(g4.at(x, 5), -0.4f) << x;
  s.clear_max_height_m = NAN;
  EXPECT_THROW(validate(s), Error);
}

TEST(Grid, RaysDoNotEraseOccupiedCellsNearTheSensor) {
  // A post at cell (5, 5), 0.3 m from the sensor at (0.25, 0.55) - nearer than a Kinect's minimum
  // depth, so it returns no point; a ray to a floor point beyond runs through its cell.
  GridUpdateSettings s;
  s.grow_margin_cells = 0;
  GridUpdateWorkspace ws;
  const Eigen::Vector2f sensor(0.25f, 0.55f);
  const std::vector<Eigen::Vector3f> post{{0.55f, 0.55f, 0.3f}}, beyond{{1.55f, 0.55f, 0.0f}};
  const std::vector<PointLabel> obstacle{PointLabel::kObstacle}, floor_l{PointLabel::kFloor};
  for (const float keep : {0.0f, 0.35f}) {
    SCOPED_TRACE(keep);
    s.keep_occupied_within_m = keep;
    OccupancyGrid g(0.1f, Eigen::Vector2f(0, 0), 20, 10);
    update_grid(g, sensor, post, obstacle, s, ws);
    update_grid(g, sensor, post, obstacle, s, ws);
    ASSERT_FLOAT_EQ(g.at(5, 5), 1.7f);
    update_grid(g, sensor, beyond, floor_l, s, ws);  // the ray crosses cells 2..14 of row 5
    // Off: the post's cell is lowered like any other; on: kept. Cells beyond it (6..14) and the
    // free ones nearer (2..4: log-odds <= 0, cleared by all three rays) are cleared either way.
    EXPECT_FLOAT_EQ(g.at(5, 5), keep > 0.0f ? 1.7f : 1.3f);
    for (int x = 2; x < 5; ++x) EXPECT_FLOAT_EQ(g.at(x, 5), -1.2f) << x;
    for (int x = 6; x < 15; ++x) EXPECT_FLOAT_EQ(g.at(x, 5), -0.4f) << x;
  }
  // The limit is inclusive and measured to the cell's centre: (0.55, 0.55) is 0.3 m away.
  for (const auto& [keep, want] : std::vector<std::pair<float, float>>{{0.3f, 0.85f}, {0.29f, 0.45f}}) {
    s.keep_occupied_within_m = keep;
    OccupancyGrid g(0.1f, Eigen::Vector2f(0, 0), 20, 10);
    update_grid(g, sensor, post, obstacle, s, ws);
    update_grid(g, sensor, beyond, floor_l, s, ws);
    EXPECT_FLOAT_EQ(g.at(5, 5), want) << keep;
  }
  // keep_occupied_logodds: only cells above it are kept - two hits (1.7) are not above 2, three (2.55) are.
  s.keep_occupied_within_m = 1.0f;
  s.keep_occupied_logodds = 2.0f;
  for (const auto& [hits, want] : std::vector<std::pair<int, float>>{{2, 1.3f}, {3, 2.55f}}) {
    OccupancyGrid g(0.1f, Eigen::Vector2f(0, 0), 20, 10);
    for (int k = 0; k < hits; ++k) update_grid(g, sensor, post, obstacle, s, ws);
    update_grid(g, sensor, beyond, floor_l, s, ws);
    EXPECT_FLOAT_EQ(g.at(5, 5), want) << hits << " hits";
  }
  s.keep_occupied_logodds = NAN;
  EXPECT_THROW(validate(s), Error);
  s.keep_occupied_logodds = 0.0f;
  // A hit or a floor point in the cell still counts: a floor point there lowers it.
  s.keep_occupied_within_m = 1.0f;
  OccupancyGrid g(0.1f, Eigen::Vector2f(0, 0), 20, 10);
  update_grid(g, sensor, post, obstacle, s, ws);
  update_grid(g, sensor, std::vector<Eigen::Vector3f>{{0.55f, 0.55f, 0.0f}}, floor_l, s, ws);
  EXPECT_FLOAT_EQ(g.at(5, 5), 0.45f);
  for (const float bad : {-0.1f, NAN, INFINITY}) {
    s.keep_occupied_within_m = bad;
    EXPECT_THROW(validate(s), Error) << bad;
  }
}

TEST(Grid, OneUpdatePerCellPerCallAndHitWins) {
  OccupancyGrid g(0.1f, Eigen::Vector2f(0, 0), 30, 10);
  GridUpdateSettings s;
  s.grow_margin_cells = 0;
  GridUpdateWorkspace ws;
  std::vector<Eigen::Vector3f> p;
  std::vector<PointLabel> l;
  // 50 obstacle and 50 floor points in cell (10, 5); a far floor point at (25, 5) whose ray crosses (10, 5).
  for (int i = 0; i < 50; ++i) {
    p.emplace_back(1.01f + 0.0015f * static_cast<float>(i), 0.52f, 0.0f);
    l.push_back(PointLabel::kObstacle);
    p.emplace_back(1.02f + 0.0015f * static_cast<float>(i), 0.57f, 0.0f);
    l.push_back(PointLabel::kFloor);
  }
  p.emplace_back(2.55f, 0.55f, 0.0f);
  l.push_back(PointLabel::kFloor);
  for (int i = 0; i < 20; ++i) {  // floor points in cell (20, 5), also on the ray
    p.emplace_back(2.01f + 0.004f * static_cast<float>(i), 0.55f, 0.0f);
    l.push_back(PointLabel::kFloor);
  }
  update_grid(g, Eigen::Vector2f(0.05f, 0.55f), p, l, s, ws);
  EXPECT_FLOAT_EQ(g.at(10, 5), 0.85f);   // hit once, no miss
  EXPECT_FLOAT_EQ(g.at(20, 5), -0.4f);   // one miss, though 20 end points and a ray
  EXPECT_FLOAT_EQ(g.at(25, 5), -0.4f);
  EXPECT_FLOAT_EQ(g.at(0, 5), -0.4f);
  EXPECT_TRUE(std::isnan(g.at(26, 5)));
}

TEST(Grid, ClampingOverRepeatedCalls) {
  OccupancyGrid g(0.1f, Eigen::Vector2f(0, 0), 20, 3);
  GridUpdateSettings s;
  s.grow_margin_cells = 0;
  GridUpdateWorkspace ws;
  const std::vector<Eigen::Vector3f> p{{1.55f, 0.15f, 0.0f}};
  const std::vector<PointLabel> l{PointLabel::kObstacle};
  for (int k = 1; k <= 10; ++k) {
    update_grid(g, Eigen::Vector2f(0.05f, 0.15f), p, l, s, ws);
    EXPECT_FLOAT_EQ(g.at(15, 1), std::min(3.5f, 0.85f * static_cast<float>(k))) << k;
    EXPECT_FLOAT_EQ(g.at(5, 1), std::max(-2.0f, -0.4f * static_cast<float>(k))) << k;
  }
  EXPECT_EQ(g.at(15, 1), 3.5f);
  EXPECT_EQ(g.at(5, 1), -2.0f);
  // An occupied cell seen free again goes down from the clamp.
  const std::vector<PointLabel> floor{PointLabel::kFloor};
  update_grid(g, Eigen::Vector2f(0.05f, 0.15f), p, floor, s, ws);
  EXPECT_FLOAT_EQ(g.at(15, 1), 3.1f);
}

TEST(Grid, IgnoredNonFiniteAndFarPointsAreSkipped) {
  OccupancyGrid g(0.1f);
  GridUpdateSettings s;
  s.max_ray_length_m = 3.0f;
  s.grow_margin_cells = 2;
  GridUpdateWorkspace ws;
  const std::vector<Eigen::Vector3f> p{{1.05f, 0.05f, 0}, {kNaN, 1.0f, 0}, {1.0f, kInf, 0}, {-1.05f, 0.05f, 0}, {3.5f, 0.05f, 0},
                                       {1e30f, 5.0f, 0}};
  const std::vector<PointLabel> l{PointLabel::kIgnored, PointLabel::kObstacle, PointLabel::kObstacle, PointLabel::kObstacle,
                                  PointLabel::kObstacle, PointLabel::kFloor};
  update_grid(g, Eigen::Vector2f(0.05f, 0.05f), p, l, s, ws);
  // Only the point at -1.05 counts: 1 hit + 11 ray cells (sensor cell 0 to -10); the grid covers it
  // plus the margin only.
  EXPECT_EQ(g.known_cells(), 12u);
  const Eigen::Vector2i c = g.cell_of(Eigen::Vector2f(-1.05f, 0.05f));
  EXPECT_FLOAT_EQ(g.at(c.x(), c.y()), 0.85f);
  const Eigen::Vector2i ignored = g.cell_of(Eigen::Vector2f(1.05f, 0.05f));
  EXPECT_FALSE(g.in_bounds(ignored.x(), ignored.y()) && !std::isnan(g.at(ignored.x(), ignored.y())));
  EXPECT_LE(g.width(), 11 + 2 * 2 + 1);
  EXPECT_LE(g.height(), 1 + 2 * 2 + 1);
  // A point exactly at max_ray_length counts.
  OccupancyGrid h(0.5f, Eigen::Vector2f(-5, -5), 20, 20);
  const std::vector<Eigen::Vector3f> q{{3.0f, 0.0f, 0.0f}};
  const std::vector<PointLabel> ql{PointLabel::kObstacle};
  update_grid(h, Eigen::Vector2f(0.0f, 0.0f), q, ql, s, ws);
  EXPECT_FLOAT_EQ(h.at(h.cell_of(q[0].head<2>()).x(), 10), 0.85f);
  // All ignored / empty scan: only growth to hold the sensor, no update.
  OccupancyGrid e(0.1f);
  update_grid(e, Eigen::Vector2f(2.0f, 3.0f), {}, {}, s, ws);
  EXPECT_EQ(e.known_cells(), 0u);
  const Eigen::Vector2i sc = e.cell_of(Eigen::Vector2f(2.0f, 3.0f));
  EXPECT_TRUE(e.in_bounds(sc.x(), sc.y()));
}

TEST(Grid, BadInputThrows) {
  OccupancyGrid g(0.1f, Eigen::Vector2f(0, 0), 10, 10);
  GridUpdateWorkspace ws;
  const std::vector<Eigen::Vector3f> p{{0.5f, 0.5f, 0}, {0.6f, 0.5f, 0}};
  const std::vector<PointLabel> one{PointLabel::kObstacle};
  const std::vector<PointLabel> two(2, PointLabel::kObstacle);
  const auto kInv = ErrorCode::kInvalidArgument;
  EXPECT_DUET_ERROR(update_grid(g, Eigen::Vector2f(0, 0), p, one, {}, ws), kInv, "labels");
  EXPECT_DUET_ERROR(update_grid(g, Eigen::Vector2f(kNaN, 0), p, two, {}, ws), kInv, "sensor");
  struct Bad {
    GridUpdateSettings s;
    const char* field;
  };
  std::vector<Bad> bad;
  GridUpdateSettings s;
  s.hit_logodds = 0.0f;
  bad.push_back({s, "hit_logodds"});
  s = {};
  s.miss_logodds = 0.1f;
  bad.push_back({s, "miss_logodds"});
  s = {};
  s.min_logodds = 0.5f;
  bad.push_back({s, "min_logodds"});
  s = {};
  s.max_logodds = kInf;
  bad.push_back({s, "max_logodds"});
  s = {};
  s.max_ray_length_m = 0.0f;
  bad.push_back({s, "max_ray_length_m"});
  s = {};
  s.grow_margin_cells = -1;
  bad.push_back({s, "grow_margin_cells"});
  for (const auto& b : bad) {
    EXPECT_DUET_ERROR(update_grid(g, Eigen::Vector2f(0, 0), p, two, b.s, ws), kInv, b.field);
    EXPECT_DUET_ERROR(validate(b.s), kInv, b.field);
  }
  EXPECT_EQ(g.known_cells(), 0u);  // nothing applied
  // Huge coordinates within a huge max_ray_length: beyond the map frame's limit (kMaxCoordinateM)
  // a point is dropped like a point out of range; within it, the growth limit - never a wrong
  // or giant grid.
  s = {};
  s.max_ray_length_m = 1e7f;
  for (const float x : {5e6f, 1e17f, -1e38f}) {
    const std::vector<Eigen::Vector3f> far{{x, 0, 0}};
    update_grid(g, Eigen::Vector2f(0, 0), far, one, s, ws);
    EXPECT_LE(g.width(), 100);  // at most grown round the sensor, never towards the point
    EXPECT_LE(g.height(), 100);
    EXPECT_EQ(g.known_cells(), 0u);
  }
  const int w = g.width();
  const std::vector<Eigen::Vector3f> far{{9e3f, 9e3f, 0}};  // within +-1e4 m: 1.8e5 x 1.8e5 cells
  EXPECT_DUET_ERROR(update_grid(g, Eigen::Vector2f(0, 0), far, one, s, ws), ErrorCode::kOutOfRange, "limit");
  EXPECT_EQ(g.width(), w);
  // A sensor beyond the limit (a pose of 1e17 m through the C API): an error, not a 0-wide grid.
  EXPECT_DUET_ERROR(update_grid(g, Eigen::Vector2f(1e17f, 0), p, two, s, ws), ErrorCode::kOutOfRange, "limit of +-10000");
  EXPECT_EQ(g.known_cells(), 0u);
  // Resolutions: [1 mm, 100 m]; a grid beyond the map frame's limits is refused.
  for (const float r : {0.0f, 1e-4f, 101.0f, 3e38f}) EXPECT_DUET_ERROR(OccupancyGrid{r}, kInv, "resolution must be in");
  EXPECT_NO_THROW(OccupancyGrid{kMinGridResolutionM});
  EXPECT_NO_THROW(OccupancyGrid{kMaxGridResolutionM});
  EXPECT_DUET_ERROR(OccupancyGrid(1.0f, Eigen::Vector2f(9990.0f, 0.0f), 20, 1), ErrorCode::kOutOfRange, "limit");
  EXPECT_EQ(g.width(), w);
}

TEST(Grid, IdenticalWithOneAndTwoThreads) {
  const auto run = [](int threads) {
    return test::in_arena(threads, [] {
      OccupancyGrid g(0.05f);
      GridUpdateWorkspace ws;
      for (std::uint32_t call = 0; call < test::full_or(4u, 3u); ++call) {
        const Scan sc = random_scan(500 + call, test::full_or<std::size_t>(20000, 5000), 6.0f, Eigen::Vector2f(0.5f * static_cast<float>(call), 0.0f));
        update_grid(g, sc.sensor, sc.pts, sc.labels, {}, ws);
      }
      return g;
    });
  };
  const OccupancyGrid a = run(1), b = run(2);
  EXPECT_TRUE(same_grid(a, b));
  const std::vector<float> la(a.logodds().begin(), a.logodds().end()), lb(b.logodds().begin(), b.logodds().end());
  EXPECT_TRUE(test::bitwise_equal(la, lb));
  EXPECT_GT(a.known_cells(), 10000u);
}

}  // namespace test_grid
}  // namespace duet
