/// @file renderer.cpp
/// Simulated RGB-D sensors (issue 4, part 2; see renderer.hpp): world mesh, Embree scene and the public
/// RgbdRenderer. The per-tile ray tracing, depth noise and colour are in renderer_tiles.cpp.
#include <duet/sim/renderer.hpp>

#include <duet/kernels/embree_device.hpp>
#include <duet/kernels/error.hpp>

#include "renderer_detail.hpp"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <utility>

namespace duet::sim {
namespace {

using render_detail::check_range;
using render_detail::Face;
using render_detail::FrameParams;
using render_detail::make_params;
using render_detail::num;
using render_detail::render_tile;
using render_detail::splitmix64;

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

// ---- per-face shading data ------------------------------------------------------------------------

std::uint32_t surface_seed(std::size_t surface_index) {
  return static_cast<std::uint32_t>(splitmix64(0xD0E7u + surface_index) >> 32);
}

Face make_face(const WorldMesh& mesh, std::size_t t, const Eigen::Vector3f& l, const RenderSettings& s) {
  const auto& tri = mesh.triangles[t];
  const Eigen::Vector3f &a = mesh.vertices[tri[0]], &b = mesh.vertices[tri[1]], &c = mesh.vertices[tri[2]];
  Eigen::Vector3f n = (b - a).cross(c - a);
  n = n.norm() > 0.0f ? Eigen::Vector3f(n.normalized()) : Eigen::Vector3f::UnitZ();
  const std::uint32_t si = mesh.triangle_surface[t];
  const Surface& surf = mesh.surfaces[si];
  const float inv_scale = 1.0f / surf.texture_scale_m;
  Face f{};
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
  return f;
}

/// The faces of a mesh, deduplicated (bitwise-equal shading data = one Face), and per triangle
/// the index of its face.
void make_faces(const WorldMesh& mesh, const RenderSettings& s, std::vector<Face>& faces, std::vector<std::uint32_t>& tri_face) {
  const Eigen::Vector3f l = s.light_direction.normalized();
  using Key = std::array<std::uint32_t, 18>;
  std::map<Key, std::uint32_t> index;
  faces.clear();
  tri_face.resize(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Face f = make_face(mesh, t, l, s);
    Key key{};
    const float fl[16] = {f.n[0], f.n[1], f.n[2], f.tu[0], f.tu[1], f.tu[2], f.tu[3], f.tv[0],
                          f.tv[1], f.tv[2], f.tv[3], f.shade_front, f.shade_back, f.base.r, f.base.g, f.base.b};
    std::memcpy(key.data(), fl, sizeof(fl));
    key[16] = f.seed;
    key[17] = static_cast<std::uint32_t>(f.texture);
    const auto [it, inserted] = index.try_emplace(key, static_cast<std::uint32_t>(faces.size()));
    if (inserted) faces.push_back(f);
    tri_face[t] = it->second;
  }
  if (faces.empty()) faces.push_back(Face{});  // never read: keeps faces.data() valid
}

/// The growth margin of grown_triangles() [m]: 0.02 mm plus 5e-7 of the largest coordinate
/// (several float ulps there), 0.026 mm in the 11 m lab, 0.05 mm in the 61 m
/// Willow Garage map - far below a pixel's footprint (1.6 mm at 1 m) and the depth unit (1 mm).
double grow_margin_m(const WorldMesh& mesh) {
  double extent = 0.0;
  for (const Eigen::Vector3f& v : mesh.vertices) extent = std::max(extent, static_cast<double>(v.cwiseAbs().maxCoeff()));
  return 2e-5 + 5e-7 * extent;
}

/// Embree's vertices for the fast mode (RenderSettings::robust_intersection = false): every
/// triangle on its own, grown in its plane by `margin` [m] (each edge moved outward by margin,
/// the vertices to the new edges' intersections; the move is capped at 16 x margin at
/// needle-sharp corners, where the grown triangle still contains the original). Neighbouring
/// triangles then overlap by a few hundredths of a millimetre, so Embree's fast (non-robust)
/// intersection does not let rays slip through the crack of a shared edge - the artefact its
/// robust mode avoids at about 1.6x the traversal cost (measured on the Willow Garage map:
/// 319 pixels in 600 frames hit something > 1 cm behind the true surface without the growth;
/// with a 0.02 mm growth 1 pixel differed from the robust mode on the same grown triangles).
/// Degenerate triangles are left as they are. Returns 9 floats per triangle.
std::vector<float> grown_triangles(const WorldMesh& mesh, double margin) {
  std::vector<float> out(9 * mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    Eigen::Vector3d v[3];
    for (std::size_t k = 0; k < 3; ++k) v[k] = mesh.vertices[mesh.triangles[t][k]].cast<double>();
    const Eigen::Vector3d nn = (v[1] - v[0]).cross(v[2] - v[0]);
    Eigen::Vector3d w[3] = {v[0], v[1], v[2]};
    if (nn.norm() > 1e-12 && margin > 0.0) {
      const Eigen::Vector3d n = nn.normalized();
      Eigen::Vector3d m[3];  // outward in-plane normal of edge k -> k+1 (CCW about n)
      for (std::size_t k = 0; k < 3; ++k) m[k] = (v[(k + 1) % 3] - v[k]).cross(n).normalized();
      for (std::size_t k = 0; k < 3; ++k) {
        const Eigen::Vector3d& a = m[(k + 2) % 3];  // edge into vertex k
        const Eigen::Vector3d& b = m[k];            // edge out of vertex k
        Eigen::Vector3d d = margin * (a + b) / std::max(1e-6, 1.0 + a.dot(b));
        if (d.norm() > 16.0 * margin) d *= 16.0 * margin / d.norm();
        w[k] = v[k] + d;
      }
    }
    for (std::size_t k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) out[9 * t + 3 * k + static_cast<std::size_t>(c)] = static_cast<float>(w[k][c]);
  }
  return out;
}

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
  std::vector<Face> faces;               // deduplicated shading data
  std::vector<std::uint32_t> tri_face;   // per triangle (Embree primID): index into faces
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
    device = new_embree_device("RgbdRenderer");
    scene = rtcNewScene(device);
    check("rtcNewScene");
    // Robust mode: no cracks at shared edges, about 1.6x the ray cost; otherwise the fast mode
    // on triangles grown by a fraction of a millimetre (grown_triangles()).
    rtcSetSceneFlags(scene, settings.robust_intersection ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    check("rtcNewGeometry");
    rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_HIGH);
    const bool grow = !settings.robust_intersection;
    const std::vector<float> grown = grow ? grown_triangles(mesh, grow_margin_m(mesh)) : std::vector<float>();
    const std::size_t nv = grow ? 3 * mesh.triangles.size() : mesh.vertices.size();
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv));
    auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                                               mesh.triangles.size()));
    if (!v || !idx) {
      rtcReleaseGeometry(g);
      check("rtcSetNewGeometryBuffer");
      fail(ErrorCode::kInternal, "RgbdRenderer: rtcSetNewGeometryBuffer returned null");
    }
    if (grow) {
      std::copy(grown.begin(), grown.end(), v);
      for (std::size_t i = 0; i < 3 * mesh.triangles.size(); ++i) idx[i] = static_cast<unsigned>(i);
    } else {
      for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
        for (int k = 0; k < 3; ++k) v[3 * i + static_cast<std::size_t>(k)] = mesh.vertices[i][k];
      for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
        for (int k = 0; k < 3; ++k) idx[3 * i + static_cast<std::size_t>(k)] = mesh.triangles[i][static_cast<std::size_t>(k)];
    }
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(scene, g, 0);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene);
    check("rtcCommitScene");
  }

  void render(std::span<const RenderJob> jobs) const;
};

