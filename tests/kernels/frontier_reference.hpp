#pragma once
// Simple references for the frontier search tests (test_frontier.cpp): clusters by a flood fill,
// distances by Dijkstra with a heap of doubles, approach cells, enclosed pockets, and the check of
// a find_frontier() result against them.
#include "frontier_test_grids.hpp"

#include <duet/kernels/frontier.hpp>
#include <duet/kernels/inflation.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <queue>
#include <vector>

namespace duet {
namespace frontier_test {

struct RefCluster {
  std::vector<std::size_t> cells;
};

inline std::vector<RefCluster> reference_clusters(const std::vector<std::uint8_t>& m, int w, int h, int min_cells,
                                           std::vector<int>& label) {
  std::vector<RefCluster> out;
  label.assign(m.size(), -1);
  std::vector<char> seen(m.size(), 0);
  for (std::size_t i = 0; i < m.size(); ++i) {
    if (!m[i] || seen[i]) continue;
    RefCluster c;
    std::queue<std::size_t> q;
    q.push(i);
    seen[i] = 1;
    while (!q.empty()) {
      const std::size_t k = q.front();
      q.pop();
      c.cells.push_back(k);
      const int x = int(k % std::size_t(w)), y = int(k / std::size_t(w));
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
          const std::size_t ni = std::size_t(ny * w + nx);
          if (m[ni] && !seen[ni]) {
            seen[ni] = 1;
            q.push(ni);
          }
        }
    }
    if (static_cast<int>(c.cells.size()) >= min_cells) {
      for (auto k : c.cells) label[k] = static_cast<int>(out.size());
      out.push_back(std::move(c));
    }
  }
  return out;
}

inline std::vector<double> reference_distances(const InflatedGrid& g, std::size_t start) {
  std::vector<double> dist(g.cell_count(), std::numeric_limits<double>::infinity());
  using Item = std::pair<double, std::size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> pq;
  dist[start] = 0.0;
  pq.push({0.0, start});
  while (!pq.empty()) {
    const auto [d, c] = pq.top();
    pq.pop();
    if (d > dist[c]) continue;
    const int x = int(c % std::size_t(g.width)), y = int(c / std::size_t(g.width));
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0) continue;
        const int nx = x + dx, ny = y + dy;
        if (!g.in_bounds(nx, ny) || !g.traversable[g.index(nx, ny)]) continue;
        const bool diag = dx != 0 && dy != 0;
        if (diag && (!g.traversable[g.index(nx, y)] || !g.traversable[g.index(x, ny)])) continue;
        const double nd = d + (diag ? std::numbers::sqrt2 : 1.0) * g.resolution_m;
        if (nd < dist[g.index(nx, ny)]) {
          dist[g.index(nx, ny)] = nd;
          pq.push({nd, g.index(nx, ny)});
        }
      }
  }
  return dist;
}

inline bool connected(const InflatedGrid& g, std::size_t c) {
  const int x = int(c % std::size_t(g.width)), y = int(c / std::size_t(g.width));
  return x > 0 && y > 0 && x < g.width - 1 && y < g.height - 1;
}

// Approach cells (FrontierSettings::approach_radius_m), written plainly from the header's rule:
// src[c] = the frontier cell whose wave claimed c (or -1); approach[c] = traversable, not a kept
// frontier cell, claimed.
inline void reference_approach(const InflatedGrid& g, const std::vector<int>& label,
                        std::size_t clusters, float radius_m, std::vector<long>& src, std::vector<char>& approach) {
  src.assign(g.cell_count(), -1);
  approach.assign(g.cell_count(), 0);
  if (!(radius_m > 0.0f)) return;
  std::vector<char> has_trav(clusters, 0);
  for (std::size_t c = 0; c < g.cell_count(); ++c)
    if (label[c] >= 0 && g.traversable[c]) has_trav[std::size_t(label[c])] = 1;
  std::queue<std::size_t> q;
  for (std::size_t c = 0; c < g.cell_count(); ++c)
    if (label[c] >= 0 && !has_trav[std::size_t(label[c])] && connected(g, c)) {
      src[c] = long(c);
      q.push(c);
    }
  const double r = radius_m / g.resolution_m;
  while (!q.empty()) {
    const std::size_t c = q.front();
    q.pop();
    const auto s = std::size_t(src[c]);
    const int x = int(c % std::size_t(g.width)), y = int(c / std::size_t(g.width));
    const int sx = int(s % std::size_t(g.width)), sy = int(s / std::size_t(g.width));
    for (int d = 0; d < 8; ++d) {  // the kernel's neighbour order: E, W, N, S, NE, NW, SE, SW
      static constexpr int kx[8] = {1, -1, 0, 0, 1, -1, 1, -1}, ky[8] = {0, 0, 1, -1, 1, 1, -1, -1};
      const int nx = x + kx[d], ny = y + ky[d];
      if (!g.in_bounds(nx, ny)) continue;
      const std::size_t ni = g.index(nx, ny);
      if (src[ni] >= 0 || g.state[ni] != CellState::kFree) continue;
      if (std::hypot(double(nx - sx), double(ny - sy)) > r + 1e-9) continue;
      src[ni] = long(s);
      q.push(ni);
      if (g.traversable[ni] && label[ni] < 0) approach[ni] = 1;
    }
  }
}

