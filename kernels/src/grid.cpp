#include <duet/kernels/error.hpp>
#include <duet/kernels/grid.hpp>

#include "parallel.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>

namespace duet {

OccupancyGrid::OccupancyGrid(float resolution_m) : res_(resolution_m) {
  if (!(resolution_m >= kMinGridResolutionM && resolution_m <= kMaxGridResolutionM))
    fail(ErrorCode::kInvalidArgument, "OccupancyGrid: resolution must be in [" + std::to_string(kMinGridResolutionM) + ", " +
                                          std::to_string(kMaxGridResolutionM) + "] m, got " + std::to_string(resolution_m));
}

OccupancyGrid::OccupancyGrid(float resolution_m, Eigen::Vector2f origin, int width, int height)
    : OccupancyGrid(resolution_m) {
  if (width < 0 || height < 0 || !origin.allFinite())
    fail(ErrorCode::kInvalidArgument, "OccupancyGrid: size must be >= 0 and origin finite");
  if (static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height) > (std::uint64_t{1} << 31))
    fail(ErrorCode::kOutOfRange, "OccupancyGrid: " + std::to_string(width) + "x" + std::to_string(height) + " cells is too large");
  const Eigen::Vector2f far = origin + Eigen::Vector2f(static_cast<float>(width), static_cast<float>(height)) * resolution_m;
  if (!within_map_limits(origin) || !within_map_limits(far))
    fail(ErrorCode::kOutOfRange, "OccupancyGrid: the grid spans [" + std::to_string(origin.x()) + ", " + std::to_string(far.x()) +
                                     "] x [" + std::to_string(origin.y()) + ", " + std::to_string(far.y()) +
                                     "] m, beyond the map frame's limit of +-" + std::to_string(kMaxCoordinateM) + " m");
  origin_ = origin;
  w_ = width;
  h_ = height;
  cells_.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), kUnknown);
}

Eigen::Vector2i OccupancyGrid::cell_of(const Eigen::Vector2f& xy) const noexcept {
  return {static_cast<int>(std::floor((xy.x() - origin_.x()) / res_)),
          static_cast<int>(std::floor((xy.y() - origin_.y()) / res_))};
}

Eigen::Vector2f OccupancyGrid::cell_center(int ix, int iy) const noexcept {
  return {origin_.x() + (static_cast<float>(ix) + 0.5f) * res_, origin_.y() + (static_cast<float>(iy) + 0.5f) * res_};
}

void OccupancyGrid::ensure_contains(const Eigen::Vector2f& lo, const Eigen::Vector2f& hi, int margin_cells,
                                    std::size_t max_cells) {
  if (!lo.allFinite() || !hi.allFinite())
    fail(ErrorCode::kOutOfRange, "OccupancyGrid::ensure_contains: bounds are not finite");
  if (!within_map_limits(lo) || !within_map_limits(hi))
    fail(ErrorCode::kOutOfRange, "OccupancyGrid::ensure_contains: [" + std::to_string(lo.x()) + ", " + std::to_string(hi.x()) +
                                     "] x [" + std::to_string(lo.y()) + ", " + std::to_string(hi.y()) +
                                     "] m is beyond the map frame's limit of +-" + std::to_string(kMaxCoordinateM) + " m");
  if (margin_cells < 0) margin_cells = 0;
  // Work in integer cell coordinates relative to the current origin (whole cells: alignment kept).
  const double r = res_;
  auto cell = [&](double v, double o) { return std::floor((v - o) / r); };
  const double need_x0 = cell(lo.x(), origin_.x()) - margin_cells, need_y0 = cell(lo.y(), origin_.y()) - margin_cells;
  const double need_x1 = cell(hi.x(), origin_.x()) + margin_cells + 1, need_y1 = cell(hi.y(), origin_.y()) + margin_cells + 1;
  if (w_ > 0 && h_ > 0 && need_x0 >= 0 && need_y0 >= 0 && need_x1 <= w_ && need_y1 <= h_) return;
  const double x0 = (w_ > 0 && h_ > 0) ? std::min(0.0, need_x0) : need_x0;
  const double y0 = (w_ > 0 && h_ > 0) ? std::min(0.0, need_y0) : need_y0;
  const double x1 = (w_ > 0 && h_ > 0) ? std::max<double>(w_, need_x1) : need_x1;
  const double y1 = (w_ > 0 && h_ > 0) ? std::max<double>(h_, need_y1) : need_y1;
  const double nw = x1 - x0, nh = y1 - y0;
  if (!(nw * nh <= static_cast<double>(max_cells)) || nw > 1e9 || nh > 1e9)
    fail(ErrorCode::kOutOfRange, "OccupancyGrid: growing to cover [" + std::to_string(lo.x()) + ", " + std::to_string(hi.x()) +
                                     "] x [" + std::to_string(lo.y()) + ", " + std::to_string(hi.y()) + "] m needs " +
                                     std::to_string(static_cast<long long>(nw)) + "x" + std::to_string(static_cast<long long>(nh)) +
                                     " cells, more than the limit of " + std::to_string(max_cells));
  const int new_w = static_cast<int>(nw), new_h = static_cast<int>(nh);
  const int dx = static_cast<int>(-x0), dy = static_cast<int>(-y0);
  std::vector<float> cells(static_cast<std::size_t>(new_w) * static_cast<std::size_t>(new_h), kUnknown);
  for (int y = 0; y < h_; ++y)
    std::copy_n(cells_.begin() + static_cast<std::ptrdiff_t>(y) * w_, w_,
                cells.begin() + static_cast<std::ptrdiff_t>(y + dy) * new_w + dx);
  cells_.swap(cells);
  origin_ = Eigen::Vector2f(static_cast<float>(origin_.x() + x0 * r), static_cast<float>(origin_.y() + y0 * r));
  w_ = new_w;
  h_ = new_h;
}