void RgbdRenderer::Impl::render(std::span<const RenderJob> jobs) const {
  // Validate every job before touching any output.
  std::vector<FrameParams> frames;
  frames.reserve(jobs.size());
  for (std::size_t j = 0; j < jobs.size(); ++j) {
    const RenderJob& job = jobs[j];
    if (!job.sensor || !job.out)
      fail(ErrorCode::kInvalidArgument, "RgbdRenderer::render_batch: job " + std::to_string(j) + ": sensor and out must not be null");
    for (std::size_t i = 0; i < j; ++i)
      if (jobs[i].out == job.out)
        fail(ErrorCode::kInvalidArgument, "RgbdRenderer::render_batch: jobs " + std::to_string(i) + " and " + std::to_string(j) +
                                              " write the same output image");
    frames.push_back(make_params(settings, *job.sensor, job.T_world_optical, job.frame_seed, job.colour));
  }
  std::vector<int> first_tile(frames.size() + 1, 0);
  for (std::size_t j = 0; j < frames.size(); ++j) {
    FrameParams& P = frames[j];
    RgbdImage& out = *jobs[j].out;
    const std::size_t pixels = static_cast<std::size_t>(P.w) * static_cast<std::size_t>(P.h);
    out.width = P.w;
    out.height = P.h;
    out.depth.resize(pixels);
    if (P.colour)
      out.rgb.resize(3 * pixels);
    else
      out.rgb.clear();
    P.depth = out.depth.data();
    P.rgb = P.colour ? out.rgb.data() : nullptr;
    first_tile[j + 1] = first_tile[j] + P.tiles;
  }
  if (frames.empty()) return;
  // One parallel loop over the tiles of all frames: no barrier between frames, and the threads
  // balance over the whole batch. Every pixel is a pure function of its job, so the images do
  // not depend on the thread count or the tile order.
  const Face* faces_ptr = faces.data();
  const std::uint32_t* tri_ptr = tri_face.data();
  const RTCScene sc = scene;
  const FrameParams* fp = frames.data();
  const int* ft = first_tile.data();
  const int n_frames = static_cast<int>(frames.size());
  tbb::parallel_for(tbb::blocked_range<int>(0, first_tile.back()), [&](const tbb::blocked_range<int>& r) {
    int j = 0;
    for (int i = r.begin(); i != r.end(); ++i) {
      while (j + 1 < n_frames && i >= ft[j + 1]) ++j;
      while (j > 0 && i < ft[j]) --j;
      render_tile(fp[j], faces_ptr, tri_ptr, sc, i - ft[j]);
    }
  });
}