// Full comparison of find_frontier with the references; robot_xy must be in a traversable cell.
// min_unknown_region_m2: clears the frontier cells whose unknown 8-neighbours all lie in unknown
// components (8-connected, labelled in full) of fewer than min_cells cells not touching the border.
inline void reference_drop_pockets(const InflatedGrid& g, double min_m2, std::vector<std::uint8_t>& m) {
  if (!(min_m2 > 0.0)) return;
  const double min_cells = std::ceil(min_m2 / (double(g.resolution_m) * double(g.resolution_m)));
  std::vector<int> comp(g.cell_count(), -1);
  std::vector<char> large;
  for (std::size_t i = 0; i < g.cell_count(); ++i) {
    if (g.state[i] != CellState::kUnknown || comp[i] >= 0) continue;
    const int id = int(large.size());
    std::queue<std::size_t> q;
    q.push(i);
    comp[i] = id;
    std::size_t size = 0;
    bool border = false;
    while (!q.empty()) {
      const std::size_t c = q.front();
      q.pop();
      ++size;
      const int x = int(c % std::size_t(g.width)), y = int(c / std::size_t(g.width));
      border = border || x == 0 || y == 0 || x == g.width - 1 || y == g.height - 1;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (!g.in_bounds(nx, ny)) continue;
          const std::size_t ni = g.index(nx, ny);
          if (g.state[ni] == CellState::kUnknown && comp[ni] < 0) {
            comp[ni] = id;
            q.push(ni);
          }
        }
    }
    large.push_back(border || double(size) >= min_cells);
  }
  for (std::size_t i = 0; i < g.cell_count(); ++i) {
    if (!m[i]) continue;
    const int x = int(i % std::size_t(g.width)), y = int(i / std::size_t(g.width));
    bool keep = false;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        if (g.in_bounds(x + dx, y + dy) && comp[g.index(x + dx, y + dy)] >= 0 && large[std::size_t(comp[g.index(x + dx, y + dy)])])
          keep = true;
    if (!keep) m[i] = 0;
  }
}