void OccupancyGrid::to_probabilities(std::span<float> out) const {
  if (out.size() != cells_.size())
    fail(ErrorCode::kInvalidArgument, "to_probabilities: output has " + std::to_string(out.size()) + " entries, grid has " +
                                          std::to_string(cells_.size()) + " cells");
  detail::for_each_index(cells_.size(), 8192, [&](std::size_t i) {
    const float l = cells_[i];
    out[i] = std::isnan(l) ? -1.0f : 1.0f - 1.0f / (1.0f + std::exp(l));
  });
}

void OccupancyGrid::to_ros_trinary(std::span<std::int8_t> out, float occupied_threshold, float free_threshold) const {
  if (out.size() != cells_.size())
    fail(ErrorCode::kInvalidArgument, "to_ros_trinary: output has " + std::to_string(out.size()) + " entries, grid has " +
                                          std::to_string(cells_.size()) + " cells");
  if (!(free_threshold >= 0.0f && free_threshold < occupied_threshold && occupied_threshold <= 1.0f))
    fail(ErrorCode::kInvalidArgument, "to_ros_trinary: need 0 <= free_threshold < occupied_threshold <= 1");
  // Compare in log-odds: p >= t  <=>  l >= log(t / (1 - t)).
  const float lo = std::log(occupied_threshold / (1.0f - occupied_threshold));
  const float lf = free_threshold > 0.0f ? std::log(free_threshold / (1.0f - free_threshold)) : -INFINITY;
  detail::for_each_index(cells_.size(), 8192, [&](std::size_t i) {
    const float l = cells_[i];
    out[i] = std::isnan(l) ? std::int8_t{-1} : l >= lo ? std::int8_t{100} : l <= lf ? std::int8_t{0} : std::int8_t{-1};
  });
}

std::size_t OccupancyGrid::known_cells() const noexcept {
  return static_cast<std::size_t>(std::count_if(cells_.begin(), cells_.end(), [](float l) { return !std::isnan(l); }));
}

