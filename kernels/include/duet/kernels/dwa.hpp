#pragma once
/// @file dwa.hpp
/// The dynamic window approach (Fox, Burgard, Thrun 1997) following a global path, with the
/// paper's motion constraint (Yu & Wang 2019, abstract and §4.1 (3): "cost function was added
/// with the motion constraint, based on a dynamic window control algorithm" - fast turns
/// disturb the RGB-D mapping, so |omega| and |domega/dt| are bounded while exploring) and a
/// defined recovery when nothing is admissible or the robot oscillates.
///
/// Frames and units: everything in the map frame (REP 103), SI units; poses and twists as in
/// motion_model.hpp; the path is a polyline of world waypoints [m] from the planner, ending at
/// the goal.
///
/// One control step (dwa_step), in this order:
///  1. Empty path -> kNoPath, zero command (state reset).
///  2. |pose - path.back()| <= goal_tolerance_m -> kGoalReached, zero command (state reset).
///  3. Path geometry: P = the point of the path closest to the robot (first segment wins a tie),
///     L = the lookahead point lookahead_m further along the path from P (clamped to the goal);
///     the "local path" is the polyline P -> waypoints in between -> L.
///  4. An active recovery phase (see below) continues, or ends and falls through to 6.
///  5. Oscillation: the robot is commanded to move but has neither translated by
///     oscillation_min_progress_m nor turned by oscillation_min_turn_rad from the pose where it
///     last did so, for oscillation_window_calls consecutive calls -> a recovery phase starts.
///  6. The window (Fox et al. §4, "dynamic window"), with T = control_period_s:
///       v     in [max(min_v, v_c - max_accel*T),  min(max_v, v_c + max_accel*T)]
///       omega in [max(-W, w_c - A*T), min(W, w_c + A*T)]
///     with W = min(limits.max_omega_rps, mapping_max_omega_rps) and
///          A = min(limits.max_alpha_rps2, mapping_max_alpha_rps2)  (the paper's constraint).
///     If `current` lies outside a speed limit the window on that axis is the single value
///     nearest the limit that one period of acceleration reaches (never further out).
///     Samples: v_i = lo + (hi - lo) * (float(i) / float(n - 1)), i = 0..n-1 (n = 1: (lo+hi)/2),
///     the same for omega. Trajectory (i, j): (v_i, omega_j) held for `steps` steps of
///     dt = sim_time_s / steps, poses by Eq. (4) (motion_step). It is admissible iff the
///     clearance (ClearanceView::at) at the pose after every step 1..steps is
///     > robot_radius_m + safety_margin_m.
///  7. Score of an admissible trajectory with final position p_N and minimum clearance c_min
///     over steps 1..steps (thr = robot_radius_m + safety_margin_m):
///       w_progress  * (|p_0 - L| - |p_N - L|)          progress towards the lookahead [m]
///     - w_path      * dist(p_N, local path)            distance to the path [m]
///     + w_clearance * min(c_min - thr, clearance_cap_m) clearance beyond the margin [m]
///     + w_speed     * v_i                              forward speed [m/s]
///     computed in float in exactly this order (left to right). The best score wins; ties go to
///     the smaller i * omega_samples + j (deterministic for any thread count).
///  8. Nothing admissible -> a recovery phase starts.
///
/// Recovery (a phase lasts at most recovery_max_calls calls; its command honours the paper's
/// omega constraint: omega moves toward its target by at most A*T per call, |omega| <= W):
///  - kRotateInPlace, if the heading error to L exceeds rotate_tolerance_rad and rotating is
///    collision-free (the circular footprint sweeps nothing new: clearance at the pose >
///    robot_radius_m): command (0, omega -> sign(error) * rotate_omega_rps). v = 0 is a stop
///    request: no sampled trajectory (the hardest braking included) was safe. Ends when the
///    heading error is within the tolerance, rotating stops being free, or the time is up.
///  - else kBackOff, if min_v < 0 and the straight reverse of backoff_distance_m is clear
///    (clearance > robot_radius_m at every half cell behind the robot): command
///    (max(-s, min(v_c, 0) - max_accel*T), omega -> 0) with s = min(backoff_speed_mps, -min_v).
///    Ends after backoff_distance_m of travel from where it started, when the space behind
///    stops being clear, or when the time is up.
///  - else: after nothing admissible, kNoValidTrajectory with a zero command (the phase does
///    not start); after an oscillation, the normal window is used (the detector restarts).
/// When a phase ends the oscillation detector restarts from the current pose.
///
/// Thread safety: dwa_step is reentrant with one DwaState and one DwaWorkspace per concurrent
/// call (a robot owns its state); it is TBB-parallel over v samples inside the caller's arena
/// when the work is large enough, and its result does not depend on the number of threads.
#include <duet/kernels/grid_view.hpp>
#include <duet/kernels/motion_model.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <span>
#include <vector>

