#include <duet/kernels/error.hpp>
#include <duet/kernels/voxel_filter.hpp>

#include "parallel.hpp"
#include "radix_sort.hpp"

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

namespace duet {

void validate(const VoxelFilterSettings& s) {
  if (!(s.leaf_size_m > 0.0f) || !std::isfinite(s.leaf_size_m))
    fail(ErrorCode::kInvalidArgument, "VoxelFilterSettings.leaf_size_m must be finite and > 0 m, got " +
                                          std::to_string(s.leaf_size_m));
  if (s.min_points_per_voxel < 1)
    fail(ErrorCode::kInvalidArgument, "VoxelFilterSettings.min_points_per_voxel must be >= 1");
}

namespace {

using Map = detail::VoxelAccumMap;
constexpr std::size_t kBlock = 1 << 15;
constexpr std::uint64_t kEmpty = std::numeric_limits<std::uint64_t>::max();

// floor() for |x| < 2^31 without a libm call (x86-64 baseline has no SSE4.1 round): the same
// value as std::floor, so voxel assignment matches pcl::VoxelGrid exactly.
inline std::int64_t fast_floor(float x) {
  const auto i = static_cast<std::int32_t>(x);
  return static_cast<std::int64_t>(i - (x < static_cast<float>(i) ? 1 : 0));
}

void map_reset(Map& m, std::size_t expected) {
  const std::size_t cap = std::bit_ceil(std::max<std::size_t>(64, 2 * expected));
  m.slot_key.assign(cap, kEmpty);
  m.slot_index.resize(cap);
  m.mask = cap - 1;
  m.shift = 64 - std::countr_zero(cap);
  m.keys.clear();
  m.acc.clear();
}

std::uint32_t map_insert(Map& m, std::uint64_t key);

void map_grow(Map& m) {
  const std::size_t cap = 2 * m.slot_key.size();
  m.slot_key.assign(cap, kEmpty);
  m.slot_index.resize(cap);
  m.mask = cap - 1;
  m.shift = 64 - std::countr_zero(cap);
  for (std::size_t i = 0; i < m.keys.size(); ++i) {
    std::uint64_t h = (m.keys[i] * 0x9E3779B97F4A7C15ull) >> m.shift;
    while (m.slot_key[h] != kEmpty) h = (h + 1) & m.mask;
    m.slot_key[h] = m.keys[i];
    m.slot_index[h] = static_cast<std::uint32_t>(i);
  }
}

inline std::uint32_t map_insert(Map& m, std::uint64_t key) {
  std::uint64_t h = (key * 0x9E3779B97F4A7C15ull) >> m.shift;
  while (true) {
    const std::uint64_t k = m.slot_key[h];
    if (k == key) return m.slot_index[h];
    if (k == kEmpty) break;
    h = (h + 1) & m.mask;
  }
  if (2 * (m.keys.size() + 1) > m.slot_key.size()) {
    map_grow(m);
    return map_insert(m, key);
  }
  const auto idx = static_cast<std::uint32_t>(m.keys.size());
  m.slot_key[h] = key;
  m.slot_index[h] = idx;
  m.keys.push_back(key);
  m.acc.emplace_back();
  return idx;
}

struct Bounds {
  Eigen::Vector3f lo{std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
                     std::numeric_limits<float>::infinity()};
  Eigen::Vector3f hi = -lo;
  std::size_t finite = 0;
};

}  // namespace

void voxel_filter(PointsView points, ColorsView colors, const VoxelFilterSettings& settings,
                  VoxelFilterWorkspace& ws, PointCloud& out) {
  validate(settings);
  const std::size_t n = points.size();
  const bool with_color = !colors.empty();
  if (with_color && colors.size() != n)
    fail(ErrorCode::kInvalidArgument, "voxel_filter: " + std::to_string(colors.size()) + " colours for " +
                                          std::to_string(n) + " points");
  if (n >= std::numeric_limits<std::uint32_t>::max())
    fail(ErrorCode::kInvalidArgument, "voxel_filter: more than 2^32-2 points");
  // In-place use (out is the cloud being viewed): filter into a temporary, then move.
  auto overlaps = [](const void* p, const void* b, std::size_t bytes) {
    const auto pi = reinterpret_cast<std::uintptr_t>(p), bi = reinterpret_cast<std::uintptr_t>(b);
    return p != nullptr && b != nullptr && pi >= bi && pi < bi + bytes;
  };
  if (n > 0 && (overlaps(points.ptr(0), out.points.data(), out.points.size() * sizeof(Eigen::Vector3f)) ||
                (with_color && overlaps(colors.ptr(0), out.colors.data(), out.colors.size() * sizeof(Rgb8))))) {
    PointCloud tmp;
    voxel_filter(points, colors, settings, ws, tmp);
    out = std::move(tmp);
    return;
  }
  out.clear();
  if (n == 0) return;

  // 1. Bounds of the finite points (min/max are exact: the reduction order does not matter).
  //    The fast pass takes every finite coordinate, also of points with a NaN in another one;
  //    that only widens the box, and if the wider box fails the range check below, the bounds
  //    are recomputed from the finite points alone before any error is raised.
  auto exact_bounds = [&](std::size_t begin, std::size_t end) {
    Bounds bb;
    for (std::size_t i = begin; i < end; ++i) {
      const Eigen::Vector3f q = points[i];
      if (!is_finite(q)) continue;
      bb.lo = bb.lo.cwiseMin(q);
      bb.hi = bb.hi.cwiseMax(q);
      ++bb.finite;
    }
    return bb;
  };
  const std::size_t nb = detail::block_count(n, kBlock);
  std::vector<Bounds> block_bounds(nb);
  detail::for_blocks(n, kBlock, [&](std::size_t b, std::size_t begin, std::size_t end) {
    // Plain float min/max: written as (x < lo ? x : lo), a NaN never replaces a bound.
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (std::size_t i = begin; i < end; ++i) {
      const float* p = points.ptr(i);
      for (int a = 0; a < 3; ++a) {
        lo[a] = p[a] < lo[a] ? p[a] : lo[a];
        hi[a] = p[a] > hi[a] ? p[a] : hi[a];
      }
    }
    Bounds bb;
    bb.lo = Eigen::Vector3f(lo[0], lo[1], lo[2]);
    bb.hi = Eigen::Vector3f(hi[0], hi[1], hi[2]);
    if (!bb.lo.allFinite() || !bb.hi.allFinite()) {  // an infinite point (or none finite): exact pass
      bb = exact_bounds(begin, end);
    } else {
      bb.finite = 1;  // at least one finite point (the exact count is not needed)
    }
    block_bounds[b] = bb;
  });
  Bounds all;
  for (const auto& bb : block_bounds) {
    if (bb.finite == 0) continue;
    all.lo = all.lo.cwiseMin(bb.lo);
    all.hi = all.hi.cwiseMax(bb.hi);
    all.finite += bb.finite;
  }
  if (all.finite == 0) return;

  // 2. Voxel index range, exactly as pcl::VoxelGrid: floor(p * inverse_leaf) in float.
  const float inv = 1.0f / settings.leaf_size_m;
  constexpr float kLimit = 2147483520.0f;  // largest float below 2^31
  auto in_range = [&](const Bounds& b) {
    for (int a = 0; a < 3; ++a)
      if (!(std::fabs(b.lo[a] * inv) < kLimit) || !(std::fabs(b.hi[a] * inv) < kLimit)) return false;
    return true;
  };
  if (!in_range(all)) {
    all = exact_bounds(0, n);
    if (all.finite == 0) return;
  }
  std::int64_t min_b[3], div[3];
  for (int a = 0; a < 3; ++a) {
    const float lo = all.lo[a] * inv, hi = all.hi[a] * inv;
    if (!(std::fabs(lo) < kLimit) || !(std::fabs(hi) < kLimit))
      fail(ErrorCode::kOutOfRange, "voxel_filter: coordinate " +
                                       std::to_string(std::fabs(lo) > std::fabs(hi) ? all.lo[a] : all.hi[a]) +
                                       " m on axis " + "xyz"[a] + " is too large for a voxel index at leaf " +
                                       std::to_string(settings.leaf_size_m) + " m (|p / leaf| must be < 2^31)");
    min_b[a] = fast_floor(lo);
    div[a] = fast_floor(hi) - min_b[a] + 1;
  }
  std::uint64_t total = 0, dxy = 0;
  const bool overflow =
      __builtin_mul_overflow(static_cast<std::uint64_t>(div[0]), static_cast<std::uint64_t>(div[1]), &dxy) ||
      __builtin_mul_overflow(dxy, static_cast<std::uint64_t>(div[2]), &total) || total >= (std::uint64_t{1} << 63);
  if (overflow)
    fail(ErrorCode::kOutOfRange, "voxel_filter: the bounding box holds more than 2^63 voxels at leaf " +
                                     std::to_string(settings.leaf_size_m) + " m; the voxel index would overflow");
  const std::uint64_t mul_y = static_cast<std::uint64_t>(div[0]);
  const std::uint64_t mul_z = dxy;

  // 3. Per block: sums per voxel (key = z-major linear voxel index, PCL's order).
  if (ws.blocks.size() < nb) ws.blocks.resize(nb);
  detail::for_blocks(n, kBlock, [&](std::size_t b, std::size_t begin, std::size_t end) {
    Map& m = ws.blocks[b];
    map_reset(m, std::max<std::size_t>(m.keys.size(), 256));
    // Runs of consecutive points in one voxel (neighbouring pixels) are summed in registers and
    // added to the map once per run.
    std::uint64_t run_key = kEmpty;
    double sx = 0, sy = 0, sz = 0;
    std::uint64_t sr = 0, sg = 0, sb = 0;
    std::uint32_t sc = 0;
    auto flush = [&] {
      if (sc == 0) return;
      auto& a = m.acc[map_insert(m, run_key)];
      a.x += sx;
      a.y += sy;
      a.z += sz;
      a.r += sr;
      a.g += sg;
      a.b += sb;
      a.count += sc;
      sx = sy = sz = 0;
      sr = sg = sb = 0;
      sc = 0;
    };
    for (std::size_t i = begin; i < end; ++i) {
      const float* p = points.ptr(i);
      if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) continue;
      const auto ix = static_cast<std::uint64_t>(fast_floor(p[0] * inv) - min_b[0]);
      const auto iy = static_cast<std::uint64_t>(fast_floor(p[1] * inv) - min_b[1]);
      const auto iz = static_cast<std::uint64_t>(fast_floor(p[2] * inv) - min_b[2]);
      const std::uint64_t key = ix + iy * mul_y + iz * mul_z;
      if (key != run_key) {
        flush();
        run_key = key;
      }
      sx += p[0];
      sy += p[1];
      sz += p[2];
      ++sc;
      if (with_color) {
        const std::uint8_t* c = colors.ptr(i);
        sr += c[0];
        sg += c[1];
        sb += c[2];
      }
    }
    flush();
  });

