// back_project_camera() and transform_points(): the frames read once, the points put where
// they are needed - the same points as back_project(), bit for bit.
#include "back_projection_fixtures.hpp"
#include "kernel_test_util.hpp"

#include <duet/kernels/back_projection.hpp>

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cstring>
#include <limits>
#include <random>
#include <filesystem>
#include <vector>

namespace duet {
namespace test_camera_points {

using namespace test::back_projection;

// Back-projected once (back_project_camera) and transformed (transform_points), the points are
// back_project()'s bit for bit, with each point's pixel; on a real Kinect frame as two sensors
// and on random frames with padding, holes and a pixel step.
TEST(BackProjection, CameraPointsTransformedAreBackProjectBitForBit) {
  std::vector<std::vector<SensorFrame>> cases;
  const int w = 37, h = 23;
  const Image a = make_u16_depth(w, h, 6, 31, 0.3), b = make_u16_depth(w, h, 0, 32, 0.0);
  const Image ca = make_color(w, h, 3, 2, 33);
  cases.push_back({make_frame(a, w, h, &ca, 3, true, test::paper_sensor1()), make_frame(b, w, h, nullptr, 3, false, test::paper_sensor2())});
  test::RgbdFrame rf;
  if (std::filesystem::exists(std::filesystem::path(DUET_DATA_DIR) / "rgbd/slambook2_ch5/depth/1.pgm")) {
    rf = test::load_slambook_frame(1);
    SensorFrame f1 = test::slambook_sensor_frame(rf), f2 = f1;
    f1.T_robot_camera = test::paper_sensor1();
    f2.T_robot_camera = test::paper_sensor2();
    cases.push_back({f1, f2});
  }
  for (const auto& frames : cases)
    for (const int step : {1, 2, 5}) {
      SCOPED_TRACE(step);
      BackProjectionSettings s;
      s.pixel_step = step;
      std::vector<std::size_t> off;
      const PointCloud ref = run(frames, s, &off);
      CameraPoints cam;
      back_project_camera(frames, s, cam);
      EXPECT_EQ(cam.offsets, off);
      EXPECT_EQ(cam.pixel_step, step);
      ASSERT_EQ(cam.cloud.size(), ref.size());
      ASSERT_EQ(cam.pixel.size(), ref.size());
      std::vector<Eigen::Vector3f> moved(cam.cloud.size());
      for (std::size_t i = 0; i < frames.size(); ++i)
        transform_points(cam.cloud.points.data() + off[i], off[i + 1] - off[i], frames[i].T_robot_camera, moved.data() + off[i]);
      for (std::size_t k = 0; k < ref.size(); ++k) {
        ASSERT_EQ(std::memcmp(moved[k].data(), ref.points[k].data(), sizeof(float) * 3), 0) << k;
        ASSERT_EQ(cam.cloud.colors[k], ref.colors[k]) << k;
      }
      // Each point's pixel: on the step's lattice, ascending within a frame, and its camera-frame
      // z is that pixel's depth.
      for (std::size_t i = 0; i < frames.size(); ++i) {
        const SensorFrame& f = frames[i];
        for (std::size_t k = off[i]; k < off[i + 1]; ++k) {
          const std::uint32_t u = cam.pixel[k] % static_cast<std::uint32_t>(f.depth.width), v = cam.pixel[k] / static_cast<std::uint32_t>(f.depth.width);
          ASSERT_EQ(u % static_cast<std::uint32_t>(step), 0u);
          ASSERT_EQ(v % static_cast<std::uint32_t>(step), 0u);
          if (k > off[i]) {
            ASSERT_GT(cam.pixel[k], cam.pixel[k - 1]);
          }
          std::uint16_t raw;
          const std::size_t stride = f.depth.row_stride_bytes ? f.depth.row_stride_bytes : 2 * static_cast<std::size_t>(f.depth.width);
          std::memcpy(&raw, static_cast<const std::uint8_t*>(f.depth.data) + v * stride + 2 * u, 2);
          ASSERT_EQ(cam.cloud.points[k].z(), static_cast<float>(raw) / f.depth.depth_units_per_m);
        }
      }
    }
  // Nothing in, nothing out; in place works.
  CameraPoints none;
  back_project_camera({}, {}, none);
  EXPECT_EQ(none.cloud.size(), 0u);
  EXPECT_EQ(none.offsets, (std::vector<std::size_t>{0}));
  std::vector<Eigen::Vector3f> p{{1.0f, 2.0f, 3.0f}};
  transform_points(p.data(), 1, test::paper_sensor1(), p.data());
  EXPECT_TRUE(p[0].isApprox(test::paper_sensor1() * Eigen::Vector3f(1.0f, 2.0f, 3.0f)));
  transform_points(nullptr, 0, test::paper_sensor1(), nullptr);
}

// transform_points() against Eigen's R * p + t, to the bit: random points over several blocks (a
// partial last one), huge and tiny values, NaN and infinities; with one thread and with two; in place.
TEST(TransformPoints, SameBitsAsEigenForAnyInputAndThreadCount) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-20.0f, 20.0f);
  std::vector<Eigen::Vector3f> p(3 * 4096 + 17);
  for (auto& q : p) q = {u(rng), u(rng), u(rng)};
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  p[1] = {3e38f, -3e38f, 1e-38f};
  p[2] = {nan, 1.0f, 2.0f};
  p[3] = {inf, -inf, 0.0f};
  p[4] = {-0.0f, 0.0f, 1e-45f};
  Eigen::Isometry3f T = test::paper_sensor1();
  T.translation() += Eigen::Vector3f(0.3f, -1.7f, 0.05f);
  auto same_bits = [](const Eigen::Vector3f& a, const Eigen::Vector3f& b) { return std::memcmp(a.data(), b.data(), sizeof(a)) == 0; };
  for (const int threads : {1, 2}) {
    std::vector<Eigen::Vector3f> out(p.size(), Eigen::Vector3f::Constant(-1.0f));
    tbb::task_arena(threads).execute([&] { transform_points(p.data(), p.size(), T, out.data()); });
    for (std::size_t i = 0; i < p.size(); ++i) {
      const Eigen::Vector3f want = T.linear() * p[i] + T.translation();
      ASSERT_TRUE(same_bits(out[i], want)) << "point " << i << " with " << threads << " threads: " << out[i].transpose() << " vs "
                                           << want.transpose();
    }
  }
  std::vector<Eigen::Vector3f> q = p;
  transform_points(q.data(), q.size(), T, q.data());
  for (std::size_t i = 0; i < p.size(); ++i) ASSERT_TRUE(same_bits(q[i], T.linear() * p[i] + T.translation())) << i;
}
}  // namespace test_camera_points
}  // namespace duet
