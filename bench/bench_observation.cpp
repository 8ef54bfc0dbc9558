// Observation/{duet_embree,duet_embree_1t,duet_dda,duet_dda_1t,naive}/{400x400,2000x2000,willow}:
// the paper's observation model (§3.1: ray fans, Eq. 5 entropy summed up to the first occupied
// cell) for a batch of 256 random free poses (fixed seed) x the paper's two sensors (Eq. 6) x 30
// rays, 0.5-5 m.
// Grids: a synthetic indoor map at 0.05 m (rooms 3-6 m with 1-cell walls and 0.9 m doors along
// corridors, a third of the rooms still unknown, clutter and graded log-odds; fixed seed) of 400x400
// (20 m) and 2000x2000 (100 m) cells, and the Willow Garage map (0.10 m, 566x608) when
// ../shared/data is present.
// naive = a plain scalar float DDA written here: walks the float log-odds grid, classifies each
// cell with the thresholds and computes Eq. (5) with std::exp/std::log per cell (what a
// straightforward implementation does), single-threaded.
// Items = grid cells visited (the same count for every contender, from the DDA model); "bits" =
// the summed entropy of the last iteration, to cross-check the contenders.
// The models (set_grid: Embree scene build included) are built once, outside the timed loops.
#include "bench_util.hpp"

#include <duet/kernels/observation.hpp>

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace duet::bench {
namespace {

constexpr float kNaNf = std::numeric_limits<float>::quiet_NaN();

struct ObsInput {
  std::string name, label;
  std::vector<float> logodds;
  GridView view;
  std::vector<Pose2> poses;
  std::vector<SensorSector> sensors;
  std::unique_ptr<ObservationModel> dda, embree;
  std::size_t cells = 0;  ///< cells visited by one batch (DDA model)
  std::size_t rays = 0;
};

// Rooms along corridors on a square map: each block of 4-7 m holds one room (walls 1 cell thick,
// a 0.9 m door to the corridor), corridors 1.5 m wide between blocks; a third of the rooms and
// the map border region unknown (not yet explored); clutter boxes; graded log-odds.
void synthetic_indoor(int n, float res, std::uint32_t seed, std::vector<float>& lo) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> noise(-0.5f, 0.5f);
  lo.assign(static_cast<std::size_t>(n) * static_cast<std::size_t>(n), kNaNf);
  auto at = [&](int x, int y) -> float& { return lo[static_cast<std::size_t>(y) * static_cast<std::size_t>(n) + static_cast<std::size_t>(x)]; };
  auto cells = [&](float m) { return std::max(1, static_cast<int>(std::lround(m / res))); };
  const int corridor = cells(1.5f), door = cells(0.9f);
  std::uniform_int_distribution<int> block(cells(4.0f), cells(7.0f));
  std::uniform_int_distribution<int> pct(0, 99);
  for (int by = 0; by < n;) {
    const int bh = block(rng);
    for (int bx = 0; bx < n;) {
      const int bw = block(rng);
      const int x0 = bx, y0 = by, x1 = std::min(n - 1, bx + bw), y1 = std::min(n - 1, by + bh);
      const bool explored = pct(rng) >= 33;
      // Corridor (free) around the room: the band [x0, x0 + corridor) and [y0, y0 + corridor).
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x)
          if (x < x0 + corridor || y < y0 + corridor) at(x, y) = -2.0f + noise(rng);
      const int rx0 = x0 + corridor, ry0 = y0 + corridor;
      if (rx0 + 2 < x1 && ry0 + 2 < y1) {
        for (int y = ry0; y <= y1; ++y)
          for (int x = rx0; x <= x1; ++x) {
            const bool wall = x == rx0 || x == x1 || y == ry0 || y == y1;
            if (wall) at(x, y) = 2.5f + noise(rng);
            else at(x, y) = explored ? -2.0f + noise(rng) : kNaNf;
          }
        // Door in the south wall (towards the corridor), and one in the west wall.
        const int dx = rx0 + 1 + static_cast<int>(rng() % static_cast<unsigned>(std::max(1, x1 - rx0 - door - 1)));
        for (int x = dx; x < std::min(x1, dx + door); ++x) at(x, ry0) = -1.5f;
        const int dy = ry0 + 1 + static_cast<int>(rng() % static_cast<unsigned>(std::max(1, y1 - ry0 - door - 1)));
        for (int y = dy; y < std::min(y1, dy + door); ++y) at(rx0, y) = -1.5f;
        if (explored) {  // clutter: a few boxes of 0.2-0.6 m
          std::uniform_int_distribution<int> bs(cells(0.2f), cells(0.6f));
          for (int k = 0; k < 3; ++k) {
            const int s = bs(rng);
            if (x1 - rx0 - s - 2 <= 0 || y1 - ry0 - s - 2 <= 0) continue;
            const int cx = rx0 + 1 + static_cast<int>(rng() % static_cast<unsigned>(x1 - rx0 - s - 1));
            const int cy = ry0 + 1 + static_cast<int>(rng() % static_cast<unsigned>(y1 - ry0 - s - 1));
            for (int y = cy; y < cy + s; ++y)
              for (int x = cx; x < cx + s; ++x) at(x, y) = 1.0f + noise(rng);
          }
        }
      }
      bx += bw + 1;
    }
    by += bh + 1;
  }
}

