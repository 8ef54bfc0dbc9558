// PartialSim/{duet,duet_1t,naive}/400x400: Procedure 1 with the case (N = 100, I = 5,
// phi_i = i + 1, H = 4, the paper's two sensors of 30 rays each) on a 400 x 400 grid at 0.05 m.
// Decision/{duet,duet_1t}/400x400: one whole decision of the combined strategy (Fig. 6):
// Procedure 1 plus the global frontier search (decide_goal with eps_R forcing both to run).
// The grid: a 20 m x 20 m office (rooms of 4 m with doors on a corridor) of which the part within
// 5 m of the robot is known (free cells at -2, walls at 3.5, as after repeated observations) and
// the rest unknown; the observation model and the inflated grid are built once, outside the loop.
// naive = Procedure 1 written plainly and serially: per-cell entropy with std::log2, a scalar DDA
// per ray and sample, a std::unordered_map overlay per sample, one Bernoulli draw per unknown
// cell, std::mt19937 and std::normal_distribution; same settings, same rejection rule.
// Items = decisions (one Procedure 1 run); compare the times. The "points" counter is the number
// of cells each contender processed in its observation walks (duet skips known-free cells at the
// clamp, whose reward is exactly 0).
#include "bench_util.hpp"

#include <duet/kernels/exploration.hpp>
#include <duet/kernels/partial_sim.hpp>

#include <cmath>
#include <random>
#include <unordered_map>

