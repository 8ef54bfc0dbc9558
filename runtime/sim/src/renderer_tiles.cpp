/// @file renderer_tiles.cpp
/// The renderer's per-frame work: packet ray tracing over pixel tiles, Kinect-like depth noise and
/// procedural colour (issue 4, part 2). See renderer.hpp; the scene is built in renderer.cpp.
#include <duet/sim/renderer.hpp>

#include <duet/kernels/error.hpp>

#include "renderer_detail.hpp"
#include "texture.hpp"
#include "texture_simd.hpp"

#include <embree3/rtcore.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <string>

namespace duet::sim {
namespace {

using render_detail::check_range;
using render_detail::Face;
using render_detail::FrameParams;
using render_detail::kGolden;
using render_detail::splitmix64;

/// N(0, 1) by the inverse CDF, tabulated at 4096 equal-probability knots and linearly
/// interpolated (exact quantiles at the knots; the two tail bins end where their mean matches
/// the conditional mean of the tail). A 32-bit uniform maps to one sample: no libm call per pixel.
struct GaussTable {
  static constexpr int kBits = 12;
  static constexpr int kN = 1 << kBits;
  std::array<float, kN + 1> q{};

  GaussTable() {
    auto cdf = [](double x) { return 0.5 * std::erfc(-x / std::numbers::sqrt2); };
    auto quantile = [&](double p) {
      double lo = -10.0, hi = 10.0;
      for (int i = 0; i < 100; ++i) {
        const double mid = 0.5 * (lo + hi);
        (cdf(mid) < p ? lo : hi) = mid;
      }
      return 0.5 * (lo + hi);
    };
    for (int k = 1; k < kN; ++k) q[static_cast<std::size_t>(k)] = static_cast<float>(quantile(static_cast<double>(k) / kN));
    const double a = q[1];
    const double pdf = std::exp(-0.5 * a * a) / std::sqrt(2.0 * std::numbers::pi);
    const double tail_mean = -pdf / cdf(a);  // E[Z | Z < a]
    q[0] = static_cast<float>(2.0 * tail_mean - a);
    q[kN] = -q[0];
  }
  [[nodiscard]] float sample(std::uint32_t h) const noexcept {
    const std::uint32_t i = h >> (32 - kBits);
    const float f = static_cast<float>(h & ((1u << (32 - kBits)) - 1u)) * (1.0f / static_cast<float>(1u << (32 - kBits)));
    return q[i] + f * (q[i + 1] - q[i]);
  }
};

const GaussTable& gauss_table() {
  static const GaussTable t;
  return t;
}

void validate_sensor(const SensorProfile& s) {
  const PinholeIntrinsics& in = s.intrinsics;
  const std::string who = "RgbdRenderer: sensor '" + s.name + "'";
  if (in.width < 1 || in.width > 16384 || in.height < 1 || in.height > 16384)
    fail(ErrorCode::kInvalidArgument, who + ": intrinsics.width/height = " + std::to_string(in.width) + "x" +
                                          std::to_string(in.height) + ": expected each in [1, 16384]");
  check_range(who.c_str(), "intrinsics.fx", in.fx, 0.0f, 1e6f, true, false);
  check_range(who.c_str(), "intrinsics.fy", in.fy, 0.0f, 1e6f, true, false);
  check_range(who.c_str(), "intrinsics.cx", in.cx, -1e6f, 1e6f, false, false);
  check_range(who.c_str(), "intrinsics.cy", in.cy, -1e6f, 1e6f, false, false);
  check_range(who.c_str(), "min_depth_m", s.min_depth_m, 0.0f, 100.0f, false, true);
  check_range(who.c_str(), "max_depth_m", s.max_depth_m, s.min_depth_m, 100.0f, true, false);
  check_range(who.c_str(), "depth_units_per_m", s.depth_units_per_m, 0.0f, 1e6f, true, false);
}

// ---- packets ------------------------------------------------------------------------------------

template <int N>
struct PacketTraits;
template <>
struct PacketTraits<4> {
  using RayHit = RTCRayHit4;
  static void intersect(const int* valid, RTCScene s, RTCIntersectContext* c, RayHit* rh) { rtcIntersect4(valid, s, c, rh); }
};
template <>
struct PacketTraits<8> {
  using RayHit = RTCRayHit8;
  static void intersect(const int* valid, RTCScene s, RTCIntersectContext* c, RayHit* rh) { rtcIntersect8(valid, s, c, rh); }
};
template <>
struct PacketTraits<16> {
  using RayHit = RTCRayHit16;
  static void intersect(const int* valid, RTCScene s, RTCIntersectContext* c, RayHit* rh) { rtcIntersect16(valid, s, c, rh); }
};

// Packets of kPacketW x kPacketH neighbouring pixels (coherent rays: one origin, close
// directions), tiles of kTileW x kTileH pixels per TBB task. Measured on the lab benchmark
// (1 thread, CPU time of both frames): 4x4 packets (rtcIntersect16) 33.5 ms, 8x2 33.3 ms,
// 4x2 (rtcIntersect8) 36.8 ms, 2x2 (rtcIntersect4) 47.8 ms; tiles of 16x16, 32x16 and 64x16
// the same within noise.
constexpr int kPacketW = 4;
constexpr int kPacketH = 4;
constexpr int kPacket = kPacketW * kPacketH;
constexpr int kTileW = 32;
constexpr int kTileH = 16;

/// The depth noise model (KinectNoiseSettings, steps 1-6) for one packet of kPacket lanes:
/// t = hit distance (= true optical z: the direction has optical z = 1), (dx, dy, dz) the ray
/// direction, dn = normal . direction, g = N(0, 1) draw, hit / kept = 0 or 1. raw = output units.
/// SSE2 (x86-64 baseline, 4 lanes per instruction, no branches) with a scalar fallback of the
/// same formulas; the compiler cannot vectorise the scalar loop itself under the default
/// -ftrapping-math (its float selects do not if-convert).
template <bool kNoise, bool kQuantise, bool kAngular>
void depth_model_impl(const FrameParams& P, const float* t, const float* dx, const float* dy, const float* dz, const float* dn,
                      const float* g, const std::int32_t* hit, const std::int32_t* kept, std::int32_t* raw) {
  constexpr float kHalfPi = std::numbers::pi_v<float> / 2.0f;
#if defined(__SSE2__)
  static_assert(kPacket % 4 == 0);
  const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f), half = _mm_set1_ps(0.5f);
  const __m128i izero = _mm_setzero_si128();
  for (int k = 0; k < kPacket; k += 4) {
    __m128 z = _mm_load_ps(t + k);
    __m128i ok = _mm_and_si128(_mm_cmpgt_epi32(_mm_load_si128(reinterpret_cast<const __m128i*>(hit + k)), izero),
                               _mm_castps_si128(_mm_cmple_ps(z, _mm_set1_ps(P.depth_tfar))));
    if constexpr (kNoise) {
      const __m128 vx = _mm_load_ps(dx + k), vy = _mm_load_ps(dy + k), vz = _mm_load_ps(dz + k), vn = _mm_load_ps(dn + k);
      const __m128 d2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(vx, vx), _mm_mul_ps(vy, vy)), _mm_mul_ps(vz, vz));
      const __m128 cos2 = _mm_div_ps(_mm_mul_ps(vn, vn), d2);
      // 1. grazing incidence, 5. dropout
      ok = _mm_and_si128(ok, _mm_castps_si128(_mm_cmpge_ps(cos2, _mm_set1_ps(P.cos2_min))));
      ok = _mm_and_si128(ok, _mm_cmpgt_epi32(_mm_load_si128(reinterpret_cast<const __m128i*>(kept + k)), izero));
      // 2. axial noise (Nguyen et al. 2012)
      const __m128 zc = _mm_sub_ps(z, _mm_set1_ps(P.c));
      __m128 sigma = _mm_add_ps(_mm_set1_ps(P.a), _mm_mul_ps(_mm_set1_ps(P.b), _mm_mul_ps(zc, zc)));
      if constexpr (kAngular) {
        const __m128 c = _mm_min_ps(_mm_max_ps(_mm_sqrt_ps(cos2), zero), one);
        // acos (Abramowitz & Stegun 4.4.45)
        __m128 poly = _mm_add_ps(_mm_set1_ps(0.0742610f), _mm_mul_ps(c, _mm_set1_ps(-0.0187293f)));
        poly = _mm_add_ps(_mm_set1_ps(-0.2121144f), _mm_mul_ps(c, poly));
        poly = _mm_add_ps(_mm_set1_ps(1.5707288f), _mm_mul_ps(c, poly));
        const __m128 theta = _mm_mul_ps(_mm_sqrt_ps(_mm_sub_ps(one, c)), poly);
        const __m128 r = _mm_div_ps(theta, _mm_max_ps(_mm_set1_ps(1e-3f), _mm_sub_ps(_mm_set1_ps(kHalfPi), theta)));
        const __m128 sz = _mm_sqrt_ps(_mm_max_ps(z, _mm_set1_ps(1e-6f)));
        sigma = _mm_add_ps(sigma, _mm_div_ps(_mm_mul_ps(_mm_set1_ps(P.ang), _mm_mul_ps(r, r)), sz));
      }
      z = _mm_add_ps(z, _mm_mul_ps(sigma, _mm_load_ps(g + k)));
      // 3. disparity quantisation (Khoshelham & Elberink 2012): 1/z rounded to multiples of q
      if constexpr (kQuantise) {
        const __m128 q = _mm_set1_ps(P.q);
        __m128 inv = _mm_div_ps(one, _mm_mul_ps(_mm_max_ps(z, _mm_set1_ps(1e-6f)), q));
        inv = _mm_min_ps(_mm_max_ps(inv, zero), _mm_set1_ps(1e9f));
        const __m128 steps = _mm_cvtepi32_ps(_mm_cvttps_epi32(_mm_add_ps(inv, half)));
        const __m128 zq = _mm_div_ps(one, _mm_mul_ps(_mm_max_ps(steps, half), q));
        const __m128 pos = _mm_cmpgt_ps(steps, zero);
        z = _mm_or_ps(_mm_and_ps(pos, zq), _mm_andnot_ps(pos, _mm_set1_ps(1e30f)));
      }
    }
    // 4. range, 6. raw units (round half up)
    ok = _mm_and_si128(ok, _mm_castps_si128(_mm_and_ps(_mm_cmpge_ps(z, _mm_set1_ps(P.min_depth)), _mm_cmple_ps(z, _mm_set1_ps(P.max_depth)))));
    const __m128 scaled = _mm_min_ps(_mm_max_ps(_mm_mul_ps(z, _mm_set1_ps(P.units)), zero), _mm_set1_ps(1e9f));
    const __m128i r = _mm_cvttps_epi32(_mm_add_ps(scaled, half));
    ok = _mm_and_si128(ok, _mm_and_si128(_mm_cmpgt_epi32(r, izero), _mm_cmplt_epi32(r, _mm_set1_epi32(65536))));
    _mm_store_si128(reinterpret_cast<__m128i*>(raw + k), _mm_and_si128(ok, r));
  }
