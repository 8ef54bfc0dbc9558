// The ROS side without a master: image checks and views (image_view.hpp), the depth/colour
// pairing (frame_sync.hpp), the map messages (map_messages.hpp), against the C API they feed.
#include <duet_ros/frame_sync.hpp>
#include <duet_ros/image_view.hpp>
#include <duet_ros/map_messages.hpp>

#include <gtest/gtest.h>

#include <boost/make_shared.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace {

using duet_ros::rgbd_view;

duet_runtime_sensor_info kinect() {
  duet_runtime_sensor_info s{};
  s.width = 640;
  s.height = 480;
  s.fx = s.fy = 580.0f;
  s.cx = 319.5f;
  s.cy = 239.5f;
  s.depth_units_per_m = 1000.0f;
  return s;
}

sensor_msgs::Image image(const std::string& encoding, std::uint32_t w, std::uint32_t h, std::uint32_t bpp, std::uint32_t pad = 0,
                         double stamp = 10.0) {
  sensor_msgs::Image m;
  m.header.stamp = ros::Time(stamp);
  m.encoding = encoding;
  m.width = w;
  m.height = h;
  m.step = w * bpp + pad;
  m.data.assign(static_cast<std::size_t>(m.step) * h, 7);
  return m;
}

TEST(RosImageView, SixteenBitMillimetresArePointedAtNotCopied) {
  const auto d = image("16UC1", 640, 480, 2, 64);
  const auto v = rgbd_view(d, nullptr, nullptr, kinect());
  ASSERT_EQ(v.error, "");
  EXPECT_EQ(v.image.depth, d.data.data());
  EXPECT_EQ(v.image.depth_format, DUET_DEPTH_U16);
  EXPECT_EQ(v.image.depth_units_per_m, 1000.0f);
  EXPECT_EQ(v.image.depth_row_stride, 640u * 2 + 64);
  EXPECT_EQ(v.image.color, nullptr);
  EXPECT_DOUBLE_EQ(v.image.stamp_s, 10.0);
  EXPECT_EQ(v.c_image().intrinsics, nullptr);
  EXPECT_EQ(rgbd_view(image("mono16", 640, 480, 2), nullptr, nullptr, kinect()).error, "");
}

TEST(RosImageView, FloatMetresAndEveryColourLayout) {
  const auto d = image("32FC1", 640, 480, 4);
  struct Case {
    const char* enc;
    int channels, bgr;
  } cases[] = {{"rgb8", 3, 0}, {"bgr8", 3, 1}, {"rgba8", 4, 0}, {"bgra8", 4, 1}};
  for (const auto& c : cases) {
    const auto col = image(c.enc, 640, 480, static_cast<std::uint32_t>(c.channels), 8);
    const auto v = rgbd_view(d, &col, nullptr, kinect());
    ASSERT_EQ(v.error, "") << c.enc;
    EXPECT_EQ(v.image.depth_format, DUET_DEPTH_F32);
    EXPECT_EQ(v.image.color, col.data.data());
    EXPECT_EQ(v.image.color_channels, c.channels) << c.enc;
    EXPECT_EQ(v.image.color_bgr, c.bgr) << c.enc;
    EXPECT_EQ(v.image.color_row_stride, col.step);
  }
}

