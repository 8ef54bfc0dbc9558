#pragma once
/// @file sim_explore.hpp
/// The paper's experiment end to end in the simulator (issue 4): a robot with the profile's
/// RGB-D sensors set down in a World explores it through the same runtime pieces a real robot
/// uses - sensor frames and wheel odometry, the approximate-time synchronizer, the mapper on
/// the mapping kernels, the explorer and the controller on the exploration kernels - on a
/// clock that is simulated (lockstep, default) or the wall clock (realtime).
///
/// The simulator implements the robot interfaces of robot_io.hpp (SimChassis is the
/// ChassisInterface, SimRgbdSensor the RgbdSensorInterface) and drives the same
/// ExplorationRuntime a real robot runs. One loop iteration per control period (20 Hz):
///  1. the chassis advances one period (physics at 5 ms, odometry messages at 50 Hz);
///  2. the sensors render when their period is due (sensor_rate_hz; default: the map rate,
///     i.e. only the frames the pipeline consumes), stamped with the render time, posed by the
///     TRUE robot pose (the world does not know about odometry drift);
///  3. ExplorationRuntime::tick(): synchronizer -> mapper (1 Hz) -> explorer -> command; the
///     pose is the noisy wheel odometry corrected by scan-to-map matching (pose_correction;
///     enabled = false: the raw odometry) - the true pose only with use_true_pose (a debugging
///     option, never the default);
///  4. the run is scored: coverage, time-area curve, collisions, target region.
/// Frames: the odometry starts at the world's start pose, so the map frame is the world frame
/// up to the pose estimate's drift; coverage is measured by looking up the world's reachable free cells
/// in the map.
///
/// Determinism: the same world, profile and seed give the same trajectory, map and summary
/// (except wall times) for any number of threads, in lockstep mode.
/// Thread safety: one SimExplore per thread of calls; it runs TBB-parallel kernels in the
/// caller's task arena.
#include <duet/kernels/grid.hpp>
#include <duet/runtime/robot/exploration_runtime.hpp>
#include <duet/runtime/navigation/explorer.hpp>
#include <duet/runtime/mapping/mapper.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/sim/chassis.hpp>
#include <duet/sim/renderer.hpp>
#include <duet/sim/sim_robot.hpp>
#include <duet/sim/world.hpp>
#include <duet/runtime/robot/clock.hpp>
#include <duet/runtime/robot/faults.hpp>
#include <duet/runtime/io/recording.hpp>
#include <duet/runtime/robot/synchronizer.hpp>

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

