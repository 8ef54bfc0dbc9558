// walk_cells, sector_rays and ObservationModel (both backends) vs references written here:
//  - an exact cell-crossing walk in double (crossing times recomputed from the cell boundaries at
//    every step) that also reports how close the ray passes to a cell corner (the only place where
//    float rounding may legitimately pick the other cell), and a dense-sampling check;
//  - a per-ray observation (Eq. 5 entropy in double, NaN/outside = 1 bit, stop at the first cell
//    classify() calls occupied, hit cell included) on top of that walk.
// (The sensors' sectors and heading_to_look(): test_sensor_sectors.cpp.)
// Grids: empty, one wall, a room with a door, all unknown, 1x1, 0x0, and the Willow Garage map
// (../shared/data/maps). Embree == DDA on random poses; update_grid == fresh set_grid with the
// expected number of rebuilt tiles; 1 vs 2 threads; invalid settings and sizes.
// The model's grid updates, moves, threads, errors and min range: test_observation_model.cpp.
#include "observation_test_util.hpp"
#include "embree_config.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace duet {
namespace test_observation {

// ---- walk_cells ----------------------------------------------------------------------------------

std::vector<RefCell> walk(const GridView& g, const Eigen::Vector2f& o, const Eigen::Vector2f& d, float t0, float t1) {
  std::vector<RefCell> v;
  walk_cells(g, o, d, t0, t1, [&](int ix, int iy, float te, float tx) {
    v.push_back({ix, iy, te, tx});
    return v.size() < 100000;
  });
  return v;
}

::testing::AssertionResult same_walk(const std::vector<RefCell>& got, const std::vector<RefCell>& want) {
  if (got.size() != want.size())
    return ::testing::AssertionFailure() << "visited " << got.size() << " cells, want " << want.size();
  for (std::size_t i = 0; i < got.size(); ++i) {
    if (got[i].ix != want[i].ix || got[i].iy != want[i].iy)
      return ::testing::AssertionFailure() << "cell " << i << ": (" << got[i].ix << "," << got[i].iy << ") want ("
                                           << want[i].ix << "," << want[i].iy << ")";
    if (std::fabs(got[i].te - want[i].te) > 1e-4 || std::fabs(got[i].tx - want[i].tx) > 1e-4)
      return ::testing::AssertionFailure() << "cell " << i << ": t [" << got[i].te << "," << got[i].tx << "] want ["
                                           << want[i].te << "," << want[i].tx << "]";
  }
  return ::testing::AssertionSuccess();
}

const GridView kWalkGeometry(std::span<const float>(), 40, 30, 0.05f, Eigen::Vector2f(-1.3f, 0.7f));

TEST(WalkCells, MatchesExactReferenceOnRandomRays) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> ux(-2.5f, 1.9f), uy(-0.5f, 3.4f), ua(-kPi, kPi), ut(0.0f, 1.0f), ul(0.0f, 4.0f);
  int ambiguous = 0, checked = 0;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector2f o(ux(rng), uy(rng));
    const float a = ua(rng);
    const Eigen::Vector2f d(std::cos(a), std::sin(a));
    const float t0 = i % 3 == 0 ? 0.0f : ut(rng);
    const float t1 = t0 + (i % 50 == 0 ? 0.0f : ul(rng));
    const RefWalk ref = reference_walk(kWalkGeometry, o, d, t0, t1);
    if (ref.corner_gap < ambiguous_m(ObservationBackend::kDda, 3.0)) {
      ++ambiguous;
      continue;
    }
    ++checked;
    ASSERT_TRUE(same_walk(walk(kWalkGeometry, o, d, t0, t1), ref.cells)) << "ray " << i;
  }
  EXPECT_LT(ambiguous, 1000);
  EXPECT_GT(checked, 19000);
}