void validate(const GridUpdateSettings& s) {
  if (!(s.hit_logodds > 0.0f) || !std::isfinite(s.hit_logodds))
    fail(ErrorCode::kInvalidArgument, "GridUpdateSettings.hit_logodds must be > 0, got " + std::to_string(s.hit_logodds));
  if (!(s.miss_logodds < 0.0f) || !std::isfinite(s.miss_logodds))
    fail(ErrorCode::kInvalidArgument, "GridUpdateSettings.miss_logodds must be < 0, got " + std::to_string(s.miss_logodds));
  if (!(s.min_logodds < 0.0f && s.max_logodds > 0.0f) || !std::isfinite(s.min_logodds) || !std::isfinite(s.max_logodds))
    fail(ErrorCode::kInvalidArgument, "GridUpdateSettings: need min_logodds < 0 < max_logodds, both finite");
  if (!(s.max_ray_length_m > 0.0f) || !std::isfinite(s.max_ray_length_m))
    fail(ErrorCode::kInvalidArgument, "GridUpdateSettings.max_ray_length_m must be finite and > 0 m");
  if (!std::isfinite(s.keep_occupied_within_m) || !(s.keep_occupied_within_m >= 0.0f))
    fail(ErrorCode::kInvalidArgument,
         "GridUpdateSettings.keep_occupied_within_m must be finite and >= 0 [m], got " + std::to_string(s.keep_occupied_within_m));
  if (!std::isfinite(s.keep_occupied_logodds))
    fail(ErrorCode::kInvalidArgument, "GridUpdateSettings.keep_occupied_logodds must be finite, got " + std::to_string(s.keep_occupied_logodds));
  if (std::isnan(s.clear_max_height_m))
    fail(ErrorCode::kInvalidArgument, "GridUpdateSettings.clear_max_height_m must not be NaN (+inf: every ray clears)");
  if (s.grow_margin_cells < 0 || s.grow_margin_cells > 100000)
    fail(ErrorCode::kInvalidArgument, "GridUpdateSettings.grow_margin_cells must be in [0, 100000]");
}

