#pragma once
// Helpers shared by the observation tests (test_observation.cpp, test_observation_model.cpp): an
// exact cell-crossing walk in double and a per-ray reference observation on top of it, test grids
// (empty, a wall, a room with a door, the Willow Garage map), and the model-against-reference
// comparison.
#include "kernel_test_util.hpp"

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
inline constexpr double kDInf = std::numeric_limits<double>::infinity();
inline constexpr float kPi = std::numbers::pi_v<float>;
inline constexpr float kFree = -3.0f, kOcc = 3.0f;
// Rays passing closer than ambiguous_m() to a cell corner [m] (or starting this close to a grid
// line, or crossing one this close to their end) may legitimately visit either side cell (float
// rounding of the crossing times, Embree's float quads at world coordinates): not compared.
// 1e-7 m for the walk (in double); for Embree 2e-6 m plus ~2 ulp of the largest coordinate.
inline double ambiguous_m(ObservationBackend b, double max_coord) {
  return b == ObservationBackend::kDda ? 1e-7 : 2e-6 + 2.5e-7 * max_coord;
}

// Range tolerance [m]: the walk is set up in double (1e-4 is generous); Embree intersects float
// quads at world coordinates (ulp 4e-6 m at 60 m), which moves a crossing by ~1e-5 m / |dir
// component|.
inline double range_tol(ObservationBackend b, const Eigen::Vector2f& d) {
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
inline RefWalk reference_walk(const GridView& g, const Eigen::Vector2f& of, const Eigen::Vector2f& df, float t0f, float t1f,
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
inline RefWalk reference_walk(const GridView& g, const Eigen::Vector2f& o, const Eigen::Vector2f& d, float t0, float t1) {
  return reference_walk(g, o, d, t0, t1, [](int, int) { return false; });
}

inline double eq5(float l) {
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

inline RefObs reference_observe(const GridView& g, const CellThresholds& th, const Eigen::Vector2f& o, const Eigen::Vector2f& d,
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

inline TestGrid empty_grid() { return TestGrid(80, 60, 0.05f, Eigen::Vector2f(-2.0f, -1.5f), kFree); }
inline TestGrid wall_grid() {
  TestGrid g = empty_grid();
  for (int iy = 0; iy < g.h; ++iy) g.at(60, iy) = kOcc;  // x in [1.0, 1.05)
  return g;
}
// A 3 m x 2.5 m room (walls one cell thick), a 0.6 m door in the east wall, unknown outside,
// a partly unknown interior and some clutter with values near the thresholds.
inline TestGrid room_grid() {
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

inline std::vector<Pose2> random_poses(const TestGrid& g, int n, std::uint32_t seed, bool free_only, float margin = 1.0f) {
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
inline bool load_willow(TestGrid& g) {
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
inline CompareStats expect_matches_reference(const ObservationModel& m, const TestGrid& g, const std::vector<Pose2>& poses,
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
inline std::vector<Eigen::Vector2f> all_dirs(const std::vector<Pose2>& poses, const std::vector<SensorSector>& sensors) {
  std::vector<Eigen::Vector2f> out;
  for (const auto& p : poses)
    for (const auto& s : sensors) {
      std::vector<Eigen::Vector2f> o(static_cast<std::size_t>(s.rays)), d(o.size());
      sector_rays(p, s, o, d);
      out.insert(out.end(), d.begin(), d.end());
    }
  return out;
}

inline ObservationSettings settings_for(ObservationBackend b, int tile = 64) {
  ObservationSettings s;
  s.backend = b;
  s.tile_cells = tile;
  return s;
}

inline constexpr ObservationBackend kBackends[] = {ObservationBackend::kDda, ObservationBackend::kEmbree};
inline const char* name_of(ObservationBackend b) { return b == ObservationBackend::kDda ? "dda" : "embree"; }

}  // namespace test_observation
}  // namespace duet
