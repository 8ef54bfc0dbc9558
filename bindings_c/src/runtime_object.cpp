// The object behind duet_runtime (runtime_object.hpp): the time line, the control period, what
// it publishes, the events and the runtime's own thread.
#include "runtime_object.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace duet::capi {
namespace {

duet_explorer_state to_c(ExplorerState s) {
  switch (s) {
    case ExplorerState::kIdle: return DUET_EXPLORER_IDLE;
    case ExplorerState::kExploring: return DUET_EXPLORER_EXPLORING;
    case ExplorerState::kReturningHome: return DUET_EXPLORER_RETURNING_HOME;
    case ExplorerState::kPatrolling: return DUET_EXPLORER_PATROLLING;
    case ExplorerState::kDone: return DUET_EXPLORER_DONE;
  }
  return DUET_EXPLORER_DONE;
}

}  // namespace

const SensorProfile& sensor_of(const Profile& p, std::size_t i) {
  if (i >= p.sensors.size())
    invalid_argument("sensor " + std::to_string(i) + " out of range (the profile has " + std::to_string(p.sensors.size()) + " sensors)");
  return p.sensors[i];
}

duet_runtime_sensor_info sensor_info(const Profile& p, std::size_t i) {
  const SensorProfile& s = sensor_of(p, i);
  duet_runtime_sensor_info out{};
  out.width = s.intrinsics.width;
  out.height = s.intrinsics.height;
  out.fx = s.intrinsics.fx;
  out.fy = s.intrinsics.fy;
  out.cx = s.intrinsics.cx;
  out.cy = s.intrinsics.cy;
  out.depth_units_per_m = s.depth_units_per_m;
  out.rate_hz = static_cast<float>(p.runtime.sensor_rate_hz);
  const Eigen::Matrix4f T = s.T_robot_optical().matrix();
  std::memcpy(out.T_robot_optical, T.data(), sizeof out.T_robot_optical);
  const std::size_t n = std::min(s.name.size(), sizeof out.name - 1);
  std::memcpy(out.name, s.name.data(), n);
  out.name[n] = '\0';
  return out;
}

Profile c_profile(int kind, const char* profile, const char* const* sets, std::size_t set_count, std::uint64_t seed) {
  check_not_null(profile, "profile");
  if (set_count > 0) check_not_null(sets, "sets");
  if (set_count > 10000) invalid_argument("set_count is " + std::to_string(set_count) + " (at most 10000)");
  std::vector<ProfileOverlay> overlays;
  for (std::size_t i = 0; i < set_count; ++i) {
    if (sets[i] == nullptr) invalid_argument("sets[" + std::to_string(i) + "] is NULL");
    overlays.push_back(set_overlay(sets[i]));
  }
  Profile p;
  switch (kind) {
    case DUET_PROFILE_NAME_OR_FILE: p = resolve_profile(profile, overlays); break;
    case DUET_PROFILE_YAML_TEXT: p = parse_profile(profile, "<profile text>", overlays); break;
    default: invalid_argument("kind is " + std::to_string(kind) + " (expected DUET_PROFILE_NAME_OR_FILE or DUET_PROFILE_YAML_TEXT)");
  }
  return seed != 0 ? with_run_seed(std::move(p), seed) : p;
}

Runtime::Runtime(std::shared_ptr<Device> d, Profile p)
    : Object(Kind::kRuntime), device(std::move(d)), profile(std::move(p)), robot(profile.sensors.size()) {}

Runtime::~Runtime() {
  try {
    join();
  } catch (...) {
    // A recording's write error at release: nothing left to report it to.
  }
}

void Runtime::ensure_origin(double t) {
  if (!std::isfinite(t)) return;
  std::lock_guard lock(origin_mutex);
  if (origin_set) return;
  origin = std::floor(t) - 10.0;
  origin_set = true;
  robot.set_time_origin(origin + paused_total);
}

