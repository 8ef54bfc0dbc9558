/// @file frontier.cpp
/// FrontierSettings, GoalBlacklist and frontier_mask (SSE2 / AVX2 row passes); find_frontier: frontier_search.cpp.
#include <duet/kernels/error.hpp>
#include <duet/kernels/frontier.hpp>

#include "parallel.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#ifdef __SSE2__
#include <emmintrin.h>
#endif
#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <vector>

namespace duet {

void validate(const FrontierSettings& s) {
  if (s.min_cluster_cells < 1)
    fail(ErrorCode::kInvalidArgument,
         "FrontierSettings.min_cluster_cells must be >= 1 [cells], got " + std::to_string(s.min_cluster_cells));
  if (!std::isfinite(s.min_goal_distance_m) || !(s.min_goal_distance_m >= 0.0f))
    fail(ErrorCode::kInvalidArgument,
         "FrontierSettings.min_goal_distance_m must be finite and >= 0 [m], got " + std::to_string(s.min_goal_distance_m));
  if (!std::isfinite(s.blacklist_radius_m) || !(s.blacklist_radius_m >= 0.0f))
    fail(ErrorCode::kInvalidArgument,
         "FrontierSettings.blacklist_radius_m must be finite and >= 0 [m], got " + std::to_string(s.blacklist_radius_m));
  if (!std::isfinite(s.min_unknown_region_m2) || !(s.min_unknown_region_m2 >= 0.0f))
    fail(ErrorCode::kInvalidArgument,
         "FrontierSettings.min_unknown_region_m2 must be finite and >= 0 [m^2], got " + std::to_string(s.min_unknown_region_m2));
  if (!std::isfinite(s.approach_radius_m) || !(s.approach_radius_m >= 0.0f))
    fail(ErrorCode::kInvalidArgument,
         "FrontierSettings.approach_radius_m must be finite and >= 0 [m], got " + std::to_string(s.approach_radius_m));
  if (!(s.potential_scale >= 0.0f && s.potential_scale <= 1e3f))
    fail(ErrorCode::kInvalidArgument, "FrontierSettings.potential_scale must be in [0, 1000], got " + std::to_string(s.potential_scale));
  if (!(s.gain_scale >= 0.0f && s.gain_scale <= 1e3f))
    fail(ErrorCode::kInvalidArgument, "FrontierSettings.gain_scale must be in [0, 1000], got " + std::to_string(s.gain_scale));
  if (s.selection != FrontierSelection::kNearest && s.selection != FrontierSelection::kExploreLite)
    fail(ErrorCode::kInvalidArgument, "FrontierSettings.selection must be kNearest or kExploreLite");
}

const char* to_string(FrontierSelection s) { return s == FrontierSelection::kExploreLite ? "explore_lite" : "nearest"; }

const char* to_string(FrontierStatus s) {
  switch (s) {
    case FrontierStatus::kFound: return "found";
    case FrontierStatus::kNoFrontier: return "no frontier";
    case FrontierStatus::kAllUnreachable: return "all frontiers unreachable";
    case FrontierStatus::kAllBlacklisted: return "all frontiers blacklisted or too near";
    case FrontierStatus::kRobotBlocked: return "robot blocked";
  }
  return "unknown";
}

// ---- GoalBlacklist ------------------------------------------------------------------------------

void GoalBlacklist::add(Eigen::Vector2f xy, double now_s, double ttl_s) {
  if (!xy.allFinite()) fail(ErrorCode::kInvalidArgument, "GoalBlacklist::add: xy must be finite");
  if (!std::isfinite(now_s)) fail(ErrorCode::kInvalidArgument, "GoalBlacklist::add: now_s must be finite");
  if (std::isnan(ttl_s) || !(ttl_s > 0.0))
    fail(ErrorCode::kInvalidArgument, "GoalBlacklist::add: ttl_s must be > 0 [s] (+inf = forever), got " + std::to_string(ttl_s));
  entries_.push_back({xy, now_s + ttl_s});
}

void GoalBlacklist::expire(double now_s) {
  std::erase_if(entries_, [now_s](const Entry& e) { return e.expiry_s <= now_s; });
}

bool GoalBlacklist::blocks(Eigen::Vector2f xy, float radius_m, double now_s) const {
  const float r2 = radius_m * radius_m;
  for (const Entry& e : entries_)
    if (e.expiry_s > now_s && (e.xy - xy).squaredNorm() <= r2) return true;
  return false;
}

// ---- frontier mask ------------------------------------------------------------------------------
//
// One pass per fixed block of rows. Row y+1 is classified into two byte rows (0x00 / 0xFF: free,
// unknown) kept in L1 with a zero byte on each side; its unknown row is dilated horizontally
// (OR of the bytes at x-1, x, x+1: three unaligned loads) into a ring of three rows; row y's mask
// is then free(y) AND (h(y-1) | h(y) | h(y+1)), 16 cells per SSE2 step, no per-cell branch; the
// count is a byte sum (psadbw). Rows outside the grid contribute zeros (the outside is not unknown).

namespace {

/// Rows per task: fixed (thread-count independent); ~64k cells per block, at least 8 rows.
std::size_t row_block(std::size_t w) { return std::clamp<std::size_t>((std::size_t{1} << 16) / std::max<std::size_t>(w, 1), 8, 512); }

/// mask of rows [y0, y1): classify_row(y, free_out, unknown_out) fills row y as 0x00 / 0xFF bytes.
template <class ClassifyRow>
std::size_t mask_rows(std::size_t w, std::size_t h, std::size_t y0, std::size_t y1, std::uint8_t* mask, ClassifyRow& classify_row,
                      std::vector<std::uint8_t>& buf) {
  // Row stride: w rounded up to 16, plus 16 bytes on each side (zero padding for the x-1 / x+1 loads).
  const std::size_t stride = ((w + 15) & ~std::size_t{15}) + 32;
  buf.assign(6 * stride, 0);
  std::uint8_t* hu[3];  // horizontally dilated unknown rows y-1, y, y+1
  for (int k = 0; k < 3; ++k) hu[k] = buf.data() + static_cast<std::size_t>(k) * stride + 16;
  std::uint8_t* u = buf.data() + 3 * stride + 16;      // unknown row being classified
  std::uint8_t* fcur = buf.data() + 4 * stride + 16;   // free row y
  std::uint8_t* fnext = buf.data() + 5 * stride + 16;  // free row y+1
  const std::size_t wv = (w + 15) & ~std::size_t{15};  // bytes processed per row (tail bytes are 0)
  // Classifies row y (zeros outside the grid) into fout and hout.
  const auto load_row = [&](std::size_t y, bool inside, std::uint8_t* fout, std::uint8_t* hout) {
    if (!inside) {
      std::memset(fout, 0, wv);
      std::memset(hout, 0, wv);
      return;
    }
    classify_row(y, fout, u);
#ifdef __SSE2__
    for (std::size_t x = 0; x < wv; x += 16) {
      const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(u + x - 1));
      const __m128i b = _mm_load_si128(reinterpret_cast<const __m128i*>(u + x));
      const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(u + x + 1));
      _mm_store_si128(reinterpret_cast<__m128i*>(hout + x), _mm_or_si128(_mm_or_si128(a, b), c));
    }
#else
    for (std::size_t x = 0; x < wv; ++x) hout[x] = static_cast<std::uint8_t>(u[x - 1] | u[x] | u[x + 1]);
#endif
  };
  load_row(y0 - 1, y0 > 0, fnext, hu[0]);  // (y0 - 1 wraps for y0 = 0; not used then)
  load_row(y0, true, fcur, hu[1]);
  std::size_t count = 0;
  for (std::size_t y = y0; y < y1; ++y) {
    load_row(y + 1, y + 1 < h, fnext, hu[2]);
    std::uint8_t* m = mask + y * w;
    const std::uint8_t* h0 = hu[0];
    const std::uint8_t* h1 = hu[1];
    const std::uint8_t* h2 = hu[2];
    std::size_t x = 0;
#ifdef __SSE2__
    const __m128i one = _mm_set1_epi8(1), zero = _mm_setzero_si128();
    __m128i acc = zero;
    for (; x + 16 <= w; x += 16) {
      const __m128i d = _mm_or_si128(_mm_or_si128(_mm_load_si128(reinterpret_cast<const __m128i*>(h0 + x)),
                                                  _mm_load_si128(reinterpret_cast<const __m128i*>(h1 + x))),
                                     _mm_load_si128(reinterpret_cast<const __m128i*>(h2 + x)));
      const __m128i v = _mm_and_si128(_mm_and_si128(d, _mm_load_si128(reinterpret_cast<const __m128i*>(fcur + x))), one);
      _mm_storeu_si128(reinterpret_cast<__m128i*>(m + x), v);
      acc = _mm_add_epi64(acc, _mm_sad_epu8(v, zero));
    }
    count += static_cast<std::size_t>(_mm_cvtsi128_si64(acc)) + static_cast<std::size_t>(_mm_cvtsi128_si64(_mm_unpackhi_epi64(acc, acc)));
#endif
    for (; x < w; ++x) {
      const auto v = static_cast<std::uint8_t>(fcur[x] & (h0[x] | h1[x] | h2[x]) & 1);
      m[x] = v;
      count += v;
    }
    std::swap(fcur, fnext);
    std::uint8_t* t = hu[0];
    hu[0] = hu[1];
    hu[1] = hu[2];
    hu[2] = t;
  }
  return count;
}

