#pragma once
/// @file grid_view.hpp
/// A read-only view of a 2D log-odds grid in caller memory (an OccupancyGrid, a C API buffer)
/// and the three-state classification every planning kernel works on (exploration, frontier
/// search, inflation, path search, dynamic window).
///
/// Layout and frame: as OccupancyGrid (grid.hpp): row-major, row 0 at the lowest y, cell
/// (ix, iy) covers [origin.x + ix*res, origin.x + (ix+1)*res) x [origin.y + iy*res, ...).
/// A NaN log-odds is "unknown".
///
/// Thread safety: a GridView is a trivially copyable read-only view; any number of threads may
/// use it while nobody writes the underlying memory.
#include <duet/kernels/grid.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>

namespace duet {

struct GridView {
  std::span<const float> logodds;      ///< width*height log-odds, NaN = unknown
  int width = 0;                       ///< cells along x
  int height = 0;                      ///< cells along y
  float resolution_m = 0.05f;          ///< cell edge [m]
  Eigen::Vector2f origin{0.0f, 0.0f};  ///< world (x, y) of the lower-left corner of cell (0, 0) [m]

  GridView() = default;
  GridView(std::span<const float> l, int w, int h, float res, Eigen::Vector2f o)
      : logodds(l), width(w), height(h), resolution_m(res), origin(o) {}
  explicit GridView(const OccupancyGrid& g)
      : logodds(g.logodds()), width(g.width()), height(g.height()), resolution_m(g.resolution()),
        origin(g.origin()) {}

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
  /// World coordinates of the centre of cell (ix, iy).
  [[nodiscard]] Eigen::Vector2f cell_center(int ix, int iy) const noexcept {
    return {origin.x() + (static_cast<float>(ix) + 0.5f) * resolution_m,
            origin.y() + (static_cast<float>(iy) + 0.5f) * resolution_m};
  }
};

/// Throws duet::Error naming `what` if the view is inconsistent (kInvalidArgument): negative
/// sizes, logodds.size() != width*height, a resolution outside [kMinGridResolutionM,
/// kMaxGridResolutionM]; or its origin is beyond +-2 kMaxCoordinateM or not finite (kOutOfRange).
/// An empty grid (0 x 0) is valid.
void validate(const GridView& grid, const char* what = "grid");

/// Distance from each cell's centre to the nearest blocked cell [m], on the geometry of a grid
/// (produced by inflate() in inflation.hpp; read by the dynamic window and the planners).
/// A robot of radius r centred in cell i is collision-free iff clearance_m[i] > r.
/// Cells outside the grid have clearance 0 (blocked).
struct ClearanceView {
  std::span<const float> clearance_m;  ///< width*height distances [m]
  int width = 0;
  int height = 0;
  float resolution_m = 0.05f;          ///< cell edge [m]
  Eigen::Vector2f origin{0.0f, 0.0f};  ///< world (x, y) of the lower-left corner of cell (0, 0) [m]

  /// Clearance at world point (x, y): that of the containing cell, 0 outside the grid.
  [[nodiscard]] float at(float x, float y) const noexcept {
    const float fx = (x - origin.x()) / resolution_m, fy = (y - origin.y()) / resolution_m;
    if (!(fx >= 0.0f) || !(fy >= 0.0f) || !(fx < static_cast<float>(width)) || !(fy < static_cast<float>(height)))
      return 0.0f;
    return clearance_m[static_cast<std::size_t>(static_cast<int>(fy)) * static_cast<std::size_t>(width) +
                       static_cast<std::size_t>(static_cast<int>(fx))];
  }
};

/// Three states of a cell for planning.
enum class CellState : std::uint8_t {
  kFree = 0,      ///< log-odds <= free_logodds
  kUnknown = 1,   ///< never observed (NaN), or observed but between the thresholds
  kOccupied = 2,  ///< log-odds >= occupied_logodds
};

/// Thresholds of the classification, in log-odds (the defaults match OccupancyGrid::to_ros_trinary:
/// occupied at p >= 0.65, free at p <= 0.45, so one hit is occupied and one miss is free).
struct CellThresholds {
  float occupied_logodds = 0.6190392f;  ///< log(0.65/0.35): cells at or above are occupied
  float free_logodds = -0.2006707f;     ///< log(0.45/0.55): cells at or below are free
};
void validate(const CellThresholds& t);

[[nodiscard]] inline CellState classify(float logodds, const CellThresholds& t) noexcept {
  if (logodds >= t.occupied_logodds) return CellState::kOccupied;  // false for NaN
  if (logodds <= t.free_logodds) return CellState::kFree;          // false for NaN
  return CellState::kUnknown;
}

/// out[i] = classify(grid.logodds[i]) for every cell; out.size() must be grid.cell_count().
/// TBB-parallel over rows; the result does not depend on the thread count.
void classify_grid(const GridView& grid, const CellThresholds& t, std::span<CellState> out);

}  // namespace duet
