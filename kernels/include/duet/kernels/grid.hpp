#pragma once
/// @file grid.hpp
/// 2D log-odds occupancy grid built from the segmented cloud (paper §2.2, Fig. 4: "the grid map
/// is constructed with the (x, y) coordinates from the obstacle portion of the point cloud").
/// Frame: the grid lies in the x-y plane of the map frame (z up). Cell (ix, iy) covers
/// [origin.x + ix*res, origin.x + (ix+1)*res) x [origin.y + iy*res, ...); storage is row-major
/// with row 0 at the lowest y (ROS map_server convention before its PGM flip).
/// A cell never observed holds NaN ("unknown"); observed cells hold clamped log-odds.
///
/// Thread safety: OccupancyGrid is a value type; const members may be called concurrently,
/// update_grid() needs exclusive access to the grid and the workspace.
#include <duet/kernels/motion_model.hpp>
#include <duet/kernels/segmentation.hpp>
#include <duet/kernels/types.hpp>

#include <cstdint>
#include <cmath>
#include <limits>
#include <span>
#include <vector>

namespace duet {

/// The map frame's limits (a contract: checked where data enters). A cell is 1 mm to 100 m wide;
/// coordinates - points, poses, grid bounds - lie within +-10 km of the origin, where a float
/// still resolves 1 mm (its spacing at 1e4 is 0.98 mm), far beyond any building. A grid with
/// another resolution or bounds beyond them is refused (kInvalidArgument / kOutOfRange); map
/// points beyond them are dropped like points out of range.
inline constexpr float kMinGridResolutionM = 1e-3f;
inline constexpr float kMaxGridResolutionM = 100.0f;
inline constexpr float kMaxCoordinateM = 1e4f;

/// Whether |x| and |y| are within kMaxCoordinateM (false for NaN).
[[nodiscard]] inline bool within_map_limits(const Eigen::Vector2f& p) noexcept {
  return std::fabs(p.x()) <= kMaxCoordinateM && std::fabs(p.y()) <= kMaxCoordinateM;
}

class OccupancyGrid {
 public:
  static constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();

  /// resolution_m in [kMinGridResolutionM, kMaxGridResolutionM].
  explicit OccupancyGrid(float resolution_m = 0.05f);
  /// An all-unknown grid of width x height cells whose cell (0,0) starts at origin [m].
  OccupancyGrid(float resolution_m, Eigen::Vector2f origin, int width, int height);

  [[nodiscard]] float resolution() const noexcept { return res_; }
  [[nodiscard]] Eigen::Vector2f origin() const noexcept { return origin_; }
  [[nodiscard]] int width() const noexcept { return w_; }
  [[nodiscard]] int height() const noexcept { return h_; }
  [[nodiscard]] std::size_t cell_count() const noexcept { return cells_.size(); }
  [[nodiscard]] std::span<const float> logodds() const noexcept { return cells_; }
  [[nodiscard]] std::span<float> logodds() noexcept { return cells_; }
  [[nodiscard]] float at(int ix, int iy) const { return cells_[index(ix, iy)]; }
  [[nodiscard]] std::size_t index(int ix, int iy) const noexcept {
    return static_cast<std::size_t>(iy) * static_cast<std::size_t>(w_) + static_cast<std::size_t>(ix);
  }
  [[nodiscard]] bool in_bounds(int ix, int iy) const noexcept {
    return ix >= 0 && iy >= 0 && ix < w_ && iy < h_;
  }
  /// Cell containing world point (x, y) (may be outside the grid).
  [[nodiscard]] Eigen::Vector2i cell_of(const Eigen::Vector2f& xy) const noexcept;
  /// World coordinates of the centre of cell (ix, iy).
  [[nodiscard]] Eigen::Vector2f cell_center(int ix, int iy) const noexcept;

  /// Grows (never shrinks) so that [lo, hi] plus margin_cells is inside; existing cells keep
  /// their world position. Throws duet::Error(kOutOfRange) if the grid would exceed
  /// max_cells (default 2^28 cells = 1 GiB) or the coordinates are beyond kMaxCoordinateM.
  void ensure_contains(const Eigen::Vector2f& lo, const Eigen::Vector2f& hi, int margin_cells,
                       std::size_t max_cells = std::size_t{1} << 28);

  /// Probability of occupancy per cell (1 - 1/(1+exp(l))), -1 for unknown.
  void to_probabilities(std::span<float> out) const;
  /// ROS nav_msgs/OccupancyGrid trinary values: 100 occupied (p >= occupied_threshold),
  /// 0 free (p <= free_threshold), -1 unknown or in between. With the defaults one hit
  /// (p = 0.70) is occupied, one miss (p = 0.40) free, a hit and a miss (p = 0.61) unknown.
  void to_ros_trinary(std::span<std::int8_t> out, float occupied_threshold = 0.65f,
                      float free_threshold = 0.45f) const;
  /// Number of cells observed at least once.
  [[nodiscard]] std::size_t known_cells() const noexcept;