namespace duet::sim {

struct ExploreSettings {
  std::uint64_t seed = 1;          ///< seeds the chassis noise, the sensor noise and Procedure 1
  double max_time_s = 900.0;       ///< stop after this much simulated time [s], (0, 1e6]
  /// Stop once the scored coverage (CurvePoint::coverage, measured every curve_period_s)
  /// reaches this fraction, [0, 1]; 0 = never. For measuring times to a coverage (T_90) without
  /// running on to the end: such a run stops with StopReason::kCoverageReached.
  double stop_at_coverage = 0.0;
  /// Sensor render rate [Hz]; 0 = the map rate (render only what the pipeline consumes, the
  /// default); the profile's rate (30 Hz) renders every frame a Kinect would give. [0, 1000]
  double sensor_rate_hz = 0.0;
  bool realtime = false;           ///< pace the loop by the wall clock (`--realtime`)
  bool use_true_pose = false;      ///< DEBUGGING ONLY: map and plan with the true pose
  double curve_period_s = 1.0;     ///< time-area curve sampling [s], (0, 60]
  float coverage_resolution_m = 0.05f;  ///< ground-truth raster for coverage [m], (0, 1]
  RenderSettings render;
  /// Chassis simulation: from the profile's chassis (limits, odometry rate) with the gyro
  /// heading of a Kobuki when unset; its seed is replaced by a value derived from `seed`.
  std::optional<ChassisSimSettings> chassis;
  /// The robot's runtime: rates, execution (lockstep: deterministic; background: as on a
  /// robot), explorer, synchronizer, pose correction, loop closure. Its sensor_rate_hz is
  /// replaced by the render rate above.
  RuntimeSettings runtime;
  /// Faults injected into the run (faults.hpp: "camera_stop:1@60+10", ...): the stream faults
  /// between the simulated robot and the runtime, extrinsics and kidnap in the simulator.
  std::vector<std::string> faults;
  /// The run's health (resident memory, per-cycle time, map size) sampled every this often
  /// [s], [0, 3600]; 0 = never.
  double health_period_s = 60.0;
  /// Record every input stream the runtime takes into this folder (new or empty;
  /// runtime/io/recording.hpp); empty = no recording. `duet replay` maps it again.
  std::string record_dir;
};
void validate(const ExploreSettings& s);

/// The settings `duet explore` runs a profile with: the profile's settings tree (runtime,
/// localization, exploration, control) and its faults, the seed and the time limit [s].
/// sensor_rate_hz: < 0 = every frame the profile's sensors give; 0 = what the pipeline consumes
/// (the map rate, or vision's rate when the profile enables visual odometry); > 0 = that rate.
ExploreSettings explore_settings(const Profile& profile, std::uint64_t seed, double max_time_s, double sensor_rate_hz = 0.0);

/// One health sample: the last health_period_s of the run.
struct HealthSample {
  double t_s = 0.0;               ///< simulated time at the end of the window [s]
  double rss_mb = -1.0;           ///< resident memory [MiB] (-1: cannot be read here)
  double tick_mean_ms = 0.0;      ///< the runtime's tick (wall time) over the window: mean [ms]
  double tick_max_ms = 0.0;       ///< ... and max [ms]
  double step_mean_ms = 0.0;      ///< the whole simulated period (physics, rendering, tick, scoring): mean [ms]
  std::size_t grid_cells = 0;     ///< cells of the map grid
  long submaps = -1;              ///< the mapper's submaps (-1: not readable while a background task runs)
  std::string explorer_state;     ///< the explorer's state at the end of the window
  double heading_rate_radps = 0.0;  ///< the rate the pose correction adds to the odometry's heading (minus its estimated drift) [rad/s]
};

struct CurvePoint {
  double t_s = 0.0;          ///< simulated time [s]
  double area_m2 = 0.0;      ///< explored area: known (free or occupied) cells of the grid [m^2]
  double coverage = 0.0;     ///< fraction of the world's reachable free area known as free, [0, 1]
};

/// Why the run stopped.
enum class StopReason {
  kRunning,
  kExplorerDone,   ///< the explorer found nothing left to explore (see explorer_status)
  kTimeLimit,      ///< max_time_s reached
  kCoverageReached,  ///< the scored coverage reached ExploreSettings::stop_at_coverage
  kInterrupted,    ///< interrupt() (e.g. SIGINT): stopped early, the run so far is complete and scored
};
[[nodiscard]] const char* to_string(StopReason r);

struct ExploreSummary {
  std::string world, profile;
  Pose2 start;  ///< the robot's start pose (world frame)
  std::uint64_t seed = 0;
  StopReason stop_reason = StopReason::kRunning;
  std::string explorer_status;           ///< the explorer's last decision status (when done)
  std::string stop_detail;               ///< why the explorer stopped, in words (Navigator::stop_detail())
  std::vector<UnexploredRegion> left;    ///< what the explorer left, where and why (Navigator::left_unexplored())
  std::string explorer_state;            ///< idle, exploring, returning_home or done
  double sim_time_s = 0.0;
  double wall_time_s = 0.0;
  double explored_area_m2 = 0.0;
  double reachable_free_area_m2 = 0.0;   ///< the denominator of coverage
  double coverage = 0.0;
  double t90_s = -1.0;                   ///< first time coverage >= 90 % (-1: never)
  double t_paper_area_s = -1.0;          ///< first time area >= 31.0 m^2 (paper: 196 s dual) (-1: never)
  double target_entered_s = -1.0;        ///< first time the true pose entered the target region (-1: never / none)
  double path_length_m = 0.0;            ///< true path length
  std::size_t collisions = 0;
  ExplorerStats explorer;
  std::size_t frames_rendered = 0;
  std::size_t sets_integrated = 0;       ///< synchronized sets the mapper integrated
  std::size_t sets_not_integrated = 0;   ///< sets between map times (no consumer yet)
  std::uint64_t frame_drops = 0;         ///< sensor frames the synchronizer dropped (all sensors)
  std::uint64_t odometry_unmatched = 0;  ///< odometry messages in no set (expected: 50 Hz vs the sensor rate)
  double odometry_error_m = 0.0;         ///< |raw wheel odometry - truth| at the end [m]
  double pose_error_m = 0.0;             ///< |pose estimate (corrected odometry) - truth| at the end [m]
  double pose_error_max_m = 0.0;         ///< max over the run of |pose estimate - truth| [m]
  double heading_error_deg = 0.0;        ///< |pose estimate's heading - truth's| at the end [deg]
  double heading_rate_radps = 0.0;       ///< the rate the pose correction adds to the odometry's heading at the end (minus its estimated drift) [rad/s]
  double gyro_bias_radps = 0.0;          ///< the simulated gyro's true bias (0 without a gyro) [rad/s]
  bool visual_odometry = false;          ///< localization.visual_odometry was on
  VisualLocalizationStats visual;        ///< its counters
  std::size_t visual_sets_incomplete = 0;
  std::size_t visual_sets_busy = 0;     ///< background execution: sets skipped while the front end ran
  std::string localization_health;       ///< at the end: good / degraded / lost ("" without vision)
  std::size_t scan_matches = 0;          ///< map updates whose scan match was accepted
  std::size_t scan_match_rejected = 0;   ///< map updates whose scan match was not (correction kept)
  double scan_match_time_s = 0.0;        ///< wall time in the scan-to-map correction [s]
  Execution execution = Execution::kLockstep;  ///< how the runtime ran
  bool realtime = false;                 ///< the loop was paced by the wall clock
  RuntimeTiming timing;                  ///< the runtime's control period, latencies (wall clock)
  std::size_t map_sets_skipped = 0;      ///< background: map updates skipped while the last one ran
  bool loop_closure = false;             ///< the loop closer ran
  LoopClosureStats loops;                ///< its counters (all 0 without it)
  std::vector<FaultCount> faults;        ///< each injected fault and how often it acted
  InputStats input;                      ///< what the runtime's input guard did (input_guard.hpp)
  std::uint64_t sets_with_missing = 0;   ///< sets mapped with a silent or garbled sensor left out
  std::uint64_t blind_holds = 0;         ///< control periods held still with no frame mapped
  std::size_t relocalizations = 0;       ///< wide re-matches that moved the pose
  std::size_t relocalizations_held = 0;  ///< wide re-matches not tried: vision confirmed the odometry
  std::size_t relocalizations_new_space = 0;  ///< wide re-matches not tried: the scan saw new space
  std::size_t relocalizations_ambiguous = 0;  ///< wide re-matches not taken: another fit nearly as good
  std::size_t relocalizations_in_obstacle = 0;  ///< wide re-matches not taken: the robot would stand in a wall
  std::size_t relocalizations_at_edge = 0;      ///< wide re-matches not taken: on the window's edge
  std::size_t relocalizations_asked = 0; ///< wide re-matches tried at once: vision gated out a jump
  double occupied_on_obstacles = -1.0;   ///< share of the grid's occupied cells within 0.1 m of a true obstacle (-1: none occupied)
};

/// What a grid knows of a world: the known (free or occupied, by `cells`) area [m^2], and the
/// share of the `reachable` cells of `truth` (reachable_free_mask) it knows, [0, 1] (0 when
/// none is reachable). The grid's frame is the world frame. The measure of the run summary.
struct CoverageMeasure {
  double area_m2 = 0.0;
  double coverage = 0.0;
};
[[nodiscard]] CoverageMeasure measure_coverage(const OccupancyGrid& grid, const CellThresholds& cells, const TruthGrid& truth,
                                               std::span<const std::uint8_t> reachable);

/// One collision (a contact onset of the chassis).
struct CollisionRecord {
  double t_s = 0.0;
  Pose2 true_pose;     ///< where the robot stopped
  Twist command;       ///< the command it was following
  Pose2 estimated_pose;  ///< where the robot believed it was (the runtime's pose)
  /// Distance from the estimated centre to the nearest occupied cell centre of the robot's own
  /// map [m], searched within 1 m (infinity: none): below the chassis radius the robot drove
  /// into what it had mapped; above, the map or the pose was off by the difference.
  float map_clearance_m = std::numeric_limits<float>::infinity();
};

/// The distance from `xy` to the nearest occupied cell centre of `g` within `radius_m` [m]
/// (infinity: none, or `xy` not finite).
[[nodiscard]] float occupied_clearance(const OccupancyGrid& g, const CellThresholds& cells, const Eigen::Vector2f& xy, float radius_m);

/// One stamped pose of a trajectory.
struct StampedPose {
  double t_s = 0.0;
  Pose2 pose;
};

class SimExplore {
 public:
  /// Builds the renderer, the chassis, the mapper and the explorer. Throws duet::Error for an
  /// invalid world, profile or settings (the message names what is wrong).
  SimExplore(World world, Profile profile, ExploreSettings settings = {});
  ~SimExplore();
  SimExplore(const SimExplore&) = delete;
  SimExplore& operator=(const SimExplore&) = delete;

