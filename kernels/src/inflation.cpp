#include <duet/kernels/error.hpp>
#include <duet/kernels/inflation.hpp>

#include "parallel.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <emmintrin.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>
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

/// Pass 1 of inflate() for 4 cells of a row in SSE2: their classify() states and their vertical
/// distance from the row below (0 where blocked, prev + 1 else, +inf without a previous row) -
/// the scalar loop's results bit for bit (NaN compares false in both; prev + 1 is one IEEE add).
void classify_block(const float* l4, const float* prev4, const CellThresholds& t, bool unknown_blocks, bool uncertain_blocks,
                    CellState* st4, float* cl4) {
  const __m128 l = _mm_loadu_ps(l4);
  const __m128 occ = _mm_cmpge_ps(l, _mm_set1_ps(t.occupied_logodds));  // false for NaN
  const __m128 fr = _mm_cmple_ps(l, _mm_set1_ps(t.free_logodds));        // false for NaN
  const __m128 nan = _mm_cmpunord_ps(l, l);
  const __m128 unk = _mm_andnot_ps(_mm_or_ps(occ, fr), _mm_castsi128_ps(_mm_set1_epi32(-1)));
  const __m128 ub = _mm_castsi128_ps(_mm_set1_epi32(unknown_blocks ? -1 : 0));
  const __m128 cb = _mm_castsi128_ps(_mm_set1_epi32(uncertain_blocks ? -1 : 0));
  const __m128 blocked = _mm_or_ps(occ, _mm_and_ps(unk, _mm_or_ps(_mm_and_ps(nan, ub), _mm_andnot_ps(nan, cb))));
  const __m128 up = prev4 ? _mm_add_ps(_mm_loadu_ps(prev4), _mm_set1_ps(1.0f)) : _mm_set1_ps(kUnreached);
  _mm_storeu_ps(cl4, _mm_andnot_ps(blocked, up));
  // kOccupied = 2, kUnknown = 1, kFree = 0: minus the sum of the all-ones masks occ and (occ | unk).
  const __m128i s32 = _mm_sub_epi32(_mm_setzero_si128(), _mm_add_epi32(_mm_castps_si128(occ), _mm_castps_si128(_mm_or_ps(occ, unk))));
  const __m128i s16 = _mm_packs_epi32(s32, s32);
  const std::uint32_t packed = static_cast<std::uint32_t>(_mm_cvtsi128_si32(_mm_packus_epi16(s16, s16)));
  std::memcpy(st4, &packed, 4);
}

