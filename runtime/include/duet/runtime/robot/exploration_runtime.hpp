#pragma once
/// @file exploration_runtime.hpp
/// The exploration loop of a robot (DESIGN.md §3), independent of where the data comes from:
/// it reads the ChassisInterface and RgbdSensorInterface of robot_io.hpp (the simulator, a
/// recording, the C API or real drivers) and, once per control period (tick()):
///  1. odometry and frames -> the approximate-time synchronizer (sensor 0..n-1, then odometry);
///  2. a synchronized set at the map rate (paper §4.2: 1 Hz) -> a map update: the pose at the
///     frames' time (wheel odometry interpolated, corrected by scan-to-map matching,
///     PoseCorrector) -> the mapper -> loop closure (LoopCloser: the map frame may move, and
///     what is kept in it moves too) -> the recent obstacles (ObstacleMemory) -> the
///     navigator's costmaps and re-planned path (Navigator);
///  3. control: the pose (latest odometry, corrected) -> the controller follows the
///     navigator's path (Controller), asking it for a decision when it has no goal -> command.
///
/// Execution (RuntimeSettings::execution):
///  - kLockstep: tick() runs the map update and any decision before it returns. Deterministic:
///    the same inputs give the same commands, bit for bit, whatever the thread count. The
///    simulator's default and single-threaded embedding.
///  - kBackground: tick() never waits for a map update, a decision or loop closure. They run as
///    background tasks (BackgroundWorker, in the runtime's own TBB arena of background_threads)
///    and their results are taken by the first tick() after they finish; meanwhile the
///    controller follows the current path, and stops (zero twist) when it has none. A map
///    update due while the last one still runs is skipped (stats().map_sets_skipped). The
///    controller's events (trail, stall, goal reached or abandoned) reach the navigator at the
///    start of its next task.
/// Until visual odometry exists the map frame is the odometry frame corrected by the matcher
/// and the loop closer (with the correction off: the odometry frame itself).
///
/// Thread safety: one thread (the control thread) calls tick() and the accessors. In
/// kBackground, mapper(), explorer() and loop_closer() belong to the background task: read
/// them only after drain(); state(), stop_status(), explorer_stats() and map_grid() are safe.
#include <duet/runtime/localization/visual_localization.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/robot/runtime_settings.hpp>
#include <duet/runtime/localization/loop_closure.hpp>
#include <duet/runtime/localization/pose_corrector.hpp>
#include <duet/runtime/mapping/mapper.hpp>
#include <duet/runtime/navigation/explorer.hpp>
#include <duet/runtime/navigation/obstacle_memory.hpp>
#include <duet/runtime/robot/input_guard.hpp>
#include <duet/runtime/robot/latency.hpp>
#include <duet/runtime/robot/robot_io.hpp>
#include <duet/runtime/robot/synchronizer.hpp>

#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

