/// @file exploration_runtime.cpp
/// The exploration loop on the robot interfaces (see exploration_runtime.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/robot/background_worker.hpp>
#include <duet/runtime/robot/exploration_runtime.hpp>

#include "exploration_runtime_tasks.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <thread>

namespace duet {
namespace {

ApproximateTimeSettings sync_settings(const Profile& profile, const RuntimeSettings& s) {
  ApproximateTimeSettings a = s.sync;
  const double odom_rate = profile.chassis.odometry_rate_hz;
  // Odometry runs at 50 Hz against frames at sensor_rate_hz: hold at least two frame periods of
  // it so that overflow never takes the message a set needs.
  a.queue_size = std::max<std::size_t>(a.queue_size, static_cast<std::size_t>(std::ceil(2.0 * odom_rate / s.sensor_rate_hz)) + 2);
  // True lower bounds on the stamp intervals let sets be emitted at once.
  a.inter_message_lower_bounds_s.assign(profile.sensors.size(), 0.9 / s.sensor_rate_hz);
  a.inter_message_lower_bounds_s.push_back(0.9 / odom_rate);
  return a;
}

}  // namespace

const char* to_string(Execution e) { return e == Execution::kBackground ? "background" : "lockstep"; }

void validate(const RuntimeSettings& s) {
  auto bad = [](const std::string& what) { fail(ErrorCode::kInvalidArgument, "RuntimeSettings::" + what); };
  if (!(std::isfinite(s.control_rate_hz) && s.control_rate_hz > 0.0 && s.control_rate_hz <= 1000.0))
    bad("control_rate_hz must be in (0, 1000] Hz, got " + std::to_string(s.control_rate_hz));
  if (!(std::isfinite(s.map_rate_hz) && s.map_rate_hz > 0.0 && s.map_rate_hz <= s.control_rate_hz))
    bad("map_rate_hz must be in (0, control_rate_hz] Hz, got " + std::to_string(s.map_rate_hz));
  if (!(std::isfinite(s.sensor_rate_hz) && s.sensor_rate_hz > 0.0 && s.sensor_rate_hz <= 1000.0))
    bad("sensor_rate_hz must be in (0, 1000] Hz, got " + std::to_string(s.sensor_rate_hz));
  if (s.background_threads < 0 || s.background_threads > 256)
    bad("background_threads must be in [0, 256], got " + std::to_string(s.background_threads));
  if (!(std::isfinite(s.decision_delay_s) && s.decision_delay_s >= 0.0 && s.decision_delay_s <= 60.0))
    bad("decision_delay_s must be in [0, 60] s, got " + std::to_string(s.decision_delay_s));
  validate(s.explorer);
  validate(s.sync);
  validate(s.input);
  validate(s.pose_correction);
  validate(s.loop_closure);
  validate(s.visual_odometry);
}

ExplorationRuntime::ExplorationRuntime(const Profile& profile, ChassisInterface& chassis,
                                       std::span<RgbdSensorInterface* const> sensors, const RuntimeSettings& settings)
    : profile_(profile),
      settings_((validate(settings), settings)),
      chassis_(chassis),
      sensors_(sensors.begin(), sensors.end()),
      mapper_(profile.mapping),
      explorer_(profile, settings.explorer),
      corrector_(profile, settings.pose_correction),
      memory_(settings.explorer),
      guard_(profile, settings.sensor_rate_hz, settings.input),
      sync_(profile.sensors.size() + 1, sync_settings(profile, settings)) {
  if (sensors_.size() != profile_.sensors.size())
    fail(ErrorCode::kInvalidArgument, "ExplorationRuntime: " + std::to_string(sensors_.size()) + " sensors for a profile with " +
                                          std::to_string(profile_.sensors.size()));
  for (std::size_t i = 0; i < sensors_.size(); ++i)
    if (sensors_[i] == nullptr) fail(ErrorCode::kInvalidArgument, "ExplorationRuntime: sensor " + std::to_string(i) + " is null");
  if (settings_.loop_closure.enabled && settings_.pose_correction.enabled)
    loop_.emplace(settings_.loop_closure, profile_.exploration.cells, mapper_);
  if (settings_.visual_odometry.enabled) visual_ = std::make_unique<VisualLocalization>(settings_.visual_odometry);
  if (settings_.execution == Execution::kBackground) {
    link_ = std::make_unique<Link>(*this);
    worker_ = std::make_unique<BackgroundWorker>(settings_.background_threads);
    if (visual_) visual_worker_ = std::make_unique<BackgroundWorker>(settings_.background_threads);
  }
}

ExplorationRuntime::~ExplorationRuntime() {  // the workers first: their tasks use the members
  worker_.reset();
  visual_worker_.reset();
}

ExplorerState ExplorationRuntime::state() const {
  if (!worker_) return explorer_.state();
  if (stop_asked_) return ExplorerState::kDone;
  return plan_ ? plan_->state : ExplorerState::kIdle;
}

std::optional<Pose2> ExplorationRuntime::goal() const {
  if (!worker_) return explorer_.goal();
  if (stop_asked_ || !plan_) return std::nullopt;
  return plan_->goal;
}

std::span<const Eigen::Vector2f> ExplorationRuntime::path() const {
  if (!worker_) return explorer_.path();
  if (stop_asked_ || !plan_) return {};
  return plan_->path;
}

ExplorationStatus ExplorationRuntime::stop_status() const {
  if (!worker_) return explorer_.stop_status();
  return plan_ ? plan_->stop_status : ExplorationStatus::kNoFrontier;
}

std::string ExplorationRuntime::stop_detail() const {
  if (!worker_) return explorer_.stop_detail();
  if (stop_asked_ && !(plan_ && plan_->state == ExplorerState::kDone)) return stop_why_;
  return plan_ ? plan_->stop_detail : std::string();
}

std::vector<UnexploredRegion> ExplorationRuntime::left_unexplored() const {
  if (!worker_) return explorer_.left_unexplored();
  return plan_ ? plan_->left : std::vector<UnexploredRegion>{};
}

void ExplorationRuntime::return_home(double now_s) {
  if (!worker_) {
    explorer_.navigator().return_home(pose_, now_s);
    return;
  }
  Event e;
  e.kind = Event::Kind::kReturnHome;
  e.robot = pose_;
  e.t_s = now_s;
  link_->request(std::move(e));
  submit_decision(pose_, now_s);  // a task that hears of it now (or the next map update, if one is in flight)
}

void ExplorationRuntime::stop(const std::string& why) {
  if (!worker_) {
    explorer_.navigator().stop(why);
    return;
  }
  stop_asked_ = true;
  stop_why_ = why;
  Event e;
  e.kind = Event::Kind::kStop;
  e.text = why;
  link_->request(std::move(e));
}

ExplorerStats ExplorationRuntime::explorer_stats() const {
  if (!worker_) return explorer_.stats();
  return merge_stats(nav_stats_, explorer_.controller().stats());
}

const OccupancyGrid& ExplorationRuntime::map_grid() const {
  if (!worker_) return mapper_.grid();
  return grid_copy_ ? *grid_copy_ : empty_grid_;
}

RuntimeTiming ExplorationRuntime::timing() const {
  RuntimeTiming t;
  t.nominal_period_s = 1.0 / settings_.control_rate_hz;
  t.control_period = period_.summary();
  t.command_latency = command_.summary();
  t.frame_to_map = frame_to_map_.summary();
  t.decision = worker_ ? decision_latency_.summary() : explorer_.navigator().decide_latency().summary();
  t.late_periods = period_.count_above(1.1 * t.nominal_period_s);
  t.missed_periods = period_.count_above(2.0 * t.nominal_period_s);
  return t;
}

Pose2 ExplorationRuntime::odometry_at(double t, const OdometryMsg& fallback) const {
  // The two messages around t in the recent history (stamps increasing); else the fallback.
  for (std::size_t k = 1; k < odom_history_.size(); ++k) {
    const OdometryMsg& a = odom_history_[k - 1];
    const OdometryMsg& b = odom_history_[k];
    if (!(a.stamp_s <= t && t <= b.stamp_s)) continue;
    const double span = b.stamp_s - a.stamp_s;
    const float u = span > 0.0 ? static_cast<float>((t - a.stamp_s) / span) : 0.0f;
    const float dth = std::remainder(b.pose.theta - a.pose.theta, 2.0f * std::numbers::pi_v<float>);
    return {a.pose.x + u * (b.pose.x - a.pose.x), a.pose.y + u * (b.pose.y - a.pose.y),
            std::remainder(a.pose.theta + u * dth, 2.0f * std::numbers::pi_v<float>)};
  }
  return fallback.pose;
}

std::optional<Pose2> ExplorationRuntime::map_update(MapInput& in) {
  const double w0 = runtime_wall_s();
  const std::size_t n = sensors_.size();
  std::vector<SensorFrame> frames;
  frames.reserve(n);
  for (std::size_t i = 0; i < n; ++i)  // a missing frame (a silent or garbled sensor) is left out
    if (in.images[i].width > 0) frames.push_back(frame_view(in.images[i], profile_.sensors[i], profile_.sensors[i].T_robot_optical()));
  // Each depth image is read once: the matcher and the mapper transform the same points.
  back_project_camera(frames, profile_.mapping.back_projection, camera_points_);
  // The pose at the frames' time: the odometry interpolated to their mean stamp, corrected by
  // scan matching against the map before it integrates them (or, debugging, the override).
  Pose2 at;
  Pose2 pose = in.override_pose ? *in.override_pose : compose(corrector_.correction(), in.odom_latest);
  if (in.override_pose) {
    at = *in.override_pose;
  } else {
    at = compose(corrector_.correction(), in.odom_at);
    if (settings_.pose_correction.enabled) {
      corrector_.confirm_odometry(in.odometry_confirmed);
      if (in.odometry_contradicted) corrector_.contradict_odometry();
      at = corrector_.update(camera_points_, frames, in.odom_at, mapper_.grid(), in.t_frames);
      pose = compose(corrector_.correction(), in.odom_latest);
    }
  }
  mapper_.integrate(camera_points_, frames, to_isometry(at));
  std::optional<Pose2> shift;
  if (!mapper_.cloud_frozen()) {
    // Exploration is over (patrolling, driving home, done): the map is finished - the grid
    // keeps up with what the sensors see, the cloud and the submaps stay as explored.
    const ExplorerState s = explorer_.navigator().state();
    if (s != ExplorerState::kIdle && s != ExplorerState::kExploring) {
      mapper_.freeze_cloud();
      if (loop_) loop_->freeze(in.t_frames);
    }
  }
  if (loop_ && !in.override_pose) {
    // The map frame moved: so do the correction, the pose, and what the navigator keeps.
    shift = loop_->update(mapper_, at, in.t_frames);
    if (shift) {
      corrector_.shift(*shift);
      pose = compose(corrector_.correction(), in.odom_latest);
      at = compose(*shift, at);
      explorer_.navigator().shift(*shift);
    }
  }
  if (settings_.explorer.recent_obstacles_s > 0.0f)
    explorer_.set_recent_obstacles(memory_.add(mapper_.last_obstacles(), at, in.odom_at, in.t_frames, mapper_.grid().resolution()));
  explorer_.update_map(mapper_.grid(), pose, in.now_s);
  if (!worker_) frame_to_map_.add((in.now_s - in.t_frames) + (runtime_wall_s() - w0));
  return shift;
}

void ExplorationRuntime::handle_set(const ApproximateTimeCore::Set& set, double now_s) {
  const std::size_t n = sensors_.size();
  MapInput in;
  in.images.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    auto it = frames_.find(set.ids[i]);
    if (it == frames_.end()) fail(ErrorCode::kInternal, "synchronizer returned an unknown frame id");
    in.images[i] = std::move(it->second);
    frames_.erase(it);
  }
  auto ot = odometry_.find(set.ids[n]);
  if (ot == odometry_.end()) fail(ErrorCode::kInternal, "synchronizer returned an unknown odometry id");
  const OdometryMsg odom = ot->second;
  odometry_.erase(ot);
  const double stamp = set.stamps_s[n];
  if (visual_) track_visual(in.images, set, now_s);
  if (map_t_restart_) {  // a new time base: the first set is due
    next_map_t_ = stamp;
    map_t_restart_ = false;
  }
  bool missing = false, seen = false;
  for (std::size_t i = 0; i < n; ++i) (in.images[i].width > 0 ? seen : missing) = true;
  if (seen) last_seen_t_ = now_s;
  if (missing) ++stats_.sets_with_missing;
  const bool due = stamp + 1e-9 >= next_map_t_;
  if (due && worker_ && (map_in_flight_ || map_updates_held_)) {
    ++stats_.map_sets_skipped;  // the last update still runs: the next set after it is taken
  } else if (due) {
    for (std::size_t i = 0; i < n; ++i) in.t_frames += set.stamps_s[i];
    in.t_frames /= static_cast<double>(n);
    in.odom_at = odometry_at(in.t_frames, odom);
    in.odom_latest = odom_pose_;
    in.now_s = now_s;
    in.override_pose = pose_override_;
    in.odometry_confirmed = visual_ && visual_->confirms_odometry(now_s);
    // The pose may be off: the robot stalled against something where its map shows free floor,
    // or vision saw a jump the wheels did not make. (orebro seed 2, stop 51: back at its start
    // 0.25 m off, it hit a wall twice; the wide match asked then found no clearly better fit -
    // the drifted walls had been mapped again - and a loop closure against the old submaps
    // moved the pose.)
    in.odometry_contradicted = explorer_.controller().stats().stalls > stalls_seen_;
    stalls_seen_ = explorer_.controller().stats().stalls;
    if (visual_) {
      in.odometry_contradicted = in.odometry_contradicted || visual_->stats().gated > visual_gated_seen_;
      visual_gated_seen_ = visual_->stats().gated;
    }
    while (next_map_t_ <= stamp + 1e-9) next_map_t_ += 1.0 / settings_.map_rate_hz;
    if (worker_) {
      submit_map_update(std::move(in));
      return;
    }
    if (map_update(in)) ++stats_.loop_closures;
    correction_ = corrector_.correction();
    heading_rate_ = corrector_.heading_rate();
    if (!pose_override_) pose_ = compose(correction_, odom_pose_);
    stats_.scan_matches = corrector_.matches();
    stats_.scan_match_rejected = corrector_.rejected();
    stats_.relocalizations_held = corrector_.relocalizations_held();
    stats_.relocalizations_new_space = corrector_.relocalizations_new_space();
    stats_.relocalizations_ambiguous = corrector_.relocalizations_ambiguous();
    stats_.relocalizations_in_obstacle = corrector_.relocalizations_in_obstacle();
    stats_.relocalizations_at_edge = corrector_.relocalizations_at_edge();
    stats_.relocalizations_asked = corrector_.relocalizations_asked();
    note_relocalization(corrector_.relocalizations(), corrector_.last_relocalization(), corrector_.last_relocalization_scores(),
                        corrector_.last_conflict(), now_s);
    stats_.scan_match_time_s = corrector_.time_s();
    ++stats_.sets_integrated;
  } else {
    ++stats_.sets_not_integrated;
  }
  for (std::size_t i = 0; i < n; ++i) sensors_[i]->recycle(std::move(in.images[i]));
}

