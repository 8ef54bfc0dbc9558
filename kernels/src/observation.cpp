// The ray-tracing observation model of the paper (§3.1, Fig. 5; entropy of Eq. 5 summed along the
// rays of each sensor's sector), with a 2D DDA backend and an Embree backend (observation.hpp).
#include <duet/kernels/observation.hpp>

#include <duet/kernels/entropy.hpp>
#include <duet/kernels/error.hpp>

#include "parallel.hpp"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <mutex>
#include <numbers>
#include <string>

namespace duet {
namespace {

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

std::string fstr(float v) { return std::to_string(v); }

using detail::fan_direction;
using detail::fan_origin;
using detail::turn;

}  // namespace

// ---- sensors ------------------------------------------------------------------------------------

std::vector<SensorSector> paper_dual_sensors(int rays_per_sensor) {
  SensorSector s1;
  s1.x_m = -0.118f;
  s1.y_m = 0.0f;
  s1.yaw_rad = 0.0f;
  s1.rays = rays_per_sensor;
  SensorSector s2 = s1;
  s2.yaw_rad = -std::numbers::pi_v<float> / 2.0f;
  validate(s1);
  return {s1, s2};
}

void validate(const SensorSector& s) {
  if (!std::isfinite(s.x_m) || !std::isfinite(s.y_m) || !std::isfinite(s.yaw_rad))
    fail(ErrorCode::kInvalidArgument, "SensorSector: x_m, y_m, yaw_rad must be finite");
  if (!(s.fov_rad > 0.0f) || !(s.fov_rad <= 2.0f * std::numbers::pi_v<float>))
    fail(ErrorCode::kInvalidArgument, "SensorSector.fov_rad must be in (0, 2 pi], got " + fstr(s.fov_rad));
  if (!(s.min_range_m >= 0.0f) || !std::isfinite(s.min_range_m))
    fail(ErrorCode::kInvalidArgument, "SensorSector.min_range_m must be finite and >= 0, got " + fstr(s.min_range_m));
  if (!(s.max_range_m >= s.min_range_m) || !std::isfinite(s.max_range_m))
    fail(ErrorCode::kInvalidArgument, "SensorSector.max_range_m must be finite and >= min_range_m (" +
                                          fstr(s.min_range_m) + "), got " + fstr(s.max_range_m));
  if (s.rays < 1 || s.rays > 100000)
    fail(ErrorCode::kInvalidArgument, "SensorSector.rays must be in [1, 100000], got " + std::to_string(s.rays));
}

void validate(std::span<const SensorSector> sensors) {
  if (sensors.empty()) fail(ErrorCode::kInvalidArgument, "sensors: at least one SensorSector is required");
  for (const auto& s : sensors) validate(s);
}

void sector_rays(const Pose2& pose, const SensorSector& s, std::span<Eigen::Vector2f> origins,
                 std::span<Eigen::Vector2f> dirs) {
  validate(s);
  if (origins.size() != static_cast<std::size_t>(s.rays) || dirs.size() != static_cast<std::size_t>(s.rays))
    fail(ErrorCode::kInvalidArgument, "sector_rays: origins and dirs must have SensorSector.rays = " +
                                          std::to_string(s.rays) + " elements, got " + std::to_string(origins.size()) +
                                          " and " + std::to_string(dirs.size()));
  const float c = std::cos(pose.theta), sn = std::sin(pose.theta);
  for (int r = 0; r < s.rays; ++r) {
    origins[static_cast<std::size_t>(r)] = fan_origin(pose, s, c, sn);
    dirs[static_cast<std::size_t>(r)] = turn(c, sn, fan_direction(s, r));
  }
}

void validate(const ObservationSettings& s) {
  validate(s.thresholds);
  if (s.backend != ObservationBackend::kEmbree && s.backend != ObservationBackend::kDda)
    fail(ErrorCode::kInvalidArgument, "ObservationSettings.backend must be kEmbree or kDda");
  if (s.tile_cells < 1 || s.tile_cells > 65536)
    fail(ErrorCode::kInvalidArgument,
         "ObservationSettings.tile_cells must be in [1, 65536], got " + std::to_string(s.tile_cells));
}

// ---- the model ----------------------------------------------------------------------------------

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

