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
/// Implementation: points are cut into fixed blocks (independent of the thread count). Within a
/// block, runs of consecutive points in one voxel (neighbouring pixels) are summed without a
/// branch (SSE2) and each run is added to a per-thread hash table of integer voxel cells; a
/// block hands over its distinct cells with their sums. All blocks' cells are then sorted by
/// linear voxel index (stable radix sort: the cells of a voxel stay in block order) and summed
/// per voxel. No bounds pass: the index range comes from the distinct cells. Sums are in double.
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
/// Sums of the points of one voxel cell within one block of input points.
struct VoxelCellSums {
  std::int32_t x = 0, y = 0, z = 0;
  std::uint32_t count = 0;  ///< 0 = empty hash slot
  double sx = 0, sy = 0, sz = 0;
  std::uint32_t r = 0, g = 0, b = 0;
};

/// Per-thread hash table cell -> sums (sums stored in the slot: one cache line per lookup);
/// cleared after each block by resetting only the used slots.
/// One run of consecutive input points in one voxel (64 bytes).
struct alignas(16) VoxelRunRecord {
  std::int32_t x, y, z, zero;
  double sx, sy, sz, pad;
  std::uint32_t r, g, b, count;
};

struct VoxelCellTable {
  struct alignas(64) Slot {
    VoxelCellSums s;
  };
  std::vector<Slot> slots;
  std::vector<VoxelRunRecord> runs;  ///< scratch: the runs of one chunk of points
  std::vector<std::uint32_t> used;  ///< occupied slots in insertion order
  std::uint64_t mask = 0;
  int shift = 64;
};

/// What one block of input points contributes: its distinct cells in first-seen order.
struct VoxelBlock {
  std::vector<VoxelCellSums> cells;
  std::int32_t lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};  ///< cell range (when cells is non-empty)
  // The first finite coordinate whose voxel index does not fit (error report).
  bool out_of_range = false;
  float bad_value = 0.0f;
  int bad_axis = 0;
};
}  // namespace detail

/// Reusable scratch memory: keep one per thread of calls to avoid allocation per call.
struct VoxelFilterWorkspace {
  std::vector<detail::VoxelBlock> blocks;      ///< one per fixed block of input points
  std::vector<detail::VoxelCellTable> tables;  ///< one per worker thread
  std::vector<std::size_t> offsets;  ///< first global cell of each block
  std::vector<const detail::VoxelCellSums*> cell_ptr;
  std::vector<std::size_t> chunk_kept;
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