 private:
  float res_;
  Eigen::Vector2f origin_{0.0f, 0.0f};
  int w_ = 0, h_ = 0;
  std::vector<float> cells_;
};

struct GridUpdateSettings {
  float hit_logodds = 0.85f;    ///< added to a cell hit by an obstacle point (p = 0.7)
  float miss_logodds = -0.4f;   ///< added to a cell seen free (p = 0.4)
  float min_logodds = -2.0f;    ///< clamp (p = 0.12), as OctoMap
  float max_logodds = 3.5f;     ///< clamp (p = 0.97), as OctoMap
  bool clear_along_rays = true; ///< free space is also cleared along each ray (DESIGN.md §7)
  /// Only rays to floor points and to obstacle points with z <= this clear free space [m, in
  /// the points' frame]; +inf = every ray (the default). A 2D ray to a high point (a wall above
  /// a bench) passes OVER lower obstacles in 3D and would wrongly clear them; a ray whose end is
  /// at most this high cannot pass over an obstacle taller than this and the sensor. Not NaN.
  float clear_max_height_m = std::numeric_limits<float>::infinity();
  float max_ray_length_m = 8.0f;///< hits farther than this from the sensor are ignored [m]
  /// Rays do not lower a cell whose log-odds is above keep_occupied_logodds and whose centre lies
  /// within this distance of the sensor [m, 2D], >= 0; 0 = off (the default). A thin obstacle
  /// nearer than the sensor's minimum depth returns no point to keep it, while the rays passing
  /// beside it cross its cell (a 2D cell is cleared when a ray crosses any part of it): without
  /// this a robot erases a post as it passes it. Hits and floor points in the cell still count.
  float keep_occupied_within_m = 0.0f;
  /// The log-odds a cell must exceed to be kept (keep_occupied_within_m), finite; 0 = every cell
  /// more likely occupied than free. Higher keeps only obstacles seen several times, not the
  /// single noisy hits beside a wall that the rays along it would clear.
  float keep_occupied_logodds = 0.0f;
  int grow_margin_cells = 40;   ///< growth step around new data [cells]
};

struct GridUpdateWorkspace {
  std::vector<std::uint64_t> hit_cells, free_cells, tmp;
  std::vector<std::uint8_t> mask;
};

/// One scan from one sensor at sensor_xy [m]: obstacle points mark their cells occupied,
/// floor points mark their cells free, and (clear_along_rays) every cell crossed by the 2D ray
/// from the sensor to the cell of each floor point and of each obstacle point no higher than
/// clear_max_height_m is free. Each cell gets at most
/// one update per call: hit if any obstacle point falls in it, else miss (OctoMap's
/// computeUpdate semantics); rays run to the centre of each distinct end cell.
/// With keep_occupied_within_m > 0, a cell only a ray cleared keeps its log-odds when it is above
/// keep_occupied_logodds and the cell's centre lies within that distance of sensor_xy.
/// kIgnored and non-finite points are skipped. labels has points.size() entries.
void update_grid(OccupancyGrid& grid, const Eigen::Vector2f& sensor_xy, PointsView points,
                 std::span<const PointLabel> labels, const GridUpdateSettings& settings,
                 GridUpdateWorkspace& workspace);

void validate(const GridUpdateSettings& settings);

/// The box [lo, hi] [m] covering the grid's observed (non-NaN) cells; false (lo, hi untouched)
/// when no cell is observed.
[[nodiscard]] bool observed_extent(const OccupancyGrid& grid, Eigen::Vector2f& lo, Eigen::Vector2f& hi);

/// Adds the log-odds of `src`, placed in dst's frame by T (a point p of src's frame lies at T p),
/// to `dst` (the same resolution): every dst cell whose centre, taken back by T^-1, falls in an
/// observed src cell (nearest cell) gets that cell's log-odds added - an unknown dst cell counts
/// as 0 - and the sum is clamped to [min_logodds, max_logodds]. dst grows (never shrinks, origin
/// alignment kept) to hold src's observed cells. This is how a grid is rebuilt from submaps
/// after their poses move (loop closure): the sum of the submaps' log-odds is the log-odds of
/// their observations combined (clamping aside). src with no observed cell: nothing happens.
/// Throws duet::Error(kInvalidArgument) for different resolutions, a non-finite T or
/// min_logodds > max_logodds (dst unchanged).
void accumulate_grid(OccupancyGrid& dst, const OccupancyGrid& src, const Pose2& T, float min_logodds, float max_logodds);


}  // namespace duet
