/// @file observation_embree.cpp
/// ObservationModel's Embree backend: per-tile scenes of occupied-cell faces, 8-wide tracing, sums to the hit.
#include "observation_model.hpp"

#include <duet/kernels/embree_device.hpp>
#include <duet/kernels/error.hpp>

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

namespace duet {

// ---- Embree scenes ------------------------------------------------------------------------------

void ObservationModel::Impl::on_error(void* user, RTCError code, const char* str) {
  auto* self = static_cast<Impl*>(user);
  const std::lock_guard<std::mutex> lock(self->error_mutex);
  self->error_message = "Embree error " + std::to_string(static_cast<int>(code)) + ": " + (str ? str : "");
}

void ObservationModel::Impl::check(const char* what) {
  const RTCError e = rtcGetDeviceError(device);
  if (e == RTC_ERROR_NONE) return;
  std::string msg;
  {
    const std::lock_guard<std::mutex> lock(error_mutex);
    msg = error_message;
  }
  fail(e == RTC_ERROR_OUT_OF_MEMORY ? ErrorCode::kOutOfMemory : ErrorCode::kInternal,
       std::string("ObservationModel: ") + what + " failed: " + (msg.empty() ? std::to_string(static_cast<int>(e)) : msg));
}

void ObservationModel::Impl::init_embree() {
  device = new_embree_device("ObservationModel");
  rtcSetDeviceErrorFunction(device, &Impl::on_error, this);
  top = rtcNewScene(device);
  check("rtcNewScene");
}

void ObservationModel::Impl::release_tile(std::size_t t) {
  Tile& tile = tiles[t];
  if (tile.instance) {
    rtcDetachGeometry(top, static_cast<unsigned>(t));
    rtcReleaseGeometry(tile.instance);
    tile.instance = nullptr;
  }
  if (tile.scene) {
    rtcReleaseScene(tile.scene);
    tile.scene = nullptr;
  }
  tile.quads.clear();
}

void ObservationModel::Impl::release_tiles() {
  for (std::size_t t = 0; t < tiles.size(); ++t) release_tile(t);
}

void ObservationModel::Impl::build_tile_scene(std::size_t t) {
  Tile& tile = tiles[t];
  const int T = settings.tile_cells;
  const int tx = static_cast<int>(t % static_cast<std::size_t>(tiles_x)), ty = static_cast<int>(t / static_cast<std::size_t>(tiles_x));
  const int x0 = tx * T, x1 = std::min(view.width, x0 + T), y0 = ty * T, y1 = std::min(view.height, y0 + T);
  tile.quads.clear();
  for (int iy = y0; iy < y1; ++iy)
    for (int ix = x0; ix < x1; ++ix) {
      if (!occupied(ix, iy)) continue;
      const std::uint32_t c = static_cast<std::uint32_t>(view.index(ix, iy)) << 2;
      if (!occupied(ix - 1, iy)) tile.quads.push_back(c | 0u);
      if (!occupied(ix + 1, iy)) tile.quads.push_back(c | 1u);
      if (!occupied(ix, iy - 1)) tile.quads.push_back(c | 2u);
      if (!occupied(ix, iy + 1)) tile.quads.push_back(c | 3u);
    }
  if (tile.quads.empty()) return;
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_QUAD);
  const std::size_t nq = tile.quads.size();
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 4 * nq));
  auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4, 4 * sizeof(unsigned), nq));
  if (!v || !idx) {
    rtcReleaseGeometry(g);
    return;  // reported through the device error (checked by the caller)
  }
  const float res = view.resolution_m, ox = view.origin.x(), oy = view.origin.y();
  const int w = view.width;
  for (std::size_t q = 0; q < nq; ++q) {
    const std::uint32_t cell = tile.quads[q] >> 2, face = tile.quads[q] & 3u;
    const int ix = static_cast<int>(cell % static_cast<std::uint32_t>(w)), iy = static_cast<int>(cell / static_cast<std::uint32_t>(w));
    const float xa = ox + static_cast<float>(ix) * res, xb = ox + static_cast<float>(ix + 1) * res;
    const float ya = oy + static_cast<float>(iy) * res, yb = oy + static_cast<float>(iy + 1) * res;
    float ax, ay, bx, by;  // the face's segment
    switch (face) {
      case 0: ax = xa; ay = ya; bx = xa; by = yb; break;
      case 1: ax = xb; ay = ya; bx = xb; by = yb; break;
      case 2: ax = xa; ay = ya; bx = xb; by = ya; break;
      default: ax = xa; ay = yb; bx = xb; by = yb; break;
    }
    float* p = v + 12 * q;
    p[0] = ax; p[1] = ay; p[2] = -1.0f;
    p[3] = bx; p[4] = by; p[5] = -1.0f;
    p[6] = bx; p[7] = by; p[8] = 1.0f;
    p[9] = ax; p[10] = ay; p[11] = 1.0f;
    const auto b = static_cast<unsigned>(4 * q);
    idx[4 * q + 0] = b;
    idx[4 * q + 1] = b + 1;
    idx[4 * q + 2] = b + 2;
    idx[4 * q + 3] = b + 3;
  }
  rtcCommitGeometry(g);
  tile.scene = rtcNewScene(device);
  rtcAttachGeometryByID(tile.scene, g, 0);
  rtcReleaseGeometry(g);
  rtcCommitScene(tile.scene);
  tile.instance = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
  rtcSetGeometryInstancedScene(tile.instance, tile.scene);
  static constexpr float kIdentity[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
  rtcSetGeometryTransform(tile.instance, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, kIdentity);
  rtcCommitGeometry(tile.instance);
}

