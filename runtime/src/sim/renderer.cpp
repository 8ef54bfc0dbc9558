// Simulated RGB-D sensors: world mesh, Embree scene, packet ray tracing over pixel tiles,
// Kinect-like depth noise and procedural colour (issue 4, part 2). See renderer.hpp.
#include <duet/runtime/sim/renderer.hpp>

#include <duet/kernels/error.hpp>

#include "sim/texture.hpp"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <utility>

namespace duet::sim {
namespace {

std::string num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

void check_range(const char* owner, const char* field, float v, float lo, float hi, bool lo_open, bool hi_open) {
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

// ---- mesh ---------------------------------------------------------------------------------------

float cross2(const Eigen::Vector2f& a, const Eigen::Vector2f& b, const Eigen::Vector2f& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

/// Ear clipping of a simple counter-clockwise polygon; triangles are CCW (indices into poly).
std::vector<std::array<std::uint32_t, 3>> ear_clip(const std::vector<Eigen::Vector2f>& poly, const std::string& name) {
  std::vector<std::array<std::uint32_t, 3>> tris;
  std::vector<std::uint32_t> idx(poly.size());
  for (std::size_t i = 0; i < poly.size(); ++i) idx[i] = static_cast<std::uint32_t>(i);
  std::size_t guard = 0;
  std::size_t i = 0;
  while (idx.size() > 3) {
    const std::size_t n = idx.size();
    const std::uint32_t ia = idx[(i + n - 1) % n], ib = idx[i % n], ic = idx[(i + 1) % n];
    const Eigen::Vector2f &a = poly[ia], &b = poly[ib], &c = poly[ic];
    const float area = cross2(a, b, c);
    bool ear = false;
    if (area == 0.0f) {
      // Collinear (or repeated) vertex: drop it without a triangle.
      idx.erase(idx.begin() + static_cast<std::ptrdiff_t>(i % n));
      guard = 0;
      continue;
    }
    if (area > 0.0f) {
      ear = true;
      for (const std::uint32_t j : idx) {
        if (j == ia || j == ib || j == ic) continue;
        const Eigen::Vector2f& p = poly[j];
        if (p == a || p == b || p == c) continue;
        if (cross2(a, b, p) >= 0.0f && cross2(b, c, p) >= 0.0f && cross2(c, a, p) >= 0.0f) {
          ear = false;
          break;
        }
      }
    }
    if (ear) {
      tris.push_back({ia, ib, ic});
      idx.erase(idx.begin() + static_cast<std::ptrdiff_t>(i % n));
      guard = 0;
      if (i >= idx.size()) i = 0;
      continue;
    }
    i = (i + 1) % n;
    if (++guard > n)
      fail(ErrorCode::kInvalidArgument, "render mesh: solid '" + name +
                                            "': its polygon cannot be triangulated (not simple or not counter-clockwise; "
                                            "call sim::validate(world) first)");
  }
  if (idx.size() == 3 && cross2(poly[idx[0]], poly[idx[1]], poly[idx[2]]) != 0.0f) tris.push_back({idx[0], idx[1], idx[2]});
  return tris;
}

// ---- per-triangle shading data --------------------------------------------------------------------

/// Everything the shader needs about one triangle (flat: one plane, one surface).
struct Face {
  float n[3];            ///< unit normal (outward)
  float tu[4], tv[4];    ///< texture coordinates [cells]: u = tu . (x, y, z, 1)
  float shade_front;     ///< Lambert + ambient, seen from the normal's side
  float shade_back;      ///< seen from behind
  detail::Rgbf base;     ///< surface colour 0..255
  std::uint32_t seed;    ///< texture seed of the surface
  Texture texture;
};

std::uint32_t surface_seed(std::size_t surface_index) {
  return static_cast<std::uint32_t>(splitmix64(0xD0E7u + surface_index) >> 32);
}

std::vector<Face> make_faces(const WorldMesh& mesh, const RenderSettings& s) {
  const Eigen::Vector3f l = s.light_direction.normalized();
  std::vector<Face> faces(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const Eigen::Vector3f &a = mesh.vertices[tri[0]], &b = mesh.vertices[tri[1]], &c = mesh.vertices[tri[2]];
    Eigen::Vector3f n = (b - a).cross(c - a);
    n = n.norm() > 0.0f ? Eigen::Vector3f(n.normalized()) : Eigen::Vector3f::UnitZ();
    const std::uint32_t si = mesh.triangle_surface[t];
    const Surface& surf = mesh.surfaces[si];
    const float inv_scale = 1.0f / surf.texture_scale_m;
    Face& f = faces[t];
    f.n[0] = n.x();
    f.n[1] = n.y();
    f.n[2] = n.z();
    // Texture plane: horizontal faces use (x, y); vertical ones (horizontal tangent, z), the
    // tangent perpendicular to the normal - world coordinates, so views agree.
    Eigen::Vector3f eu, ev;
    if (std::abs(n.z()) > 0.5f) {
      eu = Eigen::Vector3f::UnitX();
      ev = Eigen::Vector3f::UnitY();
    } else {
      eu = Eigen::Vector3f(-n.y(), n.x(), 0.0f).normalized();
      ev = Eigen::Vector3f::UnitZ();
    }
    for (int k = 0; k < 3; ++k) {
      f.tu[k] = eu[k] * inv_scale;
      f.tv[k] = ev[k] * inv_scale;
    }
    f.tu[3] = 0.0f;
    f.tv[3] = 0.0f;
    f.shade_front = s.ambient + (1.0f - s.ambient) * std::max(0.0f, n.dot(l));
    f.shade_back = s.ambient + (1.0f - s.ambient) * std::max(0.0f, -n.dot(l));
    f.base = {static_cast<float>(surf.colour.r), static_cast<float>(surf.colour.g), static_cast<float>(surf.colour.b)};
    f.seed = surface_seed(si);
    f.texture = surf.texture;
  }
  return faces;
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

}  // namespace

// ---- public: settings -------------------------------------------------------------------------

void validate(const KinectNoiseSettings& s) {
  const char* o = "KinectNoiseSettings";
  check_range(o, "axial_a_m", s.axial_a_m, 0.0f, 1.0f, false, false);
  check_range(o, "axial_b_per_m", s.axial_b_per_m, 0.0f, 1.0f, false, false);
  check_range(o, "axial_c_m", s.axial_c_m, 0.0f, 10.0f, false, false);
  check_range(o, "axial_angular_m", s.axial_angular_m, 0.0f, 1.0f, false, false);
  check_range(o, "quantisation_per_m", s.quantisation_per_m, 0.0f, 1.0f, false, false);
  check_range(o, "max_incidence_deg", s.max_incidence_deg, 0.0f, 90.0f, true, false);
  check_range(o, "dropout_rate", s.dropout_rate, 0.0f, 1.0f, false, false);
}

void validate(const RenderSettings& s) {
  validate(s.noise);
  const Eigen::Vector3f& l = s.light_direction;
  if (!l.allFinite() || !(l.norm() > 1e-6f))
    fail(ErrorCode::kInvalidArgument, "RenderSettings.light_direction = (" + num(l.x()) + ", " + num(l.y()) + ", " +
                                          num(l.z()) + "): expected a finite non-zero vector");
  check_range("RenderSettings", "ambient", s.ambient, 0.0f, 1.0f, false, false);
}

// ---- public: mesh -------------------------------------------------------------------------------

WorldMesh build_world_mesh(const World& world) {
  const Region& fl = world.floor;
  if (!fl.min.allFinite() || !fl.max.allFinite() || !(fl.max.x() > fl.min.x()) || !(fl.max.y() > fl.min.y()))
    fail(ErrorCode::kInvalidArgument, "render mesh: world '" + world.name + "': the floor rectangle is empty or not finite");
  if (!std::isfinite(world.ceiling_height_m) || world.ceiling_height_m < 0.0f)
    fail(ErrorCode::kInvalidArgument, "render mesh: world '" + world.name + "': ceiling_height_m = " +
                                          num(world.ceiling_height_m) + ": expected 0 (none) or a positive height");
  WorldMesh m;
  m.surfaces.reserve(world.solids.size() + 2);
  m.surfaces.push_back(world.floor_surface);
  m.surfaces.push_back(world.ceiling_surface);
  auto add_vertex = [&](float x, float y, float z) {
    m.vertices.emplace_back(x, y, z);
    return static_cast<std::uint32_t>(m.vertices.size() - 1);
  };
  auto add_tri = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t surface) {
    m.triangles.push_back({a, b, c});
    m.triangle_surface.push_back(surface);
  };
  // Floor (normal +z) and ceiling (normal -z).
  {
    const std::uint32_t a = add_vertex(fl.min.x(), fl.min.y(), 0.0f), b = add_vertex(fl.max.x(), fl.min.y(), 0.0f);
    const std::uint32_t c = add_vertex(fl.max.x(), fl.max.y(), 0.0f), d = add_vertex(fl.min.x(), fl.max.y(), 0.0f);
    add_tri(a, b, c, 0);
    add_tri(a, c, d, 0);
  }
  if (world.ceiling_height_m > 0.0f) {
    const float h = world.ceiling_height_m;
    const std::uint32_t a = add_vertex(fl.min.x(), fl.min.y(), h), b = add_vertex(fl.max.x(), fl.min.y(), h);
    const std::uint32_t c = add_vertex(fl.max.x(), fl.max.y(), h), d = add_vertex(fl.min.x(), fl.max.y(), h);
    add_tri(a, c, b, 1);
    add_tri(a, d, c, 1);
  }
  for (std::size_t s = 0; s < world.solids.size(); ++s) {
    const Solid& solid = world.solids[s];
    const auto surface = static_cast<std::uint32_t>(s + 2);
    const std::size_t n = solid.polygon.size();
    bool finite = std::isfinite(solid.z_min_m) && std::isfinite(solid.z_max_m);
    for (const auto& p : solid.polygon) finite = finite && p.allFinite();
    if (n < 3 || !finite || !(solid.z_max_m > solid.z_min_m))
      fail(ErrorCode::kInvalidArgument, "render mesh: solid '" + solid.name +
                                            "': expected >= 3 finite vertices and z_max_m > z_min_m (call sim::validate(world))");
    if (!(solid.surface.texture_scale_m > 0.0f) || !std::isfinite(solid.surface.texture_scale_m))
      fail(ErrorCode::kInvalidArgument, "render mesh: solid '" + solid.name + "': texture_scale_m must be > 0");
    m.surfaces.push_back(solid.surface);
    const auto base = static_cast<std::uint32_t>(m.vertices.size());
    for (const auto& p : solid.polygon) add_vertex(p.x(), p.y(), solid.z_min_m);
    for (const auto& p : solid.polygon) add_vertex(p.x(), p.y(), solid.z_max_m);
    // Sides: edge a -> b of a CCW polygon has the outward normal (dy, -dx).
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t j = (i + 1) % n;
      if (solid.polygon[i] == solid.polygon[j]) continue;
      const auto a0 = static_cast<std::uint32_t>(base + i), b0 = static_cast<std::uint32_t>(base + j);
      const auto a1 = static_cast<std::uint32_t>(base + n + i), b1 = static_cast<std::uint32_t>(base + n + j);
      add_tri(a0, b0, b1, surface);
      add_tri(a0, b1, a1, surface);
    }
    const auto caps = ear_clip(solid.polygon, solid.name);
    for (const auto& t : caps) add_tri(static_cast<std::uint32_t>(base + n + t[0]), static_cast<std::uint32_t>(base + n + t[1]),
                                       static_cast<std::uint32_t>(base + n + t[2]), surface);
    if (solid.z_min_m > 0.0f)
      for (const auto& t : caps) add_tri(static_cast<std::uint32_t>(base + t[0]), static_cast<std::uint32_t>(base + t[2]),
                                         static_cast<std::uint32_t>(base + t[1]), surface);
  }
  for (const Surface& s : m.surfaces)
    if (!(s.texture_scale_m > 0.0f) || !std::isfinite(s.texture_scale_m))
      fail(ErrorCode::kInvalidArgument, "render mesh: world '" + world.name + "': a texture_scale_m must be > 0");
  return m;
}

// ---- the renderer -------------------------------------------------------------------------------

struct RgbdRenderer::Impl {
  RenderSettings settings;
  WorldMesh mesh;
  std::vector<Face> faces;
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;