  // ---- Embree ----
  static void on_error(void* user, RTCError code, const char* str) {
    auto* self = static_cast<Impl*>(user);
    const std::lock_guard<std::mutex> lock(self->error_mutex);
    self->error_message = "Embree error " + std::to_string(static_cast<int>(code)) + ": " + (str ? str : "");
  }
  void check(const char* what) {
    const RTCError e = rtcGetDeviceError(device);
    if (e == RTC_ERROR_NONE) return;
    std::string msg;
    {
      const std::lock_guard<std::mutex> lock(error_mutex);
      msg = error_message;
    }
    fail(e == RTC_ERROR_OUT_OF_MEMORY ? ErrorCode::kOutOfMemory : ErrorCode::kInternal,
         std::string("ObservationModel: ") + what + " failed: " + (msg.empty() ? std::to_string(static_cast<int>(e)) : msg));
  }
  void init_embree() {
    device = rtcNewDevice(nullptr);
    if (!device)
      fail(ErrorCode::kInternal, "ObservationModel: rtcNewDevice failed (Embree error " +
                                     std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) + ")");
    rtcSetDeviceErrorFunction(device, &Impl::on_error, this);
    top = rtcNewScene(device);
    check("rtcNewScene");
  }
  void release_tile(std::size_t t) {
    Tile& tile = tiles[t];
    if (tile.instance) {
      rtcDetachGeometry(top, static_cast<unsigned>(t));
      rtcReleaseGeometry(tile.instance);
      tile.instance = nullptr;
    }
    if (tile.scene) {
      rtcReleaseScene(tile.scene);
      tile.scene = nullptr;
    }
    tile.quads.clear();
  }
  void release_tiles() {
    for (std::size_t t = 0; t < tiles.size(); ++t) release_tile(t);
  }

  /// Builds tile t's scene (not attached): the faces of its occupied cells whose neighbour (in
  /// this or another tile, or outside the grid) is not occupied. Safe to run for different tiles
  /// in parallel (each touches only its own scene and Tile).
  void build_tile_scene(std::size_t t) {
    Tile& tile = tiles[t];
    const int T = settings.tile_cells;
    const int tx = static_cast<int>(t % static_cast<std::size_t>(tiles_x)), ty = static_cast<int>(t / static_cast<std::size_t>(tiles_x));
    const int x0 = tx * T, x1 = std::min(view.width, x0 + T), y0 = ty * T, y1 = std::min(view.height, y0 + T);
    tile.quads.clear();
    for (int iy = y0; iy < y1; ++iy)
      for (int ix = x0; ix < x1; ++ix) {
        if (!occupied(ix, iy)) continue;
        const std::uint32_t c = static_cast<std::uint32_t>(view.index(ix, iy)) << 2;
        if (!occupied(ix - 1, iy)) tile.quads.push_back(c | 0u);
        if (!occupied(ix + 1, iy)) tile.quads.push_back(c | 1u);
        if (!occupied(ix, iy - 1)) tile.quads.push_back(c | 2u);
        if (!occupied(ix, iy + 1)) tile.quads.push_back(c | 3u);
      }
    if (tile.quads.empty()) return;
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_QUAD);
    const std::size_t nq = tile.quads.size();
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 4 * nq));
    auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4, 4 * sizeof(unsigned), nq));
    if (!v || !idx) {
      rtcReleaseGeometry(g);
      return;  // reported through the device error (checked by the caller)
    }
    const float res = view.resolution_m, ox = view.origin.x(), oy = view.origin.y();
    const int w = view.width;
    for (std::size_t q = 0; q < nq; ++q) {
      const std::uint32_t cell = tile.quads[q] >> 2, face = tile.quads[q] & 3u;
      const int ix = static_cast<int>(cell % static_cast<std::uint32_t>(w)), iy = static_cast<int>(cell / static_cast<std::uint32_t>(w));
      const float xa = ox + static_cast<float>(ix) * res, xb = ox + static_cast<float>(ix + 1) * res;
      const float ya = oy + static_cast<float>(iy) * res, yb = oy + static_cast<float>(iy + 1) * res;
      float ax, ay, bx, by;  // the face's segment
      switch (face) {
        case 0: ax = xa; ay = ya; bx = xa; by = yb; break;
        case 1: ax = xb; ay = ya; bx = xb; by = yb; break;
        case 2: ax = xa; ay = ya; bx = xb; by = ya; break;
        default: ax = xa; ay = yb; bx = xb; by = yb; break;
      }
      float* p = v + 12 * q;
      p[0] = ax; p[1] = ay; p[2] = -1.0f;
      p[3] = bx; p[4] = by; p[5] = -1.0f;
      p[6] = bx; p[7] = by; p[8] = 1.0f;
      p[9] = ax; p[10] = ay; p[11] = 1.0f;
      const auto b = static_cast<unsigned>(4 * q);
      idx[4 * q + 0] = b;
      idx[4 * q + 1] = b + 1;
      idx[4 * q + 2] = b + 2;
      idx[4 * q + 3] = b + 3;
    }
    rtcCommitGeometry(g);
    tile.scene = rtcNewScene(device);
    rtcAttachGeometryByID(tile.scene, g, 0);
    rtcReleaseGeometry(g);
    rtcCommitScene(tile.scene);
    tile.instance = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(tile.instance, tile.scene);
    static constexpr float kIdentity[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
    rtcSetGeometryTransform(tile.instance, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, kIdentity);
    rtcCommitGeometry(tile.instance);
  }

  /// Rebuilds the listed tiles (parallel scene builds, serial attach) and commits the top scene.
  void rebuild_tiles(const std::vector<std::size_t>& list) {
    for (const std::size_t t : list) release_tile(t);
    check("releasing tiles");
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, list.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) build_tile_scene(list[i]);
    });
    check("building tile scenes");
    for (const std::size_t t : list)
      if (tiles[t].instance) rtcAttachGeometryByID(top, tiles[t].instance, static_cast<unsigned>(t));
    rtcCommitScene(top);
    check("rtcCommitScene");
  }

  // ---- grid ingestion ----
  [[nodiscard]] bool same_geometry(const GridView& g) const noexcept {
    return g.width == view.width && g.height == view.height && g.resolution_m == view.resolution_m &&
           g.origin == view.origin;
  }

  /// Copies the log-odds and recomputes states, entropy and the packed words. If dirty != nullptr
  /// (same geometry), marks every tile whose faces may change: the tile of each cell whose
  /// occupancy changed and the tiles of its 4 neighbours.
  void ingest(const GridView& g, std::atomic<std::uint8_t>* dirty) {
    const std::size_t n = g.cell_count();
    logodds.assign(g.logodds.begin(), g.logodds.end());
    view = GridView(std::span<const float>(logodds), g.width, g.height, g.resolution_m, g.origin);
    states.resize(n);
    entropy.resize(n);
    classify_grid(view, settings.thresholds, states);
    grid_entropy(view, entropy);
    const std::size_t bx = (static_cast<std::size_t>(g.width) + 3) / 4, by = (static_cast<std::size_t>(g.height) + 3) / 4;
    const bool keep = dirty != nullptr && packed.size() == bx * by * 16 && blocks_x == bx;
    blocks_x = bx;
    packed.resize(bx * by * 16, kUnknownWord);
    const int w = view.width, h = view.height, T = settings.tile_cells;
    detail::for_blocks(static_cast<std::size_t>(h), 16, [&](std::size_t, std::size_t rb, std::size_t re) {
      for (std::size_t iy = rb; iy < re; ++iy)
        for (int ix = 0; ix < w; ++ix) {
          const std::size_t i = iy * static_cast<std::size_t>(w) + static_cast<std::size_t>(ix);
          const std::uint32_t nw = fixed_entropy(entropy[i]) |
                                   (states[i] == CellState::kOccupied ? kOccupiedBit : 0u);
          std::uint32_t& pw = packed[packed_index(static_cast<unsigned>(ix), static_cast<unsigned>(iy))];
          if (keep && ((pw ^ nw) & kOccupiedBit)) {
            const int y = static_cast<int>(iy);
            const int nb[5][2] = {{ix, y}, {ix - 1, y}, {ix + 1, y}, {ix, y - 1}, {ix, y + 1}};
            for (const auto& c : nb)
              if (c[0] >= 0 && c[1] >= 0 && c[0] < w && c[1] < h)
                dirty[static_cast<std::size_t>(c[1] / T) * static_cast<std::size_t>(tiles_x) + static_cast<std::size_t>(c[0] / T)]
                    .store(1, std::memory_order_relaxed);
          }
          pw = nw;
        }
    });
  }

  void full_rebuild(const GridView& g) {
    validate(g, "ObservationModel::set_grid: grid");
    if (settings.backend == ObservationBackend::kEmbree && g.cell_count() >= (std::size_t{1} << 30))
      fail(ErrorCode::kOutOfRange, "ObservationModel::set_grid: the Embree backend supports grids of < 2^30 cells, got " +
                                       std::to_string(g.cell_count()));
    if (settings.backend == ObservationBackend::kEmbree) {
      release_tiles();
      check("releasing tiles");
    }
    ingest(g, nullptr);
    if (settings.backend != ObservationBackend::kEmbree) return;
    const int T = settings.tile_cells;
    tiles_x = (view.width + T - 1) / T;
    tiles_y = (view.height + T - 1) / T;
    tiles.clear();
    tiles.resize(static_cast<std::size_t>(tiles_x) * static_cast<std::size_t>(tiles_y));
    std::vector<std::size_t> all(tiles.size());
    for (std::size_t t = 0; t < all.size(); ++t) all[t] = t;
    rebuild_tiles(all);
  }

  std::size_t incremental(const GridView& g) {
    validate(g, "ObservationModel::update_grid: grid");
    if (!same_geometry(g) || states.size() != g.cell_count()) {
      full_rebuild(g);
      return tiles.size();
    }
    if (settings.backend != ObservationBackend::kEmbree) {
      ingest(g, nullptr);
      return 0;
    }
    std::unique_ptr<std::atomic<std::uint8_t>[]> dirty(new std::atomic<std::uint8_t>[tiles.size()]);
    for (std::size_t t = 0; t < tiles.size(); ++t) dirty[t].store(0, std::memory_order_relaxed);
    ingest(g, dirty.get());
    std::vector<std::size_t> list;
    for (std::size_t t = 0; t < tiles.size(); ++t)
      if (dirty[t].load(std::memory_order_relaxed)) list.push_back(t);
    if (!list.empty()) rebuild_tiles(list);
    return list.size();
  }

  // ---- tracing ----
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

  /// The cell a ray is in just after t0 (the first cell of its walk).
  [[nodiscard]] Eigen::Vector2i first_cell(const Eigen::Vector2f& o, const Eigen::Vector2f& d, float t0, float t1) const noexcept {
    Eigen::Vector2i c(std::numeric_limits<int>::min(), std::numeric_limits<int>::min());
    walk_cells(view, o, d, t0, t1, [&](int ix, int iy, float, float) {
      c = Eigen::Vector2i(ix, iy);
      return false;
    });
    return c;
  }

  /// Embree: up to 8 rays; hit[k] = range, cell[k] = hit cell index or -1 (no hit).
  /// A ray starting in an occupied cell hits at t0 without tracing; a hit on a face the ray leaves
  /// (it started on that face) is skipped by re-tracing just past it.
  void trace8(const Eigen::Vector2f* o, const Eigen::Vector2f* d, int count, float t0, float t1, float* range,
              std::int64_t* cell) const {
    alignas(32) int valid[8];
    RTCRayHit8 rh;
    for (int k = 0; k < 8; ++k) {
      valid[k] = 0;
      range[k] = t1;
      cell[k] = -1;
      if (k >= count) continue;
      const Eigen::Vector2i c0 = first_cell(o[k], d[k], t0, t1);
      if (view.in_bounds(c0.x(), c0.y()) && occupied(c0.x(), c0.y())) {
        range[k] = t0;
        cell[k] = static_cast<std::int64_t>(view.index(c0.x(), c0.y()));
        continue;
      }
      valid[k] = -1;
      rh.ray.org_x[k] = o[k].x();
      rh.ray.org_y[k] = o[k].y();
      rh.ray.org_z[k] = 0.0f;
      rh.ray.dir_x[k] = d[k].x();
      rh.ray.dir_y[k] = d[k].y();
      rh.ray.dir_z[k] = 0.0f;
      rh.ray.tnear[k] = t0;
      rh.ray.tfar[k] = t1;
      rh.ray.time[k] = 0.0f;
      rh.ray.mask[k] = 0xFFFFFFFFu;
      rh.ray.id[k] = static_cast<unsigned>(k);
      rh.ray.flags[k] = 0;
      rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    rtcIntersect8(valid, top, &ctx, &rh);
    for (int k = 0; k < count; ++k) {
      if (!valid[k]) continue;
      for (int retry = 0; retry < 4 && rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID; ++retry) {
        const std::uint32_t code = tiles[rh.hit.instID[0][k]].quads[rh.hit.primID[k]];
        const std::uint32_t face = code & 3u;
        const float dn = face == 0 ? -d[k].x() : face == 1 ? d[k].x() : face == 2 ? -d[k].y() : d[k].y();
        if (dn < 0.0f) {  // entering the occupied cell: a real hit
          range[k] = rh.ray.tfar[k];
          cell[k] = static_cast<std::int64_t>(code >> 2);
          break;
        }
        // Leaving an occupied cell (the ray started on its face): trace on from just past it.
        RTCRayHit one;
        one.ray.org_x = o[k].x();
        one.ray.org_y = o[k].y();
        one.ray.org_z = 0.0f;
        one.ray.dir_x = d[k].x();
        one.ray.dir_y = d[k].y();
        one.ray.dir_z = 0.0f;
        one.ray.tnear = std::nextafter(rh.ray.tfar[k], std::numeric_limits<float>::infinity());
        one.ray.tfar = t1;
        one.ray.time = 0.0f;
        one.ray.mask = 0xFFFFFFFFu;
        one.ray.id = 0;
        one.ray.flags = 0;
        one.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        one.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        RTCIntersectContext c1;
        rtcInitIntersectContext(&c1);
        rtcIntersect1(top, &c1, &one);
        rh.hit.geomID[k] = one.hit.geomID;
        rh.hit.instID[0][k] = one.hit.instID[0];
        rh.hit.primID[k] = one.hit.primID;
        rh.ray.tfar[k] = one.ray.tfar;
      }
    }
  }

  /// Embree: entropy summed by a walk without occupancy checks up to the hit cell (included).
  /// If the walk misses the hit cell (a ray through a cell corner), it stops at the first cell
  /// entered after the hit distance (+ 1e-4 m).
  [[nodiscard]] RayObservation sum_to(const Eigen::Vector2f& o, const Eigen::Vector2f& d, float t0, float t1,
                                      float range, std::int64_t cell) const noexcept {
    RayObservation r{0.0f, cell >= 0 ? range : t1, cell >= 0, 0};
    const int hx = cell >= 0 ? static_cast<int>(cell % view.width) : std::numeric_limits<int>::min();
    const int hy = cell >= 0 ? static_cast<int>(cell / view.width) : std::numeric_limits<int>::min();
    const float stop = cell >= 0 ? range + 1e-4f : std::numeric_limits<float>::infinity();
    std::uint64_t sum = 0;
    std::int32_t n = 0;
    walk_cells(view, o, d, t0, t1, [&](int ix, int iy, float te, float) {
      if (te > stop) return false;
      sum += word_entropy(word(ix, iy));
      ++n;
      return !(ix == hx && iy == hy);
    });
    r.entropy_bits = bits_of(sum);
    r.cells = n;
    return r;
  }
};

