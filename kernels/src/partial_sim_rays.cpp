/// @file partial_sim_rays.cpp
/// Partial map simulation's ray precomputation: the window of cells the rays can reach (codes,
/// stored cells, empty-space skipping blocks) and RayWalker.
#include "partial_sim_rays.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <duet/kernels/error.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <vector>

namespace duet::detail::partial_sim {

// Walks every ray of every stage once (the known part does not depend on j) and stores the cells:
// known-occupied cells end a ray; unknown and free cells are stored with their kind.
// Empty-space skipping for the walks: the window is cut into kBlock x kBlock blocks; dist[b] is
// the chessboard distance, in blocks, from block b to the nearest block that holds a cell that is
// not kSkipCode (or lies on the window's border). From a cell of a block with dist D >= 2 every cell
// within kBlock * (D - 1) cells (chessboard) is a skip cell, so a ray can jump that far at once.

namespace {

void build_skip_blocks(int w, int h, std::span<const std::uint8_t> codes, SkipBlocks& sb) {
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
  // Chessboard distance transform (two raster passes; outside the window counts as distance 0).
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

/// The margin in cells around a fan's origin that holds every cell its rays cross: a cell crossed
/// at a time t <= max_range is within max_range / resolution + 1 cells of the origin's cell along
/// each axis (+ 1 for CellWalk's choice of the lower cell on a boundary). add_ray_box() adds one
/// cell more, so that rounding in its own origin computation cannot matter.
int ray_reach_cells(float max_range_m, float resolution_m) {
  return static_cast<int>(std::ceil(static_cast<double>(max_range_m) / static_cast<double>(resolution_m))) + 2;
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
  RayWalker(const GridView& grid, const Window& win)
      : grid_(grid), win_(win), w_(static_cast<unsigned>(win.w)), cell_(win.cell.data()), codes_(win.codes.data()),
        sb_(win.skip) {}

  /// Starts a ray; its cells are appended to out (which must have room for max_cells()). reach:
  /// ray_reach_cells(max_range, resolution), the same for a fan's rays.
  void start(const Eigen::Vector2f& o, const Eigen::Vector2f& d, float min_range, float max_range, int reach, RayCell* out) {
    out_ = out;
    n_ = 0;
    done_ = !w_walk_.init(grid_, o, d, 0.0f, max_range);  // on the grid: the same cells as every other walk
    if (done_) return;
    w_walk_.ix -= win_.box.x0;  // to the window's cells (exact)
    w_walk_.iy -= win_.box.y0;
    if (w_walk_.ix < reach || w_walk_.iy < reach || w_walk_.ix + reach >= win_.w || w_walk_.iy + reach >= win_.h)
      fail(ErrorCode::kInternal, "partial_map_simulation: a ray from window cell (" + std::to_string(w_walk_.ix) + ", " +
                                     std::to_string(w_walk_.iy) + ") can leave the window of " + std::to_string(win_.w) + " x " +
                                     std::to_string(win_.h) + " cells");
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
    const std::size_t idx = static_cast<std::size_t>(c.iy) * w_ + static_cast<unsigned>(c.ix);  // in the window (start())
    const std::uint32_t code = codes_[idx];
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
      {  // tight loop over the following skip cells (most of the walk in known space)
        const std::int64_t sx = c.sx, step_y = c.sy * static_cast<std::int64_t>(w_);
        const std::int64_t dx = c.dx, dy = c.dy, end = c.end;
        const std::uint8_t* const codes = codes_;
        auto i = static_cast<std::int64_t>(idx);
        std::int64_t mx = c.mx, my = c.my, t_now = t_now_;
        for (;;) {
          const std::int64_t tn = mx < my ? mx : my;
          if (tn >= end) {
            done_ = true;
            return;
          }
          t_now = tn;
          step_indexed(i, mx, my, sx, step_y, dx, dy);
          if (codes[i] != kSkipCode) {
            keep(mx, my, i, t_now);  // the next advance() handles this cell
            return;
          }
        }
      }
    } else if (observing_) {
      store_run();
      return;
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
  /// detail::CellWalk::step on locals, on the cell's window index i = iy * w + ix alone (step_y =
  /// sy * w; keep() gives ix and iy back): the hot loops of advance() and store_run(), which then
  /// keep fewer values in registers.
  static void step_indexed(std::int64_t& i, std::int64_t& mx, std::int64_t& my, std::int64_t sx, std::int64_t step_y,
                           std::int64_t dx, std::int64_t dy) noexcept {
    const bool bx = mx <= my, by = my <= mx;  // both on a tie
    i += (bx ? sx : 0) + (by ? step_y : 0);
    mx += bx ? dx : 0;
    my += by ? dy : 0;
  }

  /// Stores the current cell (observed, not a skip cell) and those after it, in a loop over
  /// locals like the skip loop in advance(): the walk is past min_range, so every cell from here
  /// on is observed. Ends the ray at a known obstacle or at max_range, or stops on a skip cell,
  /// which the next advance() handles (its jump test). The same cells as one advance() per cell
  /// (measured on Willow: ~35 of a ray's ~42 cells are stored).
  void store_run() {
    detail::CellWalk& c = w_walk_;
    const std::int64_t sx = c.sx, step_y = c.sy * static_cast<std::int64_t>(w_);
    const std::int64_t dx = c.dx, dy = c.dy, end = c.end;
    const std::uint8_t* const codes = codes_;
    const RayCell* const cell = cell_;
    RayCell* const out = out_;
    std::size_t n = n_;
    std::int64_t mx = c.mx, my = c.my, t_now = t_now_;
    std::int64_t i = static_cast<std::int64_t>(c.iy) * static_cast<std::int64_t>(w_) + c.ix;
    for (;;) {
      const std::uint32_t code = codes[i];
      if (code == kSkipCode) break;
      out[n++] = cell[i];
      if (code == kOccupiedCell + 1) {
        done_ = true;
        break;
      }
      const std::int64_t tn = mx < my ? mx : my;
      if (tn >= end) {
        done_ = true;
        break;
      }
      t_now = tn;
      step_indexed(i, mx, my, sx, step_y, dx, dy);
    }
    n_ = n;
    keep(mx, my, i, t_now);
  }

  /// Puts the walk state a hot loop kept in locals (i: the window index) back into the walk.
  void keep(std::int64_t mx, std::int64_t my, std::int64_t i, std::int64_t t_now) noexcept {
    const auto u = static_cast<std::uint64_t>(i);  // >= 0: the walk is in the window
    w_walk_.mx = mx;
    w_walk_.my = my;
    w_walk_.iy = static_cast<int>(u / w_);
    w_walk_.ix = static_cast<int>(u - static_cast<std::uint64_t>(w_walk_.iy) * w_);
    t_now_ = t_now;
  }

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
  const Window& win_;
  unsigned w_;
  const RayCell* cell_;
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

}  // namespace

void add_ray_box(const GridView& grid, std::span<const Pose2> x, std::span<const SensorSector> sensors, CellBox& box) {
  const double res = grid.resolution_m;
  for (const Pose2& pose : x) {
    const float c = std::cos(pose.theta), sn = std::sin(pose.theta);  // as precompute_rays()
    for (const SensorSector& sec : sensors) {
      const Eigen::Vector2f o = detail::fan_origin(pose, sec, c, sn);
      const double px = (static_cast<double>(o.x()) - static_cast<double>(grid.origin.x())) / res;
      const double py = (static_cast<double>(o.y()) - static_cast<double>(grid.origin.y())) / res;
      if (!(std::fabs(px) < 1e9) || !(std::fabs(py) < 1e9)) continue;  // CellWalk::init refuses it: nothing is walked
      const int ix = static_cast<int>(std::floor(px)), iy = static_cast<int>(std::floor(py));
      const int r = ray_reach_cells(sec.max_range_m, grid.resolution_m) + 1;
      box.add(CellBox{ix - r, iy - r, ix + r, iy + r});
    }
  }
}

// The window's per-cell codes: kind + 1, or kSkipCode for a known-free cell at exactly
// min_logodds: a miss keeps it at the clamp for any noise (l_ISM < 0), so its reward is exactly 0
// and it never stops a ray - leaving it out changes no result and saves most of the work in
// well-observed space. Cells outside the grid: kOutsideCode.
void build_window(const ObservationModel& model, float clamp_min, const CellBox& box, Window& win) {
  if (box.cells() >= (std::int64_t{1} << 30))
    fail(ErrorCode::kOutOfRange, "partial_map_simulation: the simulated rays reach a box of " + std::to_string(box.x1 - box.x0 + 1) +
                                     " x " + std::to_string(box.y1 - box.y0 + 1) +
                                     " cells, 2^30 or more (lower the sensors' max_range_m or the motions' reach)");
  const GridView& grid = model.grid();
  const auto logodds = grid.logodds;
  const auto states = model.states();
  const EntropyTable& et = entropy_table();
  win.box = box;
  win.w = box.empty() ? 0 : box.x1 - box.x0 + 1;
  win.h = box.empty() ? 0 : box.y1 - box.y0 + 1;
  win.codes.resize(win.cells());
  win.cell.resize(win.cells());
  tbb::parallel_for(tbb::blocked_range<int>(0, win.h, 16), [&](const tbb::blocked_range<int>& rg) {
    for (int y = rg.begin(); y != rg.end(); ++y) {
      const int gy = box.y0 + y;
      const std::size_t row = static_cast<std::size_t>(y) * static_cast<std::size_t>(win.w);
      for (int x = 0; x < win.w; ++x) {
        const int gx = box.x0 + x;
        std::uint8_t& code = win.codes[row + static_cast<std::size_t>(x)];
        RayCell& cell = win.cell[row + static_cast<std::size_t>(x)];
        if (gx < 0 || gy < 0 || gx >= grid.width || gy >= grid.height) {
          code = static_cast<std::uint8_t>(kOutsideCode);
          cell = RayCell{(kOutside << 2) | kUnknownNan, 0.0f, 0.0f};
          continue;
        }
        const std::size_t i = static_cast<std::size_t>(gy) * static_cast<std::size_t>(grid.width) + static_cast<std::size_t>(gx);
        const float l = logodds[i];
        std::uint32_t kind;
        switch (states[i]) {
          case CellState::kOccupied: kind = kOccupiedCell; break;
          case CellState::kFree: kind = kFreeCell; break;
          default: kind = std::isnan(l) ? kUnknownNan : kUnknownFinite; break;
        }
        code = static_cast<std::uint8_t>(kind == kFreeCell && l == clamp_min ? kSkipCode : kind + 1);
        const auto packed = (static_cast<std::uint32_t>(row + static_cast<std::size_t>(x)) << 2) | kind;
        // (a skip cell is never stored: its E(l) is not needed, and most cells of a mapped area are such)
        cell = kind == kUnknownNan || code == kSkipCode ? RayCell{packed, 0.0f, 0.0f} : RayCell{packed, l, et(l)};
      }
    }
  });
  build_skip_blocks(win.w, win.h, win.codes, win.skip);
}

void precompute_rays(const GridView& grid, const Window& win, std::span<const Pose2> x, std::span<const SensorSector> sensors,
                     std::span<const std::vector<Eigen::Vector2f>> fans, ThreadScratch& ts) {
  ts.cells.clear();
  ts.ray_end.clear();
  RayWalker a(grid, win), b(grid, win);
  for (const Pose2& pose : x) {
    const float c = std::cos(pose.theta), sn = std::sin(pose.theta);
    for (std::size_t si = 0; si < sensors.size(); ++si) {
      const SensorSector& sec = sensors[si];
      const auto nr = static_cast<std::size_t>(sec.rays);
      ts.dirs.resize(nr);
      const Eigen::Vector2f org = detail::fan_origin(pose, sec, c, sn);
      for (std::size_t r = 0; r < nr; ++r) ts.dirs[r] = detail::turn(c, sn, fans[si][r]);
      const std::size_t cap = RayWalker::max_cells(sec.max_range_m, grid.resolution_m);
      const int reach = ray_reach_cells(sec.max_range_m, grid.resolution_m);
      for (std::size_t r = 0; r < nr; r += 2) {
        const bool two = r + 1 < nr;
        RayCell* const out = ts.cells.room(2 * cap);  // ray a's cells in place, b's after a's room
        a.start(org, ts.dirs[r], sec.min_range_m, sec.max_range_m, reach, out);
        if (two) b.start(org, ts.dirs[r + 1], sec.min_range_m, sec.max_range_m, reach, out + cap);
        while (!a.done() && two && !b.done()) {
          a.advance();
          b.advance();
        }
        while (!a.done()) a.advance();
        while (two && !b.done()) b.advance();
        ts.cells.keep(a.count());
        ts.ray_end.push_back(static_cast<std::uint32_t>(ts.cells.size()));
        if (two) {
          std::memmove(out + a.count(), out + cap, b.count() * sizeof(RayCell));  // down to follow a's
          ts.cells.keep(b.count());
          ts.ray_end.push_back(static_cast<std::uint32_t>(ts.cells.size()));
        }
      }
    }
  }
}

}  // namespace duet::detail::partial_sim