TEST(WalkCells, DenseSamplesLieInTheVisitedCellsInOrder) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f), ua(-kPi, kPi);
  const GridView& g = kWalkGeometry;
  for (int i = 0; i < test::full_or(300, 40); ++i) {  // 300 rays x 28000 samples; fewer in Debug
    const Eigen::Vector2f o(u(rng), u(rng) + 1.5f);
    const float a = ua(rng);
    const Eigen::Vector2f d(std::cos(a), std::sin(a));
    const auto cells = walk(g, o, d, 0.2f, 3.0f);
    ASSERT_FALSE(cells.empty());
    EXPECT_EQ(cells.front().te, 0.2f);
    EXPECT_EQ(cells.back().tx, 3.0f);
    std::size_t at = 0;
    for (double t = 0.2; t <= 3.0; t += 1e-4) {
      const Eigen::Vector2d p = o.cast<double>() + t * d.cast<double>();
      const double fx = (p.x() - g.origin.x()) / g.resolution_m, fy = (p.y() - g.origin.y()) / g.resolution_m;
      if (std::fabs(fx - std::round(fx)) < 1e-3 || std::fabs(fy - std::round(fy)) < 1e-3) continue;  // on a boundary
      const int cx = static_cast<int>(std::floor(fx)), cy = static_cast<int>(std::floor(fy));
      while (at < cells.size() && (cells[at].ix != cx || cells[at].iy != cy)) ++at;
      ASSERT_LT(at, cells.size()) << "ray " << i << ": sample at t = " << t << " in cell (" << cx << "," << cy
                                  << ") not visited (in order)";
      EXPECT_GE(t, cells[at].te - 1e-4);
      EXPECT_LE(t, cells[at].tx + 1e-4);
    }
    for (std::size_t k = 1; k < cells.size(); ++k) {  // contiguous times, neighbouring cells
      EXPECT_EQ(cells[k].te, cells[k - 1].tx);
      EXPECT_LE(std::abs(cells[k].ix - cells[k - 1].ix) + std::abs(cells[k].iy - cells[k - 1].iy), 2);
    }
  }
}

TEST(WalkCells, AxisAlignedDiagonalOutsideZeroLength) {
  const GridView& g = kWalkGeometry;  // x in [-1.3, 0.7), y in [0.7, 2.2)
  // +x from outside the grid (left of it), along a row centre: every column, outside ones too.
  {
    const auto c = walk(g, Eigen::Vector2f(-1.49f, 0.725f), Eigen::Vector2f(1, 0), 0.0f, 2.5f);
    const auto ref = reference_walk(g, Eigen::Vector2f(-1.49f, 0.725f), Eigen::Vector2f(1, 0), 0.0f, 2.5f).cells;
    EXPECT_TRUE(same_walk(c, ref));
    ASSERT_EQ(c.size(), 51u);  // x from -1.49 to 1.01 (grid x from -1.3): cells -4 .. 46
    EXPECT_EQ(c.front().ix, -4);
    EXPECT_EQ(c.back().ix, 46);
    for (const auto& x : c) EXPECT_EQ(x.iy, 0);
  }
  // -y, -x (negative steps; origin exactly on a cell boundary: the lower cell comes first).
  for (const Eigen::Vector2f& d : {Eigen::Vector2f(0, -1), Eigen::Vector2f(-1, 0), Eigen::Vector2f(0, 1)}) {
    const Eigen::Vector2f o = g.origin + Eigen::Vector2f(10.0f * 0.05f, 10.0f * 0.05f) + Eigen::Vector2f(0.01f, 0.01f);
    EXPECT_TRUE(same_walk(walk(g, o, d, 0.0f, 1.3f), reference_walk(g, o, d, 0.0f, 1.3f).cells)) << d.transpose();
  }
  {
    const Eigen::Vector2f o(-1.3f + 0.5f, 1.2125f);  // x on the boundary between columns 9 and 10 (in float)
    const auto c = walk(g, o, Eigen::Vector2f(-1, 0), 0.0f, 0.12f);
    ASSERT_FALSE(c.empty());
    EXPECT_EQ(c.front().ix, g.cell_of(o).x() - 1);
    EXPECT_GT(c.front().tx, c.front().te);  // no zero-length first cell
  }
  // Exactly diagonal through corners: steps both axes at once, no zero-length side cells.
  {
    const GridView unit(std::span<const float>(), 8, 8, 1.0f, Eigen::Vector2f(0, 0));
    const float s = std::sqrt(0.5f);
    const auto c = walk(unit, Eigen::Vector2f(0.0f, 0.0f), Eigen::Vector2f(1.0f, 1.0f) * s * 1.0f, 0.0f, 5.0f);
    for (std::size_t k = 0; k < c.size(); ++k) {
      EXPECT_EQ(c[k].ix, c[k].iy) << k;
      EXPECT_GT(c[k].tx, c[k].te) << k;
    }
  }
  // Zero length: one cell; reversed, non-finite: nothing; callback false: stops.
  {
    const auto c = walk(g, Eigen::Vector2f(0.01f, 1.01f), Eigen::Vector2f(0.6f, 0.8f), 0.3f, 0.3f);
    ASSERT_EQ(c.size(), 1u);
    EXPECT_EQ(c[0].te, 0.3f);
    EXPECT_EQ(c[0].tx, 0.3f);
    const Eigen::Vector2i want = g.cell_of(Eigen::Vector2f(0.01f + 0.3f * 0.6f, 1.01f + 0.3f * 0.8f));
    EXPECT_EQ(c[0].ix, want.x());
    EXPECT_EQ(c[0].iy, want.y());
    EXPECT_TRUE(walk(g, Eigen::Vector2f(0, 1), Eigen::Vector2f(1, 0), 0.5f, 0.4f).empty());
    EXPECT_TRUE(walk(g, Eigen::Vector2f(kNaN, 1), Eigen::Vector2f(1, 0), 0.0f, 1.0f).empty());
    EXPECT_TRUE(walk(g, Eigen::Vector2f(0, 1), Eigen::Vector2f(1, 0), 0.0f, test::kInf).empty());
    int n = 0;
    walk_cells(g, Eigen::Vector2f(-1.29f, 0.71f), Eigen::Vector2f(1, 0), 0.0f, 1.0f, [&](int, int, float, float) {
      return ++n < 3;
    });
    EXPECT_EQ(n, 3);
  }
}