#if defined(__GNUC__) && defined(__x86_64__)
#define DUET_FRONTIER_AVX2 1
// AVX2 variant of mask_rows (same bytes, 32 cells per step), compiled for AVX2 only here and
// chosen at run time (the library is built for baseline x86-64 = SSE2).
#define DUET_AVX2 __attribute__((target("avx2")))

struct F32ClassifyAvx2 {
  const float* lo;
  std::size_t w;
  float fr, oc;
  DUET_AVX2 void operator()(std::size_t y, std::uint8_t* f, std::uint8_t* u) const {
    const float* row = lo + y * w;
    const __m256 vfr = _mm256_set1_ps(fr), voc = _mm256_set1_ps(oc);
    const __m256i ones = _mm256_set1_epi8(-1), perm = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
    std::size_t x = 0;
    for (; x + 32 <= w; x += 32) {
      __m256i fm[4], om[4];
      for (int k = 0; k < 4; ++k) {
        const __m256 l = _mm256_loadu_ps(row + x + 8 * static_cast<std::size_t>(k));
        fm[k] = _mm256_castps_si256(_mm256_cmp_ps(l, vfr, _CMP_LE_OQ));  // false for NaN
        om[k] = _mm256_castps_si256(_mm256_cmp_ps(l, voc, _CMP_GE_OQ));  // false for NaN
      }
      const __m256i f8 = _mm256_permutevar8x32_epi32(
          _mm256_packs_epi16(_mm256_packs_epi32(fm[0], fm[1]), _mm256_packs_epi32(fm[2], fm[3])), perm);
      const __m256i o8 = _mm256_permutevar8x32_epi32(
          _mm256_packs_epi16(_mm256_packs_epi32(om[0], om[1]), _mm256_packs_epi32(om[2], om[3])), perm);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(f + x), f8);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(u + x), _mm256_andnot_si256(_mm256_or_si256(f8, o8), ones));
    }
    for (; x < w; ++x) {
      const float l = row[x];
      const bool is_free = l <= fr, is_occ = l >= oc;
      f[x] = is_free ? 0xFF : 0;
      u[x] = !is_free && !is_occ ? 0xFF : 0;
    }
  }
};