namespace duet {

class BackgroundWorker;



struct RuntimeStats {
  std::size_t sets_integrated = 0;       ///< synchronized sets the mapper integrated
  std::size_t sets_not_integrated = 0;   ///< sets between map times
  std::size_t map_sets_skipped = 0;      ///< kBackground: sets due for a map update while the last one still ran
  std::uint64_t frames_received = 0;
  std::uint64_t frame_drops = 0;         ///< frames the synchronizer dropped (all sensors)
  std::uint64_t odometry_received = 0;
  std::uint64_t odometry_unmatched = 0;  ///< odometry in no set (50 Hz odometry vs the frame rate: expected)
  std::size_t scan_matches = 0;          ///< map updates whose scan match was accepted
  std::size_t scan_match_rejected = 0;   ///< ... not accepted: correction kept
  double scan_match_time_s = 0.0;        ///< wall time in the correction [s]
  std::size_t loop_closures = 0;         ///< closures that moved the map frame
  std::size_t decisions_requested = 0;   ///< kBackground: decision tasks started
  InputStats input;                      ///< what the input guard dropped, absorbed or replaced (input_guard.hpp)
  std::uint64_t sets_with_missing = 0;   ///< sets mapped with a missing frame (silent or garbled sensor)
  std::uint64_t blind_holds = 0;         ///< control periods held still: no frame mapped for too long
  std::size_t relocalizations = 0;       ///< wide re-matches that moved the pose (pushed, slipped)
  std::size_t relocalizations_held = 0;  ///< wide re-matches not tried: vision confirmed the odometry
  std::size_t relocalizations_ambiguous = 0;   ///< wide re-matches not taken: another fit in the window nearly as good
  std::size_t relocalizations_in_obstacle = 0;  ///< wide re-matches not taken: the robot would stand in a wall
  std::size_t relocalizations_at_edge = 0;      ///< wide re-matches not taken: on the window's edge
  std::size_t relocalizations_new_space = 0;  ///< wide re-matches not tried: the scan saw new space, the map did not contradict the prediction
  std::size_t relocalizations_asked = 0; ///< wide re-matches tried at once: vision gated out a jump the wheels did not make
  VisualLocalizationStats visual;        ///< visual odometry + EKF (all 0 when localization.visual_odometry is off)
  std::size_t visual_sets_incomplete = 0;  ///< sets vision skipped: a sensor's frame missing
  std::size_t visual_sets_busy = 0;        ///< kBackground: sets vision skipped, the front end still on the last one
};

/// Wall-clock timing of the loop (meaningful when the loop is paced by the wall clock).
struct RuntimeTiming {
  double nominal_period_s = 0.05;
  LatencySummary control_period;   ///< between the starts of consecutive ticks
  LatencySummary command_latency;  ///< odometry taken -> command sent, within a tick
  LatencySummary frame_to_map;     ///< frames' stamp -> their map update done (runtime clock + wall)
  LatencySummary decision;         ///< a decision asked for -> its goal delivered to the controller
  std::size_t late_periods = 0;    ///< periods longer than 1.1 x nominal
  std::size_t missed_periods = 0;  ///< periods longer than 2 x nominal (a deadline missed by more than one period)
};

class ExplorationRuntime {
 public:
  /// `chassis` and `sensors` (one per profile sensor, in the profile's order) must outlive the
  /// runtime. Throws duet::Error(kInvalidArgument) for a sensor count that does not match the
  /// profile or invalid settings.
  ExplorationRuntime(const Profile& profile, ChassisInterface& chassis, std::span<RgbdSensorInterface* const> sensors,
                     const RuntimeSettings& settings);
  /// ... with the profile's runtime settings (Profile::runtime).
  ExplorationRuntime(const Profile& profile, ChassisInterface& chassis, std::span<RgbdSensorInterface* const> sensors)
      : ExplorationRuntime(profile, chassis, sensors, profile.runtime) {}
  ~ExplorationRuntime();
  ExplorationRuntime(const ExplorationRuntime&) = delete;
  ExplorationRuntime& operator=(const ExplorationRuntime&) = delete;

  /// One control period at runtime time now_s [s] (non-decreasing). In kBackground it never
  /// waits for a background task; it rethrows the first error a task raised.
  void tick(double now_s);
  /// kBackground: waits for the background tasks and takes their results (for shutdown and
  /// tests, not for the control thread). kLockstep: nothing to wait for.
  void drain();
  /// kBackground: while held, no new map update is submitted (the sets due are skipped as while
  /// one is in flight, counted in map_sets_skipped); control and decisions go on. With
  /// wait_background_idle() it lets another thread read the map without holding control for a
  /// map update: hold (between ticks), wait for the background off the control thread, then
  /// drain() and read (between ticks), then let go. Control thread, between ticks.
  void hold_map_updates(bool hold) noexcept { map_updates_held_ = hold; }
  /// kBackground: blocks until the background tasks are done (their results not taken: drain()
  /// does that). Any thread; not the control thread. kLockstep: returns at once.
  void wait_background_idle() const;

  /// The operator's requests (control thread, between ticks). return_home(): stop exploring
  /// and drive back to the start (Navigator::return_home). stop(): the explorer is done now,
  /// the robot holds still; stop_detail() = `why`. In kBackground the navigator hears of them at
  /// the start of its next task (a decision submitted now, or the map update in flight); the
  /// controller stops following the old goal at once.
  void return_home(double now_s);
  void stop(const std::string& why);

  /// DEBUGGING ONLY: map and plan with this pose instead of the odometry (nullopt: odometry).
  void override_pose(const std::optional<Pose2>& pose) { pose_override_ = pose; }