namespace duet::bench {
namespace {

struct SimInput {
  std::vector<float> logodds;
  int size = 0;
  GridView view;
  ObservationModel model;
  InflatedGrid inflated;
  Pose2 robot{10.1f, 10.1f, 0.3f};
  std::vector<SensorSector> sensors = paper_dual_sensors(30);
  PartialSimSettings settings;  // the defaults are the case (N 100, I 5, phi_i = i + 1, H 4)
};

// Office: walls every 4 m in x (rooms) on both sides of a 2 m corridor along y = 9..11 m, doors
// of 1 m; the known part is a disc of 5 m around the robot.
const SimInput& sim_input(int size) {
  static std::unordered_map<int, std::unique_ptr<SimInput>> cache;
  auto& slot = cache[size];
  if (slot) return *slot;
  slot = std::make_unique<SimInput>();
  SimInput& in = *slot;
  in.size = size;
  const float res = 0.05f;
  const auto n = static_cast<std::size_t>(size) * static_cast<std::size_t>(size);
  std::vector<float> truth(n, -2.0f);
  auto occ = [&](int x, int y) {
    if (x >= 0 && y >= 0 && x < size && y < size)
      truth[static_cast<std::size_t>(y) * static_cast<std::size_t>(size) + static_cast<std::size_t>(x)] = 3.5f;
  };
  const int cells_per_m = 20;
  for (int i = 0; i < size; ++i) {
    occ(i, 0), occ(i, size - 1), occ(0, i), occ(size - 1, i);
  }
  const int c0 = 9 * cells_per_m, c1 = 11 * cells_per_m;  // corridor
  for (int x = 0; x < size; ++x) {
    const int mx = x % (2 * cells_per_m * 2);
    const bool door = mx >= 30 && mx < 50;
    if (!door) occ(x, c0), occ(x, c1);
  }
  for (int x = 4 * cells_per_m; x < size; x += 4 * cells_per_m)
    for (int y = 0; y < size; ++y)
      if (y < c0 || y > c1) occ(x, y);
  in.logodds.assign(n, std::numeric_limits<float>::quiet_NaN());
  const float rx = in.robot.x / res, ry = in.robot.y / res, r = 5.0f / res;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x)
      if ((x - rx) * (x - rx) + (y - ry) * (y - ry) < r * r) {
        const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(size) + static_cast<std::size_t>(x);
        in.logodds[i] = truth[i];
      }
  in.view = GridView(in.logodds, size, size, res, Eigen::Vector2f(0.0f, 0.0f));
  ObservationSettings os;
  os.backend = ObservationBackend::kDda;
  in.model = ObservationModel(os);
  in.model.set_grid(in.view);
  inflate(in.view, InflationSettings{}, in.inflated);
  return in;
}

// ---- naive Procedure 1 -------------------------------------------------------------------------

double entropy_naive(float l) {
  if (std::isnan(l)) return 1.0;
  const double p = 1.0 / (1.0 + std::exp(-static_cast<double>(l)));
  double e = 0.0;
  if (p > 0.0) e -= p * std::log2(p);
  if (1.0 - p > 0.0) e -= (1.0 - p) * std::log2(1.0 - p);
  return e;
}

struct NaiveResult {
  Pose2 goal;
  double reward = 0.0;
  std::int64_t visits = 0;
};

NaiveResult naive_partial_sim(const SimInput& in, std::uint64_t seed) {
  const PartialSimSettings& s = in.settings;
  const CellThresholds th;
  const GridView& g = in.view;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  const int N = s.particles, H = s.stages;
  std::vector<std::vector<Twist>> u(static_cast<std::size_t>(N), std::vector<Twist>(static_cast<std::size_t>(H)));
  std::vector<std::vector<Pose2>> x(static_cast<std::size_t>(N), std::vector<Pose2>(static_cast<std::size_t>(H)));
  std::vector<double> w(static_cast<std::size_t>(N), 1.0 / N), reward(static_cast<std::size_t>(N), 0.0);
  std::vector<char> valid(static_cast<std::size_t>(N), 0);
  NaiveResult out;
  for (int i = 1; i <= s.iterations; ++i) {
    const int phi = s.phi_a * i + s.phi_b;
    for (int n = 0; n < N; ++n) {
      auto& un = u[static_cast<std::size_t>(n)];
      for (Twist& t : un) {
        if (i == 1) {
          t.v = s.v_min_mps + (s.v_max_mps - s.v_min_mps) * uni(rng);
          t.omega = -s.omega_max_rps + 2.0f * s.omega_max_rps * uni(rng);
        } else {
          t.v = std::clamp(t.v + s.sigma_v_mps * normal(rng), s.v_min_mps, s.v_max_mps);
          t.omega = std::clamp(t.omega + s.sigma_omega_rps * normal(rng), -s.omega_max_rps, s.omega_max_rps);
        }
      }
      // rollout with the same rejection rule
      Pose2 p = in.robot;
      const Eigen::Vector2i start = g.cell_of({p.x, p.y});
      bool ok = true;
      for (int k = 0; k < H && ok; ++k) {
        const int sub = std::max(1, static_cast<int>(std::ceil(un[static_cast<std::size_t>(k)].v * s.stage_dt_s / s.collision_step_m)));
        for (int q = 0; q < sub && ok; ++q) {
          p = motion_step(p, un[static_cast<std::size_t>(k)], s.stage_dt_s / static_cast<float>(sub));
          const Eigen::Vector2i c = g.cell_of({p.x, p.y});
          if (c == start) continue;
          ok = g.in_bounds(c.x(), c.y()) && in.inflated.traversable[g.index(c.x(), c.y())];
        }
        x[static_cast<std::size_t>(n)][static_cast<std::size_t>(k)] = p;
      }
      const float d = std::hypot(p.x - in.robot.x, p.y - in.robot.y);
      ok = ok && d >= s.min_goal_distance_m && d <= s.max_goal_distance_m;
      valid[static_cast<std::size_t>(n)] = ok;
      if (!ok) {
        w[static_cast<std::size_t>(n)] = 0.0;
        continue;
      }
      double prod = 1.0, rsum = 0.0;
      for (int j = 0; j < phi; ++j) {
        std::unordered_map<std::size_t, bool> overlay;  // cell -> sampled occupied
        double disc = 0.0;
        for (int k = 0; k < H; ++k) {
          const float delta = -s.ism_noise_logodds + 2.0f * s.ism_noise_logodds * uni(rng);
          double rk = 0.0;
          const Pose2& pose = x[static_cast<std::size_t>(n)][static_cast<std::size_t>(k)];
          for (const SensorSector& sec : in.sensors) {
            std::vector<Eigen::Vector2f> org(static_cast<std::size_t>(sec.rays)), dir(static_cast<std::size_t>(sec.rays));
            sector_rays(pose, sec, org, dir);
            for (std::size_t r = 0; r < org.size(); ++r) {
              // scalar DDA from the sensor to max range
              walk_cells(g, org[r], dir[r], 0.0f, sec.max_range_m, [&](int ix, int iy, float, float t_exit) {
                const bool inside = g.in_bounds(ix, iy);
                const std::size_t idx = inside ? g.index(ix, iy) : 0;
                const float l = inside ? g.logodds[idx] : std::numeric_limits<float>::quiet_NaN();
                const CellState st = classify(l, th);
                if (t_exit <= sec.min_range_m && t_exit < sec.max_range_m) return st != CellState::kOccupied;
                ++out.visits;
                if (inside) {
                  auto it = overlay.find(idx);
                  if (it != overlay.end()) return !it->second;
                }
                bool hit = st == CellState::kOccupied;
                if (st == CellState::kUnknown) hit = uni(rng) < s.unknown_hit_probability;
                const float prior = std::isnan(l) ? 0.0f : l;
                const float post = std::clamp(prior + (hit ? s.hit_logodds : s.miss_logodds) + delta, s.min_logodds, s.max_logodds);
                rk += entropy_naive(l) - entropy_naive(post);
                if (inside) overlay[idx] = hit;
                return !hit;
              });
            }
          }
          disc += std::pow(static_cast<double>(s.gamma), k - H) * rk;
          rsum += rk;
        }
        prod *= disc;
      }
      w[static_cast<std::size_t>(n)] *= prod;
      reward[static_cast<std::size_t>(n)] = rsum / phi;
    }
    double sum = 0.0;
    for (double v : w) sum += v;
    if (sum > 0.0)
      for (double& v : w) v /= sum;
    double sq = 0.0;
    for (double v : w) sq += v * v;
    if (i < s.iterations && sum > 0.0 && 1.0 / sq < s.resample_ess_fraction * N) {
      std::discrete_distribution<int> pick(w.begin(), w.end());
      auto u2 = u;
      for (int n = 0; n < N; ++n) u2[static_cast<std::size_t>(n)] = u[static_cast<std::size_t>(pick(rng))];
      u.swap(u2);
      std::fill(w.begin(), w.end(), 1.0 / N);
    }
  }
  const auto best = static_cast<std::size_t>(std::max_element(w.begin(), w.end()) - w.begin());
  out.goal = x[best].back();
  out.reward = reward[best];
  return out;
}

}  // namespace

