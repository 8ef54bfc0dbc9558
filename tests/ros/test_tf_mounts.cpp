// The sensors' mounts from tf (tf_mounts.hpp): a camera's optical frame in the base frame, turned
// into the profile's Eq. (6) keys and loaded by the C API, gives the runtime the same optical
// mount (duet_runtime_sensor_info.T_robot_optical, duet's own conversion) - for the built-in
// profile's two Kinects and for tilted, rolled mounts; bad transforms are named.
#include <duet_ros/tf_mounts.hpp>

#include <duet.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace {

struct Mount {
  double xyz[3];
  double zyx_deg[3];
};

/// The runtime's optical mount of sensor `index` with `sets` laid over the "dual" profile.
std::vector<float> runtime_mount(duet_device dev, const std::vector<std::string>& sets, std::size_t index) {
  std::vector<const char*> argv;
  for (const auto& s : sets) argv.push_back(s.c_str());
  duet_runtime rt = duet_runtime_new(dev, DUET_PROFILE_NAME_OR_FILE, "dual", argv.data(), argv.size(), 1);
  EXPECT_NE(rt, nullptr) << duet_device_get_error_message(dev);
  if (rt == nullptr) return {};
  duet_runtime_sensor_info info{};
  duet_runtime_get_sensor_info(rt, index, &info);
  duet_runtime_release(rt);
  return std::vector<float>(info.T_robot_optical, info.T_robot_optical + 16);
}

}  // namespace

TEST(RosTfMounts, AMountThroughTfGivesTheRuntimeTheSameOpticalFrame) {
  duet_device dev = duet_device_new("threads=1");
  ASSERT_NE(dev, nullptr);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-0.5, 0.5), yaw(-179.0, 179.0), tilt(-60.0, 60.0);
  std::vector<Mount> mounts = {{{-0.118, 0.0, 0.271}, {0.0, 0.0, 0.0}},     // the paper's sensor 1
                               {{-0.118, 0.0, 0.481}, {-90.0, 0.0, 0.0}},   // and sensor 2 (Eq. (6))
                               {{0.2, 0.1, 0.4}, {30.0, 25.0, -10.0}}};    // tilted down, rolled
  for (int k = 0; k < 8; ++k) mounts.push_back({{pos(rng), pos(rng), 0.3 + pos(rng)}, {yaw(rng), tilt(rng), tilt(rng)}});
  for (const Mount& m : mounts) {
    // What a robot description would publish for this mount: the optical frame's pose.
    const geometry_msgs::Transform T = duet_ros::optical_from_mount(m.xyz, m.zyx_deg);
    const std::vector<std::string> sets = duet_ros::mount_overrides(1, "kinect_right", T);
    ASSERT_EQ(sets.size(), 2u);
    EXPECT_EQ(sets[0].rfind("sensors.1.extrinsics.xyz_m=", 0), 0u) << sets[0];
    EXPECT_EQ(sets[1].rfind("sensors.1.extrinsics.zyx_euler_deg=", 0), 0u) << sets[1];
    // Expected: duet's own conversion of the same mount given as profile keys.
    auto key = [](const char* k, const double v[3]) {
      return std::string("sensors.1.extrinsics.") + k + "=[" + std::to_string(v[0]) + ", " + std::to_string(v[1]) + ", " +
             std::to_string(v[2]) + "]";
    };
    const std::vector<float> want = runtime_mount(dev, {key("xyz_m", m.xyz), key("zyx_euler_deg", m.zyx_deg)}, 1);
    const std::vector<float> got = runtime_mount(dev, sets, 1);
    ASSERT_EQ(want.size(), 16u);
    ASSERT_EQ(got.size(), 16u);
    for (int i = 0; i < 16; ++i) EXPECT_NEAR(got[i], want[i], 2e-5) << "element " << i << " of " << sets[1];
    // The other sensor keeps the profile's mount.
    EXPECT_EQ(runtime_mount(dev, sets, 0), runtime_mount(dev, {}, 0));
  }
  duet_device_release(dev);
}

TEST(RosTfMounts, BadTransformsAreNamed) {
  geometry_msgs::Transform T;
  T.rotation.w = 1.0;
  EXPECT_NO_THROW((void)duet_ros::mount_overrides(0, "kinect_front", T));
  geometry_msgs::Transform nan = T;
  nan.translation.y = std::numeric_limits<double>::quiet_NaN();
  geometry_msgs::Transform zero = T;
  zero.rotation.w = 0.0;
  for (const geometry_msgs::Transform& bad : {nan, zero}) {
    try {
      (void)duet_ros::mount_overrides(0, "kinect_front", bad);
      ADD_FAILURE() << "accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("sensor 0 (kinect_front)"), std::string::npos) << e.what();
    }
  }
}
