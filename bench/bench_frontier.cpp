// Global frontier search (paper §3.2).
//
// Frontier/{duet,duet_1t,naive}/{400x400,2000x2000,willow}: the whole search from the robot.
//   duet  = find_frontier on the inflated grid (inflation done once outside the loop: it is done
//           once per map update and benchmarked as Inflation/ in bench_path.cpp): parallel frontier
//           mask, clustering, exact two-queue Dijkstra over the robot's whole traversable component,
//           goal + path + every cluster's reachability.
//   naive = a std::queue BFS over the raw log-odds grid (8-connected, free cells), classifying
//           neighbours on the fly and collecting the frontier cells it reaches in BFS order (the
//           first is the nearest by hops) - what a straightforward implementation does; it does not
//           inflate, cluster, or compute metric path lengths, so it does less than duet.
// FrontierScan/{duet,duet_1t,naive}/{...}: frontier_mask over the whole log-odds grid; bytes =
//   cells * sizeof(float), to compare with Memory/stream in the same run. naive = a serial per-cell
//   loop classifying the 3x3 neighbourhood.
// Items = grid cells. Grids: a synthetic indoor map (rooms, doors, furniture, the far 40% and a few
// patches unknown; 0.05 m, fixed seed) at 400x400 (20 m) and 2000x2000 (100 m), and the Willow
// Garage map (0.1 m, 566x608) when ../shared/data is present (205 = unknown, darker = occupied,
// lighter = free; see tests/kernels/test_frontier.cpp).
#include "bench_util.hpp"

#include <duet/kernels/frontier.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/kernels/path.hpp>

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <queue>
#include <random>
#include <string>
#include <vector>

