// ObservationModel beyond the reference comparisons (test_observation.cpp): update_grid equals a
// fresh set_grid and rebuilds only the changed tiles, the model owns its data and moves, one and
// two threads give the same bytes, invalid settings and sizes are errors, an obstacle nearer than
// the min range blocks the ray. Helpers: observation_test_util.hpp.
#include "observation_test_util.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <span>
#include <vector>

namespace duet {
namespace test_observation {

// ---- update_grid -----------------------------------------------------------------------------------

void expect_same_observations(const ObservationModel& a, const ObservationModel& b, const std::vector<Pose2>& poses,
                              const std::vector<SensorSector>& sensors) {
  std::vector<RayObservation> x(poses.size() * 60), y(x.size());
  a.observe(poses, sensors, x);
  b.observe(poses, sensors, y);
  for (std::size_t i = 0; i < x.size(); ++i) {
    ASSERT_EQ(x[i].hit, y[i].hit) << i;
    ASSERT_EQ(x[i].cells, y[i].cells) << i;
    ASSERT_EQ(x[i].entropy_bits, y[i].entropy_bits) << i;
    ASSERT_EQ(x[i].range_m, y[i].range_m) << i;
  }
}

TEST(ObservationModel, UpdateGridRebuildsOnlyChangedTiles) {
  TestGrid g = room_grid();  // 100 x 90, tile 8: 13 x 12 tiles
  for (const auto& [ix, iy] : {std::pair{35, 35}, {39, 36}, {39, 39}, {30, 30}, {43, 43}, {44, 43}, {24, 21}})
    g.at(ix, iy) = -2.0f;  // free before the steps below (the clutter is random)
  const auto poses = random_poses(g, 200, 31, false, 0.3f);
  const auto sensors = paper_dual_sensors(30);
  for (const auto b : kBackends) {
    TestGrid cur = g;
    ObservationModel m(settings_for(b, 8));
    m.set_grid(cur.view());
    if (b == ObservationBackend::kEmbree) {
      EXPECT_EQ(m.tiles_x(), 13);
      EXPECT_EQ(m.tiles_y(), 12);
    }
    const bool emb = b == ObservationBackend::kEmbree;
    struct Step {
      std::vector<std::pair<int, int>> cells;
      float value;
      std::size_t tiles;  // expected rebuilt tiles (Embree)
    };
    const std::vector<Step> steps = {
        {{{35, 35}}, kOcc, 1},                  // inside tile (4, 4)
        {{{35, 35}}, kFree, 1},                 // back
        {{{39, 36}}, kOcc, 2},                  // on the east edge of tile (4, 4): its face in tile (5, 4)
        {{{39, 39}}, kOcc, 3},                  // a tile corner: (4,4), (5,4), (4,5)
        {{{30, 30}}, kNaN, 0},                  // free -> unknown: entropy changes, geometry doesn't
        {{{30, 30}}, 0.3f, 0},                  // unknown-ish: no change of occupancy
        {{{43, 43}, {44, 43}, {90, 5}}, kOcc, 2},  // two cells in tile (5,5); one outside the room
        {{}, 0.0f, 0},                          // no change
        {{{24, 21}}, kOcc, 2},                  // west edge of tile (3, 2): its face in tile (2, 2)
    };
    for (std::size_t k = 0; k < steps.size(); ++k) {
      for (const auto& [ix, iy] : steps[k].cells) cur.at(ix, iy) = steps[k].value;
      const std::size_t rebuilt = m.update_grid(cur.view());
      if (emb) {
        EXPECT_EQ(rebuilt, steps[k].tiles) << "step " << k;
      } else {
        EXPECT_EQ(rebuilt, 0u) << "step " << k;
      }
      ObservationModel fresh(settings_for(b, 8));
      fresh.set_grid(cur.view());
      expect_same_observations(m, fresh, poses, sensors);
      ASSERT_EQ(m.entropy().size(), fresh.entropy().size());
      EXPECT_TRUE(std::equal(m.entropy().begin(), m.entropy().end(), fresh.entropy().begin()));
      EXPECT_TRUE(std::equal(m.states().begin(), m.states().end(), fresh.states().begin()));
    }
    // A different geometry falls back to a full rebuild.
    TestGrid other(30, 20, 0.05f, Eigen::Vector2f(0.0f, 0.0f), kOcc);
    const std::size_t rebuilt = m.update_grid(other.view());
    EXPECT_EQ(rebuilt, emb ? 4u * 3u : 0u);
    EXPECT_EQ(m.grid().width, 30);
    ObservationModel fresh(settings_for(b, 8));
    fresh.set_grid(other.view());
    expect_same_observations(m, fresh, poses, sensors);
  }
}

TEST(ObservationModel, OwnsItsDataAndMoves) {
  TestGrid g = wall_grid();
  ObservationModel m(settings_for(ObservationBackend::kEmbree));
  m.set_grid(g.view());
  const auto poses = random_poses(g, 30, 1, false);
  const auto sensors = paper_dual_sensors(30);
  std::vector<RayObservation> before(poses.size() * 60), after(before.size());
  m.observe(poses, sensors, before);
  std::fill(g.lo.begin(), g.lo.end(), kNaN);  // the caller's buffer changes; the model keeps its copy
  EXPECT_EQ(m.grid().logodds[0], kFree);
  ObservationModel moved(std::move(m));
  moved.observe(poses, sensors, after);
  for (std::size_t i = 0; i < before.size(); ++i) ASSERT_EQ(before[i].entropy_bits, after[i].entropy_bits);
  EXPECT_DUET_ERROR(m.observe(poses, sensors, after), ErrorCode::kInvalidArgument, "moved");  // NOLINT(bugprone-use-after-move)
  ObservationModel other;
  other = std::move(moved);
  other.observe(poses, sensors, after);
  for (std::size_t i = 0; i < before.size(); ++i) ASSERT_EQ(before[i].range_m, after[i].range_m);
}

// ---- threads, errors -----------------------------------------------------------------------------

TEST(ObservationModel, SameResultWithOneAndTwoThreads) {
  const TestGrid g = room_grid();
  const auto poses = random_poses(g, 300, 77, false, 0.5f);
  const auto sensors = paper_dual_sensors(30);
  for (const auto b : kBackends) {
    auto run = [&](int threads) {
      return test::in_arena(threads, [&] {
        ObservationModel m(settings_for(b, 8));
        m.set_grid(g.view());
        std::vector<RayObservation> out(poses.size() * 60);
        m.observe(poses, sensors, out);
        std::vector<float> flat;
        for (const auto& r : out) {
          flat.push_back(r.entropy_bits);
          flat.push_back(r.range_m);
          flat.push_back(static_cast<float>(r.cells) + (r.hit ? 0.5f : 0.0f));
        }
        std::vector<Eigen::Vector2f> o(500), d(500);
        for (std::size_t i = 0; i < o.size(); ++i) {
          o[i] = Eigen::Vector2f(poses[i % poses.size()].x, poses[i % poses.size()].y);
          d[i] = Eigen::Vector2f(std::cos(0.01f * static_cast<float>(i)), std::sin(0.01f * static_cast<float>(i)));
        }
        std::vector<RayHit> hits(o.size());
        m.cast(o, d, 0.1f, 3.0f, hits);
        for (const auto& h : hits) {
          flat.push_back(h.range_m);
          flat.push_back(h.hit ? 1.0f : 0.0f);
        }
        return flat;
      });
    };
    EXPECT_TRUE(test::bitwise_equal(run(1), run(2))) << name_of(b);
  }
}

TEST(ObservationModel, InvalidSettingsAndSizesThrow) {
  ObservationSettings s;
  s.tile_cells = 0;
  EXPECT_DUET_ERROR(ObservationModel{s}, ErrorCode::kInvalidArgument, "tile_cells");
  s = {};
  s.thresholds.free_logodds = 1.0f;  // above occupied
  EXPECT_DUET_ERROR(ObservationModel{s}, ErrorCode::kInvalidArgument, "CellThresholds");
  s = {};
  s.backend = static_cast<ObservationBackend>(7);
  EXPECT_DUET_ERROR(ObservationModel{s}, ErrorCode::kInvalidArgument, "backend");

  for (const auto b : kBackends) {
    ObservationModel m(settings_for(b));
    const TestGrid g = wall_grid();
    m.set_grid(g.view());
    std::vector<float> lo(10);
    EXPECT_DUET_ERROR(m.set_grid(GridView(lo, 4, 3, 0.05f, Eigen::Vector2f::Zero())), ErrorCode::kInvalidArgument, "grid");
    EXPECT_DUET_ERROR(m.update_grid(GridView(lo, 5, 2, -1.0f, Eigen::Vector2f::Zero())), ErrorCode::kInvalidArgument,
                      "resolution");
    const auto sensors = paper_dual_sensors(30);
    const std::vector<Pose2> poses(3);
    std::vector<RayObservation> out(179);
    EXPECT_DUET_ERROR(m.observe(poses, sensors, out), ErrorCode::kInvalidArgument, "out");
    out.resize(180);
    EXPECT_NO_THROW(m.observe(poses, sensors, out));
    EXPECT_DUET_ERROR(m.observe(poses, std::span<const SensorSector>(), out), ErrorCode::kInvalidArgument, "sensors");
    auto bad_sensors = sensors;
    bad_sensors[1].rays = -1;
    EXPECT_DUET_ERROR(m.observe(poses, bad_sensors, out), ErrorCode::kInvalidArgument, "rays");
    const std::vector<Pose2> nan_pose{Pose2{kNaN, 0.0f, 0.0f}};
    std::vector<RayObservation> out60(60);
    EXPECT_DUET_ERROR(m.observe(nan_pose, sensors, out60), ErrorCode::kInvalidArgument, "pose");
    EXPECT_NO_THROW(m.observe(std::span<const Pose2>(), sensors, std::span<RayObservation>()));

    std::vector<Eigen::Vector2f> o(4, Eigen::Vector2f(0, 0)), d(4, Eigen::Vector2f(1, 0));
    std::vector<RayHit> h(4), h3(3);
    EXPECT_DUET_ERROR(m.cast(o, d, 0.0f, 1.0f, h3), ErrorCode::kInvalidArgument, "same size");
    EXPECT_DUET_ERROR(m.cast(o, d, 2.0f, 1.0f, h), ErrorCode::kInvalidArgument, "t0");
    EXPECT_DUET_ERROR(m.cast(o, d, -1.0f, 1.0f, h), ErrorCode::kInvalidArgument, "t0");
    EXPECT_DUET_ERROR(m.cast(o, d, 0.0f, test::kInf, h), ErrorCode::kInvalidArgument, "t1");
    d[2] = Eigen::Vector2f(2, 0);
    EXPECT_DUET_ERROR(m.cast(o, d, 0.0f, 1.0f, h), ErrorCode::kInvalidArgument, "unit");
    d[2] = Eigen::Vector2f(1, 0);
    o[3] = Eigen::Vector2f(kNaN, 0);
    EXPECT_DUET_ERROR(m.cast(o, d, 0.0f, 1.0f, h), ErrorCode::kInvalidArgument, "origin");
    // Finite but beyond the map frame (Embree refuses rays with origins beyond ~1.8e18 by an
    // assertion in Debian's build: found by fuzz_capi); poses and sensor mounts alike.
    o[3] = Eigen::Vector2f(3e38f, 0);
    EXPECT_DUET_ERROR(m.cast(o, d, 0.0f, 1.0f, h), ErrorCode::kInvalidArgument, "origin");
    const std::vector<Pose2> far_pose{Pose2{0.0f, -3e38f, 0.0f}};
    EXPECT_DUET_ERROR(m.observe(far_pose, sensors, out60), ErrorCode::kOutOfRange, "pose 0");
    auto far_mount = sensors;
    far_mount[0].x_m = 3e38f;
    EXPECT_DUET_ERROR(m.observe(poses, far_mount, out), ErrorCode::kInvalidArgument, "x_m");
    EXPECT_NO_THROW(m.observe(std::vector<Pose2>{Pose2{9999.0f, -9999.0f, 1e30f}}, sensors, out60));
    // The work budget: 100000 rays of 100 m on a 5 cm grid at 300 poses would walk 1.2e12 cells.
    std::vector<SensorSector> wide(1);
    wide[0].rays = 100000;
    wide[0].max_range_m = 100.0f;
    const std::vector<Pose2> many(300);
    std::vector<RayObservation> big(300 * 100000);
    EXPECT_DUET_ERROR(m.observe(many, wide, big), ErrorCode::kInvalidArgument, "cell visits per call");
  }
}

}  // namespace test_observation
}  // namespace duet