struct StateClassifyAvx2 {
  const std::uint8_t* st;
  std::size_t w;
  DUET_AVX2 void operator()(std::size_t y, std::uint8_t* f, std::uint8_t* u) const {
    const std::uint8_t* row = st + y * w;
    const __m256i vfree = _mm256_setzero_si256(), vunk = _mm256_set1_epi8(1);
    std::size_t x = 0;
    for (; x + 32 <= w; x += 32) {
      const __m256i s = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(row + x));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(f + x), _mm256_cmpeq_epi8(s, vfree));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(u + x), _mm256_cmpeq_epi8(s, vunk));
    }
    for (; x < w; ++x) {
      f[x] = row[x] == 0 ? 0xFF : 0;
      u[x] = row[x] == 1 ? 0xFF : 0;
    }
  }
};

template <class Classify>
DUET_AVX2 std::size_t mask_rows_avx2(std::size_t w, std::size_t h, std::size_t y0, std::size_t y1, std::uint8_t* mask,
                                     const Classify& classify_row, std::vector<std::uint8_t>& buf) {
  const std::size_t wv = (w + 31) & ~std::size_t{31};  // bytes processed per row (bytes past w are 0)
  const std::size_t stride = wv + 64;                  // 32 zero bytes on each side
  buf.assign(6 * stride, 0);
  std::uint8_t* hu[3];
  for (int k = 0; k < 3; ++k) hu[k] = buf.data() + static_cast<std::size_t>(k) * stride + 32;
  std::uint8_t* u = buf.data() + 3 * stride + 32;
  std::uint8_t* fcur = buf.data() + 4 * stride + 32;
  std::uint8_t* fnext = buf.data() + 5 * stride + 32;
  const auto load_row = [&](std::size_t y, bool inside, std::uint8_t* fout, std::uint8_t* hout) DUET_AVX2 {
    if (!inside) {
      std::memset(fout, 0, wv);
      std::memset(hout, 0, wv);
      return;
    }
    classify_row(y, fout, u);
    for (std::size_t x = 0; x < wv; x += 32) {
      const __m256i a = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(u + x - 1));
      const __m256i b = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(u + x));
      const __m256i c = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(u + x + 1));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(hout + x), _mm256_or_si256(_mm256_or_si256(a, b), c));
    }
  };
  load_row(y0 - 1, y0 > 0, fnext, hu[0]);
  load_row(y0, true, fcur, hu[1]);
  std::size_t count = 0;
  const __m256i one = _mm256_set1_epi8(1), zero = _mm256_setzero_si256();
  for (std::size_t y = y0; y < y1; ++y) {
    load_row(y + 1, y + 1 < h, fnext, hu[2]);
    std::uint8_t* m = mask + y * w;
    const std::uint8_t* h0 = hu[0];
    const std::uint8_t* h1 = hu[1];
    const std::uint8_t* h2 = hu[2];
    __m256i acc = zero;
    std::size_t x = 0;
    for (; x + 32 <= w; x += 32) {
      const __m256i d = _mm256_or_si256(_mm256_or_si256(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(h0 + x)),
                                                        _mm256_loadu_si256(reinterpret_cast<const __m256i*>(h1 + x))),
                                        _mm256_loadu_si256(reinterpret_cast<const __m256i*>(h2 + x)));
      const __m256i v =
          _mm256_and_si256(_mm256_and_si256(d, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(fcur + x))), one);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(m + x), v);
      acc = _mm256_add_epi64(acc, _mm256_sad_epu8(v, zero));
    }
    alignas(32) std::uint64_t lanes[4];
    _mm256_store_si256(reinterpret_cast<__m256i*>(lanes), acc);
    count += static_cast<std::size_t>(lanes[0] + lanes[1] + lanes[2] + lanes[3]);
    for (; x < w; ++x) {
      const auto v = static_cast<std::uint8_t>(fcur[x] & (h0[x] | h1[x] | h2[x]) & 1);
      m[x] = v;
      count += v;
    }
    std::swap(fcur, fnext);
    std::uint8_t* t = hu[0];
    hu[0] = hu[1];
    hu[1] = hu[2];
    hu[2] = t;
  }
  return count;
}

