#pragma once
/// @file normals.hpp
/// Surface normals and curvature from the k nearest neighbours (paper §2.2, Eq. (2), k = 10):
///   C = 1/k sum_i (p_i - p_mean)(p_i - p_mean)^T,  normal = eigenvector of the SMALLEST
/// eigenvalue of C. (Eq. (2) as printed takes the largest; that vector lies in the surface,
/// so it is a tangent, not a normal - we follow [30] and PCL.) The neighbourhood includes the
/// query point itself, as in pcl::NormalEstimation. Each normal is flipped toward the
/// viewpoint (dot(viewpoint - p, n) >= 0). curvature = l0 / (l0 + l1 + l2).
/// Points that are not finite, have fewer than 3 neighbours, or whose neighbours are collinear
/// (second eigenvalue <= 1e-7 of the trace) get NaN normal and curvature.
///
/// Neighbours come from KdTree::knn_leaf (exact k nearest, ties by the smaller index; their
/// order in the sums is fixed by the tree, so results are identical for any thread count).
///
/// Thread safety: reentrant; parallel inside (TBB); results identical for any thread count.
#include <duet/kernels/kdtree.hpp>
#include <duet/kernels/types.hpp>

#include <span>

namespace duet {

struct NormalSettings {
  int k = 10;                                               ///< neighbours incl. the point, >= 3
  Eigen::Vector3f viewpoint = Eigen::Vector3f::Zero();      ///< normals face this point [m]
};

/// Normals for every point of `points` using `tree` (built over the same points).
/// normals and curvature must have points.size() entries (curvature may be empty).
void estimate_normals(PointsView points, const KdTree& tree, const NormalSettings& settings,
                      std::span<Eigen::Vector3f> normals, std::span<float> curvature);

/// Builds the tree and fills cloud.normals and cloud.curvature.
void estimate_normals(PointCloud& cloud, const NormalSettings& settings);

/// Normal and curvature of one neighbourhood (the reference math; exposed for tests and ICP).
/// Returns false (and NaNs) when fewer than 3 points are given or they are degenerate.
bool normal_from_neighbours(std::span<const Eigen::Vector3f> nbrs, Eigen::Vector3f& normal,
                            float& curvature);

void validate(const NormalSettings& settings);

}  // namespace duet
