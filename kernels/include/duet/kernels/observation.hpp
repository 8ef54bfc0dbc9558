#pragma once
/// @file observation.hpp
/// The ray-tracing observation model of the paper (§3.1, Fig. 5): each RGB-D sensor is a
/// horizontal sector (origin, radius = max range, centre angle = field of view) sampled by a fan
/// of rays; a ray stops at the first occupied cell, and the entropy (Eq. 5, entropy.hpp) of the
/// cells it crosses is the information it would gather. Procedure 1 sums it as its reward.
///
/// Two backends give the same results (ObservationBackend):
///  - kDda: a 2D Amanatides-Woo walk (walk_cells) over a packed per-cell array (entropy bits with
///    the occupied flag in the sign bit): the walk sums the entropy and stops at the first
///    occupied cell, in one pass.
///  - kEmbree: the occupied cells' boundary faces as vertical quads (z in [-1, 1], rays at z = 0),
///    one Embree instance per tile of tile_cells^2 cells so that update_grid rebuilds only the
///    tiles whose occupied cells changed; rays traced in packets of 8 (rtcIntersect8), then the
///    entropy summed by a walk without occupancy checks that stops at the hit cell.
///   The default is kDda: the entropy sum needs a walk over the crossed cells anyway, and that
///   walk finds the hit for free, so tracing the rays through a BVH first only adds work
///   (bench_observation.cpp, 256 poses x 2 sensors x 30 rays, 1 thread, medians: DDA 1.9-2.7x
///   faster than Embree on 400x400, 2000x2000 and the Willow map).
///
/// Frames and units: the map frame (grid_view.hpp), metres, radians; sensor sectors in the robot
/// frame (x forward, y left), paper Eq. (6). A ray's parameter t is the distance from its origin
/// [m] (directions are unit vectors).
///
/// Corner cases (documented, not hidden): the DDA walk is exact to ~1e-9 m (double set-up, 64-bit
/// fixed-point walk). Embree intersects float quads at world coordinates, so a ray passing within
/// ~2e-6 m + 2 ulp of the coordinates (~1e-5 m at 50 m from the origin) of an occupied cell's
/// corner may hit the other cell beside that corner, or slip past the corner: the two backends
/// may then differ in the hit flag, the range (by up to ~1e-5 m / |dir component|) and the last
/// cells. Measured: 0 of 15360 rays on 400x400 and Willow, 5 of 15360 on a 100 m x 100 m map.
///
/// Thread safety: walk_cells, sector_rays, paper_dual_sensors and validate are pure. An
/// ObservationModel may be used by any number of threads through its const members (cast,
/// observe, information_bits, grid, states, entropy) while no thread calls a non-const member
/// (set_grid, update_grid, assignment); it is not copyable (it owns an Embree device and scene).
#include <duet/kernels/grid_view.hpp>
#include <duet/kernels/motion_model.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <vector>