  /// One control period. Returns false once the run has stopped (explorer done or time limit).
  bool step();
  /// Steps until the run stops; calls `progress` about once per simulated second.
  void run(const std::function<void(const SimExplore&)>& progress = {});
  /// Stops a running run now (StopReason::kInterrupted): background tasks are finished and the
  /// run is scored as it stands. `why` becomes the summary's stop_detail. No effect once stopped.
  void interrupt(const std::string& why);

  [[nodiscard]] double now_s() const noexcept { return t_; }
  /// Opens the closed door (Solid::door) called `name` now (SimRobot::open_door); false if there
  /// is none. Coverage already counts the area behind every door.
  bool open_door(const std::string& name) { return robot_.open_door(name); }
  [[nodiscard]] bool running() const noexcept { return reason_ == StopReason::kRunning; }
  [[nodiscard]] ExploreSummary summary() const;
  [[nodiscard]] const std::vector<CurvePoint>& curve() const noexcept { return curve_; }
  [[nodiscard]] const std::vector<StampedPose>& estimated_trajectory() const noexcept { return est_traj_; }
  [[nodiscard]] const std::vector<StampedPose>& true_trajectory() const noexcept { return true_traj_; }
  [[nodiscard]] const std::vector<CollisionRecord>& collision_log() const noexcept { return collision_log_; }
  /// The health samples so far (ExploreSettings::health_period_s).
  [[nodiscard]] const std::vector<HealthSample>& health() const noexcept { return health_; }
  /// The recording's counters (all 0 without ExploreSettings::record_dir).
  [[nodiscard]] RecorderStats recording() const { return recorder_ ? recorder_->stats() : RecorderStats{}; }
  [[nodiscard]] Mapper& mapper() noexcept { return runtime_->mapper(); }
  [[nodiscard]] const Explorer& explorer() const noexcept { return runtime_->explorer(); }
  [[nodiscard]] const ExplorationRuntime& runtime() const noexcept { return *runtime_; }
  /// The world as loaded (doors closed); robot().world() is the world as it stands.
  [[nodiscard]] const World& world() const noexcept { return *world_; }
  [[nodiscard]] const SimChassis& chassis() const noexcept { return robot_.sim_chassis(); }
  /// Current explored area [m^2] and coverage (as in the curve).
  [[nodiscard]] CurvePoint measure() const;

