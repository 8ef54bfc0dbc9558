// Partial map simulation, Procedure 1 of the paper (see partial_sim.hpp for the line-by-line map).
#include <duet/kernels/error.hpp>
#include <duet/kernels/partial_sim.hpp>

#include "random.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

namespace duet {

namespace {

// floor() to int without a libm call (baseline x86-64 has no roundss): the walks and rollouts
// call it per jump and per sub-step. Clamped to +-1e9 first, so the conversion is defined for any
// finite input (callers never pass NaN).
inline int floor_int(float x) noexcept {
  x = std::min(std::max(x, -1e9f), 1e9f);
  const int i = static_cast<int>(x);
  return i - (static_cast<float>(i) > x ? 1 : 0);
}

// Eq. (5) in bits for finite log-odds, by linear interpolation in a table over [-kTableL, kTableL]
// (step 1/256; the interpolation error is below 2e-7 bits). Posteriors are clamped to the
// settings' [min_logodds, max_logodds], which validate() keeps inside the table.
constexpr float kTableL = 20.0f;
constexpr float kTableScale = 256.0f;
constexpr int kTableSize = static_cast<int>(2 * kTableL * kTableScale) + 2;

double entropy_bits_exact(double l) {
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

const EntropyTable& entropy_table() {
  static const EntropyTable table;  // immutable after construction (thread-safe static init)
  return table;
}

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
};
inline RayCell make_cell(std::uint32_t index, std::uint32_t kind, float l) { return {(index << 2) | kind, l}; }

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

struct Particle {
  std::vector<Twist> u;     // U_{0:H-1}
  std::vector<Pose2> x;     // X_{1:H}
  double log_w = 0.0;       // log w_i^(n)
  bool valid = false;
  float reward_mean = 0.0f; // mean over j of sum_t R_{t,j} (bits)
  std::int64_t visits = 0;
};

}  // namespace

struct PartialSimWorkspace::Impl {
  tbb::enumerable_thread_specific<ThreadScratch> scratch;
  std::vector<Particle> particles, resampled;
  std::vector<std::uint8_t> codes;  // per cell, see build_codes()
  SkipBlocks skip;                   // see build_skip_blocks()
};

PartialSimWorkspace::PartialSimWorkspace() : impl_(std::make_unique<Impl>()) {}
PartialSimWorkspace::~PartialSimWorkspace() = default;
PartialSimWorkspace::PartialSimWorkspace(PartialSimWorkspace&&) noexcept = default;
PartialSimWorkspace& PartialSimWorkspace::operator=(PartialSimWorkspace&&) noexcept = default;

void validate(const PartialSimSettings& s) {
  auto bad = [](const char* key, double v, const char* range) {
    fail(ErrorCode::kInvalidArgument,
         std::string("PartialSimSettings.") + key + " = " + std::to_string(v) + " is outside " + range);
  };
  auto finite = [](float v) { return std::isfinite(v); };
  if (s.iterations < 1 || s.iterations > 1000) bad("iterations", s.iterations, "[1, 1000]");
  if (s.particles < 1 || s.particles > 100000) bad("particles", s.particles, "[1, 100000]");
  if (s.stages < 1 || s.stages > 100) bad("stages", s.stages, "[1, 100]");
  for (int i = 1; i <= s.iterations; ++i) {
    const long phi = static_cast<long>(s.phi_a) * i + s.phi_b;
    if (phi < 1 || phi > 1000)
      fail(ErrorCode::kInvalidArgument, "PartialSimSettings: phi_i = phi_a * i + phi_b = " + std::to_string(phi) +
                                            " at i = " + std::to_string(i) + " is outside [1, 1000]");
  }
  if (!finite(s.stage_dt_s) || !(s.stage_dt_s > 0.0f) || s.stage_dt_s > 60.0f) bad("stage_dt_s", s.stage_dt_s, "(0, 60]");
  if (!finite(s.v_min_mps) || !finite(s.v_max_mps) || s.v_min_mps > s.v_max_mps || s.v_max_mps <= 0.0f)
    bad("v_min_mps/v_max_mps", s.v_min_mps, "finite with v_min_mps <= v_max_mps and v_max_mps > 0");
  if (!finite(s.omega_max_rps) || s.omega_max_rps < 0.0f) bad("omega_max_rps", s.omega_max_rps, "[0, inf)");
  if (!finite(s.sigma_v_mps) || s.sigma_v_mps < 0.0f) bad("sigma_v_mps", s.sigma_v_mps, "[0, inf)");
  if (!finite(s.sigma_omega_rps) || s.sigma_omega_rps < 0.0f) bad("sigma_omega_rps", s.sigma_omega_rps, "[0, inf)");
  if (!finite(s.resample_ess_fraction) || !(s.resample_ess_fraction > 0.0f) || s.resample_ess_fraction > 1.0f)
    bad("resample_ess_fraction", s.resample_ess_fraction, "(0, 1]");
  if (!finite(s.gamma) || !(s.gamma > 0.0f) || s.gamma > 10.0f) bad("gamma", s.gamma, "(0, 10]");
  if (!finite(s.unknown_hit_probability) || !(s.unknown_hit_probability > 0.0f) || !(s.unknown_hit_probability < 1.0f))
    bad("unknown_hit_probability", s.unknown_hit_probability, "(0, 1)");
  if (!(s.min_logodds < 0.0f) || !(s.max_logodds > 0.0f) || s.min_logodds < -15.0f || s.max_logodds > 15.0f)
    bad("min_logodds/max_logodds", s.min_logodds, "[-15, 0) and (0, 15]");
  if (!finite(s.hit_logodds) || !(s.hit_logodds > 0.0f) || s.hit_logodds > 15.0f) bad("hit_logodds", s.hit_logodds, "(0, 15]");
  if (!finite(s.miss_logodds) || !(s.miss_logodds < 0.0f) || s.miss_logodds < -15.0f)
    bad("miss_logodds", s.miss_logodds, "[-15, 0)");
  if (!finite(s.ism_noise_logodds) || s.ism_noise_logodds < 0.0f || !(s.ism_noise_logodds < -s.miss_logodds) ||
      !(s.ism_noise_logodds < s.hit_logodds))
    bad("ism_noise_logodds", s.ism_noise_logodds, "[0, min(hit_logodds, -miss_logodds)) (noise must not flip an observation)");
  if (!finite(s.min_goal_distance_m) || s.min_goal_distance_m < 0.0f) bad("min_goal_distance_m", s.min_goal_distance_m, "[0, inf)");
  if (!finite(s.max_goal_distance_m) || !(s.max_goal_distance_m > s.min_goal_distance_m))
    bad("max_goal_distance_m", s.max_goal_distance_m, "(min_goal_distance_m, inf)");
  if (!finite(s.collision_step_m) || !(s.collision_step_m > 0.0f)) bad("collision_step_m", s.collision_step_m, "(0, inf)");
}

namespace {

// Line 9 plus the rejection rule: rolls U out from x0 with Eq. (4); false if the rollout enters a
// non-traversable cell (other than the start cell) or ends outside the goal distance band.
bool rollout(const InflatedGrid& g, const Pose2& x0, const PartialSimSettings& s, std::span<const Twist> u,
             std::span<Pose2> x) {
  const float res = g.resolution_m;
  const int sx = floor_int((x0.x - g.origin.x()) / res);
  const int sy = floor_int((x0.y - g.origin.y()) / res);
  Pose2 p = x0;
  for (std::size_t k = 0; k < u.size(); ++k) {
    const float travel = std::fabs(u[k].v) * s.stage_dt_s;
    const int sub = std::max(1, static_cast<int>(std::ceil(travel / s.collision_step_m)));
    const float dt = s.stage_dt_s / static_cast<float>(sub);
    for (int q = 0; q < sub; ++q) {
      p = motion_step(p, u[k], dt);
      const int ix = floor_int((p.x - g.origin.x()) / res);
      const int iy = floor_int((p.y - g.origin.y()) / res);
      if (ix == sx && iy == sy) continue;
      if (ix < 0 || iy < 0 || ix >= g.width || iy >= g.height) return false;
      if (!g.traversable[static_cast<std::size_t>(iy) * static_cast<std::size_t>(g.width) + static_cast<std::size_t>(ix)])
        return false;
    }
    x[k] = p;
  }
  const float d = std::hypot(p.x - x0.x, p.y - x0.y);
  return d >= s.min_goal_distance_m && d <= s.max_goal_distance_m;
}

// Walks every ray of every stage once (the known part does not depend on j) and stores the cells:
// known-occupied cells end a ray; unknown and free cells are stored with their kind.
// Empty-space skipping for the walks: the grid is cut into kBlock x kBlock blocks; dist[b] is
// the chessboard distance, in blocks, from block b to the nearest block that holds a cell that is
// not kSkipCode (or lies on the grid's border). From a cell of a block with dist D >= 2 every cell
// within kBlock * (D - 1) cells (chessboard) is a skip cell, so a ray can jump that far at once.

void build_skip_blocks(const GridView& grid, std::span<const std::uint8_t> codes, SkipBlocks& sb) {
  const int w = grid.width, h = grid.height;
  sb.bw = (w + kBlock - 1) / kBlock;
  sb.bh = (h + kBlock - 1) / kBlock;
  const auto nb = static_cast<std::size_t>(sb.bw) * static_cast<std::size_t>(sb.bh);
  sb.dist.assign(nb, 0);
  // 1 where the whole block is skip cells (partial blocks at the border are never all-skip).
  tbb::parallel_for(tbb::blocked_range<int>(0, sb.bh, 1), [&](const tbb::blocked_range<int>& r) {
    for (int by = r.begin(); by != r.end(); ++by)
      for (int bx = 0; bx < sb.bw; ++bx) {
        bool all = (bx + 1) * kBlock <= w && (by + 1) * kBlock <= h;
        for (int y = by * kBlock; all && y < (by + 1) * kBlock; ++y) {
          const std::uint8_t* row = codes.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(w);
          for (int x = bx * kBlock; x < (bx + 1) * kBlock; ++x) all = all && row[x] == kSkipCode;
        }
        sb.dist[static_cast<std::size_t>(by) * static_cast<std::size_t>(sb.bw) + static_cast<std::size_t>(bx)] = all ? 255 : 0;
      }
  });
  // Chessboard distance transform (two raster passes; outside the grid counts as distance 0).
  auto at = [&](int x, int y) -> int {
    if (x < 0 || y < 0 || x >= sb.bw || y >= sb.bh) return 0;
    return sb.dist[static_cast<std::size_t>(y) * static_cast<std::size_t>(sb.bw) + static_cast<std::size_t>(x)];
  };
  auto set = [&](int x, int y, int v) {
    sb.dist[static_cast<std::size_t>(y) * static_cast<std::size_t>(sb.bw) + static_cast<std::size_t>(x)] =
        static_cast<std::uint8_t>(v);
  };
  for (int y = 0; y < sb.bh; ++y)
    for (int x = 0; x < sb.bw; ++x)
      if (at(x, y)) set(x, y, std::min({at(x, y), at(x - 1, y) + 1, at(x - 1, y - 1) + 1, at(x, y - 1) + 1, at(x + 1, y - 1) + 1}));
  for (int y = sb.bh - 1; y >= 0; --y)
    for (int x = sb.bw - 1; x >= 0; --x)
      if (at(x, y)) set(x, y, std::min({at(x, y), at(x + 1, y) + 1, at(x + 1, y + 1) + 1, at(x, y + 1) + 1, at(x - 1, y + 1) + 1}));
}

// The cells a ray crosses from its sensor to max_range, by a 2D DDA (Amanatides & Woo) on the
// 64-bit fixed-point times of detail::CellWalk (observation.hpp), jumping over runs of skip cells
// (SkipBlocks). The step is branch-free (the x-or-y choice is a conditional move on integers: a
// float compare there compiles to a branch that mispredicts every other cell on diagonal rays,
// and a float add chain costs ~8 cycles per cell; the integer chain compare-select-add ~3).
// Same cells as walk_cells() (an exact tie, a ray through a cell corner, steps both axes), except
// the skip cells jumped over: a jump to time T lands exactly where the walk would be at T (the
// crossings before T are counted, not stepped), so jumping never changes the cells stored.
// A known obstacle nearer than min_range blocks the ray (the sensor then measures nothing);
// cells are observed from min_range on (a cell is observed if it is left after min_range).
// Resumable (one cell per advance()), so that two rays can be walked in one loop.
class RayWalker {
 public:
  RayWalker(const GridView& grid, std::span<const std::uint8_t> codes, const SkipBlocks& sb)
      : grid_(grid), w_(static_cast<unsigned>(grid.width)), h_(static_cast<unsigned>(grid.height)),
        logodds_(grid.logodds.data()), codes_(codes.data()), sb_(sb) {}