// ---- the model vs the reference ------------------------------------------------------------------

TEST(ObservationModel, HandMadeGridsMatchReference) {
  struct Case {
    const char* name;
    TestGrid g;
  };
  std::vector<Case> cases;
  cases.push_back({"empty", empty_grid()});
  cases.push_back({"wall", wall_grid()});
  cases.push_back({"room", room_grid()});
  cases.push_back({"unknown", TestGrid(50, 40, 0.05f, Eigen::Vector2f(-1.0f, -1.0f), kNaN)});
  cases.push_back({"1x1 occupied", TestGrid(1, 1, 0.5f, Eigen::Vector2f(0.3f, 0.1f), kOcc)});
  cases.push_back({"1x1 free", TestGrid(1, 1, 0.5f, Eigen::Vector2f(0.3f, 0.1f), kFree)});
  cases.push_back({"0x0", TestGrid(0, 0, 0.05f, Eigen::Vector2f(0.0f, 0.0f), 0.0f)});
  auto sensors = paper_dual_sensors(30);
  SensorSector wide;  // a full circle from the robot centre, min range 0: starts in the robot's cell
  wide.fov_rad = 2.0f * kPi;
  wide.min_range_m = 0.0f;
  wide.max_range_m = 3.0f;
  wide.rays = 37;
  sensors.push_back(wide);
  for (const auto& c : cases) {
    const auto poses = random_poses(c.g, 40, 17, false);
    for (const auto b : kBackends) {
      for (const int tile : {64, 7}) {
        if (b == ObservationBackend::kDda && tile != 64) continue;
        ObservationModel m(settings_for(b, tile));
        m.set_grid(c.g.view());
        const std::string what = std::string(c.name) + "/" + name_of(b) + "/tile " + std::to_string(tile);
        const auto st = expect_matches_reference(m, c.g, poses, sensors, what.c_str());
        if (std::string(c.name) == "wall" || std::string(c.name) == "room") {
          EXPECT_GT(st.hits, st.rays / 10) << what;
        }
        if (std::string(c.name) == "empty" || std::string(c.name) == "unknown") {
          EXPECT_EQ(st.hits, 0u) << what;
        }
      }
    }
  }
}

// A grid larger than the DDA's prefetching threshold (4 MiB of packed words: 1100 x 1100 cells),
// so observe() takes its prefetching path; rays from poses in and around the grid (prefetch
// points outside the grid are skipped): the same results as the reference.
TEST(ObservationModel, LargeGridWithPrefetchingMatchesReference) {
  TestGrid g(1100, 1100, 0.05f, Eigen::Vector2f(-3.0f, 2.0f), kFree);
  std::mt19937 rng(23);
  std::uniform_int_distribution<int> c(0, 1099), kind(0, 3);
  for (int k = 0; k < 60000; ++k) g.at(c(rng), c(rng)) = kind(rng) == 0 ? kOcc : kind(rng) == 1 ? kNaN : -0.3f;
  ObservationModel m(settings_for(ObservationBackend::kDda));
  m.set_grid(g.view());
  const auto st = expect_matches_reference(m, g, random_poses(g, 64, 29, false, 3.0f), paper_dual_sensors(30), "large");
  EXPECT_GT(st.hits, st.rays / 10);
  EXPECT_LT(st.hits, st.rays);
}

