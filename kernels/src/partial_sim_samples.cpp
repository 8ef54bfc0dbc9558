/// @file partial_sim_samples.cpp
/// Procedure 1's samples (lines 10-17 and 19) over the cells the walks stored: one sample at a time
/// (the reference), or up to 8 samples at once in AVX2 lanes - the same bits (every lane does the
/// scalar's float operations in the scalar's order; no FMA), at about half the time.
#include "partial_sim_samples.hpp"

#include <duet/kernels/error.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define DUET_PARTIAL_SIM_LANES 1
#else
#define DUET_PARTIAL_SIM_LANES 0
#endif

namespace duet::detail {

PartialSimSamples partial_sim_samples = PartialSimSamples::kAuto;

bool partial_sim_lanes_available() {
#if DUET_PARTIAL_SIM_LANES
  static const bool avx2 = __builtin_cpu_supports("avx2");
  return avx2;
#else
  return false;
#endif
}

}  // namespace duet::detail

namespace duet::detail::partial_sim {
namespace {

// What a sample needs of the settings, read once (the compiler reloaded them through s per cell).
struct SampleConstants {
  int H;
  std::size_t rays;
  float l_min, l_max, inv_log_q;
  explicit SampleConstants(const PartialSimSettings& s, std::size_t rays_per_stage)
      : H(s.stages), rays(rays_per_stage), l_min(s.min_logodds), l_max(s.max_logodds),
        inv_log_q(1.0f / std::log1p(-s.unknown_hit_probability)) {}
};

// z ~ chi (line 13): the number of unknown cells a ray passes before a sampled hit is geometric,
// floor(log(u) / log(1 - p)) for u uniform in (0, 1]; counts of 1e9 or more never end a ray.
inline std::int64_t unknown_cells_before_hit(float u, float inv_log_q) {
  const float g = std::log(u) * inv_log_q;  // >= 0: truncation is the floor
  return g < 1e9f ? static_cast<std::int64_t>(g) : std::numeric_limits<std::int64_t>::max();
}

// Line 14's noise of sample j at stage k: drawn once per (j, k), before the stage's rays.
inline float ism_noise(const PartialSimSettings& s, Rng& rng) {
  return s.ism_noise_logodds > 0.0f ? rng.uniform(-s.ism_noise_logodds, s.ism_noise_logodds) : 0.0f;
}

// What a (sample, stage) adds to the priors: l_ISM of a hit and of a miss (line 14), and lines
// 15-16 for a never-observed cell (prior 0, E = 1 bit), the same for all of them.
struct IsmTerms {
  float l_hit, l_miss, r_hit_nan, r_miss_nan;
  IsmTerms(const PartialSimSettings& s, const SampleConstants& sc, float delta)
      : l_hit(s.hit_logodds + delta), l_miss(s.miss_logodds + delta),
        r_hit_nan(1.0f - entropy_table()(std::clamp(l_hit, sc.l_min, sc.l_max))),
        r_miss_nan(1.0f - entropy_table()(std::clamp(l_miss, sc.l_min, sc.l_max))) {}
};

// One sample at a time: the reference the lanes are tested against.
SampleTotals one_at_a_time(const PartialSimSettings& s, const SampleConstants& sc, int phi, Rng& rng, ThreadScratch& ts,
                           std::size_t n_cells) {
  const EntropyTable& et = entropy_table();
  SampleTotals out;
  const RayCell* const cells = ts.cells.data();
  const std::uint32_t* const ray_end = ts.ray_end.data();
  const float l_min = sc.l_min, l_max = sc.l_max;
  std::int64_t visits = 0;
  for (int j = 0; j < phi; ++j) {
    const std::uint32_t stamp = ts.overlay.next(n_cells, (1u << 31) - 1);  // (stamp << 1) must fit
    std::uint32_t* const ov = ts.overlay.word.data();
    double disc_sum = 0.0;
    for (int k = 0; k < sc.H; ++k) {
      const IsmTerms ism(s, sc, ism_noise(s, rng));
      const float l_hit = ism.l_hit, l_miss = ism.l_miss, r_hit_nan = ism.r_hit_nan, r_miss_nan = ism.r_miss_nan;
      float r_k = 0.0f, r_unknown = 0.0f;
      for (std::size_t r = 0; r < sc.rays; ++r) {
        const std::size_t ray = static_cast<std::size_t>(k) * sc.rays + r;
        const std::uint32_t begin = ray == 0 ? 0u : ray_end[ray - 1];
        const std::uint32_t end = ray_end[ray];
        // u is drawn for every ray (the stream does not depend on the cells), its log only when
        // the ray meets an unknown cell (most rays end on a known wall): unknown_left < 0 = not yet.
        const float u = 1.0f - rng.uniform01();  // (0, 1]
        std::int64_t unknown_left = -1;
        for (std::uint32_t c = begin; c < end; ++c) {
          const RayCell cell = cells[c];
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
            if (unknown_left < 0) unknown_left = unknown_cells_before_hit(u, sc.inv_log_q);
            hit = unknown_left == 0;
            --unknown_left;
          }
          if (kind == kUnknownNan) {
            const float gain = hit ? r_hit_nan : r_miss_nan;  // 1 bit - E(clamp(l_ISM))
            r_k += gain;
            r_unknown += gain;
          } else {
            const float post = std::clamp(cell.l + (hit ? l_hit : l_miss), l_min, l_max);  // line 15
            const float gain = cell.e - et(post);  // line 16 (cell.e = E(l_prior), from the walk)
            r_k += gain;
            if (kind == kUnknownFinite) r_unknown += gain;
          }
          if (idx != kOutside) ov[idx] = (stamp << 1) | (hit ? 1u : 0u);
          if (hit) break;
        }
      }
      disc_sum += std::pow(static_cast<double>(s.gamma), static_cast<double>(k - sc.H)) * r_k;  // line 19 term
      out.reward_sum += r_k;
      out.unknown_sum += r_unknown;
    }
    out.log_w += disc_sum > 0.0 ? std::log(disc_sum) : -std::numeric_limits<double>::infinity();
  }
  out.visits = visits;
  return out;
}

#if DUET_PARTIAL_SIM_LANES

/// All ones in the lanes whose bit is set in bits (lane_bit: 1, 2, 4, ... 128).
__attribute__((target("avx2"))) inline __m256i lane_mask(std::uint32_t bits, __m256i lane_bit) {
  return _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(static_cast<int>(bits)), lane_bit), lane_bit);
}