void register_partial_sim() {
  for (const int size : {400}) {
    const std::string sz = std::to_string(size) + "x" + std::to_string(size);
    for (const DuetImpl impl : kDuetImpls) {
      benchmark::RegisterBenchmark(bench_name("PartialSim", impl.name, sz).c_str(), [impl, size](benchmark::State& state) {
        const SimInput& in = sim_input(size);
        PartialSimWorkspace ws;
        PartialSimResult r;
        std::int64_t visits = 0;
        for (auto _ : state) {
          arena(impl.threads).execute([&] { r = partial_map_simulation(in.model, in.inflated, in.robot, in.sensors, in.settings, ws); });
          visits = r.cells_visited;
          benchmark::DoNotOptimize(r.goal);
        }
        report(state, 1, r.reward_bits);
        state.counters["cells"] = static_cast<double>(visits);
        state.counters["valid"] = r.valid_particles;
      })->Unit(benchmark::kMillisecond)->UseRealTime();
      benchmark::RegisterBenchmark(bench_name("Decision", impl.name, sz).c_str(), [impl, size](benchmark::State& state) {
        const SimInput& in = sim_input(size);
        ExplorationWorkspace ws;
        ExplorationSettings es;
        es.simulation = in.settings;
        es.eps_r_bits = 1e30f;  // both halves of Fig. 6 always run
        GoalBlacklist bl;
        ExplorationDecision d;
        for (auto _ : state) {
          arena(impl.threads).execute([&] { d = decide_goal(in.model, in.inflated, in.robot, in.sensors, bl, 0.0, es, ws); });
          benchmark::DoNotOptimize(d.goal);
        }
        report(state, 1, d.reward_bits);
        state.counters["frontier_found"] = d.status == ExplorationStatus::kFrontierGoal ? 1 : 0;
      })->Unit(benchmark::kMillisecond)->UseRealTime();
    }
    benchmark::RegisterBenchmark(bench_name("PartialSim", "naive", sz).c_str(), [size](benchmark::State& state) {
      const SimInput& in = sim_input(size);
      NaiveResult r;
      for (auto _ : state) {
        r = naive_partial_sim(in, 1);
        benchmark::DoNotOptimize(r.goal);
      }
      report(state, 1, r.reward);
      state.counters["cells"] = static_cast<double>(r.visits);
    })->Unit(benchmark::kMillisecond)->UseRealTime();
  }
}

}  // namespace duet::bench