void Runtime::make_runtime(Execution execution) {
  RuntimeSettings s = profile.runtime;
  s.execution = execution;
  RobotSource* source = &robot;
  if (!record_dir.empty()) {
    Profile recorded = profile;
    recorded.runtime = s;  // the settings the runtime runs with: a replay runs the same
    recorder = std::make_unique<Recorder>(record_dir, recorded);
    recording = std::make_unique<RecordingSource>(robot, *recorder);
    source = recording.get();
  }
  rt = std::make_unique<ExplorationRuntime>(profile, source->chassis(), source->sensors(), s);
  if (stop_requested) rt->stop("stopped by the operator");
}

void Runtime::tick_locked(double now, std::vector<std::pair<double, std::string>>& events) {
  if (!std::isfinite(now)) invalid_argument("now_s is not finite");
  if (now < last_now) invalid_argument("now_s " + std::to_string(now) + " is before the last period's " + std::to_string(last_now));
  ensure_origin(now);
  if (!rt) make_runtime(mode == Mode::kThread ? Execution::kBackground : profile.runtime.execution);
  if (paused.load()) {
    robot.chassis().command(Twist{0.0f, 0.0f});
    std::lock_guard lock(pub);
    published.status.command = duet_twist{0.0f, 0.0f};
    published.status.paused = 1;
    return;
  }
  const double period = 1.0 / profile.runtime.control_rate_hz;
  if (resume_pending) {  // the time line skips the pause: this period follows the last one
    paused_total += std::max(0.0, (now - last_now) - period);
    resume_pending = false;
  }
  last_now = now;
  double base = 0.0;
  {
    std::lock_guard lock(origin_mutex);
    base = origin + paused_total;
  }
  robot.set_time_origin(base);
  const double t = now - base;
  if (recording) recording->advance(t);  // the arrival time of what the runtime takes now
  in_arena(*device, [&] { rt->tick(t); });
  ++periods;
  trajectory.emplace_back(now, rt->pose());
  // What happened, for the callback.
  const auto& ev = rt->events();
  for (; events_seen < ev.size(); ++events_seen) events.emplace_back(ev[events_seen].t_s + base, ev[events_seen].what);
  const ExplorerState st = rt->state();
  if (st != last_state) {
    std::string line = std::string("explorer: ") + to_string(last_state) + " -> " + to_string(st);
    if (st == ExplorerState::kDone || st == ExplorerState::kReturningHome) line += " (" + rt->stop_detail() + ")";
    events.emplace_back(now, std::move(line));
    last_state = st;
  }
  publish_locked(now);
}

void Runtime::publish_locked(double now) {
  const RuntimeStats& st = rt->stats();
  // Pose health from the matcher's recent verdicts.
  if (st.scan_match_rejected > last_rejects && st.scan_matches == last_matches) rejects_in_row += static_cast<int>(st.scan_match_rejected - last_rejects);
  if (st.scan_matches > last_matches) rejects_in_row = 0;
  last_matches = st.scan_matches;
  last_rejects = st.scan_match_rejected;
  double t_rt = 0.0;
  {
    std::lock_guard lock(origin_mutex);
    t_rt = now - origin - paused_total;
  }
  if (st.relocalizations != last_relocs) {
    last_relocs = st.relocalizations;
    last_reloc_t = t_rt;
  }
  duet_pose_health health = DUET_POSE_GOOD;
  if (rt->blind()) health = DUET_POSE_LOST;
  else if (!profile.runtime.pose_correction.enabled || rejects_in_row >= 3 || t_rt - last_reloc_t < 10.0) health = DUET_POSE_DEGRADED;

  std::shared_ptr<const OccupancyGrid> grid;
  if (st.sets_integrated != last_sets) {
    last_sets = st.sets_integrated;
    grid = std::make_shared<const OccupancyGrid>(rt->map_grid());
  }
  duet_runtime_status s{};
  s.time_s = now;
  s.command = duet_twist{rt->last_command().v, rt->last_command().omega};
  s.pose = to_c(rt->pose());
  s.map_from_odom = to_c(rt->correction());
  s.health = health;
  s.state = to_c(rt->state());
  s.paused = 0;
  s.map_updates = st.sets_integrated;
  s.visual_odometry = profile.runtime.visual_odometry.enabled ? 1 : 0;
  s.odometry_health = DUET_POSE_DEGRADED;
  if (const auto h = rt->localization_health())
    s.odometry_health = *h == LocalizationHealth::kGood ? DUET_POSE_GOOD : *h == LocalizationHealth::kDegraded ? DUET_POSE_DEGRADED : DUET_POSE_LOST;
  std::vector<float> path;
  const std::optional<Pose2> goal = rt->goal();
  for (const auto& p : rt->path()) path.insert(path.end(), {p.x(), p.y()});
  s.has_goal = goal ? 1 : 0;
  if (goal) s.goal = to_c(*goal);
  s.path_points = path.size() / 2;
  std::string detail = rt->stop_detail();
  std::lock_guard lock(pub);
  published.status = s;
  published.path.swap(path);
  published.stop_detail.swap(detail);
  if (grid) published.grid = std::move(grid);
  published.control_periods = periods;
  published.stats = st;
  if (recorder) published.recorded = recorder->stats();
}