  /// Starts a ray; its cells are appended to out (which must have room for max_cells()).
  void start(const Eigen::Vector2f& o, const Eigen::Vector2f& d, float min_range, float max_range, RayCell* out) {
    out_ = out;
    n_ = 0;
    done_ = !w_walk_.init(grid_, o, d, 0.0f, max_range);
    if (done_) return;
    const double scale = 1.0 / w_walk_.inv_scale;
    t_min_ = static_cast<std::int64_t>(static_cast<double>(min_range) * scale + 0.5);
    jump_unit_ = static_cast<double>(grid_.resolution_m) * scale;  // one cell of travel [fixed point]
    inv_dx_ = 1.0 / static_cast<double>(w_walk_.dx);
    inv_dy_ = 1.0 / static_cast<double>(w_walk_.dy);
    ix0_ = w_walk_.ix;
    iy0_ = w_walk_.iy;
    mx0_ = w_walk_.mx;
    my0_ = w_walk_.my;
    t_now_ = 0;
    observing_ = false;
  }
  [[nodiscard]] bool done() const noexcept { return done_; }
  [[nodiscard]] std::size_t count() const noexcept { return n_; }
  /// Upper bound of the cells of one ray of length max_range [m] at resolution res [m].
  static std::size_t max_cells(float max_range, float res) {
    return static_cast<std::size_t>(2.0f * max_range / res) + 8;
  }

