#pragma once
/// @file inflation.hpp
/// Obstacle inflation of a 2D log-odds grid by an exact Euclidean distance transform: the
/// clearance of every cell (distance to the nearest blocked cell) and the cells a round robot of
/// a given radius may occupy. Input of the global path search (path.hpp), the global frontier
/// search (frontier.hpp) and the dynamic window (through clearance()).
///
/// Semantics (decided here, the paper is silent):
///  - A cell is *blocked* if it is kOccupied; or observed but neither free nor occupied (finite
///    log-odds strictly between the two thresholds: its hits and misses disagree) when
///    uncertain_is_obstacle is set (the default); or never observed (NaN) when
///    unknown_is_obstacle is set. Why uncertain cells block by default: a wall face seen at a
///    grazing angle gets a hit from one scan and misses from the grazing rays of the next ones
///    (each ray to a farther point of the face crosses the cells of the nearer part), so its
///    cells hover around p = 0.5; treating them as free let a lab run plan a goal 3 cm from a
///    shelf's face and drive into it.
///  - clearance_m[i] is the exact Euclidean distance between the centre of cell i and the centre
///    of the nearest blocked cell, in metres: res * sqrt(dx^2 + dy^2) for integer cell offsets
///    (0 for a blocked cell, +inf when the grid has no blocked cell). The area outside the grid is
///    NOT blocked (the grid border is not a wall): a known-free corridor running off the edge of
///    the map stays traversable.
///  - state[i] is classify(): kUnknown covers both never-observed and uncertain cells.
///  - traversable[i] = 1 iff state[i] == kFree and clearance_m[i] > robot_radius_m (strictly). So
///    unknown cells are never traversable (whatever unknown_is_obstacle says), and with the default
///    unknown_is_obstacle = false the robot may drive right up to the edge of the known free space
///    (what frontier exploration needs: frontier cells border unknown space).
///
/// Frames and units: the grid's (see grid_view.hpp): row-major, row 0 at the lowest y, metres.
/// Thread safety: inflate() is reentrant; it runs TBB-parallel inside the caller's arena and its
/// output is bitwise identical for any thread count. An InflatedGrid is a plain value: concurrent
/// reads are safe, writes (inflate into it) need exclusive access.
#include <duet/kernels/grid_view.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace duet {

struct InflationSettings {
  CellThresholds thresholds;         ///< log-odds -> {free, unknown, occupied}
  float robot_radius_m = 0.20f;      ///< Kobuki 0.177 m + margin [m]; cells with clearance <= this are not traversable; >= 0
  bool unknown_is_obstacle = false;  ///< never-observed (NaN) cells block too (true) or not (false)
  bool uncertain_is_obstacle = true; ///< observed cells between the free and occupied thresholds block too (true) or not (false)
};
/// Throws duet::Error(kInvalidArgument) naming the field: robot_radius_m finite and >= 0,
/// thresholds as validate(CellThresholds).
void validate(const InflationSettings& s);

/// Output of inflate(): owns its buffers; reused across calls (no reallocation when the size is
/// unchanged). Geometry fields are copied from the input grid.
struct InflatedGrid {
  int width = 0;                       ///< cells along x
  int height = 0;                      ///< cells along y
  float resolution_m = 0.05f;          ///< cell edge [m]
  Eigen::Vector2f origin{0.0f, 0.0f};  ///< world (x, y) of the lower-left corner of cell (0, 0) [m]
  float robot_radius_m = 0.20f;        ///< the robot_radius_m used by inflate() [m]

  std::vector<CellState> state;           ///< classify() of each cell
  std::vector<float> clearance_m;         ///< exact Euclidean distance from the cell centre to the nearest blocked cell centre [m] (+inf if none)
  std::vector<std::uint8_t> traversable;  ///< 1 iff state == kFree and clearance_m > robot_radius_m

  /// View of clearance_m with this grid's geometry (valid while this object is alive and unchanged).
  [[nodiscard]] ClearanceView clearance() const noexcept {
    ClearanceView v;
    v.clearance_m = clearance_m;
    v.width = width;
    v.height = height;
    v.resolution_m = resolution_m;
    v.origin = origin;
    return v;
  }
  [[nodiscard]] std::size_t cell_count() const noexcept {
    return static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  }
  [[nodiscard]] std::size_t index(int ix, int iy) const noexcept {
    return static_cast<std::size_t>(iy) * static_cast<std::size_t>(width) + static_cast<std::size_t>(ix);
  }
  [[nodiscard]] bool in_bounds(int ix, int iy) const noexcept {
    return ix >= 0 && iy >= 0 && ix < width && iy < height;
  }
  /// Cell containing world point (x, y) (may be outside the grid; floor, not truncation).
  [[nodiscard]] Eigen::Vector2i cell_of(const Eigen::Vector2f& xy) const noexcept {
    return {static_cast<int>(std::floor((xy.x() - origin.x()) / resolution_m)),
            static_cast<int>(std::floor((xy.y() - origin.y()) / resolution_m))};
  }
  /// Cell containing (x, y), false if it is outside the grid (or not finite).
  [[nodiscard]] bool cell_of(const Eigen::Vector2f& xy, Eigen::Vector2i& cell) const noexcept {
    const float fx = std::floor((xy.x() - origin.x()) / resolution_m);
    const float fy = std::floor((xy.y() - origin.y()) / resolution_m);
    if (!(fx >= 0.0f) || !(fy >= 0.0f) || !(fx < static_cast<float>(width)) || !(fy < static_cast<float>(height)))
      return false;
    cell = {static_cast<int>(fx), static_cast<int>(fy)};
    return true;
  }
  /// World coordinates of the centre of cell (ix, iy).
  [[nodiscard]] Eigen::Vector2f cell_center(int ix, int iy) const noexcept {
    return {origin.x() + (static_cast<float>(ix) + 0.5f) * resolution_m,
            origin.y() + (static_cast<float>(iy) + 0.5f) * resolution_m};
  }
  [[nodiscard]] Eigen::Vector2f cell_center(std::size_t i) const noexcept {
    return cell_center(static_cast<int>(i % static_cast<std::size_t>(width)),
                       static_cast<int>(i / static_cast<std::size_t>(width)));
  }
};

/// Throws duet::Error(kInvalidArgument) naming `what` if g's buffers do not have width*height
/// entries, a size is negative, the resolution is not finite and > 0 or the origin not finite.
void validate(const InflatedGrid& g, const char* what = "InflatedGrid");

/// Classifies every cell (state), computes clearance_m by an exact Euclidean distance transform
/// (Felzenszwalb & Huttenlocher 2012, separable: a two-sweep 1D transform of every column -
/// TBB-parallel over blocks of columns, swept row by row so memory is read in order - then the
/// lower envelope of parabolas along every row, TBB-parallel over rows; integer arithmetic on
/// squared cell distances, so the result is exact and independent of the thread count) and
/// traversable. Throws duet::Error(kInvalidArgument) for an invalid grid or settings, and
/// kOutOfRange for grids of 2^31 cells or more. An empty (0 x 0) grid gives empty buffers.
void inflate(const GridView& grid, const InflationSettings& s, InflatedGrid& out);

}  // namespace duet
