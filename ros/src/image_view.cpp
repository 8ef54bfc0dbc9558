#include <duet_ros/image_view.hpp>

#include <cmath>
#include <cstdint>
#include <string>

namespace duet_ros {
namespace {

constexpr bool kHostBigEndian = false;  // x86-64 and arm64 Linux; the check below is on the message's flag
static_assert(sizeof(float) == 4);

std::string size_text(std::uint32_t w, std::uint32_t h) { return std::to_string(w) + "x" + std::to_string(h); }

/// Step and data size of one image: "" or the reason.
std::string check_layout(const sensor_msgs::Image& m, std::size_t bytes_per_pixel, const char* what, bool word_pixels) {
  const std::size_t row = static_cast<std::size_t>(m.width) * bytes_per_pixel;
  if (m.step < row)
    return std::string(what) + " image: step " + std::to_string(m.step) + " bytes is shorter than a row of " + std::to_string(m.width) +
           " pixels (" + std::to_string(row) + " bytes)";
  const std::size_t need = static_cast<std::size_t>(m.step) * (m.height - 1) + row;
  if (m.height > 0 && m.data.size() < need)
    return std::string(what) + " image: " + std::to_string(m.data.size()) + " bytes of data, " + size_text(m.width, m.height) +
           " with step " + std::to_string(m.step) + " needs " + std::to_string(need);
  if (word_pixels && (m.is_bigendian != 0) != kHostBigEndian)
    return std::string(what) + " image: big-endian data is not supported";
  if (word_pixels) {  // 16- and 32-bit depth pixels are read as such: rows start aligned
    if (m.step % bytes_per_pixel != 0 || reinterpret_cast<std::uintptr_t>(m.data.data()) % bytes_per_pixel != 0)
      return std::string(what) + " image: step " + std::to_string(m.step) + " is not a multiple of its " + std::to_string(bytes_per_pixel) +
             "-byte pixels";
  }
  return {};
}

}  // namespace

RgbdView rgbd_view(const sensor_msgs::Image& depth, const sensor_msgs::Image* color, const sensor_msgs::CameraInfo* info,
                   const duet_runtime_sensor_info& expect) {
  RgbdView v;
  duet_rgbd_image_init(&v.image);
  duet_rgbd_image& img = v.image;
  img.stamp_s = depth.header.stamp.toSec();
  if (depth.width != static_cast<std::uint32_t>(expect.width) || depth.height != static_cast<std::uint32_t>(expect.height)) {
    v.error = "depth image is " + size_text(depth.width, depth.height) + ", the profile's sensor is " +
              size_text(static_cast<std::uint32_t>(expect.width), static_cast<std::uint32_t>(expect.height));
    return v;
  }
  std::size_t depth_bpp = 0;
  if (depth.encoding == "16UC1" || depth.encoding == "mono16") {
    img.depth_format = DUET_DEPTH_U16;
    img.depth_units_per_m = 1000.0f;  // REP 118: 16-bit depth in millimetres
    depth_bpp = 2;
  } else if (depth.encoding == "32FC1") {
    img.depth_format = DUET_DEPTH_F32;
    depth_bpp = 4;
  } else {
    v.error = "depth image encoding '" + depth.encoding + "' is not 16UC1, mono16 (mm) or 32FC1 (m)";
    return v;
  }
  if (v.error = check_layout(depth, depth_bpp, "depth", true); !v.error.empty()) return v;
  img.depth = depth.data.data();
  img.width = static_cast<int>(depth.width);
  img.height = static_cast<int>(depth.height);
  img.depth_row_stride = depth.step;

  if (color != nullptr) {
    int channels = 0, bgr = 0;
    if (color->encoding == "rgb8") channels = 3;
    else if (color->encoding == "bgr8") channels = 3, bgr = 1;
    else if (color->encoding == "rgba8") channels = 4;
    else if (color->encoding == "bgra8") channels = 4, bgr = 1;
    else {
      v.error = "colour image encoding '" + color->encoding + "' is not rgb8, bgr8, rgba8 or bgra8";
      return v;
    }
    if (color->width != depth.width || color->height != depth.height) {
      v.error = "colour image is " + size_text(color->width, color->height) + ", its depth image " + size_text(depth.width, depth.height) +
                " (colour must be registered to depth)";
      return v;
    }
    if (v.error = check_layout(*color, static_cast<std::size_t>(channels), "colour", false); !v.error.empty()) return v;
    img.color = color->data.data();
    img.color_row_stride = color->step;
    img.color_channels = channels;
    img.color_bgr = bgr;
  }

  if (info != nullptr) {
    const double fx = info->K[0], fy = info->K[4], cx = info->K[2], cy = info->K[5];
    const bool calibrated = std::isfinite(fx) && std::isfinite(fy) && fx > 0.0 && fy > 0.0;
    if (calibrated) {
      if (info->width != depth.width || info->height != depth.height) {
        v.error = "camera_info is for " + size_text(info->width, info->height) + " images, the depth image is " + size_text(depth.width, depth.height);
        return v;
      }
      if (!(std::isfinite(cx) && std::isfinite(cy) && cx >= 0.0 && cx <= depth.width && cy >= 0.0 && cy <= depth.height)) {
        v.error = "camera_info's principal point (" + std::to_string(cx) + ", " + std::to_string(cy) + ") is outside the " +
                  size_text(depth.width, depth.height) + " image";
        return v;
      }
      v.intrinsics = {static_cast<float>(fx), static_cast<float>(fy), static_cast<float>(cx), static_cast<float>(cy)};
      v.has_intrinsics = true;
    }
  }
  return v;
}

}  // namespace duet_ros
