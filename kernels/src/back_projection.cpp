#include <duet/kernels/back_projection.hpp>
#include <duet/kernels/error.hpp>

#include "parallel.hpp"

#include <cmath>
#include <limits>
#include <string>

namespace duet {

static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "a point is three packed floats");

namespace {

/// A rigid transform as twelve scalars, applied to packed floats: p' = R p + t summed in Eigen's
/// order ((r0 x + r1 y) + r2 z, then + t), so the result is Eigen's R * p + t to the bit - without
/// Eigen's small expressions per point, which the sanitized builds do not inline. Keep a copy in
/// each loop's locals: behind a reference, every float store through the output (which may alias
/// it) makes the compiler reload it.
struct ScalarPose {
  float r00, r01, r02, tx, r10, r11, r12, ty, r20, r21, r22, tz;
  explicit ScalarPose(const Eigen::Isometry3f& T)
      : r00(T.linear()(0, 0)), r01(T.linear()(0, 1)), r02(T.linear()(0, 2)), tx(T.translation().x()),
        r10(T.linear()(1, 0)), r11(T.linear()(1, 1)), r12(T.linear()(1, 2)), ty(T.translation().y()),
        r20(T.linear()(2, 0)), r21(T.linear()(2, 1)), r22(T.linear()(2, 2)), tz(T.translation().z()) {}
  void apply(float x, float y, float z, float* out) const noexcept {
    out[0] = ((r00 * x + r01 * y) + r02 * z) + tx;
    out[1] = ((r10 * x + r11 * y) + r12 * z) + ty;
    out[2] = ((r20 * x + r21 * y) + r22 * z) + tz;
  }
};

}  // namespace

void validate(const BackProjectionSettings& s) {
  if (!(s.min_depth_m >= 0.0f) || !std::isfinite(s.min_depth_m))
    fail(ErrorCode::kInvalidArgument, "BackProjectionSettings.min_depth_m must be >= 0 m, got " + std::to_string(s.min_depth_m));
  if (!(s.max_depth_m > s.min_depth_m) || !std::isfinite(s.max_depth_m))
    fail(ErrorCode::kInvalidArgument, "BackProjectionSettings.max_depth_m must be finite and > min_depth_m (" +
                                          std::to_string(s.min_depth_m) + " m), got " + std::to_string(s.max_depth_m));
  if (s.pixel_step < 1 || s.pixel_step > 64)
    fail(ErrorCode::kInvalidArgument, "BackProjectionSettings.pixel_step must be in [1, 64], got " + std::to_string(s.pixel_step));
}