  // 4. Merge the blocks in block order (deterministic sums), then sort the distinct voxels.
  Map* merged = &ws.blocks[0];
  if (nb > 1) {
    std::size_t expected = 0;
    for (std::size_t b = 0; b < nb; ++b) expected = std::max(expected, ws.blocks[b].keys.size());
    map_reset(ws.merged, 2 * expected);
    for (std::size_t b = 0; b < nb; ++b) {
      const Map& m = ws.blocks[b];
      for (std::size_t v = 0; v < m.keys.size(); ++v) {
        auto& dst = ws.merged.acc[map_insert(ws.merged, m.keys[v])];
        const auto& src = m.acc[v];
        dst.x += src.x;
        dst.y += src.y;
        dst.z += src.z;
        dst.r += src.r;
        dst.g += src.g;
        dst.b += src.b;
        dst.count += src.count;
      }
    }
    merged = &ws.merged;
  }
  const std::size_t nvox = merged->keys.size();
  ws.keys.assign(merged->keys.begin(), merged->keys.end());
  ws.order.resize(nvox);
  for (std::size_t v = 0; v < nvox; ++v) ws.order[v] = static_cast<std::uint32_t>(v);
  detail::radix_sort_pairs(ws.keys, ws.order, ws.keys_tmp, ws.order_tmp, total - 1);