  Impl() = default;
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }

  void check(const char* what) const {
    const RTCError e = rtcGetDeviceError(device);
    if (e != RTC_ERROR_NONE)
      fail(ErrorCode::kInternal, std::string("RgbdRenderer: ") + what + " failed (Embree error " + std::to_string(static_cast<int>(e)) + ")");
  }

  void build() {
    device = rtcNewDevice(nullptr);
    if (!device)
      fail(ErrorCode::kInternal, "RgbdRenderer: rtcNewDevice failed (Embree error " +
                                     std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) + ")");
    scene = rtcNewScene(device);
    check("rtcNewScene");
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    check("rtcNewGeometry");
    rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_HIGH);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                          mesh.vertices.size()));
    auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                                               mesh.triangles.size()));
    if (!v || !idx) {
      rtcReleaseGeometry(g);
      check("rtcSetNewGeometryBuffer");
      fail(ErrorCode::kInternal, "RgbdRenderer: rtcSetNewGeometryBuffer returned null");
    }
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
      for (int k = 0; k < 3; ++k) v[3 * i + static_cast<std::size_t>(k)] = mesh.vertices[i][k];
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
      for (int k = 0; k < 3; ++k) idx[3 * i + static_cast<std::size_t>(k)] = mesh.triangles[i][static_cast<std::size_t>(k)];
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(scene, g, 0);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene);
    check("rtcCommitScene");
  }

  void render(const SensorProfile& sensor, const Eigen::Isometry3f& T_world_optical, std::uint64_t frame_seed, RgbdImage& out,
              bool colour) const;
};

