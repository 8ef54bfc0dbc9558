// The runtime's status through the C API with localization.visual_odometry on and off:
// duet_runtime_status.visual_odometry and odometry_health (duet_runtime.h).
#include <duet.h>

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

TEST(CapiVisualOdometry, StatusReportsVisionAndItsHealth) {
  duet_device device = duet_device_new(nullptr);
  ASSERT_NE(device, nullptr);
  const char* off_sets[] = {"runtime.sensor_rate_hz=1"};
  const char* on_sets[] = {"runtime.sensor_rate_hz=1", "localization.visual_odometry.enabled=true"};
  std::vector<uint16_t> depth(640 * 480, 2000);
  for (const bool on : {false, true}) {
    duet_runtime rt = duet_runtime_new(device, DUET_PROFILE_NAME_OR_FILE, "single", on ? on_sets : off_sets, on ? 2 : 1, 1);
    ASSERT_NE(rt, nullptr);
    duet_runtime_set_time_origin(rt, 0.0);
    for (int k = 0; k <= 150; ++k) duet_runtime_push_odometry(rt, 0.02 * k, duet_pose2{0, 0, 0}, duet_twist{0, 0});
    // Depth without colour: vision has nothing to track.
    for (const double t : {0.5, 1.5, 2.5}) {
      duet_rgbd_image im;
      duet_rgbd_image_init(&im);
      im.stamp_s = t;
      im.width = 640;
      im.height = 480;
      im.depth = depth.data();
      duet_runtime_push_rgbd(rt, 0, &im);
    }
    for (int k = 1; k <= 60; ++k) duet_runtime_spin_once(rt, 0.05 * k);
    duet_runtime_status s;
    duet_runtime_get_status(rt, &s);
    EXPECT_EQ(s.visual_odometry, on ? 1 : 0);
    EXPECT_NE(s.odometry_health, DUET_POSE_GOOD) << "vision saw no colour, yet reported good";
    EXPECT_GE(s.map_updates, 2u);
    duet_runtime_release(rt);
  }
  duet_device_release(device);
}