namespace duet {

/// Work budget of one dwa_step(): v_samples * omega_samples * steps rollout steps at most (the
/// defaults: 24k, ~75 us; the budget ~3 ms - a 20 Hz controller's share).
inline constexpr double kMaxDwaRolloutSteps = 1e6;

struct DwaSettings {
  ChassisLimits limits;  ///< speed/acceleration limits of the chassis (DESIGN.md §7: 0.5 m/s)
  /// Paper's motion constraint: |omega| bound while mapping [rad/s], (0, inf). 0.8 rad/s = 46
  /// deg/s is 1.5 deg per Kinect frame at 30 Hz (>97 % overlap of the 57 deg field of view for
  /// ORB matching / PnP) and 2.3 deg per 20 Hz pose update, a quarter of the Kobuki's 180 deg/s.
  float mapping_max_omega_rps = 0.8f;
  /// Paper's motion constraint: |domega/dt| bound [rad/s^2], (0, inf). 1.0 rad/s^2 reaches the
  /// 0.8 rad/s bound in 0.8 s: no jerk of the sensor head, a third of the chassis' 3 rad/s^2.
  float mapping_max_alpha_rps2 = 1.0f;
  float control_period_s = 0.05f;  ///< control period [s], (0, 10]: 20 Hz (DESIGN.md §3); window = limits * period
  int v_samples = 20;              ///< samples of v in the window, [1, 1000]
  int omega_samples = 40;          ///< samples of omega in the window, [1, 1000] (800 trajectories)
  int steps = 30;                  ///< rollout steps per trajectory, [1, 1000]
  float sim_time_s = 1.5f;         ///< rollout horizon [s], (0, 60]: 0.75 m at 0.5 m/s, > 6x the braking distance
  float robot_radius_m = 0.20f;    ///< footprint radius [m], [0, inf) (Kobuki: 0.176 m + bumper)
  float safety_margin_m = 0.02f;   ///< extra clearance a trajectory must keep [m], [0, inf)
  /// Score weights, [0, inf) each (see the file comment, step 7). Progress dominates (up to
  /// 0.75 m per horizon); the path term pulls back to the path at half that rate per metre off;
  /// clearance (capped at clearance_cap_m) and speed only break near-ties, so the robot keeps
  /// to the middle of a corridor and does not crawl.
  float w_progress = 1.0f;   ///< [1/m]
  float w_path = 0.5f;       ///< [1/m]
  float w_clearance = 0.3f;  ///< [1/m]
  float w_speed = 0.1f;      ///< [s/m]
  float clearance_cap_m = 0.30f;  ///< clearance beyond the margin counts up to this [m], [0, inf)
  float lookahead_m = 1.0f;       ///< lookahead along the path [m], (0, inf): beyond one horizon's reach
  float goal_tolerance_m = 0.15f; ///< goal reached within this distance [m], [0, inf)
  // ---- oscillation / recovery ----
  int oscillation_window_calls = 60;       ///< calls (3 s at 20 Hz) without progress while moving, [1, 1e6]
  float oscillation_min_progress_m = 0.10f;  ///< translation that counts as progress [m], [0, inf)
  float oscillation_min_turn_rad = 0.5f;     ///< heading change that counts as progress [rad], [0, pi]
  int recovery_max_calls = 60;             ///< longest recovery phase (3 s at 20 Hz), [1, 1e6]
  float rotate_omega_rps = 0.6f;           ///< target |omega| of rotate-in-place [rad/s], (0, inf), capped at W
  float rotate_tolerance_rad = 0.35f;      ///< heading error to L below which rotating is pointless [rad], [0, pi]
  float backoff_distance_m = 0.15f;        ///< reverse travel of one back-off [m], [0, 10]
  float backoff_speed_mps = 0.1f;          ///< reverse speed of the back-off [m/s], (0, inf), capped at -min_v
};
/// Throws duet::Error(kInvalidArgument) naming the field and its allowed range (see the
/// comments above; also validate(limits)).
void validate(const DwaSettings& s);

enum class DwaStatus {
  kOk,                 ///< best admissible trajectory's command
  kGoalReached,        ///< within goal_tolerance_m of path.back(); zero command
  kRotateInPlace,      ///< recovery: rotating toward the path
  kBackOff,            ///< recovery: straight reverse
  kNoValidTrajectory,  ///< nothing admissible and no recovery possible; zero command
  kNoPath,             ///< empty path; zero command
};
[[nodiscard]] const char* to_string(DwaStatus s);

struct DwaResult {
  DwaStatus status = DwaStatus::kNoPath;
  Twist cmd;                      ///< command to send [m/s, rad/s]
  float score = 0.0f;             ///< score of the chosen trajectory (kOk), else -inf
  int valid_trajectories = 0;     ///< admissible trajectories this call (0 if none were rolled out)
  int evaluated_trajectories = 0; ///< trajectories rolled out this call (v_samples * omega_samples or 0)
  bool oscillation = false;       ///< a recovery phase started this call because of an oscillation
  Eigen::Vector2f lookahead{0.0f, 0.0f};  ///< the lookahead point L [m] (zero for kNoPath)
};

/// Small state between calls (oscillation detection, recovery phase); one per robot; value
/// type. Not thread-safe: one call at a time.
struct DwaState {
  enum class Phase : std::uint8_t { kNone, kRotate, kBackOff };
  Phase phase = Phase::kNone;
  int phase_calls = 0;          ///< calls spent in the current phase
  Pose2 phase_start;            ///< pose where the phase started
  bool anchor_valid = false;    ///< oscillation detector: anchor set
  Pose2 anchor;                 ///< pose of the last progress
  int stuck_calls = 0;          ///< consecutive moving calls without progress from the anchor
  bool last_cmd_moving = false; ///< the previous call commanded motion
  void reset() { *this = DwaState{}; }
};

/// Scratch buffers (no allocation per call once warmed up with the same sample counts).
/// Not thread-safe: one call at a time.
struct DwaWorkspace {
  std::vector<float> off_x, off_y;    ///< per omega sample, per step: position offset per unit v [s]
  std::vector<float> omegas, vs;      ///< samples
  std::vector<Eigen::Vector2f> local_path;  ///< P ... L
  struct RowBest {
    float score;
    int index;
    int valid;
  };
  std::vector<RowBest> rows;          ///< per v sample
};

/// One control step (see the file comment). Throws duet::Error(kInvalidArgument) for invalid
/// settings, an inconsistent clearance view, a non-finite pose / current twist / waypoint.
/// `current` is the chassis' present twist (odometry), the centre of the dynamic window.
DwaResult dwa_step(const ClearanceView& clearance, const Pose2& pose, const Twist& current,
                   std::span<const Eigen::Vector2f> path, const DwaSettings& s, DwaState& state,
                   DwaWorkspace& ws);

/// Helpers shared with tests and the runtime (pure, thread-safe).
/// Closest point on the path polyline to `p` (first segment wins a tie): segment index (the
/// point lies on [path[seg], path[seg+1]], seg = 0 for a one-point path) and the point.
struct PathProjection {
  int segment = 0;
  Eigen::Vector2f point{0.0f, 0.0f};
};
[[nodiscard]] PathProjection project_on_path(std::span<const Eigen::Vector2f> path, const Eigen::Vector2f& p);

}  // namespace duet
