#pragma once
/// @file renderer_detail.hpp
/// Internals shared by renderer.cpp (mesh, Embree scene, the public class) and renderer_tiles.cpp
/// (per-tile ray tracing, depth noise, shading): argument checks, hashing, Face, FrameParams.
#include <duet/sim/renderer.hpp>

#include <duet/kernels/error.hpp>

#include "texture.hpp"

#include <embree3/rtcore.h>

#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

namespace duet::sim::render_detail {

inline std::string num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

inline void check_range(const char* owner, const char* field, float v, float lo, float hi, bool lo_open, bool hi_open) {
  const bool ok = std::isfinite(v) && (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  if (!ok)
    fail(ErrorCode::kInvalidArgument, std::string(owner) + "." + field + " = " + num(v) + ": expected a value in " +
                                          (lo_open ? "(" : "[") + num(lo) + ", " + num(hi) + (hi_open ? ")" : "]"));
}

// ---- counter-based random numbers --------------------------------------------------------------

constexpr std::uint64_t kGolden = 0x9E3779B97F4A7C15ull;

inline std::uint64_t splitmix64(std::uint64_t x) noexcept {
  x += kGolden;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// Everything the shader needs about one planar face of a surface (flat: one plane, one surface).
/// Triangles that share all of it (the two of a wall quad, a cap's fan) share one Face, so a ray
/// packet that a quad's diagonal splits still evaluates its texture in one pass.
struct Face {
  float n[3];            ///< unit normal (outward)
  float tu[4], tv[4];    ///< texture coordinates [cells]: u = tu . (x, y, z, 1)
  float shade_front;     ///< Lambert + ambient, seen from the normal's side
  float shade_back;      ///< seen from behind
  detail::Rgbf base;     ///< surface colour 0..255
  std::uint32_t seed;    ///< texture seed of the surface
  Texture texture;
};

/// Per-frame constants of one render job (everything a tile needs).
struct FrameParams {
  int w = 0, h = 0;
  Eigen::Vector3f origin, base_dir, du, dv;  // d(u, v) = base_dir + u * du + v * dv (optical z = 1)
  float depth_tfar = 0.0f;                   // hits farther than this give no depth
  float ray_tfar = 0.0f;                     // how far rays are traced
  float min_depth = 0.0f, max_depth = 0.0f, units = 1000.0f;
  bool noise = false;
  float a = 0.0f, b = 0.0f, c = 0.0f, ang = 0.0f, q = 0.0f, cos2_min = 0.0f;
  std::uint64_t dropout_threshold = 0;  // a pixel drops when (hash >> 32) < threshold
  std::uint64_t seed_key = 0;
  bool colour = true;
  std::uint16_t* depth = nullptr;  // output buffers (set once the image is sized)
  std::uint8_t* rgb = nullptr;     // null: depth only
  int tiles_x = 0, tiles = 0;
};

/// Frame constants from one job (renderer_tiles.cpp).
FrameParams make_params(const RenderSettings& settings, const SensorProfile& sensor, const Eigen::Isometry3f& T_world_optical,
                        std::uint64_t frame_seed, bool colour);

/// Renders tile `tile` of one frame (renderer_tiles.cpp).
void render_tile(const FrameParams& P, const Face* faces, const std::uint32_t* tri_face, RTCScene scene, int tile);

}  // namespace duet::sim::render_detail