// Up to 8 samples at once, one per lane, ray by ray and cell by cell: a cell is read once for all
// of them, and the rewards (the entropy table's interpolation, two gathers) are computed in
// vectors. Each lane does exactly the scalar's float operations in the scalar's order: the random
// numbers are drawn first in the scalar's order; per lane, a cell's reward is added to R_tj in
// the cells' order (a lane that does not count the cell keeps its sum, a blend); line 19's double
// sums are taken after, sample by sample as the scalar takes them; no FMA (only avx2 is enabled).
// The overlay word of a cell holds the group's stamp (16 bits), a bit per lane "seen in this
// sample" and a bit per lane "sampled occupied" (ThreadScratch::lanes_overlay).
__attribute__((target("avx2"))) SampleTotals lanes(const PartialSimSettings& s, const SampleConstants& sc, int phi, Rng& rng,
                                                    ThreadScratch& ts, std::size_t n_cells) {
  const EntropyTable& et = entropy_table();
  const float* const table = et.v.data();
  const int H = sc.H;
  const std::size_t R = sc.rays;
  const auto Hz = static_cast<std::size_t>(H);
  const auto phiz = static_cast<std::size_t>(phi);
  // The random numbers, in the order the scalar draws them.
  ts.lane_delta.resize(phiz * Hz);
  ts.lane_u.resize(phiz * Hz * R);
  for (std::size_t j = 0; j < phiz; ++j)
    for (std::size_t k = 0; k < Hz; ++k) {
      ts.lane_delta[j * Hz + k] = ism_noise(s, rng);
      for (std::size_t r = 0; r < R; ++r) ts.lane_u[(j * Hz + k) * R + r] = 1.0f - rng.uniform01();
    }
  ts.lane_rk.assign(phiz * Hz, 0.0f);
  ts.lane_ru.assign(phiz * Hz, 0.0f);

  const RayCell* const cells = ts.cells.data();
  const std::uint32_t* const ray_end = ts.ray_end.data();
  const __m256i lane_bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
  const __m256 v_min = _mm256_set1_ps(sc.l_min), v_max = _mm256_set1_ps(sc.l_max);
  const __m256 v_table_l = _mm256_set1_ps(kTableL), v_table_scale = _mm256_set1_ps(kTableScale);
  const __m256i one = _mm256_set1_epi32(1), zero = _mm256_setzero_si256();
  std::int64_t visits = 0;

  for (std::size_t j0 = 0; j0 < phiz; j0 += 8) {
    const int n_lanes = static_cast<int>(std::min<std::size_t>(8, phiz - j0));
    const std::uint32_t all = (1u << n_lanes) - 1u;
    const std::uint32_t stamp = ts.lanes_overlay.next(n_cells, 0xFFFFu) << 16;
    std::uint32_t* const ov = ts.lanes_overlay.word.data();
    for (int k = 0; k < H; ++k) {
      alignas(32) float lh[8], lm[8], rhn[8], rmn[8];
      for (int q = 0; q < 8; ++q) {  // lanes past n_lanes repeat the first: finite, never counted
        const std::size_t j = j0 + static_cast<std::size_t>(q < n_lanes ? q : 0);
        const IsmTerms ism(s, sc, ts.lane_delta[j * Hz + static_cast<std::size_t>(k)]);
        lh[q] = ism.l_hit;
        lm[q] = ism.l_miss;
        rhn[q] = ism.r_hit_nan;
        rmn[q] = ism.r_miss_nan;
      }
      const __m256 v_lh = _mm256_load_ps(lh), v_lm = _mm256_load_ps(lm), v_rhn = _mm256_load_ps(rhn), v_rmn = _mm256_load_ps(rmn);
      __m256 r_k = _mm256_setzero_ps(), r_unknown = _mm256_setzero_ps();
      for (std::size_t r = 0; r < R; ++r) {
        const std::size_t ray = static_cast<std::size_t>(k) * R + r;
        const std::uint32_t begin = ray == 0 ? 0u : ray_end[ray - 1];
        const std::uint32_t end = ray_end[ray];
        std::uint32_t active = all;  // lanes whose ray goes on
        __m256i left = _mm256_set1_epi32(-1);  // unknown cells before the hit; < 0: not drawn yet
        for (std::uint32_t c = begin; c < end; ++c) {
          const RayCell cell = cells[c];
          const std::uint32_t kind = cell.packed & 3u;
          const std::uint32_t idx = cell.packed >> 2;
          visits += std::popcount(active);
          const std::uint32_t o = idx != kOutside ? ov[idx] : 0u;
          const bool stamped = (o & 0xFFFF0000u) == stamp;
          const std::uint32_t seen = stamped ? (o >> 8) & 0xFFu : 0u, seen_hit = stamped ? o & 0xFFu : 0u;
          active &= ~(seen & seen_hit);  // sampled occupied before in the sample: stops this ray too
          const std::uint32_t counted = active & ~seen;
          if (counted == 0) {
            if (active == 0) break;
            continue;
          }
          std::uint32_t hit = 0;
          if (kind == kOccupiedCell) {
            hit = counted;
          } else if (kind != kFreeCell) {
            const __m256i m = lane_mask(counted, lane_bit);
            std::uint32_t draw = static_cast<std::uint32_t>(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(zero, left)))) & counted;
            if (draw != 0) {
              alignas(32) std::int32_t l32[8];
              _mm256_store_si256(reinterpret_cast<__m256i*>(l32), left);
              for (; draw != 0; draw &= draw - 1) {
                const int q = std::countr_zero(draw);
                const float u = ts.lane_u[((j0 + static_cast<std::size_t>(q)) * Hz + static_cast<std::size_t>(k)) * R + r];
                const std::int64_t g = unknown_cells_before_hit(u, sc.inv_log_q);  // counts past 2^31 - 1 never end a ray either
                l32[q] = g < std::numeric_limits<std::int32_t>::max() ? static_cast<std::int32_t>(g) : std::numeric_limits<std::int32_t>::max();
              }
              left = _mm256_load_si256(reinterpret_cast<const __m256i*>(l32));
            }
            hit = static_cast<std::uint32_t>(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(left, zero)))) & counted;
            left = _mm256_sub_epi32(left, _mm256_and_si256(m, one));
          }
          const __m256 hit_m = _mm256_castsi256_ps(lane_mask(hit, lane_bit));
          __m256 gain;
          if (kind == kUnknownNan) {
            gain = _mm256_blendv_ps(v_rmn, v_rhn, hit_m);  // 1 bit - E(clamp(l_ISM))
          } else {  // lines 15-16: E(l_prior) - E(clamp(l_prior + l_ISM)), EntropyTable::operator() per lane
            const __m256 post = _mm256_min_ps(_mm256_max_ps(_mm256_add_ps(_mm256_set1_ps(cell.l), _mm256_blendv_ps(v_lm, v_lh, hit_m)), v_min), v_max);
            const __m256 x = _mm256_mul_ps(_mm256_add_ps(post, v_table_l), v_table_scale);
            const __m256i i = _mm256_cvttps_epi32(x);
            const __m256 f = _mm256_sub_ps(x, _mm256_cvtepi32_ps(i));
            const __m256 a = _mm256_i32gather_ps(table, i, 4), b = _mm256_i32gather_ps(table + 1, i, 4);
            gain = _mm256_sub_ps(_mm256_set1_ps(cell.e), _mm256_add_ps(a, _mm256_mul_ps(f, _mm256_sub_ps(b, a))));
          }
          const __m256 counted_m = _mm256_castsi256_ps(lane_mask(counted, lane_bit));
          r_k = _mm256_blendv_ps(r_k, _mm256_add_ps(r_k, gain), counted_m);
          if (kind == kUnknownFinite || kind == kUnknownNan) r_unknown = _mm256_blendv_ps(r_unknown, _mm256_add_ps(r_unknown, gain), counted_m);
          if (idx != kOutside) ov[idx] = stamp | ((seen | counted) << 8) | (seen_hit | hit);
          active &= ~hit;
          if (active == 0) break;
        }
      }
      alignas(32) float rk[8], ru[8];
      _mm256_store_ps(rk, r_k);
      _mm256_store_ps(ru, r_unknown);
      for (int q = 0; q < n_lanes; ++q) {
        ts.lane_rk[(j0 + static_cast<std::size_t>(q)) * Hz + static_cast<std::size_t>(k)] = rk[q];
        ts.lane_ru[(j0 + static_cast<std::size_t>(q)) * Hz + static_cast<std::size_t>(k)] = ru[q];
      }
    }
  }
  // Line 19 and the reward sums in the scalar's order.
  SampleTotals out;
  for (std::size_t j = 0; j < phiz; ++j) {
    double disc_sum = 0.0;
    for (std::size_t k = 0; k < Hz; ++k) {
      const float r_k = ts.lane_rk[j * Hz + k];
      disc_sum += std::pow(static_cast<double>(s.gamma), static_cast<double>(static_cast<int>(k) - H)) * r_k;
      out.reward_sum += r_k;
      out.unknown_sum += ts.lane_ru[j * Hz + k];
    }
    out.log_w += disc_sum > 0.0 ? std::log(disc_sum) : -std::numeric_limits<double>::infinity();
  }
  out.visits = visits;
  return out;
}

#endif

}  // namespace

SampleTotals simulate_samples(const PartialSimSettings& s, std::size_t rays_per_stage, int phi, Rng& rng, ThreadScratch& ts,
                              std::size_t n_cells) {
  const SampleConstants sc(s, rays_per_stage);
  const PartialSimSamples which = partial_sim_samples;
  if (which == PartialSimSamples::kLanes && !partial_sim_lanes_available())
    fail(ErrorCode::kUnsupported, "partial_map_simulation: the samples' AVX2 lanes were asked for, and this CPU or build has no AVX2");
#if DUET_PARTIAL_SIM_LANES
  if (which == PartialSimSamples::kLanes || (which == PartialSimSamples::kAuto && partial_sim_lanes_available()))
    return lanes(s, sc, phi, rng, ts, n_cells);
#endif
  return one_at_a_time(s, sc, phi, rng, ts, n_cells);
}

}  // namespace duet::detail::partial_sim
