/// @file costmap_layers.cpp
/// The Navigator's costmap layers (contact_layer.hpp, footprint_layer.hpp, recent_obstacle_layer.hpp,
/// trail_layer.hpp).
#include <duet/kernels/motion_model.hpp>
#include <duet/kernels/error.hpp>
#include <duet/runtime/navigation/contact_layer.hpp>
#include <duet/runtime/navigation/footprint_layer.hpp>
#include <duet/runtime/navigation/recent_obstacle_layer.hpp>
#include <duet/runtime/navigation/trail_layer.hpp>

#include <algorithm>
#include <cmath>

namespace duet {

namespace {
/// Calls fn(index) for every cell of `g` whose centre is within r of p.
template <class F>
void for_each_index_in_disc(const OccupancyGrid& g, const Eigen::Vector2f& p, float r, F&& fn) {
  const int rc = static_cast<int>(std::ceil(r / g.resolution()));
  const Eigen::Vector2i c = g.cell_of(p);
  for (int dy = -rc; dy <= rc; ++dy)
    for (int dx = -rc; dx <= rc; ++dx) {
      const int x = c.x() + dx, y = c.y() + dy;
      if (!g.in_bounds(x, y) || (g.cell_center(x, y) - p).norm() > r) continue;
      fn(g.index(x, y));
    }
}

/// Calls fn(log-odds) for every cell of `g` whose centre is within r of p.
template <class F>
void for_each_cell_in_disc(OccupancyGrid& g, const Eigen::Vector2f& p, float r, F&& fn) {
  for_each_index_in_disc(g, p, r, [&](std::size_t i) { fn(g.logodds()[i]); });
}

void shift_points(std::vector<Eigen::Vector2f>& points, const Pose2& D) {
  for (Eigen::Vector2f& p : points) p = transform_point(D, p);
}
}  // namespace

// ---- ContactLayer ---------------------------------------------------------------------------

void ContactLayer::add(const Eigen::Vector2f& p) {
  if (p.allFinite()) points_.push_back(p);
}

void ContactLayer::apply(OccupancyGrid& grid) {
  for (const Eigen::Vector2f& p : points_) for_each_cell_in_disc(grid, p, radius_m_, [&](float& l) { l = occupied_; });
}

void ContactLayer::shift(const Pose2& D) { shift_points(points_, D); }

// ---- RecentObstacleLayer --------------------------------------------------------------------

void RecentObstacleLayer::set(std::span<const Eigen::Vector2f> points) {
  points_.clear();
  for (const Eigen::Vector2f& p : points)
    if (p.allFinite()) points_.push_back(p);
}

void RecentObstacleLayer::apply(OccupancyGrid& grid) {
  // Decided on the grid as given, before any cell is marked here.
  cells_.clear();
  for (const Eigen::Vector2f& p : points_) {
    const Eigen::Vector2i c = grid.cell_of(p);
    if (!grid.in_bounds(c.x(), c.y())) continue;
    bool near_obstacle = false;
    for (int dy = -1; dy <= 1 && !near_obstacle; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int x = c.x() + dx, y = c.y() + dy;
        if (grid.in_bounds(x, y) && grid.logodds()[grid.index(x, y)] >= occupied_) {
          near_obstacle = true;
          break;
        }
      }
    if (!near_obstacle) cells_.push_back(grid.index(c.x(), c.y()));
  }
  std::sort(cells_.begin(), cells_.end());
  cells_.erase(std::unique(cells_.begin(), cells_.end()), cells_.end());
  for (const std::size_t i : cells_) grid.logodds()[i] = marked_;
}

void RecentObstacleLayer::shift(const Pose2& D) { shift_points(points_, D); }

// ---- TrailLayer -----------------------------------------------------------------------------

void TrailLayer::add(const Eigen::Vector2f& p) {
  if (p.allFinite() && (points_.empty() || (points_.back() - p).norm() >= spacing_m_)) points_.push_back(p);
}

void TrailLayer::apply(OccupancyGrid& grid) {
  // The cells under the trail are kept from one map to the next while the grid's geometry
  // stays (cost per map: the cells, not the trail's length); a new geometry or a shift
  // computes them again from every point.
  const Geometry g{grid.origin().x(), grid.origin().y(), grid.width(), grid.height(), grid.resolution()};
  if (!(g == geometry_)) {
    geometry_ = g;
    cells_.clear();
    marked_.assign(static_cast<std::size_t>(grid.width()) * static_cast<std::size_t>(grid.height()), 0);
    done_ = 0;
  }
  auto mark = [&](const Eigen::Vector2f& p, float r) {
    for_each_index_in_disc(grid, p, r, [&](std::size_t i) {
      if (marked_[i]) return;
      marked_[i] = 1;
      cells_.push_back(static_cast<std::uint32_t>(i));
    });
  };
  const float res = grid.resolution();
  const float body_cells_r = body_radius_m_ - 0.7072f * res;  // half a cell's diagonal
  if (done_ == 0 && !points_.empty()) mark(points_.front(), start_radius_m_ + res);
  for (; done_ < points_.size(); ++done_) mark(points_[done_], body_cells_r);
  float* l = grid.logodds().data();
  for (const std::uint32_t i : cells_)
    if (std::isnan(l[i])) l[i] = free_;
}

void TrailLayer::shift(const Pose2& D) {
  shift_points(points_, D);
  geometry_ = {};  // the cells are computed again
}

// ---- FootprintLayer -------------------------------------------------------------------------

FootprintLayer::FootprintLayer(float body_radius_m, float occupied_logodds, float free_logodds)
    : body_radius_m_(body_radius_m), occupied_(occupied_logodds), free_(free_logodds) {
  if (!(std::isfinite(body_radius_m) && body_radius_m > 0.0f))
    fail(ErrorCode::kInvalidArgument, "FootprintLayer: body_radius_m must be > 0, got " + std::to_string(body_radius_m));
  if (!std::isfinite(occupied_logodds) || !std::isfinite(free_logodds) || !(free_logodds < occupied_logodds))
    fail(ErrorCode::kInvalidArgument, "FootprintLayer: free_logodds must be below occupied_logodds, both finite");
}

template <class F>
void FootprintLayer::for_each_under(const OccupancyGrid& grid, const Eigen::Vector2f& xy, F&& fn) const {
  if (!xy.allFinite() || grid.width() <= 0 || grid.height() <= 0) return;
  const float r = body_radius_m_ - 0.7072f * grid.resolution();  // wholly under: less half a cell's diagonal
  if (!(r > 0.0f)) return;
  for_each_index_in_disc(grid, xy, r, fn);
}

std::size_t FootprintLayer::occupied_under(const OccupancyGrid& grid, const Eigen::Vector2f& xy) const {
  std::size_t n = 0;
  const float* l = grid.logodds().data();
  for_each_under(grid, xy, [&](std::size_t i) { n += l[i] >= occupied_; });
  return n;
}

void FootprintLayer::set(const Eigen::Vector2f& xy) {
  if (xy.allFinite()) at_ = xy;
}

void FootprintLayer::apply(OccupancyGrid& grid) {
  cleared_ = 0;
  if (!at_) return;
  float* l = grid.logodds().data();
  for_each_under(grid, *at_, [&](std::size_t i) {
    if (l[i] >= occupied_) {
      l[i] = free_;
      ++cleared_;
    }
  });
}

void FootprintLayer::shift(const Pose2& D) {
  if (at_) at_ = transform_point(D, *at_);
}

}  // namespace duet
