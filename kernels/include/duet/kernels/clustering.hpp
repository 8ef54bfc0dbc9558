#pragma once
/// @file clustering.hpp
/// Euclidean cluster extraction with pcl::EuclideanClusterExtraction semantics: two points are
/// connected when their distance is <= tolerance; clusters are the connected components;
/// components with fewer than min_size or more than max_size points are dropped (not split).
/// Implementation: a hashed uniform grid of cell size = tolerance (every neighbour within the
/// tolerance lies in the 27 surrounding cells) and a lock-free union-find; the partition is
/// unique, so the result does not depend on the thread count.
/// Output: clusters sorted by size (largest first, ties by smallest index), indices ascending.
///
/// Thread safety: reentrant with one workspace per concurrent call; parallel inside (TBB).
#include <duet/kernels/types.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace duet {

struct ClusteringSettings {
  float tolerance_m = 0.10f;               ///< max distance between neighbours in a cluster [m], > 0
  std::uint32_t min_size = 1;              ///< smaller clusters are dropped [points]
  std::uint32_t max_size = 0xFFFFFFFFu;    ///< larger clusters are dropped [points]
};

struct ClusteringWorkspace {
  std::vector<std::uint64_t> cell_keys, keys_tmp;
  std::vector<std::uint32_t> order, order_tmp, cell_begin, parent, label;
  std::vector<Eigen::Vector3f> sorted_pts;
};

/// Clusters the points of `points` selected by `subset` (all points if empty; an index listed
/// twice counts once). Returned indices are indices into `points`. Non-finite points are never clustered.
/// Throws duet::Error on bad settings, or kOutOfRange when the selected points span more than
/// 2^20 - 1 tolerances on an axis (e.g. 104 km at 0.1 m).
std::vector<std::vector<std::uint32_t>> euclidean_clusters(
    PointsView points, std::span<const std::uint32_t> subset, const ClusteringSettings& settings,
    ClusteringWorkspace& workspace);

std::vector<std::vector<std::uint32_t>> euclidean_clusters(
    PointsView points, std::span<const std::uint32_t> subset, const ClusteringSettings& settings);

void validate(const ClusteringSettings& settings);

}  // namespace duet
