#pragma once
/// @file pose_graph.hpp
/// 2D pose-graph optimisation: the node poses X_k (planar poses, map frame) that best agree
/// with a set of relative-pose measurements (odometry between consecutive nodes, loop closures
/// between a place and its revisit) - DESIGN.md §1's "pose-graph optimisation" in the plane.
///
/// For an edge (i, j) measuring Z_ij = X_i^-1 X_j, the error (Grisetti et al., "A Tutorial on
/// Graph-Based SLAM", 2010, Eq. 30 in SE(2)) is
///   e_ij = ( R_z^T (R_i^T (t_j - t_i) - t_z) ,  wrap(theta_j - theta_i - theta_z) ),
/// and the optimiser minimises  sum_ij rho(e_ij^T Omega_ij e_ij)  over all nodes but the fixed
/// one, rho = Huber on the Mahalanobis distance for edges marked robust (identity otherwise),
/// by Levenberg-Marquardt on the sparse normal equations (Eigen's SimplicialLDLT), in double.
///
/// Determinism: serial, in edge order; the same input gives the same output on any machine
/// with the same floating point.
/// Thread safety: reentrant (no shared state).
#include <duet/kernels/motion_model.hpp>

#include <cstdint>
#include <span>

namespace duet {

struct PoseGraphEdge {
  std::uint32_t from = 0;     ///< node i
  std::uint32_t to = 0;       ///< node j (!= i)
  Pose2 measurement;          ///< Z_ij = X_i^-1 X_j: node j in node i's frame [m, rad]
  float sigma_xy_m = 0.05f;   ///< std of the measured translation, per axis [m], > 0
  float sigma_theta_rad = 0.01f;  ///< std of the measured heading [rad], > 0
  bool robust = false;        ///< Huber loss (PoseGraphSettings::huber_delta) instead of squared
};

struct PoseGraphSettings {
  int max_iterations = 30;          ///< Levenberg-Marquardt iterations, [1, 1000]
  double min_relative_decrease = 1e-9;  ///< stop when the cost falls by less than this fraction, [0, 1)
  double huber_delta = 3.0;         ///< Huber threshold on the Mahalanobis distance of robust edges, > 0
  std::uint32_t fixed_node = 0;     ///< this node does not move (the gauge), < node count
};
/// Throws duet::Error(kInvalidArgument) naming the bad field.
void validate(const PoseGraphSettings& s);

struct PoseGraphResult {
  int iterations = 0;          ///< accepted and rejected LM steps taken
  double initial_cost = 0.0;   ///< sum of rho(e^T Omega e) before [unitless]
  double final_cost = 0.0;     ///< ... after
};

/// Cost of one edge's error (e^T Omega e, before the robust loss) at the given poses.
[[nodiscard]] double pose_graph_edge_chi2(std::span<const Pose2> poses, const PoseGraphEdge& edge);

/// Optimises `poses` in place (initial guess in, optimum out). No edges or one node: nothing
/// moves. Throws duet::Error(kInvalidArgument) for an edge naming a missing node or itself, a
/// non-finite pose, measurement or sigma <= 0, or invalid settings; the poses are then unchanged.
PoseGraphResult optimize_pose_graph(std::span<Pose2> poses, std::span<const PoseGraphEdge> edges,
                                    const PoseGraphSettings& settings = {});

}  // namespace duet
