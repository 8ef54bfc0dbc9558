#pragma once
/// @file texture.hpp
/// Procedural surface textures of the simulator (world.hpp enum Texture), evaluated per pixel by
/// the renderer. Internal to duet_runtime.
///
/// A texture is a function of the hit point's coordinates on the surface's plane, expressed in
/// texture cells (metres / Surface::texture_scale_m), and of a per-surface seed: the same point
/// of the same surface has the same colour from every view. It returns the surface colour
/// modulated (or, for posters, replaced) as linear 0..255 floats (before shading; may exceed 255
/// slightly, the caller clamps).
///
/// Thread safety: pure functions.
#include <duet/sim/world.hpp>

#include <cstdint>

namespace duet::sim::detail {

struct Rgbf {
  float r = 0.0f, g = 0.0f, b = 0.0f;
};

/// Integer lattice hash: the lattice point and seed mixed by two odd multipliers, then one
/// xorshift-multiply-xorshift round - enough for visual randomness at a few cycles.
[[nodiscard]] inline std::uint32_t lattice_hash(std::int32_t x, std::int32_t y, std::uint32_t seed) noexcept {
  std::uint32_t h = (static_cast<std::uint32_t>(x) * 0x9E3779B1u) ^ (static_cast<std::uint32_t>(y) * 0x85EBCA77u) ^ seed;
  h ^= h >> 15;
  h *= 0x2C1B3C6Du;
  h ^= h >> 13;
  return h;
}

/// [0, 1) from the top 24 bits.
[[nodiscard]] inline float unit_float(std::uint32_t h) noexcept {
  return static_cast<float>(h >> 8) * (1.0f / 16777216.0f);
}

/// floor() for |x| <= 1e9 (larger values are clamped; the renderer never passes NaN: hit
/// points of finite poses are finite). No libm call.
[[nodiscard]] inline std::int32_t fast_floor(float x) noexcept {
  x = x < -1.0e9f ? -1.0e9f : (x > 1.0e9f ? 1.0e9f : x);
  const auto i = static_cast<std::int32_t>(x);
  return i - (static_cast<float>(i) > x ? 1 : 0);
}

/// Smooth value noise in [0, 1): random values on the integer lattice, smoothstep-interpolated.
[[nodiscard]] inline float value_noise(float u, float v, std::uint32_t seed) noexcept {
  const std::int32_t iu = fast_floor(u), iv = fast_floor(v);
  const float fu = u - static_cast<float>(iu), fv = v - static_cast<float>(iv);
  const float su = fu * fu * (3.0f - 2.0f * fu), sv = fv * fv * (3.0f - 2.0f * fv);
  const float a = unit_float(lattice_hash(iu, iv, seed)), b = unit_float(lattice_hash(iu + 1, iv, seed));
  const float c = unit_float(lattice_hash(iu, iv + 1, seed)), d = unit_float(lattice_hash(iu + 1, iv + 1, seed));
  const float ab = a + su * (b - a), cd = c + su * (d - c);
  return ab + sv * (cd - ab);
}

/// The texture's colour at texture coordinates (u, v) [cells] of a surface with colour `base`.
///  - kPlain:   base.
///  - kNoise:   two scales - blotches of one cell (smooth value noise posterised into 4 brightness
///              levels, 40-100 %: sharp-edged patches whose outlines bend, i.e. corners) times a
///              blocky finer layer of 1/3-cell squares of +-25 % brightness (FAST / ORB need
///              steps of ~20 grey levels, also on dark, unlit surfaces).
///  - kChecker: squares of one cell, alternating base and 45 % of base.
///  - kBricks:  bricks of 2 x 1 cells, every other row offset by one cell, each brick 60-95 %
///              of base, light mortar lines 0.1 cell wide.
///  - kPosters: on a 4-cell lattice, 65 % of the squares carry a rectangle of a random saturated
///              colour with dark "text" lines on its lower half; elsewhere base.
[[nodiscard]] inline Rgbf evaluate_texture(Texture texture, const Rgbf& base, float u, float v,
                                           std::uint32_t seed) noexcept {
  switch (texture) {
    case Texture::kPlain:
      return base;
    case Texture::kNoise: {
      const float c = value_noise(u, v, seed);
      const float level = (c > 0.38f ? 1.0f : 0.0f) + (c > 0.5f ? 1.0f : 0.0f) + (c > 0.62f ? 1.0f : 0.0f);
      const float fine = unit_float(lattice_hash(fast_floor(3.0f * u), fast_floor(3.0f * v), seed ^ 0x5bd1e995u));
      const float f = (0.4f + 0.2f * level) * (0.75f + 0.5f * fine);
      return {base.r * f, base.g * f, base.b * f};
    }
    case Texture::kChecker: {
      const float f = ((fast_floor(u) + fast_floor(v)) & 1) != 0 ? 0.45f : 1.0f;
      return {base.r * f, base.g * f, base.b * f};
    }
    case Texture::kBricks: {
      const std::int32_t row = fast_floor(v);
      const float uu = u + ((row & 1) != 0 ? 1.0f : 0.0f);
      const std::int32_t col = fast_floor(0.5f * uu);
      const float fu = uu - 2.0f * static_cast<float>(col), fv = v - static_cast<float>(row);
      float f;
      if (fu < 0.1f || fv < 0.1f) {
        f = 1.3f;  // mortar
      } else {
        f = 0.6f + 0.35f * unit_float(lattice_hash(col, row, seed));
      }
      return {base.r * f, base.g * f, base.b * f};
    }
    case Texture::kPosters: {
      const std::int32_t cu = fast_floor(0.25f * u), cv = fast_floor(0.25f * v);
      const std::uint32_t h = lattice_hash(cu, cv, seed);
      if (unit_float(h) >= 0.65f) return base;
      const std::uint32_t h2 = lattice_hash(static_cast<std::int32_t>(h), 17, seed ^ 0x9e3779b9u);
      const std::uint32_t h3 = lattice_hash(static_cast<std::int32_t>(h2), 29, seed);
      const float lu = u - 4.0f * static_cast<float>(cu), lv = v - 4.0f * static_cast<float>(cv);
      const float u0 = 0.2f + 1.2f * static_cast<float>(h2 & 0xFFu) / 255.0f;
      const float u1 = 3.8f - 1.2f * static_cast<float>((h2 >> 8) & 0xFFu) / 255.0f;
      const float v0 = 0.2f + 1.2f * static_cast<float>((h2 >> 16) & 0xFFu) / 255.0f;
      const float v1 = 3.8f - 1.2f * static_cast<float>((h2 >> 24) & 0xFFu) / 255.0f;
      if (lu < u0 || lu > u1 || lv < v0 || lv > v1) return base;
      Rgbf c{40.0f + 215.0f * static_cast<float>(h3 & 0xFFu) / 255.0f,
             40.0f + 215.0f * static_cast<float>((h3 >> 8) & 0xFFu) / 255.0f,
             40.0f + 215.0f * static_cast<float>((h3 >> 16) & 0xFFu) / 255.0f};
      // "Text": dark lines, 0.25 cell apart, on the lower half, inset from the edges.
      const float mid = 0.5f * (v0 + v1);
      if (lv < mid && lu > u0 + 0.2f && lu < u1 - 0.2f && lv > v0 + 0.2f && (fast_floor(4.0f * lv) & 1) != 0) {
        c.r *= 0.25f;
        c.g *= 0.25f;
        c.b *= 0.25f;
      }
      return c;
    }
  }
  return base;
}

}  // namespace duet::sim::detail