TEST(ObservationModel, KnownValues) {
  for (const auto b : kBackends) {
    // All unknown: every cell 1 bit, no hit, ranges = max range.
    const TestGrid unknown(50, 40, 0.05f, Eigen::Vector2f(-1.0f, -1.0f), kNaN);
    ObservationModel m(settings_for(b));
    m.set_grid(unknown.view());
    const auto sensors = paper_dual_sensors(30);
    std::vector<RayObservation> out(60);
    const Pose2 pose{0.1f, 0.2f, 0.4f};
    m.observe(std::span<const Pose2>(&pose, 1), sensors, out);
    double total = 0.0;
    for (const auto& r : out) {
      EXPECT_FALSE(r.hit);
      EXPECT_EQ(r.range_m, 5.0f);
      EXPECT_EQ(r.entropy_bits, static_cast<float>(r.cells));
      EXPECT_GE(r.cells, 90);   // 4.5 m at 0.05 m: at least 90 cells
      EXPECT_LE(r.cells, 181);  // and at most 2 * 90 + 1
      total += r.entropy_bits;
    }
    EXPECT_FLOAT_EQ(m.information_bits(pose, sensors), static_cast<float>(total));

    // Wall at x in [1.0, 1.05) (free elsewhere): the forward sensor's axis ray from (0.128, y)
    // hits it 0.99 m from the sensor origin (x = 0.01); entropy = cells * H(free) + H(occ).
    const TestGrid wall = wall_grid();
    m.set_grid(wall.view());
    SensorSector fwd;
    fwd.x_m = -0.118f;
    fwd.rays = 1;
    fwd.min_range_m = 0.0f;
    std::vector<RayObservation> one(1);
    const Pose2 p2{0.128f, 0.0125f, 0.0f};
    m.observe(std::span<const Pose2>(&p2, 1), std::span<const SensorSector>(&fwd, 1), one);
    EXPECT_TRUE(one[0].hit);
    EXPECT_NEAR(one[0].range_m, 0.99f, 1e-5f);
    EXPECT_EQ(one[0].cells, 21);  // x in [0.01, 1.05): 20 free cells + the wall cell
    EXPECT_NEAR(one[0].entropy_bits, 20.0f * entropy_bits(kFree) + entropy_bits(kOcc), 1e-5f);
    // A ray starting inside the wall hits at t0.
    const Pose2 p3{1.02f + 0.118f, 0.0125f, 0.0f};
    m.observe(std::span<const Pose2>(&p3, 1), std::span<const SensorSector>(&fwd, 1), one);
    EXPECT_TRUE(one[0].hit);
    EXPECT_EQ(one[0].range_m, 0.0f);
    EXPECT_EQ(one[0].cells, 1);
  }
}

TEST(ObservationModel, CastMatchesReference) {
  const TestGrid g = room_grid();
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> ux(-3.0f, 3.0f), ua(-kPi, kPi);
  std::vector<Eigen::Vector2f> o(3001), d(3001);
  for (std::size_t i = 0; i < o.size(); ++i) {  // 3001: not a multiple of the packet size
    o[i] = Eigen::Vector2f(ux(rng), ux(rng) - 0.5f);
    const float a = ua(rng);
    d[i] = Eigen::Vector2f(std::cos(a), std::sin(a));
  }
  o[0] = Eigen::Vector2f(-1.49f, 0.0f);  // inside the west wall (cells ix = 20: x in [-1.5, -1.45))
  d[0] = Eigen::Vector2f(1.0f, 0.0f);
  for (const auto b : kBackends) {
    ObservationModel m(settings_for(b, 16));
    m.set_grid(g.view());
    for (const auto& [t0, t1] : {std::pair{0.0f, 4.0f}, std::pair{0.3f, 2.0f}, std::pair{1.0f, 1.0f}}) {
      std::vector<RayHit> out(o.size());
      m.cast(o, d, t0, t1, out);
      int failures = 0, hits = 0;
      for (std::size_t i = 0; i < o.size(); ++i) {
        const RefObs ref = reference_observe(g.view(), m.settings().thresholds, o[i], d[i], t0, t1, false);  // cast: [t0, t1] only
        if (ref.corner_gap < ambiguous_m(b, 6.0)) continue;
        hits += ref.hit;
        if ((out[i].hit != ref.hit || std::fabs(out[i].range_m - ref.range) > range_tol(b, d[i])) && ++failures <= 5)
          ADD_FAILURE() << name_of(b) << " ray " << i << " t [" << t0 << "," << t1 << "]: got (" << out[i].hit << ", "
                        << out[i].range_m << ") want (" << ref.hit << ", " << ref.range << ")";
      }
      EXPECT_EQ(failures, 0);
      if (t1 > t0) {
        EXPECT_GT(hits, 100);
      }
      if (t0 == 0.0f) {
        EXPECT_TRUE(out[0].hit);
        EXPECT_EQ(out[0].range_m, 0.0f);
      }
    }
  }
}

