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

// Heap order: the top is the smallest f, then the largest g, then the smallest cell index.
struct HeapLess {
  bool operator()(const PathWorkspace::Node& a, const PathWorkspace::Node& b) const noexcept {
    if (a.f != b.f) return a.f > b.f;
    if (a.g != b.g) return a.g < b.g;  // deeper first
    return a.cell > b.cell;
  }
};

void next_generation(PathWorkspace& ws, std::size_t n) {
  if (ws.rec.size() != n) {
    ws.rec.assign(n, PathWorkspace::CellRec{0.0, 0, 0});
    ws.goal_stamp.assign(n, 0);
    ws.generation = 0;
  }
  if (++ws.generation >= (1u << 31)) {  // tags hold 2 * generation + 1: clear once every 2^31 calls
    std::fill(ws.rec.begin(), ws.rec.end(), PathWorkspace::CellRec{0.0, 0, 0});
    std::fill(ws.goal_stamp.begin(), ws.goal_stamp.end(), 0u);
    ws.generation = 1;
  }
}

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
  const int w = g.width;
  const double rm = g.resolution_m;
  const double ox = g.origin.x(), oy = g.origin.y();
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
    for (int y = std::max(0, gc.y() - k); y <= std::min(g.height - 1, gc.y() + k); ++y)
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
  const auto heuristic = [&](std::uint32_t c) -> double {
    const int x = static_cast<int>(c % static_cast<std::uint32_t>(w)), y = static_cast<int>(c / static_cast<std::uint32_t>(w));
    if (tol > 0.0) {
      const double dx = ox + (x + 0.5) * rm - gx, dy = oy + (y + 0.5) * rm - gy;
      return std::max(0.0, std::sqrt(dx * dx + dy * dy) - reach_r);
    }
    const int ax = std::abs(x - gc.x()), ay = std::abs(y - gc.y());
    if (!diag) return (ax + ay) * rm;
    const int lo = std::min(ax, ay), hi = std::max(ax, ay);
    return ((hi - lo) + lo * kSqrt2) * rm;
  };
  const double radius = g.robot_radius_m;
  const double wgt = s.clearance_weight, inv_decay = 1.0 / s.clearance_decay_m;
  const auto penalty = [&](std::size_t c) -> double {
    return std::max(0.0, 1.0 - (static_cast<double>(g.clearance_m[c]) - radius) * inv_decay);
  };

  const std::uint8_t* tr = g.traversable.data();
  auto& heap = ws.heap;
  auto* rec = ws.rec.data();
  const std::uint32_t open_tag = 2 * gen, closed_tag = 2 * gen + 1;
  heap.clear();
  const auto st = static_cast<std::uint32_t>(start);
  rec[st] = {0.0, open_tag, st};
  heap.push_back({heuristic(st), 0.0f, st});
  std::int64_t found = -1;
  static constexpr int kDx[8] = {1, -1, 0, 0, 1, -1, 1, -1};
  static constexpr int kDy[8] = {0, 0, 1, -1, 1, 1, -1, -1};
  const int dirs = diag ? 8 : 4;
  const bool single_goal = !(tol > 0.0);
  while (!heap.empty()) {
    std::pop_heap(heap.begin(), heap.end(), HeapLess{});
    const PathWorkspace::Node top = heap.back();
    heap.pop_back();
    const std::uint32_t c = top.cell;
    if (rec[c].tag == closed_tag) continue;  // stale duplicate
    rec[c].tag = closed_tag;
    ++res.expanded;
    if (single_goal ? c == goal_cell : ws.goal_stamp[c] == gen) {
      found = c;
      break;
    }
    const double gc_cost = rec[c].g;
    const int x = static_cast<int>(c % static_cast<std::uint32_t>(w)), y = static_cast<int>(c / static_cast<std::uint32_t>(w));
    const double pc = penalty(c);
    for (int d = 0; d < dirs; ++d) {
      const int nx = x + kDx[d], ny = y + kDy[d];
      if (!g.in_bounds(nx, ny)) continue;
      const std::size_t ni = g.index(nx, ny);
      if (!tr[ni]) continue;
      double len = rm;
      if (d >= 4) {  // diagonal: both cells passed between must be traversable (no corner cutting)
        if (!tr[g.index(nx, y)] || !tr[g.index(x, ny)]) continue;
        len = kSqrt2 * rm;
      }
      PathWorkspace::CellRec& r = rec[ni];
      if (r.tag == closed_tag) continue;
      const double ng = gc_cost + len * (1.0 + wgt * 0.5 * (pc + penalty(ni)));
      if (r.tag == open_tag && r.g <= ng) continue;
      r = {ng, open_tag, c};
      const auto nc = static_cast<std::uint32_t>(ni);
      heap.push_back({ng + heuristic(nc), static_cast<float>(ng), nc});
      std::push_heap(heap.begin(), heap.end(), HeapLess{});
    }
  }
  if (found < 0) {
    res.status = PathStatus::kNoPath;
    return res;
  }
  res.status = PathStatus::kFound;
  res.cost = static_cast<float>(rec[static_cast<std::size_t>(found)].g);
  std::uint32_t c = static_cast<std::uint32_t>(found);
  std::size_t n_orth = 0, n_diag = 0;
  for (;;) {
    res.waypoints.push_back(g.cell_center(static_cast<std::size_t>(c)));
    const std::uint32_t p = rec[c].parent;
    if (p == c) break;
    const std::uint32_t uw = static_cast<std::uint32_t>(w);
    ((c % uw != p % uw) && (c / uw != p / uw) ? n_diag : n_orth) += 1;
    c = p;
  }
  std::reverse(res.waypoints.begin(), res.waypoints.end());
  res.length_m = static_cast<float>((static_cast<double>(n_orth) + static_cast<double>(n_diag) * kSqrt2) * rm);
  return res;
}

}  // namespace duet