namespace duet::bench {

namespace {
/// A planning benchmark map (shared with bench_path.cpp through the accessors below): log-odds,
/// its inflation, a robot cell.
struct PlanMap {
  std::string name;
  std::vector<float> logodds;
  int width = 0, height = 0;
  float resolution_m = 0.05f;
  InflatedGrid inflated;
  Eigen::Vector2f robot_xy{0, 0};  ///< centre of a traversable cell in the known part
  Eigen::Vector2f far_xy{0, 0};    ///< the reachable traversable cell farthest (path length) from the robot
  [[nodiscard]] GridView view() const { return GridView(logodds, width, height, resolution_m, Eigen::Vector2f(0, 0)); }
};

constexpr float kFreeL = -2.0f, kOccL = 3.0f;
constexpr float kNaNf = std::numeric_limits<float>::quiet_NaN();

void rect(PlanMap& m, int x0, int y0, int x1, int y1, float v) {  // inclusive, clipped
  for (int y = std::max(0, y0); y <= std::min(m.height - 1, y1); ++y)
    for (int x = std::max(0, x0); x <= std::min(m.width - 1, x1); ++x)
      m.logodds[static_cast<std::size_t>(y) * static_cast<std::size_t>(m.width) + static_cast<std::size_t>(x)] = v;
}

std::unique_ptr<PlanMap> make_indoor(int n, std::uint32_t seed) {
  auto m = std::make_unique<PlanMap>();
  m->name = std::to_string(n) + "x" + std::to_string(n);
  m->width = m->height = n;
  m->resolution_m = 0.05f;
  m->logodds.assign(static_cast<std::size_t>(n) * static_cast<std::size_t>(n), kFreeL);
  std::mt19937 rng(seed);
  constexpr int kRoom = 80, kDoor = 20, kWall = 2;  // 4 m rooms, 1 m doors, 0.1 m walls
  for (int k = 0; k * kRoom <= n; ++k) {  // wall lines with one door per room side
    const int c = std::min(n - kWall, k * kRoom);
    rect(*m, c, 0, c + kWall - 1, n - 1, kOccL);
    rect(*m, 0, c, n - 1, c + kWall - 1, kOccL);
  }
  std::uniform_int_distribution<int> door(kWall + 2, kRoom - kDoor - 2), box(5, 15), pos(kWall + 4, kRoom - 20);
  for (int ry = 0; ry * kRoom < n; ++ry)
    for (int rx = 0; rx * kRoom < n; ++rx) {
      const int x0 = rx * kRoom, y0 = ry * kRoom;
      if (x0 > 0) {
        const int d = y0 + door(rng);
        rect(*m, x0, d, x0 + kWall - 1, d + kDoor - 1, kFreeL);
      }
      if (y0 > 0) {
        const int d = x0 + door(rng);
        rect(*m, d, y0, d + kDoor - 1, y0 + kWall - 1, kFreeL);
      }
      for (int f = 0; f < 2; ++f) {  // furniture
        const int bx = x0 + pos(rng), by = y0 + pos(rng);
        rect(*m, bx, by, bx + box(rng), by + box(rng), kOccL);
      }
      if (rng() % 3 == 0) {  // an unobserved patch
        const int ux = x0 + pos(rng), uy = y0 + pos(rng);
        rect(*m, ux, uy, ux + box(rng), uy + box(rng), kNaNf);
      }
    }
  rect(*m, 0, 0, n - 1, kWall - 1, kOccL);  // outer walls
  rect(*m, 0, n - kWall, n - 1, n - 1, kOccL);
  rect(*m, 0, 0, kWall - 1, n - 1, kOccL);
  rect(*m, n - kWall, 0, n - 1, n - 1, kOccL);
  rect(*m, n * 6 / 10, 0, n - 1, n - 1, kNaNf);  // the far part is not explored yet
  return m;
}

std::unique_ptr<PlanMap> load_willow() {
  const std::string path = std::string(DUET_BENCH_DATA_DIR) + "/maps/willow-2010-02-18-0.10.pgm";
  if (!std::filesystem::exists(path)) return nullptr;
  const cv::Mat img = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (img.empty()) return nullptr;
  auto m = std::make_unique<PlanMap>();
  m->name = "willow";
  m->width = img.cols;
  m->height = img.rows;
  m->resolution_m = 0.10f;
  m->logodds.resize(static_cast<std::size_t>(img.cols) * static_cast<std::size_t>(img.rows));
  for (int r = 0; r < img.rows; ++r)
    for (int c = 0; c < img.cols; ++c) {
      const int v = img.at<std::uint8_t>(r, c);
      m->logodds[static_cast<std::size_t>(img.rows - 1 - r) * static_cast<std::size_t>(img.cols) + static_cast<std::size_t>(c)] =
          v == 205 ? kNaNf : v < 205 ? kOccL : kFreeL;
    }
  return m;
}

// Robot: the traversable cell nearest to `want` (cells); far: the reachable cell farthest from it.
void place_robot(PlanMap& m, Eigen::Vector2f want_cells) {
  arena(2).execute([&] { inflate(m.view(), InflationSettings{}, m.inflated); });
  const InflatedGrid& g = m.inflated;
  float best = std::numeric_limits<float>::infinity();
  std::size_t robot = 0;
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      if (!g.traversable[g.index(x, y)]) continue;
      const float d = (Eigen::Vector2f(float(x), float(y)) - want_cells).squaredNorm();
      if (d < best) {
        best = d;
        robot = g.index(x, y);
      }
    }
  m.robot_xy = g.cell_center(robot);
  FrontierWorkspace ws;
  (void)arena(2).execute([&] { return find_frontier(g, m.robot_xy, GoalBlacklist{}, 0.0, FrontierSettings{}, ws); });
  std::size_t far = robot;
  for (std::size_t i = 0; i < g.cell_count(); ++i)
    if (std::isfinite(ws.dist[i]) && ws.dist[i] > ws.dist[far]) far = i;
  m.far_xy = g.cell_center(far);
}

std::size_t naive_frontier_bfs(const PlanMap& m, const CellThresholds& t, std::vector<std::size_t>& found) {
  const int w = m.width, h = m.height;
  std::vector<std::uint8_t> visited(m.logodds.size(), 0);
  found.clear();
  const auto cls = [&](int x, int y) { return classify(m.logodds[static_cast<std::size_t>(y * w + x)], t); };
  const Eigen::Vector2i s(static_cast<int>(std::floor(m.robot_xy.x() / m.resolution_m)),
                          static_cast<int>(std::floor(m.robot_xy.y() / m.resolution_m)));
  std::queue<std::pair<int, int>> q;
  q.push({s.x(), s.y()});
  visited[static_cast<std::size_t>(s.y() * w + s.x())] = 1;
  std::size_t reached = 0;
  while (!q.empty()) {
    const auto [x, y] = q.front();
    q.pop();
    ++reached;
    bool frontier = false;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = x + dx, ny = y + dy;
        if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
        const CellState c = cls(nx, ny);
        if (c == CellState::kUnknown) frontier = true;
        const std::size_t ni = static_cast<std::size_t>(ny * w + nx);
        if (c == CellState::kFree && !visited[ni]) {
          visited[ni] = 1;
          q.push({nx, ny});
        }
      }
    if (frontier) found.push_back(static_cast<std::size_t>(y * w + x));
  }
  return reached;
}

std::size_t naive_mask(const PlanMap& m, const CellThresholds& t, std::vector<std::uint8_t>& mask) {
  const int w = m.width, h = m.height;
  std::size_t n = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      std::uint8_t v = 0;
      if (classify(m.logodds[static_cast<std::size_t>(y * w + x)], t) == CellState::kFree) {
        for (int dy = -1; dy <= 1 && !v; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
            if (classify(m.logodds[static_cast<std::size_t>(ny * w + nx)], t) == CellState::kUnknown) {
              v = 1;
              break;
            }
          }
      }
      mask[static_cast<std::size_t>(y * w + x)] = v;
      n += v;
    }
  return n;
}