bool load_willow(std::vector<float>& lo, int& w, int& h) {
  const std::filesystem::path file = std::filesystem::path(DUET_BENCH_DATA_DIR) / "maps/willow-2010-02-18-0.10.pgm";
  if (!std::filesystem::exists(file)) return false;
  const cv::Mat img = cv::imread(file.string(), cv::IMREAD_UNCHANGED);
  if (img.empty() || img.type() != CV_8UC1) return false;
  w = img.cols;
  h = img.rows;
  lo.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), kNaNf);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {  // map_server, negate 0: p = (255 - v) / 255; 205 = unknown
      const int v = img.at<std::uint8_t>(r, c);
      const float p = std::clamp((255.0f - static_cast<float>(v)) / 255.0f, 0.02f, 0.98f);
      lo[static_cast<std::size_t>(h - 1 - r) * static_cast<std::size_t>(w) + static_cast<std::size_t>(c)] =
          v == 205 ? kNaNf : std::log(p / (1.0f - p));
    }
  return true;
}

std::vector<Pose2> free_poses(const GridView& g, int n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> ux(0, g.width - 1), uy(0, g.height - 1);
  std::uniform_real_distribution<float> uf(0.0f, 1.0f), ut(-std::numbers::pi_v<float>, std::numbers::pi_v<float>);
  std::vector<Pose2> poses;
  for (int guard = 0; static_cast<int>(poses.size()) < n && guard < 10000000; ++guard) {
    const int x = ux(rng), y = uy(rng);
    if (!(g.logodds[g.index(x, y)] <= -1.0f)) continue;
    const Eigen::Vector2f c = g.origin + Eigen::Vector2f(static_cast<float>(x) + uf(rng), static_cast<float>(y) + uf(rng)) * g.resolution_m;
    poses.push_back({c.x(), c.y(), ut(rng)});
  }
  return poses;
}

// ---- naive ---------------------------------------------------------------------------------------

float naive_entropy(float l) {
  if (std::isnan(l)) return 1.0f;
  const float p = 1.0f - 1.0f / (1.0f + std::exp(l));
  float e = 0.0f;
  if (p > 0.0f) e -= p * std::log(p) / std::log(2.0f);
  if (p < 1.0f) e -= (1.0f - p) * std::log(1.0f - p) / std::log(2.0f);
  return e;
}

struct NaiveTotals {
  double bits = 0.0;
  std::size_t cells = 0;
};

NaiveTotals naive_observe(const GridView& g, const CellThresholds& th, const std::vector<Pose2>& poses,
                          const std::vector<SensorSector>& sensors) {
  NaiveTotals tot;
  for (const Pose2& pose : poses)
    for (const SensorSector& s : sensors)
      for (int r = 0; r < s.rays; ++r) {
        const float c = std::cos(pose.theta), sn = std::sin(pose.theta);
        const float ox = pose.x + c * s.x_m - sn * s.y_m, oy = pose.y + sn * s.x_m + c * s.y_m;
        const float a = s.yaw_rad + pose.theta - 0.5f * s.fov_rad + s.fov_rad * static_cast<float>(r) / static_cast<float>(s.rays - 1);
        const float dx = std::cos(a), dy = std::sin(a);
        // Amanatides-Woo in float from min range to max range.
        const float px = (ox + s.min_range_m * dx - g.origin.x()) / g.resolution_m;
        const float py = (oy + s.min_range_m * dy - g.origin.y()) / g.resolution_m;
        int ix = static_cast<int>(std::floor(px)), iy = static_cast<int>(std::floor(py));
        const int stx = dx > 0 ? 1 : -1, sty = dy > 0 ? 1 : -1;
        const float tdx = dx != 0 ? std::fabs(g.resolution_m / dx) : std::numeric_limits<float>::infinity();
        const float tdy = dy != 0 ? std::fabs(g.resolution_m / dy) : std::numeric_limits<float>::infinity();
        float tmx = dx != 0 ? s.min_range_m + ((dx > 0 ? static_cast<float>(ix + 1) - px : px - static_cast<float>(ix)) * tdx)
                            : std::numeric_limits<float>::infinity();
        float tmy = dy != 0 ? s.min_range_m + ((dy > 0 ? static_cast<float>(iy + 1) - py : py - static_cast<float>(iy)) * tdy)
                            : std::numeric_limits<float>::infinity();
        float sum = 0.0f;
        for (;;) {
          float l = kNaNf;
          if (ix >= 0 && iy >= 0 && ix < g.width && iy < g.height) l = g.logodds[g.index(ix, iy)];
          sum += naive_entropy(l);
          ++tot.cells;
          if (classify(l, th) == CellState::kOccupied) break;
          const float tn = std::min(tmx, tmy);
          if (tn >= s.max_range_m) break;
          if (tmx < tmy) {
            ix += stx;
            tmx += tdx;
          } else {
            iy += sty;
            tmy += tdy;
          }
        }
        tot.bits += sum;
      }
  return tot;
}

