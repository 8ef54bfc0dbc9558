// Each map update reads every depth image once (back_project_camera): the pose corrector and the
// mapper fed with those points give what they give from the frames, bit for bit, along a drive
// through the rendered lab; points that do not belong to the frames are refused.
#include <duet/kernels/back_projection.hpp>
#include <duet/kernels/error.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/localization/pose_corrector.hpp>
#include <duet/runtime/mapping/mapper.hpp>
#include <duet/runtime/robot/robot_io.hpp>
#include <duet/sim/renderer.hpp>
#include <duet/sim/world.hpp>

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

namespace duet {
namespace test_back_project_once {

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(BackProjectOnce, CorrectorAndMapperFromOnePassMatchTheirOwn) {
  Profile profile = builtin_profile("dual");
  const sim::World world = sim::builtin_world("lab");
  const sim::RgbdRenderer renderer(world);
  Mapper own_mapper(profile.mapping), shared_mapper(profile.mapping);
  PoseCorrector own_corrector(profile, profile.runtime.pose_correction), shared_corrector(profile, profile.runtime.pose_correction);
  std::vector<RgbdImage> images(profile.sensors.size());
  CameraPoints points;
  Pose2 truth = world.start;
  for (int k = 0; k < 8; ++k) {
    const double t = k;
    truth.theta += 0.25f;  // turning in place: the map constrains the matcher from the second update
    truth.x += 0.05f;
    std::vector<SensorFrame> frames;
    for (std::size_t i = 0; i < profile.sensors.size(); ++i) {
      const SensorProfile& sp = profile.sensors[i];
      renderer.render(sp, to_isometry(truth) * sp.T_robot_optical(), 17 + static_cast<std::uint64_t>(k * 2) + i, images[i]);
      frames.push_back(frame_view(images[i], sp, sp.T_robot_optical()));
    }
    const Pose2 odom{truth.x + 0.02f * static_cast<float>(k), truth.y, truth.theta + 0.01f * static_cast<float>(k)};
    const Pose2 a = own_corrector.update(frames, odom, own_mapper.grid(), t);
    back_project_camera(frames, profile.mapping.back_projection, points);
    const Pose2 b = shared_corrector.update(points, frames, odom, shared_mapper.grid(), t);
    ASSERT_TRUE(same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.theta, b.theta)) << "update " << k;
    own_mapper.integrate(frames, to_isometry(a));
    shared_mapper.integrate(points, frames, to_isometry(b));
  }
  EXPECT_GT(own_corrector.matches(), 0u);  // the matcher did run on these points
  EXPECT_EQ(own_corrector.matches(), shared_corrector.matches());
  const auto ga = own_mapper.grid().logodds(), gb = shared_mapper.grid().logodds();
  ASSERT_EQ(ga.size(), gb.size());
  EXPECT_EQ(std::memcmp(ga.data(), gb.data(), ga.size() * sizeof(float)), 0);
  const PointCloud& ca = own_mapper.cloud();
  const PointCloud& cb = shared_mapper.cloud();
  ASSERT_EQ(ca.size(), cb.size());
  EXPECT_GT(ca.size(), 1000u);
  EXPECT_EQ(std::memcmp(ca.points.data(), cb.points.data(), ca.size() * sizeof(Eigen::Vector3f)), 0);
}

TEST(BackProjectOnce, PointsOfOtherFramesOrStepsAreRefused) {
  Profile profile = builtin_profile("dual");
  const sim::World world = sim::builtin_world("lab");
  const sim::RgbdRenderer renderer(world);
  std::vector<RgbdImage> images(profile.sensors.size());
  std::vector<SensorFrame> frames;
  for (std::size_t i = 0; i < profile.sensors.size(); ++i) {
    const SensorProfile& sp = profile.sensors[i];
    renderer.render(sp, to_isometry(world.start) * sp.T_robot_optical(), 5, images[i]);
    frames.push_back(frame_view(images[i], sp, sp.T_robot_optical()));
  }
  CameraPoints one;
  back_project_camera(std::span<const SensorFrame>(frames).first(1), profile.mapping.back_projection, one);
  Mapper mapper(profile.mapping);
  PoseCorrector corrector(profile, profile.runtime.pose_correction);
  EXPECT_THROW(mapper.integrate(one, frames, to_isometry(world.start)), Error);
  EXPECT_THROW((void)corrector.update(one, frames, world.start, mapper.grid(), 0.0), Error);
  BackProjectionSettings coarse = profile.mapping.back_projection;
  coarse.pixel_step = 3;
  CameraPoints sparse;
  back_project_camera(frames, coarse, sparse);
  EXPECT_THROW(mapper.integrate(sparse, frames, to_isometry(world.start)), Error);
  // The corrector takes any sampling: on another lattice it reads the images itself.
  PoseCorrector own(profile, profile.runtime.pose_correction);
  const Pose2 a = own.update(frames, world.start, mapper.grid(), 0.0);
  const Pose2 b = corrector.update(sparse, frames, world.start, mapper.grid(), 0.0);
  EXPECT_TRUE(same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.theta, b.theta));
}

}  // namespace test_back_project_once
}  // namespace duet