std::vector<std::unique_ptr<PlanMap>>& maps_storage() {
  static std::vector<std::unique_ptr<PlanMap>> maps;
  return maps;
}

}  // namespace

/// The planning benchmark maps (built once, on first use, outside any timed loop).
static const std::vector<std::unique_ptr<PlanMap>>& plan_maps() {
  auto& maps = maps_storage();
  if (maps.empty()) {
    for (const int n : {400, 2000}) {
      auto m = make_indoor(n, 2019u + static_cast<std::uint32_t>(n));
      place_robot(*m, Eigen::Vector2f(40.0f, 40.0f));
      maps.push_back(std::move(m));
    }
    if (auto w = load_willow()) {
      place_robot(*w, Eigen::Vector2f(float(w->width) / 2, float(w->height) / 2));
      maps.push_back(std::move(w));
    }
  }
  return maps;
}

// Accessors for bench_path.cpp (no shared header: bench/common.hpp belongs to the lead).
std::size_t plan_map_count() { return plan_maps().size(); }
const std::string& plan_map_name(std::size_t i) { return plan_maps()[i]->name; }
GridView plan_map_view(std::size_t i) { return plan_maps()[i]->view(); }
const InflatedGrid& plan_map_inflated(std::size_t i) { return plan_maps()[i]->inflated; }
Eigen::Vector2f plan_map_robot(std::size_t i) { return plan_maps()[i]->robot_xy; }
Eigen::Vector2f plan_map_far(std::size_t i) { return plan_maps()[i]->far_xy; }

void register_frontier() {
  for (const auto& mp : plan_maps()) {
    const PlanMap* m = mp.get();
    const std::size_t cells = m->logodds.size();
    for (const DuetImpl impl : kDuetImpls) {
      benchmark::RegisterBenchmark(bench_name("Frontier", impl.name, m->name).c_str(), [m, impl, cells](benchmark::State& state) {
        FrontierWorkspace ws;
        FrontierResult r;
        run_guarded(state, [&] {
          for (auto _ : state) {
            r = arena(impl.threads).execute(
                [&] { return find_frontier(m->inflated, m->robot_xy, GoalBlacklist{}, 0.0, FrontierSettings{}, ws); });
            benchmark::DoNotOptimize(r.goal_xy.data());
          }
        });
        state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(cells));
        state.counters["reached"] = static_cast<double>(r.reached_cells);
        state.counters["frontier"] = static_cast<double>(r.frontier_cells);
        state.counters["clusters"] = static_cast<double>(r.clusters.size());
        state.counters["goal_m"] = r.path_length_m;
        state.SetLabel(to_string(r.status));
      });
    }
    benchmark::RegisterBenchmark(bench_name("Frontier", "naive", m->name).c_str(), [m, cells](benchmark::State& state) {
      std::vector<std::size_t> found;
      std::size_t reached = 0;
      for (auto _ : state) {
        reached = naive_frontier_bfs(*m, CellThresholds{}, found);
        benchmark::DoNotOptimize(found.data());
      }
      state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(cells));
      state.counters["reached"] = static_cast<double>(reached);
      state.counters["frontier"] = static_cast<double>(found.size());
    });

    for (const DuetImpl impl : kDuetImpls) {
      benchmark::RegisterBenchmark(bench_name("FrontierScan", impl.name, m->name).c_str(), [m, impl, cells](benchmark::State& state) {
        std::vector<std::uint8_t> mask(cells);
        std::size_t n = 0;
        run_guarded(state, [&] {
          for (auto _ : state) {
            n = arena(impl.threads).execute([&] { return frontier_mask(m->view(), CellThresholds{}, mask); });
            benchmark::DoNotOptimize(mask.data());
          }
        });
        state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(cells));
        state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(cells * sizeof(float)));
        state.counters["bytes"] = static_cast<double>(cells * sizeof(float));  // per call, for the ratio table
        state.counters["frontier"] = static_cast<double>(n);
      })->UseRealTime();
    }
    benchmark::RegisterBenchmark(bench_name("FrontierScan", "naive", m->name).c_str(), [m, cells](benchmark::State& state) {
      std::vector<std::uint8_t> mask(cells);
      std::size_t n = 0;
      for (auto _ : state) {
        n = naive_mask(*m, CellThresholds{}, mask);
        benchmark::DoNotOptimize(mask.data());
      }
      state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(cells));
      state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(cells * sizeof(float)));
      state.counters["bytes"] = static_cast<double>(cells * sizeof(float));
      state.counters["frontier"] = static_cast<double>(n);
    })->UseRealTime();
  }
}

}  // namespace duet::bench
