// duet replay of ROS 1 bags (bag_replay.hpp): a bag written from duet's simulator (the node's
// topics) maps like the same input pushed straight into the C API; bad bags are named errors.
#include <duet.h>
#include <duet_ros/bag_replay.hpp>

#include <gtest/gtest.h>

#include <boost/make_shared.hpp>

#include <nav_msgs/Odometry.h>
#include <nlohmann/json.hpp>
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

fs::path temp(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("duet_test_bag_" + name);
  fs::remove_all(p);
  return p;
}

struct Written {
  std::size_t frames = 0, odometry = 0;
};

/// `seconds` of the simulator standing in the lab, turning on the spot, as the node's topics.
Written write_sim_bag(const fs::path& bag_path, double seconds, bool malformed = false) {
  Written w;
  duet_device dev = duet_device_new("threads=1");
  const char* sets[] = {"runtime.sensor_rate_hz=5"};
  duet_sim sim = duet_sim_new(dev, "lab", DUET_PROFILE_NAME_OR_FILE, "dual", sets, 1, 3);
  EXPECT_NE(sim, nullptr) << duet_device_get_error_message(dev);
  rosbag::Bag bag;
  bag.open(bag_path.string(), rosbag::bagmode::Write);
  const std::size_t n = duet_sim_get_sensor_count(sim);
  std::vector<std::uint16_t> depth;
  std::vector<std::uint8_t> rgb;
  for (double t = 0.0; t < seconds; t += 0.02) {
    duet_sim_step(sim, duet_twist{0.0f, 0.6f}, 0.02);
    double stamps[8];
    duet_pose2 poses[8];
    duet_twist twists[8];
    const std::size_t k = duet_sim_take_odometry(sim, stamps, poses, twists, 8);
    for (std::size_t j = 0; j < k; ++j) {
      nav_msgs::Odometry m;
      m.header.stamp = ros::Time(100.0 + stamps[j]);
      m.pose.pose.position.x = poses[j].x;
      m.pose.pose.position.y = poses[j].y;
      m.pose.pose.orientation.z = std::sin(poses[j].theta / 2.0);
      m.pose.pose.orientation.w = std::cos(poses[j].theta / 2.0);
      m.twist.twist.linear.x = twists[j].v;
      m.twist.twist.angular.z = twists[j].omega;
      bag.write("/odom", m.header.stamp, m);
      ++w.odometry;
    }
    for (std::size_t i = 0; i < n; ++i) {
      duet_runtime_sensor_info si{};
      duet_sim_get_sensor_info(sim, i, &si);
      const std::size_t px = static_cast<std::size_t>(si.width) * si.height;
      depth.resize(px);
      rgb.resize(3 * px);
      double st = 0.0;
      while (duet_sim_take_frame(sim, i, &st, depth.data(), 0, rgb.data(), 0, si.width, si.height) == 1) {
        const std::string ns = std::string("/") + si.name;
        sensor_msgs::Image d, c;
        d.header.stamp = c.header.stamp = ros::Time(100.0 + st);
        d.width = c.width = static_cast<std::uint32_t>(si.width);
        d.height = c.height = static_cast<std::uint32_t>(si.height);
        d.encoding = "16UC1";
        d.step = 2 * d.width;
        d.data.resize(2 * px);
        std::memcpy(d.data.data(), depth.data(), 2 * px);
        c.encoding = "rgb8";
        c.step = 3 * c.width;
        c.data = rgb;
        if (malformed && i == 0 && w.frames == 4) d.encoding = "8UC3";  // sensor 0 writes frames 0, 2, 4, ...
        if (malformed && i == 0 && w.frames == 2) {  // a message of another type on a depth topic
          nav_msgs::Odometry wrong;
          wrong.header.stamp = d.header.stamp;
          // Another publisher's connection (rosbag keeps one connection per topic and caller).
          const auto caller = boost::make_shared<ros::M_string>();
          (*caller)["callerid"] = "/another_node";
          bag.write(ns + "/depth_registered/image_raw", wrong.header.stamp, wrong, caller);
        }
        bag.write(ns + "/rgb/image_rect_color", c.header.stamp, c);
        bag.write(ns + "/depth_registered/image_raw", d.header.stamp, d);
        ++w.frames;
      }
    }
  }
  bag.close();
  duet_sim_release(sim);
  duet_device_release(dev);
  return w;
}

nlohmann::json summary(const fs::path& dir) {
  std::ifstream in(dir / "summary.json");
  return nlohmann::json::parse(in);
}

