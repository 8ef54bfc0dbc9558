// extract_orb: a wrapper of cv::ORB, checked against cv::ORB itself on real Kinect frames (every
// kept feature is one of OpenCV's, with its descriptor), the bucketing's spread, determinism across
// runs and thread counts, RGB / BGR / RGBA / strided views, blank, tiny and null images, and
// named errors for bad views and settings.
#include "kernels/kernel_test_util.hpp"

#include <duet/kernels/orb.hpp>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include <set>

namespace duet {
namespace test_orb {

ColorImageView view_of(const cv::Mat& bgr) {
  ColorImageView v;
  v.data = bgr.data;
  v.width = bgr.cols;
  v.height = bgr.rows;
  v.row_stride_bytes = bgr.step[0];
  v.channels = bgr.channels();
  v.bgr = true;
  return v;
}

TEST(Orb, GrayMatchesOpenCv) {
  DUET_REQUIRE_DATA("rgbd/slambook2_ch5/color/1.png");
  const auto f = test::load_slambook_frame(1);
  std::vector<std::uint8_t> gray;
  to_gray(view_of(f.color), gray);
  cv::Mat ref;
  cv::cvtColor(f.color, ref, cv::COLOR_BGR2GRAY);
  ASSERT_EQ(gray.size(), static_cast<std::size_t>(ref.total()));
  int worst = 0;
  for (std::size_t i = 0; i < gray.size(); ++i) worst = std::max(worst, std::abs(int(gray[i]) - int(ref.data[i])));
  EXPECT_LE(worst, 1);
}

TEST(Orb, EveryFeatureIsOneOfOpenCvsWithItsDescriptor) {
  DUET_REQUIRE_DATA("rgbd/slambook2_ch5/color/1.png");
  for (int frame = 1; frame <= 5; ++frame) {
    const auto f = test::load_slambook_frame(frame);
    OrbSettings s;
    OrbFeatures got;
    extract_orb(view_of(f.color), s, got);
    ASSERT_GE(got.size(), 500u) << "frame " << frame;
    ASSERT_LE(got.size(), static_cast<std::size_t>(s.max_features));
    ASSERT_EQ(got.descriptors.size(), got.size());
    ASSERT_EQ(got.responses.size(), got.size());
    ASSERT_EQ(got.octaves.size(), got.size());
    // The reference: cv::ORB on OpenCV's grey image with the wrapper's budget.
    std::vector<std::uint8_t> gray;
    to_gray(view_of(f.color), gray);
    const cv::Mat g(f.color.rows, f.color.cols, CV_8UC1, gray.data());
    std::vector<cv::KeyPoint> kp;
    cv::Mat desc;
    cv::ORB::create(2 * s.max_features, s.scale_factor, s.levels, s.edge_threshold, 0, 2, cv::ORB::HARRIS_SCORE, 31, s.fast_threshold)
        ->detectAndCompute(g, cv::noArray(), kp, desc);
    std::map<std::tuple<float, float, int>, int> index;
    for (std::size_t i = 0; i < kp.size(); ++i) index[{kp[i].pt.x, kp[i].pt.y, kp[i].octave}] = static_cast<int>(i);
    for (std::size_t i = 0; i < got.size(); ++i) {
      const auto it = index.find({got.pixels[i].x(), got.pixels[i].y(), int(got.octaves[i])});
      ASSERT_NE(it, index.end()) << "feature " << i << " is not one of cv::ORB's";
      EXPECT_EQ(std::memcmp(desc.ptr(it->second), got.descriptors[i].data(), 32), 0) << "feature " << i;
      EXPECT_EQ(got.responses[i], kp[static_cast<std::size_t>(it->second)].response);
      if (i > 0) {
        EXPECT_GE(got.responses[i - 1], got.responses[i]) << "not sorted by response at " << i;
      }
      EXPECT_GE(got.pixels[i].x(), 0.0f);
      EXPECT_LT(got.pixels[i].x(), 640.0f);
      EXPECT_GE(got.pixels[i].y(), 0.0f);
      EXPECT_LT(got.pixels[i].y(), 480.0f);
    }
  }
}

TEST(Orb, BucketingSpreadsFeaturesWiderThanTheStrongestN) {
  DUET_REQUIRE_DATA("rgbd/slambook2_ch5/color/1.png");
  const auto f = test::load_slambook_frame(1);
  OrbSettings s;
  s.max_features = 300;
  OrbFeatures got;
  extract_orb(view_of(f.color), s, got);
  // The strongest 300 of cv::ORB's own selection, no bucketing.
  std::vector<cv::KeyPoint> kp;
  cv::Mat gray;
  cv::cvtColor(f.color, gray, cv::COLOR_BGR2GRAY);
  cv::ORB::create(300)->detect(gray, kp);
  auto cells = [&](auto&& pixel_of, std::size_t n) {
    std::set<int> c;
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector2f p = pixel_of(i);
      c.insert(static_cast<int>(p.y() / 80.0f) * 8 + static_cast<int>(p.x() / 80.0f));
    }
    return c.size();
  };
  const auto ours = cells([&](std::size_t i) { return got.pixels[i]; }, got.size());
  const auto plain = cells([&](std::size_t i) { return Eigen::Vector2f(kp[i].pt.x, kp[i].pt.y); }, kp.size());
  EXPECT_GT(ours, plain) << "bucketed cells " << ours << ", plain " << plain;
}

TEST(Orb, DeterministicAcrossRunsThreadsAndChannelOrders) {
  DUET_REQUIRE_DATA("rgbd/slambook2_ch5/color/2.png");
  const auto f = test::load_slambook_frame(2);
  OrbFeatures a, b, c, d, e;
  test::in_arena(1, [&] { extract_orb(view_of(f.color), {}, a); });
  test::in_arena(4, [&] { extract_orb(view_of(f.color), {}, b); });
  EXPECT_TRUE(test::bitwise_equal(a.pixels, b.pixels));
  EXPECT_TRUE(test::bitwise_equal(a.descriptors, b.descriptors));
  // The same pixels as RGB, and as strided RGBA.
  cv::Mat rgb, rgba;
  cv::cvtColor(f.color, rgb, cv::COLOR_BGR2RGB);
  cv::cvtColor(f.color, rgba, cv::COLOR_BGR2RGBA);
  ColorImageView v = view_of(rgb);
  v.bgr = false;
  extract_orb(v, {}, c);
  cv::Mat padded(rgba.rows, rgba.cols + 7, CV_8UC4, cv::Scalar(9, 9, 9, 9));
  rgba.copyTo(padded(cv::Rect(0, 0, rgba.cols, rgba.rows)));
  ColorImageView w = view_of(padded);
  w.width = rgba.cols;
  w.bgr = false;
  extract_orb(w, {}, d);
  EXPECT_TRUE(test::bitwise_equal(a.pixels, c.pixels));
  EXPECT_TRUE(test::bitwise_equal(a.descriptors, c.descriptors));
  EXPECT_TRUE(test::bitwise_equal(a.pixels, d.pixels));
  EXPECT_TRUE(test::bitwise_equal(a.descriptors, d.descriptors));
  extract_orb(view_of(f.color), {}, e);
  EXPECT_TRUE(test::bitwise_equal(a.descriptors, e.descriptors));
}

TEST(Orb, BlankTinyAndMissingImagesGiveNoFeatures) {
  OrbFeatures out;
  cv::Mat blank(480, 640, CV_8UC3, cv::Scalar(120, 130, 140));
  extract_orb(view_of(blank), {}, out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(out.width, 640);
  cv::Mat tiny(20, 30, CV_8UC3);
  cv::randu(tiny, 0, 255);
  extract_orb(view_of(tiny), {}, out);
  EXPECT_TRUE(out.empty());
  extract_orb(ColorImageView{}, {}, out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(out.width, 0);
  // Random noise has corners everywhere: max_features is respected.
  cv::Mat noise(480, 640, CV_8UC3);
  cv::theRNG().state = 7;
  cv::randu(noise, 0, 255);
  OrbSettings s;
  s.max_features = 123;
  extract_orb(view_of(noise), s, out);
  EXPECT_EQ(out.size(), 123u);
}

TEST(Orb, BadViewsAndSettingsAreNamed) {
  cv::Mat img(100, 100, CV_8UC3, cv::Scalar(0, 0, 0));
  OrbFeatures out;
  auto expect = [&](const ColorImageView& v, const OrbSettings& s, const std::string& what) {
    try {
      extract_orb(v, s, out);
      ADD_FAILURE() << "no error for " << what;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  ColorImageView v = view_of(img);
  ColorImageView bad = v;
  bad.channels = 2;
  expect(bad, {}, "channels");
  bad = v;
  bad.width = 0;
  expect(bad, {}, "size");
  bad = v;
  bad.row_stride_bytes = 10;
  expect(bad, {}, "row stride");
  OrbSettings s;
  s.max_features = 0;
  expect(v, s, "max_features");
  s = {};
  s.scale_factor = 1.0f;
  expect(v, s, "scale_factor");
  s = {};
  s.scale_factor = test::kNaN;
  expect(v, s, "scale_factor");
  s = {};
  s.levels = 0;
  expect(v, s, "levels");
  s = {};
  s.min_fast_threshold = 30;
  expect(v, s, "min_fast_threshold");
  s = {};
  s.grid_cols = 0;
  expect(v, s, "grid_cols");
}

}  // namespace test_orb
}  // namespace duet
