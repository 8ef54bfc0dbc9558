// entropy_bits (paper Eq. 5) vs the formula evaluated in double, its limits (NaN, +-inf, +-100,
// 0), and grid_entropy vs a serial loop (sizes, errors, thread counts).
#include "kernel_test_util.hpp"

#include <duet/kernels/entropy.hpp>
#include <duet/kernels/error.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace duet {
namespace test_entropy {

using test::kInf;
using test::kNaN;

// Eq. (5) exactly as written, in double (0 log 0 = 0).
double eq5(double l) {
  const double p = 1.0 - 1.0 / (1.0 + std::exp(l));
  auto term = [](double x) { return x > 0.0 ? -x * std::log2(x) : 0.0; };
  return term(p) + term(1.0 - p);
}

TEST(EntropyBits, MatchesEq5InDouble) {
  for (double l = -30.0; l <= 30.0; l += 0.01) {
    const float lf = static_cast<float>(l);
    const double want = eq5(static_cast<double>(lf));
    const float got = entropy_bits(lf);
    // The naive double formula itself loses relative precision for |l| > ~20 (1 - p rounds),
    // so compare absolutely there.
    EXPECT_NEAR(got, want, std::fabs(lf) < 15.0f ? 2e-6 * want + 1e-7 : 1e-6) << "l = " << lf;
  }
}

TEST(EntropyBits, Limits) {
  EXPECT_FLOAT_EQ(entropy_bits(0.0f), 1.0f);   // p = 0.5
  EXPECT_FLOAT_EQ(entropy_bits(-0.0f), 1.0f);
  EXPECT_EQ(entropy_bits(kNaN), 1.0f);         // unknown: 1 bit (§3.1)
  EXPECT_EQ(entropy_bits(-kNaN), 1.0f);
  EXPECT_EQ(entropy_bits(kInf), 0.0f);         // p = 1
  EXPECT_EQ(entropy_bits(-kInf), 0.0f);        // p = 0
  for (float l : {100.0f, -100.0f, 1e30f, -1e30f, 88.0f, -88.0f, std::numeric_limits<float>::max()}) {
    const float e = entropy_bits(l);
    EXPECT_FALSE(std::isnan(e)) << l;
    EXPECT_GE(e, 0.0f) << l;
    EXPECT_LT(e, 1e-30f) << l;
  }
  // Symmetric, and strictly decreasing in |l| where float can resolve it.
  float prev = 1.0f;
  for (float l = 0.25f; l < 40.0f; l += 0.25f) {
    EXPECT_EQ(entropy_bits(l), entropy_bits(-l)) << l;
    EXPECT_LT(entropy_bits(l), prev) << l;
    prev = entropy_bits(l);
  }
  // One hit of the default grid update (p = 0.7): H(0.7) = 0.881290899 bits.
  EXPECT_NEAR(entropy_bits(std::log(0.7f / 0.3f)), 0.8812909f, 1e-6f);
}

std::vector<float> random_logodds(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-8.0f, 8.0f);
  std::uniform_int_distribution<int> pick(0, 9);
  std::vector<float> v(n);
  for (auto& x : v) {
    const int k = pick(rng);
    x = k < 3 ? kNaN : k == 3 ? (pick(rng) < 5 ? kInf : -kInf) : u(rng);
  }
  return v;
}

TEST(GridEntropy, MatchesLoopAndThreadCounts) {
  const int w = 517, h = 203;  // not a multiple of the block size
  const auto lo = random_logodds(static_cast<std::size_t>(w) * h, 7);
  const GridView g(lo, w, h, 0.05f, Eigen::Vector2f(-3.0f, 2.0f));
  std::vector<float> want(lo.size());
  for (std::size_t i = 0; i < lo.size(); ++i) want[i] = entropy_bits(lo[i]);
  std::vector<float> got1(lo.size(), -1.0f), got2(lo.size(), -2.0f);
  test::in_arena(1, [&] { grid_entropy(g, got1); });
  test::in_arena(2, [&] { grid_entropy(g, got2); });
  EXPECT_TRUE(test::bitwise_equal(got1, want));
  EXPECT_TRUE(test::bitwise_equal(got2, want));
  // Spot-check against Eq. (5) itself.
  for (std::size_t i = 0; i < lo.size(); i += 97)
    EXPECT_NEAR(got1[i], std::isnan(lo[i]) ? 1.0 : eq5(lo[i]), 1e-6) << i;
}

TEST(GridEntropy, EmptyTinyAndErrors) {
  std::vector<float> none;
  EXPECT_NO_THROW(grid_entropy(GridView(none, 0, 0, 0.05f, Eigen::Vector2f::Zero()), std::span<float>()));
  std::vector<float> one{kNaN};
  std::vector<float> out(1, 0.0f);
  grid_entropy(GridView(one, 1, 1, 0.05f, Eigen::Vector2f::Zero()), out);
  EXPECT_EQ(out[0], 1.0f);

  std::vector<float> lo(12, 0.0f), small(11);
  const GridView g(lo, 4, 3, 0.05f, Eigen::Vector2f::Zero());
  EXPECT_DUET_ERROR(grid_entropy(g, small), ErrorCode::kInvalidArgument, "cell_count");
  const GridView bad(lo, 5, 3, 0.05f, Eigen::Vector2f::Zero());  // 15 != 12
  std::vector<float> out15(15);
  EXPECT_DUET_ERROR(grid_entropy(bad, out15), ErrorCode::kInvalidArgument, "grid");
  const GridView badres(lo, 4, 3, 0.0f, Eigen::Vector2f::Zero());
  std::vector<float> out12(12);
  EXPECT_DUET_ERROR(grid_entropy(badres, out12), ErrorCode::kInvalidArgument, "resolution");
  // Every planning kernel's view obeys the map frame's limits (grid.hpp; validate(GridView)).
  EXPECT_DUET_ERROR(grid_entropy(GridView(lo, 4, 3, 1e-30f, Eigen::Vector2f::Zero()), out12), ErrorCode::kInvalidArgument, "resolution");
  EXPECT_DUET_ERROR(grid_entropy(GridView(lo, 4, 3, 101.0f, Eigen::Vector2f::Zero()), out12), ErrorCode::kInvalidArgument, "resolution");
  EXPECT_DUET_ERROR(grid_entropy(GridView(lo, 4, 3, 0.05f, Eigen::Vector2f(3e4f, 0.0f)), out12), ErrorCode::kOutOfRange, "origin");
  EXPECT_NO_THROW(grid_entropy(GridView(lo, 4, 3, kMinGridResolutionM, Eigen::Vector2f(-1.5e4f, 1.5e4f)), out12));
}

}  // namespace test_entropy
}  // namespace duet
