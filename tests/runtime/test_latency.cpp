// LatencyStats (runtime/robot/latency.hpp) against a plain reference (every sample kept and
// sorted): exact while it keeps every sample, within its 1 % bins once past kExactSamples
// (memory bounded over a run of days), and the edge cases (none, NaN, negative, 0, huge).
#include <duet/runtime/robot/latency.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace {

struct Reference {
  std::vector<double> v;
  double rank(double q) const {
    std::vector<double> s = v;
    std::sort(s.begin(), s.end());
    const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(s.size())));
    return s[std::clamp<std::size_t>(k, 1, s.size()) - 1];
  }
  std::size_t above(double t) const { return static_cast<std::size_t>(std::count_if(v.begin(), v.end(), [t](double x) { return x > t; })); }
  std::size_t within(double lo, double hi) const {
    return static_cast<std::size_t>(std::count_if(v.begin(), v.end(), [&](double x) { return x >= lo && x <= hi; }));
  }
};

}  // namespace

TEST(LatencyStats, EmptyAndInvalidSamples) {
  duet::LatencyStats s;
  const duet::LatencySummary e = s.summary();
  EXPECT_EQ(e.count, 0u);
  EXPECT_EQ(e.p50_s, 0.0);
  EXPECT_EQ(e.p99_s, 0.0);
  EXPECT_EQ(e.max_s, 0.0);
  EXPECT_EQ(e.mean_s, 0.0);
  EXPECT_EQ(s.count_above(0.0), 0u);
  for (const double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(), -1.0, -0.0 - 1e-300})
    s.add(bad);
  EXPECT_EQ(s.size(), 0u);
  s.add(0.0);
  EXPECT_EQ(s.summary().count, 1u);
  EXPECT_EQ(s.summary().p99_s, 0.0);
}

TEST(LatencyStats, ExactWhileEverySampleIsKept) {
  std::mt19937 rng(11);
  std::lognormal_distribution<double> d(std::log(0.002), 0.8);
  duet::LatencyStats s;
  Reference ref;
  for (int i = 0; i < 5000; ++i) {
    const double x = d(rng);
    s.add(x);
    ref.v.push_back(x);
  }
  ASSERT_TRUE(s.exact());
  const duet::LatencySummary r = s.summary();
  EXPECT_EQ(r.count, 5000u);
  EXPECT_EQ(r.p50_s, ref.rank(0.50));
  EXPECT_EQ(r.p99_s, ref.rank(0.99));
  EXPECT_EQ(r.max_s, *std::max_element(ref.v.begin(), ref.v.end()));
  double sum = 0.0;
  for (const double x : ref.v) sum += x;
  EXPECT_NEAR(r.mean_s, sum / 5000.0, 1e-12);
  for (const double t : {0.0, 0.001, 0.002, 0.01, 1.0}) EXPECT_EQ(s.count_above(t), ref.above(t)) << t;
}

TEST(LatencyStats, BoundedPastTheExactSamplesAndWithinABin) {
  std::mt19937 rng(12);
  std::lognormal_distribution<double> d(std::log(0.05), 0.3);  // a control period around 50 ms
  duet::LatencyStats s;
  Reference ref;
  const std::size_t n = duet::LatencyStats::kExactSamples * 3 + 17;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = i == 1000 ? 0.0 : i == 2000 ? 5e4 : d(rng);  // 0 and a huge one: the end bins
    s.add(x);
    ref.v.push_back(x);
  }
  EXPECT_FALSE(s.exact());
  const duet::LatencySummary r = s.summary();
  EXPECT_EQ(r.count, n);
  EXPECT_EQ(r.max_s, 5e4);
  double sum = 0.0;
  for (const double x : ref.v) sum += x;
  EXPECT_NEAR(r.mean_s, sum / static_cast<double>(n), 1e-9 * sum / static_cast<double>(n));
  // Percentiles: within half a bin (0.5 %) of the exact ones.
  EXPECT_NEAR(r.p50_s, ref.rank(0.50), 0.006 * ref.rank(0.50));
  EXPECT_NEAR(r.p99_s, ref.rank(0.99), 0.006 * ref.rank(0.99));
  // count_above: exact but for the samples within t's 1 % bin.
  for (const double t : {0.0, 0.03, 0.05, 0.055, 0.1, 1.0, 1e5}) {
    const double slack = static_cast<double>(ref.within(t / 1.011, t * 1.011)) + 1.0;
    EXPECT_NEAR(static_cast<double>(s.count_above(t)), static_cast<double>(ref.above(t)), slack) << t;
  }
  EXPECT_EQ(s.count_above(5e4), 0u);
}
