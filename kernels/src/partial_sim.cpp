// Partial map simulation, Procedure 1 of the paper (see partial_sim.hpp for the line-by-line map).
#include <duet/kernels/error.hpp>
#include <duet/kernels/partial_sim.hpp>

#include "partial_sim_rays.hpp"
#include "partial_sim_samples.hpp"
#include "random.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

namespace duet {

namespace {

// floor() to int without a libm call (baseline x86-64 has no roundss): the walks and rollouts
// call it per jump and per sub-step. Clamped to +-1e9 first (NaN to -1e9), so the conversion is
// defined for any input.
inline int floor_int(float x) noexcept {
  x = x > -1e9f ? x : -1e9f;  // also NaN -> -1e9 (off any grid): no undefined conversion
  x = x < 1e9f ? x : 1e9f;
  const int i = static_cast<int>(x);
  return i - (static_cast<float>(i) > x ? 1 : 0);
}

using namespace detail::partial_sim;  // the precomputed rays (partial_sim_rays.hpp)

// Cells added around the first iteration's rays when the window is built, so that the later
// iterations' rays (the particles move a little) seldom need another window.
constexpr int kWindowMargin = 16;

struct Particle {
  std::vector<Twist> u;     // U_{0:H-1}
  std::vector<Pose2> x;     // X_{1:H}
  double log_w = 0.0;       // log w_i^(n)
  bool valid = false;
  float reward_mean = 0.0f; // mean over j of sum_t R_{t,j} (bits)
  float unknown_reward_mean = 0.0f; // the part of reward_mean from cells whose state is unknown (bits)
  std::int64_t visits = 0;
  std::int64_t stored = 0;  // cells the walks stored (this iteration)
  detail::Rng rng{0};       // the particle's stream of this iteration, between its rollout and its samples
  CellBox rays;             // the cells its rays can reach (add_ray_box)
};

}  // namespace

struct PartialSimWorkspace::Impl {
  tbb::enumerable_thread_specific<ThreadScratch> scratch;
  std::vector<Particle> particles, resampled;
  Window window;  // the cells the rays of an iteration can reach, see build_window()
};

PartialSimWorkspace::PartialSimWorkspace() : impl_(std::make_unique<Impl>()) {}
PartialSimWorkspace::~PartialSimWorkspace() = default;
PartialSimWorkspace::PartialSimWorkspace(PartialSimWorkspace&&) noexcept = default;
PartialSimWorkspace& PartialSimWorkspace::operator=(PartialSimWorkspace&&) noexcept = default;

void validate(const PartialSimSettings& s) {
  auto bad = [](const char* key, double v, const char* range) {
    fail(ErrorCode::kInvalidArgument,
         std::string("PartialSimSettings.") + key + " = " + std::to_string(v) + " is outside " + range);
  };
  auto finite = [](float v) { return std::isfinite(v); };
  if (s.iterations < 1 || s.iterations > 1000) bad("iterations", s.iterations, "[1, 1000]");
  if (s.particles < 1 || s.particles > 100000) bad("particles", s.particles, "[1, 100000]");
  if (s.stages < 1 || s.stages > 100) bad("stages", s.stages, "[1, 100]");
  for (int i = 1; i <= s.iterations; ++i) {
    const long phi = static_cast<long>(s.phi_a) * i + s.phi_b;
    if (phi < 1 || phi > 1000)
      fail(ErrorCode::kInvalidArgument, "PartialSimSettings: phi_i = phi_a * i + phi_b = " + std::to_string(phi) +
                                            " at i = " + std::to_string(i) + " is outside [1, 1000]");
  }
  if (!finite(s.stage_dt_s) || !(s.stage_dt_s > 0.0f) || s.stage_dt_s > 60.0f) bad("stage_dt_s", s.stage_dt_s, "(0, 60]");
  // Speeds within a robot's (found by fuzz_capi: |v| or |omega| near 3e38 made the rollouts'
  // poses NaN; and |v_min| beyond v_max escaped the sub-step budget).
  if (!finite(s.v_min_mps) || !finite(s.v_max_mps) || s.v_min_mps > s.v_max_mps || s.v_max_mps <= 0.0f || s.v_min_mps < -10.0f ||
      s.v_max_mps > 10.0f)
    bad("v_min_mps/v_max_mps", s.v_min_mps, "[-10, 10] m/s with v_min_mps <= v_max_mps and v_max_mps > 0");
  if (!finite(s.omega_max_rps) || s.omega_max_rps < 0.0f || s.omega_max_rps > 100.0f) bad("omega_max_rps", s.omega_max_rps, "[0, 100] rad/s");
  if (!finite(s.sigma_v_mps) || s.sigma_v_mps < 0.0f || s.sigma_v_mps > 10.0f) bad("sigma_v_mps", s.sigma_v_mps, "[0, 10] m/s");
  if (!finite(s.sigma_omega_rps) || s.sigma_omega_rps < 0.0f || s.sigma_omega_rps > 100.0f)
    bad("sigma_omega_rps", s.sigma_omega_rps, "[0, 100] rad/s");
  if (!finite(s.resample_ess_fraction) || !(s.resample_ess_fraction > 0.0f) || s.resample_ess_fraction > 1.0f)
    bad("resample_ess_fraction", s.resample_ess_fraction, "(0, 1]");
  if (!finite(s.gamma) || !(s.gamma > 0.0f) || s.gamma > 10.0f) bad("gamma", s.gamma, "(0, 10]");
  if (!finite(s.unknown_hit_probability) || !(s.unknown_hit_probability > 0.0f) || !(s.unknown_hit_probability < 1.0f))
    bad("unknown_hit_probability", s.unknown_hit_probability, "(0, 1)");
  if (!(s.min_logodds < 0.0f) || !(s.max_logodds > 0.0f) || s.min_logodds < -15.0f || s.max_logodds > 15.0f)
    bad("min_logodds/max_logodds", s.min_logodds, "[-15, 0) and (0, 15]");
  if (!finite(s.hit_logodds) || !(s.hit_logodds > 0.0f) || s.hit_logodds > 15.0f) bad("hit_logodds", s.hit_logodds, "(0, 15]");
  if (!finite(s.miss_logodds) || !(s.miss_logodds < 0.0f) || s.miss_logodds < -15.0f)
    bad("miss_logodds", s.miss_logodds, "[-15, 0)");
  if (!finite(s.ism_noise_logodds) || s.ism_noise_logodds < 0.0f || !(s.ism_noise_logodds < -s.miss_logodds) ||
      !(s.ism_noise_logodds < s.hit_logodds))
    bad("ism_noise_logodds", s.ism_noise_logodds, "[0, min(hit_logodds, -miss_logodds)) (noise must not flip an observation)");
  if (!finite(s.min_goal_distance_m) || s.min_goal_distance_m < 0.0f) bad("min_goal_distance_m", s.min_goal_distance_m, "[0, inf)");
  if (!finite(s.max_goal_distance_m) || !(s.max_goal_distance_m > s.min_goal_distance_m))
    bad("max_goal_distance_m", s.max_goal_distance_m, "(min_goal_distance_m, inf)");
  if (!finite(s.collision_step_m) || !(s.collision_step_m > 0.0f)) bad("collision_step_m", s.collision_step_m, "(0, inf)");
  // Work budgets (issue 19: a range bounds the work it causes). Defaults use 20 sub-steps per
  // stage and 8000 particle-sample-stages per call (about 25 ms on 2 cores on a real state);
  // the budgets allow 500x and 125x that, so one call stays within a few seconds.
  const double sub_steps = std::max(static_cast<double>(s.v_max_mps), -static_cast<double>(s.v_min_mps)) * s.stage_dt_s / s.collision_step_m;
  if (!(sub_steps <= kMaxRolloutSubSteps))
    fail(ErrorCode::kInvalidArgument, "PartialSimSettings: v_max_mps * stage_dt_s / collision_step_m = " + std::to_string(sub_steps) +
                                          " rollout sub-steps per stage, more than the budget of " +
                                          std::to_string(static_cast<long>(kMaxRolloutSubSteps)) + " (raise collision_step_m)");
  const double work = simulated_observations(s);
  if (!(work <= kMaxParticleSampleStages))
    fail(ErrorCode::kInvalidArgument, "PartialSimSettings: particles * sum_i(phi_i) * stages = " + std::to_string(static_cast<long long>(work)) +
                                          ", more than the budget of " + std::to_string(static_cast<long>(kMaxParticleSampleStages)) +
                                          " simulated observations per decision");
}

double simulated_observations(const PartialSimSettings& s) {
  double samples = 0.0;
  for (int i = 1; i <= s.iterations; ++i) samples += static_cast<double>(s.phi_a) * i + s.phi_b;
  return static_cast<double>(s.particles) * samples * s.stages;
}

namespace {

// Line 9 plus the rejection rule: rolls U out from x0 with Eq. (4); false if the rollout enters a
// non-traversable cell (other than the start cell) or ends outside the goal distance band.
bool rollout(const InflatedGrid& g, const Pose2& x0, const PartialSimSettings& s, std::span<const Twist> u,
             std::span<Pose2> x) {
  const float res = g.resolution_m;
  const int sx = floor_int((x0.x - g.origin.x()) / res);
  const int sy = floor_int((x0.y - g.origin.y()) / res);
  Pose2 p = x0;
  for (std::size_t k = 0; k < u.size(); ++k) {
    const float travel = std::fabs(u[k].v) * s.stage_dt_s;
    const int sub = std::max(1, static_cast<int>(std::ceil(travel / s.collision_step_m)));
    const float dt = s.stage_dt_s / static_cast<float>(sub);
    for (int q = 0; q < sub; ++q) {
      p = motion_step(p, u[k], dt);
      const int ix = floor_int((p.x - g.origin.x()) / res);
      const int iy = floor_int((p.y - g.origin.y()) / res);
      if (ix == sx && iy == sy) continue;
      if (ix < 0 || iy < 0 || ix >= g.width || iy >= g.height) return false;
      if (!g.traversable[static_cast<std::size_t>(iy) * static_cast<std::size_t>(g.width) + static_cast<std::size_t>(ix)])
        return false;
    }
    x[k] = p;
  }
  const float d = std::hypot(p.x - x0.x, p.y - x0.y);
  return d >= s.min_goal_distance_m && d <= s.max_goal_distance_m;
}

// Each sensor's ray directions in the robot frame (detail::fan_directions, the fan of
// sector_rays() at theta = 0); a pose's rays are these turned by its heading.
std::vector<std::vector<Eigen::Vector2f>> robot_fans(std::span<const SensorSector> sensors) {
  std::vector<std::vector<Eigen::Vector2f>> fans(sensors.size());
  for (std::size_t i = 0; i < sensors.size(); ++i) fans[i] = detail::fan_directions(sensors[i]);
  return fans;
}

// Lines 10-17 and 19 for one particle whose rays are in ts (partial_sim_samples.cpp): adds
// log(prod_j sum_t gamma^(t-H) R_tj) to its log-weight and keeps the mean undiscounted reward.
void observe_particle(std::span<const SensorSector> sensors, const PartialSimSettings& s, int phi, detail::Rng& rng,
                      ThreadScratch& ts, std::size_t n_cells, Particle& part) {
  std::size_t rays_per_stage = 0;
  for (const SensorSector& sec : sensors) rays_per_stage += static_cast<std::size_t>(sec.rays);
  const SampleTotals t = simulate_samples(s, rays_per_stage, phi, rng, ts, n_cells);
  part.log_w += t.log_w;
  part.reward_mean = static_cast<float>(t.reward_sum / phi);
  part.unknown_reward_mean = static_cast<float>(t.unknown_sum / phi);
  part.visits = t.visits;
}

}  // namespace

PartialSimResult partial_map_simulation(const ObservationModel& model, const InflatedGrid& inflated,
                                        const Pose2& robot, std::span<const SensorSector> sensors,
                                        const PartialSimSettings& s, PartialSimWorkspace& workspace) {
  validate(s);
  if (sensors.empty()) fail(ErrorCode::kInvalidArgument, "partial_map_simulation: no sensors");
  for (const SensorSector& sec : sensors) validate(sec);
  if (!std::isfinite(robot.x) || !std::isfinite(robot.y) || !std::isfinite(robot.theta))
    fail(ErrorCode::kInvalidArgument, "partial_map_simulation: robot pose is not finite");
  const GridView& grid = model.grid();
  if (grid.width != inflated.width || grid.height != inflated.height || grid.resolution_m != inflated.resolution_m ||
      grid.origin != inflated.origin)
    fail(ErrorCode::kInvalidArgument,
         "partial_map_simulation: the observation model's grid (" + std::to_string(grid.width) + " x " +
             std::to_string(grid.height) + ") and the inflated grid (" + std::to_string(inflated.width) + " x " +
             std::to_string(inflated.height) + ") differ in geometry");
  if (grid.cell_count() >= (std::size_t{1} << 30))
    fail(ErrorCode::kOutOfRange, "partial_map_simulation: grids of 2^30 cells or more are not supported");
  {
    // The cells one call may walk: every simulated observation walks every ray to its range.
    const double cells = simulated_observations(s) * fan_cells(sensors, grid.resolution_m);
    if (!(cells <= kMaxSimulatedCells))
      fail(ErrorCode::kInvalidArgument, "partial_map_simulation: particles * sum_i(phi_i) * stages * the sensors' rays * their cells (" +
                                            std::to_string(static_cast<long long>(cells)) + ") is more than the budget of " +
                                            std::to_string(static_cast<long long>(kMaxSimulatedCells)) +
                                            " cell visits per call (fewer particles or rays, a shorter range or coarser cells)");
  }

  auto& ws = workspace.impl();
  const std::vector<std::vector<Eigen::Vector2f>> fans = robot_fans(sensors);
  const int N = s.particles, H = s.stages;
  const auto Nz = static_cast<std::size_t>(N), Hz = static_cast<std::size_t>(H);
  ws.particles.resize(Nz);
  for (Particle& p : ws.particles) {
    p.u.assign(Hz, Twist{});
    p.x.assign(Hz, robot);
    p.log_w = 0.0;
    p.valid = false;
    p.reward_mean = 0.0f;
    p.unknown_reward_mean = 0.0f;
    p.visits = 0;
    p.stored = 0;
  }
  PartialSimResult result;
  result.goal = robot;
  const Pose2 x0 = robot;  // line 1
  const float omega_max = s.omega_max_rps;

  bool weights_all_zero = false;
  for (int i = 1; i <= s.iterations; ++i) {  // line 2
    const int phi = s.phi_a * i + s.phi_b;
    tbb::parallel_for(tbb::blocked_range<int>(0, N, 1), [&](const tbb::blocked_range<int>& range) {
      for (int n = range.begin(); n != range.end(); ++n) {  // line 3
        Particle& part = ws.particles[static_cast<std::size_t>(n)];
        part.rng = detail::Rng(detail::stream_seed(s.seed, static_cast<std::uint64_t>(i), static_cast<std::uint64_t>(n)));
        detail::Rng& rng = part.rng;
        for (int k = 0; k < H; ++k) {
          Twist& u = part.u[static_cast<std::size_t>(k)];
          if (i == 1) {  // line 5: zeta_1 uniform over U_range
            u.v = rng.uniform(s.v_min_mps, s.v_max_mps);
            u.omega = rng.uniform(-omega_max, omega_max);
          } else {  // line 7: zeta_i normal around the particle's last motions, Sigma diagonal
            u.v = std::clamp(u.v + s.sigma_v_mps * rng.normal(), s.v_min_mps, s.v_max_mps);
            u.omega = std::clamp(u.omega + s.sigma_omega_rps * rng.normal(), -omega_max, omega_max);
          }
        }
        part.valid = rollout(inflated, x0, s, part.u, part.x);  // line 9
        part.reward_mean = 0.0f;
        part.unknown_reward_mean = 0.0f;
        part.visits = 0;
        part.stored = 0;
        part.rays = CellBox{};
        if (!part.valid) {
          part.log_w = -std::numeric_limits<double>::infinity();
          continue;
        }
        add_ray_box(grid, part.x, sensors, part.rays);
      }
    });
    // The window of the iteration's rays: built from this call's map at the first iteration, and
    // again only when a later iteration's rays leave it (a margin makes that rare).
    CellBox reach;
    for (const Particle& p : ws.particles) reach.add(p.rays);
    if (i == 1 || !ws.window.box.contains(reach)) build_window(model, s.min_logodds, reach.grown(kWindowMargin), ws.window);
    tbb::parallel_for(tbb::blocked_range<int>(0, N, 1), [&](const tbb::blocked_range<int>& range) {
      ThreadScratch& ts = ws.scratch.local();
      for (int n = range.begin(); n != range.end(); ++n) {
        Particle& part = ws.particles[static_cast<std::size_t>(n)];
        if (!part.valid) continue;
        precompute_rays(grid, ws.window, part.x, sensors, fans, ts);
        part.stored = static_cast<std::int64_t>(ts.cells.size());
        observe_particle(sensors, s, phi, part.rng, ts, ws.window.cells(), part);  // lines 10-19
      }
    });
    for (const Particle& p : ws.particles) {
      result.cells_visited += p.visits;
      result.cells_stored += p.stored;
    }
    // Lines 21-23: normalisation (in the log domain, so long products cannot underflow).
    double max_lw = -std::numeric_limits<double>::infinity();
    for (const Particle& p : ws.particles) max_lw = std::max(max_lw, p.log_w);
    std::vector<double> w(Nz, 1.0 / N);
    weights_all_zero = !std::isfinite(max_lw);
    if (std::isfinite(max_lw)) {
      double sum = 0.0;
      for (std::size_t n = 0; n < Nz; ++n) sum += (w[n] = std::exp(ws.particles[n].log_w - max_lw));
      for (double& v : w) v /= sum;
    }
    double sum_sq = 0.0;
    for (double v : w) sum_sq += v * v;
    const bool last = i == s.iterations;
    if (!last && 1.0 / sum_sq < static_cast<double>(s.resample_ess_fraction) * N) {  // line 24
      // Line 25: systematic resampling; motions are copied, weights reset to 1/N.
      detail::Rng rng(detail::stream_seed(s.seed, static_cast<std::uint64_t>(i), ~0ull));
      const double step = 1.0 / N;
      double target = rng.uniform01_open0() * step, cum = w[0];
      std::size_t src = 0;
      ws.resampled.resize(Nz);
      for (std::size_t n = 0; n < Nz; ++n) {
        while (cum < target && src + 1 < Nz) cum += w[++src];
        ws.resampled[n] = ws.particles[src];
        ws.resampled[n].log_w = std::log(step);
        target += step;
      }
      std::swap(ws.particles, ws.resampled);
      ++result.resamples;
    } else {
      for (std::size_t n = 0; n < Nz; ++n) ws.particles[n].log_w = w[n] > 0.0 ? std::log(w[n]) : -std::numeric_limits<double>::infinity();
    }
    if (last) {
      result.weights.assign(w.begin(), w.end());
    }
  }

  // Lines 28-29: the particle of highest weight (lowest index on ties).
  std::size_t best = 0;
  for (std::size_t n = 1; n < Nz; ++n)
    if (result.weights[n] > result.weights[best]) best = n;
  for (const Particle& p : ws.particles) result.valid_particles += p.valid ? 1 : 0;
  if (weights_all_zero) {  // every weight of the last iteration was 0: rank by reward instead
    for (std::size_t n = 0; n < Nz; ++n) {
      const Particle& p = ws.particles[n];
      const Particle& b = ws.particles[best];
      if (p.valid && (!b.valid || p.reward_mean > b.reward_mean)) best = n;
    }
  }
  const Particle& pb = ws.particles[best];
  if (pb.valid && pb.reward_mean > 0.0f) {
    result.found = true;
    result.best_particle = static_cast<int>(best);
    result.goal = pb.x.back();
    result.reward_bits = pb.reward_mean;
    result.unknown_reward_bits = pb.unknown_reward_mean;
    result.best_trajectory = pb.x;
    result.best_motions = pb.u;
  }
  return result;
}

}  // namespace duet