namespace {
ObservationModel::Impl& need(const std::unique_ptr<ObservationModel::Impl>& p) {
  if (!p) fail(ErrorCode::kInvalidArgument, "ObservationModel: used after being moved from");
  return *p;
}

void check_rays(std::span<const Eigen::Vector2f> origins, std::span<const Eigen::Vector2f> dirs, float t0, float t1,
                std::size_t out_size) {
  if (origins.size() != dirs.size() || out_size != origins.size())
    fail(ErrorCode::kInvalidArgument, "ObservationModel::cast: origins (" + std::to_string(origins.size()) + "), dirs (" +
                                          std::to_string(dirs.size()) + ") and out (" + std::to_string(out_size) +
                                          ") must have the same size");
  if (!(t0 >= 0.0f) || !(t1 >= t0) || !std::isfinite(t1))
    fail(ErrorCode::kInvalidArgument, "ObservationModel::cast: need 0 <= t0 <= t1 < inf, got t0 = " + fstr(t0) +
                                          ", t1 = " + fstr(t1));
  for (std::size_t i = 0; i < origins.size(); ++i) {
    if (!origins[i].allFinite() || !dirs[i].allFinite() || !(std::fabs(dirs[i].squaredNorm() - 1.0f) <= 2e-3f))
      fail(ErrorCode::kInvalidArgument, "ObservationModel::cast: ray " + std::to_string(i) +
                                            ": origin must be finite and dir a unit vector (|dir| within 1e-3 of 1)");
  }
}
}  // namespace