namespace duet {
namespace test_observation {
// A wall nearer than the min range (0.3 m ahead, min range 0.5 m): the sensor sees nothing, with
// both backends; the wall 0.55 m ahead is seen.
TEST(ObservationModel, ObstacleNearerThanMinRangeBlocksTheRay) {
  TestGrid g(100, 100, 0.05f, Eigen::Vector2f(0.0f, 0.0f), kNaN);
  for (int iy = 0; iy < 100; ++iy) g.at(56, iy) = kOcc;  // x in [2.80, 2.85)
  SensorSector fwd;
  fwd.rays = 5;
  fwd.fov_rad = 0.2f;
  for (const auto b : kBackends) {
    ObservationModel m(settings_for(b, 16));
    m.set_grid(g.view());
    std::vector<RayObservation> out(5);
    const Pose2 near_wall{2.5f, 2.5f, 0.0f};  // wall 0.3 m ahead
    m.observe(std::span<const Pose2>(&near_wall, 1), std::span<const SensorSector>(&fwd, 1), out);
    for (const auto& r : out) {
      EXPECT_TRUE(r.hit);
      EXPECT_EQ(r.cells, 0);
      EXPECT_EQ(r.entropy_bits, 0.0f);
      EXPECT_NEAR(r.range_m, 0.3f, 0.02f);
    }
    const Pose2 farther{2.25f, 2.5f, 0.0f};  // wall 0.55 m ahead: observed, cells from 0.5 m on
    m.observe(std::span<const Pose2>(&farther, 1), std::span<const SensorSector>(&fwd, 1), out);
    for (const auto& r : out) {
      EXPECT_TRUE(r.hit);
      EXPECT_GE(r.cells, 1);
      EXPECT_NEAR(r.range_m, 0.55f, 0.01f);
    }
  }
}
}  // namespace test_observation
}  // namespace duet
