// back_project vs a naive per-pixel reference; Eq. (6) extrinsics; formats, strides, colour
// orders; real slambook2 frame; thread-count independence; bad input.
#include "back_projection_fixtures.hpp"
#include "kernel_test_util.hpp"

#include <duet/kernels/back_projection.hpp>
#include <duet/kernels/error.hpp>

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <random>
#include <vector>

namespace duet {
namespace test_back_projection {

using test::kInf;
using test::kNaN;
using namespace test::back_projection;  // synthetic frames (back_projection_fixtures.hpp)

// ---- reference -----------------------------------------------------------------------------------

// Plain serial per-pixel back-projection written straight from the header.
PointCloud reference_back_project(const std::vector<SensorFrame>& frames, const BackProjectionSettings& s,
                                  std::vector<std::size_t>* offsets) {
  PointCloud out;
  if (offsets) offsets->assign(1, 0);
  for (const SensorFrame& f : frames) {
    const std::size_t px = f.depth.format == DepthFormat::kU16 ? 2 : 4;
    const std::size_t dstride = f.depth.row_stride_bytes ? f.depth.row_stride_bytes : px * f.depth.width;
    const std::size_t cstride =
        f.color.row_stride_bytes ? f.color.row_stride_bytes : static_cast<std::size_t>(f.color.channels) * f.color.width;
    for (int v = 0; v < f.depth.height; v += s.pixel_step) {
      for (int u = 0; u < f.depth.width; u += s.pixel_step) {
        const auto* base = static_cast<const std::uint8_t*>(f.depth.data) + static_cast<std::size_t>(v) * dstride;
        float z;
        if (f.depth.format == DepthFormat::kU16) {
          std::uint16_t raw;
          std::memcpy(&raw, base + 2 * static_cast<std::size_t>(u), 2);
          if (raw == 0) continue;
          z = static_cast<float>(raw) / f.depth.depth_units_per_m;
        } else {
          std::memcpy(&z, base + 4 * static_cast<std::size_t>(u), 4);
        }
        if (std::isnan(z) || std::isinf(z) || z == 0.0f || z < s.min_depth_m || z > s.max_depth_m) continue;
        const auto& K = f.intrinsics;
        const Eigen::Vector3f pc(z * (static_cast<float>(u) - K.cx) / K.fx, z * (static_cast<float>(v) - K.cy) / K.fy, z);
        out.points.push_back(f.T_robot_camera * pc);
        if (f.color.data == nullptr) {
          out.colors.push_back(Rgb8{255, 255, 255});
        } else {
          const std::uint8_t* c = f.color.data + static_cast<std::size_t>(v) * cstride +
                                  static_cast<std::size_t>(u) * static_cast<std::size_t>(f.color.channels);
          out.colors.push_back(f.color.bgr ? Rgb8{c[2], c[1], c[0]} : Rgb8{c[0], c[1], c[2]});
        }
      }
    }
    if (offsets) offsets->push_back(out.points.size());
  }
  return out;
}

void expect_clouds_match(const PointCloud& got, const PointCloud& ref) {
  ASSERT_EQ(got.size(), ref.size());
  ASSERT_EQ(got.colors.size(), ref.colors.size());
  EXPECT_TRUE(got.normals.empty());
  EXPECT_TRUE(got.curvature.empty());
  std::size_t bad = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const float tol = 2e-6f * (1.0f + ref.points[i].norm());
    if (!((got.points[i] - ref.points[i]).cwiseAbs().maxCoeff() <= tol) || !(got.colors[i] == ref.colors[i])) {
      if (++bad <= 5)
        ADD_FAILURE() << "point " << i << ": got (" << got.points[i].transpose() << ") rgb " << int(got.colors[i].r) << ","
                      << int(got.colors[i].g) << "," << int(got.colors[i].b) << ", expected (" << ref.points[i].transpose()
                      << ") rgb " << int(ref.colors[i].r) << "," << int(ref.colors[i].g) << "," << int(ref.colors[i].b);
    }
  }
  EXPECT_EQ(bad, 0u);
}

// ---- synthetic images ----------------------------------------------------------------------------

// ---- tests -----------------------------------------------------------------------------------------

TEST(BackProjection, U16MatchesReferenceWithPaddedStrides) {
  const int w = 97, h = 61;
  const Image depth = make_u16_depth(w, h, 6, 1);
  const Image color = make_color(w, h, 3, 5, 2);
  Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
  T.linear() = Eigen::AngleAxisf(0.3f, Eigen::Vector3f(1, 2, 3).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3f(0.1f, -0.2f, 0.3f);
  const std::vector<SensorFrame> frames{make_frame(depth, w, h, &color, 3, false, T)};
  BackProjectionSettings s;
  std::vector<std::size_t> off, ref_off;
  const PointCloud got = run(frames, s, &off);
  const PointCloud ref = reference_back_project(frames, s, &ref_off);
  EXPECT_GT(ref.size(), static_cast<std::size_t>(w * h / 2));
  EXPECT_LT(ref.size(), static_cast<std::size_t>(w * h));  // range and zeros dropped something
  expect_clouds_match(got, ref);
  EXPECT_EQ(off, ref_off);
}

TEST(BackProjection, TightlyPackedStrideZero) {
  const int w = 64, h = 48;
  const Image depth = make_u16_depth(w, h, 0, 3);
  const Image color = make_color(w, h, 4, 0, 4);
  const std::vector<SensorFrame> frames{make_frame(depth, w, h, &color, 4, false, Eigen::Isometry3f::Identity(), false)};
  expect_clouds_match(run(frames, {}), reference_back_project(frames, {}, nullptr));
}

TEST(BackProjection, DepthUnitsPerMetre) {
  const int w = 40, h = 30;
  const Image depth = make_u16_depth(w, h, 0, 5);
  std::vector<SensorFrame> frames{make_frame(depth, w, h, nullptr, 3, false, Eigen::Isometry3f::Identity())};
  frames[0].depth.depth_units_per_m = 5000.0f;  // TUM convention
  BackProjectionSettings s;
  s.min_depth_m = 0.1f;
  const PointCloud got = run(frames, s);
  expect_clouds_match(got, reference_back_project(frames, s, nullptr));
  for (const auto& p : got.points) EXPECT_LE(p.z(), 6500.0f / 5000.0f + 1e-6f);
}

TEST(BackProjection, FloatMetresInvalidValuesAndRangeBoundaries) {
  const int w = 16, h = 2;
  // Row 0: special values; row 1: boundaries of [0.5, 5.0].
  const std::vector<float> d = {0.0f, kNaN, kInf, -kInf, -1.0f, 0.4999f, 5.0001f, 1e30f, -0.0f, 1.0f, 2.0f, 3.0f,
                                4.0f, 4.999f, 0.5001f, 2.5f,
                                0.5f, 5.0f, 0.49999997f, 5.0000005f, 1.5f, 0.0f, kNaN, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f,
                                1.0f, 1.0f, 1.0f, 1.0f};
  SensorFrame f;
  f.depth.data = d.data();
  f.depth.width = w;
  f.depth.height = h;
  f.depth.format = DepthFormat::kF32;
  f.depth.depth_units_per_m = -7.0f;  // ignored for float depth
  f.intrinsics.cx = 7.5f;
  f.intrinsics.cy = 0.5f;
  const std::vector<SensorFrame> frames{f};
  BackProjectionSettings s;  // [0.5, 5.0]
  const PointCloud got = run(frames, s);
  const PointCloud ref = reference_back_project(frames, s, nullptr);
  expect_clouds_match(got, ref);
  // Row 0 keeps 1,2,3,4,4.999,0.5001,2.5 (7); row 1 keeps 0.5, 5.0, 1.5 and nine 1.0 (12).
  EXPECT_EQ(got.size(), 7u + 12u);
  for (const auto& p : got.points) {
    EXPECT_TRUE(is_finite(p));
    EXPECT_GE(p.z(), 0.5f);
    EXPECT_LE(p.z(), 5.0f);
  }
  for (const auto& c : got.colors) EXPECT_EQ(c, (Rgb8{255, 255, 255}));  // no colour image: white
}

TEST(BackProjection, PixelStep) {
  for (const int step : {1, 2, 3, 7, 64}) {
    for (const auto& [w, h] : {std::pair{37, 23}, std::pair{64, 48}, std::pair{5, 130}}) {
      const Image depth = make_u16_depth(w, h, 2, 100 + static_cast<std::uint32_t>(step));
      const Image color = make_color(w, h, 3, 1, 200 + static_cast<std::uint32_t>(step));
      const std::vector<SensorFrame> frames{make_frame(depth, w, h, &color, 3, true, Eigen::Isometry3f::Identity())};
      BackProjectionSettings s;
      s.pixel_step = step;
      SCOPED_TRACE("step " + std::to_string(step) + " size " + std::to_string(w) + "x" + std::to_string(h));
      std::vector<std::size_t> off, ref_off;
      expect_clouds_match(run(frames, s, &off), reference_back_project(frames, s, &ref_off));
      EXPECT_EQ(off, ref_off);
    }
  }
}

TEST(BackProjection, ColourOrders) {
  const int w = 20, h = 10;
  const Image depth = make_u16_depth(w, h, 0, 9, 0.0);
  for (const int ch : {3, 4})
    for (const bool bgr : {false, true}) {
      const Image color = make_color(w, h, ch, 3, 10 + static_cast<std::uint32_t>(ch));
      const std::vector<SensorFrame> frames{make_frame(depth, w, h, &color, ch, bgr, Eigen::Isometry3f::Identity())};
      BackProjectionSettings s;
      s.min_depth_m = 0.0f;
      s.max_depth_m = 100.0f;
      const PointCloud got = run(frames, s);
      ASSERT_EQ(got.size(), static_cast<std::size_t>(w * h));  // all depths valid
      expect_clouds_match(got, reference_back_project(frames, s, nullptr));
      // Spot-check pixel (u=3, v=2) directly.
      const std::uint8_t* px = color.bytes.data() + 2 * color.stride + 3 * static_cast<std::size_t>(ch);
      const Rgb8 want = bgr ? Rgb8{px[2], px[1], px[0]} : Rgb8{px[0], px[1], px[2]};
      EXPECT_EQ(got.colors[2 * w + 3], want) << "channels " << ch << " bgr " << bgr;
    }
}

TEST(BackProjection, TwoSensorsWithPaperExtrinsicsEq6) {
  const int w = 64, h = 48;
  // A constant-depth image: every pixel at 2.0 m.
  std::vector<std::uint16_t> d(static_cast<std::size_t>(w * h), 2000);
  SensorFrame f1;
  f1.depth.data = d.data();
  f1.depth.width = w;
  f1.depth.height = h;
  f1.intrinsics.width = w;
  f1.intrinsics.height = h;
  f1.intrinsics.cx = 32.0f;  // pixel (32, 24) is the principal point
  f1.intrinsics.cy = 24.0f;
  f1.T_robot_camera = test::paper_sensor1();
  SensorFrame f2 = f1;
  f2.T_robot_camera = test::paper_sensor2();
  const std::vector<SensorFrame> frames{f1, f2};
  std::vector<std::size_t> off;
  const PointCloud got = run(frames, {}, &off);
  ASSERT_EQ(off, (std::vector<std::size_t>{0, static_cast<std::size_t>(w * h), static_cast<std::size_t>(2 * w * h)}));
  std::vector<std::size_t> ref_off;
  expect_clouds_match(got, reference_back_project(frames, {}, &ref_off));
  const std::size_t centre = 24 * w + 32;
  // Sensor 1 looks forward (+x) from (-0.118, 0, 0.271).
  EXPECT_TRUE(got.points[centre].isApprox(Eigen::Vector3f(-0.118f + 2.0f, 0.0f, 0.271f), 1e-5f)) << got.points[centre].transpose();
  // Sensor 2 is yawed -90 deg: it looks to the robot's right (-y) from (-0.118, 0, 0.481).
  EXPECT_TRUE(got.points[w * h + centre].isApprox(Eigen::Vector3f(-0.118f, -2.0f, 0.481f), 1e-5f))
      << got.points[w * h + centre].transpose();
  // Image right (u > cx) is the robot's right (-y) for sensor 1, image down (v > cy) is lower z.
  EXPECT_LT(got.points[centre + 10].y(), -0.03f);  // 10 px at 2 m, f = 525: 0.038 m
  EXPECT_LT(got.points[centre + 10 * w].z(), 0.271f - 0.03f);
  // For sensor 2, image right is the robot's back (-x).
  EXPECT_LT(got.points[w * h + centre + 10].x(), -0.118f - 0.03f);
}

TEST(BackProjection, SensorOffsetsWithEmptyAndFullFrames) {
  const int w = 31, h = 17;
  const Image a = make_u16_depth(w, h, 4, 21);
  const std::vector<std::uint16_t> zeros(static_cast<std::size_t>(w * h), 0);
  const Image b = make_u16_depth(w, h, 0, 22, 0.5);
  std::vector<SensorFrame> frames{make_frame(a, w, h, nullptr, 3, false, test::paper_sensor1()),
                                  make_frame(a, w, h, nullptr, 3, false, test::paper_sensor2()),
                                  make_frame(b, w, h, nullptr, 3, false, test::paper_sensor2())};
  SensorFrame empty = frames[0];
  empty.depth.data = zeros.data();
  empty.depth.row_stride_bytes = 0;
  frames.insert(frames.begin() + 1, empty);
  std::vector<std::size_t> off, ref_off;
  const PointCloud got = run(frames, {}, &off);
  expect_clouds_match(got, reference_back_project(frames, {}, &ref_off));
  EXPECT_EQ(off, ref_off);
  ASSERT_EQ(off.size(), 5u);
  EXPECT_EQ(off[1], off[2]);  // the all-zero frame contributes nothing
}

TEST(BackProjection, EmptyInputsAndReplacedOutput) {
  PointCloud out;
  out.points.assign(3, Eigen::Vector3f::Ones());
  out.colors.assign(3, Rgb8{1, 2, 3});
  out.normals.assign(3, Eigen::Vector3f::UnitZ());
  out.curvature.assign(3, 0.5f);
  std::vector<std::size_t> off{7, 7, 7};
  back_project({}, {}, out, &off);
  EXPECT_TRUE(out.empty());
  EXPECT_TRUE(out.colors.empty());
  EXPECT_TRUE(out.normals.empty());
  EXPECT_TRUE(out.curvature.empty());
  EXPECT_EQ(off, (std::vector<std::size_t>{0}));

  // One pixel; all-invalid image.
  const std::uint16_t one = 1234;
  SensorFrame f;
  f.depth.data = &one;
  f.depth.width = 1;
  f.depth.height = 1;
  f.intrinsics.cx = 0.0f;
  f.intrinsics.cy = 0.0f;
  out.normals.assign(1, Eigen::Vector3f::UnitZ());
  back_project(std::span<const SensorFrame>(&f, 1), {}, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_TRUE(out.points[0].isApprox(Eigen::Vector3f(0, 0, 1.234f)));
  EXPECT_TRUE(out.normals.empty());
  const std::vector<float> nan_img(12, kNaN);
  f.depth.data = nan_img.data();
  f.depth.format = DepthFormat::kF32;
  f.depth.width = 4;
  f.depth.height = 3;
  back_project(std::span<const SensorFrame>(&f, 1), {}, out, &off);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(off, (std::vector<std::size_t>{0, 0}));
}

TEST(BackProjection, HugeDepthsStayFiniteAndMatchReference) {
  const std::vector<float> d = {1e20f, 3e37f, 1e30f, 2.0f};
  SensorFrame f;
  f.depth.data = d.data();
  f.depth.width = 2;
  f.depth.height = 2;
  f.depth.format = DepthFormat::kF32;
  f.intrinsics.cx = 0.5f;
  f.intrinsics.cy = 0.5f;
  f.T_robot_camera = test::paper_sensor2();
  BackProjectionSettings s;
  s.max_depth_m = 1e31f;  // 3e37 is dropped
  const std::vector<SensorFrame> frames{f};
  const PointCloud got = run(frames, s);
  expect_clouds_match(got, reference_back_project(frames, s, nullptr));
  EXPECT_EQ(got.size(), 3u);
}

TEST(BackProjection, RealSlambookFrameMatchesReference) {
  DUET_REQUIRE_DATA("rgbd/slambook2_ch5/depth/1.pgm");
  const test::RgbdFrame rf = test::load_slambook_frame(1);
  ASSERT_EQ(rf.depth.type(), CV_16UC1);
  ASSERT_EQ(rf.color.type(), CV_8UC3);
  ASSERT_EQ(rf.depth.cols, 640);
  ASSERT_EQ(rf.depth.rows, 480);
  std::vector<SensorFrame> frames{test::slambook_sensor_frame(rf)};
  frames[0].T_robot_camera = rf.T_world_camera;
  for (const int step : {1, 3}) {
    BackProjectionSettings s;
    s.pixel_step = step;
    const PointCloud got = run(frames, s);
    const PointCloud ref = reference_back_project(frames, s, nullptr);
    // A Kinect frame of a room: most pixels valid, some holes.
    EXPECT_GT(ref.size(), 100000u / static_cast<std::size_t>(step * step));
    expect_clouds_match(got, ref);
  }
  // Same frame given as RGBA with the world pose and as two sensors: still the reference.
  cv::Mat rgba(rf.color.rows, rf.color.cols, CV_8UC4);
  for (int v = 0; v < rgba.rows; ++v)
    for (int u = 0; u < rgba.cols; ++u) {
      const cv::Vec3b bgr = rf.color.at<cv::Vec3b>(v, u);
      rgba.at<cv::Vec4b>(v, u) = cv::Vec4b(bgr[2], bgr[1], bgr[0], 255);
    }
  SensorFrame f2 = frames[0];
  f2.color.data = rgba.data;
  f2.color.channels = 4;
  f2.color.bgr = false;
  f2.color.row_stride_bytes = rgba.step[0];
  f2.T_robot_camera = test::paper_sensor2();
  frames.push_back(f2);
  std::vector<std::size_t> off, ref_off;
  const PointCloud got = run(frames, {}, &off);
  expect_clouds_match(got, reference_back_project(frames, {}, &ref_off));
  EXPECT_EQ(off, ref_off);
  // The two copies of the frame have the same colours.
  ASSERT_EQ(off[2] - off[1], off[1]);
  for (std::size_t i = 0; i < off[1]; i += 997) EXPECT_EQ(got.colors[i], got.colors[off[1] + i]);
}

TEST(BackProjection, Real3dmatchFrameMatchesReference) {
  DUET_REQUIRE_DATA("rgbd/3dmatch_seq01/frame-000116.depth.png");
  const std::string base = test::data_path("rgbd/3dmatch_seq01/frame-000116").string();
  const cv::Mat depth = cv::imread(base + ".depth.png", cv::IMREAD_UNCHANGED);
  const cv::Mat color = cv::imread(base + ".color.png", cv::IMREAD_COLOR);
  ASSERT_EQ(depth.type(), CV_16UC1);
  ASSERT_EQ(color.type(), CV_8UC3);
  std::ifstream pose(base + ".pose.txt");
  Eigen::Matrix4f M;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) pose >> M(r, c);
  ASSERT_TRUE(pose.good() || pose.eof());
  SensorFrame f;
  f.depth.data = depth.data;
  f.depth.width = depth.cols;
  f.depth.height = depth.rows;
  f.depth.row_stride_bytes = depth.step[0];
  f.color.data = color.data;
  f.color.width = color.cols;
  f.color.height = color.rows;
  f.color.row_stride_bytes = color.step[0];
  f.color.bgr = true;
  f.intrinsics.fx = f.intrinsics.fy = 570.342205f;  // camera-intrinsics.txt
  f.intrinsics.cx = 320.0f;
  f.intrinsics.cy = 240.0f;
  f.T_robot_camera.matrix() = M;  // camera -> world
  const std::vector<SensorFrame> frames{f};
  BackProjectionSettings s;
  s.max_depth_m = 8.0f;
  const PointCloud got = run(frames, s);
  const PointCloud ref = reference_back_project(frames, s, nullptr);
  EXPECT_GT(ref.size(), 50000u);
  expect_clouds_match(got, ref);
}

TEST(BackProjection, IdenticalWithOneAndTwoThreads) {
  std::vector<SensorFrame> frames;
  const int w = 160, h = 120;
  const Image a = make_u16_depth(w, h, 8, 31), b = make_u16_depth(w, h, 0, 32, 0.4);
  const Image ca = make_color(w, h, 3, 2, 33), cb = make_color(w, h, 4, 0, 34);
  frames.push_back(make_frame(a, w, h, &ca, 3, true, test::paper_sensor1()));
  frames.push_back(make_frame(b, w, h, &cb, 4, false, test::paper_sensor2()));
  test::RgbdFrame rf;
  if (test::have_data("rgbd/slambook2_ch5/depth/2.pgm")) {
    rf = test::load_slambook_frame(2);
    frames.push_back(test::slambook_sensor_frame(rf));
  }
  for (const int step : {1, 2}) {
    BackProjectionSettings s;
    s.pixel_step = step;
    std::vector<std::size_t> o1, o2;
    const PointCloud c1 = test::in_arena(1, [&] { return run(frames, s, &o1); });
    const PointCloud c2 = test::in_arena(2, [&] { return run(frames, s, &o2); });
    EXPECT_TRUE(test::bitwise_equal(c1, c2));
    EXPECT_EQ(o1, o2);
    EXPECT_GT(c1.size(), 0u);
  }
}

TEST(BackProjection, BadInputThrowsInvalidArgumentWithUsefulMessage) {
  const int w = 8, h = 6;
  const Image depth = make_u16_depth(w, h, 0, 41);
  const Image color = make_color(w, h, 3, 0, 42);
  const SensorFrame good = make_frame(depth, w, h, &color, 3, false, Eigen::Isometry3f::Identity());
  PointCloud out;
  auto call = [&](const SensorFrame& bad, const BackProjectionSettings& s = {}) {
    const std::vector<SensorFrame> frames{good, bad};  // the bad one is frame 1
    back_project(std::span<const SensorFrame>(frames), s, out);
  };
  const auto kInv = ErrorCode::kInvalidArgument;
  {
    SensorFrame f = good;
    f.depth.data = nullptr;
    EXPECT_DUET_ERROR(call(f), kInv, "frame 1");
    EXPECT_DUET_ERROR(call(f), kInv, "null");
  }
  {
    SensorFrame f = good;
    f.depth.width = 0;
    EXPECT_DUET_ERROR(call(f), kInv, "depth size");
    f.depth.width = w;
    f.depth.height = -3;
    EXPECT_DUET_ERROR(call(f), kInv, "depth size");
  }
  {
    SensorFrame f = good;
    f.color.width = w + 1;
    EXPECT_DUET_ERROR(call(f), kInv, "colour");
    f = good;
    f.color.height = h - 1;
    EXPECT_DUET_ERROR(call(f), kInv, "colour");
    f = good;
    f.color.channels = 2;
    EXPECT_DUET_ERROR(call(f), kInv, "channels");
    f = good;
    f.color.row_stride_bytes = 3 * w - 1;
    EXPECT_DUET_ERROR(call(f), kInv, "stride");
  }
  {
    SensorFrame f = good;
    f.depth.row_stride_bytes = 2 * w - 1;
    EXPECT_DUET_ERROR(call(f), kInv, "stride");
    f = good;
    f.depth.depth_units_per_m = 0.0f;
    EXPECT_DUET_ERROR(call(f), kInv, "depth_units_per_m");
    f.depth.depth_units_per_m = kNaN;
    EXPECT_DUET_ERROR(call(f), kInv, "depth_units_per_m");
    f = good;
    f.depth.format = static_cast<DepthFormat>(7);
    EXPECT_DUET_ERROR(call(f), kInv, "format");
  }
  {
    SensorFrame f = good;
    f.intrinsics.fx = 0.0f;
    EXPECT_DUET_ERROR(call(f), kInv, "fx");
    f.intrinsics.fx = -500.0f;
    EXPECT_DUET_ERROR(call(f), kInv, "fx");
    f = good;
    f.intrinsics.fy = kNaN;
    EXPECT_DUET_ERROR(call(f), kInv, "fy");
    f = good;
    f.intrinsics.cx = kInf;
    EXPECT_DUET_ERROR(call(f), kInv, "cx");
    f = good;
    f.T_robot_camera.translation().x() = kNaN;
    EXPECT_DUET_ERROR(call(f), kInv, "T_robot_camera");
  }
  {
    BackProjectionSettings s;
    s.pixel_step = 0;
    EXPECT_DUET_ERROR(call(good, s), kInv, "pixel_step");
    EXPECT_DUET_ERROR(validate(s), kInv, "pixel_step");
    s.pixel_step = 65;
    EXPECT_DUET_ERROR(call(good, s), kInv, "pixel_step");
    s = {};
    s.min_depth_m = -0.1f;
    EXPECT_DUET_ERROR(call(good, s), kInv, "min_depth_m");
    s.min_depth_m = kNaN;
    EXPECT_DUET_ERROR(call(good, s), kInv, "min_depth_m");
    s = {};
    s.max_depth_m = 0.5f;  // == min
    EXPECT_DUET_ERROR(call(good, s), kInv, "max_depth_m");
    s.max_depth_m = kInf;
    EXPECT_DUET_ERROR(call(good, s), kInv, "max_depth_m");
  }
  // The good frame alone is fine, and a failed call leaves no half-written garbage requirement.
  EXPECT_NO_THROW(back_project(std::span<const SensorFrame>(&good, 1), {}, out));
}


}  // namespace test_back_projection
}  // namespace duet
