// Global path search and inflation (maps: built in bench_frontier.cpp, see its header comment:
// synthetic indoor 400x400 and 2000x2000 at 0.05 m, fixed seed, and the Willow map when present).
//
// Path/duet/{400x400,2000x2000,willow}: plan_path (A*, default PathSettings: clearance cost on)
//   from the robot to the reachable cell farthest from it by path length (across the map). Serial;
//   fixed-point integer costs, one 128-bit key (f, h, cell) per entry of a 4-ary heap.
// Path/naive/{...}: what a straightforward implementation does on the same inflated grid and the
//   same cost (clearance-weighted step length, octile heuristic, no corner cutting): a
//   std::priority_queue A* with a closed set, g in a std::vector<double> filled per call, the
//   penalty computed per step. Its cost must equal duet's (counter "cost").
// Inflation/{duet,duet_1t}/{...}: inflate() (classification + exact Euclidean distance transform +
//   traversability, default InflationSettings), 2 threads / 1 thread.
// Items = grid cells.
#include "bench_util.hpp"

#include <duet/kernels/inflation.hpp>
#include <duet/kernels/path.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <queue>
#include <string>
#include <vector>

namespace duet::bench {

// Defined in bench_frontier.cpp.
std::size_t plan_map_count();
const std::string& plan_map_name(std::size_t i);
GridView plan_map_view(std::size_t i);
const InflatedGrid& plan_map_inflated(std::size_t i);
Eigen::Vector2f plan_map_robot(std::size_t i);
Eigen::Vector2f plan_map_far(std::size_t i);

namespace {

/// Straightforward A* (see the file comment); returns the cost of the path found (+inf if none)
/// and the number of expanded cells.
double naive_astar(const InflatedGrid& g, const Eigen::Vector2f& a, const Eigen::Vector2f& b, const PathSettings& s,
                   std::size_t& expanded) {
  const Eigen::Vector2i sc = g.cell_of(a), gc = g.cell_of(b);
  const std::size_t start = g.index(sc.x(), sc.y()), goal = g.index(gc.x(), gc.y());
  const double res = g.resolution_m;
  const auto h = [&](int x, int y) {
    const int dx = std::abs(x - gc.x()), dy = std::abs(y - gc.y());
    return (std::max(dx, dy) - std::min(dx, dy) + std::numbers::sqrt2 * std::min(dx, dy)) * res;
  };
  const auto pen = [&](std::size_t c) {
    return std::max(0.0, 1.0 - (static_cast<double>(g.clearance_m[c]) - g.robot_radius_m) / s.clearance_decay_m);
  };
  std::vector<double> gcost(g.cell_count(), std::numeric_limits<double>::infinity());
  std::vector<char> closed(g.cell_count(), 0);
  using Item = std::pair<double, std::size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  gcost[start] = 0.0;
  open.push({h(sc.x(), sc.y()), start});
  expanded = 0;
  while (!open.empty()) {
    const std::size_t c = open.top().second;
    open.pop();
    if (closed[c]) continue;
    closed[c] = 1;
    ++expanded;
    if (c == goal) return gcost[c];
    const int x = static_cast<int>(c % static_cast<std::size_t>(g.width)), y = static_cast<int>(c / static_cast<std::size_t>(g.width));
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0) continue;
        const int nx = x + dx, ny = y + dy;
        if (!g.in_bounds(nx, ny)) continue;
        const std::size_t n = g.index(nx, ny);
        if (!g.traversable[n] || closed[n]) continue;
        const bool diag = dx != 0 && dy != 0;
        if (diag && (!g.traversable[g.index(nx, y)] || !g.traversable[g.index(x, ny)])) continue;
        const double len = (diag ? std::numbers::sqrt2 : 1.0) * res;
        const double ng = gcost[c] + len * (1.0 + s.clearance_weight * 0.5 * (pen(c) + pen(n)));
        if (ng < gcost[n]) {
          gcost[n] = ng;
          open.push({ng + h(nx, ny), n});
        }
      }
  }
  return std::numeric_limits<double>::infinity();
}

}  // namespace

void register_path() {
  for (std::size_t i = 0; i < plan_map_count(); ++i) {
    const std::string& name = plan_map_name(i);
    const std::size_t cells = plan_map_view(i).cell_count();
    benchmark::RegisterBenchmark(bench_name("Path", "duet", name).c_str(), [i, cells](benchmark::State& state) {
      const InflatedGrid& g = plan_map_inflated(i);
      const Eigen::Vector2f a = plan_map_robot(i), b = plan_map_far(i);
      PathWorkspace ws;
      PathResult r;
      run_guarded(state, [&] {
        for (auto _ : state) {
          r = plan_path(g, a, b, PathSettings{}, ws);
          benchmark::DoNotOptimize(r.waypoints.data());
        }
      });
      state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(cells));
      state.counters["expanded"] = static_cast<double>(r.expanded);
      state.counters["length_m"] = r.length_m;
      state.counters["cost"] = r.cost;
      state.SetLabel(to_string(r.status));
    });
    benchmark::RegisterBenchmark(bench_name("Path", "naive", name).c_str(), [i, cells](benchmark::State& state) {
      const InflatedGrid& g = plan_map_inflated(i);
      const Eigen::Vector2f a = plan_map_robot(i), b = plan_map_far(i);
      double cost = 0.0;
      std::size_t expanded = 0;
      for (auto _ : state) {
        cost = naive_astar(g, a, b, PathSettings{}, expanded);
        benchmark::DoNotOptimize(cost);
      }
      state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(cells));
      state.counters["expanded"] = static_cast<double>(expanded);
      state.counters["cost"] = cost;
    });
    for (const DuetImpl impl : kDuetImpls) {
      benchmark::RegisterBenchmark(bench_name("Inflation", impl.name, name).c_str(), [i, impl, cells](benchmark::State& state) {
        const GridView v = plan_map_view(i);
        InflatedGrid out;
        run_guarded(state, [&] {
          for (auto _ : state) {
            arena(impl.threads).execute([&] { inflate(v, InflationSettings{}, out); });
            benchmark::DoNotOptimize(out.clearance_m.data());
          }
        });
        state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(cells));
        state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(cells * sizeof(float)));
      });
    }
  }
}

}  // namespace duet::bench
