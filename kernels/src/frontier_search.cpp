/// @file frontier_search.cpp
/// find_frontier: clusters of frontier cells, an exact two-queue Dijkstra from the robot, the goal choice.
#include <duet/kernels/error.hpp>
#include <duet/kernels/frontier.hpp>
#include <duet/kernels/path.hpp>

#include "parallel.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <type_traits>
#include <vector>

namespace duet {

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


// ---- exact two-queue Dijkstra in fixed-point path length ------------------------------------------
//
// Costs are integers in units of res / 2^16: an orthogonal step is 65536, a diagonal one
// round(sqrt(2) * 65536) = 92682 (relative error 2e-6, far below the float rounding of a sum of
// metres). Integer sums are exact, so the two FIFO queues (one per step length) each receive
// strictly non-decreasing keys and merging their heads is exact. The search runs on uint32 costs
// (max ~ 65535 cells of path length) and reruns on uint64 costs if a popped cost comes near the
// uint32 limit (same unit, so the same result).
// Per popped interior cell: branch-free relaxations (a non-traversable cell holds cost 0, so it
// never improves; a diagonal is gated by its two orthogonal cells), a branch-free queue push
// (the entry is always written, the tail advances only on improvement) and a branch-free merge
// (each ring holds a sentinel key = max at its tail).

constexpr std::uint32_t kUnitOrth = 65536;
constexpr std::uint32_t kUnitDiag = 92682;  // round(sqrt(2) * 65536)

template <class C>
using QEntry = std::conditional_t<sizeof(C) == 4, FrontierWorkspace::Entry32, FrontierWorkspace::Entry64>;

/// Initialises the per-cell search arrays of row y: cost (traversable: max = not reached;
/// blocked: 0 = never improves) and flags (bit 0 traversable, bit 1 frontier cell of a kept
/// cluster, bit 2 on the grid border).
template <class C>
void init_rows(const InflatedGrid& g, const std::uint8_t* mask, std::uint8_t* flags, C* cost, std::size_t y, bool with_flags) {
  const std::size_t w = static_cast<std::size_t>(g.width), row = y * w;
  const std::uint8_t* t = g.traversable.data() + row;
  C* co = cost + row;
  for (std::size_t x = 0; x < w; ++x) co[x] = static_cast<C>(C{0} - static_cast<C>(t[x]));
  if (!with_flags) return;
  std::uint8_t* f = flags + row;
  const std::uint8_t* m = mask + row;
  for (std::size_t x = 0; x < w; ++x) f[x] = static_cast<std::uint8_t>(t[x] | ((m[x] != 0) << 1));
  if (y == 0 || y + 1 == static_cast<std::size_t>(g.height)) {
    for (std::size_t x = 0; x < w; ++x) f[x] |= 4;
  } else {
    f[0] |= 4;
    f[w - 1] |= 4;
  }
}

/// Dijkstra from start over the traversable cells (fl: flags); on_frontier(cell, cost, flags) is
/// called for each settled frontier cell (flags bit 1) in settling order. Returns false on uint32
/// overflow. No parent pointers: costs are exact integers, so the path is traced back afterwards
/// from the costs alone (trace_back). Everything the loop needs lives in locals.
template <class C, class OnFrontier>
bool dijkstra(const InflatedGrid& g, const std::uint8_t* fl, C* cost, std::vector<QEntry<C>>& bo, std::vector<QEntry<C>>& bd,
              std::uint32_t start, OnFrontier&& on_frontier, std::size_t& reached_out) {
  using E = QEntry<C>;
  constexpr C kMax = std::numeric_limits<C>::max();
  constexpr C Ko = kUnitOrth, Kd = kUnitDiag;
  constexpr C kLimit = kMax - 2 * Kd;  // a popped cost above this may overflow when relaxed
  const std::size_t uw = static_cast<std::size_t>(g.width);
  if (bo.size() < 1024) bo.resize(1024);
  if (bd.size() < 1024) bd.resize(1024);
  E* po = bo.data();
  E* pd = bd.data();
  std::size_t mo = bo.size() - 1, md = bd.size() - 1;  // sizes are powers of 2
  std::size_t ho = 0, to = 1, hd = 0, td = 0;
  const auto grow = [](std::vector<E>& b, E*& p, std::size_t& m, std::size_t head, std::size_t tail) {
    std::vector<E> nb(b.size() * 2);
    const std::size_t nm = nb.size() - 1;
    for (std::size_t k = head; k != tail; ++k) nb[k & nm] = b[k & m];
    b.swap(nb);
    p = b.data();
    m = nm;
  };
  cost[start] = 0;
  po[0] = E{0, start};
  po[1].d = kMax;  // sentinels
  pd[0].d = kMax;
  std::size_t reached = 0;
  // Branch-free relaxation of neighbour ni with cost v through direction dv (ok: step allowed).
#define DUET_RELAX(ni, v, ok, P, M, T)                                               \
  do {                                                                               \
    const std::size_t n_ = (ni);                                                     \
    const C old_ = cost[n_];                                                         \
    const bool u_ = (ok) & ((v) < old_);                                             \
    cost[n_] = u_ ? (v) : old_;                                                      \
    P[T & M] = E{(v), static_cast<std::uint32_t>(n_)};                               \
    T += u_;                                                                         \
  } while (0)
  for (;;) {
    if (to - ho + 6 > mo) [[unlikely]] {
      grow(bo, po, mo, ho, to);
      po[to & mo].d = kMax;
    }
    if (td - hd + 6 > md) [[unlikely]] {
      grow(bd, pd, md, hd, td);
      pd[td & md].d = kMax;
    }
    const E eo = po[ho & mo], ed = pd[hd & md];
    const bool take_o = eo.d <= ed.d;  // ties: the orthogonal ring first
    // Branch-free select (the comparison is unpredictable).
    const C d = ed.d ^ ((eo.d ^ ed.d) & (C{0} - static_cast<C>(take_o)));
    const std::uint32_t c = ed.cell ^ ((eo.cell ^ ed.cell) & (0u - static_cast<std::uint32_t>(take_o)));
    if (d == kMax) break;  // both rings hold only their sentinel
    ho += take_o;
    hd += !take_o;
    if (d != cost[c]) continue;  // stale: the cell was settled with a smaller cost
    if constexpr (sizeof(C) < 8) {
      if (d > kLimit) [[unlikely]] return false;
    }
    ++reached;
    const std::uint8_t f = fl[c];
    if (f & 2) [[unlikely]] on_frontier(c, d, f);
    const C vo = d + Ko, vd = d + Kd;
    const std::size_t cs = c;
    if (!(f & 4)) [[likely]] {  // interior: all eight neighbours exist
      const bool te = fl[cs + 1] & 1, tw = fl[cs - 1] & 1, tn = fl[cs + uw] & 1, ts = fl[cs - uw] & 1;
      DUET_RELAX(cs + 1, vo, true, po, mo, to);
      DUET_RELAX(cs - 1, vo, true, po, mo, to);
      DUET_RELAX(cs + uw, vo, true, po, mo, to);
      DUET_RELAX(cs - uw, vo, true, po, mo, to);
      DUET_RELAX(cs + uw + 1, vd, tn & te, pd, md, td);
      DUET_RELAX(cs + uw - 1, vd, tn & tw, pd, md, td);
      DUET_RELAX(cs - uw + 1, vd, ts & te, pd, md, td);
      DUET_RELAX(cs - uw - 1, vd, ts & tw, pd, md, td);
    } else {  // grid border: bounds checks
      const int x = static_cast<int>(cs % uw), y = static_cast<int>(cs / uw);
      for (int k = 0; k < 8; ++k) {
        const int nx = x + kDx[k], ny = y + kDy[k];
        if (!g.in_bounds(nx, ny)) continue;
        const std::size_t ni = g.index(nx, ny);
        if (k < 4) {
          DUET_RELAX(ni, vo, true, po, mo, to);
        } else {
          const bool ok = (fl[g.index(nx, y)] & 1) && (fl[g.index(x, ny)] & 1);  // no corner cutting
          DUET_RELAX(ni, vd, ok, pd, md, td);
        }
      }
    }
    po[to & mo].d = kMax;
    pd[td & md].d = kMax;
  }
#undef DUET_RELAX
  reached_out = reached;
  return true;
}

/// Shortest path start -> c from the settled costs: each step goes to the first neighbour p (in
/// the order of kDx/kDy) that is traversable, allowed (no corner cutting) and has cost[p] + step ==
/// cost[c] exactly. Appends the cells from c back to the start; counts the step kinds.
template <class C>
void trace_back(const InflatedGrid& g, const C* cost, std::size_t start, std::size_t c, std::vector<std::size_t>& cells,
                std::size_t& n_orth, std::size_t& n_diag) {
  const std::uint8_t* tr = g.traversable.data();
  cells.push_back(c);
  while (c != start) {
    const int x = static_cast<int>(c % static_cast<std::size_t>(g.width)), y = static_cast<int>(c / static_cast<std::size_t>(g.width));
    std::size_t next = c;
    for (int k = 0; k < 8; ++k) {
      const int px = x - kDx[k], py = y - kDy[k];  // p -> c is a step in direction k
      if (!g.in_bounds(px, py)) continue;
      const std::size_t p = g.index(px, py);
      if (!tr[p]) continue;
      if (k >= 4 && (!tr[g.index(px, y)] || !tr[g.index(x, py)])) continue;
      if (cost[p] + static_cast<C>(k < 4 ? kUnitOrth : kUnitDiag) != cost[c]) continue;
      next = p;
      ++(k < 4 ? n_orth : n_diag);
      break;
    }
    if (next == c) fail(ErrorCode::kInternal, "find_frontier: broken search tree");  // cannot happen
    c = next;
    cells.push_back(c);
  }
}

/// Drops (mask = 0) the frontier cells whose unknown 8-neighbours all lie in enclosed unknown
/// regions of fewer than min_cells cells (see min_unknown_region_m2 in frontier.hpp). Each region
/// is measured once, by a breadth-first search over kUnknown cells that stops as soon as it has
/// min_cells cells, touches the grid border or meets a cell already proved large.
void drop_enclosed_pockets(const InflatedGrid& g, std::size_t min_cells, FrontierWorkspace& ws) {
  const std::size_t n = g.cell_count();
  if (ws.region.size() != n) ws.region.assign(n, 0);
  ws.region_cells.clear();
  const int w = g.width, h = g.height;
  const auto uw = static_cast<std::uint32_t>(w);
  auto on_border = [&](std::uint32_t c) {
    const int x = static_cast<int>(c % uw), y = static_cast<int>(c / uw);
    return x == 0 || y == 0 || x == w - 1 || y == h - 1;
  };
  // The verdict (1 small, 2 large) of the region of unknown cell u.
  auto measure = [&](std::uint32_t u) -> std::uint8_t {
    if (ws.region[u] == 1 || ws.region[u] == 2) return ws.region[u];
    const std::size_t first = ws.region_cells.size();
    ws.region[u] = 3;
    ws.region_cells.push_back(u);
    bool large = false;
    for (std::size_t head = first; head < ws.region_cells.size() && !large; ++head) {
      const std::uint32_t c = ws.region_cells[head];
      if (on_border(c) || ws.region_cells.size() - first >= min_cells) {
        large = true;
        break;
      }
      const int x = static_cast<int>(c % uw), y = static_cast<int>(c / uw);
      for (int d = 0; d < 8; ++d) {
        const int nx = x + kDx[d], ny = y + kDy[d];
        if (!g.in_bounds(nx, ny)) continue;
        const std::size_t ni = g.index(nx, ny);
        if (g.state[ni] != CellState::kUnknown) continue;
        if (ws.region[ni] == 2) {
          large = true;
          break;
        }
        if (ws.region[ni] != 0) continue;  // in this search already (a small region is never adjacent)
        ws.region[ni] = 3;
        ws.region_cells.push_back(static_cast<std::uint32_t>(ni));
      }
    }
    const std::uint8_t v = large ? 2 : 1;
    for (std::size_t k = first; k < ws.region_cells.size(); ++k) ws.region[ws.region_cells[k]] = v;
    return v;
  };
  for (const std::uint32_t f : ws.frontier) {
    if (!ws.mask[f]) continue;
    const int x = static_cast<int>(f % uw), y = static_cast<int>(f / uw);
    bool keep = false;
    for (int d = 0; d < 8 && !keep; ++d) {
      const int nx = x + kDx[d], ny = y + kDy[d];
      if (!g.in_bounds(nx, ny)) continue;
      const std::size_t ni = g.index(nx, ny);
      if (g.state[ni] == CellState::kUnknown) keep = measure(static_cast<std::uint32_t>(ni)) == 2;
    }
    if (!keep) ws.mask[f] = 0;
  }
  for (const std::uint32_t c : ws.region_cells) ws.region[c] = 0;
  ws.region_cells.clear();
}

/// Approach cells (see approach_radius_m in frontier.hpp): a FIFO breadth-first search from the
/// connected frontier cells of the kept clusters that have no traversable cell (has_traversable[k]
/// = 0; ascending index order) over kFree cells,
/// each cell inheriting the source of the wave that reached it first and spreading only within
/// radius of that source. Reached traversable non-frontier cells get mask 3 and their source's
/// cluster label. The visited cells are listed in ws.approach_queue (their approach_src is reset
/// by reset_approach()).
void mark_approach_cells(const InflatedGrid& g, float radius_m, const std::vector<std::uint8_t>& has_traversable,
                         FrontierWorkspace& ws) {
  constexpr std::uint32_t kUnclaimed = std::numeric_limits<std::uint32_t>::max();
  const std::size_t n = g.cell_count();
  if (ws.approach_src.size() != n) ws.approach_src.assign(n, kUnclaimed);
  ws.approach_queue.clear();
  const int w = g.width, h = g.height;
  const auto uw = static_cast<std::uint32_t>(w);
  const float r_cells = radius_m / g.resolution_m;
  const float r2 = r_cells * r_cells;
  for (const std::uint32_t f : ws.frontier) {
    if (ws.mask[f] != 1 || has_traversable[static_cast<std::size_t>(ws.label[f])]) continue;
    const int x = static_cast<int>(f % uw), y = static_cast<int>(f / uw);
    if (x == 0 || y == 0 || x == w - 1 || y == h - 1) continue;  // not connected (§3.2)
    if (ws.approach_src[f] != kUnclaimed) continue;                    // claimed by an earlier wave
    ws.approach_src[f] = f;
    ws.approach_queue.push_back(f);
  }
  for (std::size_t head = 0; head < ws.approach_queue.size(); ++head) {
    const std::uint32_t c = ws.approach_queue[head];
    const std::uint32_t src = ws.approach_src[c];
    const int x = static_cast<int>(c % uw), y = static_cast<int>(c / uw);
    const int sx = static_cast<int>(src % uw), sy = static_cast<int>(src / uw);
    for (int d = 0; d < 8; ++d) {
      const int nx = x + kDx[d], ny = y + kDy[d];
      if (!g.in_bounds(nx, ny)) continue;
      const std::size_t ni = g.index(nx, ny);
      if (ws.approach_src[ni] != kUnclaimed || g.state[ni] != CellState::kFree) continue;
      const auto ddx = static_cast<float>(nx - sx), ddy = static_cast<float>(ny - sy);
      if (ddx * ddx + ddy * ddy > r2) continue;
      ws.approach_src[ni] = src;
      ws.approach_queue.push_back(static_cast<std::uint32_t>(ni));
      if (g.traversable[ni] && ws.mask[ni] == 0) {
        ws.mask[ni] = 3;
        ws.label[ni] = ws.label[src];
      }
    }
  }
}

/// Undoes mark_approach_cells (approach_src back to "not visited", mask 3 back to 0).
void reset_approach(FrontierWorkspace& ws) {
  for (const std::uint32_t c : ws.approach_queue) {
    ws.approach_src[c] = std::numeric_limits<std::uint32_t>::max();
    if (ws.mask[c] == 3) ws.mask[c] = 0;
  }
  ws.approach_queue.clear();
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
  if (s.min_unknown_region_m2 > 0.0f) {
    const double cells = std::ceil(static_cast<double>(s.min_unknown_region_m2) /
                                   (static_cast<double>(g.resolution_m) * static_cast<double>(g.resolution_m)));
    drop_enclosed_pockets(g, cells >= 1e15 ? std::size_t{1} << 50 : static_cast<std::size_t>(cells), ws);
  }

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
  std::vector<std::uint8_t> has_traversable(res.clusters.size(), 0);
  for (const std::uint32_t c : ws.frontier) {
    if (ws.mask[c] == 0) continue;  // dropped as the border of an enclosed pocket
    const std::int32_t k = ws.cluster_raw[static_cast<std::size_t>(ws.label[c])];
    if (k < 0) {
      ws.mask[c] = 0;
      continue;
    }
    ws.mask[c] = 1;
    ws.label[c] = k;
    has_traversable[static_cast<std::size_t>(k)] |= g.traversable[c];
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
  // 2b. Approach cells of the frontier cells the robot cannot stand on (undone on every return:
  // approach_src must be all "not visited" for the next call).
  struct ApproachReset {
    FrontierWorkspace& ws;
    ~ApproachReset() { reset_approach(ws); }
  } approach_reset{ws};
  if (s.approach_radius_m > 0.0f) mark_approach_cells(g, s.approach_radius_m, has_traversable, ws);

  // 3. Robot cell (plan_path's start rule).
  Eigen::Vector2i rc;
  const std::int64_t start = g.cell_of(robot_xy, rc) ? traversable_start(g, rc) : -1;
  if (start < 0) {
    res.status = FrontierStatus::kRobotBlocked;
    return res;
  }

  // 4. Exact two-queue Dijkstra on path length (see dijkstra() above), over the robot's whole
  // traversable component. Per-cell arrays (flags: bit 0 traversable, bit 1 frontier cell of a
  // kept cluster, bit 2 on the grid border; cost; dist) are initialised in one parallel pass.
  ws.dist.resize(n);
  ws.flags.resize(n);
  ws.cost32.resize(n);
  detail::for_each_index(static_cast<std::size_t>(h), 16, [&](std::size_t y) {
    init_rows(g, ws.mask.data(), ws.flags.data(), ws.cost32.data(), y, true);
  });
  const std::vector<FrontierCluster> clusters0 = res.clusters;  // restored if the uint32 search overflows
  const double min_units = (static_cast<double>(s.min_goal_distance_m) / g.resolution_m - 1e-3) * kUnitOrth;
  std::int64_t goal = -1;
  bool any_connected_reached = false;
  const double scale = static_cast<double>(g.resolution_m) / kUnitOrth;
  const auto run = [&]<class C>(C* cost, std::vector<QEntry<C>>& bo, std::vector<QEntry<C>>& bd) {
    // Tolerance of 1e-3 cell below min_goal_distance_m (as the reference in metres).
    const C min_cost = !(min_units > 0.0) ? C{0}
                       : min_units >= static_cast<double>(std::numeric_limits<C>::max())
                           ? std::numeric_limits<C>::max()
                           : static_cast<C>(std::ceil(min_units));
    ws.cand.assign(res.clusters.size(), 0);
    ws.cluster_goal.assign(res.clusters.size(), -1);
    goal = -1;
    any_connected_reached = false;
    const auto on_frontier = [&](std::uint32_t c, C d, std::uint8_t f) {
      const auto k = static_cast<std::size_t>(ws.label[c]);
      FrontierCluster& fc = res.clusters[k];
      if (!fc.reachable) {
        fc.reachable = true;
        fc.nearest_xy = g.cell_center(static_cast<std::size_t>(c));
        fc.path_length_m = static_cast<float>(static_cast<double>(d) * scale);
      }
      if (f & 4) return;  // not connected (§3.2): on the grid border
      any_connected_reached = true;
      if (d < min_cost) return;
      // An approach cell is blocked by the blacklist near itself or near the frontier cell it is for.
      const bool blocked = bl.blocks(g.cell_center(static_cast<std::size_t>(c)), s.blacklist_radius_m, now_s) ||
                           (ws.mask[c] == 3 && bl.blocks(g.cell_center(static_cast<std::size_t>(ws.approach_src[c])),
                                                         s.blacklist_radius_m, now_s));
      if (blocked) {
        ws.cand[k] = std::max<std::uint8_t>(ws.cand[k], 1);
      } else {
        ws.cand[k] = 2;
        if (goal < 0) goal = c;
        if (ws.cluster_goal[k] < 0) ws.cluster_goal[k] = c;  // settled in path order: the cluster's nearest
      }
    };
    if (!dijkstra<C>(g, ws.flags.data(), cost, bo, bd, static_cast<std::uint32_t>(start), on_frontier, res.reached_cells))
      return false;
    // dist: path length of the settled cells, +inf elsewhere (parallel, after the search).
    const std::uint8_t* fl = ws.flags.data();
    float* dist = ws.dist.data();
    detail::for_blocks(n, std::size_t{1} << 15, [&](std::size_t, std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i)
        dist[i] = (fl[i] & 1) && cost[i] != std::numeric_limits<C>::max() ? static_cast<float>(static_cast<double>(cost[i]) * scale)
                                                                          : std::numeric_limits<float>::infinity();
    });
    return true;
  };
  const bool wide = !run(ws.cost32.data(), ws.ring32_o, ws.ring32_d);
  if (wide) {
    // Path lengths beyond ~65535 cells: rerun with 64-bit costs (same unit, same result).
    res.clusters = clusters0;
    ws.cost64.resize(n);
    detail::for_each_index(static_cast<std::size_t>(h), 16, [&](std::size_t y) {
      init_rows(g, ws.mask.data(), ws.flags.data(), ws.cost64.data(), y, false);
    });
    (void)run(ws.cost64.data(), ws.ring64_o, ws.ring64_d);
  }
  for (std::size_t k = 0; k < res.clusters.size(); ++k) res.clusters[k].blacklisted = ws.cand[k] == 1;

  if (goal < 0) {
    res.status = any_connected_reached ? FrontierStatus::kAllBlacklisted : FrontierStatus::kAllUnreachable;
    return res;
  }
  if (s.selection == FrontierSelection::kExploreLite) {
    // explore_lite's cost over the clusters that offer a goal (ties: the lower cluster id).
    float best = std::numeric_limits<float>::infinity();
    for (std::size_t k = 0; k < res.clusters.size(); ++k) {
      if (ws.cluster_goal[k] < 0) continue;
      const float d = std::sqrt(best_e[k]);
      const float cost = s.potential_scale * d - s.gain_scale * static_cast<float>(res.clusters[k].cells) * g.resolution_m;
      if (cost < best) {
        best = cost;
        goal = ws.cluster_goal[k];
      }
    }
  }
  res.status = FrontierStatus::kFound;
  const auto gl = static_cast<std::size_t>(goal);
  res.goal_xy = g.cell_center(gl);
  res.target_xy = ws.mask[gl] == 3 ? g.cell_center(static_cast<std::size_t>(ws.approach_src[gl])) : res.goal_xy;
  std::vector<std::size_t> cells;
  std::size_t n_orth = 0, n_diag = 0;
  if (wide) trace_back(g, ws.cost64.data(), static_cast<std::size_t>(start), gl, cells, n_orth, n_diag);
  else trace_back(g, ws.cost32.data(), static_cast<std::size_t>(start), gl, cells, n_orth, n_diag);
  res.path.reserve(cells.size());
  for (const std::size_t c : cells) res.path.push_back(g.cell_center(c));
  std::reverse(res.path.begin(), res.path.end());
  // Exact length of the step sequence (the fixed-point cost differs by < 1e-5 cell per step).
  res.path_length_m = static_cast<float>((static_cast<double>(n_orth) + static_cast<double>(n_diag) * std::numbers::sqrt2) *
                                         g.resolution_m);
  return res;
}

}  // namespace duet