ObservationModel::ObservationModel(const ObservationSettings& s) {
  validate(s);
  impl_ = std::make_unique<Impl>(s);
  if (s.backend == ObservationBackend::kEmbree) impl_->init_embree();
}
ObservationModel::~ObservationModel() = default;
ObservationModel::ObservationModel(ObservationModel&&) noexcept = default;
ObservationModel& ObservationModel::operator=(ObservationModel&&) noexcept = default;

const ObservationSettings& ObservationModel::settings() const { return need(impl_).settings; }
void ObservationModel::set_grid(const GridView& grid) { need(impl_).full_rebuild(grid); }
std::size_t ObservationModel::update_grid(const GridView& grid) { return need(impl_).incremental(grid); }
const GridView& ObservationModel::grid() const { return need(impl_).view; }
std::span<const CellState> ObservationModel::states() const { return need(impl_).states; }
std::span<const float> ObservationModel::entropy() const { return need(impl_).entropy; }
int ObservationModel::tiles_x() const { return need(impl_).tiles_x; }
int ObservationModel::tiles_y() const { return need(impl_).tiles_y; }

void ObservationModel::cast(std::span<const Eigen::Vector2f> origins, std::span<const Eigen::Vector2f> dirs, float t0,
                            float t1, std::span<RayHit> out) const {
  const Impl& m = need(impl_);
  check_rays(origins, dirs, t0, t1, out.size());
  const std::size_t n = origins.size();
  if (m.settings.backend == ObservationBackend::kDda) {
    detail::for_blocks(n, 64, [&](std::size_t, std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) out[i] = m.cast_dda(origins[i], dirs[i], t0, t1);
    });
    return;
  }
  detail::for_blocks(detail::block_count(n, 8), 8, [&](std::size_t, std::size_t pb, std::size_t pe) {
    for (std::size_t p = pb; p < pe; ++p) {
      const std::size_t b = p * 8;
      const int count = static_cast<int>(std::min<std::size_t>(8, n - b));
      float range[8];
      std::int64_t cell[8];
      m.trace8(origins.data() + b, dirs.data() + b, count, t0, t1, range, cell);
      for (int k = 0; k < count; ++k) out[b + static_cast<std::size_t>(k)] = RayHit{range[k], cell[k] >= 0};
    }
  });
}

