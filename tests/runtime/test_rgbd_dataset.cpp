// RGB-D dataset reader: the real recorded sequences in ../shared/data/rgbd, and small
// malformed folders written to a temp dir.
#include <duet/kernels/back_projection.hpp>
#include <duet/kernels/error.hpp>
#include <duet/kernels/kdtree.hpp>
#include <duet/runtime/io/rgbd_dataset.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <gtest/gtest.h>

#include "runtime_test_util.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace test_rgbd_dataset {

namespace fs = std::filesystem;

namespace {

const fs::path kRgbd = fs::path(DUET_DATA_DIR) / "rgbd";

#define SKIP_WITHOUT_DATA(dir)                                                              \
  if (!fs::is_directory(dir)) GTEST_SKIP() << "real data not found at " << (dir).string() \
                                           << " (../shared/data is absent)"

using duet_test::TempDir;

void write_text(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

cv::Mat depth_image(int w, int h, std::uint16_t base = 1000) {
  cv::Mat d(h, w, CV_16UC1);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) d.at<std::uint16_t>(r, c) = static_cast<std::uint16_t>(base + r * w + c);
  return d;
}
cv::Mat color_image(int w, int h) {
  cv::Mat c(h, w, CV_8UC3);
  for (int r = 0; r < h; ++r)
    for (int x = 0; x < w; ++x) c.at<cv::Vec3b>(r, x) = cv::Vec3b(10, 20, static_cast<std::uint8_t>(30 + x));  // B G R
  return c;
}

// A valid slambook2-style folder of n 4x3 frames.
void make_slambook(const fs::path& dir, int n, int w = 4, int h = 3) {
  fs::create_directories(dir / "color");
  fs::create_directories(dir / "depth");
  std::string poses;
  for (int i = 1; i <= n; ++i) {
    ASSERT_TRUE(cv::imwrite((dir / "color" / (std::to_string(i) + ".png")).string(), color_image(w, h)));
    ASSERT_TRUE(cv::imwrite((dir / "depth" / (std::to_string(i) + ".pgm")).string(), depth_image(w, h)));
    poses += std::to_string(i) + " 0 0 0 0 0 1\n";
  }
  write_text(dir / "pose.txt", poses);
}

// A valid 3dmatch-style folder of n 4x3 frames.
void make_3dmatch(const fs::path& dir, int n, int w = 4, int h = 3) {
  fs::create_directories(dir);
  write_text(dir / "camera-intrinsics.txt", "500 0 2\n0 501 1.5\n0 0 1\n");
  for (int i = 0; i < n; ++i) {
    char stem[32];
    std::snprintf(stem, sizeof stem, "frame-%06d", i * 7);
    ASSERT_TRUE(cv::imwrite((dir / (std::string(stem) + ".color.png")).string(), color_image(w, h)));
    ASSERT_TRUE(cv::imwrite((dir / (std::string(stem) + ".depth.png")).string(), depth_image(w, h)));
    write_text(dir / (std::string(stem) + ".pose.txt"),
               "1 0 0 " + std::to_string(i) + "\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  }
}

// slambook2's built-in intrinsics are for 640x480; the tiny synthetic folders need their own.
duet::RgbdDatasetOptions tiny_options() {
  duet::RgbdDatasetOptions opt;
  duet::PinholeIntrinsics k;
  k.width = 4;
  k.height = 3;
  k.fx = k.fy = 100.0f;
  k.cx = 1.5f;
  k.cy = 1.0f;
  opt.intrinsics = k;
  return opt;
}

duet::Error open_error(const fs::path& dir, const duet::RgbdDatasetOptions& opt = {}) {
  try {
    (void)duet::RgbdDataset::open(dir, opt);
  } catch (const duet::Error& e) {
    return e;
  }
  ADD_FAILURE() << "no error opening " << dir;
  return duet::Error(duet::ErrorCode::kInternal, "");
}

duet::Error load_error(const duet::RgbdDataset& ds, std::size_t i) {
  try {
    (void)ds.load(i);
  } catch (const duet::Error& e) {
    return e;
  }
  ADD_FAILURE() << "no error loading frame " << i;
  return duet::Error(duet::ErrorCode::kInternal, "");
}

void expect_contains(const std::string& msg, const std::string& part) {
  EXPECT_NE(msg.find(part), std::string::npos) << "message: " << msg << "\nexpected to contain: " << part;
}

}  // namespace

// ---- real data --------------------------------------------------------------------------------

TEST(RgbdDatasetReal, Slambook2) {
  const fs::path dir = kRgbd / "slambook2_ch5";
  SKIP_WITHOUT_DATA(dir);
  const duet::RgbdDataset ds = duet::RgbdDataset::open(dir);
  EXPECT_EQ(ds.layout(), "slambook2");
  ASSERT_EQ(ds.size(), 5u);
  const duet::PinholeIntrinsics& k = ds.intrinsics();
  EXPECT_EQ(k.width, 640);
  EXPECT_EQ(k.height, 480);
  EXPECT_FLOAT_EQ(k.fx, 518.0f);
  EXPECT_FLOAT_EQ(k.fy, 519.0f);
  EXPECT_FLOAT_EQ(k.cx, 325.5f);
  EXPECT_FLOAT_EQ(k.cy, 253.5f);
  EXPECT_FLOAT_EQ(ds.depth_units_per_m(), 1000.0f);
  for (std::size_t i = 0; i < ds.size(); ++i) EXPECT_EQ(ds.frame_name(i), std::to_string(i + 1));

  // First line of pose.txt: -0.228993 0.00645704 0.0287837 -0.0004327 -0.113131 -0.0326832 0.993042
  const Eigen::Isometry3f& T0 = ds.pose(0);
  EXPECT_LT((T0.translation() - Eigen::Vector3f(-0.228993f, 0.00645704f, 0.0287837f)).norm(), 1e-6f);
  const Eigen::Quaternionf q(T0.linear());
  const Eigen::Quaternionf q_file = Eigen::Quaternionf(0.993042f, -0.0004327f, -0.113131f, -0.0326832f).normalized();
  EXPECT_GT(std::fabs(q.dot(q_file)), 1.0f - 1e-6f);
  EXPECT_LT((T0.linear() * T0.linear().transpose() - Eigen::Matrix3f::Identity()).norm(), 1e-5f);

  const duet::RgbdFrame f = ds.load(2);
  EXPECT_EQ(f.name, "3");
  EXPECT_EQ(f.width, 640);
  EXPECT_EQ(f.height, 480);
  ASSERT_EQ(f.depth.size(), 640u * 480u);
  ASSERT_EQ(f.color.size(), 640u * 480u);
  // Real Kinect depth: mostly valid, in millimetres, indoor range.
  std::vector<std::uint16_t> valid;
  for (auto d : f.depth)
    if (d > 0) valid.push_back(d);
  EXPECT_GT(valid.size(), f.depth.size() / 2);
  std::nth_element(valid.begin(), valid.begin() + static_cast<std::ptrdiff_t>(valid.size() / 2), valid.end());
  const std::uint16_t median = valid[valid.size() / 2];
  EXPECT_GT(median, 500);
  EXPECT_LT(median, 8000);
  // Colour is RGB (not BGR): compare with OpenCV's own decoding of one pixel.
  const cv::Mat bgr = cv::imread((dir / "color" / "3.png").string(), cv::IMREAD_COLOR);
  const cv::Vec3b px = bgr.at<cv::Vec3b>(100, 200);
  const duet::Rgb8 ours = f.color[100 * 640 + 200];
  EXPECT_EQ(ours.r, px[2]);
  EXPECT_EQ(ours.g, px[1]);
  EXPECT_EQ(ours.b, px[0]);
}

TEST(RgbdDatasetReal, ThreeDMatch) {
  const fs::path dir = kRgbd / "3dmatch_seq01";
  SKIP_WITHOUT_DATA(dir);
  const duet::RgbdDataset ds = duet::RgbdDataset::open(dir);
  EXPECT_EQ(ds.layout(), "3dmatch");
  ASSERT_EQ(ds.size(), 5u);
  // Sorted numerically, zero padding kept.
  EXPECT_EQ(ds.frame_name(0), "frame-000000");
  EXPECT_EQ(ds.frame_name(3), "frame-000116");
  EXPECT_EQ(ds.frame_name(4), "frame-000422");
  EXPECT_NEAR(ds.intrinsics().fx, 570.342205f, 1e-3f);
  EXPECT_NEAR(ds.intrinsics().fy, 570.342205f, 1e-3f);
  EXPECT_FLOAT_EQ(ds.intrinsics().cx, 320.0f);
  EXPECT_FLOAT_EQ(ds.intrinsics().cy, 240.0f);
  EXPECT_EQ(ds.intrinsics().width, 640);
  EXPECT_EQ(ds.intrinsics().height, 480);
  // frame-000000.pose.txt, translation column: 1.973046 1.125734 0.309820
  EXPECT_LT((ds.pose(0).translation() - Eigen::Vector3f(1.973046f, 1.125734f, 0.309820f)).norm(), 1e-5f);
  EXPECT_NEAR(ds.pose(0).linear()(0, 0), 0.313181f, 1e-4f);

  const duet::RgbdFrame f = ds.load(4);
  EXPECT_EQ(f.name, "frame-000422");
  EXPECT_EQ(f.depth.size(), 640u * 480u);
  EXPECT_EQ(f.color.size(), 640u * 480u);
  EXPECT_GT(std::count_if(f.depth.begin(), f.depth.end(), [](auto d) { return d > 0; }),
            static_cast<std::ptrdiff_t>(f.depth.size() / 2));

  // Without colour.
  duet::RgbdDatasetOptions opt;
  opt.load_color = false;
  EXPECT_TRUE(duet::RgbdDataset::open(dir, opt).load(0).color.empty());
}

TEST(RgbdDatasetReal, SensorFrameFeedsBackProjection) {
  const fs::path dir = kRgbd / "slambook2_ch5";
  SKIP_WITHOUT_DATA(dir);
  const duet::RgbdDataset ds = duet::RgbdDataset::open(dir);
  const duet::RgbdFrame f = ds.load(0);
  const duet::SensorFrame sf = f.sensor_frame(f.T_world_camera);
  EXPECT_EQ(sf.depth.data, f.depth.data());
  EXPECT_EQ(sf.color.data, &f.color.front().r);
  EXPECT_EQ(sf.depth.width, 640);
  EXPECT_EQ(sf.depth.format, duet::DepthFormat::kU16);
  EXPECT_FLOAT_EQ(sf.depth.depth_units_per_m, 1000.0f);
  EXPECT_TRUE(sf.T_robot_camera.isApprox(f.T_world_camera));

  duet::BackProjectionSettings s;
  s.min_depth_m = 0.0f;
  s.max_depth_m = 100.0f;
  duet::PointCloud cloud;
  duet::back_project(std::span<const duet::SensorFrame>(&sf, 1), s, cloud);
  const auto valid = static_cast<std::size_t>(std::count_if(f.depth.begin(), f.depth.end(), [](auto d) { return d > 0; }));
  ASSERT_EQ(cloud.size(), valid);
  // The first valid pixel (row-major), back-projected by hand as in slambook2's joinMap.
  std::size_t idx = 0;
  while (f.depth[idx] == 0) ++idx;
  const int u = static_cast<int>(idx % 640), v = static_cast<int>(idx / 640);
  const float z = f.depth[idx] / 1000.0f;
  const Eigen::Vector3f p_cam((u - 325.5f) * z / 518.0f, (v - 253.5f) * z / 519.0f, z);
  EXPECT_LT((cloud.points[0] - f.T_world_camera * p_cam).norm(), 1e-4f);
}

// The poses are camera -> world: consecutive frames back-projected into the world overlap
// (median nearest-neighbour distance of a few cm), and much worse with the inverted poses.
namespace {
// Fraction of frame b's points within 5 cm of frame a's points, both in the world frame.
// mode 0: T_world_camera, 1: its inverse, 2: identity (poses ignored).
double overlap(const duet::RgbdFrame& fa, const duet::RgbdFrame& fb, int mode) {
  duet::BackProjectionSettings s;
  s.pixel_step = 4;
  const auto T = [&](const duet::RgbdFrame& f) {
    return mode == 0 ? f.T_world_camera : mode == 1 ? f.T_world_camera.inverse() : Eigen::Isometry3f::Identity();
  };
  duet::PointCloud ca, cb;
  const duet::SensorFrame sa = fa.sensor_frame(T(fa)), sb = fb.sensor_frame(T(fb));
  duet::back_project(std::span<const duet::SensorFrame>(&sa, 1), s, ca);
  duet::back_project(std::span<const duet::SensorFrame>(&sb, 1), s, cb);
  const duet::KdTree tree(ca.points_view());
  std::size_t n = 0, close = 0;
  for (std::size_t i = 0; i < cb.size(); i += 7, ++n) {
    std::uint32_t idx = 0;
    float d2 = 0.0f;
    if (tree.knn(cb.points[i], 1, &idx, &d2) == 1 && d2 < 0.05f * 0.05f) ++close;
  }
  return n ? static_cast<double>(close) / static_cast<double>(n) : 0.0;
}
}  // namespace

TEST(RgbdDatasetReal, PosesAreCameraToWorld) {
  for (const char* name : {"slambook2_ch5", "3dmatch_seq01"}) {
    const fs::path dir = kRgbd / name;
    SKIP_WITHOUT_DATA(dir);
    const duet::RgbdDataset ds = duet::RgbdDataset::open(dir);
    int tested = 0;
    for (std::size_t b = 1; b < ds.size(); ++b) {
      // Only pairs that moved enough for the poses to matter (3dmatch frames 0-2 barely move).
      const Eigen::Isometry3f rel = ds.pose(b - 1).inverse() * ds.pose(b);
      if (rel.translation().norm() < 0.10f && Eigen::AngleAxisf(rel.linear()).angle() < 0.1f) continue;
      ++tested;
      const duet::RgbdFrame fa = ds.load(b - 1), fb = ds.load(b);
      const double good = overlap(fa, fb, 0), inv = overlap(fa, fb, 1), none = overlap(fa, fb, 2);
      EXPECT_GT(good, 0.15) << name << " frames " << b - 1 << ", " << b;
      EXPECT_GT(good, std::max(inv, none) + 0.1) << name << " frames " << b - 1 << ", " << b;
      std::printf("%s frame %zu -> %zu: %.3f of points within 5 cm (inverted poses %.3f, no poses %.3f)\n", name,
                  b, b - 1, good, inv, none);
    }
    EXPECT_GT(tested, 0) << name << ": no pair of frames moved enough to test the poses";
  }
}

// ---- malformed folders ---------------------------------------------------------------------------

TEST(RgbdDatasetErrors, ValidSyntheticFoldersOpen) {
  TempDir tmp;
  make_slambook(tmp.path() / "sb", 3);
  // The layout's built-in intrinsics are for 640x480 images.
  expect_contains(open_error(tmp.path() / "sb").what(), "depth image is 4x3 but the intrinsics are for 640x480 images");
  duet::RgbdDatasetOptions opt = tiny_options();
  opt.depth_units_per_m = 5000.0f;
  const duet::RgbdDataset b = duet::RgbdDataset::open(tmp.path() / "sb", opt);
  EXPECT_EQ(b.layout(), "slambook2");
  ASSERT_EQ(b.size(), 3u);
  const duet::RgbdFrame f = b.load(1);
  EXPECT_FLOAT_EQ(f.intrinsics.fx, 100.0f);
  EXPECT_FLOAT_EQ(f.depth_units_per_m, 5000.0f);
  EXPECT_EQ(f.depth[5], 1005);
  EXPECT_EQ(f.color[3], (duet::Rgb8{33, 20, 10}));
  EXPECT_FLOAT_EQ(f.T_world_camera.translation().x(), 2.0f);

  make_3dmatch(tmp.path() / "m", 3);
  const duet::RgbdDataset c = duet::RgbdDataset::open(tmp.path() / "m");
  EXPECT_EQ(c.layout(), "3dmatch");
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c.frame_name(2), "frame-000014");
  EXPECT_EQ(c.intrinsics().width, 4);
  EXPECT_FLOAT_EQ(c.intrinsics().fy, 501.0f);
  EXPECT_FLOAT_EQ(c.pose(2).translation().x(), 2.0f);
}

TEST(RgbdDatasetErrors, MissingFolder) {
  TempDir tmp;
  const duet::Error e = open_error(tmp.path() / "nope");
  EXPECT_EQ(e.code(), duet::ErrorCode::kIo);
  expect_contains(e.what(), (tmp.path() / "nope").string());
  expect_contains(e.what(), "not found");
}

TEST(RgbdDatasetErrors, UnknownLayout) {
  TempDir tmp;
  write_text(tmp.path() / "readme.txt", "hello");
  const duet::Error e = open_error(tmp.path());
  EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
  expect_contains(e.what(), "not a known RGB-D dataset layout");
  duet::RgbdDatasetOptions opt;
  opt.layout = "kitti";
  EXPECT_EQ(open_error(tmp.path(), opt).code(), duet::ErrorCode::kInvalidArgument);
  opt.layout = "tum";  // known, but its files are missing
  const duet::Error t = open_error(tmp.path(), opt);
  EXPECT_EQ(t.code(), duet::ErrorCode::kIo);
  expect_contains(t.what(), "rgb.txt");
}

TEST(RgbdDatasetErrors, MissingFrameFile) {
  TempDir tmp;
  make_slambook(tmp.path(), 3);
  fs::remove(tmp.path() / "depth" / "2.pgm");
  const duet::Error e = open_error(tmp.path());
  EXPECT_EQ(e.code(), duet::ErrorCode::kIo);
  expect_contains(e.what(), (tmp.path() / "depth" / "2.pgm").string());
  expect_contains(e.what(), "missing frame file");

  TempDir tmp2;
  make_3dmatch(tmp2.path(), 3);
  fs::remove(tmp2.path() / "frame-000007.color.png");
  const duet::Error e2 = open_error(tmp2.path());
  expect_contains(e2.what(), "frame-000007.color.png: missing frame file");
}

TEST(RgbdDatasetErrors, PoseLineWithWrongCount) {
  TempDir tmp;
  make_slambook(tmp.path(), 3);
  write_text(tmp.path() / "pose.txt", "1 0 0 0 0 0 1\n2 0 0 0 0 1\n3 0 0 0 0 0 1\n");
  const duet::Error e = open_error(tmp.path());
  EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
  expect_contains(e.what(), "pose.txt:2: expected 7 numbers 'tx ty tz qx qy qz qw', got 6");

  TempDir tmp2;
  make_3dmatch(tmp2.path(), 2);
  write_text(tmp2.path() / "frame-000007.pose.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n");
  const duet::Error e2 = open_error(tmp2.path());
  expect_contains(e2.what(), "frame-000007.pose.txt: expected 16 numbers (a 4x4 camera-to-world matrix), got 12");
}

TEST(RgbdDatasetErrors, NonNumericValue) {
  TempDir tmp;
  make_slambook(tmp.path(), 2);
  write_text(tmp.path() / "pose.txt", "1 0 0 0 0 0 1\n2 0 abc 0 0 0 1\n");
  const duet::Error e = open_error(tmp.path());
  EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
  expect_contains(e.what(), "pose.txt:2: value 3 'abc' is not a number");

  TempDir tmp2;
  make_3dmatch(tmp2.path(), 1);
  write_text(tmp2.path() / "camera-intrinsics.txt", "500 0 2\n0 fy 1.5\n0 0 1\n");
  const duet::Error e2 = open_error(tmp2.path());
  expect_contains(e2.what(), "camera-intrinsics.txt: value 5 'fy' is not a number");
}

TEST(RgbdDatasetErrors, NonUnitQuaternion) {
  TempDir tmp;
  make_slambook(tmp.path(), 2);
  // Within 1e-3 of unit: normalised.
  write_text(tmp.path() / "pose.txt", "1 0 0 0 0 0 1.0005\n2 0 0 0 0 0 1\n");
  const duet::RgbdDataset ds = duet::RgbdDataset::open(tmp.path(), tiny_options());
  EXPECT_LT((ds.pose(0).linear() - Eigen::Matrix3f::Identity()).norm(), 1e-6f);
  // Far from unit: an error.
  write_text(tmp.path() / "pose.txt", "1 0 0 0 0 0 1\n2 0 0 0 0 0 0.5\n");
  const duet::Error e = open_error(tmp.path());
  EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
  expect_contains(e.what(), "pose.txt:2: quaternion (qx qy qz qw) has norm 0.5");

  TempDir tmp2;
  make_3dmatch(tmp2.path(), 1);
  write_text(tmp2.path() / "frame-000000.pose.txt", "2 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  expect_contains(open_error(tmp2.path()).what(), "frame-000000.pose.txt: the rotation part is not a rotation");
  write_text(tmp2.path() / "frame-000000.pose.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 1\n");
  expect_contains(open_error(tmp2.path()).what(), "frame-000000.pose.txt: the last row of the pose must be 0 0 0 1");
}

TEST(RgbdDatasetErrors, DepthNot16Bit) {
  TempDir tmp;
  make_slambook(tmp.path(), 2);
  cv::Mat d8(3, 4, CV_8UC1, cv::Scalar(7));
  ASSERT_TRUE(cv::imwrite((tmp.path() / "depth" / "2.pgm").string(), d8));
  const duet::RgbdDataset ds = duet::RgbdDataset::open(tmp.path(), tiny_options());
  const duet::Error e = load_error(ds, 1);
  EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
  expect_contains(e.what(), (tmp.path() / "depth" / "2.pgm").string());
  expect_contains(e.what(), "depth image is 8-bit with 1 channel; expected 16-bit single-channel");
  EXPECT_NO_THROW((void)ds.load(0));
}

TEST(RgbdDatasetErrors, ColorDepthSizeMismatch) {
  TempDir tmp;
  make_3dmatch(tmp.path(), 2);
  ASSERT_TRUE(cv::imwrite((tmp.path() / "frame-000007.color.png").string(), color_image(5, 3)));
  const duet::RgbdDataset ds = duet::RgbdDataset::open(tmp.path());
  const duet::Error e = load_error(ds, 1);
  EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
  expect_contains(e.what(), "frame-000007.color.png: colour image is 5x3 but depth image");
  expect_contains(e.what(), "is 4x3");
  // A depth image of another size than the dataset's.
  ASSERT_TRUE(cv::imwrite((tmp.path() / "frame-000007.depth.png").string(), depth_image(2, 2)));
  expect_contains(load_error(ds, 1).what(), "frame-000007.depth.png: depth image is 2x2, expected 4x3");
  // Intrinsics that do not fit the images.
  duet::RgbdDatasetOptions opt;
  opt.intrinsics = duet::PinholeIntrinsics{};  // 640x480
  expect_contains(open_error(tmp.path(), opt).what(), "depth image is 4x3 but the intrinsics are for 640x480 images");
}

TEST(RgbdDatasetErrors, PoseCountDiffersFromFrameCount) {
  TempDir tmp;
  make_slambook(tmp.path(), 3);
  write_text(tmp.path() / "pose.txt", "1 0 0 0 0 0 1\n2 0 0 0 0 0 1\n");
  const duet::Error e = open_error(tmp.path());
  EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
  expect_contains(e.what(), "pose.txt: has 2 poses but the folder has 3 frames");

  TempDir tmp2;
  make_3dmatch(tmp2.path(), 2);
  fs::remove(tmp2.path() / "frame-000007.pose.txt");
  expect_contains(open_error(tmp2.path()).what(), "frame-000007.pose.txt: missing frame file");
}

TEST(RgbdDatasetErrors, GapInTheFrameNumbersIsNamedNotPairedByRank) {
  // Frames 1, 2, 4 and three poses: pairing by rank would give frame 4 the pose of frame 3.
  TempDir tmp;
  make_slambook(tmp.path(), 4);
  fs::remove(tmp.path() / "color" / "3.png");
  fs::remove(tmp.path() / "depth" / "3.pgm");
  write_text(tmp.path() / "pose.txt", "1 0 0 0 0 0 1\n2 0 0 0 0 0 1\n4 0 0 0 0 0 1\n");
  const duet::Error e = open_error(tmp.path());
  EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
  expect_contains(e.what(), "3.png: missing frame: the frames jump from 2 to 4");
}

TEST(RgbdDatasetErrors, FarPoseIsNamedWithItsLine) {
  // A pose of 1e30 m failed inside the voxel filter, naming no file.
  TempDir tmp;
  make_slambook(tmp.path(), 2);
  write_text(tmp.path() / "pose.txt", "0 0 0 0 0 0 1\n1e30 0 0 0 0 0 1\n");
  const duet::Error e = open_error(tmp.path());
  EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
  expect_contains(e.what(), "pose.txt:2: the camera position (1e+30, 0, 0) m is beyond the map frame's limit");
}

TEST(RgbdDatasetErrors, FrameIndexOutOfRange) {
  TempDir tmp;
  make_slambook(tmp.path(), 1);
  const duet::RgbdDataset ds = duet::RgbdDataset::open(tmp.path(), tiny_options());
  EXPECT_EQ(load_error(ds, 1).code(), duet::ErrorCode::kInvalidArgument);
  EXPECT_THROW((void)ds.pose(5), duet::Error);
}

}  // namespace test_rgbd_dataset
