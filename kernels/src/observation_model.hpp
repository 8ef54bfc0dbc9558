#pragma once
// Internal: ObservationModel::Impl, shared by observation.cpp (sensors, grid ingestion, the public
// methods) and observation_embree.cpp (the Embree tile scenes and tracing). The DDA walks, called
// per ray by ObservationModel::observe/cast, are defined in the class here (inline).
#include <duet/kernels/observation.hpp>

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

namespace duet::detail::observation {

// Packed per-cell word: bit 31 = occupied, bits 0-30 = entropy in fixed point, 2^30 = 1 bit
// (entropy is in [0, 1]; quantisation 2^-31 bit). Summing integers along a ray makes the sum exact
// and order-free (both backends give bitwise equal sums over the same cells) and keeps the walk's
// loop-carried chain on 1-cycle integer adds.
constexpr std::uint32_t kOccupiedBit = 0x80000000u;
constexpr double kFixedOne = 1073741824.0;  // 2^30
constexpr std::uint32_t kUnknownWord = 1u << 30;  // a cell outside the grid is unknown: 1 bit

inline std::uint32_t word_entropy(std::uint32_t w) noexcept { return w & ~kOccupiedBit; }
inline std::uint32_t fixed_entropy(float e) noexcept {
  return static_cast<std::uint32_t>(std::lround(static_cast<double>(std::clamp(e, 0.0f, 1.0f)) * kFixedOne));
}
inline float bits_of(std::uint64_t sum) noexcept { return static_cast<float>(static_cast<double>(sum) / kFixedOne); }

}  // namespace duet::detail::observation

namespace duet {

// The packed-word helpers, unqualified in Impl below and in observation.cpp / observation_embree.cpp.
using detail::observation::bits_of;
using detail::observation::fixed_entropy;
using detail::observation::kOccupiedBit;
using detail::observation::kUnknownWord;
using detail::observation::word_entropy;

struct ObservationModel::Impl {
  ObservationSettings settings;
  std::vector<float> logodds;
  GridView view;
  std::vector<CellState> states;
  std::vector<float> entropy;
  /// Per cell: fixed_entropy(entropy_bits) | kOccupiedBit if occupied (see kOccupiedBit), in
  /// 4 x 4-cell blocks of one 64-byte cache line each (block rows of blocks_x blocks), so that a
  /// ray's steps along y stay in the same line (see packed_index). Padding words are never read.
  std::vector<std::uint32_t> packed;
  std::size_t blocks_x = 0;

  [[nodiscard]] std::size_t packed_index(unsigned ix, unsigned iy) const noexcept {
    return (((static_cast<std::size_t>(iy >> 2) * blocks_x) + (ix >> 2)) << 4) | ((iy & 3u) << 2) | (ix & 3u);
  }

  // Embree (kEmbree only).
  struct Tile {
    RTCScene scene = nullptr;
    RTCGeometry instance = nullptr;
    /// Per quad: (cell index << 2) | face, face 0: -x, 1: +x, 2: -y, 3: +y (outward normal).
    std::vector<std::uint32_t> quads;
  };
  RTCDevice device = nullptr;
  RTCScene top = nullptr;
  std::vector<Tile> tiles;
  int tiles_x = 0, tiles_y = 0;
  std::mutex error_mutex;
  std::string error_message;

  explicit Impl(const ObservationSettings& s) : settings(s) {}
  ~Impl() {
    release_tiles();
    if (top) rtcReleaseScene(top);
    if (device) rtcReleaseDevice(device);
  }

  // ---- per-cell data ----
  [[nodiscard]] std::uint32_t word(int ix, int iy) const noexcept {
    if (static_cast<unsigned>(ix) < static_cast<unsigned>(view.width) &&
        static_cast<unsigned>(iy) < static_cast<unsigned>(view.height))
      return packed[packed_index(static_cast<unsigned>(ix), static_cast<unsigned>(iy))];
    return kUnknownWord;
  }
  [[nodiscard]] bool occupied(int ix, int iy) const noexcept { return (word(ix, iy) & kOccupiedBit) != 0; }

  // ---- Embree (observation_embree.cpp) ----
  static void on_error(void* user, RTCError code, const char* str);
  void check(const char* what);
  void init_embree();
  void release_tile(std::size_t t);
  void release_tiles();

