// duet_runtime: the robot loop through the C API (duet_runtime.h).
#include "runtime_object.hpp"

#include <duet/runtime/io/cloud_io.hpp>
#include <duet/runtime/io/grid_io.hpp>
#include <duet/runtime/io/output.hpp>
#include <duet/runtime/io/runtime_outputs.hpp>

#include <map>
#include <optional>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace duet::capi {
namespace {

template <class F>
void with_runtime(duet_runtime handle, const char* fn, F&& body) noexcept {
  auto r = resolve<Runtime>(handle, fn, "runtime");
  if (!r) return;
  guarded(r->device.get(), fn, [&] { body(*r); });
}

/// The caller's frame as the runtime's RgbdImage (depth converted to the sensor's units).
void convert(const duet_rgbd_image& in, const SensorProfile& sensor, RgbdImage& out) {
  const int w = sensor.intrinsics.width, h = sensor.intrinsics.height;
  if (in.width != w || in.height != h)
    invalid_argument("image is " + std::to_string(in.width) + " x " + std::to_string(in.height) + " px, sensor '" + sensor.name +
                     "' is " + std::to_string(w) + " x " + std::to_string(h) + " px (its profile's intrinsics)");
  check_not_null(in.depth, "image->depth");
  const int fmt = enum_value(in.depth_format);
  if (fmt != DUET_DEPTH_U16 && fmt != DUET_DEPTH_F32) invalid_argument("image->depth_format is " + std::to_string(fmt));
  const std::size_t px = fmt == DUET_DEPTH_U16 ? 2 : 4;
  const std::size_t ds = in.depth_row_stride == 0 ? px * static_cast<std::size_t>(w) : in.depth_row_stride;
  if (ds < px * static_cast<std::size_t>(w) || ds % px != 0 || reinterpret_cast<std::uintptr_t>(in.depth) % px != 0)
    invalid_argument("image->depth_row_stride " + std::to_string(in.depth_row_stride) + " (or the depth pointer) is not aligned to the pixel size or is shorter than a row");
  const float units = sensor.depth_units_per_m;
  out.width = w;
  out.height = h;
  out.depth.resize(static_cast<std::size_t>(w) * h);
  const auto* base = static_cast<const std::byte*>(in.depth);
  if (fmt == DUET_DEPTH_U16) {
    if (!(std::isfinite(in.depth_units_per_m) && in.depth_units_per_m > 0.0f && in.depth_units_per_m <= 1e6f))
      invalid_argument("image->depth_units_per_m is " + std::to_string(in.depth_units_per_m) + " (must be in (0, 1e6])");
    const bool same = in.depth_units_per_m == units;
    const double scale = static_cast<double>(units) / in.depth_units_per_m;
    for (int y = 0; y < h; ++y) {
      const auto* row = reinterpret_cast<const std::uint16_t*>(base + static_cast<std::size_t>(y) * ds);
      std::uint16_t* dst = out.depth.data() + static_cast<std::size_t>(y) * w;
      if (same) {
        std::memcpy(dst, row, sizeof(std::uint16_t) * w);
        continue;
      }
      for (int x = 0; x < w; ++x) {
        const double v = std::round(row[x] * scale);
        dst[x] = v > 65535.0 ? 0 : static_cast<std::uint16_t>(v);  // beyond the sensor's range: no return
      }
    }
  } else {
    for (int y = 0; y < h; ++y) {
      const auto* row = reinterpret_cast<const float*>(base + static_cast<std::size_t>(y) * ds);
      std::uint16_t* dst = out.depth.data() + static_cast<std::size_t>(y) * w;
      for (int x = 0; x < w; ++x) {
        const double v = std::round(static_cast<double>(row[x]) * units);
        dst[x] = (std::isfinite(v) && v > 0.0 && v <= 65535.0) ? static_cast<std::uint16_t>(v) : 0;
      }
    }
  }
  out.intrinsics.reset();
  if (in.intrinsics != nullptr) {
    const float fx = in.intrinsics[0], fy = in.intrinsics[1], cx = in.intrinsics[2], cy = in.intrinsics[3];
    if (!(std::isfinite(fx) && std::isfinite(fy) && fx > 0.0f && fy > 0.0f && fx <= 1e6f && fy <= 1e6f && cx >= 0.0f &&
          cx <= static_cast<float>(w) && cy >= 0.0f && cy <= static_cast<float>(h)))
      invalid_argument("image->intrinsics (" + std::to_string(fx) + ", " + std::to_string(fy) + ", " + std::to_string(cx) + ", " +
                       std::to_string(cy) + "): fx, fy must be in (0, 1e6], cx in [0, width], cy in [0, height]");
    out.intrinsics = PinholeIntrinsics{w, h, fx, fy, cx, cy};
  }
  if (in.color == nullptr) {
    out.rgb.clear();
    return;
  }
  if (in.color_channels != 3 && in.color_channels != 4)
    invalid_argument("image->color_channels is " + std::to_string(in.color_channels) + " (3 or 4)");
  const std::size_t ch = static_cast<std::size_t>(in.color_channels);
  const std::size_t cs = in.color_row_stride == 0 ? ch * static_cast<std::size_t>(w) : in.color_row_stride;
  if (cs < ch * static_cast<std::size_t>(w)) invalid_argument("image->color_row_stride " + std::to_string(in.color_row_stride) + " is shorter than a row");
  out.rgb.resize(static_cast<std::size_t>(w) * h * 3);
  const std::size_t r = in.color_bgr ? 2 : 0, b = in.color_bgr ? 0 : 2;
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* row = in.color + static_cast<std::size_t>(y) * cs;
    std::uint8_t* dst = out.rgb.data() + static_cast<std::size_t>(y) * w * 3;
    if (ch == 3 && !in.color_bgr) {  // the runtime's own layout: one copy per row
      std::memcpy(dst, row, 3 * static_cast<std::size_t>(w));
      continue;
    }
    for (int x = 0; x < w; ++x, row += ch, dst += 3) {
      dst[0] = row[r];
      dst[1] = row[1];
      dst[2] = row[b];
    }
  }
}

}  // namespace
}  // namespace duet::capi

