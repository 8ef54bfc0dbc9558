#include <duet/kernels/error.hpp>
#include <duet/runtime/mapping/mapper.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

namespace duet {

Mapper::Mapper(const MappingSettings& settings, const Eigen::Isometry3f& T_map_world)
    : settings_(settings), T_map_world_(T_map_world), grid_(settings.grid_resolution_m) {
  validate(settings_.back_projection);
  validate(settings_.voxel_filter);
  validate(settings_.normals);
  validate(settings_.segmentation);
  validate(settings_.grid_update);
  if (!T_map_world_.matrix().allFinite()) fail(ErrorCode::kInvalidArgument, "Mapper: T_map_world is not finite");
}

void Mapper::integrate(std::span<const SensorFrame> frames, const Eigen::Isometry3f& T_world_robot) {
  if (!T_world_robot.matrix().allFinite()) fail(ErrorCode::kInvalidArgument, "Mapper::integrate: robot pose is not finite");
  // All frames are validated and back-projected before anything is integrated.
  back_project_camera(frames, settings_.back_projection, camera_);
  integrate(camera_, frames, T_world_robot);
}

void Mapper::integrate(const CameraPoints& points, std::span<const SensorFrame> frames, const Eigen::Isometry3f& T_world_robot) {
  if (!T_world_robot.matrix().allFinite()) fail(ErrorCode::kInvalidArgument, "Mapper::integrate: robot pose is not finite");
  if (points.offsets.size() != frames.size() + 1 || points.offsets.back() != points.cloud.size())
    fail(ErrorCode::kInvalidArgument, "Mapper::integrate: the points are not those of the " + std::to_string(frames.size()) + " frames");
  if (points.pixel_step != settings_.back_projection.pixel_step)
    fail(ErrorCode::kInvalidArgument, "Mapper::integrate: the points were sampled every " + std::to_string(points.pixel_step) +
                                          " pixels, the mapping settings say " + std::to_string(settings_.back_projection.pixel_step));
  const Eigen::Isometry3f T_map_robot = T_map_world_ * T_world_robot;
  const std::vector<std::size_t>& off = points.offsets;
  stats_.raw_points += points.cloud.size();
  obstacles_.clear();
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const Eigen::Isometry3f T_map_camera = T_map_robot * frames[i].T_robot_camera;  // optical -> map
    const std::size_t b = off[i], n = off[i + 1] - b;
    map_points_.resize(n);
    transform_points(points.cloud.points.data() + b, n, T_map_camera, map_points_.data());
    const PointsView pts = n ? PointsView(map_points_[0].data(), n) : PointsView();
    const ColorsView col = n ? ColorsView(&points.cloud.colors[b].r, n) : ColorsView();
    voxel_filter(pts, col, settings_.voxel_filter, vf_ws_, filtered_);
    stats_.filtered_points += filtered_.size();
    const Eigen::Vector3f origin = T_map_camera.translation();
    NormalSettings ns = settings_.normals;
    ns.viewpoint = origin;
    estimate_normals(filtered_, ns);
    labels_.resize(filtered_.size());
    segment(filtered_.points_view(), filtered_.normals, settings_.segmentation, labels_);
    for (std::size_t k = 0; k < labels_.size(); ++k) {
      const PointLabel l = labels_[k];
      stats_.obstacle_points += l == PointLabel::kObstacle;
      stats_.floor_points += l == PointLabel::kFloor;
      if (l == PointLabel::kObstacle) obstacles_.push_back(filtered_.points[k].head<2>());
    }
    update_grid(grid_, origin.head<2>(), filtered_.points_view(), labels_, settings_.grid_update, grid_ws_);
    filtered_.normals.clear();
    filtered_.curvature.clear();
    if (keep_submaps_) {
      Submap& sm = submaps_.back();
      update_grid(sm.grid, origin.head<2>(), filtered_.points_view(), labels_, settings_.grid_update, grid_ws_);
      if (!cloud_frozen_) {
        sm.cloud.append(filtered_);
        cloud_dirty_ = true;
      }
      ++sm.frames;
    } else if (!cloud_frozen_) {
      pending_.append(filtered_);
    }
    ++stats_.frames;
  }
  ++stats_.observations;
  if (keep_submaps_) {
    // The open submap's cloud is re-filtered as it grows (as the global cloud is without submaps).
    // Each refilter leaves the voxels of the area covered; a submap that covers much (the one a
    // finished map keeps open: LoopCloser::freeze()) waits until its cloud doubles again.
    Submap& sm = submaps_.back();
    if (sm.cloud.size() > std::max<std::size_t>(400'000, 2 * open_filtered_size_)) {
      refilter(sm.cloud);
      open_filtered_size_ = sm.cloud.size();
    }
  } else if (pending_.size() > std::max<std::size_t>(global_.size(), 2'000'000)) {
    compact();
  }
}

void Mapper::freeze_cloud() {
  if (cloud_frozen_) return;
  cloud_frozen_ = true;
  if (keep_submaps_) {
    Submap& sm = submaps_.back();
    if (!sm.cloud.empty()) refilter(sm.cloud);  // and its growth's slack released
  } else {
    compact();
  }
}

void Mapper::keep_submaps() {
  if (stats_.observations > 0) fail(ErrorCode::kInvalidArgument, "Mapper::keep_submaps: call it before the first integrate()");
  if (keep_submaps_) return;
  keep_submaps_ = true;
  submaps_.clear();
  submaps_.push_back(Submap{OccupancyGrid(settings_.grid_resolution_m), {}, {}, 0});
}

std::size_t Mapper::open_submap() {
  if (!keep_submaps_) fail(ErrorCode::kInvalidArgument, "Mapper::open_submap: submaps are not kept (call keep_submaps() first)");
  Submap& last = submaps_.back();
  if (last.frames == 0) return submaps_.size() - 1;
  if (!last.cloud.empty()) refilter(last.cloud);
  open_filtered_size_ = 0;
  submaps_.push_back(Submap{OccupancyGrid(settings_.grid_resolution_m), {}, {}, 0});
  return submaps_.size() - 1;
}

void Mapper::place_submaps(std::span<const Pose2> placements) {
  if (!keep_submaps_) fail(ErrorCode::kInvalidArgument, "Mapper::place_submaps: submaps are not kept (call keep_submaps() first)");
  if (placements.size() != submaps_.size())
    fail(ErrorCode::kInvalidArgument, "Mapper::place_submaps: " + std::to_string(placements.size()) + " placements for " +
                                          std::to_string(submaps_.size()) + " submaps");
  for (std::size_t i = 0; i < placements.size(); ++i)
    if (!(std::isfinite(placements[i].x) && std::isfinite(placements[i].y) && std::isfinite(placements[i].theta)))
      fail(ErrorCode::kInvalidArgument, "Mapper::place_submaps: placement " + std::to_string(i) + " is not finite");
  OccupancyGrid grid(settings_.grid_resolution_m);
  for (std::size_t i = 0; i < submaps_.size(); ++i) {
    submaps_[i].placement = placements[i];
    accumulate_grid(grid, submaps_[i].grid, placements[i], settings_.grid_update.min_logodds, settings_.grid_update.max_logodds);
  }
  grid_ = std::move(grid);
  cloud_dirty_ = true;
}

void Mapper::refilter(PointCloud& cloud) {
  PointCloud merged;
  voxel_filter(cloud.points_view(), cloud.colors_view(), settings_.voxel_filter, vf_ws_, merged);
  cloud = std::move(merged);
}

void Mapper::compact() {
  if (pending_.empty()) return;
  global_.append(pending_);
  pending_.clear();
  refilter(global_);
}

const PointCloud& Mapper::cloud() {
  if (!keep_submaps_) {
    compact();
    return global_;
  }
  if (!cloud_dirty_) return global_;
  // The submaps' points at their placements, voxel-filtered together.
  PointCloud all;
  for (const Submap& sm : submaps_) {
    const std::size_t b = all.size();
    all.append(sm.cloud);
    if (sm.placement.x == 0.0f && sm.placement.y == 0.0f && sm.placement.theta == 0.0f) continue;
    for (std::size_t k = b; k < all.size(); ++k) all.points[k].head<2>() = transform_point(sm.placement, all.points[k].head<2>());
  }
  voxel_filter(all.points_view(), all.colors_view(), settings_.voxel_filter, vf_ws_, global_);
  cloud_dirty_ = false;
  return global_;
}

Eigen::Isometry3f gravity_alignment(const Eigen::Vector3f& up) {
  if (!up.allFinite() || up.norm() < 1e-6f)
    fail(ErrorCode::kInvalidArgument, "gravity_alignment: the up direction must be a finite non-zero vector");
  Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
  T.linear() = Eigen::Quaternionf::FromTwoVectors(up.normalized(), Eigen::Vector3f::UnitZ()).toRotationMatrix();
  return T;
}

Eigen::Vector3f refine_up(const PointCloud& cloud, const Eigen::Vector3f& initial_up, float cone_deg) {
  if (!initial_up.allFinite() || initial_up.norm() < 1e-6f)
    fail(ErrorCode::kInvalidArgument, "refine_up: the initial up direction must be a finite non-zero vector");
  Eigen::Vector3f up = initial_up.normalized();
  if (cloud.normals.size() != cloud.size()) fail(ErrorCode::kInvalidArgument, "refine_up: the cloud needs normals");
  for (const float cone : {cone_deg, cone_deg / 2}) {
    const float c = std::cos(cone * std::numbers::pi_v<float> / 180.0f);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    std::size_t count = 0;
    for (const auto& n : cloud.normals) {
      if (!is_finite(n)) continue;
      const float d = n.dot(up);
      if (std::fabs(d) < c) continue;
      sum += (d < 0 ? -n : n).cast<double>();
      ++count;
    }
    if (count < 100) break;
    up = sum.normalized().cast<float>();
  }
  return up;
}

float estimate_floor_z(const PointCloud& cloud, float max_tilt_deg) {
  if (cloud.empty()) return std::numeric_limits<float>::quiet_NaN();
  if (cloud.normals.size() != cloud.size())
    fail(ErrorCode::kInvalidArgument, "estimate_floor_z: the cloud needs normals");
  const float cos_tilt = std::cos(max_tilt_deg * std::numbers::pi_v<float> / 180.0f);
  std::vector<float> z_all, z_h;
  z_all.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto& p = cloud.points[i];
    if (!is_finite(p)) continue;
    z_all.push_back(p.z());
    const auto& n = cloud.normals[i];
    if (is_finite(n) && std::fabs(n.z()) >= cos_tilt) z_h.push_back(p.z());
  }
  if (z_all.empty()) return std::numeric_limits<float>::quiet_NaN();
  std::sort(z_h.begin(), z_h.end());
  const std::size_t need = std::max<std::size_t>(50, z_h.size() / 50);
  constexpr float kBand = 0.05f;
  for (std::size_t b = 0; b < z_h.size();) {
    const auto e = static_cast<std::size_t>(std::upper_bound(z_h.begin() + static_cast<std::ptrdiff_t>(b), z_h.end(), z_h[b] + kBand) - z_h.begin());
    if (e - b >= need) return z_h[b + (e - b) / 2];
    ++b;
  }
  std::sort(z_all.begin(), z_all.end());
  return z_all[z_all.size() / 100];
}

}  // namespace duet