  /// Builds tile t's scene (not attached): the faces of its occupied cells whose neighbour (in
  /// this or another tile, or outside the grid) is not occupied. Safe to run for different tiles
  /// in parallel (each touches only its own scene and Tile).
  void build_tile_scene(std::size_t t);

  /// Rebuilds the listed tiles (parallel scene builds, serial attach) and commits the top scene.
  void rebuild_tiles(const std::vector<std::size_t>& list);

  // ---- grid ingestion (observation.cpp) ----
  [[nodiscard]] bool same_geometry(const GridView& g) const noexcept {
    return g.width == view.width && g.height == view.height && g.resolution_m == view.resolution_m &&
           g.origin == view.origin;
  }

  /// Copies the log-odds and recomputes states, entropy and the packed words. If dirty != nullptr
  /// (same geometry), marks every tile whose faces may change: the tile of each cell whose
  /// occupancy changed and the tiles of its 4 neighbours.
  void ingest(const GridView& g, std::atomic<std::uint8_t>* dirty);
  void full_rebuild(const GridView& g);
  std::size_t incremental(const GridView& g);

  // ---- DDA tracing (inline here: called per ray) ----
  /// DDA: the walk sums entropy and stops at the first occupied cell. The same arithmetic as
  /// walk_cells (detail::CellWalk), with the sum in registers and the hit time computed only once.
  /// A known obstacle in a cell the ray leaves at or before t_min (the sensor's min range) blocks
  /// the ray: the sensor measures nothing there (a Kinect returns no depth below 0.5 m). Returns
  /// the entry distance of that cell [m], or -1 when the ray is not blocked.
  [[nodiscard]] float blocked_before(const Eigen::Vector2f& o, const Eigen::Vector2f& d, float t_min) const noexcept {
    if (!(t_min > 0.0f)) return -1.0f;
    detail::CellWalk w;
    if (!w.init(view, o, d, 0.0f, t_min)) return -1.0f;
    const std::uint32_t* const cells = packed.data();
    const unsigned width = static_cast<unsigned>(view.width), height = static_cast<unsigned>(view.height);
    std::int64_t entered = -1;
    for (;;) {
      const std::int64_t tn = w.next();
      if (tn > w.end) return -1.0f;  // this cell reaches beyond t_min: it is observed, not before
      const bool inside = static_cast<unsigned>(w.ix) < width && static_cast<unsigned>(w.iy) < height;
      if (inside && (cells[packed_index(static_cast<unsigned>(w.ix), static_cast<unsigned>(w.iy))] & kOccupiedBit))
        return entered < 0 ? 0.0f : w.time(entered);
      entered = tn;
      w.step();
    }
  }

  /// Grids whose packed words exceed this are walked with software prefetching (prefetch_ray):
  /// beyond the last-level private cache the walk waits for memory, within it prefetching only
  /// costs instructions.
  static constexpr std::size_t kPrefetchBytes = std::size_t{4} << 20;

  /// Prefetches the cache lines (4 x 4-cell blocks) along origin + t*dir for t in [0, t1], one
  /// every 3 cells of travel, so that the walk finds them in flight (memory-level parallelism
  /// that the walk's own loads, a few cells ahead at most, do not have). A hint only.
  void prefetch_ray(const Eigen::Vector2f& o, const Eigen::Vector2f& d, float t1) const noexcept {
    const float inv = 1.0f / view.resolution_m;
    const float px = (o.x() - view.origin.x()) * inv, py = (o.y() - view.origin.y()) * inv;
    const float ux = d.x() * 3.0f, uy = d.y() * 3.0f;
    const int n = static_cast<int>(t1 * inv / 3.0f) + 1;
    const std::uint32_t* const cells = packed.data();
    const auto w = static_cast<float>(view.width), h = static_cast<float>(view.height);
    for (int k = 0; k <= n; ++k) {
      const float x = px + ux * static_cast<float>(k), y = py + uy * static_cast<float>(k);
      if (!(x >= 0.0f && y >= 0.0f && x < w && y < h)) continue;
      __builtin_prefetch(cells + packed_index(static_cast<unsigned>(x), static_cast<unsigned>(y)));
    }
  }