void ExplorationRuntime::tick(double now_s) {
  const double w0 = runtime_wall_s();
  if (last_tick_wall_ >= 0.0) period_.add(w0 - last_tick_wall_);
  last_tick_wall_ = w0;
  last_now_s_ = now_s;
  if (worker_) take_results();
  finish_visual(now_s);  // kBackground: the last set's visual update, if the front end is done
  const std::size_t n = sensors_.size();
  // 1. Odometry (pose at up to the odometry rate) and frames into the synchronizer, through the
  // input guard.
  take_inputs(now_s);
  // 2. Synchronized sets -> map updates (map rate); drops release their payloads.
  for (const auto& set : sync_.take_sets()) handle_set(set, now_s);
  for (const auto& d : sync_.take_drops()) {
    if (d.stream < n) {
      ++stats_.frame_drops;
      auto it = frames_.find(d.id);
      if (it != frames_.end()) {
        sensors_[d.stream]->recycle(std::move(it->second));
        frames_.erase(it);
      }
    } else {
      ++stats_.odometry_unmatched;
      odometry_.erase(d.id);
    }
  }
  update_health(now_s);
  // 3. Control on the pose estimate - held still while no frame has been mapped for long: the
  // map the controller steers by is no longer the world (every sensor silent or garbled).
  if (last_seen_t_ < 0.0) last_seen_t_ = now_s;
  const double blind_after = std::max(3.0, 5.0 / settings_.sensor_rate_hz);
  const bool blind = now_s - last_seen_t_ > blind_after;
  if (blind != blind_) {
    guard_.note(now_s, blind ? "no frame mapped for " + std::to_string(now_s - last_seen_t_) + " s: holding still until a sensor delivers"
                             : "a sensor delivers again: moving on");
    blind_ = blind;
  }
  explorer_.controller().set_localization_health(health_, now_s);
  last_cmd_ = worker_ ? explorer_.controller().control(pose_, odom_twist_, now_s, *link_) : explorer_.control(pose_, odom_twist_, now_s);
  if (stop_asked_) last_cmd_ = Twist{0.0f, 0.0f};  // kBackground: until the navigator has heard
  if (blind) {
    last_cmd_ = Twist{0.0f, 0.0f};
    ++stats_.blind_holds;
  }
  chassis_.command(last_cmd_);
  command_.add(runtime_wall_s() - w0);
}