namespace {

/// Per-frame constants of render().
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
};

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

}  // namespace

void RgbdRenderer::Impl::render(const SensorProfile& sensor, const Eigen::Isometry3f& T_world_optical, std::uint64_t frame_seed,
                                RgbdImage& out, bool colour) const {
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

  const std::size_t pixels = static_cast<std::size_t>(P.w) * static_cast<std::size_t>(P.h);
  out.width = P.w;
  out.height = P.h;
  out.depth.resize(pixels);
  if (colour)
    out.rgb.resize(3 * pixels);
  else
    out.rgb.clear();

  const GaussTable& gauss = gauss_table();
  const Face* faces_ptr = faces.data();
  std::uint16_t* depth = out.depth.data();
  std::uint8_t* rgb = colour ? out.rgb.data() : nullptr;
  const RTCScene sc = scene;
  const int tiles_x = (P.w + kTileW - 1) / kTileW, tiles_y = (P.h + kTileH - 1) / kTileH;

  auto render_tile = [&](int tx, int ty) {
    using Traits = PacketTraits<kPacket>;
    alignas(64) typename Traits::RayHit rh;
    alignas(64) int valid[kPacket];
    alignas(64) float dxs[kPacket], dys[kPacket], dzs[kPacket];
    alignas(64) float dn[kPacket], gauss_sample[kPacket];
    alignas(64) std::int32_t hit[kPacket], kept[kPacket], raw[kPacket];
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    const int x_end = std::min(P.w, (tx + 1) * kTileW), y_end = std::min(P.h, (ty + 1) * kTileH);
    for (int y0 = ty * kTileH; y0 < y_end; y0 += kPacketH) {
      for (int x0 = tx * kTileW; x0 < x_end; x0 += kPacketW) {
        for (int k = 0; k < kPacket; ++k) {
          const int x = x0 + k % kPacketW, y = y0 + k / kPacketW;
          const float fx = static_cast<float>(x), fy = static_cast<float>(y);
          valid[k] = (x < x_end && y < y_end) ? -1 : 0;
          dxs[k] = P.base_dir.x() + fx * P.du.x() + fy * P.dv.x();
          dys[k] = P.base_dir.y() + fx * P.du.y() + fy * P.dv.y();
          dzs[k] = P.base_dir.z() + fx * P.du.z() + fy * P.dv.z();
          rh.ray.org_x[k] = P.origin.x();
          rh.ray.org_y[k] = P.origin.y();
          rh.ray.org_z[k] = P.origin.z();
          rh.ray.dir_x[k] = dxs[k];
          rh.ray.dir_y[k] = dys[k];
          rh.ray.dir_z[k] = dzs[k];
          rh.ray.tnear[k] = 0.0f;
          rh.ray.tfar[k] = P.ray_tfar;
          rh.ray.time[k] = 0.0f;
          rh.ray.mask[k] = 0xFFFFFFFFu;
          rh.ray.id[k] = static_cast<unsigned>(k);
          rh.ray.flags[k] = 0;
          rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
          rh.hit.primID[k] = 0;
          rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
        }
        Traits::intersect(valid, sc, &ctx, &rh);
        // Stage 1 (scalar gathers): face normal . direction, the pixel's random draws.
        for (int k = 0; k < kPacket; ++k) {
          const bool h = valid[k] != 0 && rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
          hit[k] = h ? 1 : 0;
          const Face& f = faces_ptr[h ? rh.hit.primID[k] : 0u];
          dn[k] = f.n[0] * dxs[k] + f.n[1] * dys[k] + f.n[2] * dzs[k];
          if (P.noise) {
            const int x = x0 + k % kPacketW, y = y0 + k / kPacketW;
            const std::uint64_t pix = static_cast<std::uint64_t>(y) * static_cast<std::uint64_t>(P.w) + static_cast<std::uint64_t>(x);
            const std::uint64_t hsh = splitmix64(P.seed_key + pix * kGolden);
            kept[k] = (hsh >> 32) >= P.dropout_threshold ? 1 : 0;  // 5. random dropout
            gauss_sample[k] = gauss.sample(static_cast<std::uint32_t>(hsh));
          }
        }
        // Stage 2 (branch-free, vectorisable): the depth noise model.
        depth_model(P, rh.ray.tfar, dxs, dys, dzs, dn, gauss_sample, hit, kept, raw);
        // Stage 3: store; colour.
        for (int k = 0; k < kPacket; ++k) {
          if (!valid[k]) continue;
          const int x = x0 + k % kPacketW, y = y0 + k / kPacketW;
          const std::size_t pix = static_cast<std::size_t>(y) * static_cast<std::size_t>(P.w) + static_cast<std::size_t>(x);
          depth[pix] = static_cast<std::uint16_t>(raw[k]);
          if (!rgb) continue;
          if (!hit[k]) {
            rgb[3 * pix] = rgb[3 * pix + 1] = rgb[3 * pix + 2] = 0;
            continue;
          }
          // Colour: texture at the hit point on the surface's plane, Lambert + ambient.
          const Face& f = faces_ptr[rh.hit.primID[k]];
          const float t = rh.ray.tfar[k];
          const float px = P.origin.x() + t * dxs[k], py = P.origin.y() + t * dys[k], pz = P.origin.z() + t * dzs[k];
          const float u = f.tu[0] * px + f.tu[1] * py + f.tu[2] * pz + f.tu[3];
          const float v = f.tv[0] * px + f.tv[1] * py + f.tv[2] * pz + f.tv[3];
          const detail::Rgbf c = detail::evaluate_texture(f.texture, f.base, u, v, f.seed);
          const float shade = dn[k] <= 0.0f ? f.shade_front : f.shade_back;
          rgb[3 * pix] = static_cast<std::uint8_t>(std::min(255.0f, c.r * shade + 0.5f));
          rgb[3 * pix + 1] = static_cast<std::uint8_t>(std::min(255.0f, c.g * shade + 0.5f));
          rgb[3 * pix + 2] = static_cast<std::uint8_t>(std::min(255.0f, c.b * shade + 0.5f));
        }
      }
    }
  };

  tbb::parallel_for(tbb::blocked_range<int>(0, tiles_x * tiles_y), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i != r.end(); ++i) render_tile(i % tiles_x, i / tiles_x);
  });
}