namespace duet {

/// The longest sensor range a SensorSector may have [m] (the profile's depth limit too): a
/// ray's walk is range / cell cells long, so the range bounds the work of every walk.
inline constexpr float kMaxSensorRangeM = 100.0f;
/// Work budget of one ObservationModel::observe() call: poses * sum over sensors of rays *
/// (2 max_range / resolution + 2) cell visits at most (~4 s on 2 cores; a decision's 60 rays on
/// a 5 cm grid walk 12k per pose).
inline constexpr double kMaxObservedCells = 1e9;

/// One sensor's horizontal fan, in the robot frame (paper §3.1: a sector of radius max range and
/// centre angle = the horizontal field of view; Eq. 6 for the extrinsics).
struct SensorSector {
  float x_m = 0.0f, y_m = 0.0f;        ///< sensor origin in the robot frame [m], within +-kMaxSensorRangeM
  float yaw_rad = 0.0f;                ///< optical axis yaw in the robot frame [rad] (Eq. 6)
  float fov_rad = 0.99483767f;         ///< horizontal field of view, 57 deg [rad], in (0, 2 pi]
  float min_range_m = 0.5f;            ///< cells nearer than this are not observed [m], >= 0
  float max_range_m = 5.0f;            ///< [m], in [min_range_m, kMaxSensorRangeM]
  int rays = 30;                       ///< rays in the fan, in [1, 100000]
};

/// The paper's robot (Eq. 6): sensor 1 at (-0.118, 0) yaw 0, sensor 2 at (-0.118, 0) yaw -90 deg
/// (facing right); Kinect 57 deg, 0.5-5 m (DESIGN.md §7). Throws if rays_per_sensor < 1.
std::vector<SensorSector> paper_dual_sensors(int rays_per_sensor = 30);

/// The robot heading [rad, in (-pi, pi]] that points one of `sensors`' optical axes along
/// `look_rad` (a frontier or a place to look at): of the headings look_rad - yaw_i, the one the
/// robot reaches from `from_rad` with the least turn (ties: the lower sensor index). With one
/// sensor facing forward this is look_rad; with the paper's two (front and right), a robot that
/// arrives with the place on its right keeps its heading instead of turning 90 degrees to it.
/// No sensors, or a non-finite angle: look_rad.
[[nodiscard]] float heading_to_look(float look_rad, float from_rad, std::span<const SensorSector> sensors);

/// The most cells one fan of every sensor walks on a grid of `resolution_m` cells [m] (clamped to
/// kMinGridResolutionM): the sum of rays * (2 max_range / resolution + 2) - the unit of the
/// observation and Procedure 1 work budgets.
[[nodiscard]] double fan_cells(std::span<const SensorSector> sensors, float resolution_m);

/// Throws duet::Error(kInvalidArgument) naming the field and its range.
void validate(const SensorSector& s);
/// Each sector, and the span must be non-empty.
void validate(std::span<const SensorSector> sensors);

/// Ray r of a fan (rays > 1) points at yaw + pose.theta - fov/2 + fov * r/(rays-1); a single ray
/// points along the axis. Origin = pose (x,y) + R(theta) * (x_m, y_m). Map frame; dirs are unit.
/// origins.size() and dirs.size() must both be s.rays (else duet::Error); s is validated.
void sector_rays(const Pose2& pose, const SensorSector& s, std::span<Eigen::Vector2f> origins,
                 std::span<Eigen::Vector2f> dirs);

/// Visit, in order, the grid cells crossed by origin + t*dir for t in [t0, t1] (dir unit; a 2D
/// Amanatides-Woo DDA on the geometry of `grid`, t in metres along the ray):
/// f(ix, iy, t_enter, t_exit) -> bool (false stops). The first cell is the one the ray is in just
/// after t0 (t_enter = t0), the last one has t_exit = t1; consecutive cells share a face, except
/// that a ray through a cell corner exactly steps diagonally (both axes at once).
/// t1 == t0 visits one cell with t_enter = t_exit = t0; t1 < t0 or any non-finite input visits
/// nothing. Cells outside the grid are visited too (ix/iy out of range) so callers can treat them
/// as unknown. Only the geometry of `grid` is read (origin, resolution), never its log-odds.
/// Header-only inline template: Procedure 1 uses it with its own per-cell logic.
/// Precision: set-up in double, the walk in 64-bit fixed point (~1e-12 m for t < 500 m), times
/// handed out as float: the cells are those of the exact segment except for rays passing within
/// ~1e-9 m of a cell corner. The cost is proportional to (t1 - t0) / resolution: bound t1.
namespace detail {

/// The state of the Amanatides-Woo walk behind walk_cells() (exposed so that the observation
/// model's hot loop can run the very same arithmetic without computing float times per cell).
/// Set-up in double: the start cell and the first crossing times carry no rounding of the world
/// coordinates (in float, a ray at y = 60 m would get its crossing times wrong by ~4e-6 m /
/// |dir.y|). The walk itself runs on 64-bit fixed-point times (units of 1/scale m): the
/// loop-carried chain "compare, select, add" is integer and exact. Times are clamped to a cap
/// > t1, so a crossing beyond t1 is never taken.
struct CellWalk {
  int ix = 0, iy = 0;             ///< current cell
  int sx = 0, sy = 0;             ///< steps along x / y (-1, 0, 1)
  std::int64_t mx = 0, my = 0;    ///< next x / y crossing times (fixed point)
  std::int64_t dx = 0, dy = 0;    ///< crossing period along x / y (fixed point)
  std::int64_t end = 0;           ///< t1 (fixed point)
  double inv_scale = 0.0;         ///< metres per fixed-point unit