#else
  for (int k = 0; k < kPacket; ++k) {
    float z = t[k];
    bool ok = hit[k] != 0 && z <= P.depth_tfar;
    if constexpr (kNoise) {
      const float d2 = dx[k] * dx[k] + dy[k] * dy[k] + dz[k] * dz[k];
      const float cos2 = dn[k] * dn[k] / d2;
      ok = ok && cos2 >= P.cos2_min && kept[k] != 0;  // 1. grazing incidence, 5. dropout
      const float zc = z - P.c;
      float sigma = P.a + P.b * zc * zc;  // 2. axial noise (Nguyen et al. 2012)
      if constexpr (kAngular) {
        const float c = std::clamp(std::sqrt(cos2), 0.0f, 1.0f);
        const float theta = std::sqrt(1.0f - c) * (1.5707288f + c * (-0.2121144f + c * (0.0742610f - 0.0187293f * c)));
        const float r = theta / std::max(1e-3f, kHalfPi - theta);
        sigma += P.ang * r * r / std::sqrt(std::max(z, 1e-6f));
      }
      z += sigma * g[k];
      if constexpr (kQuantise) {  // 3. disparity quantisation (Khoshelham & Elberink 2012)
        const float inv = std::clamp(1.0f / (std::max(z, 1e-6f) * P.q), 0.0f, 1e9f);
        const float steps = static_cast<float>(static_cast<std::int32_t>(inv + 0.5f));
        z = steps > 0.0f ? 1.0f / (std::max(steps, 0.5f) * P.q) : 1e30f;
      }
    }
    ok = ok && z >= P.min_depth && z <= P.max_depth;  // 4. range
    const auto r = static_cast<std::int32_t>(std::clamp(z * P.units, 0.0f, 1e9f) + 0.5f);  // 6. raw units
    raw[k] = ok && r >= 1 && r <= 65535 ? r : 0;
  }