void ObservationModel::observe(std::span<const Pose2> poses, std::span<const SensorSector> sensors,
                               std::span<RayObservation> out) const {
  const Impl& m = need(impl_);
  validate(sensors);
  std::size_t total = 0;
  for (const auto& s : sensors) total += static_cast<std::size_t>(s.rays);
  if (out.size() != poses.size() * total)
    fail(ErrorCode::kInvalidArgument, "ObservationModel::observe: out has " + std::to_string(out.size()) +
                                          " elements, must be poses.size() * total rays = " +
                                          std::to_string(poses.size() * total));
  for (std::size_t p = 0; p < poses.size(); ++p)
    if (!std::isfinite(poses[p].x) || !std::isfinite(poses[p].y) || !std::isfinite(poses[p].theta))
      fail(ErrorCode::kInvalidArgument, "ObservationModel::observe: pose " + std::to_string(p) + " is not finite");
  std::vector<std::size_t> first(sensors.size());
  for (std::size_t s = 0, acc = 0; s < sensors.size(); ++s) {
    first[s] = acc;
    acc += static_cast<std::size_t>(sensors[s].rays);
  }
  const std::size_t ns = sensors.size();
  const bool dda = m.settings.backend == ObservationBackend::kDda;
  // Each sensor's fan in the robot frame, turned per pose (one sin/cos per pose, not per ray).
  std::vector<std::vector<Eigen::Vector2f>> fans(ns);
  for (std::size_t si = 0; si < ns; ++si) fans[si] = detail::fan_directions(sensors[si]);
  // One task item = one sensor's fan at one pose; per-ray outputs, so any partition gives the same.
  detail::for_each_index(poses.size() * ns, 1, [&](std::size_t job) {
    const std::size_t p = job / ns, si = job % ns;
    const Pose2& pose = poses[p];
    const SensorSector& s = sensors[si];
    RayObservation* o = out.data() + p * total + first[si];
    const float c = std::cos(pose.theta), sn = std::sin(pose.theta);
    const Eigen::Vector2f org = fan_origin(pose, s, c, sn);
    const std::vector<Eigen::Vector2f>& fan = fans[si];
    if (dda) {
      const bool prefetch = m.packed.size() * sizeof(std::uint32_t) > Impl::kPrefetchBytes;
      for (int r = 0; r < s.rays; ++r) {
        const Eigen::Vector2f dir = turn(c, sn, fan[static_cast<std::size_t>(r)]);
        if (prefetch) m.prefetch_ray(org, dir, s.max_range_m);
        o[r] = m.observe_dda_from_sensor(org, dir, s.min_range_m, s.max_range_m);
      }
      return;
    }
    for (int r0 = 0; r0 < s.rays; r0 += 8) {
      const int count = std::min(8, s.rays - r0);
      Eigen::Vector2f orgs[8], dir[8];
      for (int k = 0; k < count; ++k) {
        orgs[k] = org;
        dir[k] = turn(c, sn, fan[static_cast<std::size_t>(r0 + k)]);
      }
      float range[8];
      std::int64_t cell[8];
      m.trace8(orgs, dir, count, s.min_range_m, s.max_range_m, range, cell);
      for (int k = 0; k < count; ++k) {
        const float blocked = m.blocked_before(org, dir[k], s.min_range_m);
        o[r0 + k] = blocked >= 0.0f ? RayObservation{0.0f, blocked, true, 0}
                                    : m.sum_to(org, dir[k], s.min_range_m, s.max_range_m, range[k], cell[k]);
      }
    }
  });
}

float ObservationModel::information_bits(const Pose2& pose, std::span<const SensorSector> sensors) const {
  validate(sensors);
  std::size_t total = 0;
  for (const auto& s : sensors) total += static_cast<std::size_t>(s.rays);
  std::vector<RayObservation> obs(total);
  observe(std::span<const Pose2>(&pose, 1), sensors, obs);
  double sum = 0.0;
  for (const auto& r : obs) sum += static_cast<double>(r.entropy_bits);
  return static_cast<float>(sum);
}

}  // namespace duet
