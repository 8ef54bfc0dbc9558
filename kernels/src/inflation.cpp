#include <duet/kernels/error.hpp>
#include <duet/kernels/inflation.hpp>

#include "parallel.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace duet {

void validate(const InflationSettings& s) {
  validate(s.thresholds);
  if (!std::isfinite(s.robot_radius_m) || !(s.robot_radius_m >= 0.0f))
    fail(ErrorCode::kInvalidArgument,
         "InflationSettings.robot_radius_m must be finite and >= 0 [m], got " + std::to_string(s.robot_radius_m));
}

namespace {

constexpr float kUnreached = std::numeric_limits<float>::infinity();
constexpr std::size_t kColumnBlock = 128;  // columns per task of the vertical pass (fixed: thread-count independent)

/// 1D squared-distance transform of one row (Felzenszwalb & Huttenlocher, lower envelope of the
/// parabolas (x - p)^2 + f[p] over the columns p with a finite f), in exact integer arithmetic.
/// col_d[x] = vertical distance in cells (float holding an integer, or +inf); writes the squared
/// 2D distance in cells to d2[x] (-1 = none).
void row_transform(const float* col_d, int w, std::int64_t* d2, int* v, std::int64_t* F) {
  int k = -1;  // index of the rightmost parabola of the envelope
  for (int q = 0; q < w; ++q) {
    if (!(col_d[q] < kUnreached)) continue;
    const auto g = static_cast<std::int64_t>(col_d[q]);
    const std::int64_t Fq = g * g + static_cast<std::int64_t>(q) * q;
    // Pop parabolas hidden by q: s(q, v[k]) <= s(v[k], v[k-1]), compared by cross-multiplication
    // (s(a, b) = (F_a - F_b) / (2 (a - b)), all denominators positive).
    while (k >= 1) {
      const int p = v[k], r = v[k - 1];
      if ((Fq - F[k]) * (p - r) <= (F[k] - F[k - 1]) * (q - p)) --k;
      else break;
    }
    ++k;
    v[k] = q;
    F[k] = Fq;
  }
  if (k < 0) {
    for (int q = 0; q < w; ++q) d2[q] = -1;
    return;
  }
  int j = 0;
  for (int q = 0; q < w; ++q) {
    // Advance while the next parabola's region starts at or before q: s(v[j+1], v[j]) <= q.
    while (j < k && (F[j + 1] - F[j]) <= 2 * static_cast<std::int64_t>(q) * (v[j + 1] - v[j])) ++j;
    const std::int64_t dx = q - v[j];
    d2[q] = dx * dx + (F[j] - static_cast<std::int64_t>(v[j]) * v[j]);
  }
}

}  // namespace

void inflate(const GridView& grid, const InflationSettings& s, InflatedGrid& out) {
  validate(grid, "inflate: grid");
  validate(s);
  const std::size_t n = grid.cell_count();
  if (n >= (std::size_t{1} << 31))
    fail(ErrorCode::kOutOfRange, "inflate: grid of " + std::to_string(n) + " cells, at most 2^31 - 1 supported");
  out.width = grid.width;
  out.height = grid.height;
  out.resolution_m = grid.resolution_m;
  out.origin = grid.origin;
  out.robot_radius_m = s.robot_radius_m;
  out.state.resize(n);
  out.clearance_m.resize(n);
  out.traversable.resize(n);
  if (n == 0) return;

  const int w = grid.width, h = grid.height;
  const std::size_t sw = static_cast<std::size_t>(w);
  const float* lo = grid.logodds.data();
  CellState* st = out.state.data();
  float* cl = out.clearance_m.data();
  std::uint8_t* tr = out.traversable.data();
  const CellThresholds t = s.thresholds;
  const bool unknown_blocks = s.unknown_is_obstacle;
  const bool uncertain_blocks = s.uncertain_is_obstacle;

  // Pass 1: classification and the vertical 1D distance (in cells, +inf = none in the column),
  // parallel over fixed blocks of columns, each swept row by row (sequential memory per row).
  detail::for_blocks(sw, kColumnBlock, [&](std::size_t, std::size_t x0, std::size_t x1) {
    for (int y = 0; y < h; ++y) {
      const std::size_t row = static_cast<std::size_t>(y) * sw;
      const float* prev = y > 0 ? cl + row - sw : nullptr;
      for (std::size_t x = x0; x < x1; ++x) {
        const float l = lo[row + x];
        const CellState c = classify(l, t);
        st[row + x] = c;
        const bool blocked = c == CellState::kOccupied ||
                             (c == CellState::kUnknown && (std::isnan(l) ? unknown_blocks : uncertain_blocks));
        cl[row + x] = blocked ? 0.0f : (prev ? prev[x] + 1.0f : kUnreached);
      }
    }
    for (int y = h - 2; y >= 0; --y) {
      const std::size_t row = static_cast<std::size_t>(y) * sw;
      for (std::size_t x = x0; x < x1; ++x) cl[row + x] = std::min(cl[row + x], cl[row + sw + x] + 1.0f);
    }
  });

  // Pass 2: along every row, the lower envelope of parabolas; then clearance and traversable.
  const double res = grid.resolution_m;
  const float radius = s.robot_radius_m;
  tbb::parallel_for(tbb::blocked_range<int>(0, h, 8), [&](const tbb::blocked_range<int>& r) {
    std::vector<std::int64_t> d2(sw), F(sw);
    std::vector<int> v(sw);
    for (int y = r.begin(); y != r.end(); ++y) {
      const std::size_t row = static_cast<std::size_t>(y) * sw;
      row_transform(cl + row, w, d2.data(), v.data(), F.data());
      for (int x = 0; x < w; ++x) {
        const std::size_t i = row + static_cast<std::size_t>(x);
        const float c = d2[x] < 0 ? kUnreached : static_cast<float>(res * std::sqrt(static_cast<double>(d2[x])));
        cl[i] = c;
        tr[i] = static_cast<std::uint8_t>(st[i] == CellState::kFree && c > radius);
      }
    }
  });
}

}  // namespace duet

namespace duet {

void validate(const InflatedGrid& g, const char* what) {
  const std::string name = what ? what : "InflatedGrid";
  if (g.width < 0 || g.height < 0)
    fail(ErrorCode::kInvalidArgument, name + ": negative size " + std::to_string(g.width) + " x " + std::to_string(g.height));
  const std::size_t n = g.cell_count();
  if (g.state.size() != n || g.clearance_m.size() != n || g.traversable.size() != n)
    fail(ErrorCode::kInvalidArgument, name + ": state/clearance_m/traversable must have width*height = " +
                                          std::to_string(n) + " entries (use inflate() to fill it)");
  if (n >= (std::size_t{1} << 31))
    fail(ErrorCode::kOutOfRange, name + ": " + std::to_string(n) + " cells, at most 2^31 - 1 supported");
  if (!std::isfinite(g.resolution_m) || !(g.resolution_m > 0.0f))
    fail(ErrorCode::kInvalidArgument, name + ": resolution_m must be finite and > 0, got " + std::to_string(g.resolution_m));
  if (!std::isfinite(g.origin.x()) || !std::isfinite(g.origin.y()))
    fail(ErrorCode::kInvalidArgument, name + ": origin must be finite");
}

}  // namespace duet
