// duet_*_settings_init() and the conversion of the C settings structs to the C++ ones.
// The C++ structs' in-class defaults are the single source of the default values.
#include "capi_internal.hpp"

#include <cmath>
#include <string>

namespace duet::capi {
namespace {

duet_clustering_settings to_c(const ClusteringSettings& c) {
  duet_clustering_settings s;
  s.tolerance_m = c.tolerance_m;
  s.min_size = c.min_size;
  s.max_size = c.max_size;
  return s;
}

ClusteringSettings from_c(const duet_clustering_settings& s) {
  ClusteringSettings c;
  c.tolerance_m = s.tolerance_m;
  c.min_size = s.min_size;
  c.max_size = s.max_size;
  return c;
}

}  // namespace

BackProjectionSettings to_cpp(const duet_back_projection_settings* s) {
  BackProjectionSettings c = default_profile().mapping.back_projection;
  if (s != nullptr) {
    c.min_depth_m = s->min_depth_m;
    c.max_depth_m = s->max_depth_m;
    c.pixel_step = s->pixel_step;
  }
  validate(c);
  return c;
}

VoxelFilterSettings to_cpp(const duet_voxel_filter_settings* s) {
  VoxelFilterSettings c = default_profile().mapping.voxel_filter;
  if (s != nullptr) {
    c.leaf_size_m = s->leaf_size_m;
    c.min_points_per_voxel = s->min_points_per_voxel;
  }
  validate(c);
  return c;
}

NormalSettings to_cpp(const duet_normal_settings* s) {
  NormalSettings c = default_profile().mapping.normals;
  if (s != nullptr) {
    c.k = s->k;
    c.viewpoint = Eigen::Vector3f(s->viewpoint[0], s->viewpoint[1], s->viewpoint[2]);
  }
  validate(c);
  return c;
}

ClusteringSettings to_cpp(const duet_clustering_settings* s) {
  ClusteringSettings c = s != nullptr ? from_c(*s) : ClusteringSettings{};
  validate(c);
  return c;
}

SegmentationSettings to_cpp(const duet_segmentation_settings* s) {
  SegmentationSettings c = default_profile().mapping.segmentation;
  if (s != nullptr) {
    c.floor_z_m = s->floor_z_m;
    c.max_floor_tilt_deg = s->max_floor_tilt_deg;
    c.floor_height_threshold_m = s->floor_height_threshold_m;
    c.min_height_m = s->min_height_m;
    c.max_height_m = s->max_height_m;
    c.clustering = from_c(s->clustering);
  }
  validate(c);
  return c;
}

GridUpdateSettings to_cpp(const duet_grid_update_settings* s) {
  GridUpdateSettings c = default_profile().mapping.grid_update;
  if (s != nullptr) {
    if (s->clear_along_rays != 0 && s->clear_along_rays != 1) {
      invalid_argument("settings.clear_along_rays is " + std::to_string(s->clear_along_rays) +
                       " (allowed: 0 or 1)");
    }
    c.hit_logodds = s->hit_logodds;
    c.miss_logodds = s->miss_logodds;
    c.min_logodds = s->min_logodds;
    c.max_logodds = s->max_logodds;
    c.clear_along_rays = s->clear_along_rays != 0;
    c.max_ray_length_m = s->max_ray_length_m;
    c.grow_margin_cells = s->grow_margin_cells;
  }
  validate(c);
  return c;
}

ScanMatchSettings to_cpp(const duet_scan_match_settings* s) {
  ScanMatchSettings c = default_profile().runtime.pose_correction.match;
  if (s != nullptr) {
    c.linear_window_m = s->linear_window_m;
    c.angular_window_deg = s->angular_window_deg;
    c.linear_step_m = s->linear_step_m;
    c.angular_step_deg = s->angular_step_deg;
    c.sigma_m = s->sigma_m;
    c.max_distance_m = s->max_distance_m;
    c.prior_sigma_m = s->prior_sigma_m;
    c.prior_sigma_deg = s->prior_sigma_deg;
    c.min_points = s->min_points;
    c.min_score = s->min_score;
  }
  validate(c);
  return c;
}

const Profile& default_profile() {
  static const Profile p = builtin_profile("dual");
  return p;
}

void fill(const duet::BackProjectionSettings& c, duet_back_projection_settings* settings) {
  settings->min_depth_m = c.min_depth_m;
  settings->max_depth_m = c.max_depth_m;
  settings->pixel_step = c.pixel_step;
}

void fill(const duet::VoxelFilterSettings& c, duet_voxel_filter_settings* settings) {
  settings->leaf_size_m = c.leaf_size_m;
  settings->min_points_per_voxel = c.min_points_per_voxel;
}

void fill(const duet::NormalSettings& c, duet_normal_settings* settings) {
  settings->k = c.k;
  for (int i = 0; i < 3; ++i) settings->viewpoint[i] = c.viewpoint[i];
}

void fill(const duet::SegmentationSettings& c, duet_segmentation_settings* settings) {
  settings->floor_z_m = c.floor_z_m;
  settings->max_floor_tilt_deg = c.max_floor_tilt_deg;
  settings->floor_height_threshold_m = c.floor_height_threshold_m;
  settings->min_height_m = c.min_height_m;
  settings->max_height_m = c.max_height_m;
  settings->clustering = to_c(c.clustering);
}

void fill(const duet::GridUpdateSettings& c, duet_grid_update_settings* settings) {
  settings->hit_logodds = c.hit_logodds;
  settings->miss_logodds = c.miss_logodds;
  settings->min_logodds = c.min_logodds;
  settings->max_logodds = c.max_logodds;
  settings->clear_along_rays = c.clear_along_rays ? 1 : 0;
  settings->max_ray_length_m = c.max_ray_length_m;
  settings->grow_margin_cells = c.grow_margin_cells;
}

void fill(const duet::ScanMatchSettings& c, duet_scan_match_settings* settings) {
  settings->linear_window_m = c.linear_window_m;
  settings->angular_window_deg = c.angular_window_deg;
  settings->linear_step_m = c.linear_step_m;
  settings->angular_step_deg = c.angular_step_deg;
  settings->sigma_m = c.sigma_m;
  settings->max_distance_m = c.max_distance_m;
  settings->prior_sigma_m = c.prior_sigma_m;
  settings->prior_sigma_deg = c.prior_sigma_deg;
  settings->min_points = c.min_points;
  settings->min_score = c.min_score;
}

}  // namespace duet::capi