namespace {

void validate_frame(const SensorFrame& f, std::size_t i) {
  const std::string where = "back_project: frame " + std::to_string(i) + ": ";
  const auto& d = f.depth;
  if (d.width <= 0 || d.height <= 0 || d.width > 65536 || d.height > 65536)
    fail(ErrorCode::kInvalidArgument, where + "depth size " + std::to_string(d.width) + "x" + std::to_string(d.height) +
                                          " is not in [1, 65536]^2");
  if (d.data == nullptr) fail(ErrorCode::kInvalidArgument, where + "depth data is null");
  const std::size_t px = d.format == DepthFormat::kU16 ? 2 : 4;
  if (d.format != DepthFormat::kU16 && d.format != DepthFormat::kF32)
    fail(ErrorCode::kInvalidArgument, where + "unknown depth format");
  if (d.row_stride_bytes != 0 && d.row_stride_bytes < px * static_cast<std::size_t>(d.width))
    fail(ErrorCode::kInvalidArgument, where + "depth row stride " + std::to_string(d.row_stride_bytes) +
                                          " is smaller than a row (" + std::to_string(px * d.width) + " bytes)");
  if (d.format == DepthFormat::kU16 && !(d.depth_units_per_m > 0.0f && std::isfinite(d.depth_units_per_m)))
    fail(ErrorCode::kInvalidArgument, where + "depth_units_per_m must be > 0, got " + std::to_string(d.depth_units_per_m));
  const auto& K = f.intrinsics;
  if (!(K.fx > 0.0f) || !(K.fy > 0.0f) || !std::isfinite(K.fx) || !std::isfinite(K.fy) || !std::isfinite(K.cx) ||
      !std::isfinite(K.cy))
    fail(ErrorCode::kInvalidArgument, where + "intrinsics fx, fy must be finite and > 0, cx, cy finite");
  if (!f.T_robot_camera.matrix().allFinite()) fail(ErrorCode::kInvalidArgument, where + "T_robot_camera is not finite");
  const auto& c = f.color;
  if (c.data != nullptr) {
    if (c.width != d.width || c.height != d.height)
      fail(ErrorCode::kInvalidArgument, where + "colour image is " + std::to_string(c.width) + "x" + std::to_string(c.height) +
                                            ", depth is " + std::to_string(d.width) + "x" + std::to_string(d.height));
    if (c.channels != 3 && c.channels != 4)
      fail(ErrorCode::kInvalidArgument, where + "colour channels must be 3 or 4, got " + std::to_string(c.channels));
    if (c.row_stride_bytes != 0 && c.row_stride_bytes < static_cast<std::size_t>(c.channels) * c.width)
      fail(ErrorCode::kInvalidArgument, where + "colour row stride is smaller than a row");
  }
}

struct FrameGeometry {
  const std::byte* depth;
  std::size_t depth_stride;
  const std::uint8_t* color;
  std::size_t color_stride;
  int rows, cols;  // sampled rows / cols
  int step;
};

/// back_project() and back_project_camera(): `camera_frame` leaves the points in the optical
/// frame; `pixels` (optional) receives each point's v * width + u.
void back_project_impl(std::span<const SensorFrame> frames, const BackProjectionSettings& settings, PointCloud& out,
                       std::vector<std::size_t>* sensor_offsets, std::vector<std::uint32_t>* pixels, bool camera_frame) {
  validate(settings);
  for (std::size_t i = 0; i < frames.size(); ++i) validate_frame(frames[i], i);
  const int step = settings.pixel_step;

  // Pass 1: valid pixels per sampled row of every frame (fixed rows -> deterministic).
  std::vector<FrameGeometry> geo(frames.size());
  std::vector<std::size_t> row_base(frames.size() + 1, 0);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const auto& f = frames[i];
    auto& g = geo[i];
    const std::size_t px = f.depth.format == DepthFormat::kU16 ? 2 : 4;
    g.depth = static_cast<const std::byte*>(f.depth.data);
    g.depth_stride = f.depth.row_stride_bytes ? f.depth.row_stride_bytes : px * f.depth.width;
    g.color = f.color.data;
    g.color_stride = f.color.row_stride_bytes ? f.color.row_stride_bytes
                                              : static_cast<std::size_t>(f.color.channels) * f.color.width;
    g.step = step;
    g.rows = (f.depth.height + step - 1) / step;
    g.cols = (f.depth.width + step - 1) / step;
    row_base[i + 1] = row_base[i] + static_cast<std::size_t>(g.rows);
  }
  const std::size_t total_rows = row_base.back();
  std::vector<std::size_t> row_count(total_rows + 1, 0);

  auto frame_of_row = [&](std::size_t r) {
    std::size_t i = 0;
    while (r >= row_base[i + 1]) ++i;
    return i;
  };
  const float dmin = settings.min_depth_m, dmax = settings.max_depth_m;

  // Depth in metres for pixel u of a depth row, NaN if invalid.
  auto depth_at = [&](const SensorFrame& f, const std::byte* row, int u) -> float {
    float z;
    if (f.depth.format == DepthFormat::kU16) {
      std::uint16_t raw;
      std::memcpy(&raw, row + 2 * static_cast<std::size_t>(u), 2);
      if (raw == 0) return std::numeric_limits<float>::quiet_NaN();
      z = static_cast<float>(raw) / f.depth.depth_units_per_m;
    } else {
      std::memcpy(&z, row + 4 * static_cast<std::size_t>(u), 4);
    }
    return (z >= dmin && z <= dmax) ? z : std::numeric_limits<float>::quiet_NaN();  // NaN fails both
  };