TEST(RosImageView, MalformedMessagesAreNamedNeverRead) {
  const auto k = kinect();
  const auto good = image("16UC1", 640, 480, 2);
  EXPECT_NE(rgbd_view(image("bgr16", 640, 480, 6), nullptr, nullptr, k).error.find("encoding 'bgr16'"), std::string::npos);
  EXPECT_NE(rgbd_view(image("16UC1", 320, 240, 2), nullptr, nullptr, k).error.find("320x240"), std::string::npos);
  auto short_step = good;
  short_step.step = 100;
  EXPECT_NE(rgbd_view(short_step, nullptr, nullptr, k).error.find("step 100"), std::string::npos);
  auto short_data = good;
  short_data.data.resize(1000);
  EXPECT_NE(rgbd_view(short_data, nullptr, nullptr, k).error.find("1000 bytes"), std::string::npos);
  auto odd = image("32FC1", 640, 480, 4, 6);
  EXPECT_NE(rgbd_view(odd, nullptr, nullptr, k).error.find("not a multiple of its 4-byte pixels"), std::string::npos);
  auto big = good;
  big.is_bigendian = 1;
  EXPECT_NE(rgbd_view(big, nullptr, nullptr, k).error.find("big-endian"), std::string::npos);
  auto empty = good;
  empty.data.clear();
  EXPECT_NE(rgbd_view(empty, nullptr, nullptr, k).error, "");
  const auto col_small = image("rgb8", 320, 240, 3);
  EXPECT_NE(rgbd_view(good, &col_small, nullptr, k).error.find("registered"), std::string::npos);
  const auto col_bad = image("yuv422", 640, 480, 2);
  EXPECT_NE(rgbd_view(good, &col_bad, nullptr, k).error.find("yuv422"), std::string::npos);
  auto col_short = image("rgb8", 640, 480, 3);
  col_short.data.resize(10);
  EXPECT_NE(rgbd_view(good, &col_short, nullptr, k).error.find("colour image"), std::string::npos);
}

TEST(RosImageView, CameraInfoIntrinsicsWhenCalibratedAndOfTheImagesSize) {
  const auto d = image("16UC1", 640, 480, 2);
  sensor_msgs::CameraInfo ci;
  ci.width = 640;
  ci.height = 480;
  ci.K = {525.0, 0.0, 320.0, 0.0, 526.0, 240.5, 0.0, 0.0, 1.0};
  const auto v = rgbd_view(d, nullptr, &ci, kinect());
  ASSERT_EQ(v.error, "");
  const duet_rgbd_image img = v.c_image();
  ASSERT_NE(img.intrinsics, nullptr);
  EXPECT_EQ(img.intrinsics[0], 525.0f);
  EXPECT_EQ(img.intrinsics[1], 526.0f);
  EXPECT_EQ(img.intrinsics[2], 320.0f);
  EXPECT_EQ(img.intrinsics[3], 240.5f);
  sensor_msgs::CameraInfo uncalibrated;  // K all zero: the driver has no calibration
  EXPECT_EQ(rgbd_view(d, nullptr, &uncalibrated, kinect()).c_image().intrinsics, nullptr);
  auto other = ci;
  other.width = 320;
  EXPECT_NE(rgbd_view(d, nullptr, &other, kinect()).error.find("camera_info"), std::string::npos);
  auto off = ci;
  off.K[2] = 1e9;
  EXPECT_NE(rgbd_view(d, nullptr, &off, kinect()).error.find("principal point"), std::string::npos);
}

// Every view rgbd_view() accepts, the C API takes without an error.
TEST(RosImageView, AcceptedViewsArePushedWithoutError) {
  duet_device dev = duet_device_new("threads=1");
  ASSERT_NE(dev, nullptr);
  duet_runtime rt = duet_runtime_new(dev, DUET_PROFILE_NAME_OR_FILE, "dual", nullptr, 0, 1);
  ASSERT_NE(rt, nullptr);
  duet_runtime_sensor_info si{};
  duet_runtime_get_sensor_info(rt, 0, &si);
  EXPECT_STREQ(si.name, "kinect_front");
  const std::uint32_t w = static_cast<std::uint32_t>(si.width), h = static_cast<std::uint32_t>(si.height);
  sensor_msgs::CameraInfo ci;
  ci.width = w;
  ci.height = h;
  ci.K = {500.0, 0.0, w / 2.0, 0.0, 500.0, h / 2.0, 0.0, 0.0, 1.0};
  double t = 100.0;
  for (const char* denc : {"16UC1", "32FC1"})
    for (const char* cenc : {"rgb8", "bgra8"})
      for (const sensor_msgs::CameraInfo* info : std::vector<const sensor_msgs::CameraInfo*>{nullptr, &ci}) {
        const auto d = image(denc, w, h, std::string(denc) == "16UC1" ? 2 : 4, 8, t);
        const auto c = image(cenc, w, h, std::string(cenc) == "rgb8" ? 3 : 4, 2, t);
        const auto v = rgbd_view(d, &c, info, si);
        ASSERT_EQ(v.error, "");
        const duet_rgbd_image img = v.c_image();
        duet_runtime_push_rgbd(rt, 0, &img);
        EXPECT_EQ(duet_device_get_error(dev), DUET_ERROR_NONE) << denc << " " << cenc << " " << duet_device_get_error_message(dev);
        t += 0.1;
      }
  duet_runtime_release(rt);
  duet_device_release(dev);
}

