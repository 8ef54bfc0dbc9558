#pragma once
/// @file runtime_object.hpp
/// The object behind a duet_runtime handle (duet_runtime.h): a PushRobot the callers push into,
/// the ExplorationRuntime on it (made at the first spin or start, when the execution is known),
/// the time line, pause, the state published after each control period for the getters, and
/// the runtime's own control thread.
///
/// Locks: `run` guards the ExplorationRuntime and everything the control period changes; `pub`
/// guards what the period published (getters take only `pub`, so they never wait for a period);
/// `cb` guards the event callback. Never `pub` or `cb` while calling out, never `run` inside
/// `pub`. Callbacks are called with no lock held.
#include "capi_internal.hpp"

#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/robot/exploration_runtime.hpp>
#include <duet/runtime/robot/push_robot.hpp>
#include <duet/runtime/io/recording.hpp>

#include <atomic>
#include <condition_variable>
#include <limits>
#include <thread>

namespace duet::capi {

/// Profile from the C arguments (duet_runtime_new, duet_sim_new): kind, text or name, overrides, run seed.
Profile c_profile(int kind, const char* profile, const char* const* sets, std::size_t set_count, std::uint64_t seed);

/// Sensor i of a profile; throws ApiError(INVALID_ARGUMENT) naming the count when out of range.
const SensorProfile& sensor_of(const Profile& p, std::size_t i);
/// What the runtime (and the simulator) expect of sensor i: size, intrinsics, units, rate, mount.
duet_runtime_sensor_info sensor_info(const Profile& p, std::size_t i);

/// What one control period published.
struct Published {
  duet_runtime_status status{};
  std::vector<float> path;  ///< x, y pairs
  std::string stop_detail;
  std::shared_ptr<const OccupancyGrid> grid;
  std::uint64_t control_periods = 0;
  RuntimeStats stats;
  RecorderStats recorded;
};

struct Runtime final : Object {
  Runtime(std::shared_ptr<Device> d, Profile p);
  ~Runtime() override;
  /// The last handle reference is gone: the runtime's thread (which holds the object alive)
  /// ends after its current period; the object is freed by whichever side lets go last.
  void released() noexcept override;

  std::shared_ptr<Device> device;
  const Profile profile;
  PushRobot robot;

  // ---- time line (origin: your clock's time that is 0 for the runtime)
  std::mutex origin_mutex;
  bool origin_set = false;
  double origin = 0.0;
  /// The origin from the first time seen (see duet_runtime.h, "Time"), if not set yet.
  void ensure_origin(double t);

  // ---- the control side (lock `run`)
  std::mutex run;
  enum class Mode { kNone, kSpin, kThread } mode = Mode::kNone;
  std::string record_dir;                        ///< duet_runtime_record(): made with the runtime
  std::unique_ptr<Recorder> recorder;
  std::unique_ptr<RecordingSource> recording;    ///< between the pushes and the runtime while recording
  std::unique_ptr<ExplorationRuntime> rt;
  double last_now = -std::numeric_limits<double>::infinity();  ///< your clock, last period
  double paused_total = 0.0;     ///< runtime time skipped by pauses [s]
  bool resume_pending = false;   ///< the first period after a resume shifts the time line
  std::atomic<bool> paused{false};
  bool stop_requested = false;   ///< duet_runtime_stop() before the runtime was made
  std::atomic<std::uint64_t> paused_frames{0}, paused_odometry{0};
  std::vector<std::pair<double, Pose2>> trajectory;  ///< (your clock, pose) per period
  std::size_t events_seen = 0;
  ExplorerState last_state = ExplorerState::kIdle;
  int rejects_in_row = 0;
  std::size_t last_matches = 0, last_rejects = 0, last_relocs = 0, last_sets = 0;
  double last_reloc_t = -1e300;  ///< runtime time of the last relocalisation
  std::uint64_t periods = 0;
  int map_readers = 0;  ///< read_drained() calls holding the map updates (two readers at once: the first to finish must not let go)

  /// One control period at your clock's `now` (lock `run` held). Appends the event lines to
  /// deliver (after the lock is released) to `events`.
  void tick_locked(double now, std::vector<std::pair<double, std::string>>& events);
  /// Waits for the background tasks (lock `run` held).
  void drain_locked();
  /// Runs read(ExplorationRuntime&) on a drained runtime (lock `run` held for the read only):
  /// map updates held, their tasks waited for with the lock released - the control thread
  /// ticks on meanwhile - then the lock taken, the runtime drained (the decision or visual task
  /// still running, if any) and read. read is not called before the first control period.
  /// Takes `run` itself: call without it.
  template <class F>
  void read_drained(F&& read);

  // ---- published (lock `pub`)
  mutable std::mutex pub;
  Published published;

  // ---- event callback (lock `cb`)
  std::mutex cb;
  duet_runtime_event_fn callback = nullptr;
  void* callback_user = nullptr;
  void deliver(const std::vector<std::pair<double, std::string>>& events);

  // ---- the runtime's own thread
  std::thread thread;
  std::mutex thread_mutex;  ///< guards joining / detaching `thread`
  std::atomic<bool> quit{false};
  /// Ends the thread: joins it, or detaches it when called on the thread itself.
  void end_thread() noexcept;
  duet_clock_fn clock = nullptr;
  void* clock_user = nullptr;
  void thread_main();
  /// Stops the thread (if any) and waits for it - unless called on the runtime's own thread
  /// (a callback releasing the last reference): then the thread is detached and ends by itself.
  void join();

 private:
  void make_runtime(Execution execution);
  void publish_locked(double now);
};

template <> struct KindOf<Runtime> { static constexpr Kind value = Kind::kRuntime; };

template <class F>
void Runtime::read_drained(F&& read) {
  duet::ExplorationRuntime* rt_seen = nullptr;
  {
    std::lock_guard lock(run);
    rt_seen = rt.get();
    if (rt_seen && map_readers++ == 0) rt_seen->hold_map_updates(true);
  }
  if (!rt_seen) return;
  struct Release {
    Runtime& r;
    ~Release() {
      std::lock_guard lock(r.run);
      if (--r.map_readers == 0) r.rt->hold_map_updates(false);  // the last reader lets go
    }
  } release{*this};
  rt_seen->wait_background_idle();  // without the lock: control goes on
  std::lock_guard lock(run);
  drain_locked();
  read(*rt);
}

}  // namespace duet::capi