  /// Processes the current cell and moves to the next one.
  void advance() {
    detail::CellWalk& c = w_walk_;
    const bool inside = static_cast<unsigned>(c.ix) < w_ && static_cast<unsigned>(c.iy) < h_;
    const std::size_t idx = inside ? static_cast<std::size_t>(c.iy) * w_ + static_cast<unsigned>(c.ix) : 0;
    const std::uint32_t code = inside ? codes_[idx] : kUnknownNan + 1;
    if (!observing_) {
      const std::int64_t t_exit = c.next();
      observing_ = t_exit > t_min_ || t_exit >= c.end;
    }
    if (code == kSkipCode) {
      const std::uint8_t db = sb_.dist[static_cast<std::size_t>(c.iy >> kBlockShift) * static_cast<std::size_t>(sb_.bw) +
                                       static_cast<std::size_t>(c.ix >> kBlockShift)];
      if (db >= 2) {  // every cell within kBlock * (db - 1) cells is a skip cell: jump
        // Travelling kBlock * (db - 1) cells along the ray moves at most that far along each axis.
        const auto t = t_now_ + static_cast<std::int64_t>(static_cast<double>(kBlock * (db - 1)) * jump_unit_);
        if (t >= c.end) {
          done_ = true;
          return;
        }
        jump_to(t);
        observing_ = false;
        return;
      }
      if (inside) {  // tight loop over the following skip cells (most of the walk in known space)
        const std::int64_t sx = c.sx, sy = c.sy, step_y = c.sy * static_cast<std::int64_t>(w_);
        const std::int64_t dx = c.dx, dy = c.dy, end = c.end;
        const std::int64_t w = w_, h = h_;
        const std::uint8_t* const codes = codes_;
        auto i = static_cast<std::int64_t>(idx);
        std::int64_t mx = c.mx, my = c.my, ix = c.ix, iy = c.iy, t_now = t_now_;
        for (;;) {
          const std::int64_t tn = mx < my ? mx : my;
          if (tn >= end) {
            done_ = true;
            return;
          }
          t_now = tn;
          const bool bx = mx <= my, by = my <= mx;  // both on a tie
          ix += bx ? sx : 0;
          iy += by ? sy : 0;
          i += (bx ? sx : 0) + (by ? step_y : 0);
          mx += bx ? dx : 0;
          my += by ? dy : 0;
          if (static_cast<std::uint64_t>(ix) >= static_cast<std::uint64_t>(w) ||
              static_cast<std::uint64_t>(iy) >= static_cast<std::uint64_t>(h) || codes[i] != kSkipCode) {
            c.mx = mx;  // the next advance() handles this cell
            c.my = my;
            t_now_ = t_now;
            c.ix = static_cast<int>(ix);
            c.iy = static_cast<int>(iy);
            return;
          }
        }
      }
    } else if (observing_) {
      const std::uint32_t kind = code - 1;
      out_[n_++] = make_cell(inside ? static_cast<std::uint32_t>(idx) : kOutside, kind,
                             kind == kUnknownNan ? 0.0f : logodds_[idx]);
      if (kind == kOccupiedCell) {
        done_ = true;
        return;
      }
    } else if (code == kOccupiedCell + 1) {  // a known obstacle before min_range blocks the ray
      done_ = true;
      return;
    }
    const std::int64_t tn = c.next();
    if (tn >= c.end) {
      done_ = true;
      return;
    }
    t_now_ = tn;
    c.step();
  }

