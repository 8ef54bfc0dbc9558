// The sensors' sectors (paper_dual_sensors, sector fans, validation) and heading_to_look(): the
// heading that points one of the robot's sensor cones at a place with the least turn, against a
// brute-force search over headings on random mounts.
#include "kernel_test_util.hpp"

#include <duet/kernels/error.hpp>
#include <duet/kernels/observation.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace duet {
namespace test_sensor_sectors {

using test::kNaN;
constexpr float kPi = std::numbers::pi_v<float>;

TEST(SensorSectors, PaperRobotAndFans) {
  const auto s = paper_dual_sensors();
  ASSERT_EQ(s.size(), 2u);
  EXPECT_FLOAT_EQ(s[0].x_m, -0.118f);
  EXPECT_FLOAT_EQ(s[0].y_m, 0.0f);
  EXPECT_FLOAT_EQ(s[0].yaw_rad, 0.0f);
  EXPECT_FLOAT_EQ(s[1].x_m, -0.118f);
  EXPECT_FLOAT_EQ(s[1].yaw_rad, -kPi / 2.0f);
  for (const auto& x : s) {
    EXPECT_NEAR(x.fov_rad, 57.0f * kPi / 180.0f, 1e-6f);
    EXPECT_EQ(x.min_range_m, 0.5f);
    EXPECT_EQ(x.max_range_m, 5.0f);
    EXPECT_EQ(x.rays, 30);
  }
  EXPECT_EQ(paper_dual_sensors(7)[1].rays, 7);
  EXPECT_DUET_ERROR(paper_dual_sensors(0), ErrorCode::kInvalidArgument, "rays");

  // Fan at a pose: origin = pose + R(theta) (x_m, y_m); first/last rays at +-fov/2 about the axis.
  const Pose2 pose{1.0f, 2.0f, 0.3f};
  std::vector<Eigen::Vector2f> o(30), d(30);
  sector_rays(pose, s[1], o, d);
  const Eigen::Vector2f want_o(1.0f + std::cos(0.3f) * -0.118f, 2.0f + std::sin(0.3f) * -0.118f);
  for (int r = 0; r < 30; ++r) {
    EXPECT_NEAR((o[r] - want_o).norm(), 0.0f, 1e-6f);
    const float a = -kPi / 2 + 0.3f - s[1].fov_rad / 2 + s[1].fov_rad * r / 29.0f;
    EXPECT_NEAR(d[r].x(), std::cos(a), 1e-6f);
    EXPECT_NEAR(d[r].y(), std::sin(a), 1e-6f);
    EXPECT_NEAR(d[r].norm(), 1.0f, 1e-6f);
  }
  SensorSector one = s[0];
  one.rays = 1;
  std::vector<Eigen::Vector2f> o1(1), d1(1);
  sector_rays(Pose2{0, 0, 1.0f}, one, o1, d1);
  EXPECT_NEAR(d1[0].x(), std::cos(1.0f), 1e-6f);
  EXPECT_NEAR(d1[0].y(), std::sin(1.0f), 1e-6f);
  EXPECT_DUET_ERROR(sector_rays(pose, s[0], std::span<Eigen::Vector2f>(o).first(29), d), ErrorCode::kInvalidArgument,
                    "rays");
}

TEST(SensorSectors, InvalidFieldsThrow) {
  auto bad = [](auto mutate, const char* needle) {
    SensorSector s;
    mutate(s);
    EXPECT_DUET_ERROR(validate(s), ErrorCode::kInvalidArgument, needle);
  };
  bad([](SensorSector& s) { s.fov_rad = 0.0f; }, "fov_rad");
  bad([](SensorSector& s) { s.fov_rad = 7.0f; }, "fov_rad");
  bad([](SensorSector& s) { s.fov_rad = kNaN; }, "fov_rad");
  bad([](SensorSector& s) { s.min_range_m = -0.1f; }, "min_range_m");
  bad([](SensorSector& s) { s.max_range_m = 0.4f; }, "max_range_m");
  bad([](SensorSector& s) { s.max_range_m = test::kInf; }, "max_range_m");
  bad([](SensorSector& s) { s.max_range_m = 1e30f; }, "max_range_m");  // walked for ever before
  bad([](SensorSector& s) { s.max_range_m = 100.5f; }, "max_range_m");
  bad([](SensorSector& s) { s.rays = 0; }, "rays");
  bad([](SensorSector& s) { s.x_m = kNaN; }, "x_m");
  bad([](SensorSector& s) { s.y_m = 101.0f; }, "y_m");  // a mount offset is within the range limit
  EXPECT_DUET_ERROR(validate(std::span<const SensorSector>()), ErrorCode::kInvalidArgument, "sensors");
  SensorSector zero_len;
  zero_len.min_range_m = zero_len.max_range_m = 1.0f;
  EXPECT_NO_THROW(validate(zero_len));
}

TEST(HeadingToLook, PaperRobotTurnsTheLeastToPointACone) {
  const auto dual = paper_dual_sensors(30);
  const std::vector<SensorSector> front(dual.begin(), dual.begin() + 1);
  const float half = kPi / 2.0f;
  // The place due east, the robot arriving heading north: the right sensor already faces it.
  EXPECT_NEAR(heading_to_look(0.0f, half, dual), half, 1e-6f);
  EXPECT_NEAR(heading_to_look(0.0f, half, front), 0.0f, 1e-6f);  // one sensor: face it
  // Arriving heading east (towards it): the front sensor, no turn.
  EXPECT_NEAR(heading_to_look(0.0f, 0.0f, dual), 0.0f, 1e-6f);
  // Arriving heading south: a quarter turn either way; the front sensor (index 0) wins the tie.
  EXPECT_NEAR(heading_to_look(0.0f, -half, dual), 0.0f, 1e-6f);
  // The result is wrapped to (-pi, pi].
  EXPECT_NEAR(heading_to_look(3.0f * kPi, 0.0f, front), kPi, 1e-5f);
  // No sensors or non-finite angles: the look direction as given.
  EXPECT_FLOAT_EQ(heading_to_look(0.7f, 0.0f, std::span<const SensorSector>()), 0.7f);
  EXPECT_FLOAT_EQ(heading_to_look(0.7f, kNaN, dual), 0.7f);
  EXPECT_TRUE(std::isnan(heading_to_look(kNaN, 0.0f, dual)));
}

TEST(HeadingToLook, MatchesABruteForceTurnOnRandomMounts) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> ang(-4.0f * kPi, 4.0f * kPi);
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<SensorSector> sensors(1 + trial % 4);
    for (auto& s : sensors) s.yaw_rad = std::remainder(ang(rng), 2.0f * kPi);
    const float look = ang(rng), from = ang(rng);
    const float h = heading_to_look(look, from, sensors);
    ASSERT_GT(h, -kPi - 1e-6f);
    ASSERT_LE(h, kPi + 1e-6f);
    // Some sensor's axis points along `look` (to float precision)...
    bool points = false;
    for (const auto& s : sensors) points = points || std::fabs(std::remainder(h + s.yaw_rad - look, 2.0f * kPi)) < 1e-4f;
    ASSERT_TRUE(points) << "trial " << trial;
    // ...and pointing any other sensor's axis along `look` needs no smaller turn from `from`.
    float best = test::kInf;
    for (const auto& s : sensors) best = std::min(best, std::fabs(std::remainder(look - s.yaw_rad - from, 2.0f * kPi)));
    ASSERT_NEAR(std::fabs(std::remainder(h - from, 2.0f * kPi)), best, 1e-4f) << "trial " << trial;
  }
}

}  // namespace test_sensor_sectors
}  // namespace duet
