// PoseGraph/duet/{n}: one optimize_pose_graph() (pose_graph.hpp) of n nodes on a chain of
// laps round a 40 m x 25 m loop (odometry edges 1 cm / 0.1 deg noisy, a loop edge every lap at
// the start place), from the odometry's drifted chain; "err_m" = worst node error after.
// AccumulateGrid/duet/{n}x{n}: accumulate_grid() of an n x n submap (half observed) rotated by
// 7 deg into an empty grid: the cost per submap of rebuilding the grid after a loop closure.
// No peer in this binary (g2o / Ceres are not installed): the numbers are absolute.
#include "bench_util.hpp"

#include <duet/kernels/grid.hpp>
#include <duet/kernels/pose_graph.hpp>

#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace duet::bench {
namespace {

struct Graph {
  std::vector<Pose2> truth, guess;
  std::vector<PoseGraphEdge> edges;
};

Graph make_graph(int n) {
  Graph g;
  const float per = 130.0f;
  for (int k = 0; k < n; ++k) {
    const float s = std::fmod(2.0f * static_cast<float>(k), per);
    Pose2 p;
    if (s < 40.0f) p = {s, 0.0f, 0.0f};
    else if (s < 65.0f) p = {40.0f, s - 40.0f, std::numbers::pi_v<float> / 2};
    else if (s < 105.0f) p = {40.0f - (s - 65.0f), 25.0f, std::numbers::pi_v<float>};
    else p = {0.0f, 25.0f - (s - 105.0f), -std::numbers::pi_v<float> / 2};
    g.truth.push_back(p);
  }
  std::mt19937 rng(11);
  std::normal_distribution<float> n01(0.0f, 1.0f);
  auto add = [&](int i, int j, float sxy, float sth, bool noisy) {
    PoseGraphEdge e;
    e.from = static_cast<std::uint32_t>(i);
    e.to = static_cast<std::uint32_t>(j);
    e.measurement = compose(inverse(g.truth[static_cast<std::size_t>(i)]), g.truth[static_cast<std::size_t>(j)]);
    if (noisy) {
      e.measurement.x += sxy * n01(rng);
      e.measurement.y += sxy * n01(rng);
      e.measurement.theta += sth * n01(rng);
    }
    e.sigma_xy_m = sxy;
    e.sigma_theta_rad = sth;
    g.edges.push_back(e);
  };
  for (int k = 0; k + 1 < n; ++k) add(k, k + 1, 0.01f, 0.1f * std::numbers::pi_v<float> / 180.0f, true);
  const int lap = static_cast<int>(per / 2.0f);
  for (int k = lap; k < n; k += lap) add(0, k, 0.05f, 0.01f, false);
  g.guess.push_back(g.truth[0]);
  for (int k = 1; k < n; ++k) g.guess.push_back(compose(g.guess.back(), g.edges[static_cast<std::size_t>(k - 1)].measurement));
  return g;
}

}  // namespace

void register_pose_graph() {
  for (const int n : {250, 1000}) {
    benchmark::RegisterBenchmark(("PoseGraph/duet/" + std::to_string(n)).c_str(), [n](benchmark::State& state) {
      const Graph g = make_graph(n);
      std::vector<Pose2> x;
      PoseGraphResult r;
      for (auto _ : state) {
        x = g.guess;
        r = optimize_pose_graph(x, g.edges);
        benchmark::DoNotOptimize(x.data());
      }
      float worst = 0.0f;
      for (std::size_t k = 0; k < x.size(); ++k) worst = std::max(worst, std::hypot(x[k].x - g.truth[k].x, x[k].y - g.truth[k].y));
      float worst_guess = 0.0f;
      for (std::size_t k = 0; k < x.size(); ++k)
        worst_guess = std::max(worst_guess, std::hypot(g.guess[k].x - g.truth[k].x, g.guess[k].y - g.truth[k].y));
      state.counters["err_m"] = worst;
      state.counters["guess_err_m"] = worst_guess;
      state.counters["iterations"] = r.iterations;
      state.counters["edges"] = static_cast<double>(g.edges.size());
    })->UseRealTime()->Unit(benchmark::kMillisecond);
  }
  for (const int n : {400, 1000}) {
    benchmark::RegisterBenchmark(("AccumulateGrid/duet/" + std::to_string(n) + "x" + std::to_string(n)).c_str(), [n](benchmark::State& state) {
      OccupancyGrid src(0.05f, {0.0f, 0.0f}, n, n);
      std::mt19937 rng(5);
      std::uniform_real_distribution<float> u(-2.0f, 3.5f);
      for (float& l : src.logodds()) l = (rng() & 1) ? u(rng) : OccupancyGrid::kUnknown;
      const Pose2 T{3.0f, -2.0f, 7.0f * std::numbers::pi_v<float> / 180.0f};
      for (auto _ : state) {
        OccupancyGrid dst(0.05f);
        accumulate_grid(dst, src, T, -2.0f, 3.5f);
        benchmark::DoNotOptimize(dst.logodds().data());
      }
      state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * n * n);
    })->UseRealTime()->Unit(benchmark::kMillisecond);
  }
}

}  // namespace duet::bench
