#pragma once
/// @file voxel_filter.hpp
/// Voxel-grid down-sampling with pcl::VoxelGrid semantics (paper §2.2, Fig. 4: voxel 0.05 m):
/// one output point per occupied voxel, at the centroid of the voxel's points, with their mean
/// colour. Voxel of p: floor(p * (1 / leaf)) per axis, computed in float exactly as PCL does,
/// so both assign every point to the same voxel. Output order: voxels sorted by z, then y,
/// then x index (PCL's order). Non-finite points are skipped.
///
/// Coordinates whose voxel index does not fit (|p / leaf| >= 2^31 or more than 2^63 voxels in
/// the bounding box) raise duet::Error(kOutOfRange): never a wrong result. (PCL prints a
/// warning and returns the input unfiltered.)
///
/// Implementation: points are cut into fixed blocks (independent of the thread count); each
/// block sums its points per voxel in a hash map, the block maps are merged in block order, and
/// only the distinct voxels are sorted. Sums are in double.
///
/// Thread safety: reentrant with one workspace per concurrent call; parallel inside (TBB).
/// Results are identical for any thread count.
#include <duet/kernels/types.hpp>

#include <cstdint>
#include <vector>

namespace duet {

struct VoxelFilterSettings {
  float leaf_size_m = 0.05f;               ///< voxel edge [m], > 0
  std::uint32_t min_points_per_voxel = 1;  ///< voxels with fewer points are dropped
};

namespace detail {
/// Open-addressing map voxel key -> running sums (internal to voxel_filter, exposed only so
/// the workspace can keep its memory between calls).
struct VoxelAccumMap {
  struct Accum {
    double x = 0, y = 0, z = 0;
    std::uint64_t r = 0, g = 0, b = 0;
    std::uint32_t count = 0;
  };
  std::vector<std::uint64_t> slot_key;
  std::vector<std::uint32_t> slot_index;
  std::vector<std::uint64_t> keys;  ///< distinct keys in insertion order
  std::vector<Accum> acc;           ///< sums, parallel to keys
  std::uint64_t mask = 0;
  int shift = 64;
};
}  // namespace detail

/// Reusable scratch memory: keep one per thread of calls to avoid allocation per call.
struct VoxelFilterWorkspace {
  std::vector<detail::VoxelAccumMap> blocks;  ///< one map per fixed block of input points
  detail::VoxelAccumMap merged;
  std::vector<std::uint64_t> keys, keys_tmp;
  std::vector<std::uint32_t> order, order_tmp;
};

/// Filters `points` (and `colors`, if non-empty: must have points.size() entries) into `out`
/// (replaced; colors filled only when given). Throws duet::Error on bad settings, colour count
/// mismatch, more than 2^32-1 points, or voxel index overflow.
void voxel_filter(PointsView points, ColorsView colors, const VoxelFilterSettings& settings,
                  VoxelFilterWorkspace& workspace, PointCloud& out);

/// Convenience overload with a temporary workspace.
void voxel_filter(PointsView points, ColorsView colors, const VoxelFilterSettings& settings,
                  PointCloud& out);

void validate(const VoxelFilterSettings& settings);

}  // namespace duet
