// `duet replay` of a TUM RGB-D folder: tracked by visual odometry with no ground truth in the
// folder (trajectory.tum checked with `duet eval-traj` against the frames' recorded poses), or
// mapped with groundtruth.txt; the wrong --poses for the input named.
#include <duet/runtime/io/cloud_io.hpp>

#include "cli_run.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace fs = std::filesystem;
using duet::test::CliRun;
using duet::test::data_dir;
using duet::test::run;
using duet::test::temp_dir;

namespace {

/// 7-Scenes RedKitchen frames [0, n) as a TUM folder (30 Hz stamps, depth rescaled from
/// millimetres to TUM's 5000 units per metre, the 7-Scenes intrinsics) without groundtruth.txt;
/// the recorded poses go to `gt` (TUM format) outside the folder.
void seven_scenes_as_tum(const fs::path& dir, const fs::path& gt, int n) {
  const fs::path src = data_dir() / "rgbd" / "7scenes_redkitchen";
  std::ofstream rgb(dir / "rgb.txt"), depth(dir / "depth.txt"), truth(gt);
  rgb << "# timestamp filename\n";
  depth << "# timestamp filename\n";
  truth << "# timestamp tx ty tz qx qy qz qw\n";
  fs::copy_file(src / "camera-intrinsics.txt", dir / "camera-intrinsics.txt");
  for (int i = 0; i < n; ++i) {
    char stem[32], stamp[32];
    std::snprintf(stem, sizeof stem, "frame-%06d", i);
    std::snprintf(stamp, sizeof stamp, "%.6f", 100.0 + i / 30.0);
    fs::copy_file(src / (std::string(stem) + ".color.jpg"), dir / (std::string(stem) + ".jpg"));
    cv::Mat d = cv::imread((src / (std::string(stem) + ".depth.png")).string(), cv::IMREAD_ANYDEPTH);
    ASSERT_EQ(d.type(), CV_16UC1) << stem;
    cv::Mat d5;
    d.convertTo(d5, CV_16UC1, 5.0);  // 7-Scenes' 65535 (no return) saturates: still no valid depth
    d5.setTo(0, d == 65535);
    ASSERT_TRUE(cv::imwrite((dir / (std::string(stem) + "_depth.png")).string(), d5));
    rgb << stamp << ' ' << stem << ".jpg\n";
    depth << stamp << ' ' << stem << "_depth.png\n";
    std::ifstream pose(src / (std::string(stem) + ".pose.txt"));
    Eigen::Matrix4d T;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) pose >> T(r, c);
    const Eigen::Quaterniond q(Eigen::Matrix3d(T.block<3, 3>(0, 0)));
    truth << stamp << ' ' << T(0, 3) << ' ' << T(1, 3) << ' ' << T(2, 3) << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' '
          << q.w() << '\n';
  }
}

TEST(DuetReplayTum, AFolderWithoutGroundTruthIsTrackedByVisualOdometryAndMapped) {
  REQUIRE_DATA("rgbd/7scenes_redkitchen");
  const fs::path d = temp_dir("replay-tum-vision");
  fs::create_directories(d / "tum");
  seven_scenes_as_tum(d / "tum", d / "groundtruth.tum", 90);
  ASSERT_FALSE(fs::exists(d / "tum" / "groundtruth.txt"));
  const CliRun r = run("replay " + (d / "tum").string() + " -o " + (d / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("tracked by visual odometry"), std::string::npos) << r.output;
  const auto s = nlohmann::json::parse(std::ifstream(d / "out" / "summary.json"));
  EXPECT_EQ(s["poses"], "vision");
  EXPECT_EQ(s["visual_odometry"]["frames"].get<int>(), 90);
  EXPECT_GE(s["visual_odometry"]["tracked"].get<int>(), 85);
  EXPECT_EQ(s["frames"].get<int>(), s["visual_odometry"]["tracked"].get<int>());  // only tracked frames are mapped
  EXPECT_GT(duet::read_pcd(d / "out" / "cloud.pcd").size(), 5000u);  // 9747 points at 5 cm
  // The trajectory against the recorded poses (duet eval-traj, Umeyama-aligned): 7-Scenes
  // chained over 150 frames gives 1.65 cm (bench/RESULTS.md).
  const CliRun e = run("eval-traj --json " + (d / "out" / "trajectory.tum").string() + " " + (d / "groundtruth.tum").string());
  ASSERT_EQ(e.code, 0) << e.output;
  const auto ev = nlohmann::json::parse(e.output.substr(e.output.find('{')));
  std::printf("7-Scenes 0-89 as a TUM folder: ATE %.4f m over %d poses\n", ev["ate_m"]["rmse"].get<double>(),
              ev["association"]["pairs"].get<int>());
  EXPECT_GE(ev["association"]["pairs"].get<int>(), 85);
  EXPECT_LT(ev["ate_m"]["rmse"].get<double>(), 0.03);
  // The wrong poses for a TUM folder, named.
  const CliRun odo = run("replay -q --poses odometry " + (d / "tum").string() + " -o " + (d / "out2").string());
  EXPECT_NE(odo.code, 0);
  EXPECT_NE(odo.output.find("no wheel odometry"), std::string::npos) << odo.output;
  const CliRun gt = run("replay -q --poses groundtruth " + (d / "tum").string() + " -o " + (d / "out3").string());
  EXPECT_NE(gt.code, 0);
  EXPECT_NE(gt.output.find("groundtruth.txt: missing"), std::string::npos) << gt.output;
}

TEST(DuetReplayTum, AFolderWithGroundTruthIsMappedWithItOnRequest) {
  REQUIRE_DATA("rgbd/tum_fr2_pair");
  const fs::path d = temp_dir("replay-tum");
  const fs::path src = data_dir() / "rgbd" / "tum_fr2_pair";
  for (const char* f : {"1.png", "2.png", "1_depth.png", "2_depth.png"}) fs::copy_file(src / f, d / f);
  std::ofstream(d / "rgb.txt") << "# timestamp filename\n1.000 1.png\n1.033 2.png\n";
  std::ofstream(d / "depth.txt") << "# timestamp filename\n1.001 1_depth.png\n1.034 2_depth.png\n";
  std::ofstream(d / "groundtruth.txt") << "# timestamp tx ty tz qx qy qz qw\n0.999 0 0 0 0 0 0 1\n1.035 0.01 0 0 0 0 0 1\n";
  std::ofstream(d / "camera-intrinsics.txt") << "520.9 0 325.1\n0 521.0 249.7\n0 0 1\n";
  const CliRun r = run("replay -q --poses groundtruth " + d.string() + " -o " + (d / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_GT(duet::read_pcd(d / "out" / "cloud.pcd").size(), 1000u);
  const auto s = nlohmann::json::parse(std::ifstream(d / "out" / "summary.json"));
  EXPECT_EQ(s["frames"].get<int>(), 2);
  // The same pair by vision (the default): both frames tracked.
  const CliRun v = run("replay -q " + d.string() + " -o " + (d / "vision").string());
  ASSERT_EQ(v.code, 0) << v.output;
  const auto sv = nlohmann::json::parse(std::ifstream(d / "vision" / "summary.json"));
  EXPECT_EQ(sv["visual_odometry"]["tracked"].get<int>(), 2);
  // An unsorted list: an error naming the file and line.
  std::ofstream(d / "rgb.txt") << "# timestamp filename\n1.033 2.png\n1.000 1.png\n";
  const CliRun bad = run("replay -q --poses groundtruth " + d.string() + " -o " + (d / "out2").string());
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.output.find("rgb.txt:3"), std::string::npos) << bad.output;
}

}  // namespace
