// SolidIndex: the chassis's collision test through a grid of the world's solids gives exactly
// sim::collides()'s answers (random discs, fixed seed; edges, heights, bad input).
#include <duet/kernels/error.hpp>
#include <duet/sim/solid_index.hpp>
#include <duet/sim/world.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <random>
#include <string>

namespace test_solid_index {

using duet::sim::SolidIndex;
using duet::sim::World;

// Random discs over the floor and a margin around it; radii from 0 to 2 m; three height ranges.
void expect_same_answers(const World& w, float cell_m, std::uint32_t seed, int n) {
  const SolidIndex index(w, cell_m);
  std::mt19937 rng(seed);
  const Eigen::Vector2f lo = w.floor.min - Eigen::Vector2f(1.0f, 1.0f), hi = w.floor.max + Eigen::Vector2f(1.0f, 1.0f);
  std::uniform_real_distribution<float> ux(lo.x(), hi.x()), uy(lo.y(), hi.y()), ur(0.0f, 2.0f);
  const float heights[3][2] = {{0.0f, 0.6f}, {0.3f, 0.4f}, {2.0f, 9.0f}};
  int hits = 0, misses = 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2f c(ux(rng), uy(rng));
    const float r = i % 7 == 0 ? 0.0f : ur(rng) * (i % 3 == 0 ? 0.15f : 1.0f);
    const auto& z = heights[i % 3];
    const bool want = duet::sim::collides(w, c, r, z[0], z[1]);
    ASSERT_EQ(index.collides(w, c, r, z[0], z[1]), want) << w.name << " cell " << cell_m << ": disc " << i << " at (" << c.x() << ", "
                                                         << c.y() << ") r " << r << " z [" << z[0] << ", " << z[1] << "]";
    (want ? hits : misses) += 1;
  }
  // Both answers occur, so the comparison can fail either way.
  EXPECT_GT(hits, n / 20) << w.name;
  EXPECT_GT(misses, n / 20) << w.name;
}

TEST(SolidIndex, AnswersAsCollidesOnTheLab) {
  const World lab = duet::sim::builtin_world("lab");
  for (const float cell : {1.0f, 0.05f, 0.37f, 50.0f}) expect_same_answers(lab, cell, 11, 20000);
}

TEST(SolidIndex, AnswersAsCollidesOnARealBuildingMap) {
  const std::filesystem::path map = std::filesystem::path(DUET_DATA_DIR) / "maps/willow-2010-02-18-0.10.yaml";
  if (!std::filesystem::exists(map)) GTEST_SKIP() << map << " is absent";
  const World willow = duet::sim::world_from_map(map);
  ASSERT_GT(willow.solids.size(), 500u);  // thousands of wall rectangles: what the index is for
  expect_same_answers(willow, 1.0f, 12, 20000);
}

TEST(SolidIndex, EdgesNonFiniteAndTheWrongWorld) {
  const World lab = duet::sim::builtin_world("lab");
  const SolidIndex index(lab);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const Eigen::Vector2f mid = 0.5f * (lab.floor.min + lab.floor.max);
  for (const Eigen::Vector2f& c : {Eigen::Vector2f(nan, 0.0f), Eigen::Vector2f(inf, inf), lab.floor.min, lab.floor.max, mid})
    for (const float r : {0.0f, 0.2f, nan, inf, 1e30f})
      EXPECT_EQ(index.collides(lab, c, r, 0.0f, 0.6f), duet::sim::collides(lab, c, r, 0.0f, 0.6f)) << c.transpose() << " r " << r;
  const World other = duet::sim::builtin_world("lab");
  EXPECT_THROW((void)index.collides(other, mid, 0.2f, 0.0f, 0.6f), duet::Error);
  for (const float bad : {0.0f, -1.0f, nan, 1e9f}) EXPECT_THROW(SolidIndex(lab, bad), duet::Error) << bad;
}

}  // namespace test_solid_index