void ObservationModel::Impl::rebuild_tiles(const std::vector<std::size_t>& list) {
  for (const std::size_t t : list) release_tile(t);
  check("releasing tiles");
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, list.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) build_tile_scene(list[i]);
  });
  check("building tile scenes");
  for (const std::size_t t : list)
    if (tiles[t].instance) rtcAttachGeometryByID(top, tiles[t].instance, static_cast<unsigned>(t));
  rtcCommitScene(top);
  check("rtcCommitScene");
}

// ---- Embree tracing -----------------------------------------------------------------------------

Eigen::Vector2i ObservationModel::Impl::first_cell(const Eigen::Vector2f& o, const Eigen::Vector2f& d, float t0, float t1) const noexcept {
  Eigen::Vector2i c(std::numeric_limits<int>::min(), std::numeric_limits<int>::min());
  walk_cells(view, o, d, t0, t1, [&](int ix, int iy, float, float) {
    c = Eigen::Vector2i(ix, iy);
    return false;
  });
  return c;
}

// The distance along o + t d to the face `code` (cell << 2 | side) hit by Embree, from the face's
// line as build_tile_scene() placed it, in double: the same bits on every CPU. Embree's own
// distance goes through an approximate reciprocal whose bits differ between Intel and AMD CPUs
// and between Embree's ISAs. `fallback` (Embree's) only for a degenerate direction.
float ObservationModel::Impl::face_distance(std::uint32_t code, const Eigen::Vector2f& o, const Eigen::Vector2f& d,
                                            float fallback) const noexcept {
  const std::uint32_t cell = code >> 2, face = code & 3u;
  const int w = view.width;
  const int ix = static_cast<int>(cell % static_cast<std::uint32_t>(w)), iy = static_cast<int>(cell / static_cast<std::uint32_t>(w));
  const float res = view.resolution_m;
  double t = 0.0;
  if (face < 2) {
    const float x = view.origin.x() + static_cast<float>(ix + static_cast<int>(face)) * res;
    t = (static_cast<double>(x) - o.x()) / static_cast<double>(d.x());
  } else {
    const float y = view.origin.y() + static_cast<float>(iy + static_cast<int>(face - 2u)) * res;
    t = (static_cast<double>(y) - o.y()) / static_cast<double>(d.y());
  }
  return std::isfinite(t) && t >= 0.0 ? static_cast<float>(t) : fallback;
}