  /// False if there is nothing to walk (t1 < t0, non-finite input, |start| >= 1e9 cells).
  bool init(const GridView& grid, const Eigen::Vector2f& origin, const Eigen::Vector2f& dir, float t0,
            float t1) noexcept {
    if (!(t1 >= t0) || !std::isfinite(t0) || !std::isfinite(t1) || !origin.allFinite() || !dir.allFinite()) return false;
    const double res = grid.resolution_m;
    const double px = (static_cast<double>(origin.x()) + static_cast<double>(t0) * dir.x() - grid.origin.x()) / res;
    const double py = (static_cast<double>(origin.y()) + static_cast<double>(t0) * dir.y() - grid.origin.y()) / res;
    if (!(std::fabs(px) < 1e9) || !(std::fabs(py) < 1e9)) return false;  // also NaN; keeps ix, iy in int range
    const double cap = std::max(std::fabs(static_cast<double>(t0)), std::fabs(static_cast<double>(t1))) + 1.0;
    // scale = 2^(61 - e2) with 4 cap < 2^e2, so every time below stays < 2^60 (exponent bits
    // read directly: frexp/ldexp are library calls, and this runs once per ray).
    const int e2 = static_cast<int>((std::bit_cast<std::uint64_t>(4.0 * cap) >> 52) & 0x7ff) - 1022;
    const double scale = std::bit_cast<double>(static_cast<std::uint64_t>(1023 + 61 - e2) << 52);
    inv_scale = std::bit_cast<double>(static_cast<std::uint64_t>(1023 - 61 + e2) << 52);  // 1 / scale, exact
    auto fixed = [&](double v) {
      const double x = std::min(v, cap) * scale;
      return static_cast<std::int64_t>(x >= 0.0 ? x + 0.5 : x - 0.5);
    };
    // The cell the ray is heading into: on a boundary with a negative direction, the lower cell.
    // floor / ceil without a libm call (baseline x86-64 has no roundsd): exact for |p| < 1e9.
    auto floor_i = [](double p) { const int i = static_cast<int>(p); return static_cast<double>(i) > p ? i - 1 : i; };
    auto ceil_i = [](double p) { const int i = static_cast<int>(p); return static_cast<double>(i) < p ? i + 1 : i; };
    auto axis = [&](double p, float d, int& i, int& st, std::int64_t& m, std::int64_t& del) {
      if (d > 0.0f) {
        i = floor_i(p);
        st = 1;
        const double td = res / d;
        del = fixed(td);
        m = fixed(t0 + (i + 1 - p) * td);
      } else if (d < 0.0f) {
        i = ceil_i(p) - 1;
        st = -1;
        const double td = -res / d;
        del = fixed(td);
        m = fixed(t0 + (p - i) * td);
      } else {
        i = floor_i(p);
        st = 0;
        del = fixed(cap);
        m = fixed(cap);
      }
    };
    axis(px, dir.x(), ix, sx, mx, dx);
    axis(py, dir.y(), iy, sy, my, dy);
    end = fixed(t1);
    return true;
  }
  /// Exit time of the current cell (fixed point); the walk ends after this cell if >= end.
  [[nodiscard]] std::int64_t next() const noexcept { return mx < my ? mx : my; }
  [[nodiscard]] float time(std::int64_t v) const noexcept { return static_cast<float>(static_cast<double>(v) * inv_scale); }
  /// Branch-free step (which axis comes next is a coin flip for the branch predictor); on an
  /// exact tie (the ray goes through a cell corner) both axes step: the two side cells are only
  /// touched. An axis with no motion has its time at the cap > t1, so it never steps.
  void step() noexcept { step(ix, iy, mx, my, sx, sy, dx, dy); }
  /// The same step on a walk state the caller keeps in locals (hot loops: registers, no spills).
  template <class I, class S>
  static void step(I& ix, I& iy, std::int64_t& mx, std::int64_t& my, S sx, S sy, std::int64_t dx, std::int64_t dy) noexcept {
    const bool bx = mx <= my, by = my <= mx;
    ix += bx ? sx : 0;
    iy += by ? sy : 0;
    mx += bx ? dx : 0;
    my += by ? dy : 0;
  }
};

/// The pieces of sector_rays(), shared by the observation model and Procedure 1 so that both
/// trace exactly the same rays. A fan's directions are computed once in the robot frame
/// (fan_directions) and turned per pose (turn: one sin/cos per pose, not per ray).
inline Eigen::Vector2f fan_direction(const SensorSector& s, int r) noexcept {
  const float a = s.rays > 1 ? s.yaw_rad - 0.5f * s.fov_rad + s.fov_rad * static_cast<float>(r) / static_cast<float>(s.rays - 1)
                             : s.yaw_rad;
  return Eigen::Vector2f(std::cos(a), std::sin(a));
}
inline std::vector<Eigen::Vector2f> fan_directions(const SensorSector& s) {
  std::vector<Eigen::Vector2f> dirs(static_cast<std::size_t>(s.rays));
  for (int r = 0; r < s.rays; ++r) dirs[static_cast<std::size_t>(r)] = fan_direction(s, r);
  return dirs;
}
/// The sensor's origin at a pose whose heading has cosine c and sine sn.
inline Eigen::Vector2f fan_origin(const Pose2& pose, const SensorSector& s, float c, float sn) noexcept {
  return Eigen::Vector2f(pose.x + c * s.x_m - sn * s.y_m, pose.y + sn * s.x_m + c * s.y_m);
}
/// A robot-frame direction turned by a heading of cosine c and sine sn.
inline Eigen::Vector2f turn(float c, float sn, const Eigen::Vector2f& f) noexcept {
  return Eigen::Vector2f(c * f.x() - sn * f.y(), sn * f.x() + c * f.y());
}

}  // namespace detail

template <class F>
inline void walk_cells(const GridView& grid, Eigen::Vector2f origin, Eigen::Vector2f dir, float t0, float t1,
                       F&& f) {
  detail::CellWalk w;
  if (!w.init(grid, origin, dir, t0, t1)) return;
  float t = t0;
  for (;;) {
    const std::int64_t tn = w.next();
    const bool last = tn >= w.end;
    const float te = last ? t1 : w.time(tn);
    if (!f(w.ix, w.iy, t, te)) return;
    if (last) return;
    t = te;
    w.step();
  }
}

enum class ObservationBackend : std::uint8_t {
  kEmbree = 0,  ///< Embree BVH over the occupied cells' faces + an entropy walk up to the hit
  kDda = 1,     ///< one 2D DDA walk that sums entropy and stops at the first occupied cell
};

struct ObservationSettings {
  CellThresholds thresholds;                        ///< what counts as occupied (stops a ray)
  /// kDda by default: faster on every benchmark (bench_observation.cpp), see the file comment.
  ObservationBackend backend = ObservationBackend::kDda;
  int tile_cells = 64;                              ///< Embree: scene tile edge [cells], in [1, 65536]
};
void validate(const ObservationSettings& s);

/// cast(): range to the first occupied cell's boundary [m] (hit), or t1 (no hit).
struct RayHit {
  float range_m;
  bool hit;
};

/// observe(): one ray of one sensor at one pose.
struct RayObservation {
  float entropy_bits;  ///< sum of entropy_bits of the cells crossed from min_range to the hit (hit cell included) or max_range
  float range_m;       ///< where the ray stopped [m] (distance from the sensor origin)
  bool hit;            ///< stopped at an occupied cell
  std::int32_t cells;  ///< number of cells summed
};

/// The observation model on one grid: a copy of its log-odds, the per-cell states and entropy,
/// a packed walk array, and (kEmbree) an Embree device and scene. Not copyable; movable (a
/// moved-from model throws duet::Error from every member but destruction and assignment).
class ObservationModel {
 public:
  /// Validates the settings (duet::Error); starts with an empty (0 x 0) grid. kEmbree creates the
  /// Embree device here (Embree errors become duet::Error(kInternal)).
  explicit ObservationModel(const ObservationSettings& s = {});
  ~ObservationModel();
  ObservationModel(ObservationModel&&) noexcept;
  ObservationModel& operator=(ObservationModel&&) noexcept;
  ObservationModel(const ObservationModel&) = delete;
  ObservationModel& operator=(const ObservationModel&) = delete;

