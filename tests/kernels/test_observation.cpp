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
#include "kernel_test_util.hpp"
#include "embree_config.hpp"

#include <duet/kernels/entropy.hpp>
#include <duet/kernels/error.hpp>
#include <duet/kernels/observation.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace duet {
namespace test_observation {

using test::kNaN;
constexpr double kDInf = std::numeric_limits<double>::infinity();
constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kFree = -3.0f, kOcc = 3.0f;
// Rays passing closer than ambiguous_m() to a cell corner [m] (or starting this close to a grid
// line, or crossing one this close to their end) may legitimately visit either side cell (float
// rounding of the crossing times, Embree's float quads at world coordinates): not compared.
// 1e-7 m for the walk (in double); for Embree 2e-6 m plus ~2 ulp of the largest coordinate.
double ambiguous_m(ObservationBackend b, double max_coord) {
  return b == ObservationBackend::kDda ? 1e-7 : 2e-6 + 2.5e-7 * max_coord;
}

// Range tolerance [m]: the walk is set up in double (1e-4 is generous); Embree intersects float
// quads at world coordinates (ulp 4e-6 m at 60 m), which moves a crossing by ~1e-5 m / |dir
// component|.
double range_tol(ObservationBackend b, const Eigen::Vector2f& d) {
  if (b == ObservationBackend::kDda) return 1e-4;
  return 1e-4 + 1e-5 / std::max(std::min(std::fabs(d.x()), std::fabs(d.y())), 1e-3f);
}

// ---- references ----------------------------------------------------------------------------------

struct RefCell {
  int ix, iy;
  double te, tx;
};
struct RefWalk {
  std::vector<RefCell> cells;
  double corner_gap = kDInf;  ///< min |t_x - t_y| over the crossings made [m], or the distance to a
                              ///< grid line the ray runs along (axis-parallel rays)
};

// Exact Amanatides-Woo in double. `stop(cell)` returning true ends the walk after that cell.
template <class Stop>
RefWalk reference_walk(const GridView& g, const Eigen::Vector2f& of, const Eigen::Vector2f& df, float t0f, float t1f,
                       Stop&& stop) {
  RefWalk w;
  const double t0 = t0f, t1 = t1f, res = g.resolution_m;
  if (!(t1 >= t0)) return w;
  const Eigen::Vector2d o = of.cast<double>(), d = df.cast<double>(), org = g.origin.cast<double>();
  const Eigen::Vector2d p = (o + t0 * d - org) / res;
  int ix = d.x() < 0 ? static_cast<int>(std::ceil(p.x())) - 1 : static_cast<int>(std::floor(p.x()));
  int iy = d.y() < 0 ? static_cast<int>(std::ceil(p.y())) - 1 : static_cast<int>(std::floor(p.y()));
  const int sx = d.x() > 0 ? 1 : d.x() < 0 ? -1 : 0, sy = d.y() > 0 ? 1 : d.y() < 0 ? -1 : 0;
  w.corner_gap = std::min(w.corner_gap, res * std::min(std::fabs(p.x() - std::round(p.x())), std::fabs(p.y() - std::round(p.y()))));
  double t = t0;
  for (int guard = 0; guard < 1000000; ++guard) {
    const double tx = sx > 0 ? (org.x() + (ix + 1) * res - o.x()) / d.x()
                      : sx < 0 ? (org.x() + ix * res - o.x()) / d.x()
                               : kDInf;
    const double ty = sy > 0 ? (org.y() + (iy + 1) * res - o.y()) / d.y()
                      : sy < 0 ? (org.y() + iy * res - o.y()) / d.y()
                               : kDInf;
    const double tn = std::min(tx, ty);
    w.cells.push_back({ix, iy, t, std::min(tn, t1)});
    if (stop(ix, iy)) break;
    w.corner_gap = std::min(w.corner_gap, std::fabs(tn - t1));  // a crossing at the very end
    if (tn >= t1) break;
    if (std::isfinite(tx) && std::isfinite(ty))  // distance from the corner to the ray [m]
      w.corner_gap = std::min(w.corner_gap, std::fabs(tx - ty) * std::fabs(d.x() * d.y()));
    t = tn;
    if (tx < ty) ix += sx;
    else if (ty < tx) iy += sy;
    else {
      ix += sx;
      iy += sy;
    }
  }
  return w;
}
RefWalk reference_walk(const GridView& g, const Eigen::Vector2f& o, const Eigen::Vector2f& d, float t0, float t1) {
  return reference_walk(g, o, d, t0, t1, [](int, int) { return false; });
}

double eq5(float l) {
  if (std::isnan(l)) return 1.0;
  const double p = 1.0 - 1.0 / (1.0 + std::exp(static_cast<double>(l)));
  auto term = [](double x) { return x > 0.0 ? -x * std::log2(x) : 0.0; };
  return term(p) + term(1.0 - p);
}

struct RefObs {
  double entropy = 0.0, range = 0.0, corner_gap = kDInf;
  bool hit = false;
  int cells = 0;
};

RefObs reference_observe(const GridView& g, const CellThresholds& th, const Eigen::Vector2f& o, const Eigen::Vector2f& d,
                         float t0, float t1, bool blocked_before_t0 = true) {
  auto value = [&](int ix, int iy) { return g.in_bounds(ix, iy) ? g.logodds[g.index(ix, iy)] : kNaN; };
  // A known obstacle in a cell left at or before the min range t0 blocks the ray (every cell of
  // the walk over [0, t0] but the last, which reaches t0 and is observed).
  if (blocked_before_t0 && t0 > 0.0f) {
    const RefWalk pre = reference_walk(g, o, d, 0.0f, t0);
    for (std::size_t i = 0; i + 1 < pre.cells.size(); ++i)
      if (classify(value(pre.cells[i].ix, pre.cells[i].iy), th) == CellState::kOccupied) {
        RefObs r;
        r.hit = true;
        r.range = pre.cells[i].te;
        r.corner_gap = pre.corner_gap;
        return r;
      }
  }
  const RefWalk w = reference_walk(g, o, d, t0, t1,
                                   [&](int ix, int iy) { return classify(value(ix, iy), th) == CellState::kOccupied; });
  RefObs r;
  r.range = t1;
  r.corner_gap = w.corner_gap;
  for (const auto& c : w.cells) {
    r.entropy += eq5(value(c.ix, c.iy));
    ++r.cells;
    if (classify(value(c.ix, c.iy), th) == CellState::kOccupied) {
      r.hit = true;
      r.range = c.te;
    }
  }
  return r;
}

// ---- grids ---------------------------------------------------------------------------------------

struct TestGrid {
  std::vector<float> lo;
  int w = 0, h = 0;
  float res = 0.05f;
  Eigen::Vector2f origin{0.0f, 0.0f};
  TestGrid() = default;
  TestGrid(int w_, int h_, float res_, Eigen::Vector2f o, float fill)
      : lo(static_cast<std::size_t>(w_) * static_cast<std::size_t>(h_), fill), w(w_), h(h_), res(res_), origin(o) {}
  [[nodiscard]] GridView view() const { return GridView(lo, w, h, res, origin); }
  float& at(int ix, int iy) { return lo[static_cast<std::size_t>(iy) * static_cast<std::size_t>(w) + static_cast<std::size_t>(ix)]; }
};

TestGrid empty_grid() { return TestGrid(80, 60, 0.05f, Eigen::Vector2f(-2.0f, -1.5f), kFree); }
TestGrid wall_grid() {
  TestGrid g = empty_grid();
  for (int iy = 0; iy < g.h; ++iy) g.at(60, iy) = kOcc;  // x in [1.0, 1.05)
  return g;
}
// A 3 m x 2.5 m room (walls one cell thick), a 0.6 m door in the east wall, unknown outside,
// a partly unknown interior and some clutter with values near the thresholds.
TestGrid room_grid() {
  TestGrid g(100, 90, 0.05f, Eigen::Vector2f(-2.5f, -2.0f), kNaN);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-4.0f, 4.0f);
  for (int iy = 20; iy <= 70; ++iy)
    for (int ix = 20; ix <= 80; ++ix) {
      const bool wall = ix == 20 || ix == 80 || iy == 20 || iy == 70;
      const bool door = ix == 80 && iy >= 40 && iy < 52;
      g.at(ix, iy) = wall && !door ? kOcc : (ix > 60 && iy > 55 ? kNaN : -2.0f + 0.1f * u(rng));
    }
  for (int k = 0; k < 40; ++k) {  // clutter: occupied, unknown-ish, near thresholds
    std::uniform_int_distribution<int> cx(22, 78), cy(22, 68);
    const float v = k % 4 == 0 ? kOcc : k % 4 == 1 ? 0.6190392f : k % 4 == 2 ? 0.3f : kNaN;
    g.at(cx(rng), cy(rng)) = v;
  }
  return g;
}