bool use_avx2() noexcept { return __builtin_cpu_supports("avx2"); }
#endif

/// classify_row: the SSE2 row classifier; Avx2: the AVX2 one (used when the CPU has AVX2).
template <class ClassifyRow, class Avx2>
std::size_t mask_all(int w, int h, std::uint8_t* mask, ClassifyRow&& classify_row, [[maybe_unused]] const Avx2& avx2,
                     [[maybe_unused]] bool allow_avx2) {
  const std::size_t sw = static_cast<std::size_t>(w), sh = static_cast<std::size_t>(h);
  const std::size_t rb = row_block(sw);
#ifdef DUET_FRONTIER_AVX2
  const bool avx = allow_avx2 && use_avx2();
#endif
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, detail::block_count(sh, rb), 1), std::size_t{0},
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t acc) {
        std::vector<std::uint8_t> buf;
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
          const std::size_t y0 = b * rb, y1 = std::min(sh, (b + 1) * rb);
#ifdef DUET_FRONTIER_AVX2
          if (avx) {
            acc += mask_rows_avx2(sw, sh, y0, y1, mask, avx2, buf);
            continue;
          }
#endif
          acc += mask_rows(sw, sh, y0, y1, mask, classify_row, buf);
        }
        return acc;
      },
      [](std::size_t a, std::size_t b) { return a + b; });
}

}  // namespace