void ObservationModel::Impl::trace8(const Eigen::Vector2f* o, const Eigen::Vector2f* d, int count, float t0, float t1,
                                    float* range, std::int64_t* cell) const {
  alignas(32) int valid[8];
  RTCRayHit8 rh;
  for (int k = 0; k < 8; ++k) {
    valid[k] = 0;
    range[k] = t1;
    cell[k] = -1;
    // Every lane holds a well-formed ray, also those masked out: with stack garbage there,
    // Embree's SSE kernels (rtcIntersect8 as two packets of 4, through the tile instances) failed
    // their assertion all(valid, ray.valid()) under the sanitizer build.
    rh.ray.org_x[k] = 0.0f;
    rh.ray.org_y[k] = 0.0f;
    rh.ray.org_z[k] = 0.0f;
    rh.ray.dir_x[k] = 1.0f;
    rh.ray.dir_y[k] = 0.0f;
    rh.ray.dir_z[k] = 0.0f;
    rh.ray.tnear[k] = 0.0f;
    rh.ray.tfar[k] = 0.0f;
    rh.ray.time[k] = 0.0f;
    rh.ray.mask[k] = 0xFFFFFFFFu;
    rh.ray.id[k] = static_cast<unsigned>(k);
    rh.ray.flags[k] = 0;
    rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    if (k >= count) continue;
    const Eigen::Vector2i c0 = first_cell(o[k], d[k], t0, t1);
    if (view.in_bounds(c0.x(), c0.y()) && occupied(c0.x(), c0.y())) {
      range[k] = t0;
      cell[k] = static_cast<std::int64_t>(view.index(c0.x(), c0.y()));
      continue;
    }
    valid[k] = -1;
    rh.ray.org_x[k] = o[k].x();  // z, time, mask, id, flags and the hit as set above
    rh.ray.org_y[k] = o[k].y();
    rh.ray.dir_x[k] = d[k].x();
    rh.ray.dir_y[k] = d[k].y();
    rh.ray.tnear[k] = t0;
    rh.ray.tfar[k] = t1;
  }
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  rtcIntersect8(valid, top, &ctx, &rh);
  for (int k = 0; k < count; ++k) {
    if (!valid[k]) continue;
    for (int retry = 0; retry < 4 && rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID; ++retry) {
      const std::uint32_t code = tiles[rh.hit.instID[0][k]].quads[rh.hit.primID[k]];
      const std::uint32_t face = code & 3u;
      const float dn = face == 0 ? -d[k].x() : face == 1 ? d[k].x() : face == 2 ? -d[k].y() : d[k].y();
      if (dn < 0.0f) {  // entering the occupied cell: a real hit
        range[k] = face_distance(code, o[k], d[k], rh.ray.tfar[k]);
        cell[k] = static_cast<std::int64_t>(code >> 2);
        break;
      }
      // Leaving an occupied cell (the ray started on its face): trace on from just past it.
      RTCRayHit one;
      one.ray.org_x = o[k].x();
      one.ray.org_y = o[k].y();
      one.ray.org_z = 0.0f;
      one.ray.dir_x = d[k].x();
      one.ray.dir_y = d[k].y();
      one.ray.dir_z = 0.0f;
      one.ray.tnear = std::nextafter(rh.ray.tfar[k], std::numeric_limits<float>::infinity());
      one.ray.tfar = t1;
      one.ray.time = 0.0f;
      one.ray.mask = 0xFFFFFFFFu;
      one.ray.id = 0;
      one.ray.flags = 0;
      one.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      one.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      RTCIntersectContext c1;
      rtcInitIntersectContext(&c1);
      rtcIntersect1(top, &c1, &one);
      rh.hit.geomID[k] = one.hit.geomID;
      rh.hit.instID[0][k] = one.hit.instID[0];
      rh.hit.primID[k] = one.hit.primID;
      rh.ray.tfar[k] = one.ray.tfar;
    }
  }
}

RayObservation ObservationModel::Impl::sum_to(const Eigen::Vector2f& o, const Eigen::Vector2f& d, float t0, float t1,
                                              float range, std::int64_t cell) const noexcept {
  RayObservation r{0.0f, cell >= 0 ? range : t1, cell >= 0, 0};
  const int hx = cell >= 0 ? static_cast<int>(cell % view.width) : std::numeric_limits<int>::min();
  const int hy = cell >= 0 ? static_cast<int>(cell / view.width) : std::numeric_limits<int>::min();
  const float stop = cell >= 0 ? range + 1e-4f : std::numeric_limits<float>::infinity();
  std::uint64_t sum = 0;
  std::int32_t n = 0;
  walk_cells(view, o, d, t0, t1, [&](int ix, int iy, float te, float) {
    if (te > stop) return false;
    sum += word_entropy(word(ix, iy));
    ++n;
    return !(ix == hx && iy == hy);
  });
  r.entropy_bits = bits_of(sum);
  r.cells = n;
  return r;
}

}  // namespace duet