TEST(BagReplay, ASimulatedBagIsMappedFrameByFrame) {
  const fs::path dir = temp("sim");
  fs::create_directories(dir);
  const Written w = write_sim_bag(dir / "run.bag", 6.0, /*malformed=*/true);
  ASSERT_GT(w.frames, 40u);
  duet_ros::BagReplayOptions o;
  o.bag = (dir / "run.bag").string();
  o.output_dir = (dir / "out").string();
  const duet_ros::BagReplayResult r = duet_ros::replay_bag(o);
  // The profile expects Kinects at 30 Hz; the bag's 5 Hz is measured and used.
  EXPECT_EQ(r.profile_sensor_rate_hz, 30.0);
  EXPECT_NEAR(r.bag_sensor_rate_hz, 5.0, 0.05);
  EXPECT_EQ(r.sensor_rate_hz, 5.0);
  EXPECT_EQ(r.wrong_type, 1u);
  // ApproximateTime hands the last frame of each sensor on only when a later one comes: all but those.
  EXPECT_GE(r.frames_pushed + r.frames_dropped + 2, w.frames);
  EXPECT_EQ(r.frames_dropped, 1u);
  EXPECT_NE(r.last_drop.find("8UC3"), std::string::npos) << r.last_drop;
  EXPECT_EQ(r.odometry, w.odometry);
  EXPECT_NEAR(r.duration_s, 6.0, 0.1);
  const auto s = summary(o.output_dir);
  EXPECT_EQ(s["bag"]["frames_pushed"].get<std::uint64_t>(), r.frames_pushed);
  EXPECT_EQ(s["bag"]["wrong_type_dropped"].get<std::uint64_t>(), 1u);
  EXPECT_EQ(s["bag"]["sensor_rate_hz"].get<double>(), 5.0);
  EXPECT_EQ(s["input"]["sensor_silences"].get<std::uint64_t>(), 0u);  // no false silences at the bag's rate
  EXPECT_GE(s["sets_integrated"].get<int>(), 4);  // 1 Hz map updates over 6 s
  EXPECT_TRUE(fs::is_regular_file(fs::path(o.output_dir) / "grid.pgm"));
  EXPECT_TRUE(fs::is_regular_file(fs::path(o.output_dir) / "cloud.pcd"));
  // The same bag maps to the same grid twice (lockstep: bit for bit), here with the rate given.
  duet_ros::BagReplayOptions again = o;
  again.sets = {"runtime.sensor_rate_hz=5"};
  again.output_dir = (dir / "out2").string();
  EXPECT_EQ(duet_ros::replay_bag(again).sensor_rate_hz, 5.0);
  std::ifstream a(fs::path(o.output_dir) / "grid.pgm", std::ios::binary), b(fs::path(again.output_dir) / "grid.pgm", std::ios::binary);
  const std::string ga((std::istreambuf_iterator<char>(a)), {}), gb((std::istreambuf_iterator<char>(b)), {});
  EXPECT_FALSE(ga.empty());
  EXPECT_EQ(ga, gb);
}

TEST(BagReplay, BadBagsAreNamedErrors) {
  const fs::path dir = temp("bad");
  fs::create_directories(dir);
  duet_ros::BagReplayOptions o;
  o.output_dir = (dir / "out").string();
  // Not a bag.
  o.bag = (dir / "text.bag").string();
  std::ofstream(o.bag) << "not a bag\n";
  try {
    (void)duet_ros::replay_bag(o);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("text.bag: not a readable ROS 1 bag"), std::string::npos) << e.what();
  }
  // Missing.
  o.bag = (dir / "missing.bag").string();
  EXPECT_THROW((void)duet_ros::replay_bag(o), std::runtime_error);
  // A bag without the node's topics: the message lists what it has.
  o.bag = (dir / "other.bag").string();
  {
    rosbag::Bag bag;
    bag.open(o.bag, rosbag::bagmode::Write);
    nav_msgs::Odometry m;
    m.header.stamp = ros::Time(1.0);
    bag.write("/wheel_odom", m.header.stamp, m);
    bag.close();
  }
  try {
    (void)duet_ros::replay_bag(o);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("the bag has: /wheel_odom"), std::string::npos) << e.what();
  }
  // A bag cut short (a recording killed mid-write): an error or the part before the cut, never a crash.
  const Written w = write_sim_bag(dir / "full.bag", 3.0);
  ASSERT_GT(w.frames, 10u);
  const auto size = fs::file_size(dir / "full.bag");
  for (const double keep : {0.3, 0.7}) {
    const fs::path cut = dir / ("cut" + std::to_string(static_cast<int>(keep * 10)) + ".bag");
    fs::copy_file(dir / "full.bag", cut, fs::copy_options::overwrite_existing);
    fs::resize_file(cut, static_cast<std::uintmax_t>(static_cast<double>(size) * keep));
    o.bag = cut.string();
    try {
      const auto r = duet_ros::replay_bag(o);
      EXPECT_LE(r.frames_pushed, w.frames);
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(cut.filename().string()), std::string::npos) << e.what();
    }
  }
}

}  // namespace