void Runtime::drain_locked() {
  if (rt) in_arena(*device, [&] { rt->drain(); });
}

void Runtime::deliver(const std::vector<std::pair<double, std::string>>& events) {
  if (events.empty()) return;
  duet_runtime_event_fn fn = nullptr;
  void* user = nullptr;
  {
    std::lock_guard lock(cb);
    fn = callback;
    user = callback_user;
  }
  if (fn == nullptr) return;
  for (const auto& [t, what] : events) {
    try {
      fn(user, t, what.c_str());
    } catch (...) {
      // A C++ callback that throws must not unwind through the runtime.
    }
  }
}

void Runtime::thread_main() {
  using Clock = std::chrono::steady_clock;
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / profile.runtime.control_rate_hz));
  auto next = Clock::now();
  std::vector<std::pair<double, std::string>> events;
  while (!quit.load()) {
    const double now = clock ? clock(clock_user) : duet_time_now();
    events.clear();
    bool ok = true;
    {
      std::lock_guard lock(run);
      if (std::isfinite(now) && now >= last_now) ok = guarded(device.get(), "duet_runtime (control thread)", [&] { tick_locked(now, events); });
    }
    deliver(events);
    if (!ok) break;  // the error is on the device; the thread ends rather than repeat it every period
    next += period;
    const auto t = Clock::now();
    if (next < t - period) next = t;  // far behind (a stall): do not run a burst of periods
    std::this_thread::sleep_until(next);
  }
}

void Runtime::end_thread() noexcept {
  quit.store(true);
  std::lock_guard lock(thread_mutex);
  if (!thread.joinable()) return;
  if (thread.get_id() != std::this_thread::get_id()) thread.join();
  else thread.detach();  // on the thread itself (its event callback released the runtime): it ends by itself
}

void Runtime::released() noexcept {
  // Called with the registry's reference still held: joining here (on another thread) means the
  // thread's own reference is dropped first, so the object is freed by the releasing thread.
  end_thread();
}

void Runtime::join() {
  end_thread();
  std::lock_guard lock(run);
  try {
    drain_locked();
  } catch (...) {
    // A background task's error at shutdown: nothing left to report it to.
  }
  if (recorder) {
    std::string error;
    try {
      recorder->close();  // everything written
    } catch (const std::exception& e) {
      error = e.what();
    }
    {
      std::lock_guard l2(pub);
      published.recorded = recorder->stats();
    }
    if (!error.empty()) fail(ErrorCode::kIo, error);  // the first write error (duet_runtime_join reports it)
  }
}

}  // namespace duet::capi