 private:
  /// Moves the walk to time t (fixed point, t_now_ <= t < end): every crossing at a time <= t is
  /// taken, counted by a division rounded in double and corrected exactly in integers.
  void jump_to(std::int64_t t) {
    detail::CellWalk& c = w_walk_;
    auto crossings = [t](std::int64_t m0, std::int64_t d, double inv_d) -> std::int64_t {
      if (t < m0) return 0;
      auto k = static_cast<std::int64_t>(static_cast<double>(t - m0) * inv_d) + 1;  // ~ crossings <= t
      while (k > 0 && m0 + (k - 1) * d > t) --k;
      while (m0 + k * d <= t) ++k;
      return k;
    };
    const std::int64_t kx = c.sx != 0 ? crossings(mx0_, c.dx, inv_dx_) : 0;
    const std::int64_t ky = c.sy != 0 ? crossings(my0_, c.dy, inv_dy_) : 0;
    c.ix = ix0_ + static_cast<int>(kx) * c.sx;
    c.iy = iy0_ + static_cast<int>(ky) * c.sy;
    c.mx = mx0_ + kx * c.dx;
    c.my = my0_ + ky * c.dy;
    t_now_ = t;
  }

  const GridView& grid_;
  unsigned w_, h_;
  const float* logodds_;
  const std::uint8_t* codes_;
  const SkipBlocks& sb_;
  RayCell* out_ = nullptr;
  std::size_t n_ = 0;
  detail::CellWalk w_walk_;
  std::int64_t t_now_ = 0, t_min_ = 0, mx0_ = 0, my0_ = 0;
  double jump_unit_ = 0.0, inv_dx_ = 0.0, inv_dy_ = 0.0;
  int ix0_ = 0, iy0_ = 0;
  bool done_ = true, observing_ = false;
};

// Each sensor's ray directions in the robot frame (detail::fan_directions, the fan of
// sector_rays() at theta = 0); a pose's rays are these turned by its heading.
std::vector<std::vector<Eigen::Vector2f>> robot_fans(std::span<const SensorSector> sensors) {
  std::vector<std::vector<Eigen::Vector2f>> fans(sensors.size());
  for (std::size_t i = 0; i < sensors.size(); ++i) fans[i] = detail::fan_directions(sensors[i]);
  return fans;
}

void precompute_rays(const GridView& grid, std::span<const std::uint8_t> codes, const SkipBlocks& sb, std::span<const Pose2> x,
                     std::span<const SensorSector> sensors, std::span<const std::vector<Eigen::Vector2f>> fans, ThreadScratch& ts) {
  ts.cells.clear();
  ts.ray_end.clear();
  RayWalker a(grid, codes, sb), b(grid, codes, sb);
  for (const Pose2& pose : x) {
    const float c = std::cos(pose.theta), sn = std::sin(pose.theta);
    for (std::size_t si = 0; si < sensors.size(); ++si) {
      const SensorSector& sec = sensors[si];
      const auto nr = static_cast<std::size_t>(sec.rays);
      ts.dirs.resize(nr);
      const Eigen::Vector2f org = detail::fan_origin(pose, sec, c, sn);
      for (std::size_t r = 0; r < nr; ++r) ts.dirs[r] = detail::turn(c, sn, fans[si][r]);
      const std::size_t cap = RayWalker::max_cells(sec.max_range_m, grid.resolution_m);
      if (ts.pair_buffer.size() < 2 * cap) ts.pair_buffer.resize(2 * cap);
      for (std::size_t r = 0; r < nr; r += 2) {
        const bool two = r + 1 < nr;
        a.start(org, ts.dirs[r], sec.min_range_m, sec.max_range_m, ts.pair_buffer.data());
        if (two) b.start(org, ts.dirs[r + 1], sec.min_range_m, sec.max_range_m, ts.pair_buffer.data() + cap);
        while (!a.done() && two && !b.done()) {
          a.advance();
          b.advance();
        }
        while (!a.done()) a.advance();
        while (two && !b.done()) b.advance();
        ts.cells.insert(ts.cells.end(), ts.pair_buffer.data(), ts.pair_buffer.data() + a.count());
        ts.ray_end.push_back(static_cast<std::uint32_t>(ts.cells.size()));
        if (two) {
          ts.cells.insert(ts.cells.end(), ts.pair_buffer.data() + cap, ts.pair_buffer.data() + cap + b.count());
          ts.ray_end.push_back(static_cast<std::uint32_t>(ts.cells.size()));
        }
      }
    }
  }
}

// Per-cell code of the precomputed walks: kind + 1, or kSkipCode for a known-free cell at exactly
// min_logodds: a miss keeps it at the clamp for any noise (l_ISM < 0), so its reward is exactly 0
// and it never stops a ray - leaving it out changes no result and saves most of the work in
// well-observed space.
void build_codes(const ObservationModel& model, float clamp_min, std::vector<std::uint8_t>& codes) {
  const auto logodds = model.grid().logodds;
  const auto states = model.states();
  codes.resize(logodds.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, logodds.size(), 1 << 14), [&](const tbb::blocked_range<std::size_t>& rg) {
    for (std::size_t i = rg.begin(); i != rg.end(); ++i) {
      const float l = logodds[i];
      std::uint32_t kind;
      switch (states[i]) {
        case CellState::kOccupied: kind = kOccupiedCell; break;
        case CellState::kFree: kind = kFreeCell; break;
        default: kind = std::isnan(l) ? kUnknownNan : kUnknownFinite; break;
      }
      codes[i] = static_cast<std::uint8_t>(kind == kFreeCell && l == clamp_min ? kSkipCode : kind + 1);
    }
  });
}

// Lines 10-17 and 19 for one particle whose rays are in ts: returns log(prod_j sum_t gamma^(t-H) R_tj)
// and the mean undiscounted reward.
void observe_particle(const ObservationModel& model, std::span<const SensorSector> sensors, const PartialSimSettings& s,
                      int phi, detail::Rng& rng, ThreadScratch& ts, Particle& part) {
  const EntropyTable& et = entropy_table();
  const std::size_t n_cells = model.grid().logodds.size();
  const int H = s.stages;
  std::size_t rays_per_stage = 0;
  for (const SensorSector& sec : sensors) rays_per_stage += static_cast<std::size_t>(sec.rays);
  const float inv_log_q = 1.0f / std::log1p(-s.unknown_hit_probability);

  double log_w = 0.0;
  double reward_sum = 0.0;
  std::int64_t visits = 0;
  for (int j = 0; j < phi; ++j) {
    const std::uint32_t stamp = ts.next_stamp(n_cells);
    std::uint32_t* ov = ts.overlay.data();
    double disc_sum = 0.0;
    for (int k = 0; k < H; ++k) {
      const float delta = s.ism_noise_logodds > 0.0f ? rng.uniform(-s.ism_noise_logodds, s.ism_noise_logodds) : 0.0f;
      const float l_hit = s.hit_logodds + delta, l_miss = s.miss_logodds + delta;  // line 14
      // Lines 15-16 for a never-observed cell (prior 0, E = 1 bit), the same for all of them.
      const float r_hit_nan = 1.0f - et(std::clamp(l_hit, s.min_logodds, s.max_logodds));
      const float r_miss_nan = 1.0f - et(std::clamp(l_miss, s.min_logodds, s.max_logodds));
      float r_k = 0.0f;
      for (std::size_t r = 0; r < rays_per_stage; ++r) {
        const std::size_t ray = static_cast<std::size_t>(k) * rays_per_stage + r;
        const std::uint32_t begin = ray == 0 ? 0u : ts.ray_end[ray - 1];
        const std::uint32_t end = ts.ray_end[ray];
        // z ~ chi (line 13): the number of unknown cells passed before a sampled hit is geometric.
        // u is drawn for every ray (the stream does not depend on the cells), its log only when
        // the ray meets an unknown cell (most rays end on a known wall): unknown_left < 0 = not yet.
        const float u = 1.0f - rng.uniform01();  // (0, 1]
        std::int64_t unknown_left = -1;
        for (std::uint32_t c = begin; c < end; ++c) {
          const RayCell cell = ts.cells[c];
          const std::uint32_t kind = cell.packed & 3u;
          const std::uint32_t idx = cell.packed >> 2;
          ++visits;
          if (idx != kOutside) {
            const std::uint32_t o = ov[idx];
            if ((o >> 1) == stamp) {  // observed earlier in this sample: not counted again
              if (o & 1u) break;      // sampled occupied: stops this ray too
              continue;
            }
          }
          bool hit;
          if (kind == kOccupiedCell) {
            hit = true;
          } else if (kind == kFreeCell) {
            hit = false;
          } else {
            if (unknown_left < 0) {
              const float g = std::log(u) * inv_log_q;  // >= 0: truncation is the floor
              unknown_left = g < 1e9f ? static_cast<std::int64_t>(g) : std::numeric_limits<std::int64_t>::max();
            }
            hit = unknown_left == 0;
            --unknown_left;
          }
          if (kind == kUnknownNan) {
            r_k += hit ? r_hit_nan : r_miss_nan;  // 1 bit - E(clamp(l_ISM))
          } else {
            const float post = std::clamp(cell.l + (hit ? l_hit : l_miss), s.min_logodds, s.max_logodds);  // line 15
            r_k += et(cell.l) - et(post);  // line 16
          }
          if (idx != kOutside) ov[idx] = (stamp << 1) | (hit ? 1u : 0u);
          if (hit) break;
        }
      }
      disc_sum += std::pow(static_cast<double>(s.gamma), static_cast<double>(k - H)) * r_k;  // line 19 term
      reward_sum += r_k;
    }
    log_w += disc_sum > 0.0 ? std::log(disc_sum) : -std::numeric_limits<double>::infinity();
  }
  part.log_w += log_w;
  part.reward_mean = static_cast<float>(reward_sum / phi);
  part.visits = visits;
}

}  // namespace