  /// The pose estimate: correction() applied to the latest odometry (or the override).
  [[nodiscard]] const Pose2& pose() const noexcept { return pose_; }
  /// The correction map <- odometry frame (identity until a match is accepted).
  [[nodiscard]] const Pose2& correction() const noexcept { return correction_; }
  /// Visual odometry's health (localization.visual_odometry on), else nullopt.
  [[nodiscard]] std::optional<LocalizationHealth> localization_health() const noexcept;
  /// The rate the pose correction adds to the odometry's heading [rad/s] (PoseCorrector::
  /// heading_rate()): minus the odometry heading's drift (a gyro's bias) when it is right.
  [[nodiscard]] float heading_rate() const noexcept { return heading_rate_; }
  [[nodiscard]] const Twist& last_command() const noexcept { return last_cmd_; }
  /// The goal the controller follows and its path (map frame; none / empty without a goal).
  /// Safe on the control thread in both executions.
  [[nodiscard]] std::optional<Pose2> goal() const;
  [[nodiscard]] std::span<const Eigen::Vector2f> path() const;
  /// True while the robot holds still because no frame has been mapped for too long.
  [[nodiscard]] bool blind() const noexcept { return blind_; }
  [[nodiscard]] ExplorerState state() const;
  [[nodiscard]] ExplorationStatus stop_status() const;
  [[nodiscard]] std::string stop_detail() const;
  /// What was left unexplored when the explorer stopped (Navigator::left_unexplored()).
  [[nodiscard]] std::vector<UnexploredRegion> left_unexplored() const;
  [[nodiscard]] ExplorerStats explorer_stats() const;
  /// The latest map's grid (valid until the next tick()).
  [[nodiscard]] const OccupancyGrid& map_grid() const;
  [[nodiscard]] const RuntimeStats& stats() const noexcept { return stats_; }
  /// What the runtime noticed about its inputs and did about it, with times (capped at 1000).
  [[nodiscard]] const std::vector<RuntimeEvent>& events() const noexcept { return guard_.events(); }
  [[nodiscard]] RuntimeTiming timing() const;
  [[nodiscard]] const ApproximateTimeCore& synchronizer() const noexcept { return sync_; }
  [[nodiscard]] const Profile& profile() const noexcept { return profile_; }
  [[nodiscard]] const RuntimeSettings& settings() const noexcept { return settings_; }

  // Owned by the background task in kBackground: read only after drain().
  [[nodiscard]] Mapper& mapper() noexcept { return mapper_; }
  [[nodiscard]] const Mapper& mapper() const noexcept { return mapper_; }
  [[nodiscard]] const Explorer& explorer() const noexcept { return explorer_; }
  /// The loop closer (nullptr when loop closure or the pose correction is off).
  [[nodiscard]] const LoopCloser* loop_closer() const noexcept { return loop_ ? &*loop_ : nullptr; }

 private:
  class Link;
  struct MapInput;
  struct Result;
  struct Event;
  void handle_set(const ApproximateTimeCore::Set& set, double now_s);
  /// The map update (step 2) on `in`; returns the loop closure's shift if the map frame moved.
  std::optional<Pose2> map_update(MapInput& in);
  void submit_map_update(MapInput&& in);
  void submit_decision(const Pose2& robot, double now_s);
  void take_results();
  void apply_events();
  [[nodiscard]] Pose2 odometry_at(double t, const OdometryMsg& fallback) const;
  /// The inputs' time base stepped back: a new synchronizer and odometry history.
  void restart_time();
  void note_relocalization(std::size_t count, const Pose2& offset, const RelocalizationScores& scores, float conflict, double now_s);
  void take_inputs(double now_s);
  /// Visual odometry on a synchronised set (all sensors' frames), the EKF's update, the health;
  /// in kBackground the front end runs on visual_worker_ and finish_visual() fuses its result.
  void track_visual(const std::vector<RgbdImage>& images, const ApproximateTimeCore::Set& set, double now_s);
  void finish_visual(double now_s);  ///< kBackground: fuses a finished front end's result, if any
  void update_health(double now_s);  ///< vision's health at now_s, a change logged