#endif
}

void depth_model(const FrameParams& P, const float* t, const float* dx, const float* dy, const float* dz, const float* dn,
                 const float* g, const std::int32_t* hit, const std::int32_t* kept, std::int32_t* raw) {
  if (!P.noise) return depth_model_impl<false, false, false>(P, t, dx, dy, dz, dn, g, hit, kept, raw);
  const bool q = P.q > 0.0f, a = P.ang > 0.0f;
  if (q && a) return depth_model_impl<true, true, true>(P, t, dx, dy, dz, dn, g, hit, kept, raw);
  if (q) return depth_model_impl<true, true, false>(P, t, dx, dy, dz, dn, g, hit, kept, raw);
  if (a) return depth_model_impl<true, false, true>(P, t, dx, dy, dz, dn, g, hit, kept, raw);
  return depth_model_impl<true, false, false>(P, t, dx, dy, dz, dn, g, hit, kept, raw);
}

/// Colour of one packet: texture at the hit point on the face's plane (texture.hpp, world
/// coordinates) times the Lambert + ambient shade of the side the ray sees, rounded to 8 bits;
/// black where nothing is hit. Lanes are evaluated face by face (a packet usually sees one or
/// two faces), four lanes (one packet row) per SSE2 call - bit-identical to the scalar
/// per-pixel evaluation of the fallback below.
/// Writes rgb_out[3 * (4 r + i) + {0, 1, 2}] for every lane (valid or not; the caller stores).
void shade_packet(const FrameParams& P, const Face* faces, const float* t, const float* dx, const float* dy, const float* dz,
                  const float* dn, const std::uint32_t* face_of_lane, std::uint32_t hit_bits, std::int32_t* rgb_out) {
#if defined(__SSE2__)
  alignas(16) float cr[kPacket] = {}, cg[kPacket] = {}, cb[kPacket] = {};
  const __m128 ox = _mm_set1_ps(P.origin.x()), oy = _mm_set1_ps(P.origin.y()), oz = _mm_set1_ps(P.origin.z());
  const __m128i lane_bit = _mm_setr_epi32(1, 2, 4, 8);
  std::uint32_t pending = hit_bits;
  while (pending != 0) {
    const std::uint32_t id = face_of_lane[std::countr_zero(pending)];
    std::uint32_t lanes = 0;
    for (int k = 0; k < kPacket; ++k) lanes |= (face_of_lane[k] == id ? 1u : 0u) << k;
    lanes &= pending;
    pending &= ~lanes;
    const Face& f = faces[id];
    const __m128 tu0 = _mm_set1_ps(f.tu[0]), tu1 = _mm_set1_ps(f.tu[1]), tu2 = _mm_set1_ps(f.tu[2]), tu3 = _mm_set1_ps(f.tu[3]);
    const __m128 tv0 = _mm_set1_ps(f.tv[0]), tv1 = _mm_set1_ps(f.tv[1]), tv2 = _mm_set1_ps(f.tv[2]), tv3 = _mm_set1_ps(f.tv[3]);
    const __m128 front = _mm_set1_ps(f.shade_front), back = _mm_set1_ps(f.shade_back), half = _mm_set1_ps(0.5f);
    for (int r = 0; r < kPacketH; ++r) {
      const std::uint32_t m = (lanes >> (kPacketW * r)) & 0xFu;
      if (m == 0) continue;
      const int o = kPacketW * r;
      const __m128 tt = _mm_load_ps(t + o);
      const __m128 px = _mm_add_ps(ox, _mm_mul_ps(tt, _mm_load_ps(dx + o)));
      const __m128 py = _mm_add_ps(oy, _mm_mul_ps(tt, _mm_load_ps(dy + o)));
      const __m128 pz = _mm_add_ps(oz, _mm_mul_ps(tt, _mm_load_ps(dz + o)));
      // u = tu . (p, 1), summed left to right as the scalar code does
      const __m128 u = _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(tu0, px), _mm_mul_ps(tu1, py)), _mm_mul_ps(tu2, pz)), tu3);
      const __m128 v = _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(tv0, px), _mm_mul_ps(tv1, py)), _mm_mul_ps(tv2, pz)), tv3);
      const detail::Rgb4 c = detail::evaluate_texture4(f.texture, f.base, u, v, f.seed);
      const __m128 shade = detail::select4(_mm_cmple_ps(_mm_load_ps(dn + o), _mm_setzero_ps()), front, back);
      const __m128 sel = _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_and_si128(_mm_set1_epi32(static_cast<int>(m)), lane_bit), lane_bit));
      _mm_store_ps(cr + o, detail::select4(sel, _mm_add_ps(_mm_mul_ps(c.r, shade), half), _mm_load_ps(cr + o)));
      _mm_store_ps(cg + o, detail::select4(sel, _mm_add_ps(_mm_mul_ps(c.g, shade), half), _mm_load_ps(cg + o)));
      _mm_store_ps(cb + o, detail::select4(sel, _mm_add_ps(_mm_mul_ps(c.b, shade), half), _mm_load_ps(cb + o)));
    }
  }
  // min(255, x) as std::min(255.0f, x) ((x < 255) ? x : 255, NaN -> 255), then truncation.
  const __m128 k255 = _mm_set1_ps(255.0f);
  for (int k = 0; k < kPacket; k += 4) {
    _mm_store_si128(reinterpret_cast<__m128i*>(rgb_out + k), _mm_cvttps_epi32(_mm_min_ps(_mm_load_ps(cr + k), k255)));
    _mm_store_si128(reinterpret_cast<__m128i*>(rgb_out + kPacket + k), _mm_cvttps_epi32(_mm_min_ps(_mm_load_ps(cg + k), k255)));
    _mm_store_si128(reinterpret_cast<__m128i*>(rgb_out + 2 * kPacket + k), _mm_cvttps_epi32(_mm_min_ps(_mm_load_ps(cb + k), k255)));
  }
