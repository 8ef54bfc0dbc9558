#pragma once
/// @file texture_simd.hpp
/// SSE2 version of texture.hpp's evaluate_texture() for four texture coordinates (u, v) [cells]
/// of one surface at once (the renderer evaluates a 4-pixel row of a ray packet per call).
/// Internal to duet_runtime.
///
/// Bit-identical to the scalar evaluate_texture() for every non-NaN input, infinities and values
/// beyond the +-1e9 clamp included: the same float operations in the same order (SSE2 has no
/// FMA, so nothing is contracted), the integer lattice hash computed exactly (32-bit
/// wrap-around products), float -> int conversions by the same truncating instruction the
/// scalar code compiles to. (For NaN the scalar float -> int conversion is undefined behaviour
/// in C++; the renderer never passes NaN: hit points of finite poses are finite.) The renderer's colour therefore does not
/// depend on which path runs; tests/runtime/test_sim_renderer.cpp checks the identity.
/// Only the lattice products are reorganised: (x + 1) * A = x * A + A (mod 2^32), exact.
///
/// Thread safety: pure functions.
#include "texture.hpp"  // same directory (also found from the tests)

#if defined(__SSE2__)
#include <emmintrin.h>

namespace duet::sim::detail {

struct Rgb4 {
  __m128 r, g, b;
};

/// Low 32 bits of a * b per lane (SSE4.1's pmulld, from two SSE2 32x32 -> 64-bit products).
[[nodiscard]] inline __m128i mullo_epi32_sse2(__m128i a, __m128i b) noexcept {
  const __m128i even = _mm_mul_epu32(a, b);
  const __m128i odd = _mm_mul_epu32(_mm_srli_epi64(a, 32), _mm_srli_epi64(b, 32));
  return _mm_unpacklo_epi32(_mm_shuffle_epi32(even, _MM_SHUFFLE(0, 0, 2, 0)), _mm_shuffle_epi32(odd, _MM_SHUFFLE(0, 0, 2, 0)));
}

/// The mixing tail of lattice_hash() applied to (x * 0x9E3779B1) ^ (y * 0x85EBCA77) ^ seed.
[[nodiscard]] inline __m128i lattice_mix4(__m128i xa, __m128i yb, __m128i seed) noexcept {
  __m128i h = _mm_xor_si128(_mm_xor_si128(xa, yb), seed);
  h = _mm_xor_si128(h, _mm_srli_epi32(h, 15));
  h = mullo_epi32_sse2(h, _mm_set1_epi32(static_cast<int>(0x2C1B3C6Du)));
  return _mm_xor_si128(h, _mm_srli_epi32(h, 13));
}

[[nodiscard]] inline __m128i times_a4(__m128i x) noexcept {
  return mullo_epi32_sse2(x, _mm_set1_epi32(static_cast<int>(0x9E3779B1u)));
}
[[nodiscard]] inline __m128i times_b4(__m128i y) noexcept {
  return mullo_epi32_sse2(y, _mm_set1_epi32(static_cast<int>(0x85EBCA77u)));
}

/// lattice_hash(x, y, seed) per lane.
[[nodiscard]] inline __m128i lattice_hash4(__m128i x, __m128i y, __m128i seed) noexcept {
  return lattice_mix4(times_a4(x), times_b4(y), seed);
}

/// unit_float() per lane: [0, 1) from the top 24 bits (exact: < 2^24 converts without rounding).
[[nodiscard]] inline __m128 unit_float4(__m128i h) noexcept {
  return _mm_mul_ps(_mm_cvtepi32_ps(_mm_srli_epi32(h, 8)), _mm_set1_ps(1.0f / 16777216.0f));
}

/// Lane-wise a ? x : y for a float mask a.
[[nodiscard]] inline __m128 select4(__m128 mask, __m128 x, __m128 y) noexcept {
  return _mm_or_ps(_mm_and_ps(mask, x), _mm_andnot_ps(mask, y));
}

/// fast_floor() per lane (values compared beyond +-1e9 are clamped, as in the scalar code; NaN
/// passes the clamp and converts to INT_MIN).
[[nodiscard]] inline __m128i fast_floor4(__m128 x) noexcept {
  const __m128 lo = _mm_set1_ps(-1.0e9f), hi = _mm_set1_ps(1.0e9f);
  const __m128 below = _mm_cmplt_ps(x, lo), above = _mm_cmpgt_ps(x, hi);
  x = select4(below, lo, select4(above, hi, x));
  const __m128i i = _mm_cvttps_epi32(x);
  // i - (float(i) > x ? 1 : 0): the compare mask is -1 where true.
  return _mm_add_epi32(i, _mm_castps_si128(_mm_cmpgt_ps(_mm_cvtepi32_ps(i), x)));
}

/// value_noise() per lane.
[[nodiscard]] inline __m128 value_noise4(__m128 u, __m128 v, __m128i seed) noexcept {
  const __m128i iu = fast_floor4(u), iv = fast_floor4(v);
  const __m128 fu = _mm_sub_ps(u, _mm_cvtepi32_ps(iu)), fv = _mm_sub_ps(v, _mm_cvtepi32_ps(iv));
  const __m128 three = _mm_set1_ps(3.0f), two = _mm_set1_ps(2.0f);
  const __m128 su = _mm_mul_ps(_mm_mul_ps(fu, fu), _mm_sub_ps(three, _mm_mul_ps(two, fu)));
  const __m128 sv = _mm_mul_ps(_mm_mul_ps(fv, fv), _mm_sub_ps(three, _mm_mul_ps(two, fv)));
  const __m128i xa0 = times_a4(iu), yb0 = times_b4(iv);
  const __m128i xa1 = _mm_add_epi32(xa0, _mm_set1_epi32(static_cast<int>(0x9E3779B1u)));  // (iu + 1) * A
  const __m128i yb1 = _mm_add_epi32(yb0, _mm_set1_epi32(static_cast<int>(0x85EBCA77u)));  // (iv + 1) * B
  const __m128 a = unit_float4(lattice_mix4(xa0, yb0, seed)), b = unit_float4(lattice_mix4(xa1, yb0, seed));
  const __m128 c = unit_float4(lattice_mix4(xa0, yb1, seed)), d = unit_float4(lattice_mix4(xa1, yb1, seed));
  const __m128 ab = _mm_add_ps(a, _mm_mul_ps(su, _mm_sub_ps(b, a)));
  const __m128 cd = _mm_add_ps(c, _mm_mul_ps(su, _mm_sub_ps(d, c)));
  return _mm_add_ps(ab, _mm_mul_ps(sv, _mm_sub_ps(cd, ab)));
}

[[nodiscard]] inline Rgb4 scale4(const Rgbf& base, __m128 f) noexcept {
  return {_mm_mul_ps(_mm_set1_ps(base.r), f), _mm_mul_ps(_mm_set1_ps(base.g), f), _mm_mul_ps(_mm_set1_ps(base.b), f)};
}

/// evaluate_texture(texture, base, u[i], v[i], seed) for the four lanes i (see texture.hpp).
[[nodiscard]] inline Rgb4 evaluate_texture4(Texture texture, const Rgbf& base, __m128 u, __m128 v, std::uint32_t seed) noexcept {
  const __m128i vseed = _mm_set1_epi32(static_cast<int>(seed));
  const __m128 one = _mm_set1_ps(1.0f);
  switch (texture) {
    case Texture::kPlain:
      break;
    case Texture::kNoise: {
      const __m128 c = value_noise4(u, v, vseed);
      // level = [c > 0.38] + [c > 0.5] + [c > 0.62] (small integers: exact in any order)
      const __m128 level = _mm_add_ps(_mm_add_ps(_mm_and_ps(_mm_cmpgt_ps(c, _mm_set1_ps(0.38f)), one),
                                                 _mm_and_ps(_mm_cmpgt_ps(c, _mm_set1_ps(0.5f)), one)),
                                      _mm_and_ps(_mm_cmpgt_ps(c, _mm_set1_ps(0.62f)), one));
      const __m128 three = _mm_set1_ps(3.0f);
      const __m128 fine = unit_float4(lattice_hash4(fast_floor4(_mm_mul_ps(three, u)), fast_floor4(_mm_mul_ps(three, v)),
                                                    _mm_set1_epi32(static_cast<int>(seed ^ 0x5bd1e995u))));
      const __m128 f = _mm_mul_ps(_mm_add_ps(_mm_set1_ps(0.4f), _mm_mul_ps(_mm_set1_ps(0.2f), level)),
                                  _mm_add_ps(_mm_set1_ps(0.75f), _mm_mul_ps(_mm_set1_ps(0.5f), fine)));
      return scale4(base, f);
    }
    case Texture::kChecker: {
      const __m128i odd = _mm_and_si128(_mm_add_epi32(fast_floor4(u), fast_floor4(v)), _mm_set1_epi32(1));
      const __m128 is_odd = _mm_castsi128_ps(_mm_cmpeq_epi32(odd, _mm_set1_epi32(1)));
      return scale4(base, select4(is_odd, _mm_set1_ps(0.45f), one));
    }
    case Texture::kBricks: {
      const __m128i row = fast_floor4(v);
      const __m128 odd_row = _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_and_si128(row, _mm_set1_epi32(1)), _mm_set1_epi32(1)));
      const __m128 uu = _mm_add_ps(u, _mm_and_ps(odd_row, one));  // u + (odd ? 1 : 0)
      const __m128i col = fast_floor4(_mm_mul_ps(_mm_set1_ps(0.5f), uu));
      const __m128 fu = _mm_sub_ps(uu, _mm_mul_ps(_mm_set1_ps(2.0f), _mm_cvtepi32_ps(col)));
      const __m128 fv = _mm_sub_ps(v, _mm_cvtepi32_ps(row));
      const __m128 tenth = _mm_set1_ps(0.1f);
      const __m128 mortar = _mm_or_ps(_mm_cmplt_ps(fu, tenth), _mm_cmplt_ps(fv, tenth));
      const __m128 brick = _mm_add_ps(_mm_set1_ps(0.6f), _mm_mul_ps(_mm_set1_ps(0.35f), unit_float4(lattice_hash4(col, row, vseed))));
      return scale4(base, select4(mortar, _mm_set1_ps(1.3f), brick));
    }
    case Texture::kPosters: {
      const __m128 quarter = _mm_set1_ps(0.25f), four = _mm_set1_ps(4.0f);
      const __m128i cu = fast_floor4(_mm_mul_ps(quarter, u)), cv = fast_floor4(_mm_mul_ps(quarter, v));
      const __m128i h = lattice_hash4(cu, cv, vseed);
      const __m128 poster = _mm_cmplt_ps(unit_float4(h), _mm_set1_ps(0.65f));  // scalar: !(unit >= 0.65)
      if (_mm_movemask_ps(poster) == 0) break;
      const __m128i h2 = lattice_mix4(times_a4(h), _mm_set1_epi32(static_cast<int>(17u * 0x85EBCA77u)),
                                      _mm_set1_epi32(static_cast<int>(seed ^ 0x9e3779b9u)));
      const __m128i h3 = lattice_mix4(times_a4(h2), _mm_set1_epi32(static_cast<int>(29u * 0x85EBCA77u)), vseed);
      const __m128 lu = _mm_sub_ps(u, _mm_mul_ps(four, _mm_cvtepi32_ps(cu)));
      const __m128 lv = _mm_sub_ps(v, _mm_mul_ps(four, _mm_cvtepi32_ps(cv)));
      const __m128i ff = _mm_set1_epi32(0xFF);
      const __m128 k12 = _mm_set1_ps(1.2f), k255 = _mm_set1_ps(255.0f);
      auto byte = [&](__m128i x, int shift) { return _mm_cvtepi32_ps(_mm_and_si128(_mm_srli_epi32(x, shift), ff)); };
      // 0.2 + 1.2 * b / 255 and 3.8 - 1.2 * b / 255, as the scalar code: (1.2 * b) / 255
      const __m128 u0 = _mm_add_ps(_mm_set1_ps(0.2f), _mm_div_ps(_mm_mul_ps(k12, byte(h2, 0)), k255));
      const __m128 u1 = _mm_sub_ps(_mm_set1_ps(3.8f), _mm_div_ps(_mm_mul_ps(k12, byte(h2, 8)), k255));
      const __m128 v0 = _mm_add_ps(_mm_set1_ps(0.2f), _mm_div_ps(_mm_mul_ps(k12, byte(h2, 16)), k255));
      const __m128 v1 = _mm_sub_ps(_mm_set1_ps(3.8f), _mm_div_ps(_mm_mul_ps(k12, byte(h2, 24)), k255));
      const __m128 outside = _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(lu, u0), _mm_cmpgt_ps(lu, u1)),
                                       _mm_or_ps(_mm_cmplt_ps(lv, v0), _mm_cmpgt_ps(lv, v1)));
      const __m128 use = _mm_andnot_ps(outside, poster);
      const __m128 k40 = _mm_set1_ps(40.0f), k215 = _mm_set1_ps(215.0f);
      Rgb4 c{_mm_add_ps(k40, _mm_div_ps(_mm_mul_ps(k215, byte(h3, 0)), k255)),
             _mm_add_ps(k40, _mm_div_ps(_mm_mul_ps(k215, byte(h3, 8)), k255)),
             _mm_add_ps(k40, _mm_div_ps(_mm_mul_ps(k215, byte(h3, 16)), k255))};
      // "Text": dark lines on the lower half, inset from the edges.
      const __m128 mid = _mm_mul_ps(_mm_set1_ps(0.5f), _mm_add_ps(v0, v1));
      const __m128 inset = _mm_set1_ps(0.2f);
      const __m128i line = _mm_and_si128(fast_floor4(_mm_mul_ps(four, lv)), _mm_set1_epi32(1));
      __m128 text = _mm_and_ps(_mm_cmplt_ps(lv, mid), _mm_cmpgt_ps(lu, _mm_add_ps(u0, inset)));
      text = _mm_and_ps(text, _mm_cmplt_ps(lu, _mm_sub_ps(u1, inset)));
      text = _mm_and_ps(text, _mm_cmpgt_ps(lv, _mm_add_ps(v0, inset)));
      text = _mm_and_ps(text, _mm_castsi128_ps(_mm_cmpeq_epi32(line, _mm_set1_epi32(1))));
      const __m128 dark = _mm_set1_ps(0.25f);
      c.r = select4(text, _mm_mul_ps(c.r, dark), c.r);
      c.g = select4(text, _mm_mul_ps(c.g, dark), c.g);
      c.b = select4(text, _mm_mul_ps(c.b, dark), c.b);
      return {select4(use, c.r, _mm_set1_ps(base.r)), select4(use, c.g, _mm_set1_ps(base.g)), select4(use, c.b, _mm_set1_ps(base.b))};
    }
  }
  return {_mm_set1_ps(base.r), _mm_set1_ps(base.g), _mm_set1_ps(base.b)};
}

}  // namespace duet::sim::detail

#endif  // __SSE2__