using namespace duet::capi;

extern "C" {

DUET_API void duet_back_projection_settings_init(duet_back_projection_settings* settings) {
  if (settings == nullptr) return;
  fill(default_profile().mapping.back_projection, settings);
}

DUET_API void duet_voxel_filter_settings_init(duet_voxel_filter_settings* settings) {
  if (settings == nullptr) return;
  fill(default_profile().mapping.voxel_filter, settings);
}

DUET_API void duet_normal_settings_init(duet_normal_settings* settings) {
  if (settings == nullptr) return;
  fill(default_profile().mapping.normals, settings);
}

DUET_API void duet_clustering_settings_init(duet_clustering_settings* settings) {
  if (settings == nullptr) return;
  *settings = to_c(duet::ClusteringSettings{});
}

DUET_API void duet_segmentation_settings_init(duet_segmentation_settings* settings) {
  if (settings == nullptr) return;
  fill(default_profile().mapping.segmentation, settings);
}

DUET_API void duet_grid_update_settings_init(duet_grid_update_settings* settings) {
  if (settings == nullptr) return;
  fill(default_profile().mapping.grid_update, settings);
}

DUET_API void duet_scan_match_settings_init(duet_scan_match_settings* settings) {
  if (settings == nullptr) return;
  fill(default_profile().runtime.pose_correction.match, settings);
}

DUET_API void duet_sensor_frame_init(duet_sensor_frame* frame) {
  if (frame == nullptr) return;
  const duet::SensorFrame c;
  frame->depth = nullptr;
  frame->width = 0;  // to be set: a forgotten size is an error, never an over-read (issue 20)
  frame->height = 0;
  frame->depth_row_stride = 0;
  frame->depth_format = DUET_DEPTH_U16;
  frame->depth_units_per_m = c.depth.depth_units_per_m;
  frame->color = nullptr;
  frame->color_row_stride = 0;
  frame->color_channels = c.color.channels;
  frame->color_bgr = c.color.bgr ? 1 : 0;
  frame->fx = c.intrinsics.fx;
  frame->fy = c.intrinsics.fy;
  frame->cx = c.intrinsics.cx;
  frame->cy = c.intrinsics.cy;
  for (int i = 0; i < 16; ++i) frame->T_robot_camera[i] = (i % 5 == 0) ? 1.0f : 0.0f;
}

}  // extern "C"