#else
  for (int k = 0; k < kPacket; ++k) {
    if ((hit_bits >> k & 1u) == 0) {
      rgb_out[k] = rgb_out[kPacket + k] = rgb_out[2 * kPacket + k] = 0;
      continue;
    }
    const Face& f = faces[face_of_lane[k]];
    const float px = P.origin.x() + t[k] * dx[k], py = P.origin.y() + t[k] * dy[k], pz = P.origin.z() + t[k] * dz[k];
    const float u = f.tu[0] * px + f.tu[1] * py + f.tu[2] * pz + f.tu[3];
    const float v = f.tv[0] * px + f.tv[1] * py + f.tv[2] * pz + f.tv[3];
    const detail::Rgbf c = detail::evaluate_texture(f.texture, f.base, u, v, f.seed);
    const float shade = dn[k] <= 0.0f ? f.shade_front : f.shade_back;
    rgb_out[k] = static_cast<std::int32_t>(std::min(255.0f, c.r * shade + 0.5f));
    rgb_out[kPacket + k] = static_cast<std::int32_t>(std::min(255.0f, c.g * shade + 0.5f));
    rgb_out[2 * kPacket + k] = static_cast<std::int32_t>(std::min(255.0f, c.b * shade + 0.5f));
  }
#endif
}

}  // namespace

