#include <duet/kernels/error.hpp>
#include <duet/kernels/segmentation.hpp>

#include "parallel.hpp"

#include <cmath>
#include <numbers>
#include <string>

namespace duet {

void validate(const SegmentationSettings& s) {
  if (!std::isfinite(s.floor_z_m)) fail(ErrorCode::kInvalidArgument, "SegmentationSettings.floor_z_m must be finite");
  if (!(s.max_floor_tilt_deg >= 0.0f && s.max_floor_tilt_deg <= 90.0f))
    fail(ErrorCode::kInvalidArgument, "SegmentationSettings.max_floor_tilt_deg must be in [0, 90] deg, got " +
                                          std::to_string(s.max_floor_tilt_deg));
  if (!std::isfinite(s.floor_height_threshold_m))
    fail(ErrorCode::kInvalidArgument, "SegmentationSettings.floor_height_threshold_m must be finite");
  if (!(s.min_height_m < s.max_height_m) || !std::isfinite(s.min_height_m) || !std::isfinite(s.max_height_m))
    fail(ErrorCode::kInvalidArgument, "SegmentationSettings.max_height_m must be finite and greater than min_height_m (" +
                                          std::to_string(s.min_height_m) + "), got " + std::to_string(s.max_height_m));
  validate(s.clustering);
}

void segment(PointsView points, std::span<const Eigen::Vector3f> normals, const SegmentationSettings& settings,
             std::span<PointLabel> labels) {
  validate(settings);
  const std::size_t n = points.size();
  if (normals.size() != n || labels.size() != n)
    fail(ErrorCode::kInvalidArgument, "segment: " + std::to_string(n) + " points, " + std::to_string(normals.size()) +
                                          " normals, " + std::to_string(labels.size()) + " labels (must be equal)");
  // |n . up| >= cos(max tilt)  <=>  the normal is within max tilt of vertical.
  const float cos_tilt = std::cos(settings.max_floor_tilt_deg * std::numbers::pi_v<float> / 180.0f);
  const float z0 = settings.floor_z_m;
  std::vector<std::uint8_t> horizontal(n, 0);
  detail::for_each_index(n, 4096, [&](std::size_t i) {
    const Eigen::Vector3f p = points[i];
    const Eigen::Vector3f& nr = normals[i];
    const float h = p.z() - z0;
    if (!is_finite(p) || !is_finite(nr) || !(h >= settings.min_height_m) || !(h <= settings.max_height_m)) {
      labels[i] = PointLabel::kIgnored;
    } else if (std::fabs(nr.z()) < cos_tilt * nr.norm()) {
      labels[i] = PointLabel::kObstacle;  // §2.2: normal deviates from vertical by more than the threshold
    } else {
      labels[i] = PointLabel::kIgnored;  // decided by its cluster below
      horizontal[i] = 1;
    }
  });
  std::vector<std::uint32_t> subset;
  for (std::size_t i = 0; i < n; ++i)
    if (horizontal[i]) subset.push_back(static_cast<std::uint32_t>(i));
  if (subset.empty()) return;
  ClusteringSettings cs = settings.clustering;
  cs.max_size = 0xFFFFFFFFu;  // every horizontal surface counts, however large
  const auto clusters = euclidean_clusters(points, subset, cs);
  detail::for_each_index(clusters.size(), 1, [&](std::size_t c) {
    const auto& idx = clusters[c];
    double z = 0.0;
    for (const std::uint32_t i : idx) z += points[i].z();
    const double centre = z / static_cast<double>(idx.size()) - z0;
    // §2.2: a cluster whose centre is higher than the threshold is an obstacle, else free floor.
    const PointLabel l = centre > settings.floor_height_threshold_m ? PointLabel::kObstacle : PointLabel::kFloor;
    for (const std::uint32_t i : idx) labels[i] = l;
  });
}

}  // namespace duet
