// Visual odometry on real Kinect frames (../shared/data/rgbd) against their recorded poses:
// 3dmatch_seq01 pairs 0-1 and 1-2, slambook2 ch5 consecutive pairs, 7-Scenes RedKitchen frames
// 0-149 frame to frame and chained over the whole set (ATE). Issue 21's target per pair: 2 cm
// and 1 degree. The peers (OpenCV contrib's RgbdOdometry, Open3D's) on the same frames are in
// bench/bench_odometry.cpp.
#include <duet/kernels/error.hpp>
#include <duet/kernels/trajectory_eval.hpp>
#include <duet/runtime/io/rgbd_dataset.hpp>
#include <duet/runtime/localization/visual_odometer.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>
#include <tbb/task_arena.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>

namespace duet {
namespace test_visual_odometry_real {

std::filesystem::path data(const std::string& rel) { return std::filesystem::path(DUET_DATA_DIR) / rel; }

#define REQUIRE_DATA(rel) \
  if (!std::filesystem::exists(data(rel))) GTEST_SKIP() << data(rel) << " absent: real-data test skipped"

double rot_deg(const Eigen::Isometry3d& E) { return Eigen::AngleAxisd(E.linear()).angle() * 180.0 / 3.141592653589793; }

struct PairError {
  double trans_m = 0.0, rot_deg = 0.0;
  VisualOdometryStatus status = VisualOdometryStatus::kOk;
  std::size_t inliers = 0;
};

/// The estimated motion from frame a to b against the dataset's poses.
PairError pair_error(const RgbdDataset& ds, std::size_t a, std::size_t b, const VisualOdometerSettings& s = {}) {
  const RgbdFrame fa = ds.load(a), fb = ds.load(b);
  VisualOdometer vo(s);
  const SensorFrame sa = fa.sensor_frame(), sb = fb.sensor_frame();
  (void)vo.track(std::span(&sa, 1));
  const auto step = vo.track(std::span(&sb, 1));
  const Eigen::Isometry3d truth = (fa.T_world_camera.inverse() * fb.T_world_camera).cast<double>();
  const Eigen::Isometry3d E = truth.inverse() * step.increment;
  return {E.translation().norm(), rot_deg(E), step.result.status, step.result.inliers};
}

void expect_pair(const RgbdDataset& ds, std::size_t a, std::size_t b, const char* name) {
  const PairError e = pair_error(ds, a, b);
  std::printf("%s %zu-%zu: %.2f cm %.3f deg, %zu inliers (%s)\n", name, a, b, e.trans_m * 100.0, e.rot_deg, e.inliers, to_string(e.status));
  ASSERT_EQ(e.status, VisualOdometryStatus::kOk) << name << " " << a << "-" << b;
  EXPECT_LE(e.trans_m, 0.02) << name << " " << a << "-" << b;
  EXPECT_LE(e.rot_deg, 1.0) << name << " " << a << "-" << b;
}

TEST(VisualOdometryReal, ThreeDMatchPairs) {
  REQUIRE_DATA("rgbd/3dmatch_seq01/camera-intrinsics.txt");
  const auto ds = RgbdDataset::open(data("rgbd/3dmatch_seq01"));
  expect_pair(ds, 0, 1, "3dmatch_seq01");
  expect_pair(ds, 1, 2, "3dmatch_seq01");
}

TEST(VisualOdometryReal, SlambookConsecutivePairs) {
  // slambook2's five frames are a joinMap demo, 23-73 cm and 4-25 degrees apart in a dim room:
  // wide baselines, not a tracking sequence. Frames 3-4 (23 cm, 4 deg) must meet the target; on
  // 0-1, 1-2 and 2-3 too few ORB matches survive (6-19) - the odometry must then say so (a
  // failure status, the guess kept) rather than return a wrong motion.
  REQUIRE_DATA("rgbd/slambook2_ch5/pose.txt");
  const auto ds = RgbdDataset::open(data("rgbd/slambook2_ch5"));
  expect_pair(ds, 3, 4, "slambook2_ch5");
  for (std::size_t i = 0; i + 1 < ds.size(); ++i) {
    const PairError e = pair_error(ds, i, i + 1);
    std::printf("slambook2_ch5 %zu-%zu: %.2f cm %.3f deg, %zu inliers (%s)\n", i, i + 1, e.trans_m * 100.0, e.rot_deg, e.inliers,
                to_string(e.status));
    if (e.status == VisualOdometryStatus::kOk) {
      EXPECT_LE(e.trans_m, 0.02) << i;
      EXPECT_LE(e.rot_deg, 1.0) << i;
    }
  }
}

/// OpenCV contrib's RgbdOdometry (photometric, default settings) on frames a -> b: T_a_b, or
/// nullopt when it fails. The independent witness where a frame's recorded pose is off.
std::optional<Eigen::Isometry3d> opencv_motion(const RgbdFrame& a, const RgbdFrame& b) {
  const auto& K = a.intrinsics;
  const cv::Mat cam = (cv::Mat_<float>(3, 3) << K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1);
  auto frame = [](const RgbdFrame& f) {
    cv::Mat gray, depth;
    cv::cvtColor(cv::Mat(f.height, f.width, CV_8UC3, const_cast<Rgb8*>(f.color.data())), gray, cv::COLOR_RGB2GRAY);
    cv::Mat(f.height, f.width, CV_16UC1, const_cast<std::uint16_t*>(f.depth.data())).convertTo(depth, CV_32FC1, 1.0 / f.depth_units_per_m);
    return std::make_pair(gray, depth);
  };
  const auto [ga, da] = frame(a);
  const auto [gb, db] = frame(b);
  cv::Mat Rt;
  if (!cv::rgbd::RgbdOdometry::create(cam)->compute(ga, da, cv::Mat(), gb, db, cv::Mat(), Rt)) return std::nullopt;
  Eigen::Matrix4d M;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) M(r, c) = Rt.at<double>(r, c);
  return Eigen::Isometry3d(M).inverse();  // Rt maps a's points into b: T_b_a
}

TEST(VisualOdometryReal, SevenScenesFrameToFrameAndChained) {
  REQUIRE_DATA("rgbd/7scenes_redkitchen/camera-intrinsics.txt");
  const auto ds = RgbdDataset::open(data("rgbd/7scenes_redkitchen"));
  ASSERT_EQ(ds.size(), 150u);
  VisualOdometer vo;
  std::vector<StampedPose> est, gt, peer;
  double sum_t = 0.0;
  std::size_t witnessed = 0;
  RgbdFrame prev = ds.load(0);
  Eigen::Isometry3d peer_pose = Eigen::Isometry3d::Identity();
  for (std::size_t i = 0; i < ds.size(); ++i) {
    const RgbdFrame f = i == 0 ? prev : ds.load(i);
    const SensorFrame sf = f.sensor_frame();
    const auto step = vo.track(std::span(&sf, 1));
    if (i > 0) {
      ASSERT_EQ(step.result.status, VisualOdometryStatus::kOk) << "frame " << i;
      const Eigen::Isometry3d truth = (prev.T_world_camera.inverse() * f.T_world_camera).cast<double>();
      const Eigen::Isometry3d E = truth.inverse() * step.increment;
      sum_t += E.translation().norm();
      const auto cv_motion = opencv_motion(prev, f);
      ASSERT_TRUE(cv_motion.has_value()) << "OpenCV failed on frame " << i;
      peer_pose = peer_pose * *cv_motion;
      if (E.translation().norm() > 0.02 || rot_deg(E) > 1.0) {
        // Over the target: acceptable only where the recorded pose is off - OpenCV's independent
        // photometric estimate must then agree with duet's, not with the recording.
        const Eigen::Isometry3d D = cv_motion->inverse() * step.increment;
        std::printf("7-Scenes %zu-%zu: %.2f cm %.3f deg from the recorded pose; duet vs OpenCV %.2f cm %.3f deg\n", i - 1, i,
                    E.translation().norm() * 100.0, rot_deg(E), D.translation().norm() * 100.0, rot_deg(D));
        EXPECT_LE(D.translation().norm(), 0.01) << "frame " << i;
        EXPECT_LE(rot_deg(D), 0.5) << "frame " << i;
        ++witnessed;
      }
    }
    est.push_back({i / 30.0, vo.pose()});
    gt.push_back({i / 30.0, f.T_world_camera.cast<double>()});
    peer.push_back({i / 30.0, peer_pose});
    prev = f;
  }
  const auto ate = absolute_trajectory_error(est, gt);
  const auto peer_ate = absolute_trajectory_error(peer, gt);
  std::printf("7-Scenes RedKitchen 0-149: frame to frame mean %.2f cm, %zu pairs over 2 cm / 1 deg (recorded pose off); chained "
              "ATE rmse %.2f cm max %.2f cm (OpenCV RgbdOdometry: %.2f cm), %zu location points\n",
              sum_t / 149.0 * 100.0, witnessed, ate.translation.rmse * 100.0, ate.translation.max * 100.0,
              peer_ate.translation.rmse * 100.0, vo.keyframes());
  EXPECT_LE(witnessed, 1u);
  EXPECT_LE(ate.translation.rmse, peer_ate.translation.rmse);
}

TEST(VisualOdometryReal, DeterministicForAnyThreadCount) {
  REQUIRE_DATA("rgbd/7scenes_redkitchen/camera-intrinsics.txt");
  const auto ds = RgbdDataset::open(data("rgbd/7scenes_redkitchen"));
  auto run = [&](int threads) {
    tbb::task_arena arena(threads);
    return arena.execute([&] {
      VisualOdometer vo;
      for (std::size_t i = 0; i < 6; ++i) {
        const RgbdFrame f = ds.load(i * 5);
        const SensorFrame sf = f.sensor_frame();
        (void)vo.track(std::span(&sf, 1));
      }
      return vo.pose();
    });
  };
  const auto a = run(1), b = run(2);
  EXPECT_EQ(std::memcmp(a.matrix().data(), b.matrix().data(), 16 * sizeof(double)), 0);
}

TEST(VisualOdometryReal, BlankImageFallsBackAndMalformedFramesAreNamed) {
  REQUIRE_DATA("rgbd/3dmatch_seq01/camera-intrinsics.txt");
  const auto ds = RgbdDataset::open(data("rgbd/3dmatch_seq01"));
  RgbdFrame f0 = ds.load(0), f1 = ds.load(1);
  VisualOdometer vo;
  const SensorFrame s0 = f0.sensor_frame();
  ASSERT_TRUE(vo.track(std::span(&s0, 1)).first);
  // A blank colour image: no features, the guess carries the pose, the location point stays.
  RgbdFrame blank = f1;
  std::fill(blank.color.begin(), blank.color.end(), Rgb8{128, 128, 128});
  const SensorFrame sb = blank.sensor_frame();
  Eigen::Isometry3d guess = Eigen::Isometry3d::Identity();
  guess.translation().x() = 0.05;
  const auto step = vo.track(std::span(&sb, 1), guess);
  EXPECT_EQ(step.result.status, VisualOdometryStatus::kTooFewFeatures);
  EXPECT_TRUE(step.increment.isApprox(guess));
  EXPECT_EQ(vo.failed(), 1u);
  EXPECT_TRUE(vo.pose().isApprox(guess));
  // The next good frame is matched against the location point (frame 0) again.
  const SensorFrame s1 = f1.sensor_frame();
  EXPECT_EQ(vo.track(std::span(&s1, 1)).result.status, VisualOdometryStatus::kOk);
  EXPECT_EQ(vo.tracked(), 1u);
  // A depth image of the wrong size, a missing colour image: named.
  SensorFrame bad = f1.sensor_frame();
  bad.depth.width = 320;
  try {
    (void)vo.track(std::span(&bad, 1));
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("depth image 320x480"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("camera 0"), std::string::npos) << e.what();
  }
  SensorFrame nocolour = f1.sensor_frame();
  nocolour.color.data = nullptr;
  const auto s = vo.track(std::span(&nocolour, 1));
  EXPECT_EQ(s.result.status, VisualOdometryStatus::kTooFewFeatures);
  // Two frames where the location point had one camera.
  const SensorFrame two[2] = {f1.sensor_frame(), f1.sensor_frame()};
  EXPECT_THROW((void)vo.track(two), Error);
}

}  // namespace test_visual_odometry_real
}  // namespace duet