using namespace duet::capi;
using duet::ExplorerState;
using duet::Pose2;

extern "C" {

DUET_API duet_runtime duet_runtime_new(duet_device device, enum duet_profile_kind kind, const char* profile,
                                       const char* const* sets, size_t set_count, uint64_t seed) {
  static constexpr const char* fn = "duet_runtime_new";
  auto d = resolve<Device>(device, fn, "device");
  if (!d) return nullptr;
  duet_runtime result = nullptr;
  guarded(d.get(), fn, [&] {
    auto r = std::make_shared<Runtime>(d, c_profile(enum_value(kind), profile, sets, set_count, seed));
    r->parent = d->key;
    result = to_handle<duet_runtime>(register_object(std::move(r)));
  });
  return result;
}

DUET_API void duet_profile_settings_load(duet_device device, enum duet_profile_kind kind, const char* profile,
                                         const char* const* sets, size_t set_count, duet_profile_settings* out) {
  static constexpr const char* fn = "duet_profile_settings_load";
  auto d = resolve<Device>(device, fn, "device");
  if (!d) return;
  guarded(d.get(), fn, [&] {
    check_not_null(out, "out");
    const duet::Profile p = c_profile(enum_value(kind), profile, sets, set_count, 0);
    duet_profile_settings r{};
    r.grid_resolution_m = p.mapping.grid_resolution_m;
    fill(p.mapping.back_projection, &r.back_projection);
    fill(p.mapping.voxel_filter, &r.voxel_filter);
    fill(p.mapping.normals, &r.normals);
    fill(p.mapping.segmentation, &r.segmentation);
    fill(p.mapping.grid_update, &r.grid_update);
    fill(p.runtime.pose_correction.match, &r.scan_match);
    fill(p.exploration.observation, &r.observation);
    fill(p.exploration.inflation, &r.inflation);
    fill(p.exploration.path, &r.path);
    fill(p.exploration.strategy, &r.exploration);
    fill(p.exploration.dwa, &r.dwa);
    const std::vector<duet::SensorSector> sectors = duet::observation_sectors(p);
    r.sensor_count = std::min<std::size_t>(sectors.size(), 16);
    for (std::size_t i = 0; i < r.sensor_count; ++i) r.sensors[i] = to_c(sectors[i]);
    *out = r;
  });
}

DUET_API void duet_runtime_retain(duet_runtime runtime) { retain_handle(runtime, Kind::kRuntime, "duet_runtime_retain"); }
DUET_API void duet_runtime_release(duet_runtime runtime) { release_handle(runtime, Kind::kRuntime, "duet_runtime_release"); }

DUET_API size_t duet_runtime_get_sensor_count(duet_runtime runtime) {
  size_t n = 0;
  with_runtime(runtime, "duet_runtime_get_sensor_count", [&](Runtime& r) { n = r.profile.sensors.size(); });
  return n;
}

DUET_API void duet_runtime_get_sensor_info(duet_runtime runtime, size_t sensor, duet_runtime_sensor_info* out) {
  with_runtime(runtime, "duet_runtime_get_sensor_info", [&](Runtime& r) {
    check_not_null(out, "out");
    *out = sensor_info(r.profile, sensor);
  });
}

DUET_API double duet_runtime_get_control_period(duet_runtime runtime) {
  double p = 0.0;
  with_runtime(runtime, "duet_runtime_get_control_period", [&](Runtime& r) { p = 1.0 / r.profile.runtime.control_rate_hz; });
  return p;
}

DUET_API void duet_runtime_set_time_origin(duet_runtime runtime, double origin_s) {
  with_runtime(runtime, "duet_runtime_set_time_origin", [&](Runtime& r) {
    if (!std::isfinite(origin_s)) invalid_argument("origin_s is not finite");
    std::lock_guard lock(r.origin_mutex);
    if (r.origin_set) api_fail(DUET_ERROR_INVALID_OPERATION, "the time origin is already set (by an earlier call, push or spin)");
    r.origin = origin_s;
    r.origin_set = true;
    r.robot.set_time_origin(origin_s);
  });
}

DUET_API void duet_rgbd_image_init(duet_rgbd_image* image) {
  if (image == nullptr) return;
  *image = duet_rgbd_image{};
  image->stamp_s = std::nan("");
  image->depth_format = DUET_DEPTH_U16;
  image->depth_units_per_m = 1000.0f;
  image->color_channels = 3;
  image->color_bgr = 0;
}

DUET_API void duet_runtime_push_rgbd(duet_runtime runtime, size_t sensor, const duet_rgbd_image* image) {
  with_runtime(runtime, "duet_runtime_push_rgbd", [&](Runtime& r) {
    check_not_null(image, "image");
    const duet::SensorProfile& s = sensor_of(r.profile, sensor);
    duet::RgbdImage img = r.robot.spare_image();
    convert(*image, s, img);  // validates everything before anything is queued
    if (r.paused.load()) {
      ++r.paused_frames;
      return;
    }
    r.ensure_origin(image->stamp_s);
    r.robot.push_frame(sensor, image->stamp_s, std::move(img));
  });
}

DUET_API void duet_runtime_push_odometry(duet_runtime runtime, double stamp_s, duet_pose2 pose, duet_twist twist) {
  with_runtime(runtime, "duet_runtime_push_odometry", [&](Runtime& r) {
    if (r.paused.load()) {
      ++r.paused_odometry;
      return;
    }
    r.ensure_origin(stamp_s);
    duet::OdometryMsg m;
    m.stamp_s = stamp_s;
    m.pose = Pose2{pose.x, pose.y, pose.theta};
    m.twist = duet::Twist{twist.v, twist.omega};
    r.robot.push_odometry(m);  // non-finite values: the runtime's input guard drops and counts them
  });
}

DUET_API void duet_runtime_push_gyro(duet_runtime runtime, double stamp_s, float yaw_rate_rps) {
  with_runtime(runtime, "duet_runtime_push_gyro", [&](Runtime& r) {
    if (r.paused.load()) return;  // the odometry is dropped meanwhile too
    r.ensure_origin(stamp_s);
    r.robot.push_gyro(stamp_s, yaw_rate_rps);  // non-finite values: counted drops
  });
}

DUET_API void duet_runtime_spin_once(duet_runtime runtime, double now_s) {
  auto r = resolve<Runtime>(runtime, "duet_runtime_spin_once", "runtime");
  if (!r) return;
  std::vector<std::pair<double, std::string>> events;
  guarded(r->device.get(), "duet_runtime_spin_once", [&] {
    std::lock_guard lock(r->run);
    if (r->mode == Runtime::Mode::kThread) api_fail(DUET_ERROR_INVALID_OPERATION, "the runtime runs its own thread (duet_runtime_start)");
    r->mode = Runtime::Mode::kSpin;
    r->tick_locked(now_s, events);
  });
  r->deliver(events);
}

DUET_API double duet_time_now(void) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

DUET_API void duet_runtime_start(duet_runtime runtime, duet_clock_fn clock, void* user_ptr) {
  auto self = resolve<Runtime>(runtime, "duet_runtime_start", "runtime");
  if (!self) return;
  guarded(self->device.get(), "duet_runtime_start", [&] {
    Runtime& r = *self;
    std::lock_guard lock(r.run);
    if (r.mode == Runtime::Mode::kSpin) api_fail(DUET_ERROR_INVALID_OPERATION, "duet_runtime_spin_once was used: the runtime is spun by its caller");
    if (r.mode == Runtime::Mode::kThread) api_fail(DUET_ERROR_INVALID_OPERATION, "the runtime's thread is already started");
    if (r.quit.load()) api_fail(DUET_ERROR_INVALID_OPERATION, "the runtime was joined: its thread cannot start again");
    r.mode = Runtime::Mode::kThread;
    r.clock = clock;
    r.clock_user = user_ptr;
    // The thread holds the object alive: a release (even from its own event callback) ends the
    // loop (released()), and the last of the two to let go frees it.
    r.thread = std::thread([keep = self] { keep->thread_main(); });
  });
}

DUET_API void duet_runtime_pause(duet_runtime runtime) {
  with_runtime(runtime, "duet_runtime_pause", [&](Runtime& r) { r.paused.store(true); });
}

DUET_API void duet_runtime_resume(duet_runtime runtime) {
  with_runtime(runtime, "duet_runtime_resume", [&](Runtime& r) {
    std::lock_guard lock(r.run);
    if (!r.paused.load()) return;
    r.paused.store(false);
    r.resume_pending = std::isfinite(r.last_now);
  });
}

DUET_API void duet_runtime_stop(duet_runtime runtime) {
  with_runtime(runtime, "duet_runtime_stop", [&](Runtime& r) {
    std::lock_guard lock(r.run);
    r.stop_requested = true;  // before the first period: the runtime starts done
    if (r.rt) r.rt->stop("stopped by the operator");
  });
}

DUET_API void duet_runtime_return_home(duet_runtime runtime) {
  with_runtime(runtime, "duet_runtime_return_home", [&](Runtime& r) {
    std::lock_guard lock(r.run);
    if (!r.rt) api_fail(DUET_ERROR_INVALID_OPERATION, "the runtime has not run a control period yet: there is no home to return to");
    double base = 0.0;
    {
      std::lock_guard l2(r.origin_mutex);
      base = r.origin + r.paused_total;
    }
    r.rt->return_home(r.last_now - base);
  });
}

DUET_API void duet_runtime_record(duet_runtime runtime, const char* dir) {
  with_runtime(runtime, "duet_runtime_record", [&](Runtime& r) {
    check_not_null(dir, "dir");
    std::lock_guard lock(r.run);
    if (r.rt) api_fail(DUET_ERROR_INVALID_OPERATION, "the runtime has run already: a recording starts before the first control period");
    if (!r.record_dir.empty()) api_fail(DUET_ERROR_INVALID_OPERATION, "the runtime records already, to " + r.record_dir);
    const std::filesystem::path p(dir);
    std::error_code ec;
    if (std::filesystem::exists(p, ec) && !(std::filesystem::is_directory(p, ec) && std::filesystem::is_empty(p, ec)))
      api_fail(DUET_ERROR_IO, p.string() + ": a recording needs an empty or new folder");
    duet::prepare_output_dir(p);
    r.record_dir = p.string();
  });
}

DUET_API void duet_runtime_join(duet_runtime runtime) {
  with_runtime(runtime, "duet_runtime_join", [&](Runtime& r) { r.join(); });
}

DUET_API void duet_runtime_get_status(duet_runtime runtime, duet_runtime_status* out) {
  with_runtime(runtime, "duet_runtime_get_status", [&](Runtime& r) {
    check_not_null(out, "out");
    std::lock_guard lock(r.pub);
    *out = r.published.status;
    if (r.published.control_periods == 0) out->time_s = std::nan("");
    out->paused = r.paused.load() ? 1 : 0;
    if (out->paused) out->command = duet_twist{0.0f, 0.0f};
  });
}

DUET_API duet_twist duet_runtime_get_command(duet_runtime runtime) {
  duet_twist t{0.0f, 0.0f};
  with_runtime(runtime, "duet_runtime_get_command", [&](Runtime& r) {
    if (r.paused.load()) return;
    const duet::Twist c = r.robot.latest_command();
    t = duet_twist{c.v, c.omega};
  });
  return t;
}

DUET_API size_t duet_runtime_get_stop_detail(duet_runtime runtime, char* buf, size_t capacity) {
  size_t n = 0;
  with_runtime(runtime, "duet_runtime_get_stop_detail", [&](Runtime& r) {
    if (capacity > 0) check_not_null(buf, "buf");
    std::lock_guard lock(r.pub);
    const std::string& s = r.published.stop_detail;
    n = s.size();
    if (capacity > 0) {
      const size_t k = std::min(n, capacity - 1);
      std::memcpy(buf, s.data(), k);
      buf[k] = '\0';
    }
  });
  return n;
}

DUET_API size_t duet_runtime_get_path(duet_runtime runtime, float* xy, size_t xy_stride, size_t capacity) {
  size_t n = 0;
  with_runtime(runtime, "duet_runtime_get_path", [&](Runtime& r) {
    const size_t stride = check_buffer(xy, xy_stride, capacity, 2 * sizeof(float), 4, "xy");
    std::lock_guard lock(r.pub);
    n = r.published.path.size() / 2;
    auto* p = reinterpret_cast<std::byte*>(xy);
    for (size_t i = 0; i < std::min(n, capacity); ++i) std::memcpy(p + i * stride, &r.published.path[2 * i], 2 * sizeof(float));
  });
  return n;
}

DUET_API duet_grid duet_runtime_get_grid(duet_runtime runtime) {
  duet_grid result = nullptr;
  with_runtime(runtime, "duet_runtime_get_grid", [&](Runtime& r) {
    std::shared_ptr<const duet::OccupancyGrid> g;
    {
      std::lock_guard lock(r.pub);
      g = r.published.grid;
    }
    auto obj = std::make_shared<Grid>(r.device, r.profile.mapping.grid_resolution_m);
    if (g) obj->grid = *g;
    obj->parent = r.device->key;
    result = to_handle<duet_grid>(register_object(std::move(obj)));
  });
  return result;
}

DUET_API duet_cloud duet_runtime_get_cloud(duet_runtime runtime) {
  duet_cloud result = nullptr;
  with_runtime(runtime, "duet_runtime_get_cloud", [&](Runtime& r) {
    auto obj = std::make_shared<Cloud>(r.device);
    r.read_drained([&](duet::ExplorationRuntime& rt) {
      in_arena(*r.device, [&] { obj->cloud = rt.mapper().cloud(); });  // the device's threads
    });
    obj->parent = r.device->key;
    result = to_handle<duet_cloud>(register_object(std::move(obj)));
  });
  return result;
}

DUET_API void duet_runtime_get_stats(duet_runtime runtime, duet_runtime_stats* out) {
  with_runtime(runtime, "duet_runtime_get_stats", [&](Runtime& r) {
    check_not_null(out, "out");
    duet_runtime_stats s{};
    const duet::PushStats ps = r.robot.stats();
    s.frames_pushed = ps.frames_pushed + r.paused_frames.load();
    s.frames_queue_overflow = ps.frames_overflowed;
    s.frames_paused = r.paused_frames.load();
    s.odometry_pushed = ps.odometry_pushed + r.paused_odometry.load();
    s.odometry_queue_overflow = ps.odometry_overflowed;
    s.odometry_paused = r.paused_odometry.load();
    std::lock_guard lock(r.pub);
    {
      const duet::RuntimeStats& st = r.published.stats;
      s.frames_invalid = st.input.frames_invalid;
      s.frames_out_of_order = st.input.frames_out_of_order;
      s.frames_garbled = st.input.frames_garbled;
      s.frames_dropped_sync = st.frame_drops;
      s.odometry_invalid = st.input.odometry_invalid;
      s.odometry_out_of_order = st.input.odometry_out_of_order;
      s.odometry_jumps = st.input.odometry_jumps;
      s.clock_restarts = st.input.clock_restarts;
      s.sensor_silences = st.input.sensor_silences;
      s.sets_integrated = st.sets_integrated;
      s.blind_periods = st.blind_holds;
      s.relocalizations = st.relocalizations;
      s.loop_closures = st.loop_closures;
    }
    s.control_periods = r.published.control_periods;
    s.frames_recorded = r.published.recorded.frames_recorded;
    s.frames_record_dropped = r.published.recorded.frames_dropped;
    s.gyro_pushed = ps.gyro_pushed;
    s.gyro_invalid = ps.gyro_invalid;
    s.gyro_gaps = ps.gyro_gaps;
    *out = s;
  });
}

DUET_API void duet_runtime_set_event_callback(duet_runtime runtime, duet_runtime_event_fn callback, void* user_ptr) {
  with_runtime(runtime, "duet_runtime_set_event_callback", [&](Runtime& r) {
    std::lock_guard lock(r.cb);
    r.callback = callback;
    r.callback_user = user_ptr;
  });
}

DUET_API void duet_runtime_save(duet_runtime runtime, const char* dir) {
  with_runtime(runtime, "duet_runtime_save", [&](Runtime& r) {
    check_not_null(dir, "dir");
    const std::filesystem::path out(dir);
    duet::prepare_output_dir(out);
    // Copied while the run lock is held (after the map update in flight is done, waited for
    // without the lock), written after it: a save holds control for the copy only.
    std::optional<duet::RuntimeOutputs> snapshot;
    r.read_drained([&](duet::ExplorationRuntime& rt) {
      const duet::PushStats ps = r.robot.stats();
      const std::map<std::string, double> push{
          {"frames_pushed", static_cast<double>(ps.frames_pushed)},
          {"frames_queue_overflow", static_cast<double>(ps.frames_overflowed)},
          {"frames_paused", static_cast<double>(r.paused_frames.load())},
          {"odometry_pushed", static_cast<double>(ps.odometry_pushed)},
          {"odometry_queue_overflow", static_cast<double>(ps.odometry_overflowed)},
          {"odometry_paused", static_cast<double>(r.paused_odometry.load())},
          {"gyro_pushed", static_cast<double>(ps.gyro_pushed)},
          {"gyro_invalid", static_cast<double>(ps.gyro_invalid)}};
      in_arena(*r.device, [&] { snapshot = duet::snapshot_runtime_outputs(rt, r.trajectory, push); });  // the device's threads
    });
    if (!snapshot) api_fail(DUET_ERROR_INVALID_OPERATION, "the runtime has not run a control period yet: nothing to save");
    // Serial file writing, on the caller's thread and outside the device's arena: in the arena a
    // device of one thread would hold the control thread's tick until the files are written.
    duet::write_runtime_outputs(*snapshot, out);
  });
}

DUET_API const char* duet_explorer_state_string(enum duet_explorer_state state) {
  switch (enum_value(state)) {
    case DUET_EXPLORER_IDLE: return "idle";
    case DUET_EXPLORER_EXPLORING: return "exploring";
    case DUET_EXPLORER_RETURNING_HOME: return "returning_home";
    case DUET_EXPLORER_PATROLLING: return "patrolling";
    case DUET_EXPLORER_DONE: return "done";
    default: return "?";
  }
}

DUET_API const char* duet_pose_health_string(enum duet_pose_health health) {
  switch (enum_value(health)) {
    case DUET_POSE_GOOD: return "good";
    case DUET_POSE_DEGRADED: return "degraded";
    case DUET_POSE_LOST: return "lost";
    default: return "?";
  }
}

}  // extern "C"
