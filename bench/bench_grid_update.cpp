// GridUpdate/{duet,duet_1t,naive}/{dual,accum}: the labelled raw clouds into a 0.05 m log-odds
// grid, one scan per frame from its sensor position (dual: both sensors at the robot's x-y;
// accum: each frame's camera position). The grid is pre-sized (no growth in the loop) and reset
// to unknown at the start of every iteration on both sides.
// naive = a plain serial per-point 2D Bresenham ray from the sensor cell to the point's cell,
// adding the miss log-odds to every crossed cell and hit (obstacle) / miss (floor) to the end
// cell, clamped, straight into the grid: one update per point, no de-duplication.
// Items = input points (all labels; kIgnored points are skipped by both).
#include "bench_util.hpp"

#include <duet/kernels/grid.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

namespace duet::bench {
namespace {

void naive_update(OccupancyGrid& g, const Eigen::Vector2f& sensor, PointsView pts,
                  std::span<const PointLabel> labels, const GridUpdateSettings& st) {
  std::span<float> cells = g.logodds();
  auto add = [&](int x, int y, float delta) {
    if (!g.in_bounds(x, y)) return;
    float& c = cells[g.index(x, y)];
    const float v = std::isnan(c) ? 0.0f : c;
    c = std::clamp(v + delta, st.min_logodds, st.max_logodds);
  };
  const Eigen::Vector2i c0 = g.cell_of(sensor);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (labels[i] == PointLabel::kIgnored) continue;
    const Eigen::Vector3f p = pts[i];
    if (!is_finite(p)) continue;
    if ((p.head<2>() - sensor).norm() > st.max_ray_length_m) continue;
    const Eigen::Vector2i c1 = g.cell_of(p.head<2>());
    if (st.clear_along_rays) {  // Bresenham from c0 to c1, end cell excluded
      int x = c0.x(), y = c0.y();
      const int dx = std::abs(c1.x() - x), dy = -std::abs(c1.y() - y);
      const int sx = x < c1.x() ? 1 : -1, sy = y < c1.y() ? 1 : -1;
      int err = dx + dy;
      while (x != c1.x() || y != c1.y()) {
        add(x, y, st.miss_logodds);
        const int e2 = 2 * err;
        if (e2 >= dy) {
          err += dy;
          x += sx;
        }
        if (e2 <= dx) {
          err += dx;
          y += sy;
        }
      }
    }
    add(c1.x(), c1.y(), labels[i] == PointLabel::kObstacle ? st.hit_logodds : st.miss_logodds);
  }
}

PointsView scan_points(const Input& in, const Scan& s) {
  return PointsView(std::span<const Eigen::Vector3f>(in.cloud.points).subspan(s.begin, s.end - s.begin));
}

}  // namespace

void register_grid_update() {
  for (const Input* in : {&data().dual, &data().accum}) {
    for (const DuetImpl impl : kDuetImpls) {
      benchmark::RegisterBenchmark(bench_name("GridUpdate", impl.name, in->name).c_str(), [in, impl](benchmark::State& state) {
        const GridUpdateSettings s;
        GridUpdateWorkspace ws;
        OccupancyGrid grid = in->grid_template;
        const std::span<const PointLabel> labels(in->labels);
        run_guarded(state, [&] {
          for (auto _ : state) {
            auto cells = grid.logodds();
            std::fill(cells.begin(), cells.end(), OccupancyGrid::kUnknown);
            arena(impl.threads).execute([&] {
              for (const Scan& sc : in->scans)
                update_grid(grid, sc.sensor_xy, scan_points(*in, sc), labels.subspan(sc.begin, sc.end - sc.begin), s, ws);
            });
            benchmark::DoNotOptimize(grid.logodds().data());
            benchmark::ClobberMemory();
          }
        });
        report(state, in->cloud.size(), double(grid.known_cells()));
      });
    }
    benchmark::RegisterBenchmark(bench_name("GridUpdate", "naive", in->name).c_str(), [in](benchmark::State& state) {
      const GridUpdateSettings s;
      OccupancyGrid grid = in->grid_template;
      const std::span<const PointLabel> labels(in->labels);
      for (auto _ : state) {
        auto cells = grid.logodds();
        std::fill(cells.begin(), cells.end(), OccupancyGrid::kUnknown);
        for (const Scan& sc : in->scans)
          naive_update(grid, sc.sensor_xy, scan_points(*in, sc), labels.subspan(sc.begin, sc.end - sc.begin), s);
        benchmark::DoNotOptimize(grid.logodds().data());
        benchmark::ClobberMemory();
      }
      report(state, in->cloud.size(), double(grid.known_cells()));
    });
  }
}

}  // namespace duet::bench
