#include <duet/kernels/error.hpp>
#include <duet/kernels/frontier.hpp>
#include <duet/kernels/path.hpp>

#include "parallel.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace duet {

void validate(const FrontierSettings& s) {
  if (s.min_cluster_cells < 1)
    fail(ErrorCode::kInvalidArgument,
         "FrontierSettings.min_cluster_cells must be >= 1 [cells], got " + std::to_string(s.min_cluster_cells));
  if (!std::isfinite(s.min_goal_distance_m) || !(s.min_goal_distance_m >= 0.0f))
    fail(ErrorCode::kInvalidArgument,
         "FrontierSettings.min_goal_distance_m must be finite and >= 0 [m], got " + std::to_string(s.min_goal_distance_m));
  if (!std::isfinite(s.blacklist_radius_m) || !(s.blacklist_radius_m >= 0.0f))
    fail(ErrorCode::kInvalidArgument,
         "FrontierSettings.blacklist_radius_m must be finite and >= 0 [m], got " + std::to_string(s.blacklist_radius_m));
}

const char* to_string(FrontierStatus s) {
  switch (s) {
    case FrontierStatus::kFound: return "found";
    case FrontierStatus::kNoFrontier: return "no frontier";
    case FrontierStatus::kAllUnreachable: return "all frontiers unreachable";
    case FrontierStatus::kAllBlacklisted: return "all frontiers blacklisted or too near";
    case FrontierStatus::kRobotBlocked: return "robot blocked";
  }
  return "unknown";
}

// ---- GoalBlacklist ------------------------------------------------------------------------------

void GoalBlacklist::add(Eigen::Vector2f xy, double now_s, double ttl_s) {
  if (!xy.allFinite()) fail(ErrorCode::kInvalidArgument, "GoalBlacklist::add: xy must be finite");
  if (!std::isfinite(now_s)) fail(ErrorCode::kInvalidArgument, "GoalBlacklist::add: now_s must be finite");
  if (std::isnan(ttl_s) || !(ttl_s > 0.0))
    fail(ErrorCode::kInvalidArgument, "GoalBlacklist::add: ttl_s must be > 0 [s] (+inf = forever), got " + std::to_string(ttl_s));
  entries_.push_back({xy, now_s + ttl_s});
}

void GoalBlacklist::expire(double now_s) {
  std::erase_if(entries_, [now_s](const Entry& e) { return e.expiry_s <= now_s; });
}

bool GoalBlacklist::blocks(Eigen::Vector2f xy, float radius_m, double now_s) const {
  const float r2 = radius_m * radius_m;
  for (const Entry& e : entries_)
    if (e.expiry_s > now_s && (e.xy - xy).squaredNorm() <= r2) return true;
  return false;
}

// ---- frontier mask ------------------------------------------------------------------------------

namespace {

constexpr std::size_t kRowBlock = 16;  // rows per task (fixed: thread-count independent)

/// mask of rows [y0, y1): classify_row(y, unknown, free) fills 0/1 flags of row y.
template <class ClassifyRow>
std::size_t mask_rows(int w, int h, std::size_t y0, std::size_t y1, std::uint8_t* mask, ClassifyRow&& classify_row) {
  const std::size_t sw = static_cast<std::size_t>(w);
  std::vector<std::uint8_t> buf(6 * sw);
  std::uint8_t* hu[3] = {buf.data(), buf.data() + sw, buf.data() + 2 * sw};  // rows y-1, y, y+1
  std::uint8_t* u = buf.data() + 3 * sw;
  std::uint8_t* fcur = buf.data() + 4 * sw;  // free flags of row y
  std::uint8_t* fnext = buf.data() + 5 * sw; // free flags of row y+1
  // hu = horizontal 3-OR of the unknown flags of row y (zeros outside the grid); fout = free flags.
  auto horiz = [&](int y, std::uint8_t* out, std::uint8_t* fout) {
    if (y < 0 || y >= h) {
      std::fill(out, out + sw, std::uint8_t{0});
      return;
    }
    classify_row(y, u, fout);
    if (w == 1) {
      out[0] = u[0];
      return;
    }
    out[0] = static_cast<std::uint8_t>(u[0] | u[1]);
    for (std::size_t x = 1; x + 1 < sw; ++x) out[x] = static_cast<std::uint8_t>(u[x - 1] | u[x] | u[x + 1]);
    out[sw - 1] = static_cast<std::uint8_t>(u[sw - 2] | u[sw - 1]);
  };
  horiz(static_cast<int>(y0) - 1, hu[0], fnext);
  horiz(static_cast<int>(y0), hu[1], fcur);
  std::size_t count = 0;
  for (std::size_t y = y0; y < y1; ++y) {
    horiz(static_cast<int>(y) + 1, hu[2], fnext);
    std::uint8_t* m = mask + y * sw;
    std::size_t c = 0;
    for (std::size_t x = 0; x < sw; ++x) {
      const auto v = static_cast<std::uint8_t>(fcur[x] & (hu[0][x] | hu[1][x] | hu[2][x]));
      m[x] = v;
      c += v;
    }
    count += c;
    std::swap(fcur, fnext);
    std::uint8_t* t = hu[0];
    hu[0] = hu[1];
    hu[1] = hu[2];
    hu[2] = t;
  }
  return count;
}

template <class ClassifyRow>
std::size_t mask_all(int w, int h, std::uint8_t* mask, ClassifyRow&& classify_row) {
  const std::size_t sh = static_cast<std::size_t>(h);
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, detail::block_count(sh, kRowBlock), 1), std::size_t{0},
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t acc) {
        for (std::size_t b = r.begin(); b != r.end(); ++b)
          acc += mask_rows(w, h, b * kRowBlock, std::min(sh, (b + 1) * kRowBlock), mask, classify_row);
        return acc;
      },
      [](std::size_t a, std::size_t b) { return a + b; });
}

}  // namespace

