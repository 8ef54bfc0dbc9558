// Simulated RGB-D sensors (issue 4, part 2): settings and argument validation (each error names the
// bad value), tiny images, moved renderers, and batches against single renders for any thread count.
#include "sim_renderer_test_util.hpp"

#include <duet/kernels/error.hpp>

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <functional>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace test_sim_renderer_settings {

using namespace duet_test::render;

// ---- validation -------------------------------------------------------------------------------------

void expect_invalid(const std::function<void()>& f, const std::string& part) {
  try {
    f();
  } catch (const duet::Error& e) {
    EXPECT_EQ(e.code(), duet::ErrorCode::kInvalidArgument) << e.what();
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    return;
  }
  ADD_FAILURE() << "no error (expected one naming " << part << ")";
}

TEST(SimRendererSettings, InvalidSettingsThrow) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NO_THROW(duet::sim::validate(RenderSettings{}));
  auto noise = [&](auto set, const std::string& field) {
    RenderSettings rs;
    set(rs.noise);
    expect_invalid([&] { duet::sim::validate(rs.noise); }, field);
    expect_invalid([&] { (void)RgbdRenderer(empty_world(), rs); }, field);
  };
  noise([](KinectNoiseSettings& n) { n.axial_a_m = -0.1f; }, "axial_a_m");
  noise([&](KinectNoiseSettings& n) { n.axial_a_m = nan; }, "axial_a_m");
  noise([](KinectNoiseSettings& n) { n.axial_b_per_m = 2.0f; }, "axial_b_per_m");
  noise([](KinectNoiseSettings& n) { n.axial_c_m = -1.0f; }, "axial_c_m");
  noise([](KinectNoiseSettings& n) { n.axial_angular_m = -1.0f; }, "axial_angular_m");
  noise([](KinectNoiseSettings& n) { n.quantisation_per_m = -1e-3f; }, "quantisation_per_m");
  noise([](KinectNoiseSettings& n) { n.max_incidence_deg = 0.0f; }, "max_incidence_deg");
  noise([](KinectNoiseSettings& n) { n.max_incidence_deg = 91.0f; }, "max_incidence_deg");
  noise([](KinectNoiseSettings& n) { n.dropout_rate = 1.5f; }, "dropout_rate");
  noise([&](KinectNoiseSettings& n) { n.dropout_rate = nan; }, "dropout_rate");
  RenderSettings rs;
  rs.ambient = 1.5f;
  expect_invalid([&] { duet::sim::validate(rs); }, "ambient");
  rs = RenderSettings{};
  rs.light_direction = Eigen::Vector3f::Zero();
  expect_invalid([&] { duet::sim::validate(rs); }, "light_direction");
  rs.light_direction = Eigen::Vector3f(nan, 0.0f, 1.0f);
  expect_invalid([&] { duet::sim::validate(rs); }, "light_direction");
}

TEST(SimRendererSettings, InvalidSensorPoseOrImageThrow) {
  const RgbdRenderer r(empty_world(), RenderSettings{});
  const Eigen::Isometry3f T = camera({0.0f, 0.0f, 1.0f}, 0.0f);
  RgbdImage img;
  auto bad_sensor = [&](auto set, const std::string& field) {
    auto s = kinect(16, 12);
    set(s);
    expect_invalid([&] { r.render(s, T, 0, img); }, field);
    expect_invalid([&] { r.render_depth_only(s, T, 0, img); }, field);
  };
  bad_sensor([](duet::SensorProfile& s) { s.intrinsics.width = 0; }, "width");
  bad_sensor([](duet::SensorProfile& s) { s.intrinsics.fx = 0.0f; }, "fx");
  bad_sensor([](duet::SensorProfile& s) { s.intrinsics.fy = std::numeric_limits<float>::infinity(); }, "fy");
  bad_sensor([](duet::SensorProfile& s) { s.max_depth_m = 0.4f; }, "max_depth_m");
  bad_sensor([](duet::SensorProfile& s) { s.min_depth_m = -1.0f; }, "min_depth_m");
  bad_sensor([](duet::SensorProfile& s) { s.depth_units_per_m = 0.0f; }, "depth_units_per_m");
  Eigen::Isometry3f bad = T;
  bad.translation().x() = std::numeric_limits<float>::quiet_NaN();
  expect_invalid([&] { r.render(kinect(16, 12), bad, 0, img); }, "T_world_optical");
  // frame_view checks the image against the sensor.
  const auto s = kinect(16, 12);
  r.render(s, T, 0, img);
  EXPECT_NO_THROW((void)duet::sim::frame_view(img, s, s.T_robot_optical()));
  expect_invalid([&] { (void)duet::sim::frame_view(img, kinect(32, 12), s.T_robot_optical()); }, "frame_view");
  img.rgb.pop_back();
  expect_invalid([&] { (void)duet::sim::frame_view(img, s, s.T_robot_optical()); }, "frame_view");
  expect_invalid([&] { (void)duet::sim::frame_view(RgbdImage{}, s, s.T_robot_optical()); }, "frame_view");
}