void ExplorationRuntime::note_relocalization(std::size_t count, const Pose2& offset, const RelocalizationScores& scores, float conflict,
                                             double now_s) {
  if (count == stats_.relocalizations) return;
  stats_.relocalizations = count;
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "the scan matched %.3f m / %.1f deg from the odometry's prediction (score %.2f there, %.2f at the prediction, "
                "%.2f at the best other fit; %.0f %% of it on cells the map holds free at the prediction), beyond the matcher's "
                "window: relocalised",
                std::hypot(offset.x, offset.y), offset.theta * 180.0f / std::numbers::pi_v<float>, scores.score, scores.prior,
                scores.runner_up, 100.0f * conflict);
  guard_.note(now_s, buf);
}

void ExplorationRuntime::restart_time() {
  sync_ = ApproximateTimeCore(profile_.sensors.size() + 1, sync_settings(profile_, settings_));
  frames_.clear();
  odometry_.clear();
  odom_history_.clear();
  map_t_restart_ = true;
}

void ExplorationRuntime::take_inputs(double now_s) {
  const std::size_t n = sensors_.size();
  for (OdometryMsg& m : chassis_.take_odometry()) {
    ++stats_.odometry_received;
    InputGuard::Verdict v = guard_.odometry(m, now_s);
    if (v == InputGuard::Verdict::kRestart) {
      restart_time();
      v = guard_.odometry(m, now_s);
    }
    if (v != InputGuard::Verdict::kAccept) continue;
    if (visual_) m.pose = visual_->odometry(m);  // the fused odometry replaces the wheels' from here on
    odom_pose_ = m.pose;
    pose_ = compose(correction_, m.pose);
    if (odom_history_.empty() || m.stamp_s > odom_history_.back().stamp_s) odom_history_.push_back(m);
    while (odom_history_.size() > kOdomHistory) odom_history_.pop_front();
    odom_twist_ = m.twist;
    const std::uint64_t id = next_id_++;
    const double stamp = m.stamp_s;
    odometry_.emplace(id, m);
    (void)sync_.add(n, stamp, id);  // a refused message comes back in take_drops()
  }
  if (pose_override_) pose_ = *pose_override_;
  std::vector<std::pair<std::size_t, double>> accepted;  // (sensor, stamp) of this tick's frames
  for (std::size_t i = 0; i < n; ++i)
    for (StampedRgbd& f : sensors_[i]->take_frames()) {
      ++stats_.frames_received;
      bool missing = false;
      InputGuard::Verdict v = guard_.frame(i, f, now_s, missing);
      if (v == InputGuard::Verdict::kRestart) {
        restart_time();
        v = guard_.frame(i, f, now_s, missing);
      }
      if (v != InputGuard::Verdict::kAccept || missing) sensors_[i]->recycle(std::move(f.image));
      if (v != InputGuard::Verdict::kAccept) continue;
      const std::uint64_t id = next_id_++;
      frames_.emplace(id, missing ? RgbdImage{} : std::move(f.image));
      (void)sync_.add(i, f.stamp_s, id);  // a refused message comes back in take_drops()
      accepted.emplace_back(i, f.stamp_s);
    }
  // A silent sensor (nothing this tick, nothing for a while) gets a missing frame beside each
  // frame of the others, so sets form without it.
  for (const auto& [i, stamp] : accepted)
    for (const std::size_t j : guard_.silent_sensors(i, stamp, now_s)) {
      const std::uint64_t pid = next_id_++;
      frames_.emplace(pid, RgbdImage{});
      (void)sync_.add(j, stamp, pid);
    }
  stats_.input = guard_.stats();
}

}  // namespace duet
