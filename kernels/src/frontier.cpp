#include <duet/kernels/error.hpp>
#include <duet/kernels/frontier.hpp>
#include <duet/kernels/path.hpp>

#include "parallel.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
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
#include <limits>
#include <numbers>
#include <string>
#include <type_traits>
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

// ---- find_frontier ------------------------------------------------------------------------------

namespace {

constexpr int kDx[8] = {1, -1, 0, 0, 1, -1, 1, -1};
constexpr int kDy[8] = {0, 0, 1, -1, 1, 1, -1, -1};

/// Ascending list of the cells with mask != 0 (parallel per-row counts, prefix sum, fill).
void compact(const std::vector<std::uint8_t>& mask, int w, int h, FrontierWorkspace& ws) {
  const std::size_t sw = static_cast<std::size_t>(w), sh = static_cast<std::size_t>(h);
  ws.row_count.assign(sh + 1, 0);
  detail::for_each_index(sh, 16, [&](std::size_t y) {
    const std::uint8_t* m = mask.data() + y * sw;
    std::uint32_t c = 0;
    for (std::size_t x = 0; x < sw; ++x) c += m[x] != 0;
    ws.row_count[y + 1] = c;
  });
  for (std::size_t y = 0; y < sh; ++y) ws.row_count[y + 1] += ws.row_count[y];
  ws.frontier.resize(ws.row_count[sh]);
  detail::for_each_index(sh, 16, [&](std::size_t y) {
    if (ws.row_count[y + 1] == ws.row_count[y]) return;
    const std::uint8_t* m = mask.data() + y * sw;
    std::uint32_t o = ws.row_count[y];
    for (std::size_t x = 0; x < sw; ++x)
      if (m[x]) ws.frontier[o++] = static_cast<std::uint32_t>(y * sw + x);
  });
}


// ---- exact two-queue Dijkstra in fixed-point path length ------------------------------------------
//
// Costs are integers in units of res / 2^16: an orthogonal step is 65536, a diagonal one
// round(sqrt(2) * 65536) = 92682 (relative error 2e-6, far below the float rounding of a sum of
// metres). Integer sums are exact, so the two FIFO queues (one per step length) each receive
// strictly non-decreasing keys and merging their heads is exact. The search runs on uint32 costs
// (max ~ 65535 cells of path length) and reruns on uint64 costs if a popped cost comes near the
// uint32 limit (same unit, so the same result).
// Per popped interior cell: branch-free relaxations (a non-traversable cell holds cost 0, so it
// never improves; a diagonal is gated by its two orthogonal cells), a branch-free queue push
// (the entry is always written, the tail advances only on improvement) and a branch-free merge
// (each ring holds a sentinel key = max at its tail).

constexpr std::uint32_t kUnitOrth = 65536;
constexpr std::uint32_t kUnitDiag = 92682;  // round(sqrt(2) * 65536)

template <class C>
using QEntry = std::conditional_t<sizeof(C) == 4, FrontierWorkspace::Entry32, FrontierWorkspace::Entry64>;

/// Initialises the per-cell search arrays of row y: cost (traversable: max = not reached;
/// blocked: 0 = never improves) and flags (bit 0 traversable, bit 1 frontier cell of a kept
/// cluster, bit 2 on the grid border).
template <class C>
void init_rows(const InflatedGrid& g, const std::uint8_t* mask, std::uint8_t* flags, C* cost, std::size_t y, bool with_flags) {
  const std::size_t w = static_cast<std::size_t>(g.width), row = y * w;
  const std::uint8_t* t = g.traversable.data() + row;
  C* co = cost + row;
  for (std::size_t x = 0; x < w; ++x) co[x] = static_cast<C>(C{0} - static_cast<C>(t[x]));
  if (!with_flags) return;
  std::uint8_t* f = flags + row;
  const std::uint8_t* m = mask + row;
  for (std::size_t x = 0; x < w; ++x) f[x] = static_cast<std::uint8_t>(t[x] | ((m[x] != 0) << 1));
  if (y == 0 || y + 1 == static_cast<std::size_t>(g.height)) {
    for (std::size_t x = 0; x < w; ++x) f[x] |= 4;
  } else {
    f[0] |= 4;
    f[w - 1] |= 4;
  }
}

/// Dijkstra from start over the traversable cells (fl: flags); on_frontier(cell, cost, flags) is
/// called for each settled frontier cell (flags bit 1) in settling order. Returns false on uint32
/// overflow. No parent pointers: costs are exact integers, so the path is traced back afterwards
/// from the costs alone (trace_back). Everything the loop needs lives in locals.
template <class C, class OnFrontier>
bool dijkstra(const InflatedGrid& g, const std::uint8_t* fl, C* cost, std::vector<QEntry<C>>& bo, std::vector<QEntry<C>>& bd,
              std::uint32_t start, OnFrontier&& on_frontier, std::size_t& reached_out) {
  using E = QEntry<C>;
  constexpr C kMax = std::numeric_limits<C>::max();
  constexpr C Ko = kUnitOrth, Kd = kUnitDiag;
  constexpr C kLimit = kMax - 2 * Kd;  // a popped cost above this may overflow when relaxed
  const std::size_t uw = static_cast<std::size_t>(g.width);
  if (bo.size() < 1024) bo.resize(1024);
  if (bd.size() < 1024) bd.resize(1024);
  E* po = bo.data();
  E* pd = bd.data();
  std::size_t mo = bo.size() - 1, md = bd.size() - 1;  // sizes are powers of 2
  std::size_t ho = 0, to = 1, hd = 0, td = 0;
  const auto grow = [](std::vector<E>& b, E*& p, std::size_t& m, std::size_t head, std::size_t tail) {
    std::vector<E> nb(b.size() * 2);
    const std::size_t nm = nb.size() - 1;
    for (std::size_t k = head; k != tail; ++k) nb[k & nm] = b[k & m];
    b.swap(nb);
    p = b.data();
    m = nm;
  };
  cost[start] = 0;
  po[0] = E{0, start};
  po[1].d = kMax;  // sentinels
  pd[0].d = kMax;
  std::size_t reached = 0;
  // Branch-free relaxation of neighbour ni with cost v through direction dv (ok: step allowed).
#define DUET_RELAX(ni, v, ok, P, M, T)                                               \
  do {                                                                               \
    const std::size_t n_ = (ni);                                                     \
    const C old_ = cost[n_];                                                         \
    const bool u_ = (ok) & ((v) < old_);                                             \
    cost[n_] = u_ ? (v) : old_;                                                      \
    P[T & M] = E{(v), static_cast<std::uint32_t>(n_)};                               \
    T += u_;                                                                         \
  } while (0)
  for (;;) {
    if (to - ho + 6 > mo) [[unlikely]] {
      grow(bo, po, mo, ho, to);
      po[to & mo].d = kMax;
    }
    if (td - hd + 6 > md) [[unlikely]] {
      grow(bd, pd, md, hd, td);
      pd[td & md].d = kMax;
    }
    const E eo = po[ho & mo], ed = pd[hd & md];
    const bool take_o = eo.d <= ed.d;  // ties: the orthogonal ring first
    // Branch-free select (the comparison is unpredictable).
    const C d = ed.d ^ ((eo.d ^ ed.d) & (C{0} - static_cast<C>(take_o)));
    const std::uint32_t c = ed.cell ^ ((eo.cell ^ ed.cell) & (0u - static_cast<std::uint32_t>(take_o)));
    if (d == kMax) break;  // both rings hold only their sentinel
    ho += take_o;
    hd += !take_o;
    if (d != cost[c]) continue;  // stale: the cell was settled with a smaller cost
    if constexpr (sizeof(C) < 8) {
      if (d > kLimit) [[unlikely]] return false;
    }
    ++reached;
    const std::uint8_t f = fl[c];
    if (f & 2) [[unlikely]] on_frontier(c, d, f);
    const C vo = d + Ko, vd = d + Kd;
    const std::size_t cs = c;
    if (!(f & 4)) [[likely]] {  // interior: all eight neighbours exist
      const bool te = fl[cs + 1] & 1, tw = fl[cs - 1] & 1, tn = fl[cs + uw] & 1, ts = fl[cs - uw] & 1;
      DUET_RELAX(cs + 1, vo, true, po, mo, to);
      DUET_RELAX(cs - 1, vo, true, po, mo, to);
      DUET_RELAX(cs + uw, vo, true, po, mo, to);
      DUET_RELAX(cs - uw, vo, true, po, mo, to);
      DUET_RELAX(cs + uw + 1, vd, tn & te, pd, md, td);
      DUET_RELAX(cs + uw - 1, vd, tn & tw, pd, md, td);
      DUET_RELAX(cs - uw + 1, vd, ts & te, pd, md, td);
      DUET_RELAX(cs - uw - 1, vd, ts & tw, pd, md, td);
    } else {  // grid border: bounds checks
      const int x = static_cast<int>(cs % uw), y = static_cast<int>(cs / uw);
      for (int k = 0; k < 8; ++k) {
        const int nx = x + kDx[k], ny = y + kDy[k];
        if (!g.in_bounds(nx, ny)) continue;
        const std::size_t ni = g.index(nx, ny);
        if (k < 4) {
          DUET_RELAX(ni, vo, true, po, mo, to);
        } else {
          const bool ok = (fl[g.index(nx, y)] & 1) && (fl[g.index(x, ny)] & 1);  // no corner cutting
          DUET_RELAX(ni, vd, ok, pd, md, td);
        }
      }
    }
    po[to & mo].d = kMax;
    pd[td & md].d = kMax;
  }
#undef DUET_RELAX
  reached_out = reached;
  return true;
}

/// Shortest path start -> c from the settled costs: each step goes to the first neighbour p (in
/// the order of kDx/kDy) that is traversable, allowed (no corner cutting) and has cost[p] + step ==
/// cost[c] exactly. Appends the cells from c back to the start; counts the step kinds.
template <class C>
void trace_back(const InflatedGrid& g, const C* cost, std::size_t start, std::size_t c, std::vector<std::size_t>& cells,
                std::size_t& n_orth, std::size_t& n_diag) {
  const std::uint8_t* tr = g.traversable.data();
  cells.push_back(c);
  while (c != start) {
    const int x = static_cast<int>(c % static_cast<std::size_t>(g.width)), y = static_cast<int>(c / static_cast<std::size_t>(g.width));
    std::size_t next = c;
    for (int k = 0; k < 8; ++k) {
      const int px = x - kDx[k], py = y - kDy[k];  // p -> c is a step in direction k
      if (!g.in_bounds(px, py)) continue;
      const std::size_t p = g.index(px, py);
      if (!tr[p]) continue;
      if (k >= 4 && (!tr[g.index(px, y)] || !tr[g.index(x, py)])) continue;
      if (cost[p] + static_cast<C>(k < 4 ? kUnitOrth : kUnitDiag) != cost[c]) continue;
      next = p;
      ++(k < 4 ? n_orth : n_diag);
      break;
    }
    if (next == c) fail(ErrorCode::kInternal, "find_frontier: broken search tree");  // cannot happen
    c = next;
    cells.push_back(c);
  }
}

/// Drops (mask = 0) the frontier cells whose unknown 8-neighbours all lie in enclosed unknown
/// regions of fewer than min_cells cells (see min_unknown_region_m2 in frontier.hpp). Each region
/// is measured once, by a breadth-first search over kUnknown cells that stops as soon as it has
/// min_cells cells, touches the grid border or meets a cell already proved large.
void drop_enclosed_pockets(const InflatedGrid& g, std::size_t min_cells, FrontierWorkspace& ws) {
  const std::size_t n = g.cell_count();
  if (ws.region.size() != n) ws.region.assign(n, 0);
  ws.region_cells.clear();
  const int w = g.width, h = g.height;
  const auto uw = static_cast<std::uint32_t>(w);
  auto on_border = [&](std::uint32_t c) {
    const int x = static_cast<int>(c % uw), y = static_cast<int>(c / uw);
    return x == 0 || y == 0 || x == w - 1 || y == h - 1;
  };
  // The verdict (1 small, 2 large) of the region of unknown cell u.
  auto measure = [&](std::uint32_t u) -> std::uint8_t {
    if (ws.region[u] == 1 || ws.region[u] == 2) return ws.region[u];
    const std::size_t first = ws.region_cells.size();
    ws.region[u] = 3;
    ws.region_cells.push_back(u);
    bool large = false;
    for (std::size_t head = first; head < ws.region_cells.size() && !large; ++head) {
      const std::uint32_t c = ws.region_cells[head];
      if (on_border(c) || ws.region_cells.size() - first >= min_cells) {
        large = true;
        break;
      }
      const int x = static_cast<int>(c % uw), y = static_cast<int>(c / uw);
      for (int d = 0; d < 8; ++d) {
        const int nx = x + kDx[d], ny = y + kDy[d];
        if (!g.in_bounds(nx, ny)) continue;
        const std::size_t ni = g.index(nx, ny);
        if (g.state[ni] != CellState::kUnknown) continue;
        if (ws.region[ni] == 2) {
          large = true;
          break;
        }
        if (ws.region[ni] != 0) continue;  // in this search already (a small region is never adjacent)
        ws.region[ni] = 3;
        ws.region_cells.push_back(static_cast<std::uint32_t>(ni));
      }
    }
    const std::uint8_t v = large ? 2 : 1;
    for (std::size_t k = first; k < ws.region_cells.size(); ++k) ws.region[ws.region_cells[k]] = v;
    return v;
  };
  for (const std::uint32_t f : ws.frontier) {
    if (!ws.mask[f]) continue;
    const int x = static_cast<int>(f % uw), y = static_cast<int>(f / uw);
    bool keep = false;
    for (int d = 0; d < 8 && !keep; ++d) {
      const int nx = x + kDx[d], ny = y + kDy[d];
      if (!g.in_bounds(nx, ny)) continue;
      const std::size_t ni = g.index(nx, ny);
      if (g.state[ni] == CellState::kUnknown) keep = measure(static_cast<std::uint32_t>(ni)) == 2;
    }
    if (!keep) ws.mask[f] = 0;
  }
  for (const std::uint32_t c : ws.region_cells) ws.region[c] = 0;
  ws.region_cells.clear();
}

/// Approach cells (see approach_radius_m in frontier.hpp): a FIFO breadth-first search from the
/// connected frontier cells of the kept clusters that have no traversable cell (has_traversable[k]
/// = 0; ascending index order) over kFree cells,
/// each cell inheriting the source of the wave that reached it first and spreading only within
/// radius of that source. Reached traversable non-frontier cells get mask 3 and their source's
/// cluster label. The visited cells are listed in ws.approach_queue (their approach_src is reset
/// by reset_approach()).
void mark_approach_cells(const InflatedGrid& g, float radius_m, const std::vector<std::uint8_t>& has_traversable,
                         FrontierWorkspace& ws) {
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  const std::size_t n = g.cell_count();
  if (ws.approach_src.size() != n) ws.approach_src.assign(n, kNone);
  ws.approach_queue.clear();
  const int w = g.width, h = g.height;
  const auto uw = static_cast<std::uint32_t>(w);
  const float r_cells = radius_m / g.resolution_m;
  const float r2 = r_cells * r_cells;
  for (const std::uint32_t f : ws.frontier) {
    if (ws.mask[f] != 1 || has_traversable[static_cast<std::size_t>(ws.label[f])]) continue;
    const int x = static_cast<int>(f % uw), y = static_cast<int>(f / uw);
    if (x == 0 || y == 0 || x == w - 1 || y == h - 1) continue;  // not connected (§3.2)
    if (ws.approach_src[f] != kNone) continue;                    // claimed by an earlier wave
    ws.approach_src[f] = f;
    ws.approach_queue.push_back(f);
  }
  for (std::size_t head = 0; head < ws.approach_queue.size(); ++head) {
    const std::uint32_t c = ws.approach_queue[head];
    const std::uint32_t src = ws.approach_src[c];
    const int x = static_cast<int>(c % uw), y = static_cast<int>(c / uw);
    const int sx = static_cast<int>(src % uw), sy = static_cast<int>(src / uw);
    for (int d = 0; d < 8; ++d) {
      const int nx = x + kDx[d], ny = y + kDy[d];
      if (!g.in_bounds(nx, ny)) continue;
      const std::size_t ni = g.index(nx, ny);
      if (ws.approach_src[ni] != kNone || g.state[ni] != CellState::kFree) continue;
      const auto ddx = static_cast<float>(nx - sx), ddy = static_cast<float>(ny - sy);
      if (ddx * ddx + ddy * ddy > r2) continue;
      ws.approach_src[ni] = src;
      ws.approach_queue.push_back(static_cast<std::uint32_t>(ni));
      if (g.traversable[ni] && ws.mask[ni] == 0) {
        ws.mask[ni] = 3;
        ws.label[ni] = ws.label[src];
      }
    }
  }
}

/// Undoes mark_approach_cells (approach_src back to "not visited", mask 3 back to 0).
void reset_approach(FrontierWorkspace& ws) {
  for (const std::uint32_t c : ws.approach_queue) {
    ws.approach_src[c] = std::numeric_limits<std::uint32_t>::max();
    if (ws.mask[c] == 3) ws.mask[c] = 0;
  }
  ws.approach_queue.clear();
}

}  // namespace