sensor_msgs::ImageConstPtr stamped(double t) {
  auto m = boost::make_shared<sensor_msgs::Image>();
  m->header.stamp = ros::Time(t);
  return m;
}

TEST(RosFrameSync, PairsDepthWithTheNearestColourPerSensor) {
  ros::Time::init();
  std::vector<std::pair<std::size_t, std::pair<double, double>>> got;
  duet_ros::FrameSync sync(2, {}, [&](std::size_t i, const sensor_msgs::ImageConstPtr& d, const sensor_msgs::ImageConstPtr& c) {
    ASSERT_TRUE(c);
    got.push_back({i, {d->header.stamp.toSec(), c->header.stamp.toSec()}});
  });
  for (int k = 0; k < 10; ++k) {
    const double t = 1.0 + k / 30.0;
    sync.add_color(0, stamped(t + 0.004));  // colour a few ms after depth, as the drivers stamp them
    sync.add_depth(0, stamped(t));
    sync.add_depth(1, stamped(t));
    sync.add_color(1, stamped(t));
  }
  // ApproximateTime hands a pair on once a later message on each topic shows it is the best: 9 of 10.
  ASSERT_GE(got.size(), 16u);
  for (const auto& [i, st] : got) {
    EXPECT_LT(i, 2u);
    EXPECT_NEAR(st.first, st.second, 0.0041);
  }
  EXPECT_EQ(sync.pairs(0) + sync.pairs(1), got.size());
  EXPECT_THROW(sync.add_depth(2, stamped(5.0)), std::out_of_range);
}

TEST(RosFrameSync, AColourStreamThatStopsLeavesDepthUnpairedAndFarStampsAreNeverPaired) {
  ros::Time::init();
  std::size_t pairs = 0;
  duet_ros::FrameSyncSettings s;
  s.max_interval_s = 0.02;
  duet_ros::FrameSync sync(1, s, [&](std::size_t, const sensor_msgs::ImageConstPtr&, const sensor_msgs::ImageConstPtr&) { ++pairs; });
  for (int k = 0; k < 20; ++k) sync.add_depth(0, stamped(1.0 + k / 30.0));  // no colour at all
  EXPECT_EQ(pairs, 0u);
  for (int k = 0; k < 20; ++k) {
    sync.add_depth(0, stamped(3.0 + k / 10.0));
    sync.add_color(0, stamped(3.05 + k / 10.0));  // 50 ms apart: beyond max_interval_s
  }
  EXPECT_EQ(pairs, 0u);
}

TEST(RosFrameSync, WithoutColourEveryDepthImageIsHandedOnAndBadSettingsAreNamed) {
  std::size_t n = 0;
  duet_ros::FrameSyncSettings s;
  s.use_color = false;
  duet_ros::FrameSync sync(1, s, [&](std::size_t, const sensor_msgs::ImageConstPtr& d, const sensor_msgs::ImageConstPtr& c) {
    EXPECT_TRUE(d);
    EXPECT_FALSE(c);
    ++n;
  });
  for (int k = 0; k < 5; ++k) sync.add_depth(0, stamped(k));
  sync.add_color(0, stamped(1.0));  // ignored
  EXPECT_EQ(n, 5u);
  auto none = [](std::size_t, const sensor_msgs::ImageConstPtr&, const sensor_msgs::ImageConstPtr&) {};
  EXPECT_THROW(duet_ros::FrameSync(0, {}, none), std::invalid_argument);
  duet_ros::FrameSyncSettings bad;
  bad.queue = 0;
  EXPECT_THROW(duet_ros::FrameSync(1, bad, none), std::invalid_argument);
  bad = {};
  bad.max_interval_s = std::nan("");
  EXPECT_THROW(duet_ros::FrameSync(1, bad, none), std::invalid_argument);
  EXPECT_THROW(duet_ros::FrameSync(1, {}, nullptr), std::invalid_argument);
}