  /// observe_dda() with the min-range rule folded into the same walk: the walk starts at the
  /// sensor (t = 0); a known obstacle in a cell left at or before t0 blocks the ray (entropy 0,
  /// cells 0, hit at that cell's entry); the cells from t0 on are summed as observe_dda() does.
  [[nodiscard]] RayObservation observe_dda_from_sensor(const Eigen::Vector2f& o, const Eigen::Vector2f& d, float t0,
                                                       float t1) const noexcept {
    if (!(t0 > 0.0f)) return observe_dda(o, d, t0, t1);
    RayObservation r{0.0f, t1, false, 0};
    detail::CellWalk w;
    if (!w.init(view, o, d, 0.0f, t1)) return r;
    const auto t_min = static_cast<std::int64_t>(static_cast<double>(t0) / w.inv_scale + 0.5);
    // The walk's state in locals (so that the loop does not spill it); same arithmetic as
    // CellWalk::step. (A branch-free, mask-based step measured slower here: the x/y pattern of
    // a ray is regular enough for the branch predictor, and a predicted branch cuts the chain.)
    const std::uint32_t* const cells = packed.data();
    const std::uint64_t width = static_cast<unsigned>(view.width), height = static_cast<unsigned>(view.height);
    const std::int64_t sx = w.sx, sy = w.sy, dx = w.dx, dy = w.dy, end = w.end;
    std::int64_t ix = w.ix, iy = w.iy, mx = w.mx, my = w.my;
    std::int64_t entered = -1;
    for (;;) {  // cells before the min range: only a known obstacle matters
      const std::int64_t tn = mx < my ? mx : my;  // exit time of this cell
      if (tn > t_min || tn >= end) break;         // this cell reaches beyond t0: it is observed
      const bool inside = static_cast<std::uint64_t>(ix) < width && static_cast<std::uint64_t>(iy) < height;
      if (inside && (cells[packed_index(static_cast<unsigned>(ix), static_cast<unsigned>(iy))] & kOccupiedBit))
        return RayObservation{0.0f, entered < 0 ? 0.0f : w.time(entered), true, 0};
      entered = tn;
      detail::CellWalk::step(ix, iy, mx, my, sx, sy, dx, dy);
    }
    w.ix = static_cast<int>(ix);
    w.iy = static_cast<int>(iy);
    w.mx = mx;
    w.my = my;
    return sum_walk(w, t0, t1);
  }

  /// Sums the entropy from the walk's current cell (entered at t0) to the hit or the walk's end.
  /// While the walk is inside the grid it runs without bounds checks: the time it leaves the grid
  /// is known up front (the crossing that takes ix or iy outside, exact in the walk's integers),
  /// so one end test covers both. The grid is convex: a walk that leaves it never returns, and the
  /// cells outside (unknown, 1 bit, never a hit) are counted by the checked loop after it. The
  /// entry time of the hit cell is not carried along either: it is the later of the last x and y
  /// crossings, max(mx - dx, my - dy), and at most the first cell's for the first cell (-> t0).
  /// Fewer live values, so the loop keeps its sum in a register (it was spilled before).
  [[nodiscard]] RayObservation sum_walk(const detail::CellWalk& w, float t0, float t1) const noexcept {
    RayObservation r{0.0f, t1, false, 0};
    std::uint64_t sum = 0;
    std::int32_t n = 0;
    const std::uint32_t* const cells = packed.data();
    const std::int64_t width = view.width, height = view.height;
    const std::int64_t sx = w.sx, sy = w.sy, dx = w.dx, dy = w.dy, end = w.end;
    std::int64_t ix = w.ix, iy = w.iy, mx = w.mx, my = w.my;
    const std::int64_t first_entry = std::max(mx - dx, my - dy);  // <= the fixed-point t0
    auto hit_at = [&](std::int64_t x_cross, std::int64_t y_cross) {
      const std::int64_t entry = std::max(x_cross - dx, y_cross - dy);
      r.hit = true;
      r.range_m = entry <= first_entry ? t0 : w.time(entry);
    };
    if (static_cast<std::uint64_t>(ix) < static_cast<std::uint64_t>(width) &&
        static_cast<std::uint64_t>(iy) < static_cast<std::uint64_t>(height)) {
      // Time of the crossing that leaves the grid along each axis (k-th crossing at m + (k-1) d),
      // capped at end (an overflowing product is beyond end too).
      auto leave = [end](std::int64_t m, std::int64_t d, std::int64_t k) -> std::int64_t {
        std::int64_t prod = 0;
        if (m >= end || __builtin_mul_overflow(k - 1, d, &prod) || prod >= end - m) return end;
        return m + prod;
      };
      std::int64_t t_out = end;
      if (sx != 0) t_out = std::min(t_out, leave(mx, dx, sx > 0 ? width - ix : ix + 1));
      if (sy != 0) t_out = std::min(t_out, leave(my, dy, sy > 0 ? height - iy : iy + 1));
      for (;;) {  // inside the grid: no bounds checks
        const std::uint32_t wd = cells[packed_index(static_cast<unsigned>(ix), static_cast<unsigned>(iy))];
        sum += word_entropy(wd);
        ++n;
        if (wd & kOccupiedBit) {
          hit_at(mx, my);
          r.entropy_bits = bits_of(sum);
          r.cells = n;
          return r;
        }
        const std::int64_t tn = mx < my ? mx : my;  // exit time of this cell
        if (tn >= t_out) break;
        detail::CellWalk::step(ix, iy, mx, my, sx, sy, dx, dy);  // both on a tie
      }
      if (t_out >= end) {  // the walk ended inside the grid
        r.entropy_bits = bits_of(sum);
        r.cells = n;
        return r;
      }
      detail::CellWalk::step(ix, iy, mx, my, sx, sy, dx, dy);  // step out of the grid
    }
    for (;;) {  // outside the grid (a walk that starts outside may enter it): checked
      const bool inside = static_cast<std::uint64_t>(ix) < static_cast<std::uint64_t>(width) &&
                          static_cast<std::uint64_t>(iy) < static_cast<std::uint64_t>(height);
      const std::uint32_t wd =
          inside ? cells[packed_index(static_cast<unsigned>(ix), static_cast<unsigned>(iy))] : kUnknownWord;
      sum += word_entropy(wd);
      ++n;
      if (wd & kOccupiedBit) {
        hit_at(mx, my);
        break;
      }
      const std::int64_t tn = mx < my ? mx : my;  // exit time of this cell
      if (tn >= end) break;
      detail::CellWalk::step(ix, iy, mx, my, sx, sy, dx, dy);
    }
    r.entropy_bits = bits_of(sum);
    r.cells = n;
    return r;
  }

