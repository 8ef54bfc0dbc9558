#pragma once
// Synthetic RGB-D frames for the back-projection tests: uint16 depth and colour images with
// padded rows and holes, the SensorFrame over them, and back_project() as one call.
#include <duet/kernels/back_projection.hpp>

#include <cstdint>
#include <cstring>
#include <random>
#include <span>
#include <vector>

namespace duet::test::back_projection {

struct Image {
  std::vector<std::uint8_t> bytes;
  std::size_t stride = 0;
};

// uint16 depth with padding bytes after each row (filled with valid-looking garbage).
inline Image make_u16_depth(int w, int h, std::size_t pad, std::uint32_t seed, double zero_fraction = 0.1) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> d(200, 6500);
  std::uniform_real_distribution<double> z01(0.0, 1.0);
  Image img;
  img.stride = 2 * static_cast<std::size_t>(w) + pad;
  img.bytes.assign(img.stride * static_cast<std::size_t>(h), 0x11);  // padding: 0x1111 = 4369 mm, valid
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const std::uint16_t raw = z01(rng) < zero_fraction ? 0 : static_cast<std::uint16_t>(d(rng));
      std::memcpy(&img.bytes[static_cast<std::size_t>(v) * img.stride + 2 * static_cast<std::size_t>(u)], &raw, 2);
    }
  return img;
}

inline Image make_color(int w, int h, int channels, std::size_t pad, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> c(0, 255);
  Image img;
  img.stride = static_cast<std::size_t>(channels) * w + pad;
  img.bytes.assign(img.stride * static_cast<std::size_t>(h), 0xEE);
  for (int v = 0; v < h; ++v)
    for (int k = 0; k < channels * w; ++k) img.bytes[static_cast<std::size_t>(v) * img.stride + k] = static_cast<std::uint8_t>(c(rng));
  return img;
}

inline SensorFrame make_frame(const Image& depth, int w, int h, const Image* color, int channels, bool bgr,
                       const Eigen::Isometry3f& T, bool pass_stride = true) {
  SensorFrame f;
  f.depth.data = depth.bytes.data();
  f.depth.width = w;
  f.depth.height = h;
  f.depth.row_stride_bytes = pass_stride ? depth.stride : 0;
  f.depth.format = DepthFormat::kU16;
  f.depth.depth_units_per_m = 1000.0f;
  if (color) {
    f.color.data = color->bytes.data();
    f.color.width = w;
    f.color.height = h;
    f.color.row_stride_bytes = pass_stride ? color->stride : 0;
    f.color.channels = channels;
    f.color.bgr = bgr;
  }
  f.intrinsics.width = w;
  f.intrinsics.height = h;
  f.intrinsics.fx = 530.5f;
  f.intrinsics.fy = 528.25f;
  f.intrinsics.cx = static_cast<float>(w) / 2.0f - 0.3f;
  f.intrinsics.cy = static_cast<float>(h) / 2.0f + 0.7f;
  f.T_robot_camera = T;
  return f;
}

inline PointCloud run(const std::vector<SensorFrame>& frames, const BackProjectionSettings& s,
               std::vector<std::size_t>* offsets = nullptr) {
  PointCloud out;
  back_project(std::span<const SensorFrame>(frames), s, out, offsets);
  return out;
}

}  // namespace duet::test::back_projection