// A grid with known cells: a 2 m wall 1.5 m ahead of a sensor at the origin, seen through free floor.
duet_grid wall_grid(duet_device dev) {
  duet_grid g = duet_grid_new(dev, 0.05f);
  std::vector<float> xyz;
  std::vector<std::uint8_t> labels;
  for (int i = 0; i <= 40; ++i) {
    const float y = -1.0f + 0.05f * static_cast<float>(i);
    xyz.insert(xyz.end(), {1.5f, y, 0.5f});
    labels.push_back(DUET_LABEL_OBSTACLE);
  }
  duet_grid_update_settings us;
  duet_grid_update_settings_init(&us);
  for (int k = 0; k < 3; ++k)
    duet_grid_update(g, 0.0f, 0.0f, xyz.data(), 3 * sizeof(float), labels.data(), 1, labels.size(), &us);
  return g;
}

TEST(RosMapMessages, OccupancyGridEqualsTheCApisRosCopyAndRoundTripsThroughMapServerFiles) {
  duet_device dev = duet_device_new("threads=1");
  duet_grid g = wall_grid(dev);
  const nav_msgs::OccupancyGrid m = duet_ros::to_occupancy_grid(g, "map", ros::Time(5.0));
  const int w = duet_grid_get_width(g), h = duet_grid_get_height(g);
  ASSERT_EQ(m.info.width, static_cast<std::uint32_t>(w));
  ASSERT_EQ(m.info.height, static_cast<std::uint32_t>(h));
  float ox = 0, oy = 0;
  duet_grid_get_origin(g, &ox, &oy);
  EXPECT_FLOAT_EQ(static_cast<float>(m.info.origin.position.x), ox);
  EXPECT_FLOAT_EQ(static_cast<float>(m.info.origin.position.y), oy);
  EXPECT_EQ(m.header.frame_id, "map");
  std::vector<std::int8_t> ref(static_cast<std::size_t>(w) * h);
  duet_grid_copy_ros(g, ref.data(), ref.size(), 0.65f, 0.45f);
  EXPECT_EQ(m.data, ref);
  std::size_t occupied = 0, free = 0;
  for (const auto v : m.data) occupied += v == 100, free += v == 0;
  EXPECT_GT(occupied, 30u);
  EXPECT_GT(free, 100u);
  // The wall's cells are where the wall is: x = 1.5 m.
  const int wx = static_cast<int>((1.5f - ox) / 0.05f), wy = static_cast<int>((0.0f - oy) / 0.05f);
  EXPECT_EQ(m.data[static_cast<std::size_t>(wy) * w + wx], 100);

  const std::string stem = (std::filesystem::temp_directory_path() / "duet_test_ros_map").string();
  std::string error;
  ASSERT_TRUE(duet_ros::save_map_server(m, stem, error)) << error;
  duet_grid back = duet_grid_load_map_server(dev, (stem + ".yaml").c_str());
  ASSERT_NE(back, nullptr) << duet_device_get_error_message(dev);
  const nav_msgs::OccupancyGrid m2 = duet_ros::to_occupancy_grid(back, "map", ros::Time(5.0));
  EXPECT_EQ(m2.info.width, m.info.width);
  EXPECT_EQ(m2.info.height, m.info.height);
  EXPECT_EQ(m2.data, m.data);
  EXPECT_NEAR(m2.info.origin.position.x, m.info.origin.position.x, 1e-6);
  nav_msgs::OccupancyGrid empty;
  EXPECT_FALSE(duet_ros::save_map_server(empty, stem + "_empty", error));
  duet_grid_release(back);
  duet_grid_release(g);
  duet_device_release(dev);
}