inline void check_against_reference(const InflatedGrid& g, const Eigen::Vector2f& robot_xy, const GoalBlacklist& bl, double now,
                             const FrontierSettings& s, const FrontierResult& r) {
  std::vector<std::uint8_t> m = reference_mask(g.state, g.width, g.height);
  reference_drop_pockets(g, s.min_unknown_region_m2, m);
  std::vector<int> label;
  const std::vector<RefCluster> rc = reference_clusters(m, g.width, g.height, s.min_cluster_cells, label);
  ASSERT_EQ(r.clusters.size(), rc.size());
  std::size_t cells = 0;
  for (std::size_t k = 0; k < rc.size(); ++k) {
    ASSERT_EQ(r.clusters[k].cells, static_cast<std::int32_t>(rc[k].cells.size())) << "cluster " << k;
    Eigen::Vector2d sum(0, 0);
    for (auto c : rc[k].cells) sum += g.cell_center(c).cast<double>();
    EXPECT_LT((r.clusters[k].centroid.cast<double>() - sum / double(rc[k].cells.size())).norm(), 1e-4);
    cells += rc[k].cells.size();
  }
  EXPECT_EQ(r.frontier_cells, cells);
  if (rc.empty()) {
    EXPECT_EQ(r.status, FrontierStatus::kNoFrontier);
    return;
  }
  const Eigen::Vector2i rcell = g.cell_of(robot_xy);
  ASSERT_TRUE(g.traversable[g.index(rcell.x(), rcell.y())]) << "test setup: robot must be on a traversable cell";
  const std::vector<double> dist = reference_distances(g, g.index(rcell.x(), rcell.y()));
  std::vector<long> src;
  std::vector<char> approach;
  reference_approach(g, label, rc.size(), s.approach_radius_m, src, approach);
  // Each cluster's candidate cells: its frontier cells and the approach cells its cells claimed.
  std::vector<std::vector<std::size_t>> cand_cells(rc.size());
  for (std::size_t k = 0; k < rc.size(); ++k) cand_cells[k] = rc[k].cells;
  for (std::size_t c = 0; c < g.cell_count(); ++c)
    if (approach[c]) cand_cells[std::size_t(label[std::size_t(src[c])])].push_back(c);
  double best = std::numeric_limits<double>::infinity();
  bool any_connected = false;
  for (std::size_t k = 0; k < rc.size(); ++k) {
    double near = std::numeric_limits<double>::infinity();
    bool cand_free = false, cand_blocked = false;
    for (auto c : cand_cells[k]) {
      near = std::min(near, dist[c]);
      if (!std::isfinite(dist[c]) || !connected(g, c)) continue;
      any_connected = true;
      if (dist[c] < s.min_goal_distance_m - 1e-3 * g.resolution_m) continue;
      const bool blk = bl.blocks(g.cell_center(c), s.blacklist_radius_m, now) ||
                       (approach[c] && bl.blocks(g.cell_center(std::size_t(src[c])), s.blacklist_radius_m, now));
      (blk ? cand_blocked : cand_free) = true;
      if (!blk) best = std::min(best, dist[c]);
    }
    EXPECT_EQ(r.clusters[k].reachable, std::isfinite(near)) << "cluster " << k;
    if (std::isfinite(near)) {
      EXPECT_NEAR(r.clusters[k].path_length_m, near, 1e-3) << "cluster " << k;
      EXPECT_NEAR(dist[g.index(g.cell_of(r.clusters[k].nearest_xy).x(), g.cell_of(r.clusters[k].nearest_xy).y())], near, 1e-3);
    } else {
      EXPECT_TRUE(std::isinf(r.clusters[k].path_length_m));
    }
    EXPECT_EQ(r.clusters[k].blacklisted, cand_blocked && !cand_free) << "cluster " << k;
  }
  if (!std::isfinite(best)) {
    EXPECT_EQ(r.status, any_connected ? FrontierStatus::kAllBlacklisted : FrontierStatus::kAllUnreachable);
    EXPECT_TRUE(r.path.empty());
    return;
  }
  ASSERT_EQ(r.status, FrontierStatus::kFound);
  EXPECT_NEAR(r.path_length_m, best, 1e-3);
  // The goal is a valid candidate at that distance.
  const Eigen::Vector2i gc = g.cell_of(r.goal_xy);
  const std::size_t gi = g.index(gc.x(), gc.y());
  EXPECT_TRUE((m[gi] && label[gi] >= 0) || approach[gi]);
  EXPECT_TRUE(connected(g, gi));
  EXPECT_FALSE(bl.blocks(r.goal_xy, s.blacklist_radius_m, now));
  EXPECT_NEAR(dist[gi], best, 1e-3);
  // The target: the goal itself, or the frontier cell an approach goal is for (within the radius).
  if (approach[gi]) {
    EXPECT_EQ(g.cell_of(r.target_xy), g.cell_of(g.cell_center(std::size_t(src[gi]))));
    EXPECT_LE((r.target_xy - r.goal_xy).norm(), s.approach_radius_m + 1e-4f);
    EXPECT_FALSE(bl.blocks(r.target_xy, s.blacklist_radius_m, now));
  } else {
    EXPECT_EQ(r.target_xy, r.goal_xy);
  }
  // The path: robot cell -> goal over traversable cells, no corner cutting, length = path_length_m.
  ASSERT_FALSE(r.path.empty());
  EXPECT_EQ(g.cell_of(r.path.front()), rcell);
  EXPECT_EQ(g.cell_of(r.path.back()), gc);
  double len = 0.0;
  for (std::size_t k = 0; k < r.path.size(); ++k) {
    const Eigen::Vector2i c = g.cell_of(r.path[k]);
    ASSERT_TRUE(g.traversable[g.index(c.x(), c.y())]);
    if (k == 0) continue;
    const Eigen::Vector2i p = g.cell_of(r.path[k - 1]);
    const int dx = c.x() - p.x(), dy = c.y() - p.y();
    ASSERT_TRUE(std::abs(dx) <= 1 && std::abs(dy) <= 1 && (dx || dy));
    if (dx && dy) {
      ASSERT_TRUE(g.traversable[g.index(c.x(), p.y())] && g.traversable[g.index(p.x(), c.y())]);
    }
    len += (dx && dy ? std::numbers::sqrt2 : 1.0) * g.resolution_m;
  }
  EXPECT_NEAR(len, r.path_length_m, 1e-3);
}

}  // namespace frontier_test
}  // namespace duet
