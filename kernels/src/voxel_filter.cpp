#include <duet/kernels/error.hpp>
#include <duet/kernels/voxel_filter.hpp>

#include "parallel.hpp"
#include "radix_sort.hpp"

#include <tbb/parallel_reduce.h>

#include <cmath>
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

constexpr std::size_t kBlock = 1 << 14;

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

  // 1. Bounds of the finite points (min/max are exact, so the reduction order does not matter).
  const std::size_t nb = detail::block_count(n, kBlock);
  std::vector<Bounds> block_bounds(nb);
  detail::for_blocks(n, kBlock, [&](std::size_t b, std::size_t begin, std::size_t end) {
    Bounds bb;
    for (std::size_t i = begin; i < end; ++i) {
      const Eigen::Vector3f p = points[i];
      if (!is_finite(p)) continue;
      bb.lo = bb.lo.cwiseMin(p);
      bb.hi = bb.hi.cwiseMax(p);
      ++bb.finite;
    }
    block_bounds[b] = bb;
  });
  Bounds all;
  for (const auto& bb : block_bounds) {
    all.lo = all.lo.cwiseMin(bb.lo);
    all.hi = all.hi.cwiseMax(bb.hi);
    all.finite += bb.finite;
  }
  if (all.finite == 0) return;

  // 2. Voxel index range, exactly as pcl::VoxelGrid: floor(p * inverse_leaf) in float.
  const float inv = 1.0f / settings.leaf_size_m;
  std::int64_t min_b[3], div[3];
  for (int a = 0; a < 3; ++a) {
    const float lo = all.lo[a] * inv, hi = all.hi[a] * inv;
    constexpr float kLimit = 2147483520.0f;  // largest float below 2^31
    if (!(std::fabs(lo) < kLimit) || !(std::fabs(hi) < kLimit))
      fail(ErrorCode::kOutOfRange, "voxel_filter: coordinate " + std::to_string(std::fabs(lo) > std::fabs(hi) ? all.lo[a] : all.hi[a]) +
                                       " m on axis " + "xyz"[a] + " is too large for a voxel index at leaf " +
                                       std::to_string(settings.leaf_size_m) + " m (|p / leaf| must be < 2^31)");
    min_b[a] = static_cast<std::int64_t>(std::floor(lo));
    div[a] = static_cast<std::int64_t>(std::floor(hi)) - min_b[a] + 1;
  }
  std::uint64_t total = 0, dxy = 0;
  const bool overflow =
      __builtin_mul_overflow(static_cast<std::uint64_t>(div[0]), static_cast<std::uint64_t>(div[1]), &dxy) ||
      __builtin_mul_overflow(dxy, static_cast<std::uint64_t>(div[2]), &total) || total >= (std::uint64_t{1} << 63);
  if (overflow)
    fail(ErrorCode::kOutOfRange, "voxel_filter: the bounding box holds more than 2^63 voxels at leaf " +
                                     std::to_string(settings.leaf_size_m) + " m; the voxel index would overflow");
  const std::uint64_t mul_y = static_cast<std::uint64_t>(div[0]);
  const std::uint64_t mul_z = static_cast<std::uint64_t>(div[0]) * static_cast<std::uint64_t>(div[1]);
  const std::uint64_t invalid_key = total;  // sorts after every voxel

  // 3. Keys (z-major linear voxel index, PCL's order) and sort.
  ws.keys.resize(n);
  ws.order.resize(n);
  detail::for_blocks(n, kBlock, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Eigen::Vector3f p = points[i];
      ws.order[i] = static_cast<std::uint32_t>(i);
      if (!is_finite(p)) {
        ws.keys[i] = invalid_key;
        continue;
      }
      const auto ix = static_cast<std::int64_t>(std::floor(p.x() * inv)) - min_b[0];
      const auto iy = static_cast<std::int64_t>(std::floor(p.y() * inv)) - min_b[1];
      const auto iz = static_cast<std::int64_t>(std::floor(p.z() * inv)) - min_b[2];
      ws.keys[i] = static_cast<std::uint64_t>(ix) + static_cast<std::uint64_t>(iy) * mul_y +
                   static_cast<std::uint64_t>(iz) * mul_z;
    }
  });
  detail::radix_sort_pairs(ws.keys, ws.order, ws.keys_tmp, ws.order_tmp, invalid_key);

  // 4. Segment starts (first index of each voxel run) among the finite points.
  const std::size_t m = all.finite;  // finite points are the first m after the sort
  const std::size_t mb = detail::block_count(m, kBlock);
  std::vector<std::size_t> starts_in_block(mb + 1, 0);
  detail::for_blocks(m, kBlock, [&](std::size_t b, std::size_t begin, std::size_t end) {
    std::size_t c = 0;
    for (std::size_t i = begin; i < end; ++i) c += (i == 0 || ws.keys[i] != ws.keys[i - 1]) ? 1 : 0;
    starts_in_block[b + 1] = c;
  });
  for (std::size_t b = 0; b < mb; ++b) starts_in_block[b + 1] += starts_in_block[b];
  const std::size_t nvox = starts_in_block[mb];
  ws.segment_begin.resize(nvox + 1);
  ws.segment_begin[nvox] = static_cast<std::uint32_t>(m);
  detail::for_blocks(m, kBlock, [&](std::size_t b, std::size_t begin, std::size_t end) {
    std::size_t o = starts_in_block[b];
    for (std::size_t i = begin; i < end; ++i)
      if (i == 0 || ws.keys[i] != ws.keys[i - 1]) ws.segment_begin[o++] = static_cast<std::uint32_t>(i);
  });

  // 5. Centroid and mean colour per voxel (double accumulation: exact enough for any cloud size).
  out.points.resize(nvox);
  if (with_color) out.colors.resize(nvox);
  std::vector<std::uint8_t> keep;
  const bool filter_small = settings.min_points_per_voxel > 1;
  if (filter_small) keep.assign(nvox, 0);
  detail::for_blocks(nvox, 4096, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      const std::uint32_t s = ws.segment_begin[v], e = ws.segment_begin[v + 1];
      double sx = 0, sy = 0, sz = 0;
      std::uint64_t r = 0, g = 0, bl = 0;
      for (std::uint32_t j = s; j < e; ++j) {
        const std::uint32_t i = ws.order[j];
        const float* p = points.ptr(i);
        sx += p[0];
        sy += p[1];
        sz += p[2];
        if (with_color) {
          const Rgb8 c = colors[i];
          r += c.r;
          g += c.g;
          bl += c.b;
        }
      }
      const double cnt = static_cast<double>(e - s);
      out.points[v] = Eigen::Vector3f(static_cast<float>(sx / cnt), static_cast<float>(sy / cnt),
                                      static_cast<float>(sz / cnt));
      if (with_color) {
        const std::uint64_t c = e - s;
        out.colors[v] = Rgb8{static_cast<std::uint8_t>((r + c / 2) / c), static_cast<std::uint8_t>((g + c / 2) / c),
                             static_cast<std::uint8_t>((bl + c / 2) / c)};
      }
      if (filter_small) keep[v] = (e - s) >= settings.min_points_per_voxel;
    }
  });
  if (filter_small) {
    std::size_t o = 0;
    for (std::size_t v = 0; v < nvox; ++v) {
      if (!keep[v]) continue;
      out.points[o] = out.points[v];
      if (with_color) out.colors[o] = out.colors[v];
      ++o;
    }
    out.points.resize(o);
    if (with_color) out.colors.resize(o);
  }
}

void voxel_filter(PointsView points, ColorsView colors, const VoxelFilterSettings& settings, PointCloud& out) {
  VoxelFilterWorkspace ws;
  voxel_filter(points, colors, settings, ws, out);
}

}  // namespace duet