  detail::for_each_index(total_rows, 8, [&](std::size_t r) {
    const std::size_t i = frame_of_row(r);
    const auto& f = frames[i];
    const auto& g = geo[i];
    const int v = static_cast<int>(r - row_base[i]) * g.step;
    const std::byte* row = g.depth + static_cast<std::size_t>(v) * g.depth_stride;
    std::size_t c = 0;
    for (int u = 0; u < f.depth.width; u += g.step) c += std::isnan(depth_at(f, row, u)) ? 0 : 1;
    row_count[r + 1] = c;
  });
  for (std::size_t r = 0; r < total_rows; ++r) row_count[r + 1] += row_count[r];
  const std::size_t n = row_count.back();

  out.clear();
  out.points.resize(n);
  out.colors.resize(n);
  if (pixels) pixels->resize(n);
  if (sensor_offsets) {
    sensor_offsets->resize(frames.size() + 1);
    for (std::size_t i = 0; i <= frames.size(); ++i) (*sensor_offsets)[i] = row_count[row_base[i]];
  }

  // Pass 2: write points. p_cam = z * ((u - cx)/fx, (v - cy)/fy, 1); p_robot = R p_cam + t.
  detail::for_each_index(total_rows, 8, [&](std::size_t r) {
    const std::size_t i = frame_of_row(r);
    const auto& f = frames[i];
    const auto& g = geo[i];
    const int v = static_cast<int>(r - row_base[i]) * g.step;
    const std::byte* row = g.depth + static_cast<std::size_t>(v) * g.depth_stride;
    const std::uint8_t* crow = g.color ? g.color + static_cast<std::size_t>(v) * g.color_stride : nullptr;
    const int ch = f.color.channels;
    const bool bgr = f.color.bgr;
    const ScalarPose pose(f.T_robot_camera);  // the points written as packed floats
    const float cx = f.intrinsics.cx;
    const float ifx = 1.0f / f.intrinsics.fx, ify = 1.0f / f.intrinsics.fy;
    const float yn = (static_cast<float>(v) - f.intrinsics.cy) * ify;
    float* points = reinterpret_cast<float*>(out.points.data());
    std::size_t o = row_count[r];
    for (int u = 0; u < f.depth.width; u += g.step) {
      const float z = depth_at(f, row, u);
      if (std::isnan(z)) continue;
      const float x = z * (static_cast<float>(u) - cx) * ifx, y = z * yn;
      float* p = points + 3 * o;
      if (camera_frame) {
        p[0] = x, p[1] = y, p[2] = z;
      } else {
        pose.apply(x, y, z, p);
      }
      if (pixels) (*pixels)[o] = static_cast<std::uint32_t>(v) * static_cast<std::uint32_t>(f.depth.width) + static_cast<std::uint32_t>(u);
      if (crow) {
        const std::uint8_t* px = crow + static_cast<std::size_t>(u) * ch;
        out.colors[o] = bgr ? Rgb8{px[2], px[1], px[0]} : Rgb8{px[0], px[1], px[2]};
      } else {
        out.colors[o] = Rgb8{255, 255, 255};
      }
      ++o;
    }
  });
}

}  // namespace

void back_project(std::span<const SensorFrame> frames, const BackProjectionSettings& settings, PointCloud& out,
                  std::vector<std::size_t>* sensor_offsets) {
  back_project_impl(frames, settings, out, sensor_offsets, nullptr, false);
}

void back_project_camera(std::span<const SensorFrame> frames, const BackProjectionSettings& settings, CameraPoints& out) {
  back_project_impl(frames, settings, out.cloud, &out.offsets, &out.pixel, true);
  out.pixel_step = settings.pixel_step;
}

void transform_points(const Eigen::Vector3f* in, std::size_t n, const Eigen::Isometry3f& T, Eigen::Vector3f* out) {
  // Bench TransformPoints: 1.8x slower than a plain Eigen loop on one thread with R and t behind a
  // reference and Eigen's product per point; 2.3x faster this way.
  const ScalarPose shared(T);
  detail::for_blocks(n, 4096, [&shared, in, out](std::size_t, std::size_t begin, std::size_t end) {
    const ScalarPose pose = shared;
    const float* src = reinterpret_cast<const float*>(in + begin);
    float* dst = reinterpret_cast<float*>(out + begin);
    for (std::size_t i = begin; i < end; ++i, src += 3, dst += 3) {
      const float x = src[0], y = src[1], z = src[2];  // read before written: in == out is allowed
      pose.apply(x, y, z, dst);
    }
  });
}

}  // namespace duet
