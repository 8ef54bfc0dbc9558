#pragma once
/// @file image_view.hpp
/// ROS image messages as the C API's duet_rgbd_image (duet_runtime.h): a view by pointer and
/// stride into the messages' own buffers, nothing copied (duet_runtime_push_rgbd copies).
///
/// Depth (REP 118): "16UC1" / "mono16" in millimetres or "32FC1" in metres (NaN, inf, <= 0 = no
/// return), the OpenNI / freenect drivers' `depth_registered/image_raw` and `.../image`.
/// Colour: "rgb8", "bgr8", "rgba8", "bgra8" (the drivers' `rgb/image_rect_color` is bgr8 or
/// rgb8), registered to the depth image and of its size. Intrinsics: camera_info's K when it is
/// calibrated (fx, fy > 0) and of the image's size, else the profile's.
///
/// Every check a malformed message can fail is made here, so a bad message is a counted,
/// logged drop with its reason, never a crash: an unknown encoding, a size other than the
/// profile's sensor, a row step shorter than a row or (16/32-bit depth) not a multiple of the
/// pixel size, data shorter than step x height, a big-endian 16/32-bit image, colour and depth
/// of different sizes, camera_info of another size. A view it accepts, duet_runtime_push_rgbd takes.
/// Thread safety: pure functions.
#include <duet.h>

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <array>
#include <string>

namespace duet_ros {

/// The views into the messages (valid while the messages live) or why the frame is dropped.
struct RgbdView {
  duet_rgbd_image image{};            ///< its `intrinsics` stays NULL: see c_image()
  std::array<float, 4> intrinsics{};  ///< fx, fy, cx, cy from camera_info
  bool has_intrinsics = false;        ///< camera_info was usable
  std::string error;                  ///< empty: usable; else the reason, naming the topic's message
  /// The image to push, pointing at this view's intrinsics when camera_info was usable.
  [[nodiscard]] duet_rgbd_image c_image() const {
    duet_rgbd_image i = image;
    i.intrinsics = has_intrinsics ? intrinsics.data() : nullptr;
    return i;
  }
};

/// `depth` (required), `color` (nullptr: no colour) and `info` (nullptr: the profile's
/// intrinsics) of one sensor, checked against `expect` (duet_runtime_get_sensor_info). The
/// stamp is the depth message's.
[[nodiscard]] RgbdView rgbd_view(const sensor_msgs::Image& depth, const sensor_msgs::Image* color,
                                 const sensor_msgs::CameraInfo* info, const duet_runtime_sensor_info& expect);

}  // namespace duet_ros