std::vector<Pose2> random_poses(const TestGrid& g, int n, std::uint32_t seed, bool free_only, float margin = 1.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> ux(g.origin.x() - margin, g.origin.x() + static_cast<float>(g.w) * g.res + margin);
  std::uniform_real_distribution<float> uy(g.origin.y() - margin, g.origin.y() + static_cast<float>(g.h) * g.res + margin);
  std::uniform_real_distribution<float> ut(-kPi, kPi);
  std::vector<Pose2> poses;
  const GridView v = g.view();
  for (int guard = 0; static_cast<int>(poses.size()) < n && guard < 1000000; ++guard) {
    const Pose2 p{ux(rng), uy(rng), ut(rng)};
    if (free_only) {
      const Eigen::Vector2i c = v.cell_of(Eigen::Vector2f(p.x, p.y));
      if (!v.in_bounds(c.x(), c.y()) || !(v.logodds[v.index(c.x(), c.y())] <= -1.0f)) continue;
    }
    poses.push_back(p);
  }
  return poses;
}

// Willow Garage map, ROS map_server PGM (row 0 = top, negate 0: occupancy p = (255 - v) / 255).
// The data README calls it trinary (0 occupied, 254 free, 205 unknown), but the file is a greyscale
// map (GIMP-edited: 205 for unknown, values 0-254 elsewhere): 205 -> unknown (NaN), every other value
// -> log-odds of p clamped to [0.02, 0.98], so the test sees graded entropies too.
bool load_willow(TestGrid& g) {
  const std::string rel = "maps/willow-2010-02-18-0.10.pgm";
  if (!test::have_data(rel)) return false;
  const cv::Mat img = cv::imread(test::data_path(rel).string(), cv::IMREAD_UNCHANGED);
  if (img.empty()) return false;
  g = TestGrid(img.cols, img.rows, 0.10f, Eigen::Vector2f(0.0f, 0.0f), kNaN);
  for (int r = 0; r < img.rows; ++r)
    for (int c = 0; c < img.cols; ++c) {
      const int v = img.at<std::uint8_t>(r, c);
      const float p = std::clamp((255.0f - static_cast<float>(v)) / 255.0f, 0.02f, 0.98f);
      g.at(c, img.rows - 1 - r) = v == 205 ? kNaN : std::log(p / (1.0f - p));
    }
  return true;
}

