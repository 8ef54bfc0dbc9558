#pragma once
// Internal: the precomputed rays of partial map simulation (Procedure 1, partial_sim.cpp): the window
// of cells an iteration's rays can reach (per-cell codes, stored cells and empty-space skipping blocks)
// and the walks that store each ray's cells (partial_sim_rays.cpp), with the per-thread scratch
// they fill. What is read per cell (RayCell, the kinds) is inline here.
#include <duet/kernels/grid_view.hpp>
#include <duet/kernels/motion_model.hpp>
#include <duet/kernels/observation.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <type_traits>
#include <vector>

namespace duet::detail::partial_sim {

// A cell of a precomputed ray. kind: what z ~ chi does with it and how its reward is computed.
enum : std::uint32_t {
  kFreeCell = 0,         // known free, finite prior l: a miss; reward from l
  kUnknownFinite = 1,    // unknown (between the thresholds), finite prior l: sampled; reward from l
  kUnknownNan = 2,       // never observed (prior 0, 1 bit): sampled; reward the same for all such cells
  kOccupiedCell = 3,     // known occupied: a hit, ends the ray; reward from l
};
constexpr std::uint32_t kOutside = 0x3FFFFFFFu;  // index of a cell outside the grid
// A window cell's code (Window::codes): kSkipCode, kind + 1 for a cell of the grid, or
// kOutsideCode for a cell outside the grid (a never-observed cell that the overlay cannot stamp).
// (code - 1) & 3 is the kind of every code but kSkipCode.
constexpr std::uint32_t kSkipCode = 0;          // see build_window()
constexpr std::uint32_t kOutsideCode = kUnknownNan + 5;
constexpr std::uint32_t kind_of(std::uint32_t code) noexcept { return (code - 1) & 3u; }
static_assert(kind_of(kOutsideCode) == kUnknownNan);

struct RayCell {
  std::uint32_t packed;  // (index << 2) | kind: the window's index (Window), kOutside outside the grid
                         // (l = e = 0 for kUnknownNan, outside the grid too)
  float l;               // prior log-odds (0 for kUnknownNan)
  float e;               // entropy_table()(l) [bits] (0 for kUnknownNan): once per window cell, not per sample
};
static_assert(std::is_trivially_copyable_v<RayCell>);  // (CellBuffer and the walks move cells by memmove)

// Eq. (5) in bits for finite log-odds, by linear interpolation in a table over [-kTableL, kTableL]
// (step 1/256; the interpolation error is below 2e-7 bits). Posteriors are clamped to the
// settings' [min_logodds, max_logodds], which validate() keeps inside the table.
inline constexpr float kTableL = 20.0f;
inline constexpr float kTableScale = 256.0f;
inline constexpr int kTableSize = static_cast<int>(2 * kTableL * kTableScale) + 2;

inline double entropy_bits_exact(double l) {
  const double p = 1.0 / (1.0 + std::exp(-l));
  const double q = 1.0 - p;
  double e = 0.0;
  if (p > 0.0) e -= p * std::log2(p);
  if (q > 0.0) e -= q * std::log2(q);
  return e;
}

struct EntropyTable {
  std::array<float, kTableSize> v{};
  EntropyTable() {
    for (int i = 0; i < kTableSize; ++i)
      v[static_cast<std::size_t>(i)] = static_cast<float>(entropy_bits_exact(i / static_cast<double>(kTableScale) - kTableL));
  }
  [[nodiscard]] float operator()(float l) const noexcept {
    const float x = (l + kTableL) * kTableScale;
    const int i = static_cast<int>(x);
    const float f = x - static_cast<float>(i);
    const float a = v[static_cast<std::size_t>(i)], b = v[static_cast<std::size_t>(i) + 1];
    return a + f * (b - a);
  }
};

inline const EntropyTable& entropy_table() {
  static const EntropyTable table;  // immutable after construction (thread-safe static init)
  return table;
}

// Empty-space skipping blocks (see build_skip_blocks()). 2 x 2 cells: a jump lands exactly on the
// walk (RayWalker::jump_to counts the crossings it passes), so small blocks only cost more jumps;
// measured (PartialSim/duet_1t, CPU time, noisy machine) 8 x 8: 23-25 ms, 4 x 4: 22 ms, 2 x 2: 20-21 ms.
constexpr int kBlockShift = 1;
constexpr int kBlock = 1 << kBlockShift;

struct SkipBlocks {
  int bw = 0, bh = 0;
  std::vector<std::uint8_t> dist;
};

/// A box of grid cells, bounds included (it may reach outside the grid); empty while x1 < x0.
struct CellBox {
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
  [[nodiscard]] bool empty() const noexcept { return x1 < x0 || y1 < y0; }
  [[nodiscard]] bool contains(const CellBox& b) const noexcept {
    return b.empty() || (!empty() && b.x0 >= x0 && b.y0 >= y0 && b.x1 <= x1 && b.y1 <= y1);
  }
  void add(const CellBox& b) noexcept {
    if (b.empty()) return;
    if (empty()) {
      *this = b;
      return;
    }
    x0 = std::min(x0, b.x0), y0 = std::min(y0, b.y0), x1 = std::max(x1, b.x1), y1 = std::max(y1, b.y1);
  }
  [[nodiscard]] std::int64_t cells() const noexcept {
    return empty() ? 0 : (std::int64_t{x1} - x0 + 1) * (std::int64_t{y1} - y0 + 1);
  }
  /// The box with m more cells on every side (empty stays empty).
  [[nodiscard]] CellBox grown(int m) const noexcept { return empty() ? *this : CellBox{x0 - m, y0 - m, x1 + m, y1 + m}; }
};

/// The cells one iteration's rays can reach (build_window()): window cell (x, y), index
/// y * w + x, is grid cell (box.x0 + x, box.y0 + y). Every ray walked lies inside with a margin
/// (RayWalker checks it), so the walks test no bounds, and the per-thread arrays the walks and
/// samples index (ThreadScratch::overlay, lanes_overlay) are the window's size, which is much smaller
/// than the grid's and stays in cache.
struct Window {
  CellBox box;
  int w = 0, h = 0;
  std::vector<std::uint8_t> codes;  // per window cell (kSkipCode, kind + 1, kOutsideCode)
  std::vector<RayCell> cell;        // per window cell: what a walk stores for it (index, kind, l, E(l)), once per call
  SkipBlocks skip;                  // over codes (build_skip_blocks)
  [[nodiscard]] std::size_t cells() const noexcept { return static_cast<std::size_t>(w) * static_cast<std::size_t>(h); }
};

/// The cells of a particle's rays: a growable array that is not zeroed when it grows (the walks
/// write each cell before it is read), so that two rays are walked straight into it.
class CellBuffer {
 public:
  [[nodiscard]] const RayCell* data() const noexcept { return data_.get(); }
  [[nodiscard]] std::size_t size() const noexcept { return size_; }
  void clear() noexcept { size_ = 0; }
  /// Room for n more cells after size(); valid until the next call.
  RayCell* room(std::size_t n) {
    if (size_ + n > capacity_) {
      const std::size_t c = std::max(2 * capacity_, size_ + n);
      auto grown = std::make_unique_for_overwrite<RayCell[]>(c);
      std::copy(data_.get(), data_.get() + size_, grown.get());
      data_ = std::move(grown);
      capacity_ = c;
    }
    return data_.get() + size_;
  }
  /// Keeps the first n cells of the room.
  void keep(std::size_t n) noexcept { size_ += n; }

