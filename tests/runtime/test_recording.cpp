// Recording and replay (runtime/io/recording.hpp): a recorded lockstep run replays to the same
// grid, cloud and poses bit for bit; malformed recordings are errors naming the file and line;
// the recorder refuses a folder in use and drops (counts) frames when its disk is too slow.
#include "runtime_test_util.hpp"

#include <duet/kernels/error.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/io/recording.hpp>
#include <duet/runtime/io/runtime_outputs.hpp>
#include <duet/sim/sim_explore.hpp>
#include <duet/sim/world.hpp>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <sstream>

namespace duet {
namespace test_recording {

using duet_test::TempDir;

/// A valid 16-bit PNG of 32 x 24 px (the sensors' are 640 x 480).
void cv_write_small_png(const std::filesystem::path& p) {
  const cv::Mat small(24, 32, CV_16UC1, cv::Scalar(1000));
  ASSERT_TRUE(cv::imwrite(p.string(), small));
}

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// A recorded 8 s lab run (both sensors, lockstep, seed 3) and what it ended with.
struct Recorded {
  OccupancyGrid grid{0.05f};
  std::size_t cloud_points = 0;
  std::vector<Pose2> poses;
  sim::ExploreSummary summary;
};

Recorded record_lab(const std::filesystem::path& dir, std::vector<std::string> faults = {}, double seconds = 8.0) {
  sim::ExploreSettings s;
  s.seed = 3;
  s.max_time_s = seconds;
  s.record_dir = dir.string();
  s.faults = std::move(faults);
  sim::SimExplore run(sim::builtin_world("lab"), builtin_profile("dual"), s);
  run.run();
  Recorded r;
  r.grid = run.runtime().map_grid();
  r.cloud_points = run.mapper().cloud().size();
  for (std::size_t i = 1; i < run.estimated_trajectory().size(); ++i) r.poses.push_back(run.estimated_trajectory()[i].pose);
  r.summary = run.summary();
  return r;
}

struct Replayed {
  OccupancyGrid grid{0.05f};
  std::size_t cloud_points = 0;
  std::vector<Pose2> poses;
};

Replayed replay(const std::filesystem::path& dir) {
  const Recording rec = read_recording(dir);
  ReplaySource src(rec);
  ExplorationRuntime rt(rec.profile, src.chassis(), src.sensors(), rec.profile.runtime);
  Replayed out;
  const double dt = 1.0 / rec.profile.runtime.control_rate_hz;
  for (double t = 0.0; t + 1e-9 < rec.end_s();) {
    t = t + dt;
    src.advance(t);
    rt.tick(t);
    out.poses.push_back(rt.pose());
  }
  EXPECT_TRUE(src.finished());
  rt.drain();
  out.grid = rt.map_grid();
  out.cloud_points = rt.mapper().cloud().size();
  return out;
}

void expect_same(const Recorded& a, const Replayed& b) {
  ASSERT_EQ(a.poses.size(), b.poses.size());
  for (std::size_t i = 0; i < a.poses.size(); ++i) {
    ASSERT_EQ(a.poses[i].x, b.poses[i].x) << "period " << i;
    ASSERT_EQ(a.poses[i].y, b.poses[i].y) << "period " << i;
    ASSERT_EQ(a.poses[i].theta, b.poses[i].theta) << "period " << i;
  }
  ASSERT_EQ(a.grid.width(), b.grid.width());
  ASSERT_EQ(a.grid.height(), b.grid.height());
  const auto la = a.grid.logodds(), lb = b.grid.logodds();
  ASSERT_EQ(la.size(), lb.size());
  EXPECT_EQ(std::memcmp(la.data(), lb.data(), la.size() * sizeof(float)), 0);  // bit for bit (unknown cells may be NaN)
  EXPECT_EQ(a.grid.origin(), b.grid.origin());
  EXPECT_EQ(a.cloud_points, b.cloud_points);
}

TEST(Recording, ALockstepRunReplaysBitForBit) {
  TempDir tmp;
  const Recorded a = record_lab(tmp / "rec");
  EXPECT_GT(a.grid.known_cells(), 1000u);
  const std::string meta = read_text(tmp / "rec" / "recording.yaml");
  EXPECT_NE(meta.find("format: duet-recording"), std::string::npos) << meta;
  EXPECT_NE(meta.find("frames_recorded: 18"), std::string::npos) << meta;  // 2 sensors x t = 0 ... 8 s
  EXPECT_NE(meta.find("frames_dropped: 0"), std::string::npos) << meta;
  EXPECT_TRUE(std::filesystem::exists(tmp / "rec" / "kinect_front" / "depth" / "000000.png"));
  EXPECT_TRUE(std::filesystem::exists(tmp / "rec" / "kinect_right" / "rgb" / "000008.png"));
  expect_same(a, replay(tmp / "rec"));
}

TEST(Recording, AFaultyRunReplaysBitForBitToo) {
  // Reordered and late stamps, a silent camera, an odometry jump: recorded as the runtime took
  // them (with their arrival), replayed the same.
  TempDir tmp;
  const Recorded a = record_lab(tmp / "rec", {"stamp_disorder:0@1+3", "stamp_late:1@2+2", "camera_stop:2@3+2", "odom_jump@5"});
  EXPECT_GT(a.summary.input.odometry_out_of_order, 0u);
  expect_same(a, replay(tmp / "rec"));
}

TEST(Recording, TheRecorderRefusesAFolderInUseAndCountsDrops) {
  TempDir tmp;
  tmp.write("used.txt", "x");
  EXPECT_THROW(Recorder(tmp.path(), builtin_profile("dual")), Error);
  // A queue of one frame that does not wait: a burst of frames is dropped and counted, never blocks.
  RecorderSettings s;
  s.queue_frames = 1;
  Recorder r(tmp / "rec", builtin_profile("dual"), s);
  StampedRgbd f;
  f.image.width = 640;
  f.image.height = 480;
  f.image.depth.assign(640 * 480, 1000);
  for (int i = 0; i < 50; ++i) {
    f.stamp_s = 0.01 * i;
    r.frame(0, f, f.stamp_s);
  }
  r.close();
  const RecorderStats st = r.stats();
  EXPECT_EQ(st.frames_recorded + st.frames_dropped, 50u);
  EXPECT_GT(st.frames_dropped, 0u);
  EXPECT_TRUE(st.error.empty()) << st.error;
  EXPECT_THROW(r.frame(3, f, 0.0), Error);  // no such sensor
}

class MalformedRecording : public ::testing::Test {
 protected:
  void SetUp() override { (void)record_lab(tmp_ / "rec", {}, 4.0); }
  std::filesystem::path dir() const { return tmp_ / "rec"; }
  void replace_line(const std::filesystem::path& file, int line, const std::string& text) {
    std::istringstream in(read_text(file));
    std::string out, l;
    for (int n = 1; std::getline(in, l); ++n) out += (n == line ? text : l) + "\n";
    std::ofstream(file, std::ios::binary) << out;
  }
  /// read_recording (and the replay, which reads the images) fails with a message containing `what`.
  void expect_error(const std::string& what) {
    try {
      (void)replay(dir());
      ADD_FAILURE() << "no error; expected one mentioning " << what;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  }
  TempDir tmp_;
};

TEST_F(MalformedRecording, MissingMetadata) {
  std::filesystem::remove(dir() / "recording.yaml");
  expect_error("recording.yaml");
}

TEST_F(MalformedRecording, NotARecording) {
  std::ofstream(dir() / "recording.yaml") << "format: something-else\nversion: 1\n";
  expect_error("not a duet recording");
}

TEST_F(MalformedRecording, OdometryArrivalGoesBack) {
  replace_line(dir() / "odometry.txt", 4, "0.1 0 0 0 0 0 0.01");
  expect_error("odometry.txt:4");
}

TEST_F(MalformedRecording, NonFiniteStamp) {
  replace_line(dir() / "kinect_front" / "depth.txt", 3, "nan depth/000001.png 1");
  expect_error("depth.txt:3");
}

TEST_F(MalformedRecording, WrongFieldCount) {
  replace_line(dir() / "odometry.txt", 2, "0.02 1 2");
  expect_error("odometry.txt:2");
}

TEST_F(MalformedRecording, MissingDepthFile) {
  std::filesystem::remove(dir() / "kinect_right" / "depth" / "000002.png");
  expect_error("000002.png");
}

TEST_F(MalformedRecording, CorruptPng) {
  std::ofstream(dir() / "kinect_front" / "depth" / "000001.png", std::ios::binary) << "not a png at all";
  expect_error("000001.png");
}

TEST_F(MalformedRecording, DepthOfTheWrongSize) {
  cv_write_small_png(dir() / "kinect_front" / "depth" / "000003.png");
  expect_error("000003.png");
}

}  // namespace test_recording
}  // namespace duet