TEST(ObservationModel, WillowMapMatchesReferenceAndBackendsAgree) {
  DUET_REQUIRE_DATA("maps/willow-2010-02-18-0.10.pgm");
  TestGrid g;
  ASSERT_TRUE(load_willow(g));
  ASSERT_EQ(g.w, 566);
  ASSERT_EQ(g.h, 608);
  const auto poses = random_poses(g, test::full_or(300, 60), 99, true, 0.0f);
  ASSERT_FALSE(poses.empty());
  const auto sensors = paper_dual_sensors(30);
  ObservationModel dda(settings_for(ObservationBackend::kDda)), emb(settings_for(ObservationBackend::kEmbree));
  dda.set_grid(g.view());
  emb.set_grid(g.view());
  const auto st = expect_matches_reference(dda, g, poses, sensors, "willow/dda");
  expect_matches_reference(emb, g, poses, sensors, "willow/embree");
  EXPECT_GT(st.hits, st.rays / 10);
  // Embree == DDA directly (every ray, not only those away from corners).
  std::vector<RayObservation> a(poses.size() * 60), b(a.size());
  dda.observe(poses, sensors, a);
  emb.observe(poses, sensors, b);
  const auto dirs = all_dirs(poses, sensors);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const bool same = a[i].hit == b[i].hit && a[i].cells == b[i].cells &&
                      std::fabs(a[i].entropy_bits - b[i].entropy_bits) <= 1e-5f * std::max(1.0f, a[i].entropy_bits) &&
                      std::fabs(a[i].range_m - b[i].range_m) <= range_tol(ObservationBackend::kEmbree, dirs[i]);
    differ += same ? 0 : 1;
  }
  EXPECT_LE(differ * 1000, a.size()) << differ << " of " << a.size() << " rays differ";
}

TEST(ObservationModel, EmbreeEqualsDdaOnRandomPoses) {
  const TestGrid g = room_grid();
  const auto poses = random_poses(g, 500, 5, false, 0.5f);
  const auto sensors = paper_dual_sensors(30);
  ObservationModel dda(settings_for(ObservationBackend::kDda)), emb(settings_for(ObservationBackend::kEmbree, 8));
  dda.set_grid(g.view());
  emb.set_grid(g.view());
  std::vector<RayObservation> a(poses.size() * 60), b(a.size());
  dda.observe(poses, sensors, a);
  emb.observe(poses, sensors, b);
  const auto dirs = all_dirs(poses, sensors);
  std::size_t differ = 0, hits = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    hits += a[i].hit;
    differ += (a[i].hit == b[i].hit && a[i].cells == b[i].cells && a[i].entropy_bits == b[i].entropy_bits &&
               std::fabs(a[i].range_m - b[i].range_m) <= range_tol(ObservationBackend::kEmbree, dirs[i]))
                  ? 0
                  : 1;
  }
  EXPECT_GT(hits, a.size() / 10);
  EXPECT_LE(differ * 1000, a.size()) << differ << " of " << a.size() << " rays differ";
}

// Embree's kernels (SSE, AVX2, AVX-512) and the CPU's vendor change the last bits of Embree's hit
// distances; the model computes the distance from the hit face itself (embree_device.hpp), so
// its observations are the same bytes with every kernel - and on every machine.
TEST(ObservationModel, EmbreeGivesTheSameBytesWithEveryKernel) {
  DUET_REQUIRE_DATA("maps/willow-2010-02-18-0.10.pgm");
  TestGrid g;
  ASSERT_TRUE(load_willow(g));
  const auto poses = random_poses(g, test::full_or(300, 60), 17, true, 0.0f);
  ASSERT_FALSE(poses.empty());
  const auto sensors = paper_dual_sensors(30);
  auto run = [&] {
    ObservationModel m(settings_for(ObservationBackend::kEmbree));
    m.set_grid(g.view());
    std::vector<RayObservation> out(poses.size() * 60);
    m.observe(poses, sensors, out);
    std::vector<float> flat;
    std::size_t hits = 0;
    for (const auto& r : out) {
      flat.push_back(r.entropy_bits);
      flat.push_back(r.range_m);
      flat.push_back(static_cast<float>(r.cells) + (r.hit ? 0.5f : 0.0f));
      hits += r.hit ? 1 : 0;
    }
    EXPECT_GT(hits, out.size() / 10);
    return flat;
  };
  const auto ref = duet_test::with_embree_config(duet_test::kEmbreeIsaConfigs[0], run);
  for (const char* config : duet_test::kEmbreeIsaConfigs)
    EXPECT_TRUE(test::bitwise_equal(ref, duet_test::with_embree_config(config, run))) << config;
}

}  // namespace test_observation
}  // namespace duet