void update_grid(OccupancyGrid& grid, const Eigen::Vector2f& sensor_xy, PointsView points,
                 std::span<const PointLabel> labels, const GridUpdateSettings& settings, GridUpdateWorkspace& ws) {
  validate(settings);
  const std::size_t n = points.size();
  if (labels.size() != n)
    fail(ErrorCode::kInvalidArgument, "update_grid: " + std::to_string(labels.size()) + " labels for " +
                                          std::to_string(n) + " points");
  if (!sensor_xy.allFinite()) fail(ErrorCode::kInvalidArgument, "update_grid: sensor position is not finite");
  if (!within_map_limits(sensor_xy))
    fail(ErrorCode::kOutOfRange, "update_grid: the sensor at (" + std::to_string(sensor_xy.x()) + ", " + std::to_string(sensor_xy.y()) +
                                     ") m is beyond the map frame's limit of +-" + std::to_string(kMaxCoordinateM) + " m");
  const float max_r2 = settings.max_ray_length_m * settings.max_ray_length_m;
  auto used = [&](std::size_t i, Eigen::Vector2f& xy) {
    if (labels[i] == PointLabel::kIgnored) return false;
    const float* p = points.ptr(i);
    xy = Eigen::Vector2f(p[0], p[1]);
    return within_map_limits(xy) && (xy - sensor_xy).squaredNorm() <= max_r2;  // NaN: not within
  };

  // 1. Bounds of the update (sensor + used points); grow the grid to hold them.
  constexpr std::size_t kBlock = 1 << 14;
  const std::size_t nb = detail::block_count(n, kBlock);
  std::vector<Eigen::Vector4f> bb(nb, Eigen::Vector4f(sensor_xy.x(), sensor_xy.y(), sensor_xy.x(), sensor_xy.y()));
  detail::for_blocks(n, kBlock, [&](std::size_t b, std::size_t begin, std::size_t end) {
    Eigen::Vector4f box = bb[b];
    Eigen::Vector2f xy;
    for (std::size_t i = begin; i < end; ++i)
      if (used(i, xy)) box = Eigen::Vector4f(std::min(box[0], xy.x()), std::min(box[1], xy.y()), std::max(box[2], xy.x()),
                                             std::max(box[3], xy.y()));
    bb[b] = box;
  });
  Eigen::Vector4f box(sensor_xy.x(), sensor_xy.y(), sensor_xy.x(), sensor_xy.y());
  for (const auto& b : bb)
    box = Eigen::Vector4f(std::min(box[0], b[0]), std::min(box[1], b[1]), std::max(box[2], b[2]), std::max(box[3], b[3]));
  grid.ensure_contains(box.head<2>(), box.tail<2>(), settings.grow_margin_cells);

  // 2. Masks over the update's cell window: hit / end-free per point, free along rays.
  const Eigen::Vector2i c0 = grid.cell_of(box.head<2>()), c1 = grid.cell_of(box.tail<2>());
  const int bw = c1.x() - c0.x() + 1, bh = c1.y() - c0.y() + 1;
  const std::size_t wn = static_cast<std::size_t>(bw) * static_cast<std::size_t>(bh);
  ws.mask.assign(4 * wn, 0);
  std::uint8_t* hit = ws.mask.data();
  std::uint8_t* end_free = hit + wn;
  std::uint8_t* ray_free = end_free + wn;
  std::uint8_t* ray_end = ray_free + wn;  // end cells of the rays that clear
  const float clear_z = settings.clear_max_height_m;
  auto win = [&](const Eigen::Vector2i& c) {
    return static_cast<std::size_t>(c.y() - c0.y()) * static_cast<std::size_t>(bw) + static_cast<std::size_t>(c.x() - c0.x());
  };
  auto set = [](std::uint8_t* m, std::size_t i) { std::atomic_ref<std::uint8_t>(m[i]).store(1, std::memory_order_relaxed); };
  detail::for_blocks(n, kBlock, [&](std::size_t, std::size_t begin, std::size_t end) {
    Eigen::Vector2f xy;
    for (std::size_t i = begin; i < end; ++i)
      if (used(i, xy)) {
        const bool obstacle = labels[i] == PointLabel::kObstacle;
        const std::size_t w = win(grid.cell_of(xy));
        set(obstacle ? hit : end_free, w);
        if (!obstacle || !(points.ptr(i)[2] > clear_z)) set(ray_end, w);  // a non-finite z: as before
      }
  });

  // 3. Free space along the 2D ray from the sensor to the centre of every distinct end cell
  //    (Amanatides-Woo traversal); the end cell itself is excluded.
  if (settings.clear_along_rays) {
    const Eigen::Vector2i sc = grid.cell_of(sensor_xy);
    const double res = grid.resolution();
    const double org_x = grid.origin().x(), org_y = grid.origin().y();
    detail::for_blocks(wn, 2048, [&](std::size_t, std::size_t begin, std::size_t end) {
      for (std::size_t w = begin; w < end; ++w) {
        if (!ray_end[w]) continue;
        const Eigen::Vector2i ec(c0.x() + static_cast<int>(w % static_cast<std::size_t>(bw)),
                                 c0.y() + static_cast<int>(w / static_cast<std::size_t>(bw)));
        // Crossing times in double, from the integer cell boundary at every step (no running
        // sums, whose round-off would step into a wrong cell near grid corners).
        const Eigen::Vector2f target = grid.cell_center(ec.x(), ec.y());
        const double ox = sensor_xy.x(), oy = sensor_xy.y();
        const double dx = static_cast<double>(target.x()) - ox, dy = static_cast<double>(target.y()) - oy;
        const int sx = dx > 0 ? 1 : -1, sy = dy > 0 ? 1 : -1;
        Eigen::Vector2i c = sc;
        const int steps = std::abs(ec.x() - sc.x()) + std::abs(ec.y() - sc.y());
        for (int s = 0; s < steps && c != ec; ++s) {
          set(ray_free, win(c));
          const double tx = dx != 0.0 ? (org_x + (c.x() + (sx > 0 ? 1 : 0)) * res - ox) / dx : INFINITY;
          const double ty = dy != 0.0 ? (org_y + (c.y() + (sy > 0 ? 1 : 0)) * res - oy) / dy : INFINITY;
          // Never step past the end cell's row or column: the walk stays inside the window.
          if (c.y() == ec.y() || (c.x() != ec.x() && tx < ty)) c.x() += sx;
          else c.y() += sy;
        }
      }
    });
  }

  // 4. One update per cell: hit if any obstacle point fell in it, else miss if seen free.
  const float hl = settings.hit_logodds, ml = settings.miss_logodds;
  const float lmin = settings.min_logodds, lmax = settings.max_logodds;
  std::span<float> cells = grid.logodds();
  const float keep_r2 = settings.keep_occupied_within_m * settings.keep_occupied_within_m;
  const float keep_l = settings.keep_occupied_logodds;
  detail::for_each_index(static_cast<std::size_t>(bh), 16, [&](std::size_t row) {
    for (int col = 0; col < bw; ++col) {
      const std::size_t w = row * static_cast<std::size_t>(bw) + static_cast<std::size_t>(col);
      float delta;
      if (hit[w]) delta = hl;
      else if (end_free[w] || ray_free[w]) delta = ml;
      else continue;
      float& l = cells[grid.index(c0.x() + col, c0.y() + static_cast<int>(row))];
      if (keep_r2 > 0.0f && !hit[w] && !end_free[w] && l > keep_l &&
          (grid.cell_center(c0.x() + col, c0.y() + static_cast<int>(row)) - sensor_xy).squaredNorm() <= keep_r2)
        continue;  // a ray beside an obstacle too near for the sensor: kept (keep_occupied_within_m)
      l = std::clamp((std::isnan(l) ? 0.0f : l) + delta, lmin, lmax);
    }
  });
}

}  // namespace duet