/// Lower envelope of the parabolas (x - p)^2 + f[p] of one row (Felzenszwalb & Huttenlocher)
/// over the columns p with a finite f = col_d[p] (vertical distance in cells, a float holding an
/// integer, or +inf), in exact integer arithmetic: v[0..k] the parabolas' columns, F[j] =
/// f^2 + v^2. Returns k (-1: no finite f in the row). Left out: the parabola of a column q
/// inside the row whose f is at least both neighbours' - on the left of q its left neighbour's
/// parabola is at least as low ((x-q+1)^2 + f[q-1]^2 <= (x-q)^2 + f[q]^2 for x <= q-1), on the
/// right its right neighbour's, and at q itself q's own value f[q]^2, which the caller takes as
/// a floor (row_distances); by induction along a run of such columns, every value the left-out
/// parabolas would give is matched by a kept one or by a cell's own f^2. The two ends of the row
/// are always kept. Most cells of a map where unknown space blocks are inside runs of f = 0.
int lower_envelope(const float* col_d, int w, int* v, std::int64_t* F) {
  int k = -1;  // index of the rightmost parabola of the envelope
  for (int q = 0; q < w; ++q) {
    const float f = col_d[q];
    if (!(f < kUnreached)) continue;
    if (q > 0 && q + 1 < w && f >= col_d[q - 1] && f >= col_d[q + 1]) continue;  // dominated (above)
    const auto g = static_cast<std::int64_t>(f);
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
  return k;
}

/// ceil(a / b) for b > 0.
std::int64_t ceil_div(std::int64_t a, std::int64_t b) { return a >= 0 ? (a + b - 1) / b : -((-a) / b); }

/// Squared 2D distances in cells of one row from its envelope (lower_envelope, k >= 0), at most
/// each cell's own f^2: each parabola j covers the columns from its left boundary with j - 1 up
/// to the first column q with (F[j+1] - F[j]) <= 2 q (v[j+1] - v[j]).
template <typename D>
void row_distances(const float* col_d, int w, const int* v, const std::int64_t* F, int k, D* d2) {
  int q = 0;
  for (int j = 0; j <= k; ++j) {
    int end = w;
    if (j < k) end = static_cast<int>(std::clamp<std::int64_t>(ceil_div(F[j + 1] - F[j], 2 * static_cast<std::int64_t>(v[j + 1] - v[j])), q, w));
    const std::int64_t vj = v[j], g2 = F[j] - vj * vj;
    for (; q < end; ++q) d2[q] = static_cast<D>((q - vj) * (q - vj) + g2);
  }
  for (int x = 0; x < w; ++x)
    if (col_d[x] < kUnreached) d2[x] = std::min(d2[x], static_cast<D>(static_cast<std::int64_t>(col_d[x]) * static_cast<std::int64_t>(col_d[x])));
}

/// One byte per bit of a 4-bit mask (byte u = bit u).
constexpr std::uint32_t kMaskBytes[16] = {0x00000000u, 0x00000001u, 0x00000100u, 0x00000101u, 0x00010000u, 0x00010001u,
                                          0x00010100u, 0x00010101u, 0x01000000u, 0x01000001u, 0x01000100u, 0x01000101u,
                                          0x01010000u, 0x01010001u, 0x01010100u, 0x01010101u};
static_assert(static_cast<int>(CellState::kFree) == 0 && static_cast<int>(CellState::kUnknown) == 1 && static_cast<int>(CellState::kOccupied) == 2,
              "clearance_row's free test assumes these values");

/// clearance = float(res * sqrt(double(d2))) and traversable = free && clearance > radius for
/// one row; with int32 distances 4 cells at a time in SSE2 (exactly the scalar operations: int ->
/// double is exact, sqrt and the products are IEEE-rounded the same way in either form).
template <typename D>
void clearance_row(const D* d2, const CellState* st, int w, double res, float radius, float* cl, std::uint8_t* tr) {
  int x = 0;
  if constexpr (std::is_same_v<D, std::int32_t>) {
    const __m128d r = _mm_set1_pd(res);
    const __m128 rad = _mm_set1_ps(radius);
    for (; x + 4 <= w; x += 4) {
      const __m128i d = _mm_loadu_si128(reinterpret_cast<const __m128i*>(d2 + x));
      const __m128d lo = _mm_mul_pd(r, _mm_sqrt_pd(_mm_cvtepi32_pd(d)));
      const __m128d hi = _mm_mul_pd(r, _mm_sqrt_pd(_mm_cvtepi32_pd(_mm_shuffle_epi32(d, 0xEE))));
      const __m128 c = _mm_movelh_ps(_mm_cvtpd_ps(lo), _mm_cvtpd_ps(hi));
      _mm_storeu_ps(cl + x, c);
      std::uint32_t s;
      std::memcpy(&s, st + x, 4);
      const std::uint32_t free = ~(s | (s >> 1)) & 0x01010101u;  // 1 in the bytes that are kFree (0)
      const std::uint32_t t = free & kMaskBytes[_mm_movemask_ps(_mm_cmpgt_ps(c, rad))];
      std::memcpy(tr + x, &t, 4);
    }
  }
  for (; x < w; ++x) {
    const float c = static_cast<float>(res * std::sqrt(static_cast<double>(d2[x])));
    cl[x] = c;
    tr[x] = static_cast<std::uint8_t>(st[x] == CellState::kFree && c > radius);
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
    const std::size_t xv = x0 + ((x1 - x0) & ~std::size_t{3});  // the SSE2 part: 4 columns at a time
    for (int y = 0; y < h; ++y) {
      const std::size_t row = static_cast<std::size_t>(y) * sw;
      const float* prev = y > 0 ? cl + row - sw : nullptr;
      for (std::size_t x = x0; x < xv; x += 4) classify_block(lo + row + x, prev ? prev + x : nullptr, t, unknown_blocks, uncertain_blocks, st + row + x, cl + row + x);
      for (std::size_t x = xv; x < x1; ++x) {
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
  // Squared distances in int32 (and the SSE2 rows) when every one fits, which any grid under
  // 32768 cells a side does; else in int64, one cell at a time.
  const double res = grid.resolution_m;
  const float radius = s.robot_radius_m;
  const bool narrow = static_cast<double>(w - 1) * (w - 1) + static_cast<double>(h - 1) * (h - 1) < 2147483647.0;
  tbb::parallel_for(tbb::blocked_range<int>(0, h, 8), [&](const tbb::blocked_range<int>& r) {
    std::vector<std::int64_t> F(sw);
    std::vector<int> v(sw);
    std::vector<std::int32_t> d2n(narrow ? sw : 0);
    std::vector<std::int64_t> d2w(narrow ? 0 : sw);
    for (int y = r.begin(); y != r.end(); ++y) {
      const std::size_t row = static_cast<std::size_t>(y) * sw;
      const int k = lower_envelope(cl + row, w, v.data(), F.data());
      if (k < 0) {  // no blocked cell in the row's columns: every clearance is +inf
        for (std::size_t x = 0; x < sw; ++x) {
          cl[row + x] = kUnreached;
          tr[row + x] = static_cast<std::uint8_t>(st[row + x] == CellState::kFree);
        }
        continue;
      }
      if (narrow) {
        row_distances(cl + row, w, v.data(), F.data(), k, d2n.data());
        clearance_row(d2n.data(), st + row, w, res, radius, cl + row, tr + row);
      } else {
        row_distances(cl + row, w, v.data(), F.data(), k, d2w.data());
        clearance_row(d2w.data(), st + row, w, res, radius, cl + row, tr + row);
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