  [[nodiscard]] RayObservation observe_dda(const Eigen::Vector2f& o, const Eigen::Vector2f& d, float t0, float t1) const noexcept {
    detail::CellWalk w;
    if (!w.init(view, o, d, t0, t1)) return RayObservation{0.0f, t1, false, 0};
    return sum_walk(w, t0, t1);
  }


  [[nodiscard]] RayHit cast_dda(const Eigen::Vector2f& o, const Eigen::Vector2f& d, float t0, float t1) const noexcept {
    RayHit r{t1, false};
    walk_cells(view, o, d, t0, t1, [&](int ix, int iy, float te, float) {
      if (occupied(ix, iy)) {
        r.hit = true;
        r.range_m = te;
        return false;
      }
      return true;
    });
    return r;
  }

  // ---- Embree tracing (observation_embree.cpp) ----
  /// The cell a ray is in just after t0 (the first cell of its walk).
  [[nodiscard]] Eigen::Vector2i first_cell(const Eigen::Vector2f& o, const Eigen::Vector2f& d, float t0, float t1) const noexcept;

  /// Embree: up to 8 rays; hit[k] = range, cell[k] = hit cell index or -1 (no hit).
  /// A ray starting in an occupied cell hits at t0 without tracing; a hit on a face the ray leaves
  /// (it started on that face) is skipped by re-tracing just past it.
  void trace8(const Eigen::Vector2f* o, const Eigen::Vector2f* d, int count, float t0, float t1, float* range,
              std::int64_t* cell) const;
  /// The distance along o + t d to the cell face `code` (cell << 2 | side) Embree hit, computed
  /// from the face itself (the same bits with every Embree kernel); `fallback` for a degenerate
  /// direction.
  [[nodiscard]] float face_distance(std::uint32_t code, const Eigen::Vector2f& o, const Eigen::Vector2f& d,
                                    float fallback) const noexcept;

  /// Embree: entropy summed by a walk without occupancy checks up to the hit cell (included).
  /// If the walk misses the hit cell (a ray through a cell corner), it stops at the first cell
  /// entered after the hit distance (+ 1e-4 m).
  [[nodiscard]] RayObservation sum_to(const Eigen::Vector2f& o, const Eigen::Vector2f& d, float t0, float t1,
                                      float range, std::int64_t cell) const noexcept;
};

}  // namespace duet