 private:
  void finish();  ///< the run has stopped: drain the runtime, the last curve point
  void apply_sim_faults();  ///< extrinsics and kidnap at t_
  void sample_health(double tick_s, double step_s);  ///< one period's times; a sample when due
  [[nodiscard]] RobotSource& source() {
    if (recording_) return *recording_;
    return injector_ ? static_cast<RobotSource&>(*injector_) : robot_;
  }
  [[nodiscard]] double occupied_on_obstacles() const;

  std::shared_ptr<const World> world_;
  Profile profile_;
  ExploreSettings settings_;
  SimRobot robot_;
  std::unique_ptr<FaultInjector> injector_;  ///< between robot_ and the runtime when faults are injected
  std::unique_ptr<Recorder> recorder_;          ///< ExploreSettings::record_dir
  std::unique_ptr<RecordingSource> recording_;  ///< between the source above and the runtime while recording
  std::vector<bool> fault_started_;
  std::unique_ptr<ExplorationRuntime> runtime_;
  TruthGrid truth_;
  std::vector<std::uint8_t> reachable_;
  std::size_t reachable_count_ = 0;
  SteadyClock wall_;  ///< wall time since construction; paces the loop when realtime
  double t_ = 0.0;
  double dt_ = 0.05;
  double next_curve_t_ = 0.0;
  StopReason reason_ = StopReason::kRunning;
  std::string interrupt_detail_;
  std::vector<CurvePoint> curve_;
  std::vector<CollisionRecord> collision_log_;
  std::vector<StampedPose> est_traj_, true_traj_;
  double path_length_ = 0.0;
  double pose_error_max_ = 0.0;
  double target_entered_ = -1.0;
  double t90_ = -1.0, t_paper_ = -1.0;
  double wall_elapsed_ = 0.0;
  std::vector<HealthSample> health_;
  double next_health_t_ = 0.0;
  double tick_sum_s_ = 0.0, tick_max_s_ = 0.0, step_sum_s_ = 0.0;
  std::size_t health_periods_ = 0;
};

}  // namespace duet::sim