std::size_t frontier_mask(const GridView& grid, const CellThresholds& t, std::span<std::uint8_t> mask) {
  validate(grid, "frontier_mask: grid");
  validate(t);
  if (mask.size() != grid.cell_count())
    fail(ErrorCode::kInvalidArgument, "frontier_mask: mask has " + std::to_string(mask.size()) + " cells, grid has " +
                                          std::to_string(grid.cell_count()));
  if (grid.cell_count() == 0) return 0;
  const float* lo = grid.logodds.data();
  const std::size_t sw = static_cast<std::size_t>(grid.width);
  const float fr = t.free_logodds, oc = t.occupied_logodds;
  return mask_all(grid.width, grid.height, mask.data(), [&](int y, std::uint8_t* u, std::uint8_t* f) {
    const float* row = lo + static_cast<std::size_t>(y) * sw;
    std::size_t x = 0;
#ifdef __SSE2__
    // 16 cells per step: two float compares, packed to 16 bytes of 0x00 / 0xFF, masked to 0 / 1.
    const __m128 vfr = _mm_set1_ps(fr), voc = _mm_set1_ps(oc);
    const __m128i one = _mm_set1_epi8(1);
    for (; x + 16 <= sw; x += 16) {
      __m128i fm[4], om[4];
      for (int k = 0; k < 4; ++k) {
        const __m128 l = _mm_loadu_ps(row + x + 4 * static_cast<std::size_t>(k));
        fm[k] = _mm_castps_si128(_mm_cmple_ps(l, vfr));  // false for NaN
        om[k] = _mm_castps_si128(_mm_cmpge_ps(l, voc));  // false for NaN
      }
      const __m128i f8 = _mm_packs_epi16(_mm_packs_epi32(fm[0], fm[1]), _mm_packs_epi32(fm[2], fm[3]));
      const __m128i o8 = _mm_packs_epi16(_mm_packs_epi32(om[0], om[1]), _mm_packs_epi32(om[2], om[3]));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(f + x), _mm_and_si128(f8, one));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(u + x), _mm_andnot_si128(_mm_or_si128(f8, o8), one));
    }
#endif
    for (; x < sw; ++x) {
      const float l = row[x];
      const bool is_free = l <= fr, is_occ = l >= oc;  // both false for NaN
      f[x] = static_cast<std::uint8_t>(is_free);
      u[x] = static_cast<std::uint8_t>(!is_free && !is_occ);
    }
  });
}

