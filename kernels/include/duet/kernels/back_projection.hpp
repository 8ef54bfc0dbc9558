#pragma once
/// @file back_projection.hpp
/// Depth images of any number of RGB-D sensors -> one coloured cloud in the robot frame
/// (paper §2.1: "3D feature points in the robot frame ... as the pose between the dual
/// RGB-D cameras is known"; sensor poses from Eq. (6)).
///
/// Pinhole model, camera optical frame (z forward, x right, y down):
///   p_cam = d * ((u - cx) / fx, (v - cy) / fy, 1),  p_robot = T_robot_camera * p_cam.
/// Pixels whose depth is 0, NaN, inf or outside [min_depth_m, max_depth_m] are dropped.
/// Output order: sensor by sensor, row-major within a sensor - identical for any thread count.
///
/// Thread safety: reentrant; parallel inside (TBB) in the caller's task arena.
#include <duet/kernels/types.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace duet {

struct PinholeIntrinsics {
  int width = 640;     ///< image width [px]
  int height = 480;    ///< image height [px]
  float fx = 525.0f;   ///< focal length x [px]
  float fy = 525.0f;   ///< focal length y [px]
  float cx = 319.5f;   ///< principal point x [px]
  float cy = 239.5f;   ///< principal point y [px]
};

enum class DepthFormat : std::uint8_t {
  kU16 = 0,  ///< uint16 raw units; metres = raw / depth_units_per_m (Kinect/TUM PNG: 1000 or 5000)
  kF32 = 1,  ///< float metres
};

/// An organized depth image in caller memory.
struct DepthImageView {
  const void* data = nullptr;
  int width = 0;
  int height = 0;
  std::size_t row_stride_bytes = 0;  ///< 0 = tightly packed
  DepthFormat format = DepthFormat::kU16;
  float depth_units_per_m = 1000.0f;  ///< only for kU16
};

/// An 8-bit colour image in caller memory, registered to the depth image (same size).
struct ColorImageView {
  const std::uint8_t* data = nullptr;  ///< nullptr = no colour (points get white)
  int width = 0;
  int height = 0;
  std::size_t row_stride_bytes = 0;  ///< 0 = tightly packed
  int channels = 3;                  ///< 3 (RGB/BGR) or 4 (RGBA/BGRA)
  bool bgr = false;                  ///< channel order is B, G, R (OpenCV)
};

/// One sensor's frame and where the sensor sits on the robot.
struct SensorFrame {
  DepthImageView depth;
  ColorImageView color;
  PinholeIntrinsics intrinsics;
  Eigen::Isometry3f T_robot_camera = Eigen::Isometry3f::Identity();  ///< optical frame -> robot
};

struct BackProjectionSettings {
  float min_depth_m = 0.5f;  ///< nearer returns are dropped [m] (Kinect: 0.5)
  float max_depth_m = 5.0f;  ///< farther returns are dropped [m] (Kinect: 5.0)
  int pixel_step = 1;        ///< use every n-th pixel in u and v (1 = all)
};

/// Back-projects every frame into `out` (replaced; points and colors filled, normals and
/// curvature cleared). If `sensor_offsets` is given it receives frames.size()+1 offsets:
/// the points of frame i are [offsets[i], offsets[i+1]).
/// Throws duet::Error(kInvalidArgument) on null data, bad sizes, non-positive focal length,
/// a colour image of another size, or invalid settings.
void back_project(std::span<const SensorFrame> frames, const BackProjectionSettings& settings,
                  PointCloud& out, std::vector<std::size_t>* sensor_offsets = nullptr);

/// A set of frames back-projected once, before it is known where the points go: every valid
/// sampled pixel's point in its frame's optical frame, in back_project()'s order, with the
/// pixel it came from. A pipeline that needs the points in several frames (the scan matcher
/// in the robot frame, the mapper in the map frame once the pose is corrected) reads the
/// depth images once and transforms these (transform_points()); back_project() is the same
/// two steps, bit for bit.
struct CameraPoints {
  PointCloud cloud;                   ///< points (optical frame of their sensor) and colours
  std::vector<std::uint32_t> pixel;   ///< v * width + u of each point
  std::vector<std::size_t> offsets;   ///< frames.size() + 1: the points of frame i are [offsets[i], offsets[i+1])
  int pixel_step = 1;                 ///< the settings' pixel_step
};

/// Back-projects every frame into `out` in the optical frame (T_robot_camera is not applied).
/// Same checks and errors as back_project().
void back_project_camera(std::span<const SensorFrame> frames, const BackProjectionSettings& settings, CameraPoints& out);

/// out[i] = T * in[i] for n points, as back_project() applies T_robot_camera (R p + t).
/// `in` and `out` may be the same array.
void transform_points(const Eigen::Vector3f* in, std::size_t n, const Eigen::Isometry3f& T, Eigen::Vector3f* out);

/// Validates settings; throws duet::Error(kInvalidArgument) naming the bad field.
void validate(const BackProjectionSettings& settings);

}  // namespace duet