namespace render_detail {

/// Frame constants from one job; validates the sensor and the pose (does not touch the output).
FrameParams make_params(const RenderSettings& settings, const SensorProfile& sensor, const Eigen::Isometry3f& T_world_optical,
                        std::uint64_t frame_seed, bool colour) {
  validate_sensor(sensor);
  if (!T_world_optical.matrix().allFinite())
    fail(ErrorCode::kInvalidArgument, "RgbdRenderer: sensor '" + sensor.name + "': T_world_optical is not finite");
  const PinholeIntrinsics& in = sensor.intrinsics;
  const KinectNoiseSettings& ns = settings.noise;
  FrameParams P;
  P.w = in.width;
  P.h = in.height;
  const Eigen::Matrix3f R = T_world_optical.linear();
  P.origin = T_world_optical.translation();
  P.du = R.col(0) / in.fx;
  P.dv = R.col(1) / in.fy;
  P.base_dir = R.col(2) - in.cx * P.du - in.cy * P.dv;
  P.min_depth = sensor.min_depth_m;
  P.max_depth = sensor.max_depth_m;
  P.units = sensor.depth_units_per_m;
  P.noise = ns.enabled;
  // With noise a true depth somewhat beyond max_depth may still be measured inside the range;
  // beyond 1.5 max + 1 m it cannot (sigma there is a few cm). Both render paths use this bound,
  // so their depth images are identical.
  P.depth_tfar = ns.enabled ? 1.5f * P.max_depth + 1.0f : P.max_depth;
  P.ray_tfar = colour ? std::numeric_limits<float>::infinity() : P.depth_tfar;
  P.a = ns.axial_a_m;
  P.b = ns.axial_b_per_m;
  P.c = ns.axial_c_m;
  P.ang = ns.axial_angular_m;
  P.q = ns.quantisation_per_m;
  const float cmin = std::cos(ns.max_incidence_deg * std::numbers::pi_v<float> / 180.0f);
  P.cos2_min = ns.max_incidence_deg >= 90.0f ? 0.0f : cmin * cmin;
  P.dropout_threshold = static_cast<std::uint64_t>(static_cast<double>(ns.dropout_rate) * 4294967296.0);
  P.seed_key = splitmix64(frame_seed ^ 0x6A09E667F3BCC909ull);
  P.colour = colour;
  P.tiles_x = (P.w + kTileW - 1) / kTileW;
  P.tiles = P.tiles_x * ((P.h + kTileH - 1) / kTileH);
  return P;
}

/// Renders tile `tile` (row-major over the frame's kTileW x kTileH tiles) of one frame.
void render_tile(const FrameParams& P, const Face* faces, const std::uint32_t* tri_face, RTCScene scene, int tile) {
  using Traits = PacketTraits<kPacket>;
  static_assert(kPacketW == 4, "the SSE2 paths handle one packet row of 4 lanes per vector");
  const GaussTable& gauss = gauss_table();
  alignas(64) typename Traits::RayHit rh;
  alignas(64) int valid[kPacket];
  alignas(64) float dxs[kPacket], dys[kPacket], dzs[kPacket];
  alignas(64) float dn[kPacket], gauss_sample[kPacket];
  alignas(64) std::int32_t hit[kPacket], kept[kPacket], raw[kPacket], rgb_lane[3 * kPacket];
  alignas(64) std::uint32_t face_of_lane[kPacket];
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  const int tx = tile % P.tiles_x, ty = tile / P.tiles_x;
  const int x_begin = tx * kTileW, y_begin = ty * kTileH;
  const int x_end = std::min(P.w, x_begin + kTileW), y_end = std::min(P.h, y_begin + kTileH);
  // Ray fields Embree only reads: set once per tile.
  for (int k = 0; k < kPacket; ++k) {
    rh.ray.org_x[k] = P.origin.x();
    rh.ray.org_y[k] = P.origin.y();
    rh.ray.org_z[k] = P.origin.z();
    rh.ray.tnear[k] = 0.0f;
    rh.ray.time[k] = 0.0f;
    rh.ray.mask[k] = 0xFFFFFFFFu;
    rh.ray.id[k] = static_cast<unsigned>(k);
    rh.ray.flags[k] = 0;
  }
  std::uint16_t* const depth = P.depth;
  std::uint8_t* const rgb = P.rgb;
  const std::size_t w = static_cast<std::size_t>(P.w);
  for (int y0 = y_begin; y0 < y_end; y0 += kPacketH) {
    for (int x0 = x_begin; x0 < x_end; x0 += kPacketW) {
      // Rays: d = base_dir + x du + y dv (the same sums, in the same order, for every path).
      for (int k = 0; k < kPacket; ++k) {
        const int x = x0 + k % kPacketW, y = y0 + k / kPacketW;
        const float fx = static_cast<float>(x), fy = static_cast<float>(y);
        valid[k] = (x < x_end && y < y_end) ? -1 : 0;
        dxs[k] = P.base_dir.x() + fx * P.du.x() + fy * P.dv.x();
        dys[k] = P.base_dir.y() + fx * P.du.y() + fy * P.dv.y();
        dzs[k] = P.base_dir.z() + fx * P.du.z() + fy * P.dv.z();
      }
      std::memcpy(rh.ray.dir_x, dxs, sizeof(dxs));
      std::memcpy(rh.ray.dir_y, dys, sizeof(dys));
      std::memcpy(rh.ray.dir_z, dzs, sizeof(dzs));
      for (int k = 0; k < kPacket; ++k) {
        rh.ray.tfar[k] = P.ray_tfar;
        rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
      }
      Traits::intersect(valid, scene, &ctx, &rh);
      // Stage 1 (scalar gathers): the face, normal . direction, the pixel's random draws.
      std::uint32_t hit_bits = 0;
      for (int k = 0; k < kPacket; ++k) {
        const bool h = valid[k] != 0 && rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
        hit[k] = h ? 1 : 0;
        hit_bits |= (h ? 1u : 0u) << k;
        const std::uint32_t id = h ? tri_face[rh.hit.primID[k]] : 0u;
        face_of_lane[k] = id;
        const Face& f = faces[id];
        dn[k] = f.n[0] * dxs[k] + f.n[1] * dys[k] + f.n[2] * dzs[k];
      }
      if (P.noise) {
        for (int k = 0; k < kPacket; ++k) {
          const int x = x0 + k % kPacketW, y = y0 + k / kPacketW;
          const std::uint64_t pix = static_cast<std::uint64_t>(y) * static_cast<std::uint64_t>(P.w) + static_cast<std::uint64_t>(x);
          const std::uint64_t hsh = splitmix64(P.seed_key + pix * kGolden);
          kept[k] = (hsh >> 32) >= P.dropout_threshold ? 1 : 0;  // 5. random dropout
          gauss_sample[k] = gauss.sample(static_cast<std::uint32_t>(hsh));
        }
      }
      // Stage 2 (branch-free, vectorised): the depth noise model.
      depth_model(P, rh.ray.tfar, dxs, dys, dzs, dn, gauss_sample, hit, kept, raw);
      // Stage 3: colour.
      if (rgb) shade_packet(P, faces, rh.ray.tfar, dxs, dys, dzs, dn, face_of_lane, hit_bits, rgb_lane);
      // Stage 4: store the valid lanes, one packet row at a time.
      const int cols = std::min(kPacketW, x_end - x0);
      for (int r = 0; r < kPacketH && y0 + r < y_end; ++r) {
        const std::size_t row = static_cast<std::size_t>(y0 + r) * w + static_cast<std::size_t>(x0);
        const int o = kPacketW * r;
        for (int i = 0; i < cols; ++i) depth[row + static_cast<std::size_t>(i)] = static_cast<std::uint16_t>(raw[o + i]);
        if (!rgb) continue;
        std::uint8_t* p = rgb + 3 * row;
        for (int i = 0; i < cols; ++i) {
          p[3 * i] = static_cast<std::uint8_t>(rgb_lane[o + i]);
          p[3 * i + 1] = static_cast<std::uint8_t>(rgb_lane[kPacket + o + i]);
          p[3 * i + 2] = static_cast<std::uint8_t>(rgb_lane[2 * kPacket + o + i]);
        }
      }
    }
  }
}

}  // namespace render_detail
}  // namespace duet::sim