FrontierResult find_frontier(const InflatedGrid& g, const Eigen::Vector2f& robot_xy, const GoalBlacklist& bl,
                             double now_s, const FrontierSettings& s, FrontierWorkspace& ws) {
  validate(g, "find_frontier: grid");
  validate(s);
  FrontierResult res;
  const std::size_t n = g.cell_count();
  const int w = g.width, h = g.height;
  const auto uw = static_cast<std::uint32_t>(w);

  // 1. Frontier cells (parallel) and their ascending list.
  ws.mask.resize(n);
  ws.label.resize(n);
  frontier_mask(g.state, w, h, ws.mask);
  compact(ws.mask, w, h, ws);
  if (s.min_unknown_region_m2 > 0.0f) {
    const double cells = std::ceil(static_cast<double>(s.min_unknown_region_m2) /
                                   (static_cast<double>(g.resolution_m) * static_cast<double>(g.resolution_m)));
    drop_enclosed_pockets(g, cells >= 1e15 ? std::size_t{1} << 50 : static_cast<std::size_t>(cells), ws);
  }

  // 2. Clusters: 8-connected flood fill in ascending order of the first cell (serial). mask: 1 =
  // unlabelled frontier, 2 = labelled.
  struct RawCluster {
    std::int32_t cells;
    double sx, sy;
  };
  std::vector<RawCluster> raw;
  for (const std::uint32_t seed : ws.frontier) {
    if (ws.mask[seed] != 1) continue;
    const auto id = static_cast<std::int32_t>(raw.size());
    RawCluster rc{0, 0.0, 0.0};
    ws.stack.clear();
    ws.stack.push_back(seed);
    ws.mask[seed] = 2;
    while (!ws.stack.empty()) {
      const std::uint32_t c = ws.stack.back();
      ws.stack.pop_back();
      ws.label[c] = id;
      ++rc.cells;
      const int x = static_cast<int>(c % uw), y = static_cast<int>(c / uw);
      rc.sx += x;
      rc.sy += y;
      for (int d = 0; d < 8; ++d) {
        const int nx = x + kDx[d], ny = y + kDy[d];
        if (!g.in_bounds(nx, ny)) continue;
        const std::size_t ni = g.index(nx, ny);
        if (ws.mask[ni] == 1) {
          ws.mask[ni] = 2;
          ws.stack.push_back(static_cast<std::uint32_t>(ni));
        }
      }
    }
    raw.push_back(rc);
  }
  ws.cluster_raw.assign(raw.size(), -1);
  for (std::size_t k = 0; k < raw.size(); ++k) {
    if (raw[k].cells < s.min_cluster_cells) continue;
    ws.cluster_raw[k] = static_cast<std::int32_t>(res.clusters.size());
    FrontierCluster fc;
    fc.cells = raw[k].cells;
    const double res_m = g.resolution_m;
    fc.centroid = Eigen::Vector2f(static_cast<float>(g.origin.x() + (raw[k].sx / raw[k].cells + 0.5) * res_m),
                                  static_cast<float>(g.origin.y() + (raw[k].sy / raw[k].cells + 0.5) * res_m));
    fc.path_length_m = std::numeric_limits<float>::infinity();
    res.clusters.push_back(fc);
  }
  // Relabel to kept ids, drop small clusters from the mask, Euclidean-nearest cell per cluster.
  std::vector<float> best_e(res.clusters.size(), std::numeric_limits<float>::infinity());
  std::vector<std::uint8_t> has_traversable(res.clusters.size(), 0);
  for (const std::uint32_t c : ws.frontier) {
    if (ws.mask[c] == 0) continue;  // dropped as the border of an enclosed pocket
    const std::int32_t k = ws.cluster_raw[static_cast<std::size_t>(ws.label[c])];
    if (k < 0) {
      ws.mask[c] = 0;
      continue;
    }
    ws.mask[c] = 1;
    ws.label[c] = k;
    has_traversable[static_cast<std::size_t>(k)] |= g.traversable[c];
    ++res.frontier_cells;
    const Eigen::Vector2f p = g.cell_center(static_cast<std::size_t>(c));
    const float e = (p - robot_xy).squaredNorm();
    if (e < best_e[static_cast<std::size_t>(k)]) {
      best_e[static_cast<std::size_t>(k)] = e;
      res.clusters[static_cast<std::size_t>(k)].nearest_xy = p;
    }
  }
  if (res.clusters.empty()) {
    res.status = FrontierStatus::kNoFrontier;
    return res;
  }
  // 2b. Approach cells of the frontier cells the robot cannot stand on (undone on every return:
  // approach_src must be all "not visited" for the next call).
  struct ApproachReset {
    FrontierWorkspace& ws;
    ~ApproachReset() { reset_approach(ws); }
  } approach_reset{ws};
  if (s.approach_radius_m > 0.0f) mark_approach_cells(g, s.approach_radius_m, has_traversable, ws);

  // 3. Robot cell (plan_path's start rule).
  Eigen::Vector2i rc;
  const std::int64_t start = g.cell_of(robot_xy, rc) ? traversable_start(g, rc) : -1;
  if (start < 0) {
    res.status = FrontierStatus::kRobotBlocked;
    return res;
  }

  // 4. Exact two-queue Dijkstra on path length (see dijkstra() above), over the robot's whole
  // traversable component. Per-cell arrays (flags: bit 0 traversable, bit 1 frontier cell of a
  // kept cluster, bit 2 on the grid border; cost; dist) are initialised in one parallel pass.
  ws.dist.resize(n);
  ws.flags.resize(n);
  ws.cost32.resize(n);
  detail::for_each_index(static_cast<std::size_t>(h), 16, [&](std::size_t y) {
    init_rows(g, ws.mask.data(), ws.flags.data(), ws.cost32.data(), y, true);
  });
  const std::vector<FrontierCluster> clusters0 = res.clusters;  // restored if the uint32 search overflows
  const double min_units = (static_cast<double>(s.min_goal_distance_m) / g.resolution_m - 1e-3) * kUnitOrth;
  std::int64_t goal = -1;
  bool any_connected_reached = false;
  const double scale = static_cast<double>(g.resolution_m) / kUnitOrth;
  const auto run = [&]<class C>(C* cost, std::vector<QEntry<C>>& bo, std::vector<QEntry<C>>& bd) {
    // Tolerance of 1e-3 cell below min_goal_distance_m (as the reference in metres).
    const C min_cost = !(min_units > 0.0) ? C{0}
                       : min_units >= static_cast<double>(std::numeric_limits<C>::max())
                           ? std::numeric_limits<C>::max()
                           : static_cast<C>(std::ceil(min_units));
    ws.cand.assign(res.clusters.size(), 0);
    ws.cluster_goal.assign(res.clusters.size(), -1);
    goal = -1;
    any_connected_reached = false;
    const auto on_frontier = [&](std::uint32_t c, C d, std::uint8_t f) {
      const auto k = static_cast<std::size_t>(ws.label[c]);
      FrontierCluster& fc = res.clusters[k];
      if (!fc.reachable) {
        fc.reachable = true;
        fc.nearest_xy = g.cell_center(static_cast<std::size_t>(c));
        fc.path_length_m = static_cast<float>(static_cast<double>(d) * scale);
      }
      if (f & 4) return;  // not connected (§3.2): on the grid border
      any_connected_reached = true;
      if (d < min_cost) return;
      // An approach cell is blocked by the blacklist near itself or near the frontier cell it is for.
      const bool blocked = bl.blocks(g.cell_center(static_cast<std::size_t>(c)), s.blacklist_radius_m, now_s) ||
                           (ws.mask[c] == 3 && bl.blocks(g.cell_center(static_cast<std::size_t>(ws.approach_src[c])),
                                                         s.blacklist_radius_m, now_s));
      if (blocked) {
        ws.cand[k] = std::max<std::uint8_t>(ws.cand[k], 1);
      } else {
        ws.cand[k] = 2;
        if (goal < 0) goal = c;
        if (ws.cluster_goal[k] < 0) ws.cluster_goal[k] = c;  // settled in path order: the cluster's nearest
      }
    };
    if (!dijkstra<C>(g, ws.flags.data(), cost, bo, bd, static_cast<std::uint32_t>(start), on_frontier, res.reached_cells))
      return false;
    // dist: path length of the settled cells, +inf elsewhere (parallel, after the search).
    const std::uint8_t* fl = ws.flags.data();
    float* dist = ws.dist.data();
    detail::for_blocks(n, std::size_t{1} << 15, [&](std::size_t, std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i)
        dist[i] = (fl[i] & 1) && cost[i] != std::numeric_limits<C>::max() ? static_cast<float>(static_cast<double>(cost[i]) * scale)
                                                                          : std::numeric_limits<float>::infinity();
    });
    return true;
  };
  const bool wide = !run(ws.cost32.data(), ws.ring32_o, ws.ring32_d);
  if (wide) {
    // Path lengths beyond ~65535 cells: rerun with 64-bit costs (same unit, same result).
    res.clusters = clusters0;
    ws.cost64.resize(n);
    detail::for_each_index(static_cast<std::size_t>(h), 16, [&](std::size_t y) {
      init_rows(g, ws.mask.data(), ws.flags.data(), ws.cost64.data(), y, false);
    });
    (void)run(ws.cost64.data(), ws.ring64_o, ws.ring64_d);
  }
  for (std::size_t k = 0; k < res.clusters.size(); ++k) res.clusters[k].blacklisted = ws.cand[k] == 1;

  if (goal < 0) {
    res.status = any_connected_reached ? FrontierStatus::kAllBlacklisted : FrontierStatus::kAllUnreachable;
    return res;
  }
  if (s.selection == FrontierSelection::kExploreLite) {
    // explore_lite's cost over the clusters that offer a goal (ties: the lower cluster id).
    float best = std::numeric_limits<float>::infinity();
    for (std::size_t k = 0; k < res.clusters.size(); ++k) {
      if (ws.cluster_goal[k] < 0) continue;
      const float d = std::sqrt(best_e[k]);
      const float cost = s.potential_scale * d - s.gain_scale * static_cast<float>(res.clusters[k].cells) * g.resolution_m;
      if (cost < best) {
        best = cost;
        goal = ws.cluster_goal[k];
      }
    }
  }
  res.status = FrontierStatus::kFound;
  const auto gl = static_cast<std::size_t>(goal);
  res.goal_xy = g.cell_center(gl);
  res.target_xy = ws.mask[gl] == 3 ? g.cell_center(static_cast<std::size_t>(ws.approach_src[gl])) : res.goal_xy;
  std::vector<std::size_t> cells;
  std::size_t n_orth = 0, n_diag = 0;
  if (wide) trace_back(g, ws.cost64.data(), static_cast<std::size_t>(start), gl, cells, n_orth, n_diag);
  else trace_back(g, ws.cost32.data(), static_cast<std::size_t>(start), gl, cells, n_orth, n_diag);
  res.path.reserve(cells.size());
  for (const std::size_t c : cells) res.path.push_back(g.cell_center(c));
  std::reverse(res.path.begin(), res.path.end());
  // Exact length of the step sequence (the fixed-point cost differs by < 1e-5 cell per step).
  res.path_length_m = static_cast<float>((static_cast<double>(n_orth) + static_cast<double>(n_diag) * std::numbers::sqrt2) *
                                         g.resolution_m);
  return res;
}

}  // namespace duet
