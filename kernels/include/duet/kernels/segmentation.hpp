#pragma once
/// @file segmentation.hpp
/// Obstacle / floor segmentation of a cloud with normals (paper §2.2, Fig. 4), in a frame whose
/// +z is up and whose floor is at z = floor_z_m:
///  1. points above max_height_m (ceiling, lamps) or below min_height_m are ignored;
///  2. a point whose normal deviates from vertical by more than max_floor_tilt_deg is an obstacle;
///  3. the remaining (horizontal-surface) points are Euclidean-clustered; a cluster whose centre
///     is higher than floor_height_threshold_m above the floor is an obstacle (table top, seat),
///     otherwise it is free floor; clusters smaller than min_size are ignored as speckle.
/// Points with a NaN normal are ignored.
///
/// Thread safety: reentrant; parallel inside (TBB); results identical for any thread count.
#include <duet/kernels/clustering.hpp>
#include <duet/kernels/types.hpp>

#include <cstdint>
#include <span>

namespace duet {

enum class PointLabel : std::uint8_t {
  kFloor = 0,     ///< traversable floor: clears grid cells
  kObstacle = 1,  ///< marks grid cells occupied
  kIgnored = 2,   ///< outside the height band, no normal, or speckle
};

struct SegmentationSettings {
  float floor_z_m = 0.0f;                 ///< floor height in the cloud's frame [m]
  float max_floor_tilt_deg = 20.0f;       ///< normal-to-vertical angle above which a point is an obstacle [deg]
  float floor_height_threshold_m = 0.10f; ///< cluster centre higher than this above the floor = obstacle [m]
  float min_height_m = -0.30f;            ///< points lower than this above the floor are ignored [m]
  float max_height_m = 1.20f;             ///< points higher than this above the floor are ignored [m]
  ClusteringSettings clustering{0.10f, 20, 0xFFFFFFFFu};  ///< clustering of horizontal points
};

/// Labels every point. normals has points.size() entries; labels receives points.size().
void segment(PointsView points, std::span<const Eigen::Vector3f> normals,
             const SegmentationSettings& settings, std::span<PointLabel> labels);

void validate(const SegmentationSettings& settings);

}  // namespace duet
