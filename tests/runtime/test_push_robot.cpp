// PushRobot (runtime/robot/push_robot.hpp): bounded queues that count what they drop, the time
// origin applied when the runtime takes, buffers handed back for reuse, the latest command.
#include <duet/kernels/error.hpp>
#include <duet/runtime/robot/push_robot.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <thread>

namespace duet {
namespace {

RgbdImage image(int w, int h, std::uint16_t d) {
  RgbdImage im;
  im.width = w;
  im.height = h;
  im.depth.assign(static_cast<std::size_t>(w) * h, d);
  return im;
}

TEST(PushRobot, QueuesAreBoundedAndCountTheirDrops) {
  PushRobotSettings s;
  s.frame_queue = 3;
  s.odometry_queue = 5;
  PushRobot r(2, s);
  for (int i = 0; i < 10; ++i) r.push_frame(1, i, image(4, 3, static_cast<std::uint16_t>(i)));
  for (int i = 0; i < 12; ++i) r.push_odometry(OdometryMsg{0.02 * i, Pose2{}, Twist{}});
  const PushStats st = r.stats();
  EXPECT_EQ(st.frames_pushed, 10u);
  EXPECT_EQ(st.frames_overflowed, 7u);
  EXPECT_EQ(st.odometry_pushed, 12u);
  EXPECT_EQ(st.odometry_overflowed, 7u);
  // The newest are kept, oldest first.
  const auto frames = r.sensors()[1]->take_frames();
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(frames[0].stamp_s, 7.0);
  EXPECT_EQ(frames[2].image.depth[0], 9);
  EXPECT_TRUE(r.sensors()[0]->take_frames().empty());
  const auto odom = r.chassis().take_odometry();
  ASSERT_EQ(odom.size(), 5u);
  EXPECT_DOUBLE_EQ(odom.front().stamp_s, 0.02 * 7);
  EXPECT_TRUE(r.chassis().take_odometry().empty());  // taken once
  EXPECT_THROW(r.push_frame(2, 0.0, image(1, 1, 0)), Error);
  EXPECT_THROW(PushRobot(0), Error);
  EXPECT_THROW(PushRobot(17), Error);
  s.frame_queue = 0;
  EXPECT_THROW(PushRobot(1, s), Error);
}

TEST(PushRobot, TheOriginIsSubtractedWhenTakenAndBadStampsPassThrough) {
  PushRobot r(1);
  r.push_odometry(OdometryMsg{1000.5, Pose2{1, 2, 3}, Twist{0.1f, 0.2f}});
  r.push_odometry(OdometryMsg{std::nan(""), Pose2{}, Twist{}});
  r.push_frame(0, 1001.25, image(2, 2, 7));
  r.set_time_origin(1000.0);  // set after the push: applies to what is taken from now on
  const auto odom = r.chassis().take_odometry();
  ASSERT_EQ(odom.size(), 2u);
  EXPECT_DOUBLE_EQ(odom[0].stamp_s, 0.5);
  EXPECT_EQ(odom[0].pose.y, 2.0f);
  EXPECT_TRUE(std::isnan(odom[1].stamp_s));  // the runtime's input guard drops and counts it
  const auto frames = r.sensors()[0]->take_frames();
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_DOUBLE_EQ(frames[0].stamp_s, 1.25);
}

TEST(PushRobot, BuffersComeBackAndTheCommandIsTheLatest) {
  PushRobot r(1);
  EXPECT_TRUE(r.spare_image().depth.empty());
  RgbdImage im = image(8, 6, 1);
  const std::uint16_t* buffer = im.depth.data();
  r.sensors()[0]->recycle(std::move(im));
  const RgbdImage back = r.spare_image();
  EXPECT_EQ(back.depth.data(), buffer);  // the same allocation, for the next push to fill
  EXPECT_EQ(r.latest_command().v, 0.0f);
  r.chassis().command(Twist{0.3f, -0.1f});
  EXPECT_EQ(r.latest_command().v, 0.3f);
  EXPECT_EQ(r.latest_command().omega, -0.1f);
}

TEST(PushRobot, PushesFromSeveralThreadsAreAllCounted) {
  PushRobotSettings s;
  s.frame_queue = 1024;
  s.odometry_queue = 100000;
  PushRobot r(2, s);
  auto cam = [&](std::size_t i) {
    for (int k = 0; k < 200; ++k) r.push_frame(i, k, image(2, 2, 1));
  };
  auto wheels = [&] {
    for (int k = 0; k < 1000; ++k) r.push_odometry(OdometryMsg{0.001 * k, Pose2{}, Twist{}});
  };
  std::thread a(cam, 0), b(cam, 1), c(wheels);
  std::size_t taken = 0;
  for (int k = 0; k < 50; ++k) taken += r.chassis().take_odometry().size();  // the control thread takes meanwhile
  a.join();
  b.join();
  c.join();
  taken += r.chassis().take_odometry().size();
  EXPECT_EQ(taken, 1000u);
  EXPECT_EQ(r.sensors()[0]->take_frames().size() + r.sensors()[1]->take_frames().size(), 400u);
  EXPECT_EQ(r.stats().frames_overflowed + r.stats().odometry_overflowed, 0u);
}

}  // namespace
}  // namespace duet
