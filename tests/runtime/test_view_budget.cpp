// ViewBudget (navigation/view_budget.hpp): the looking stops once a window of looking only
// added less than the minimum known area.
#include <duet/runtime/navigation/view_budget.hpp>

#include <gtest/gtest.h>

namespace {

constexpr double kCellM2 = 0.05 * 0.05;  // 5 cm cells
constexpr std::size_t kCellsPerM2 = 400;

TEST(ViewBudget, NoBudgetAlwaysAllows) {
  duet::ViewBudget b(0.0f, 600.0f);
  for (double t = 0.0; t < 10000.0; t += 100.0) {
    EXPECT_FALSE(b.counts_at(t));
    EXPECT_TRUE(b.allows(t, 0, kCellM2));
  }
  EXPECT_TRUE(b.note().empty());
}

TEST(ViewBudget, AWindowWithoutGainSpendsItAndSaysWhy) {
  duet::ViewBudget b(5.0f, 600.0f);
  EXPECT_TRUE(b.counts_at(100.0));  // the first look begins a window
  EXPECT_TRUE(b.allows(100.0, 10000, kCellM2));
  EXPECT_TRUE(b.in_window());
  EXPECT_FALSE(b.counts_at(699.0));
  EXPECT_TRUE(b.allows(699.0, 0, kCellM2));  // within the window the count is not read
  EXPECT_TRUE(b.counts_at(700.0));
  // 4.9 m^2 in 600 s: less than 5.
  EXPECT_FALSE(b.allows(700.0, 10000 + 49 * kCellsPerM2 / 10, kCellM2));
  EXPECT_NE(b.note().find("added 4.9 m^2 in the last 600 s (view_min_gain_m2 5.0)"), std::string::npos) << b.note();
  EXPECT_FALSE(b.counts_at(800.0));
  EXPECT_FALSE(b.allows(800.0, 1000000, kCellM2)) << "a spent budget stays spent while nothing is reachable";
}

TEST(ViewBudget, AWindowWithGainBeginsTheNext) {
  duet::ViewBudget b(5.0f, 600.0f);
  ASSERT_TRUE(b.allows(0.0, 1000, kCellM2));
  ASSERT_TRUE(b.allows(600.0, 1000 + 5 * kCellsPerM2, kCellM2));  // exactly 5 m^2: enough
  EXPECT_FALSE(b.counts_at(1199.0)) << "the next window began at 600 s";
  EXPECT_FALSE(b.allows(1200.0, 1000 + 5 * kCellsPerM2 + 10, kCellM2)) << "the next window is judged on its own gain";
}

TEST(ViewBudget, AReachableFrontierEndsThePhaseAndTheNextLookBeginsAWindow) {
  duet::ViewBudget b(5.0f, 600.0f);
  ASSERT_TRUE(b.allows(0.0, 1000, kCellM2));
  b.frontier_reachable();
  EXPECT_FALSE(b.in_window());
  EXPECT_TRUE(b.counts_at(700.0));
  EXPECT_TRUE(b.allows(700.0, 1000, kCellM2)) << "no gain since 0 s, but the window began with this phase";
  EXPECT_FALSE(b.counts_at(1299.0));
  EXPECT_FALSE(b.allows(1300.0, 1000, kCellM2));
}

TEST(ViewBudget, LooksAlternatingWithFrontierGoalsAreNeverJudged) {
  // What the rule does with a tail that alternates looks with short frontier goals (every 30 s,
  // 0.05 m^2 each): no window of looking only lasts 600 s, so the budget is never spent - the
  // frontier goals' own end (blacklisting) has to end such a tail.
  duet::ViewBudget b(5.0f, 600.0f);
  std::size_t known = 50000;
  for (int i = 0; i < 240; ++i) {
    const double t = 1000.0 + 30.0 * i;
    if (i % 2 == 1) {
      b.frontier_reachable();
      known += 20;
      continue;
    }
    ASSERT_TRUE(b.allows(t, known, kCellM2)) << "at " << t << " s: " << b.note();
  }
}

TEST(ViewBudget, AReachableFrontierRenewsASpentBudget) {
  duet::ViewBudget b(5.0f, 600.0f);
  ASSERT_TRUE(b.allows(0.0, 1000, kCellM2));
  ASSERT_FALSE(b.allows(600.0, 1000, kCellM2));
  b.frontier_reachable();
  EXPECT_TRUE(b.note().empty());
  EXPECT_FALSE(b.in_window());
  EXPECT_TRUE(b.counts_at(610.0)) << "the next look begins a fresh window";
  EXPECT_TRUE(b.allows(610.0, 1000, kCellM2));
  EXPECT_FALSE(b.allows(1210.0, 1000, kCellM2));
}

}  // namespace