 private:
  std::unique_ptr<RayCell[]> data_;
  std::size_t size_ = 0, capacity_ = 0;
};

/// A per-cell array of stamped words (the samples' "seen in this sample" marks): next() gives a
/// stamp that no word holds yet, so nothing is cleared between samples (only when the stamps wrap,
/// or the array grows). A window of other cells needs no clearing either: the stamps are unique.
struct StampedOverlay {
  std::vector<std::uint32_t> word;
  std::uint32_t stamp = 0;
  /// A new stamp in [1, last]; word has at least n_cells entries.
  std::uint32_t next(std::size_t n_cells, std::uint32_t last) {
    if (word.size() < n_cells) {
      word.assign(n_cells, 0);
      stamp = 0;
    }
    if (++stamp > last) {  // wrap: clear
      std::fill(word.begin(), word.end(), 0u);
      stamp = 1;
    }
    return stamp;
  }
};

struct ThreadScratch {
  StampedOverlay overlay;                 // one sample at a time: per cell (stamp << 1) | sampled occupied
  CellBuffer cells;                       // all rays of all stages
  std::vector<std::uint32_t> ray_end;     // end offset of each ray in `cells`
  std::vector<Eigen::Vector2f> dirs;
  // The samples' AVX2 lanes (partial_sim_samples.cpp): per cell (group stamp << 16) | (seen bits
  // << 8) | sampled-occupied bits, a bit per lane; the random numbers drawn first; R_tj per lane.
  StampedOverlay lanes_overlay;
  std::vector<float> lane_delta, lane_u, lane_rk, lane_ru;
};

/// Adds to box the cells within reach of the fans of `sensors` at the poses x (the window margin
/// RayWalker checks: every cell within ceil(max_range / resolution) + 2 cells of a fan's origin).
void add_ray_box(const GridView& grid, std::span<const Pose2> x, std::span<const SensorSector> sensors, CellBox& box);

/// Fills win for box (codes, cells, skipping blocks; see partial_sim_rays.cpp). Throws
/// Error(kOutOfRange) for a box of 2^30 cells or more.
void build_window(const ObservationModel& model, float clamp_min, const CellBox& box, Window& win);

/// The cells of every ray of every stage of trajectory x into ts.cells / ts.ray_end (see
/// partial_sim_rays.cpp). The rays must lie in win
/// (add_ray_box() of the same poses): else Error(kInternal).
void precompute_rays(const GridView& grid, const Window& win, std::span<const Pose2> x, std::span<const SensorSector> sensors,
                     std::span<const std::vector<Eigen::Vector2f>> fans, ThreadScratch& ts);

}  // namespace duet::detail::partial_sim