TEST(SimRendererSettings, TinyImageAndMoves) {
  World w = empty_world(2.0f);
  w.solids.push_back(wall_at_x(1.0f));
  duet::sim::validate(w);
  RgbdRenderer r(w, noise_free());
  const auto s = kinect(1, 1);  // one pixel: cx = cy = 0
  RgbdImage img;
  r.render(s, camera({0.0f, 0.0f, 1.0f}, 0.0f), 0, img);
  ASSERT_EQ(img.depth.size(), 1u);
  EXPECT_EQ(img.depth[0], 1000);
  RgbdRenderer moved(std::move(r));
  moved.render(kinect(7, 5), camera({0.0f, 0.0f, 1.0f}, 0.0f), 0, img);  // not a multiple of the packet
  ASSERT_EQ(img.depth.size(), 35u);
  for (const auto d : img.depth) EXPECT_NEAR(d, 1000, 1);
  EXPECT_EQ(moved.mesh().surfaces.size(), 3u);
}

TEST(SimRendererBatch, BatchEqualsSingleRendersForAnyThreadCount) {
  const World w = textured_room();
  const RgbdRenderer r(w, RenderSettings{});
  const auto s1 = kinect();
  const auto s2 = kinect(321, 239);  // partial tiles and packets
  const Eigen::Isometry3f T1 = camera({-0.5f, 0.3f, 0.4f}, -0.4f, 0.05f), T2 = camera({0.5f, -0.3f, 0.6f}, 0.7f, -0.1f);
  RgbdImage ref1, ref2, ref3;
  r.render(s1, T1, 5, ref1);
  r.render_depth_only(s2, T2, 6, ref2);
  r.render(s2, T1, 7, ref3);
  for (const int threads : {1, 2}) {
    tbb::task_arena arena(threads);
    RgbdImage b1, b2, b3;
    b2.rgb.assign(12, 7);  // stale colour: a depth-only job drops it
    const std::vector<duet::sim::RenderJob> jobs = {{&s1, T1, 5, &b1, true}, {&s2, T2, 6, &b2, false}, {&s2, T1, 7, &b3, true}};
    arena.execute([&] { r.render_batch(jobs); });
    EXPECT_EQ(b1.width, 640);
    EXPECT_EQ(b1.height, 480);
    EXPECT_EQ(b2.width, 321);
    EXPECT_EQ(b1.depth, ref1.depth) << threads;
    EXPECT_EQ(b1.rgb, ref1.rgb) << threads;
    EXPECT_EQ(b2.depth, ref2.depth) << threads;
    EXPECT_TRUE(b2.rgb.empty());
    EXPECT_EQ(b3.depth, ref3.depth) << threads;
    EXPECT_EQ(b3.rgb, ref3.rgb) << threads;
  }
  // The jobs are independent: a different seed changes only its own frame's noise.
  RgbdImage c1, c2;
  const std::vector<duet::sim::RenderJob> jobs = {{&s1, T1, 5, &c1, true}, {&s2, T2, 99, &c2, false}};
  r.render_batch(jobs);
  EXPECT_EQ(c1.depth, ref1.depth);
  EXPECT_NE(c2.depth, ref2.depth);
}

TEST(SimRendererBatch, EmptyAndInvalidBatches) {
  const RgbdRenderer r(empty_world(), RenderSettings{});
  const auto s = kinect(16, 12);
  const Eigen::Isometry3f T = camera({0.0f, 0.0f, 1.0f}, 0.0f);
  EXPECT_NO_THROW(r.render_batch(std::span<const duet::sim::RenderJob>()));
  RgbdImage a, b;
  expect_invalid([&] { r.render_batch(std::vector<duet::sim::RenderJob>{{nullptr, T, 0, &a, true}}); }, "null");
  expect_invalid([&] { r.render_batch(std::vector<duet::sim::RenderJob>{{&s, T, 0, nullptr, true}}); }, "null");
  expect_invalid([&] { r.render_batch(std::vector<duet::sim::RenderJob>{{&s, T, 0, &a, true}, {&s, T, 1, &a, false}}); }, "same output");
  // An invalid second job: nothing is rendered, the first job's output is not touched.
  auto bad = kinect(16, 12);
  bad.intrinsics.fx = std::numeric_limits<float>::quiet_NaN();
  expect_invalid([&] { r.render_batch(std::vector<duet::sim::RenderJob>{{&s, T, 0, &a, true}, {&bad, T, 0, &b, true}}); }, "fx");
  Eigen::Isometry3f nan_pose = T;
  nan_pose.translation().y() = std::numeric_limits<float>::quiet_NaN();
  expect_invalid([&] { r.render_batch(std::vector<duet::sim::RenderJob>{{&s, T, 0, &a, true}, {&s, nan_pose, 0, &b, true}}); },
                 "T_world_optical");
  EXPECT_EQ(a.width, 0);
  EXPECT_TRUE(a.depth.empty());
  EXPECT_TRUE(a.rgb.empty());
  // One job = render().
  RgbdImage ref;
  r.render(s, T, 3, ref);
  r.render_batch(std::vector<duet::sim::RenderJob>{{&s, T, 3, &a, true}});
  EXPECT_EQ(a.depth, ref.depth);
  EXPECT_EQ(a.rgb, ref.rgb);
}

}  // namespace test_sim_renderer_settings