// ---- set-up ----------------------------------------------------------------------------------------

std::vector<std::unique_ptr<ObsInput>>& inputs() {
  static std::vector<std::unique_ptr<ObsInput>> v;
  return v;
}

void finish_input(ObsInput& in, int w, int h, float res) {
  in.view = GridView(in.logodds, w, h, res, Eigen::Vector2f(0.0f, 0.0f));
  in.poses = free_poses(in.view, 256, 2024);
  in.sensors = paper_dual_sensors(30);
  ObservationSettings sd, se;
  sd.backend = ObservationBackend::kDda;
  se.backend = ObservationBackend::kEmbree;
  in.dda = std::make_unique<ObservationModel>(sd);
  in.embree = std::make_unique<ObservationModel>(se);
  in.dda->set_grid(in.view);
  in.embree->set_grid(in.view);
  in.rays = in.poses.size() * 60;
  std::vector<RayObservation> out(in.rays);
  in.dda->observe(in.poses, in.sensors, out);
  for (const auto& r : out) in.cells += static_cast<std::size_t>(r.cells);
}

void build_inputs() {
  if (!inputs().empty()) return;
  for (const int n : {400, 2000}) {
    auto in = std::make_unique<ObsInput>();
    in->name = std::to_string(n) + "x" + std::to_string(n);
    in->label = "synthetic indoor 0.05 m";
    synthetic_indoor(n, 0.05f, 7u + static_cast<std::uint32_t>(n), in->logodds);
    finish_input(*in, n, n, 0.05f);
    inputs().push_back(std::move(in));
  }
  auto w = std::make_unique<ObsInput>();
  int ww = 0, wh = 0;
  if (load_willow(w->logodds, ww, wh)) {
    w->name = "willow";
    w->label = "willow 0.10 m";
    finish_input(*w, ww, wh, 0.10f);
    inputs().push_back(std::move(w));
  }
}

void report_obs(benchmark::State& state, const ObsInput& in, double bits) {
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(in.cells));
  state.counters["cells"] = static_cast<double>(in.cells);
  state.counters["rays"] = static_cast<double>(in.rays);
  state.counters["bits"] = bits;
  state.SetLabel(in.label);
}

}  // namespace

void register_observation() {
  build_inputs();
  for (const auto& inp : inputs()) {
    const ObsInput* in = inp.get();
    for (const bool emb : {true, false}) {
      for (const DuetImpl impl : kDuetImpls) {
        const std::string impl_name = std::string(emb ? "duet_embree" : "duet_dda") + (impl.threads == 1 ? "_1t" : "");
        benchmark::RegisterBenchmark(bench_name("Observation", impl_name.c_str(), in->name).c_str(),
                                     [in, impl, emb](benchmark::State& state) {
                                       const ObservationModel& m = emb ? *in->embree : *in->dda;
                                       std::vector<RayObservation> out(in->rays);
                                       run_guarded(state, [&] {
                                         for (auto _ : state) {
                                           arena(impl.threads).execute([&] { m.observe(in->poses, in->sensors, out); });
                                           benchmark::DoNotOptimize(out.data());
                                           benchmark::ClobberMemory();
                                         }
                                       });
                                       double bits = 0.0;
                                       for (const auto& r : out) bits += r.entropy_bits;
                                       report_obs(state, *in, bits);
                                     });
      }
    }
    benchmark::RegisterBenchmark(bench_name("Observation", "naive", in->name).c_str(), [in](benchmark::State& state) {
      const CellThresholds th;
      NaiveTotals t;
      for (auto _ : state) {
        t = naive_observe(in->view, th, in->poses, in->sensors);
        benchmark::DoNotOptimize(t);
      }
      report_obs(state, *in, t.bits);
      state.counters["naive_cells"] = static_cast<double>(t.cells);
    });
  }
}

}  // namespace duet::bench
