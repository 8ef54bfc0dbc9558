#include <duet/kernels/error.hpp>
#include <duet/kernels/path.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <string>

namespace duet {

void validate(const PathSettings& s) {
  if (!std::isfinite(s.clearance_weight) || !(s.clearance_weight >= 0.0f))
    fail(ErrorCode::kInvalidArgument,
         "PathSettings.clearance_weight must be finite and >= 0, got " + std::to_string(s.clearance_weight));
  if (!std::isfinite(s.clearance_decay_m) || !(s.clearance_decay_m > 0.0f))
    fail(ErrorCode::kInvalidArgument,
         "PathSettings.clearance_decay_m must be finite and > 0 [m], got " + std::to_string(s.clearance_decay_m));
  if (!std::isfinite(s.goal_tolerance_m) || !(s.goal_tolerance_m >= 0.0f))
    fail(ErrorCode::kInvalidArgument,
         "PathSettings.goal_tolerance_m must be finite and >= 0 [m], got " + std::to_string(s.goal_tolerance_m));
}

const char* to_string(PathStatus s) {
  switch (s) {
    case PathStatus::kFound: return "found";
    case PathStatus::kStartBlocked: return "start blocked";
    case PathStatus::kGoalBlocked: return "goal blocked";
    case PathStatus::kNoPath: return "no path";
    case PathStatus::kOutsideGrid: return "outside grid";
  }
  return "unknown";
}

std::int64_t traversable_start(const InflatedGrid& g, const Eigen::Vector2i& cell) {
  const std::size_t c = g.index(cell.x(), cell.y());
  if (g.traversable[c]) return static_cast<std::int64_t>(c);
  const double res = g.resolution_m, r = g.robot_radius_m;
  const int k = static_cast<int>(std::floor(r / res));
  const double r2 = r * r;
  std::int64_t best = -1;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (int dy = -k; dy <= k; ++dy) {
    for (int dx = -k; dx <= k; ++dx) {
      const int x = cell.x() + dx, y = cell.y() + dy;
      if (!g.in_bounds(x, y)) continue;
      const double d2 = (static_cast<double>(dx) * dx + static_cast<double>(dy) * dy) * res * res;
      if (d2 > r2) continue;
      const std::size_t i = g.index(x, y);
      if (!g.traversable[i]) continue;
      // Row-major scan: the first cell at the smallest distance has the smallest index.
      if (d2 < best_d2) {
        best_d2 = d2;
        best = static_cast<std::int64_t>(i);
      }
    }
  }
  return best;
}

namespace {

constexpr double kSqrt2 = std::numbers::sqrt2;

__extension__ typedef unsigned __int128 Key;  // heap key: f (high 64 bits), h >> shift, cell

inline Key key_of(const PathWorkspace::Node& n) noexcept { return (static_cast<Key>(n.hi) << 64) | n.lo; }

// 4-ary min-heap on the 128-bit key (one branch-free integer comparison per step instead of three
// on doubles/floats; half the depth of a binary heap).
void heap_push(std::vector<PathWorkspace::Node>& heap, PathWorkspace::Node v) {
  std::size_t i = heap.size();
  heap.push_back(v);
  PathWorkspace::Node* h = heap.data();
  const Key k = key_of(v);
  while (i > 0) {
    const std::size_t p = (i - 1) >> 2;
    if (!(k < key_of(h[p]))) break;
    h[i] = h[p];
    i = p;
  }
  h[i] = v;
}

PathWorkspace::Node heap_pop(std::vector<PathWorkspace::Node>& heap) {
  PathWorkspace::Node* h = heap.data();
  const PathWorkspace::Node top = h[0];
  const PathWorkspace::Node last = heap.back();
  heap.pop_back();
  const std::size_t n = heap.size();
  if (n == 0) return top;
  const Key k = key_of(last);
  std::size_t i = 0;
  for (;;) {
    const std::size_t c = 4 * i + 1;
    if (c >= n) break;
    std::size_t m = c;
    Key mk = key_of(h[c]);
    const std::size_t e = std::min(c + 4, n);
    for (std::size_t j = c + 1; j < e; ++j) {
      const Key jk = key_of(h[j]);
      const bool lt = jk < mk;
      mk = lt ? jk : mk;
      m = lt ? j : m;
    }
    if (!(mk < k)) break;
    h[i] = h[m];
    i = m;
  }
  h[i] = last;
  return top;
}

void next_generation(PathWorkspace& ws, std::size_t n) {
  if (ws.rec.size() != n) {
    ws.rec.assign(n, PathWorkspace::CellRec{0, 0, 0});
    ws.goal_stamp.assign(n, 0);
    ws.generation = 0;
  }
  if (++ws.generation >= (1u << 31)) {  // tags hold 2 * generation + 1: clear once every 2^31 calls
    std::fill(ws.rec.begin(), ws.rec.end(), PathWorkspace::CellRec{0, 0, 0});
    std::fill(ws.goal_stamp.begin(), ws.goal_stamp.end(), 0u);
    ws.generation = 1;
  }
}

int bit_width_u64(std::uint64_t v) { return v == 0 ? 0 : 64 - __builtin_clzll(v); }

}  // namespace

PathResult plan_path(const InflatedGrid& g, const Eigen::Vector2f& start_xy, const Eigen::Vector2f& goal_xy,
                     const PathSettings& s, PathWorkspace& ws) {
  validate(g, "plan_path: grid");
  validate(s);
  PathResult res;
  Eigen::Vector2i sc, gc;
  if (!g.cell_of(start_xy, sc) || !g.cell_of(goal_xy, gc)) {
    res.status = PathStatus::kOutsideGrid;
    return res;
  }
  const std::int64_t start = traversable_start(g, sc);
  if (start < 0) {
    res.status = PathStatus::kStartBlocked;
    return res;
  }
  res.start_moved = static_cast<std::size_t>(start) != g.index(sc.x(), sc.y());

  const std::size_t n = g.cell_count();
  const int w = g.width, hgt = g.height;
  const double rm = g.resolution_m;
  const double ox = g.origin.x(), oy = g.origin.y();
  const double wgt = s.clearance_weight;

  // Fixed-point units (see the header): every f is below bound_cells cell lengths.
  const double bound_cells = static_cast<double>(n) * 1.4143 * (1.0 + wgt) + 1.5 * (static_cast<double>(w) + hgt) + 4.0;
  const int fbits = std::min(30, 62 - static_cast<int>(std::ceil(std::log2(bound_cells))));
  if (fbits < 4)
    fail(ErrorCode::kInvalidArgument, "PathSettings.clearance_weight too large for a grid of " + std::to_string(n) +
                                          " cells (need cell_count * (1 + clearance_weight) < ~2^57), got " +
                                          std::to_string(s.clearance_weight));
  const double unit_per_cell = std::ldexp(1.0, fbits);  // u per cell length
  const std::int64_t lo_i = std::int64_t{1} << fbits;
  const auto ld_i = static_cast<std::int64_t>(std::llround(kSqrt2 * unit_per_cell));
  const double lo_d = static_cast<double>(lo_i), ld_d = kSqrt2 * unit_per_cell;

  next_generation(ws, n);
  const std::uint32_t gen = ws.generation;

  // Goal set: the goal cell, plus (tolerance > 0) every cell whose centre is within the tolerance
  // of the goal point; only traversable cells count.
  const double tol = s.goal_tolerance_m;
  const double gx = goal_xy.x(), gy = goal_xy.y();
  const std::size_t goal_cell = g.index(gc.x(), gc.y());
  bool any_goal = false;
  double reach_r = 0.0;  // every goal-set centre is within reach_r of the goal point
  if (tol > 0.0) {
    const double cx = ox + (gc.x() + 0.5) * rm - gx, cy = oy + (gc.y() + 0.5) * rm - gy;
    reach_r = std::max(tol, std::sqrt(cx * cx + cy * cy));
    const int k = static_cast<int>(std::ceil(tol / rm)) + 1;
    for (int y = std::max(0, gc.y() - k); y <= std::min(hgt - 1, gc.y() + k); ++y)
      for (int x = std::max(0, gc.x() - k); x <= std::min(w - 1, gc.x() + k); ++x) {
        const std::size_t i = g.index(x, y);
        if (!g.traversable[i]) continue;
        const double dx = ox + (x + 0.5) * rm - gx, dy = oy + (y + 0.5) * rm - gy;
        if (i == goal_cell || dx * dx + dy * dy <= tol * tol) {
          ws.goal_stamp[i] = gen;
          any_goal = true;
        }
      }
  } else if (g.traversable[goal_cell]) {
    ws.goal_stamp[goal_cell] = gen;
    any_goal = true;
  }
  if (!any_goal) {
    res.status = PathStatus::kGoalBlocked;
    return res;
  }

  const bool diag = s.allow_diagonal;
  const bool single_goal = !(tol > 0.0);
  // Integer heuristic [u]. Octile: exact in the integer step lengths, hence consistent. Euclidean
  // (tolerance): scaled by (1 - 4 * 2^-F) before rounding down, so that the rounding (<= 1 u) and the
  // diagonal step's rounding (<= 0.5 u) are absorbed by the slack (>= 4 u per step).
  const double gxc = (gx - ox) / rm - 0.5, gyc = (gy - oy) / rm - 0.5;  // goal point in cell coordinates
  const double reach_c = reach_r / rm;
  const double eu_scale = unit_per_cell * (1.0 - 4.0 / unit_per_cell);
  const auto heuristic = [&](int x, int y) -> std::int64_t {
    if (!single_goal) {
      const double dx = x - gxc, dy = y - gyc;
      const double d = std::sqrt(dx * dx + dy * dy) - reach_c;
      return d > 0.0 ? static_cast<std::int64_t>(d * eu_scale) : 0;
    }
    const int ax = std::abs(x - gc.x()), ay = std::abs(y - gc.y());
    if (!diag) return (ax + ay) * lo_i;
    const int lo = std::min(ax, ay), hi = std::max(ax, ay);
    return (hi - lo) * lo_i + lo * ld_i;
  };
  // Key layout: low word = (h >> hshift) << cbits | cell.
  const int cbits = std::max(1, bit_width_u64(static_cast<std::uint64_t>(n - 1)));
  const double hmax = (1.5 * (static_cast<double>(w) + hgt) + 4.0) * unit_per_cell;
  const int hshift = std::max(0, bit_width_u64(static_cast<std::uint64_t>(hmax)) - (64 - cbits));
  const auto make_node = [&](std::int64_t gval, std::int64_t hval, std::uint32_t c) {
    return PathWorkspace::Node{((static_cast<std::uint64_t>(hval) >> hshift) << cbits) | c,
                               static_cast<std::uint64_t>(gval + hval)};
  };

  const double radius = g.robot_radius_m;
  const double inv_decay = 1.0 / s.clearance_decay_m, half_w = 0.5 * wgt;
  const float* clr = g.clearance_m.data();
  const auto penalty = [&](std::size_t c) -> double {
    return std::max(0.0, 1.0 - (static_cast<double>(clr[c]) - radius) * inv_decay);
  };

  const std::uint8_t* tr = g.traversable.data();
  auto& heap = ws.heap;
  auto* rec = ws.rec.data();
  const std::uint32_t open_tag = 2 * gen, closed_tag = 2 * gen + 1;
  heap.clear();
  const auto st = static_cast<std::uint32_t>(start);
  rec[st] = {0, open_tag, st};
  heap_push(heap, make_node(0, heuristic(static_cast<int>(st % static_cast<std::uint32_t>(w)),
                                         static_cast<int>(st / static_cast<std::uint32_t>(w))),
                            st));
  std::int64_t found = -1;
  const std::uint64_t cell_mask = (std::uint64_t{1} << cbits) - 1;
  const std::uint32_t uw = static_cast<std::uint32_t>(w);
  const std::ptrdiff_t sw = w;
  while (!heap.empty()) {
    const PathWorkspace::Node top = heap_pop(heap);
    const auto c = static_cast<std::uint32_t>(top.lo & cell_mask);
    PathWorkspace::CellRec& rc = rec[c];
    if (rc.tag == closed_tag) continue;  // stale duplicate
    rc.tag = closed_tag;
    ++res.expanded;
    if (single_goal ? c == goal_cell : ws.goal_stamp[c] == gen) {
      found = c;
      break;
    }
    const std::int64_t gcur = rc.g;
    const int x = static_cast<int>(c % uw), y = static_cast<int>(c / uw);
    const double pc = penalty(c);
    const bool has_w = x > 0, has_e = x + 1 < w, has_s = y > 0, has_n = y + 1 < hgt;
    // Orthogonal neighbours: traversable flags (also gate the diagonals: no corner cutting).
    const bool te = has_e && tr[c + 1], tw = has_w && tr[c - 1];
    const bool tn = has_n && tr[c + uw], ts = has_s && tr[c - uw];
    const auto relax = [&](std::size_t ni, int nx, int ny, std::int64_t len_i, double len_d) {
      PathWorkspace::CellRec& r = rec[ni];
      if (r.tag == closed_tag) return;
      const double pen = len_d * half_w * (pc + penalty(ni));
      const std::int64_t ng = gcur + len_i + static_cast<std::int64_t>(pen + 0.5);
      if (r.tag == open_tag && r.g <= ng) return;
      r = {ng, open_tag, c};
      heap_push(heap, make_node(ng, heuristic(nx, ny), static_cast<std::uint32_t>(ni)));
    };
    if (te) relax(c + 1, x + 1, y, lo_i, lo_d);
    if (tw) relax(c - 1, x - 1, y, lo_i, lo_d);
    if (tn) relax(c + uw, x, y + 1, lo_i, lo_d);
    if (ts) relax(c - uw, x, y - 1, lo_i, lo_d);
    if (diag) {
      if (te && tn && tr[c + 1 + sw]) relax(c + 1 + sw, x + 1, y + 1, ld_i, ld_d);
      if (tw && tn && tr[c - 1 + sw]) relax(c - 1 + sw, x - 1, y + 1, ld_i, ld_d);
      if (te && ts && tr[c + 1 - sw]) relax(c + 1 - sw, x + 1, y - 1, ld_i, ld_d);
      if (tw && ts && tr[c - 1 - sw]) relax(c - 1 - sw, x - 1, y - 1, ld_i, ld_d);
    }
  }
  if (found < 0) {
    res.status = PathStatus::kNoPath;
    return res;
  }
  res.status = PathStatus::kFound;
  // Trace back; length and cost recomputed in double from the header's formula.
  std::uint32_t c = static_cast<std::uint32_t>(found);
  std::size_t n_orth = 0, n_diag = 0;
  double cost = 0.0;
  for (;;) {
    res.waypoints.push_back(g.cell_center(static_cast<std::size_t>(c)));
    const std::uint32_t p = rec[c].parent;
    if (p == c) break;
    const bool is_diag = (c % uw != p % uw) && (c / uw != p / uw);
    (is_diag ? n_diag : n_orth) += 1;
    cost += (is_diag ? kSqrt2 : 1.0) * rm * (1.0 + half_w * (penalty(c) + penalty(p)));
    c = p;
  }
  std::reverse(res.waypoints.begin(), res.waypoints.end());
  res.length_m = static_cast<float>((static_cast<double>(n_orth) + static_cast<double>(n_diag) * kSqrt2) * rm);
  res.cost = static_cast<float>(cost);
  return res;
}

}  // namespace duet
