#pragma once
// Internal: the precomputed rays of partial map simulation (Procedure 1, partial_sim.cpp): per-cell
// codes, empty-space skipping blocks and the walks that store each ray's cells (partial_sim_rays.cpp),
// with the per-thread scratch they fill. What is read per cell (RayCell, the kinds) is inline here.
#include <duet/kernels/grid_view.hpp>
#include <duet/kernels/motion_model.hpp>
#include <duet/kernels/observation.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
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
constexpr std::uint32_t kSkipCode = 0;          // see build_codes()

struct RayCell {
  std::uint32_t packed;  // (index << 2) | kind; index kOutside outside the grid
  float l;               // prior log-odds (0 for kUnknownNan)
  float e;               // entropy_table()(l) [bits] (0 for kUnknownNan): once per walk, not per sample
  std::uint32_t dropped_before;  // repeats of this ray not stored just before this one (partial_sim_rays.cpp)
};

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

struct ThreadScratch {
  std::vector<std::uint32_t> overlay;  // per cell: (stamp << 1) | sampled occupied
  std::uint32_t stamp = 0;
  std::vector<RayCell> cells;             // all rays of all stages
  std::vector<RayCell> pair_buffer;       // the two rays being walked
  std::vector<std::uint32_t> ray_end;     // end offset of each ray in `cells`
  std::vector<std::uint32_t> ray_tail;    // cells not stored after each ray's last stored cell (repeats)
  std::vector<std::uint32_t> sure_ray;    // per cell: the serial of a ray that surely visits it, known free (repeats)
  std::uint32_t ray_serial = 1;           // the next ray's serial (walks of one thread, never reused until cleared)
  std::vector<Eigen::Vector2f> origins, dirs;

  std::uint32_t next_stamp(std::size_t n_cells) {
    if (overlay.size() != n_cells) {
      overlay.assign(n_cells, 0);
      stamp = 0;
    }
    if (++stamp >= (1u << 31)) {  // wrap: clear (after 2^31 samples)
      std::fill(overlay.begin(), overlay.end(), 0u);
      stamp = 1;
    }
    return stamp;
  }
};

/// The empty-space skipping blocks of codes (see partial_sim_rays.cpp).
void build_skip_blocks(const GridView& grid, std::span<const std::uint8_t> codes, SkipBlocks& sb);

/// The cells of every ray of every stage of trajectory x into ts.cells / ts.ray_end / ts.ray_tail,
/// without the repeats every sample skips (see partial_sim_rays.cpp).
void precompute_rays(const GridView& grid, std::span<const std::uint8_t> codes, const SkipBlocks& sb, std::span<const Pose2> x,
                     std::span<const SensorSector> sensors, std::span<const std::vector<Eigen::Vector2f>> fans, ThreadScratch& ts);

/// The per-cell codes of the precomputed walks (see partial_sim_rays.cpp).
void build_codes(const ObservationModel& model, float clamp_min, std::vector<std::uint8_t>& codes);

}  // namespace duet::detail::partial_sim