RgbdRenderer::RgbdRenderer(const World& world, const RenderSettings& settings) : impl_(std::make_unique<Impl>()) {
  validate(settings);
  impl_->settings = settings;
  impl_->mesh = build_world_mesh(world);
  impl_->faces = make_faces(impl_->mesh, settings);
  impl_->build();
}

RgbdRenderer::~RgbdRenderer() = default;
RgbdRenderer::RgbdRenderer(RgbdRenderer&&) noexcept = default;
RgbdRenderer& RgbdRenderer::operator=(RgbdRenderer&&) noexcept = default;

void RgbdRenderer::render(const SensorProfile& sensor, const Eigen::Isometry3f& T_world_optical, std::uint64_t frame_seed,
                          RgbdImage& out) const {
  impl_->render(sensor, T_world_optical, frame_seed, out, true);
}

void RgbdRenderer::render_depth_only(const SensorProfile& sensor, const Eigen::Isometry3f& T_world_optical,
                                     std::uint64_t frame_seed, RgbdImage& out) const {
  impl_->render(sensor, T_world_optical, frame_seed, out, false);
}

const RenderSettings& RgbdRenderer::settings() const noexcept { return impl_->settings; }
const WorldMesh& RgbdRenderer::mesh() const noexcept { return impl_->mesh; }

}  // namespace duet::sim