std::size_t frontier_mask(std::span<const CellState> state, int width, int height, std::span<std::uint8_t> mask) {
  if (width < 0 || height < 0)
    fail(ErrorCode::kInvalidArgument, "frontier_mask: negative size " + std::to_string(width) + " x " + std::to_string(height));
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (state.size() != n || mask.size() != n)
    fail(ErrorCode::kInvalidArgument, "frontier_mask: state and mask must have width*height = " + std::to_string(n) + " cells");
  if (n == 0) return 0;
  const std::size_t sw = static_cast<std::size_t>(width);
  const CellState* st = state.data();
  return mask_all(width, height, mask.data(), [&](int y, std::uint8_t* u, std::uint8_t* f) {
    const CellState* row = st + static_cast<std::size_t>(y) * sw;
    for (std::size_t x = 0; x < sw; ++x) {
      f[x] = static_cast<std::uint8_t>(row[x] == CellState::kFree);
      u[x] = static_cast<std::uint8_t>(row[x] == CellState::kUnknown);
    }
  });
}

// ---- find_frontier ------------------------------------------------------------------------------

namespace {

constexpr int kDx[8] = {1, -1, 0, 0, 1, -1, 1, -1};
constexpr int kDy[8] = {0, 0, 1, -1, 1, 1, -1, -1};

/// Ascending list of the cells with mask != 0 (parallel per-row counts, prefix sum, fill).
void compact(const std::vector<std::uint8_t>& mask, int w, int h, FrontierWorkspace& ws) {
  const std::size_t sw = static_cast<std::size_t>(w), sh = static_cast<std::size_t>(h);
  ws.row_count.assign(sh + 1, 0);
  detail::for_each_index(sh, 16, [&](std::size_t y) {
    const std::uint8_t* m = mask.data() + y * sw;
    std::uint32_t c = 0;
    for (std::size_t x = 0; x < sw; ++x) c += m[x] != 0;
    ws.row_count[y + 1] = c;
  });
  for (std::size_t y = 0; y < sh; ++y) ws.row_count[y + 1] += ws.row_count[y];
  ws.frontier.resize(ws.row_count[sh]);
  detail::for_each_index(sh, 16, [&](std::size_t y) {
    if (ws.row_count[y + 1] == ws.row_count[y]) return;
    const std::uint8_t* m = mask.data() + y * sw;
    std::uint32_t o = ws.row_count[y];
    for (std::size_t x = 0; x < sw; ++x)
      if (m[x]) ws.frontier[o++] = static_cast<std::uint32_t>(y * sw + x);
  });
}

}  // namespace