namespace duet {

bool observed_extent(const OccupancyGrid& g, Eigen::Vector2f& lo, Eigen::Vector2f& hi) {
  int x0 = g.width(), y0 = g.height(), x1 = -1, y1 = -1;
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < g.width(); ++x)
      if (!std::isnan(g.at(x, y))) {
        x0 = std::min(x0, x);
        x1 = std::max(x1, x);
        y0 = std::min(y0, y);
        y1 = std::max(y1, y);
      }
  if (x1 < 0) return false;
  const float r = g.resolution();
  lo = g.origin() + Eigen::Vector2f(static_cast<float>(x0) * r, static_cast<float>(y0) * r);
  hi = g.origin() + Eigen::Vector2f(static_cast<float>(x1 + 1) * r, static_cast<float>(y1 + 1) * r);
  return true;
}

void accumulate_grid(OccupancyGrid& dst, const OccupancyGrid& src, const Pose2& T, float min_logodds, float max_logodds) {
  if (dst.resolution() != src.resolution())
    fail(ErrorCode::kInvalidArgument, "accumulate_grid: resolutions differ (" + std::to_string(dst.resolution()) + " and " +
                                          std::to_string(src.resolution()) + " m)");
  if (!(std::isfinite(T.x) && std::isfinite(T.y) && std::isfinite(T.theta)))
    fail(ErrorCode::kInvalidArgument, "accumulate_grid: the placement T is not finite");
  if (!(min_logodds <= max_logodds)) fail(ErrorCode::kInvalidArgument, "accumulate_grid: min_logodds > max_logodds");
  Eigen::Vector2f src_lo, src_hi;
  if (!observed_extent(src, src_lo, src_hi)) return;
  Eigen::Vector2f lo(std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity()), hi = -lo;
  for (const float cx : {src_lo.x(), src_hi.x()})
    for (const float cy : {src_lo.y(), src_hi.y()}) {
      const Eigen::Vector2f q = transform_point(T, {cx, cy});
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
    }
  dst.ensure_contains(lo, hi, 1);
  const Eigen::Vector2i d0 = dst.cell_of(lo), d1 = dst.cell_of(hi);
  const float c = std::cos(T.theta), s = std::sin(T.theta);
  auto cells = dst.logodds();
  for (int y = std::max(d0.y(), 0); y <= std::min(d1.y(), dst.height() - 1); ++y)
    for (int x = std::max(d0.x(), 0); x <= std::min(d1.x(), dst.width() - 1); ++x) {
      const Eigen::Vector2f q = dst.cell_center(x, y);
      // T^-1 q = R^T (q - t)
      const float qx = q.x() - T.x, qy = q.y() - T.y;
      const Eigen::Vector2i sc = src.cell_of({c * qx + s * qy, -s * qx + c * qy});
      if (!src.in_bounds(sc.x(), sc.y())) continue;
      const float l = src.at(sc.x(), sc.y());
      if (std::isnan(l)) continue;
      float& v = cells[dst.index(x, y)];
      v = std::clamp((std::isnan(v) ? 0.0f : v) + l, min_logodds, max_logodds);
    }
}

}  // namespace duet