  CameraPoints camera_points_;  ///< the map update's frames, back-projected once (owned by whoever runs map_update)
  Profile profile_;
  RuntimeSettings settings_;
  ChassisInterface& chassis_;
  std::vector<RgbdSensorInterface*> sensors_;
  // ---- the pipeline (the control thread in kLockstep, the background task in kBackground)
  Mapper mapper_;
  Explorer explorer_;            ///< its navigator in the pipeline, its controller on the control thread
  PoseCorrector corrector_;
  ObstacleMemory memory_;
  std::optional<LoopCloser> loop_;
  // ---- the control thread
  std::unique_ptr<VisualLocalization> visual_;  ///< localization.visual_odometry: wheels + vision, the odometry the rest sees
  std::optional<LocalizationHealth> health_;
  double last_visual_t_ = -1.0;  ///< stamp of the last set vision tracked
  std::size_t visual_gated_seen_ = 0;  ///< vision's gated jumps already passed to the pose correction
  /// The controller's stalls already passed to a map update (a stall since: the robot drove into
  /// something where its map shows free floor, so the pose may be off - the update re-matches wide).
  int stalls_seen_ = 0;
  double last_now_s_ = 0.0;     ///< the last tick's time
  InputGuard guard_;
  ApproximateTimeCore sync_;
  std::unordered_map<std::uint64_t, RgbdImage> frames_;     ///< payloads waiting in the synchronizer, by id
  std::unordered_map<std::uint64_t, OdometryMsg> odometry_;
  std::uint64_t next_id_ = 0;
  double next_map_t_ = 0.0;
  bool map_t_restart_ = false;  ///< the next set sets next_map_t_ (after restart_time())
  double last_seen_t_ = -1.0;   ///< runtime time of the last set with a real frame (-1: none yet)
  bool blind_ = false;
  Pose2 pose_;
  Pose2 odom_pose_;             ///< latest odometry (the wheels', or fused with vision)
  static constexpr std::size_t kOdomHistory = 256;  ///< odometry kept for interpolation (5 s at 50 Hz)
  std::deque<OdometryMsg> odom_history_;
  Pose2 correction_;
  float heading_rate_ = 0.0f;
  Twist odom_twist_;
  Twist last_cmd_;
  std::optional<Pose2> pose_override_;
  bool stop_asked_ = false;     ///< kBackground: stop() was called (the navigator may not know yet)
  std::string stop_why_;
  RuntimeStats stats_;
  LatencyStats period_, command_, decision_latency_;
  LatencyStats frame_to_map_;   ///< added by map_update() in kLockstep, by take_results() in kBackground
  double last_tick_wall_ = -1.0;
  // ---- kBackground: what the two sides exchange
  std::unique_ptr<Link> link_;
  std::shared_ptr<const NavSnapshot> plan_;          ///< control side: the latest published plan
  std::shared_ptr<const OccupancyGrid> grid_copy_;   ///< control side: the latest map's grid
  OccupancyGrid empty_grid_;                         ///< map_grid() before the first map update
  ExplorerStats nav_stats_;                          ///< control side: the navigator's latest counters
  bool map_in_flight_ = false, decision_in_flight_ = false;
  bool map_updates_held_ = false;  ///< hold_map_updates
  double decision_asked_wall_ = 0.0;
  std::mutex inbox_mutex_;
  std::vector<Event> inbox_;                         ///< controller -> navigator events
  std::mutex results_mutex_;
  std::vector<Result> results_;                      ///< background -> control results
  // ---- kBackground with vision: the front end's set in flight (one at a time)
  bool visual_in_flight_ = false;
  VisualLocalization::Job visual_job_;               ///< control side: begin()'s job for the set in flight
  std::vector<RgbdImage> visual_images_;             ///< the set in flight (copies; the worker reads them)
  std::vector<SensorFrame> visual_views_;            ///< views into visual_images_
  std::mutex visual_mutex_;
  std::optional<VisualLocalization::Tracked> visual_result_;  ///< worker -> control
  std::unique_ptr<BackgroundWorker> visual_worker_;  ///< destroyed before the members its task uses
  std::unique_ptr<BackgroundWorker> worker_;         ///< last: destroyed first (its tasks use the members above)
};

}  // namespace duet