namespace detail {
/// frontier_mask with the SIMD level chosen: allow_avx2 = false forces the SSE2 path (tests).
std::size_t frontier_mask_isa(const GridView& grid, const CellThresholds& t, std::span<std::uint8_t> mask, bool allow_avx2);
std::size_t frontier_mask_isa(std::span<const CellState> state, int width, int height, std::span<std::uint8_t> mask,
                              bool allow_avx2);
}  // namespace detail

std::size_t frontier_mask(const GridView& grid, const CellThresholds& t, std::span<std::uint8_t> mask) {
  return detail::frontier_mask_isa(grid, t, mask, true);
}

std::size_t frontier_mask(std::span<const CellState> state, int width, int height, std::span<std::uint8_t> mask) {
  return detail::frontier_mask_isa(state, width, height, mask, true);
}

bool any_frontier_cell_within(const InflatedGrid& g, const Eigen::Vector2f& xy, float radius_m) {
  if (!xy.allFinite()) fail(ErrorCode::kInvalidArgument, "any_frontier_cell_within: xy must be finite");
  if (!std::isfinite(radius_m) || !(radius_m >= 0.0f))
    fail(ErrorCode::kInvalidArgument, "any_frontier_cell_within: radius_m must be finite and >= 0 [m], got " + std::to_string(radius_m));
  if (g.width < 0 || g.height < 0 || g.state.size() != g.cell_count())
    fail(ErrorCode::kInvalidArgument, "any_frontier_cell_within: grid state has " + std::to_string(g.state.size()) +
                                          " cells, width * height is " + std::to_string(g.cell_count()));
  if (g.cell_count() == 0) return false;
  // The square of cells whose centres can lie within the radius, clamped to the grid (in float
  // first: xy may be far outside it).
  const float inv = 1.0f / g.resolution_m;
  const auto clamp_cell = [](float v, int n) { return static_cast<int>(std::clamp(std::floor(v), -1.0f, static_cast<float>(n))); };
  const int x0 = std::max(0, clamp_cell((xy.x() - radius_m - g.origin.x()) * inv, g.width));
  const int x1 = std::min(g.width - 1, clamp_cell((xy.x() + radius_m - g.origin.x()) * inv, g.width));
  const int y0 = std::max(0, clamp_cell((xy.y() - radius_m - g.origin.y()) * inv, g.height));
  const int y1 = std::min(g.height - 1, clamp_cell((xy.y() + radius_m - g.origin.y()) * inv, g.height));
  auto unknown = [&](int x, int y) { return g.in_bounds(x, y) && g.state[g.index(x, y)] == CellState::kUnknown; };
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      if (g.state[g.index(x, y)] != CellState::kFree) continue;
      if ((g.cell_center(g.index(x, y)) - xy).norm() > radius_m) continue;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          if ((dx != 0 || dy != 0) && unknown(x + dx, y + dy)) return true;
    }
  return false;
}

