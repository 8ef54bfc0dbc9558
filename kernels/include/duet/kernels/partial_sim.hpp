#pragma once
/// @file partial_sim.hpp
/// Partial map simulation: the paper's Procedure 1 (§3.2), a particle method over motion series
/// that returns the goal pose X_g whose simulated observations reduce the map's entropy the most,
/// and the reward R_g of that goal.
///
/// Procedure 1, as implemented (line numbers of the paper's listing):
///  1      X_0 <- X_c (the robot's pose).
///  2-3    for i = 1..I, for n = 1..N (particles in parallel):
///  4-8      zeta_1: each of the H motions U_k = (v_k, omega_k) uniform over U_range;
///           zeta_i (i >= 2): normal around the particle's motions of iteration i-1 with the
///           diagonal covariance Sigma = diag(sigma_v^2, sigma_omega^2), clamped to U_range.
///  9        X_{1:H} = f(X_0, U_{0:H-1}) with the motion model Eq. (4) (motion_model.hpp), each
///           motion held for stage_dt_s. A rollout that enters a non-traversable cell of the
///           inflated grid (an inflated obstacle, or anything not known free), or whose end pose
///           lies outside [min_goal_distance_m, max_goal_distance_m] from X_0, is rejected: its
///           weight becomes 0.
///  10-17    for j = 1..phi_i (phi_i = phi_a * i + phi_b), for k = 0..H-1: the sensors' fans at
///           X_{k+1} (observation model, observation.hpp) are walked cell by cell from each
///           sensor's origin (a known obstacle nearer than min_range blocks the ray, which then
///           observes nothing; cells are observed from min_range on); z ~ chi: a known-occupied cell stops the ray (a hit); an unknown
///           cell is sampled occupied with probability unknown_hit_probability (a hit that stops
///           the ray), else free; a known-free cell is free. For each observed cell
///           l_prior = its log-odds (line 12), l_ISM = hit_logodds or miss_logodds plus a noise
///           drawn once per (j, k) uniformly in [-ism_noise_logodds, +ism_noise_logodds]
///           (line 14), l_posterior = clamp(l_prior + l_ISM) (line 15; an unknown cell's prior is
///           0), and R_{k,j} += E(l_prior) - E(l_posterior) (line 16, Eq. 5 in bits; unknown =
///           1 bit). Within one sample j of one particle a cell observed at an earlier stage (or
///           by an earlier ray) is not counted again and keeps its sampled state, so a cell
///           sampled occupied also stops later rays (a per-thread scratch overlay stamped per
///           (particle, j): no copy of the grid per particle).
///  19       w_i = w_{i-1} * prod_j sum_{t=0}^{H-1} gamma^(t-H) R_{t,j} (kept as log-weights).
///  21-23    normalisation; 24-26 systematic resampling (motions copied, w = 1/N) when
///           1 / sum w^2 < eps_N = resample_ess_fraction * N.
///  28-29    n_m = argmax_n w_I; X_g = X_H of particle n_m; R_g = the mean over its phi_I samples
///           of sum_t R_{t,j} (bits, undiscounted: the expected entropy reduction of going there).
/// When every particle of the last iteration was rejected or saw nothing, `found` is false and
/// R_g = 0, so the combined strategy (exploration.hpp) falls back to the frontier search.
///
/// Cells outside the grid count as unknown but cannot be stamped in the overlay, so a cell outside
/// the grid reached by two rays of one sample counts twice (the grid normally has a margin of
/// unknown cells around the data, grid.hpp grow_margin_cells, so this is rare).
///
/// Determinism: every particle draws from its own counter-based random stream derived from
/// (seed, iteration, particle), resampling from (seed, iteration): the result is identical for
/// any number of threads and any scheduling.
///
/// Thread safety: partial_map_simulation() reads the model and the inflated grid (which nobody may
/// write meanwhile) and needs exclusive use of its workspace; distinct workspaces may run
/// concurrently.
#include <duet/kernels/grid_view.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/kernels/motion_model.hpp>
#include <duet/kernels/observation.hpp>

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace duet {

struct PartialSimSettings {
  int iterations = 5;       ///< I (>= 1)
  int particles = 100;      ///< N (>= 1)
  int phi_a = 1;            ///< phi_i = phi_a * i + phi_b observation samples (>= 1 for every i)
  int phi_b = 1;            ///< (the issue's benchmark case: phi_i = i + 1)
  int stages = 4;           ///< H (>= 1)
  float stage_dt_s = 1.0f;  ///< duration of each simulated motion [s]; H * dt * v_max bounds the reach
  // U_range of zeta_1 (uniform) and the range every later sample is clamped to.
  float v_min_mps = 0.1f;      ///< [m/s] > 0: exploration drives forward (sensors face front/right)
  float v_max_mps = 0.5f;      ///< [m/s] the paper's exploration speed limit (DESIGN.md §7)
  float omega_max_rps = 0.8f;  ///< |omega| [rad/s]: the motion constraint that protects mapping (~46 deg/s)
  // Sigma of zeta_i (i >= 2): diagonal, a fifth of each range, so later iterations refine locally.
  float sigma_v_mps = 0.08f;      ///< [m/s]
  float sigma_omega_rps = 0.3f;   ///< [rad/s]
  float resample_ess_fraction = 0.5f;  ///< eps_N = fraction * N (the usual particle-filter rule), (0, 1]
  /// Discount of line 19, weight gamma^(t-H) of stage t: with gamma < 1 the nearer stages weigh
  /// more (0.9: stage 0 x1.52, stage 3 x1.11), since the robot re-plans before it reaches the
  /// later ones and their simulated observations are the least certain. (0, inf)
  float gamma = 0.9f;
  float unknown_hit_probability = 0.02f;  ///< chi: P(an unknown cell is occupied): mean free path 50 cells = 2.5 m at 0.05 m, (0, 1)
  float hit_logodds = 0.85f;         ///< l(p) of the inverse sensor model for a hit (as GridUpdateSettings)
  float miss_logodds = -0.4f;        ///< l(p) for a cell seen free (as GridUpdateSettings)
  float ism_noise_logodds = 0.1f;    ///< half-width of the uniform l_ISM noise, [0, |miss_logodds|)
  float min_logodds = -2.0f;         ///< posterior clamp (as GridUpdateSettings)
  float max_logodds = 3.5f;          ///< posterior clamp (as GridUpdateSettings)
  float min_goal_distance_m = 0.5f;  ///< goals nearer than this to X_0 are rejected [m] (issue 3)
  float max_goal_distance_m = 10.0f; ///< goals farther than this are rejected [m] (issue 3)
  float collision_step_m = 0.025f;   ///< rollout checked against the inflated grid every this [m] (half a cell)
  std::uint64_t seed = 1;            ///< random streams are derived from it
};
/// Checks every field's range (speeds within [-10, 10] m/s and 100 rad/s) and the work budgets:
/// max(v_max_mps, -v_min_mps) * stage_dt_s / collision_step_m
/// <= kMaxRolloutSubSteps (sub-steps of one stage's rollout) and particles * sum_i(phi_i) *
/// stages <= kMaxParticleSampleStages (simulated observations of one call), so that one call
/// stays within a few seconds whatever the settings.
void validate(const PartialSimSettings& s);
/// Simulated observations of one call: particles * sum_i(phi_i) * stages (see the budgets).
[[nodiscard]] double simulated_observations(const PartialSimSettings& s);
inline constexpr double kMaxRolloutSubSteps = 1e4;
inline constexpr double kMaxParticleSampleStages = 1e6;
/// With the sensors and the grid known (partial_map_simulation()): the cells one call may walk,
/// particles * sum_i(phi_i) * stages * sum over sensors of rays * (2 max_range / resolution + 2),
/// at most this (the defaults on a 5 cm grid: 4.8e7, ~25 ms; the budget ~8 s on 2 cores).
inline constexpr double kMaxSimulatedCells = 2e9;

struct PartialSimResult {
  bool found = false;          ///< a valid particle with a positive reward exists
  Pose2 goal;                  ///< X_g (the robot's pose when !found)
  float reward_bits = 0.0f;    ///< R_g [bits]
  /// The part of R_g from cells whose state is unknown (never observed, or between the
  /// thresholds): what going there is expected to add to the map rather than to confirm [bits].
  float unknown_reward_bits = 0.0f;
  int best_particle = -1;      ///< n_m
  int valid_particles = 0;     ///< non-rejected rollouts in the last iteration
  int resamples = 0;           ///< how many iterations resampled (line 24)
  std::vector<Pose2> best_trajectory;  ///< X_{1:H} of n_m
  std::vector<Twist> best_motions;     ///< U_{0:H-1} of n_m
  std::vector<float> weights;          ///< w_I^(n), normalised (N entries)
  /// Cells processed by the sample walks of lines 10-17 over all iterations (known-free cells at
  /// min_logodds are skipped: their reward is exactly 0 and they never stop a ray).
  std::int64_t cells_visited = 0;
  /// Cells the walks stored for the samples over all iterations (each read by every sample of
  /// its iteration that reaches it).
  std::int64_t cells_stored = 0;
};

/// Reusable state (overlays and buffers per thread, entropy table); create once and reuse.
class PartialSimWorkspace {
 public:
  PartialSimWorkspace();
  ~PartialSimWorkspace();
  PartialSimWorkspace(PartialSimWorkspace&&) noexcept;
  PartialSimWorkspace& operator=(PartialSimWorkspace&&) noexcept;
  struct Impl;
  [[nodiscard]] Impl& impl() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

/// Procedure 1. `model` gives the grid (log-odds, states, entropy); `inflated` (same geometry)
/// gives the traversable cells; `sensors` the fans (e.g. paper_dual_sensors()).
/// Throws duet::Error(kInvalidArgument) on invalid settings, sensors, a non-finite pose, or a
/// model and inflated grid of different geometry.
PartialSimResult partial_map_simulation(const ObservationModel& model, const InflatedGrid& inflated,
                                        const Pose2& robot, std::span<const SensorSector> sensors,
                                        const PartialSimSettings& settings, PartialSimWorkspace& workspace);

}  // namespace duet