// ---- comparisons ---------------------------------------------------------------------------------

struct CompareStats {
  std::size_t rays = 0, ambiguous = 0, hits = 0;
};

// The model's observations of `poses` x `sensors` vs the reference, ray by ray.
CompareStats expect_matches_reference(const ObservationModel& m, const TestGrid& g, const std::vector<Pose2>& poses,
                                      const std::vector<SensorSector>& sensors, const char* what) {
  std::size_t total = 0;
  for (const auto& s : sensors) total += static_cast<std::size_t>(s.rays);
  std::vector<RayObservation> out(poses.size() * total);
  m.observe(poses, sensors, out);
  CompareStats st;
  const GridView v = g.view();
  const double max_coord = std::max({std::fabs(g.origin.x()), std::fabs(g.origin.y()),
                                     std::fabs(g.origin.x() + static_cast<float>(g.w) * g.res),
                                     std::fabs(g.origin.y() + static_cast<float>(g.h) * g.res)}) + 6.0;
  const double amb = ambiguous_m(m.settings().backend, max_coord);
  int failures = 0;
  for (std::size_t p = 0; p < poses.size(); ++p) {
    std::size_t k = p * total;
    for (const auto& s : sensors) {
      std::vector<Eigen::Vector2f> o(static_cast<std::size_t>(s.rays)), d(o.size());
      sector_rays(poses[p], s, o, d);
      for (int r = 0; r < s.rays; ++r, ++k) {
        const RefObs ref = reference_observe(v, m.settings().thresholds, o[static_cast<std::size_t>(r)],
                                             d[static_cast<std::size_t>(r)], s.min_range_m, s.max_range_m);
        ++st.rays;
        st.hits += ref.hit ? 1 : 0;
        if (ref.corner_gap < amb) {
          ++st.ambiguous;
          continue;
        }
        const RayObservation& got = out[k];
        const bool ok = got.hit == ref.hit && got.cells == ref.cells &&
                        std::fabs(got.entropy_bits - ref.entropy) <= 1e-5 * std::max(1.0, ref.entropy) &&
                        std::fabs(got.range_m - ref.range) <= range_tol(m.settings().backend, d[static_cast<std::size_t>(r)]);
        if (!ok && ++failures <= 5)
          ADD_FAILURE() << what << ": pose " << p << " ray " << k - p * total << ": got (hit " << got.hit << ", cells "
                        << got.cells << ", bits " << got.entropy_bits << ", range " << got.range_m << ") want (hit "
                        << ref.hit << ", cells " << ref.cells << ", bits " << ref.entropy << ", range " << ref.range
                        << ")";
      }
    }
  }
  EXPECT_EQ(failures, 0) << what;
  EXPECT_LE(st.ambiguous * 20, st.rays) << what << ": too many rays near cell corners";
  return st;
}

// Ray directions of observe()'s output order.
std::vector<Eigen::Vector2f> all_dirs(const std::vector<Pose2>& poses, const std::vector<SensorSector>& sensors) {
  std::vector<Eigen::Vector2f> out;
  for (const auto& p : poses)
    for (const auto& s : sensors) {
      std::vector<Eigen::Vector2f> o(static_cast<std::size_t>(s.rays)), d(o.size());
      sector_rays(p, s, o, d);
      out.insert(out.end(), d.begin(), d.end());
    }
  return out;
}

ObservationSettings settings_for(ObservationBackend b, int tile = 64) {
  ObservationSettings s;
  s.backend = b;
  s.tile_cells = tile;
  return s;
}

constexpr ObservationBackend kBackends[] = {ObservationBackend::kDda, ObservationBackend::kEmbree};
const char* name_of(ObservationBackend b) { return b == ObservationBackend::kDda ? "dda" : "embree"; }

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
