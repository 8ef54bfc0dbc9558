// TUM trajectory files: round trip, comments and blank lines, CRLF, and malformed lines named by
// file and line (runtime/io/trajectory_io.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/io/trajectory_io.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace duet {
namespace test_trajectory_io {

TEST(TrajectoryIo, ParsesCommentsBlankLinesAndCrlf) {
  const auto t = parse_tum_trajectory("# header\n\n1.5 1 2 3 0 0 0 1\r\n  2.5,4,5,6,0,0,0.7071068,0.7071068\n# end", "t.txt");
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t[0].stamp_s, 1.5);
  EXPECT_TRUE(t[0].pose.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_EQ(t[1].stamp_s, 2.5);
  EXPECT_NEAR(Eigen::AngleAxisd(t[1].pose.linear()).angle(), 3.14159265 / 2, 1e-6);
}

TEST(TrajectoryIo, RoundTripsThroughText) {
  std::vector<StampedPose> a(3);
  for (int i = 0; i < 3; ++i) {
    a[static_cast<std::size_t>(i)].stamp_s = 1000.123456 + i;
    a[static_cast<std::size_t>(i)].pose.linear() = Eigen::AngleAxisd(0.3 * i, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
    a[static_cast<std::size_t>(i)].pose.translation() = Eigen::Vector3d(0.1 * i, -2.0, 3.5);
  }
  const auto b = parse_tum_trajectory(tum_trajectory_text(a), "round trip");
  ASSERT_EQ(b.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR(b[i].stamp_s, a[i].stamp_s, 1e-6);
    EXPECT_TRUE(b[i].pose.isApprox(a[i].pose, 1e-7));
  }
  const auto dir = std::filesystem::temp_directory_path() / "duet_test_trajectory_io";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "t.tum") << tum_trajectory_text(a);
  EXPECT_EQ(read_tum_trajectory(dir / "t.tum").size(), 3u);
  std::filesystem::remove_all(dir);
}

TEST(TrajectoryIo, MalformedLinesAreNamed) {
  auto expect = [](const std::string& text, ErrorCode code, const std::string& what) {
    try {
      (void)parse_tum_trajectory(text, "est.txt");
      ADD_FAILURE() << "no error for: " << text;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), code) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expect("", ErrorCode::kParse, "est.txt: no pose");
  expect("# only a comment\n", ErrorCode::kParse, "no pose");
  expect("1 2 3 4 0 0 0 1\n1 2 3\n", ErrorCode::kParse, "est.txt:2: 3 numbers, want 8");
  expect("1 2 3 4 0 0 0 1 9\n", ErrorCode::kParse, "est.txt:1: more than 8 numbers");
  expect("1 2 x 4 0 0 0 1\n", ErrorCode::kParse, "est.txt:1: 'x' is not a number");
  expect("1 2 nan 4 0 0 0 1\n", ErrorCode::kParse, "est.txt:1");
  expect("1 2 inf 4 0 0 0 1\n", ErrorCode::kParse, "est.txt:1");
  expect("1 2 3 4 0 0 0 2\n", ErrorCode::kParse, "quaternion norm");
  expect("1 2 3 4 0 0 0 0\n", ErrorCode::kParse, "quaternion norm");
  try {
    (void)read_tum_trajectory("/nonexistent/duet/trajectory.txt");
    ADD_FAILURE() << "no error for a missing file";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kIo);
    EXPECT_NE(std::string(e.what()).find("/nonexistent/duet/trajectory.txt"), std::string::npos) << e.what();
  }
}

}  // namespace test_trajectory_io
}  // namespace duet
