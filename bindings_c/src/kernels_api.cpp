// The kernel entry points on buffers and clouds: back-projection, voxel filter, normals,
// clustering, segmentation (duet.h). Every kernel runs inside the device's task arena.
#include "capi_internal.hpp"

#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace duet::capi {
namespace {

std::string frame_field(std::size_t i, const char* field) {
  return "frames[" + std::to_string(i) + "]." + field;
}

void check_finite(float v, std::size_t i, const char* field) {
  if (!std::isfinite(v)) invalid_argument(frame_field(i, field) + " is not finite");
}

/// Validates a C sensor frame and converts it to the kernel's view (no pixel is copied).
SensorFrame convert_frame(const duet_sensor_frame& f, std::size_t i) {
  SensorFrame out;
  if (f.depth == nullptr) invalid_argument(frame_field(i, "depth") + " is NULL");
  if (f.width <= 0 || f.height <= 0) {
    invalid_argument(frame_field(i, "width x height") + " is " + std::to_string(f.width) + " x " +
                     std::to_string(f.height) + " (must be > 0)");
  }
  const int format = enum_value(f.depth_format);
  if (format != DUET_DEPTH_U16 && format != DUET_DEPTH_F32) {
    invalid_argument(frame_field(i, "depth_format") + " is " + std::to_string(format) +
                     " (allowed: DUET_DEPTH_U16, DUET_DEPTH_F32)");
  }
  const std::size_t bpp = format == DUET_DEPTH_U16 ? 2 : 4;
  const std::size_t w = static_cast<std::size_t>(f.width);
  if (f.depth_row_stride != 0 && f.depth_row_stride < w * bpp) {
    invalid_argument(frame_field(i, "depth_row_stride") + " " + std::to_string(f.depth_row_stride) +
                     " is smaller than a row (" + std::to_string(w * bpp) + " bytes)");
  }
  if (f.depth_row_stride % bpp != 0 || reinterpret_cast<std::uintptr_t>(f.depth) % bpp != 0) {
    invalid_argument(frame_field(i, "depth") + " and its row stride must be " +
                     std::to_string(bpp) + "-byte aligned");
  }
  if (format == DUET_DEPTH_U16 && !(f.depth_units_per_m > 0.0f && std::isfinite(f.depth_units_per_m))) {
    invalid_argument(frame_field(i, "depth_units_per_m") + " must be finite and > 0");
  }
  out.depth.data = f.depth;
  out.depth.width = f.width;
  out.depth.height = f.height;
  out.depth.row_stride_bytes = f.depth_row_stride;
  out.depth.format = format == DUET_DEPTH_U16 ? DepthFormat::kU16 : DepthFormat::kF32;
  out.depth.depth_units_per_m = f.depth_units_per_m;

  if (f.color != nullptr) {
    if (f.color_channels != 3 && f.color_channels != 4) {
      invalid_argument(frame_field(i, "color_channels") + " is " +
                       std::to_string(f.color_channels) + " (allowed: 3, 4)");
    }
    if (f.color_bgr != 0 && f.color_bgr != 1) {
      invalid_argument(frame_field(i, "color_bgr") + " is " + std::to_string(f.color_bgr) +
                       " (allowed: 0, 1)");
    }
    const std::size_t row = w * static_cast<std::size_t>(f.color_channels);
    if (f.color_row_stride != 0 && f.color_row_stride < row) {
      invalid_argument(frame_field(i, "color_row_stride") + " " +
                       std::to_string(f.color_row_stride) + " is smaller than a row (" +
                       std::to_string(row) + " bytes)");
    }
    out.color.data = f.color;
    out.color.width = f.width;
    out.color.height = f.height;
    out.color.row_stride_bytes = f.color_row_stride;
    out.color.channels = f.color_channels;
    out.color.bgr = f.color_bgr != 0;
  }

  check_finite(f.fx, i, "fx");
  check_finite(f.fy, i, "fy");
  check_finite(f.cx, i, "cx");
  check_finite(f.cy, i, "cy");
  if (!(f.fx > 0.0f) || !(f.fy > 0.0f)) invalid_argument(frame_field(i, "fx/fy") + " must be > 0");
  out.intrinsics.width = f.width;
  out.intrinsics.height = f.height;
  out.intrinsics.fx = f.fx;
  out.intrinsics.fy = f.fy;
  out.intrinsics.cx = f.cx;
  out.intrinsics.cy = f.cy;

  // T_robot_camera: column-major, must be rigid.
  const Eigen::Map<const Eigen::Matrix4f> m(f.T_robot_camera);
  if (!m.allFinite()) invalid_argument(frame_field(i, "T_robot_camera") + " is not finite");
  const Eigen::RowVector4f last = m.row(3);
  if ((last - Eigen::RowVector4f(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-6f) {
    invalid_argument(frame_field(i, "T_robot_camera") +
                     " last row is not (0, 0, 0, 1) (column-major: m[3], m[7], m[11], m[15])");
  }
  const Eigen::Matrix3f r = m.topLeftCorner<3, 3>();
  const float ortho = (r.transpose() * r - Eigen::Matrix3f::Identity()).cwiseAbs().maxCoeff();
  if (ortho > 1e-3f || r.determinant() < 0.0f) {
    invalid_argument(frame_field(i, "T_robot_camera") +
                     " rotation is not orthonormal with determinant +1 (tolerance 1e-3)");
  }
  out.T_robot_camera = Eigen::Isometry3f::Identity();
  out.T_robot_camera.linear() = r;
  out.T_robot_camera.translation() = m.topRightCorner<3, 1>();
  return out;
}

/// Resolves a device, then runs `body(device)` guarded.
template <class F>
void with_device(duet_device handle, const char* fn, F&& body) noexcept {
  auto d = resolve<Device>(handle, fn, "device");
  if (!d) return;
  guarded(d.get(), fn, [&] { body(*d); });
}

template <class F>
void with_cloud(duet_cloud handle, const char* fn, const char* arg, F&& body) noexcept {
  auto c = resolve<Cloud>(handle, fn, arg);
  if (!c) return;
  guarded(c->device.get(), fn, [&] { body(*c); });
}

PointsView points_view(const float* xyz, std::size_t stride, std::size_t count, const char* name) {
  const std::size_t s = check_buffer(xyz, stride, count, 3 * sizeof(float), 4, name);
  return count == 0 ? PointsView() : PointsView(xyz, count, s);
}

}  // namespace
}  // namespace duet::capi

using namespace duet::capi;

extern "C" {

DUET_API void duet_camera_mount_matrix(float x, float y, float z, float yaw, float pitch,
                                       float roll, float out[16]) {
  if (out == nullptr) return;
  // Robot <- body: ZYX Euler (Eq. (6)); body <- optical: columns are the optical axes in body.
  const Eigen::Matrix3f r_robot_body =
      (Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()) *
       Eigen::AngleAxisf(pitch, Eigen::Vector3f::UnitY()) *
       Eigen::AngleAxisf(roll, Eigen::Vector3f::UnitX()))
          .toRotationMatrix();
  Eigen::Matrix3f r_body_optical;
  r_body_optical.col(0) = -Eigen::Vector3f::UnitY();  // optical x = right
  r_body_optical.col(1) = -Eigen::Vector3f::UnitZ();  // optical y = down
  r_body_optical.col(2) = Eigen::Vector3f::UnitX();   // optical z = forward
  Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
  m.topLeftCorner<3, 3>() = r_robot_body * r_body_optical;
  m.topRightCorner<3, 1>() = Eigen::Vector3f(x, y, z);
  Eigen::Map<Eigen::Matrix4f> dst(out);
  dst = m;
}

DUET_API void duet_back_project(duet_cloud out, const duet_sensor_frame* frames,
                                size_t frame_count,
                                const duet_back_projection_settings* settings,
                                size_t* sensor_offsets) {
  with_cloud(out, "duet_back_project", "out", [&](Cloud& c) {
    if (frames == nullptr && frame_count > 0) {
      invalid_argument("frames is NULL but frame_count is " + std::to_string(frame_count));
    }
    const auto s = to_cpp(settings);
    std::vector<duet::SensorFrame> views;
    views.reserve(frame_count);
    for (std::size_t i = 0; i < frame_count; ++i) views.push_back(convert_frame(frames[i], i));
    std::vector<std::size_t> offsets;
    std::unique_lock lock(c.mutex);
    in_arena(*c.device, [&] {
      duet::back_project(views, s, c.spare, sensor_offsets != nullptr ? &offsets : nullptr);
    });
    c.spare.normals.clear();
    c.spare.curvature.clear();
    std::swap(c.cloud, c.spare);
    if (sensor_offsets != nullptr) {
      for (std::size_t i = 0; i <= frame_count; ++i) {
        sensor_offsets[i] = i < offsets.size() ? offsets[i] : c.cloud.size();
      }
    }
  });
}

DUET_API void duet_voxel_filter(duet_cloud out, const float* xyz, size_t xyz_stride,
                                const uint8_t* rgb, size_t rgb_stride, size_t count,
                                const duet_voxel_filter_settings* settings) {
  with_cloud(out, "duet_voxel_filter", "out", [&](Cloud& c) {
    const duet::PointsView points = points_view(xyz, xyz_stride, count, "xyz");
    duet::ColorsView colors;
    if (rgb != nullptr && count > 0) {
      colors = duet::ColorsView(rgb, count, check_buffer(rgb, rgb_stride, count, 3, 1, "rgb"));
    }
    const auto s = to_cpp(settings);
    std::unique_lock lock(c.mutex);
    in_arena(*c.device, [&] { duet::voxel_filter(points, colors, s, c.voxel_workspace, c.spare); });
    c.spare.normals.clear();
    c.spare.curvature.clear();
    std::swap(c.cloud, c.spare);
  });
}

DUET_API void duet_cloud_estimate_normals(duet_cloud cloud, const duet_normal_settings* settings) {
  with_cloud(cloud, "duet_cloud_estimate_normals", "cloud", [&](Cloud& c) {
    const auto s = to_cpp(settings);
    std::unique_lock lock(c.mutex);
    const duet::PointCloud& pc = c.cloud;
    // Computed into the spare cloud's vectors, swapped in on success.
    std::vector<Eigen::Vector3f>& normals = c.spare.normals;
    std::vector<float>& curvature = c.spare.curvature;
    normals.resize(pc.size());
    curvature.resize(pc.size());
    in_arena(*c.device, [&] {
      const duet::KdTree tree(pc.points_view());
      duet::estimate_normals(pc.points_view(), tree, s, normals, curvature);
    });
    std::swap(c.cloud.normals, normals);
    std::swap(c.cloud.curvature, curvature);
  });
}

DUET_API void duet_estimate_normals(duet_device device, const float* xyz, size_t xyz_stride,
                                    size_t count, const duet_normal_settings* settings,
                                    float* normals, size_t normals_stride, float* curvature,
                                    size_t curvature_stride) {
  with_device(device, "duet_estimate_normals", [&](Device& d) {
    const duet::PointsView points = points_view(xyz, xyz_stride, count, "xyz");
    const std::size_t ns = check_buffer(normals, normals_stride, count, 12, 4, "normals");
    const std::size_t cs =
        curvature != nullptr ? check_buffer(curvature, curvature_stride, count, 4, 4, "curvature") : 0;
    const auto s = to_cpp(settings);
    std::vector<Eigen::Vector3f> n(count);
    std::vector<float> cv(curvature != nullptr ? count : 0);
    in_arena(d, [&] {
      const duet::KdTree tree(points);
      duet::estimate_normals(points, tree, s, n, cv);
    });
    scatter(n.data(), count, normals, ns);
    if (curvature != nullptr) scatter(cv.data(), count, curvature, cs);
  });
}

DUET_API void duet_euclidean_clusters(duet_device device, const float* xyz, size_t xyz_stride,
                                      size_t count, const duet_clustering_settings* settings,
                                      uint32_t* labels, size_t labels_stride,
                                      size_t* cluster_count) {
  if (cluster_count != nullptr) *cluster_count = 0;
  with_device(device, "duet_euclidean_clusters", [&](Device& d) {
    const duet::PointsView points = points_view(xyz, xyz_stride, count, "xyz");
    const std::size_t ls = check_buffer(labels, labels_stride, count, 4, 4, "labels");
    if (count >= std::numeric_limits<std::uint32_t>::max()) {
      api_fail(DUET_ERROR_OUT_OF_RANGE, "more than 2^32-2 points (" + std::to_string(count) + ")");
    }
    const auto s = to_cpp(settings);
    std::vector<std::vector<std::uint32_t>> clusters;
    in_arena(d, [&] { clusters = duet::euclidean_clusters(points, {}, s); });
    std::vector<std::uint32_t> lab(count, DUET_UNCLUSTERED);
    for (std::size_t ci = 0; ci < clusters.size(); ++ci) {
      for (const std::uint32_t idx : clusters[ci]) {
        if (idx >= count) api_fail(DUET_ERROR_UNKNOWN, "cluster index out of range (internal error)");
        lab[idx] = static_cast<std::uint32_t>(ci);
      }
    }
    scatter(lab.data(), count, labels, ls);
    if (cluster_count != nullptr) *cluster_count = clusters.size();
  });
}

DUET_API void duet_segment(duet_device device, const float* xyz, size_t xyz_stride,
                           const float* normals, size_t normals_stride, size_t count,
                           const duet_segmentation_settings* settings, uint8_t* labels,
                           size_t labels_stride) {
  with_device(device, "duet_segment", [&](Device& d) {
    const duet::PointsView points = points_view(xyz, xyz_stride, count, "xyz");
    const std::size_t ns = check_buffer(normals, normals_stride, count, 12, 4, "normals");
    const std::size_t ls = check_buffer(labels, labels_stride, count, 1, 1, "labels");
    const auto s = to_cpp(settings);
    // The kernel takes packed normals: read in place when packed, else one gathered copy.
    std::vector<Eigen::Vector3f> gathered;
    std::span<const Eigen::Vector3f> n;
    if (count > 0 && ns == sizeof(Eigen::Vector3f)) {
      n = std::span<const Eigen::Vector3f>(reinterpret_cast<const Eigen::Vector3f*>(normals), count);
    } else if (count > 0) {
      gathered.resize(count);
      gather3(normals, ns, count, gathered.data());
      n = gathered;
    }
    std::vector<duet::PointLabel> out(count);
    in_arena(d, [&] { duet::segment(points, n, s, out); });
    auto* p = static_cast<std::byte*>(static_cast<void*>(labels));
    for (std::size_t i = 0; i < count; ++i) {
      p[i * ls] = static_cast<std::byte>(static_cast<std::uint8_t>(out[i]));
    }
  });
}

}  // extern "C"