RgbdRenderer::RgbdRenderer(const World& world, const RenderSettings& settings) : impl_(std::make_unique<Impl>()) {
  validate(settings);
  impl_->settings = settings;
  impl_->mesh = build_world_mesh(world);
  make_faces(impl_->mesh, settings, impl_->faces, impl_->tri_face);
  impl_->build();
}

RgbdRenderer::~RgbdRenderer() = default;
RgbdRenderer::RgbdRenderer(RgbdRenderer&&) noexcept = default;
RgbdRenderer& RgbdRenderer::operator=(RgbdRenderer&&) noexcept = default;

void RgbdRenderer::render(const SensorProfile& sensor, const Eigen::Isometry3f& T_world_optical, std::uint64_t frame_seed,
                          RgbdImage& out) const {
  const RenderJob job{&sensor, T_world_optical, frame_seed, &out, true};
  impl_->render(std::span<const RenderJob>(&job, 1));
}

void RgbdRenderer::render_depth_only(const SensorProfile& sensor, const Eigen::Isometry3f& T_world_optical,
                                     std::uint64_t frame_seed, RgbdImage& out) const {
  const RenderJob job{&sensor, T_world_optical, frame_seed, &out, false};
  impl_->render(std::span<const RenderJob>(&job, 1));
}

void RgbdRenderer::render_batch(std::span<const RenderJob> jobs) const { impl_->render(jobs); }

const RenderSettings& RgbdRenderer::settings() const noexcept { return impl_->settings; }
const WorldMesh& RgbdRenderer::mesh() const noexcept { return impl_->mesh; }

}  // namespace duet::sim
