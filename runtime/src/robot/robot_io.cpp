/// @file robot_io.cpp
/// Views of runtime frames for the mapper (see robot_io.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/robot/robot_io.hpp>

#include <algorithm>
#include <string>

namespace duet {

Eigen::Isometry3f to_isometry(const Pose2& p) {
  Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
  T.linear() = Eigen::AngleAxisf(p.theta, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3f(p.x, p.y, 0.0f);
  return T;
}

SensorFrame frame_view(const RgbdImage& image, const SensorProfile& sensor, const Eigen::Isometry3f& T_robot_optical) {
  const PinholeIntrinsics& in = sensor.intrinsics;
  const auto pixels = static_cast<std::size_t>(std::max(0, image.width)) * static_cast<std::size_t>(std::max(0, image.height));
  if (image.width != in.width || image.height != in.height)
    fail(ErrorCode::kInvalidArgument, "frame_view: image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                                          " but sensor '" + sensor.name + "' is " + std::to_string(in.width) + "x" +
                                          std::to_string(in.height));
  if (image.depth.size() != pixels || (!image.rgb.empty() && image.rgb.size() != 3 * pixels))
    fail(ErrorCode::kInvalidArgument, "frame_view: image buffers do not match its size (depth " + std::to_string(image.depth.size()) +
                                          ", rgb " + std::to_string(image.rgb.size()) + ", pixels " + std::to_string(pixels) + ")");
  SensorFrame f;
  f.depth.data = image.depth.data();
  f.depth.width = image.width;
  f.depth.height = image.height;
  f.depth.row_stride_bytes = 0;
  f.depth.format = DepthFormat::kU16;
  f.depth.depth_units_per_m = sensor.depth_units_per_m;
  f.color.data = image.rgb.empty() ? nullptr : image.rgb.data();
  f.color.width = image.width;
  f.color.height = image.height;
  f.color.row_stride_bytes = 0;
  f.color.channels = 3;
  f.color.bgr = false;
  f.intrinsics = image.intrinsics.value_or(in);
  f.T_robot_camera = T_robot_optical;
  return f;
}

}  // namespace duet