FrontierResult find_frontier(const InflatedGrid& g, const Eigen::Vector2f& robot_xy, const GoalBlacklist& bl,
                             double now_s, const FrontierSettings& s, FrontierWorkspace& ws) {
  validate(g, "find_frontier: grid");
  validate(s);
  FrontierResult res;
  const std::size_t n = g.cell_count();
  const int w = g.width, h = g.height;
  const auto uw = static_cast<std::uint32_t>(w);

  // 1. Frontier cells (parallel) and their ascending list.
  ws.mask.resize(n);
  ws.label.resize(n);
  frontier_mask(g.state, w, h, ws.mask);
  compact(ws.mask, w, h, ws);

  // 2. Clusters: 8-connected flood fill in ascending order of the first cell (serial). mask: 1 =
  // unlabelled frontier, 2 = labelled.
  struct RawCluster {
    std::int32_t cells;
    double sx, sy;
  };
  std::vector<RawCluster> raw;
  for (const std::uint32_t seed : ws.frontier) {
    if (ws.mask[seed] != 1) continue;
    const auto id = static_cast<std::int32_t>(raw.size());
    RawCluster rc{0, 0.0, 0.0};
    ws.stack.clear();
    ws.stack.push_back(seed);
    ws.mask[seed] = 2;
    while (!ws.stack.empty()) {
      const std::uint32_t c = ws.stack.back();
      ws.stack.pop_back();
      ws.label[c] = id;
      ++rc.cells;
      const int x = static_cast<int>(c % uw), y = static_cast<int>(c / uw);
      rc.sx += x;
      rc.sy += y;
      for (int d = 0; d < 8; ++d) {
        const int nx = x + kDx[d], ny = y + kDy[d];
        if (!g.in_bounds(nx, ny)) continue;
        const std::size_t ni = g.index(nx, ny);
        if (ws.mask[ni] == 1) {
          ws.mask[ni] = 2;
          ws.stack.push_back(static_cast<std::uint32_t>(ni));
        }
      }
    }
    raw.push_back(rc);
  }
  ws.cluster_raw.assign(raw.size(), -1);
  for (std::size_t k = 0; k < raw.size(); ++k) {
    if (raw[k].cells < s.min_cluster_cells) continue;
    ws.cluster_raw[k] = static_cast<std::int32_t>(res.clusters.size());
    FrontierCluster fc;
    fc.cells = raw[k].cells;
    const double res_m = g.resolution_m;
    fc.centroid = Eigen::Vector2f(static_cast<float>(g.origin.x() + (raw[k].sx / raw[k].cells + 0.5) * res_m),
                                  static_cast<float>(g.origin.y() + (raw[k].sy / raw[k].cells + 0.5) * res_m));
    fc.path_length_m = std::numeric_limits<float>::infinity();
    res.clusters.push_back(fc);
  }
  // Relabel to kept ids, drop small clusters from the mask, Euclidean-nearest cell per cluster.
  std::vector<float> best_e(res.clusters.size(), std::numeric_limits<float>::infinity());
  for (const std::uint32_t c : ws.frontier) {
    const std::int32_t k = ws.cluster_raw[static_cast<std::size_t>(ws.label[c])];
    if (k < 0) {
      ws.mask[c] = 0;
      continue;
    }
    ws.mask[c] = 1;
    ws.label[c] = k;
    ++res.frontier_cells;
    const Eigen::Vector2f p = g.cell_center(static_cast<std::size_t>(c));
    const float e = (p - robot_xy).squaredNorm();
    if (e < best_e[static_cast<std::size_t>(k)]) {
      best_e[static_cast<std::size_t>(k)] = e;
      res.clusters[static_cast<std::size_t>(k)].nearest_xy = p;
    }
  }
  if (res.clusters.empty()) {
    res.status = FrontierStatus::kNoFrontier;
    return res;
  }

  // 3. Robot cell (plan_path's start rule).
  Eigen::Vector2i rc;
  const std::int64_t start = g.cell_of(robot_xy, rc) ? traversable_start(g, rc) : -1;
  if (start < 0) {
    res.status = FrontierStatus::kRobotBlocked;
    return res;
  }

  // 4. Bucketed Dijkstra on path length (two FIFO queues, each filled in non-decreasing order).
  constexpr float kInf = std::numeric_limits<float>::infinity();
  ws.dist.resize(n);
  ws.dir.resize(n);
  detail::for_blocks(n, std::size_t{1} << 16, [&](std::size_t, std::size_t b, std::size_t e) {
    std::fill(ws.dist.begin() + static_cast<std::ptrdiff_t>(b), ws.dist.begin() + static_cast<std::ptrdiff_t>(e), kInf);
  });
  ws.cand.assign(res.clusters.size(), 0);
  auto& qo = ws.q_orth;
  auto& qd = ws.q_diag;
  qo.clear();
  qd.clear();
  std::size_t ho = 0, hd = 0;
  const float step_o = g.resolution_m;
  const float step_d = static_cast<float>(std::numbers::sqrt2 * g.resolution_m);
  const auto st = static_cast<std::uint32_t>(start);
  ws.dist[st] = 0.0f;
  ws.dir[st] = 255;
  qo.push_back({0.0f, st});
  // Per-cell flags for the search loop (one byte read per cell, no division): bit 0 traversable,
  // bit 1 frontier cell of a kept cluster, bit 2 on the grid border.
  ws.flags.resize(n);
  detail::for_each_index(static_cast<std::size_t>(h), 16, [&](std::size_t y) {
    const std::size_t row = y * static_cast<std::size_t>(w);
    const bool border_row = y == 0 || y + 1 == static_cast<std::size_t>(h);
    for (std::size_t x = 0; x < static_cast<std::size_t>(w); ++x) {
      const bool border = border_row || x == 0 || x + 1 == static_cast<std::size_t>(w);
      ws.flags[row + x] = static_cast<std::uint8_t>(g.traversable[row + x] | (ws.mask[row + x] << 1) | (border << 2));
    }
  });
  const std::uint8_t* fl = ws.flags.data();
  const std::uint8_t* tr = g.traversable.data();
  float* dist = ws.dist.data();
  std::int64_t goal = -1;
  bool any_connected_reached = false;
  // Tolerance of 1e-3 cell: float path lengths of exact multiples (10 x 0.05 m) must pass 0.5 m.
  const float min_d = s.min_goal_distance_m - 1e-3f * g.resolution_m;
  const std::ptrdiff_t sw = w;
  const std::ptrdiff_t off[8] = {1, -1, sw, -sw, sw + 1, sw - 1, -sw + 1, -sw - 1};
  while (ho < qo.size() || hd < qd.size()) {
    FrontierWorkspace::QueueEntry e;
    if (hd >= qd.size() || (ho < qo.size() && qo[ho].d <= qd[hd].d)) e = qo[ho++];
    else e = qd[hd++];
    const std::uint32_t c = e.cell;
    if (e.d > dist[c]) continue;  // stale
    ++res.reached_cells;
    const std::uint8_t fc_flags = fl[c];
    if (fc_flags & 2) {
      const auto k = static_cast<std::size_t>(ws.label[c]);
      FrontierCluster& fc = res.clusters[k];
      if (!fc.reachable) {
        fc.reachable = true;
        fc.nearest_xy = g.cell_center(static_cast<std::size_t>(c));
        fc.path_length_m = e.d;
      }
      if (!(fc_flags & 4)) {  // connected (§3.2): all eight neighbours inside the grid
        any_connected_reached = true;
        if (e.d >= min_d) {
          if (bl.blocks(g.cell_center(static_cast<std::size_t>(c)), s.blacklist_radius_m, now_s)) {
            ws.cand[k] = std::max<std::uint8_t>(ws.cand[k], 1);
          } else {
            ws.cand[k] = 2;
            if (goal < 0) goal = c;
          }
        }
      }
    }
    const float dn_o = e.d + step_o, dn_d = e.d + step_d;
    const auto relax_o = [&](std::size_t ni, int d) {
      if (dn_o < dist[ni]) {
        dist[ni] = dn_o;
        ws.dir[ni] = static_cast<std::uint8_t>(d);
        qo.push_back({dn_o, static_cast<std::uint32_t>(ni)});
      }
    };
    const auto relax_d = [&](std::size_t ni, int d) {
      if (dn_d < dist[ni]) {
        dist[ni] = dn_d;
        ws.dir[ni] = static_cast<std::uint8_t>(d);
        qd.push_back({dn_d, static_cast<std::uint32_t>(ni)});
      }
    };
    if (!(fc_flags & 4)) {
      // Interior: the four orthogonal flags are loaded once and gate the diagonals (no corner cutting).
      const std::size_t cs = c;
      const std::size_t usw = static_cast<std::size_t>(sw);
      const bool te = fl[cs + 1] & 1, tw = fl[cs - 1] & 1, tn = fl[cs + usw] & 1, ts = fl[cs - usw] & 1;
      if (te) relax_o(cs + 1, 0);
      if (tw) relax_o(cs - 1, 1);
      if (tn) relax_o(cs + usw, 2);
      if (ts) relax_o(cs - usw, 3);
      if (tn && te && (fl[cs + usw + 1] & 1)) relax_d(cs + usw + 1, 4);
      if (tn && tw && (fl[cs + usw - 1] & 1)) relax_d(cs + usw - 1, 5);
      if (ts && te && (fl[cs - usw + 1] & 1)) relax_d(cs - usw + 1, 6);
      if (ts && tw && (fl[cs - usw - 1] & 1)) relax_d(cs - usw - 1, 7);
      continue;
    }
    const int x = static_cast<int>(c % uw), y = static_cast<int>(c / uw);
    for (int d = 0; d < 8; ++d) {
      const int nx = x + kDx[d], ny = y + kDy[d];
      if (!g.in_bounds(nx, ny)) continue;
      const std::size_t ni = g.index(nx, ny);
      if (!tr[ni]) continue;
      if (d >= 4) {  // no corner cutting
        if (!tr[g.index(nx, y)] || !tr[g.index(x, ny)]) continue;
        relax_d(ni, d);
      } else {
        relax_o(ni, d);
      }
    }
  }
  for (std::size_t k = 0; k < res.clusters.size(); ++k) res.clusters[k].blacklisted = ws.cand[k] == 1;

  if (goal < 0) {
    res.status = any_connected_reached ? FrontierStatus::kAllBlacklisted : FrontierStatus::kAllUnreachable;
    return res;
  }
  res.status = FrontierStatus::kFound;
  const auto gl = static_cast<std::size_t>(goal);
  res.goal_xy = g.cell_center(gl);
  res.path_length_m = dist[gl];
  std::size_t c = gl;
  for (;;) {
    res.path.push_back(g.cell_center(c));
    const std::uint8_t d = ws.dir[c];
    if (d == 255) break;
    c = static_cast<std::size_t>(static_cast<std::ptrdiff_t>(c) - off[d]);
  }
  std::reverse(res.path.begin(), res.path.end());
  return res;
}

}  // namespace duet