  // 5. Centroids and mean colours in voxel order; voxels below min_points_per_voxel dropped.
  const auto& acc = merged->acc;
  const std::uint32_t min_pts = settings.min_points_per_voxel;
  std::size_t kept = nvox;
  if (min_pts > 1) {
    std::size_t o = 0;
    for (std::size_t v = 0; v < nvox; ++v)
      if (acc[ws.order[v]].count >= min_pts) ws.order[o++] = ws.order[v];
    kept = o;
  }
  out.points.resize(kept);
  if (with_color) out.colors.resize(kept);
  detail::for_blocks(kept, 4096, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      const auto& a = acc[ws.order[v]];
      const double c = a.count;
      out.points[v] = Eigen::Vector3f(static_cast<float>(a.x / c), static_cast<float>(a.y / c), static_cast<float>(a.z / c));
      if (with_color) {
        const std::uint64_t h = a.count / 2;
        out.colors[v] = Rgb8{static_cast<std::uint8_t>((a.r + h) / a.count), static_cast<std::uint8_t>((a.g + h) / a.count),
                             static_cast<std::uint8_t>((a.b + h) / a.count)};
      }
    }
  });
}

void voxel_filter(PointsView points, ColorsView colors, const VoxelFilterSettings& settings, PointCloud& out) {
  VoxelFilterWorkspace ws;
  voxel_filter(points, colors, settings, ws, out);
}

}  // namespace duet