TEST(RosMapMessages, FrontierCellsAreFreeCellsBesideUnknownOnes) {
  nav_msgs::OccupancyGrid m;
  m.info.width = 5;
  m.info.height = 4;
  m.info.resolution = 0.1f;
  m.info.origin.position.x = 1.0;
  m.data = {0, 0, 0, -1, -1,  //
            0, 0, 0, -1, -1,  //
            0, 0, 0, 100, -1,  //
            100, 100, 100, 100, 100};
  // Free cells with an unknown 8-neighbour: (2,0), (2,1), (2,2)? (2,2) touches (3,1) unknown: yes.
  EXPECT_EQ(duet_ros::count_frontier_cells(m), 3u);
  const auto a = duet_ros::frontier_markers(m);
  ASSERT_EQ(a.markers.size(), 1u);
  ASSERT_EQ(a.markers[0].points.size(), 3u);
  EXPECT_NEAR(a.markers[0].points[0].x, 1.0 + 2.5 * 0.1, 1e-6);  // the resolution is a float32
  nav_msgs::OccupancyGrid none;
  EXPECT_EQ(duet_ros::count_frontier_cells(none), 0u);
  EXPECT_TRUE(duet_ros::frontier_markers(none).markers[0].points.empty());
}

TEST(RosMapMessages, MapToOdomComposesToTheMapPose) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> xy(-20.0f, 20.0f), th(-3.1f, 3.1f);
  for (int k = 0; k < 100; ++k) {
    const duet_pose2 map_base{xy(rng), xy(rng), th(rng)}, odom_base{xy(rng), xy(rng), th(rng)};
    const auto t = duet_ros::map_to_odom(map_base, odom_base, "map", "odom", ros::Time(1.0));
    const double yaw = 2.0 * std::atan2(t.transform.rotation.z, t.transform.rotation.w);
    const double c = std::cos(yaw), s = std::sin(yaw);
    const double x = t.transform.translation.x + c * odom_base.x - s * odom_base.y;
    const double y = t.transform.translation.y + s * odom_base.x + c * odom_base.y;
    EXPECT_NEAR(x, map_base.x, 1e-4);
    EXPECT_NEAR(y, map_base.y, 1e-4);
    EXPECT_NEAR(std::remainder(yaw + odom_base.theta - map_base.theta, 2.0 * M_PI), 0.0, 1e-5);
  }
  const auto t = duet_ros::map_to_odom({1, 2, 0}, {1, 2, 0}, "map", "odom", ros::Time(1.0));
  EXPECT_EQ(t.header.frame_id, "map");
  EXPECT_EQ(t.child_frame_id, "odom");
  EXPECT_NEAR(t.transform.translation.x, 0.0, 1e-6);
}

TEST(RosMapMessages, PointCloudPacksXyzAndRgbAsRvizReadsThem) {
  duet_device dev = duet_device_new("threads=1");
  duet_cloud c = duet_cloud_new(dev);
  const float xyz[6] = {1.0f, 2.0f, 3.0f, -1.0f, 0.5f, 0.25f};
  const std::uint8_t rgb[6] = {255, 0, 16, 1, 2, 3};
  duet_cloud_set_points(c, xyz, 3 * sizeof(float), rgb, 3, 2);
  const auto m = duet_ros::to_point_cloud2(c, "map", ros::Time(2.0));
  ASSERT_EQ(m.width, 2u);
  ASSERT_EQ(m.point_step, 16u);
  ASSERT_EQ(m.fields.size(), 4u);
  EXPECT_EQ(m.fields[3].name, "rgb");
  float p[3];
  std::memcpy(p, &m.data[16], 12);
  EXPECT_EQ(p[0], -1.0f);
  EXPECT_EQ(p[2], 0.25f);
  std::uint32_t packed = 0;
  std::memcpy(&packed, &m.data[12], 4);
  EXPECT_EQ(packed, (255u << 16) | (0u << 8) | 16u);
  duet_cloud_clear(c);
  EXPECT_EQ(duet_ros::to_point_cloud2(c, "map", ros::Time(2.0)).width, 0u);
  duet_cloud_release(c);
  duet_device_release(dev);
  // The path: headings point along it.
  const auto path = duet_ros::to_path({0.0f, 0.0f, 1.0f, 0.0f, 1.0f, 1.0f}, "map", ros::Time(1.0));
  ASSERT_EQ(path.poses.size(), 3u);
  EXPECT_NEAR(path.poses[0].pose.orientation.w, 1.0, 1e-9);
  EXPECT_NEAR(2.0 * std::atan2(path.poses[1].pose.orientation.z, path.poses[1].pose.orientation.w), M_PI / 2, 1e-6);
  EXPECT_TRUE(duet_ros::to_path({}, "map", ros::Time(1.0)).poses.empty());
}

}  // namespace