  [[nodiscard]] const ObservationSettings& settings() const;

  /// Full rebuild (copies the log-odds: the model owns its data). Validates the view.
  /// TBB-parallel (classification, entropy, Embree tiles).
  void set_grid(const GridView& grid);
  /// Incremental: same geometry as the last set_grid; re-classifies and re-entropies every cell,
  /// and rebuilds only the Embree tiles whose occupied cells changed; returns the number of tiles
  /// rebuilt (always 0 for kDda). A different geometry (size/origin/resolution) falls back to
  /// set_grid and returns the number of non-empty tiles built (kEmbree) / 0 (kDda).
  std::size_t update_grid(const GridView& grid);

  /// Geometry + the model's copy of the log-odds (valid until the next set/update_grid).
  [[nodiscard]] const GridView& grid() const;
  [[nodiscard]] std::span<const CellState> states() const;
  /// Per-cell entropy_bits of the copy [bits].
  [[nodiscard]] std::span<const float> entropy() const;
  /// Embree: tiles along x and y (0 for kDda), for tests and diagnostics.
  [[nodiscard]] int tiles_x() const;
  [[nodiscard]] int tiles_y() const;

  /// First occupied cell along each ray origin + t*dir, t in [t0, t1] (0 <= t0 <= t1, finite;
  /// dirs unit within 1e-3, origins within kMaxCoordinateM; out.size() == origins.size() == dirs.size(): else
  /// duet::Error). A ray starting inside an occupied cell hits at t0. Cells outside the grid
  /// never stop a ray. Embree: packets of 8 (rtcIntersect8); TBB-parallel over packets; the
  /// result does not depend on the thread count.
  void cast(std::span<const Eigen::Vector2f> origins, std::span<const Eigen::Vector2f> dirs, float t0, float t1,
            std::span<RayHit> out) const;
  /// Every sensor's fan at every pose: out[(p * total_rays) + ray] with rays ordered sensor by
  /// sensor (total_rays = sum of sensors[s].rays), each over [min_range_m, max_range_m] of its
  /// sensor. Entropy summed along each ray up to its hit, the hit cell included (cells outside
  /// the grid = unknown = 1 bit each). A known obstacle in a cell the ray leaves at or before
  /// min_range_m blocks the ray: the sensor measures nothing (entropy 0, cells 0, hit, range_m =
  /// the entry distance of that cell), as a Kinect returns no depth nearer than 0.5 m.
  /// Validates the sensors, out.size(), the work budget (kMaxObservedCells) and that poses are
  /// finite (kInvalidArgument) and within kMaxCoordinateM of the origin (kOutOfRange; grid.hpp).
  /// TBB-parallel over poses x
  /// sensors; independent of the thread count.
  void observe(std::span<const Pose2> poses, std::span<const SensorSector> sensors,
               std::span<RayObservation> out) const;
  /// Sum over all rays of all sensors at `pose` of RayObservation::entropy_bits [bits] (the
  /// paper's ray-tracing reward; a cell crossed by k rays counts k times, as in the per-ray
  /// model). Summed in ray order in double: independent of the thread count. Allocates.
  [[nodiscard]] float information_bits(const Pose2& pose, std::span<const SensorSector> sensors) const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace duet
