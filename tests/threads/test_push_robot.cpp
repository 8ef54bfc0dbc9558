// PushRobot (runtime/robot/push_robot.hpp): bounded queues that count what they drop, the time
// origin applied when the runtime takes, buffers handed back for reuse, the latest command.
#include <duet/kernels/error.hpp>
#include <duet/runtime/robot/push_robot.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <thread>

namespace duet {
namespace test_push_robot {

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

}  // namespace test_push_robot
}  // namespace duet

namespace duet {
namespace test_push_robot {

/// A robot turning on the spot at 0.5 rad/s then driving a quarter circle; its wheels slip so
/// that they report 1.3x the heading change (and the true distance). Odometry at 50 Hz, gyro
/// at 100 Hz (true rate, lagging by `lag` s).
struct Drive {
  std::vector<OdometryMsg> wheels;
  std::vector<std::pair<double, float>> gyro;
  std::vector<Pose2> truth;  ///< at each wheel message
};

Drive drive(double lag) {
  Drive d;
  Pose2 truth{}, wheel{};
  const double dt = 0.002;
  for (int k = 0; k <= 2000; ++k) {  // 4 s
    const double t = k * dt;
    const float v = t < 2.0 ? 0.0f : 0.3f, w = 0.5f;
    if (k > 0) {
      truth = Pose2{truth.x + v * static_cast<float>(dt) * std::cos(truth.theta), truth.y + v * static_cast<float>(dt) * std::sin(truth.theta),
                    truth.theta + w * static_cast<float>(dt)};
      wheel = Pose2{wheel.x + v * static_cast<float>(dt) * std::cos(wheel.theta), wheel.y + v * static_cast<float>(dt) * std::sin(wheel.theta),
                    wheel.theta + 1.3f * w * static_cast<float>(dt)};
    }
    if (k % 10 == 0) {
      d.wheels.push_back(OdometryMsg{t, wheel, Twist{v, 1.3f * w}});
      d.truth.push_back(truth);
    }
    if (k % 5 == 0) d.gyro.emplace_back(t - lag, w);
  }
  return d;
}

TEST(PushRobotGyro, TheHeadingComesFromTheGyroAndTheDistanceFromTheWheels) {
  for (const double lag : {0.0, 0.01}) {
    SCOPED_TRACE(lag);
    const Drive d = drive(lag);
    PushRobot r(1);
    std::vector<OdometryMsg> out;
    std::size_t g = 0;
    for (const OdometryMsg& m : d.wheels) {  // pushed as drivers would, taken every 50 ms
      while (g < d.gyro.size() && d.gyro[g].first <= m.stamp_s) {
        r.push_gyro(d.gyro[g].first, d.gyro[g].second);
        ++g;
      }
      r.push_odometry(m);
      auto taken = r.chassis().take_odometry();
      out.insert(out.end(), taken.begin(), taken.end());
    }
    ASSERT_EQ(out.size(), d.wheels.size());
    const Pose2& end = out.back().pose;
    const Pose2& truth = d.truth.back();
    EXPECT_NEAR(std::remainder(end.theta - truth.theta, 6.2831853f), 0.0f, 0.02f);
    EXPECT_NEAR(end.x, truth.x, 0.03f);
    EXPECT_NEAR(end.y, truth.y, 0.03f);
    EXPECT_NEAR(out.back().twist.omega, 0.5f, 1e-3f);  // the gyro's rate
    // The wheels alone are 30 % off in heading.
    EXPECT_GT(std::abs(std::remainder(d.wheels.back().pose.theta - truth.theta, 6.2831853f)), 0.5f);
    EXPECT_EQ(r.stats().gyro_gaps, 0u);
  }
}

TEST(PushRobotGyro, WithoutTheGyroTheWheelsAreKeptAndGapsAreCounted) {
  const Drive d = drive(0.0);
  PushRobot r(1);
  for (const OdometryMsg& m : d.wheels) r.push_odometry(m);
  const auto raw = r.chassis().take_odometry();
  ASSERT_EQ(raw.size(), d.wheels.size());
  EXPECT_EQ(raw.back().pose.theta, d.wheels.back().pose.theta);  // no gyro: untouched
  // A gyro that stops: the steps it does not cover keep the wheels' change, counted.
  PushRobot r2(1);
  for (std::size_t i = 0; i < d.wheels.size(); ++i) {
    if (d.wheels[i].stamp_s < 1.0) r2.push_gyro(d.wheels[i].stamp_s, 0.5f);
    r2.push_odometry(d.wheels[i]);
    (void)r2.chassis().take_odometry();
  }
  EXPECT_GT(r2.stats().gyro_gaps, 100u);
  r2.push_gyro(std::nan(""), 1.0f);
  r2.push_gyro(0.5, 1.0f);  // before the last sample
  (void)r2.chassis().take_odometry();
  EXPECT_EQ(r2.stats().gyro_invalid, 2u);
}

}  // namespace test_push_robot
}  // namespace duet
