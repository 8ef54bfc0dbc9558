#pragma once
/// @file trajectory_eval.hpp
/// Trajectory accuracy, as the TUM RGB-D benchmark defines it (Sturm et al., IROS 2012) and its
/// tools compute it (associate.py, evaluate_ate.py, evaluate_rpe.py; evo's ape / rpe):
///  - association: every estimate / ground-truth stamp pair with |t_est + offset - t_gt| <
///    max_dt, taken greedily from the smallest difference, each stamp at most once (associate.py);
///  - ATE: the estimate's positions aligned to the ground truth's by the rigid (optionally
///    similarity) transform of least squares (Horn 1987 / Umeyama 1991), then the distances;
///  - RPE: for pairs (i, j) of associated poses, E = (G_i^-1 G_j)^-1 (P_i^-1 P_j); the
///    translation error |t(E)| and the rotation error angle(E). j is i + delta frames, the first
///    pose at least delta seconds later, or the first at least delta metres further along the
///    ground truth (evaluate_rpe.py's delta units f, s, m; evo's frames and metres).
///
/// Thread safety: pure functions.
#include <Eigen/Geometry>

#include <cstddef>
#include <span>
#include <utility>
#include <vector>

namespace duet {

struct StampedPose {
  double stamp_s = 0.0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

struct AssociationSettings {
  double max_dt_s = 0.02;  ///< pairs further apart in time are never associated [s], > 0
  double offset_s = 0.0;   ///< added to the estimate's stamps [s]
};

/// Index pairs (estimate, ground truth), sorted by the estimate's stamp. Stamps need not be
/// sorted. Non-finite stamps are never associated. Throws duet::Error(kInvalidArgument) when
/// max_dt_s is not > 0 or offset_s is not finite.
[[nodiscard]] std::vector<std::pair<std::size_t, std::size_t>> associate(std::span<const StampedPose> estimate,
                                                                         std::span<const StampedPose> ground_truth,
                                                                         const AssociationSettings& settings = {});

/// Summary statistics of a list of errors.
struct ErrorStats {
  std::size_t count = 0;
  double rmse = 0.0, mean = 0.0, median = 0.0, std = 0.0, min = 0.0, max = 0.0;
};
[[nodiscard]] ErrorStats error_stats(std::span<const double> errors);

struct AteSettings {
  AssociationSettings association;
  bool align = true;         ///< false: compare as given (same world frame)
  bool with_scale = false;   ///< similarity alignment (monocular estimates)
};

struct AteResult {
  ErrorStats translation;    ///< [m]
  Eigen::Isometry3d alignment = Eigen::Isometry3d::Identity();  ///< ground truth ~ alignment * scale * estimate
  double scale = 1.0;
  std::vector<std::pair<std::size_t, std::size_t>> pairs;        ///< the associated (estimate, ground truth)
  std::vector<double> errors;                                   ///< per pair [m]
};

/// Throws duet::Error(kInvalidArgument) for fewer than 3 associated pairs when aligning (1 when
/// not), or a non-finite pose among them.
[[nodiscard]] AteResult absolute_trajectory_error(std::span<const StampedPose> estimate,
                                                  std::span<const StampedPose> ground_truth,
                                                  const AteSettings& settings = {});

enum class RpeUnit { kFrames = 0, kSeconds = 1, kMetres = 2 };

struct RpeSettings {
  AssociationSettings association;
  double delta = 1.0;              ///< > 0; an integer for kFrames
  RpeUnit unit = RpeUnit::kFrames;
};

struct RpeResult {
  ErrorStats translation;  ///< [m]
  ErrorStats rotation;     ///< [deg]
  std::size_t pairs = 0;   ///< (i, j) pairs evaluated
};

/// Throws duet::Error(kInvalidArgument) for a bad delta or no pair at that delta.
[[nodiscard]] RpeResult relative_pose_error(std::span<const StampedPose> estimate, std::span<const StampedPose> ground_truth,
                                            const RpeSettings& settings = {});

}  // namespace duet
