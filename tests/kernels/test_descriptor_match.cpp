// match_descriptors / match_descriptors_guided against a plain reference (nested loops with
// std::bitset counts) and OpenCV's BFMatcher(NORM_HAMMING, crossCheck), on seeded random
// descriptors and on real ORB features; empty inputs, bad arguments, thread-count independence.
#include "kernels/kernel_test_util.hpp"

#include <duet/kernels/descriptor_match.hpp>

#include <opencv2/features2d.hpp>

#include <bitset>
#include <random>

namespace duet {
namespace test_descriptor_match {

std::vector<Descriptor256> random_descriptors(std::size_t n, std::uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<Descriptor256> d(n);
  for (auto& x : d)
    for (auto& w : x) w = rng();
  return d;
}

/// `base` with `flips` random bits flipped (a noisy re-observation).
Descriptor256 perturb(const Descriptor256& base, int flips, std::mt19937_64& rng) {
  Descriptor256 d = base;
  for (int i = 0; i < flips; ++i) {
    const auto bit = rng() % 256;
    d[bit / 64] ^= (std::uint64_t{1} << (bit % 64));
  }
  return d;
}

int ref_distance(const Descriptor256& a, const Descriptor256& b) {
  int n = 0;
  for (int i = 0; i < 4; ++i) n += static_cast<int>(std::bitset<64>(a[i] ^ b[i]).count());
  return n;
}

/// The documented rule, written as directly as possible.
std::vector<DescriptorMatch> reference(const std::vector<Descriptor256>& q, const std::vector<Descriptor256>& t,
                                       const DescriptorMatchSettings& s,
                                       const std::function<bool(std::size_t, std::size_t)>& cand) {
  auto nearest = [&](const std::vector<Descriptor256>& from, std::size_t i, const std::vector<Descriptor256>& to,
                     bool forward, int& best, int& second) {
    best = 257, second = 257;
    std::size_t idx = SIZE_MAX;
    for (std::size_t j = 0; j < to.size(); ++j) {
      if (!(forward ? cand(i, j) : cand(j, i))) continue;
      const int d = ref_distance(from[i], to[j]);
      if (d < best) {
        second = best;
        best = d;
        idx = j;
      } else if (d < second) {
        second = d;
      }
    }
    return idx;
  };
  std::vector<DescriptorMatch> out;
  for (std::size_t i = 0; i < q.size(); ++i) {
    int best, second;
    const std::size_t j = nearest(q, i, t, true, best, second);
    if (j == SIZE_MAX || best > s.max_distance) continue;
    if (s.ratio < 1.0f && second <= 256 && !(static_cast<float>(best) < s.ratio * static_cast<float>(second))) continue;
    if (s.cross_check) {
      int b2, s2;
      if (nearest(t, j, q, false, b2, s2) != i) continue;
    }
    out.push_back({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j), static_cast<std::uint32_t>(best)});
  }
  return out;
}

TEST(DescriptorMatch, HammingDistanceMatchesBitsetCount) {
  const auto d = random_descriptors(200, 3);
  for (std::size_t i = 0; i + 1 < d.size(); ++i) EXPECT_EQ(hamming_distance(d[i], d[i + 1]), ref_distance(d[i], d[i + 1]));
  EXPECT_EQ(hamming_distance(d[0], d[0]), 0);
  Descriptor256 zero{}, ones{~0ull, ~0ull, ~0ull, ~0ull};
  EXPECT_EQ(hamming_distance(zero, ones), 256);
}

TEST(DescriptorMatch, BruteForceEqualsReferenceForEverySetting) {
  std::mt19937_64 rng(11);
  const auto train = random_descriptors(700, 5);
  std::vector<Descriptor256> query;
  for (std::size_t i = 0; i < 500; ++i) query.push_back(perturb(train[(i * 3) % train.size()], static_cast<int>(rng() % 90), rng));
  const auto extra = random_descriptors(200, 6);  // queries with no true partner
  query.insert(query.end(), extra.begin(), extra.end());
  for (const int max_d : {0, 40, 64, 256})
    for (const float ratio : {0.6f, 0.8f, 1.0f})
      for (const bool cross : {false, true}) {
        DescriptorMatchSettings s{max_d, ratio, cross};
        std::vector<DescriptorMatch> got;
        match_descriptors(query, train, s, got);
        const auto want = reference(query, train, s, [](std::size_t, std::size_t) { return true; });
        EXPECT_EQ(got, want) << "max " << max_d << " ratio " << ratio << " cross " << cross;
        if (max_d == 64 && ratio == 0.8f && cross) {
          EXPECT_GT(got.size(), 300u);
        }
      }
}

TEST(DescriptorMatch, CrossCheckEqualsOpenCvBFMatcher) {
  const auto train = random_descriptors(600, 21);
  std::mt19937_64 rng(22);
  std::vector<Descriptor256> query;
  for (std::size_t i = 0; i < 400; ++i) query.push_back(perturb(train[(i * 13) % train.size()], static_cast<int>(rng() % 120), rng));
  auto to_mat = [](const std::vector<Descriptor256>& d) {
    cv::Mat m(static_cast<int>(d.size()), 32, CV_8U);
    for (std::size_t i = 0; i < d.size(); ++i) std::memcpy(m.ptr(static_cast<int>(i)), d[i].data(), 32);
    return m;
  };
  std::vector<cv::DMatch> cv_matches;
  cv::BFMatcher(cv::NORM_HAMMING, true).match(to_mat(query), to_mat(train), cv_matches);
  std::vector<DescriptorMatch> got;
  match_descriptors(query, train, {256, 1.0f, true}, got);
  // BFMatcher breaks distance ties differently; compare where the nearest is unique.
  std::size_t compared = 0;
  for (const auto& m : cv_matches) {
    const auto it = std::find_if(got.begin(), got.end(), [&](const DescriptorMatch& g) { return g.query == static_cast<std::uint32_t>(m.queryIdx); });
    int ties = 0;
    for (const auto& t : train) ties += hamming_distance(query[static_cast<std::size_t>(m.queryIdx)], t) == static_cast<int>(m.distance) ? 1 : 0;
    if (ties != 1) continue;
    ASSERT_NE(it, got.end()) << "query " << m.queryIdx;
    EXPECT_EQ(it->train, static_cast<std::uint32_t>(m.trainIdx));
    EXPECT_EQ(it->distance, static_cast<std::uint32_t>(m.distance));
    ++compared;
  }
  EXPECT_GT(compared, 300u);
  EXPECT_LE(got.size(), cv_matches.size() + 5);
}

TEST(DescriptorMatch, GuidedEqualsReferenceWithWindows) {
  std::mt19937_64 rng(31);
  const auto train = random_descriptors(400, 32);
  std::vector<Eigen::Vector2f> train_px(train.size());
  std::uniform_real_distribution<float> U(0.0f, 640.0f);
  for (auto& p : train_px) p = {U(rng), U(rng) * 0.75f};
  std::vector<Descriptor256> query;
  std::vector<Eigen::Vector2f> predicted;
  for (std::size_t i = 0; i < 300; ++i) {
    const std::size_t j = (i * 3) % train.size();
    query.push_back(perturb(train[j], static_cast<int>(rng() % 60), rng));
    predicted.push_back(i % 17 == 0 ? Eigen::Vector2f(test::kNaN, test::kNaN)
                                    : Eigen::Vector2f(train_px[j] + Eigen::Vector2f(U(rng) / 40.0f, U(rng) / 40.0f)));
  }
  for (const float r : {5.0f, 20.0f, 80.0f}) {
    DescriptorMatchSettings s;
    std::vector<DescriptorMatch> got;
    match_descriptors_guided(query, predicted, train, train_px, r, s, got);
    const auto want = reference(query, train, s, [&](std::size_t i, std::size_t j) {
      return (predicted[i] - train_px[j]).squaredNorm() <= r * r;
    });
    EXPECT_EQ(got, want) << "radius " << r;
    for (const auto& m : got) EXPECT_NE(m.query % 17, 0u) << "a NaN prediction matched";
  }
}

TEST(DescriptorMatch, SameResultForAnyThreadCount) {
  const auto train = random_descriptors(900, 41);
  std::mt19937_64 rng(42);
  std::vector<Descriptor256> query;
  for (std::size_t i = 0; i < 900; ++i) query.push_back(perturb(train[(i * 5) % train.size()], static_cast<int>(rng() % 80), rng));
  std::vector<DescriptorMatch> one, two, many;
  test::in_arena(1, [&] { match_descriptors(query, train, {}, one); });
  test::in_arena(2, [&] { match_descriptors(query, train, {}, two); });
  test::in_arena(8, [&] { match_descriptors(query, train, {}, many); });
  EXPECT_EQ(one, two);
  EXPECT_EQ(one, many);
  EXPECT_FALSE(one.empty());
}

TEST(DescriptorMatch, EmptyAndTinyInputs) {
  const auto d = random_descriptors(3, 51);
  std::vector<DescriptorMatch> out{{1, 2, 3}};
  match_descriptors({}, d, {}, out);
  EXPECT_TRUE(out.empty());
  match_descriptors(d, {}, {}, out);
  EXPECT_TRUE(out.empty());
  // One train descriptor: no second best, the ratio test passes.
  match_descriptors(std::span(d).first(1), std::span(d).first(1), {}, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], (DescriptorMatch{0, 0, 0}));
  std::vector<Eigen::Vector2f> px(1, Eigen::Vector2f(10, 10));
  match_descriptors_guided({}, {}, {}, {}, 5.0f, {}, out);
  EXPECT_TRUE(out.empty());
  match_descriptors_guided(std::span(d).first(1), px, std::span(d).first(1), px, 5.0f, {}, out);
  EXPECT_EQ(out.size(), 1u);
}

TEST(DescriptorMatch, BadArgumentsAreNamed) {
  const auto d = random_descriptors(4, 61);
  std::vector<Eigen::Vector2f> px(4, Eigen::Vector2f::Zero()), short_px(3, Eigen::Vector2f::Zero());
  std::vector<DescriptorMatch> out;
  const auto expect = [](const std::function<void()>& fn, const std::string& what) { test::expect_error(fn, what); };
  expect([&] { match_descriptors(d, d, {300, 0.8f, true}, out); }, "max_distance");
  expect([&] { match_descriptors(d, d, {64, 0.0f, true}, out); }, "ratio");
  expect([&] { match_descriptors(d, d, {64, test::kNaN, true}, out); }, "ratio");
  expect([&] { match_descriptors_guided(d, short_px, d, px, 5.0f, {}, out); }, "predicted");
  expect([&] { match_descriptors_guided(d, px, d, short_px, 5.0f, {}, out); }, "train pixels");
  expect([&] { match_descriptors_guided(d, px, d, px, 0.0f, {}, out); }, "radius_px");
  expect([&] { match_descriptors_guided(d, px, d, px, test::kNaN, {}, out); }, "radius_px");
}

}  // namespace test_descriptor_match
}  // namespace duet