std::size_t detail::frontier_mask_isa(const GridView& grid, const CellThresholds& t, std::span<std::uint8_t> mask, bool allow_avx2) {
  validate(grid, "frontier_mask: grid");
  validate(t);
  if (mask.size() != grid.cell_count())
    fail(ErrorCode::kInvalidArgument, "frontier_mask: mask has " + std::to_string(mask.size()) + " cells, grid has " +
                                          std::to_string(grid.cell_count()));
  if (grid.cell_count() == 0) return 0;
  const float* lo = grid.logodds.data();
  const std::size_t sw = static_cast<std::size_t>(grid.width);
  const float fr = t.free_logodds, oc = t.occupied_logodds;
#ifdef DUET_FRONTIER_AVX2
  const F32ClassifyAvx2 avx2{lo, sw, fr, oc};
#else
  const int avx2 = 0;
#endif
  return mask_all(grid.width, grid.height, mask.data(), [&](std::size_t y, std::uint8_t* f, std::uint8_t* u) {
    const float* row = lo + y * sw;
    std::size_t x = 0;
#ifdef __SSE2__
    // 16 cells per step: two float compares (false for NaN), packed to 16 bytes of 0x00 / 0xFF.
    const __m128 vfr = _mm_set1_ps(fr), voc = _mm_set1_ps(oc);
    const __m128i ones = _mm_set1_epi8(-1);
    for (; x + 16 <= sw; x += 16) {
      __m128i fm[4], om[4];
      for (int k = 0; k < 4; ++k) {
        const __m128 l = _mm_loadu_ps(row + x + 4 * static_cast<std::size_t>(k));
        fm[k] = _mm_castps_si128(_mm_cmple_ps(l, vfr));
        om[k] = _mm_castps_si128(_mm_cmpge_ps(l, voc));
      }
      const __m128i f8 = _mm_packs_epi16(_mm_packs_epi32(fm[0], fm[1]), _mm_packs_epi32(fm[2], fm[3]));
      const __m128i o8 = _mm_packs_epi16(_mm_packs_epi32(om[0], om[1]), _mm_packs_epi32(om[2], om[3]));
      _mm_store_si128(reinterpret_cast<__m128i*>(f + x), f8);
      _mm_store_si128(reinterpret_cast<__m128i*>(u + x), _mm_andnot_si128(_mm_or_si128(f8, o8), ones));
    }
#endif
    for (; x < sw; ++x) {
      const float l = row[x];
      const bool is_free = l <= fr, is_occ = l >= oc;  // both false for NaN
      f[x] = is_free ? 0xFF : 0;
      u[x] = !is_free && !is_occ ? 0xFF : 0;
    }
  }, avx2, allow_avx2);
}

std::size_t detail::frontier_mask_isa(std::span<const CellState> state, int width, int height, std::span<std::uint8_t> mask,
                                      bool allow_avx2) {
  if (width < 0 || height < 0)
    fail(ErrorCode::kInvalidArgument, "frontier_mask: negative size " + std::to_string(width) + " x " + std::to_string(height));
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (state.size() != n || mask.size() != n)
    fail(ErrorCode::kInvalidArgument, "frontier_mask: state and mask must have width*height = " + std::to_string(n) + " cells");
  if (n == 0) return 0;
  const std::size_t sw = static_cast<std::size_t>(width);
  const auto* st = reinterpret_cast<const std::uint8_t*>(state.data());
  static_assert(sizeof(CellState) == 1 && static_cast<int>(CellState::kFree) == 0 && static_cast<int>(CellState::kUnknown) == 1);
#ifdef DUET_FRONTIER_AVX2
  const StateClassifyAvx2 avx2{st, sw};
#else
  const int avx2 = 0;
#endif
  return mask_all(width, height, mask.data(), [&](std::size_t y, std::uint8_t* f, std::uint8_t* u) {
    const std::uint8_t* row = st + y * sw;
    std::size_t x = 0;
#ifdef __SSE2__
    const __m128i vfree = _mm_setzero_si128(), vunk = _mm_set1_epi8(1);
    for (; x + 16 <= sw; x += 16) {
      const __m128i s = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x));
      _mm_store_si128(reinterpret_cast<__m128i*>(f + x), _mm_cmpeq_epi8(s, vfree));
      _mm_store_si128(reinterpret_cast<__m128i*>(u + x), _mm_cmpeq_epi8(s, vunk));
    }
#endif
    for (; x < sw; ++x) {
      f[x] = row[x] == 0 ? 0xFF : 0;
      u[x] = row[x] == 1 ? 0xFF : 0;
    }
  }, avx2, allow_avx2);
}

}  // namespace duet