PartialSimResult partial_map_simulation(const ObservationModel& model, const InflatedGrid& inflated,
                                        const Pose2& robot, std::span<const SensorSector> sensors,
                                        const PartialSimSettings& s, PartialSimWorkspace& workspace) {
  validate(s);
  if (sensors.empty()) fail(ErrorCode::kInvalidArgument, "partial_map_simulation: no sensors");
  for (const SensorSector& sec : sensors) validate(sec);
  if (!std::isfinite(robot.x) || !std::isfinite(robot.y) || !std::isfinite(robot.theta))
    fail(ErrorCode::kInvalidArgument, "partial_map_simulation: robot pose is not finite");
  const GridView& grid = model.grid();
  if (grid.width != inflated.width || grid.height != inflated.height || grid.resolution_m != inflated.resolution_m ||
      grid.origin != inflated.origin)
    fail(ErrorCode::kInvalidArgument,
         "partial_map_simulation: the observation model's grid (" + std::to_string(grid.width) + " x " +
             std::to_string(grid.height) + ") and the inflated grid (" + std::to_string(inflated.width) + " x " +
             std::to_string(inflated.height) + ") differ in geometry");
  if (grid.cell_count() >= (std::size_t{1} << 30))
    fail(ErrorCode::kOutOfRange, "partial_map_simulation: grids of 2^30 cells or more are not supported");

  auto& ws = workspace.impl();
  build_codes(model, s.min_logodds, ws.codes);
  build_skip_blocks(grid, ws.codes, ws.skip);
  const std::vector<std::vector<Eigen::Vector2f>> fans = robot_fans(sensors);
  const int N = s.particles, H = s.stages;
  const auto Nz = static_cast<std::size_t>(N), Hz = static_cast<std::size_t>(H);
  ws.particles.resize(Nz);
  for (Particle& p : ws.particles) {
    p.u.assign(Hz, Twist{});
    p.x.assign(Hz, robot);
    p.log_w = 0.0;
    p.valid = false;
    p.reward_mean = 0.0f;
    p.visits = 0;
  }
  PartialSimResult result;
  result.goal = robot;
  const Pose2 x0 = robot;  // line 1
  const float omega_max = s.omega_max_rps;

  bool weights_all_zero = false;
  for (int i = 1; i <= s.iterations; ++i) {  // line 2
    const int phi = s.phi_a * i + s.phi_b;
    tbb::parallel_for(tbb::blocked_range<int>(0, N, 1), [&](const tbb::blocked_range<int>& range) {
      ThreadScratch& ts = ws.scratch.local();
      for (int n = range.begin(); n != range.end(); ++n) {  // line 3
        Particle& part = ws.particles[static_cast<std::size_t>(n)];
        detail::Rng rng(detail::stream_seed(s.seed, static_cast<std::uint64_t>(i), static_cast<std::uint64_t>(n)));
        for (int k = 0; k < H; ++k) {
          Twist& u = part.u[static_cast<std::size_t>(k)];
          if (i == 1) {  // line 5: zeta_1 uniform over U_range
            u.v = rng.uniform(s.v_min_mps, s.v_max_mps);
            u.omega = rng.uniform(-omega_max, omega_max);
          } else {  // line 7: zeta_i normal around the particle's last motions, Sigma diagonal
            u.v = std::clamp(u.v + s.sigma_v_mps * rng.normal(), s.v_min_mps, s.v_max_mps);
            u.omega = std::clamp(u.omega + s.sigma_omega_rps * rng.normal(), -omega_max, omega_max);
          }
        }
        part.valid = rollout(inflated, x0, s, part.u, part.x);  // line 9
        part.reward_mean = 0.0f;
        part.visits = 0;
        if (!part.valid) {
          part.log_w = -std::numeric_limits<double>::infinity();
          continue;
        }
        precompute_rays(grid, ws.codes, ws.skip, part.x, sensors, fans, ts);
        observe_particle(model, sensors, s, phi, rng, ts, part);  // lines 10-19
      }
    });
    for (const Particle& p : ws.particles) result.cells_visited += p.visits;
    // Lines 21-23: normalisation (in the log domain, so long products cannot underflow).
    double max_lw = -std::numeric_limits<double>::infinity();
    for (const Particle& p : ws.particles) max_lw = std::max(max_lw, p.log_w);
    std::vector<double> w(Nz, 1.0 / N);
    weights_all_zero = !std::isfinite(max_lw);
    if (std::isfinite(max_lw)) {
      double sum = 0.0;
      for (std::size_t n = 0; n < Nz; ++n) sum += (w[n] = std::exp(ws.particles[n].log_w - max_lw));
      for (double& v : w) v /= sum;
    }
    double sum_sq = 0.0;
    for (double v : w) sum_sq += v * v;
    const bool last = i == s.iterations;
    if (!last && 1.0 / sum_sq < static_cast<double>(s.resample_ess_fraction) * N) {  // line 24
      // Line 25: systematic resampling; motions are copied, weights reset to 1/N.
      detail::Rng rng(detail::stream_seed(s.seed, static_cast<std::uint64_t>(i), ~0ull));
      const double step = 1.0 / N;
      double target = rng.uniform01_open0() * step, cum = w[0];
      std::size_t src = 0;
      ws.resampled.resize(Nz);
      for (std::size_t n = 0; n < Nz; ++n) {
        while (cum < target && src + 1 < Nz) cum += w[++src];
        ws.resampled[n] = ws.particles[src];
        ws.resampled[n].log_w = std::log(step);
        target += step;
      }
      std::swap(ws.particles, ws.resampled);
      ++result.resamples;
    } else {
      for (std::size_t n = 0; n < Nz; ++n) ws.particles[n].log_w = w[n] > 0.0 ? std::log(w[n]) : -std::numeric_limits<double>::infinity();
    }
    if (last) {
      result.weights.assign(w.begin(), w.end());
    }
  }

  // Lines 28-29: the particle of highest weight (lowest index on ties).
  std::size_t best = 0;
  for (std::size_t n = 1; n < Nz; ++n)
    if (result.weights[n] > result.weights[best]) best = n;
  for (const Particle& p : ws.particles) result.valid_particles += p.valid ? 1 : 0;
  if (weights_all_zero) {  // every weight of the last iteration was 0: rank by reward instead
    for (std::size_t n = 0; n < Nz; ++n) {
      const Particle& p = ws.particles[n];
      const Particle& b = ws.particles[best];
      if (p.valid && (!b.valid || p.reward_mean > b.reward_mean)) best = n;
    }
  }
  const Particle& pb = ws.particles[best];
  if (pb.valid && pb.reward_mean > 0.0f) {
    result.found = true;
    result.best_particle = static_cast<int>(best);
    result.goal = pb.x.back();
    result.reward_bits = pb.reward_mean;
    result.best_trajectory = pb.x;
    result.best_motions = pb.u;
  }
  return result;
}

}  // namespace duet
