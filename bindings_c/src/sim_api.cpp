// duet_sim: the simulator through the C API (duet_sim.h).
#include "runtime_object.hpp"

#include <duet/sim/sim_explore.hpp>
#include <duet/sim/sim_robot.hpp>
#include <duet/sim/world.hpp>

#include <cmath>
#include <deque>

namespace duet::capi {

struct Sim final : Object {
  Sim(std::shared_ptr<Device> d, Profile p, std::shared_ptr<const sim::World> w, std::uint64_t seed)
      : Object(Kind::kSim), device(std::move(d)), profile(std::move(p)), world(std::move(w)),
        robot(world, profile, settings(profile, seed)), frames(profile.sensors.size()) {
    truth = sim::rasterize(*world, 0.05f, 0.0f, 0.6f);
    float range = 0.0f;
    for (const auto& s : profile.sensors) range = std::max(range, s.max_depth_m);
    reachable = sim::reachable_free_mask(truth, world->start, profile.exploration.inflation.robot_radius_m, range);
  }
  static sim::SimRobotSettings settings(const Profile& p, std::uint64_t seed) {
    sim::SimRobotSettings s;
    s.seed = seed;
    s.sensor_rate_hz = p.runtime.sensor_rate_hz;
    return s;
  }

  std::shared_ptr<Device> device;
  const Profile profile;
  std::shared_ptr<const sim::World> world;
  sim::SimRobot robot;
  std::mutex mutex;
  double t = 0.0;
  static constexpr std::size_t kMaxFrames = 64, kMaxOdometry = 100000;
  std::vector<std::deque<StampedRgbd>> frames;
  std::deque<OdometryMsg> odometry;
  sim::TruthGrid truth;
  std::vector<std::uint8_t> reachable;
};

template <> struct KindOf<Sim> { static constexpr Kind value = Kind::kSim; };

namespace {

template <class F>
void with_sim(duet_sim handle, const char* fn, F&& body) noexcept {
  auto s = resolve<Sim>(handle, fn, "sim");
  if (!s) return;
  guarded(s->device.get(), fn, [&] {
    std::lock_guard lock(s->mutex);
    body(*s);
  });
}

}  // namespace
}  // namespace duet::capi

using namespace duet::capi;

extern "C" {

DUET_API duet_sim duet_sim_new(duet_device device, const char* world, enum duet_profile_kind kind, const char* profile,
                               const char* const* sets, size_t set_count, uint64_t seed) {
  static constexpr const char* fn = "duet_sim_new";
  auto d = resolve<Device>(device, fn, "device");
  if (!d) return nullptr;
  duet_sim result = nullptr;
  guarded(d.get(), fn, [&] {
    check_not_null(world, "world");
    duet::Profile p = c_profile(enum_value(kind), profile, sets, set_count, 0);
    duet::sim::World w = duet::sim::resolve_world(world);
    duet::sim::validate(w, w.source.empty() ? world : w.source);
    std::shared_ptr<Sim> s;
    in_arena(*d, [&] { s = std::make_shared<Sim>(d, std::move(p), std::make_shared<const duet::sim::World>(std::move(w)), seed); });
    s->parent = d->key;
    result = to_handle<duet_sim>(register_object(std::move(s)));
  });
  return result;
}

DUET_API void duet_sim_retain(duet_sim sim) { retain_handle(sim, Kind::kSim, "duet_sim_retain"); }
DUET_API void duet_sim_release(duet_sim sim) { release_handle(sim, Kind::kSim, "duet_sim_release"); }

DUET_API double duet_sim_get_time(duet_sim sim) {
  double t = std::nan("");
  with_sim(sim, "duet_sim_get_time", [&](Sim& s) { t = s.t; });
  return t;
}

DUET_API void duet_sim_step(duet_sim sim, duet_twist command, double dt_s) {
  with_sim(sim, "duet_sim_step", [&](Sim& s) {
    if (!std::isfinite(command.v) || !std::isfinite(command.omega)) invalid_argument("command is not finite");
    if (!(std::isfinite(dt_s) && dt_s > 0.0 && dt_s <= 10.0)) invalid_argument("dt_s is " + std::to_string(dt_s) + " (must be in (0, 10] s)");
    s.robot.chassis().command(duet::Twist{command.v, command.omega});
    const double t_end = s.t + dt_s;
    in_arena(*s.device, [&] { s.robot.advance(t_end); });
    s.t = t_end;
    for (std::size_t i = 0; i < s.frames.size(); ++i)
      for (duet::StampedRgbd& f : s.robot.sensors()[i]->take_frames()) {
        auto& q = s.frames[i];
        if (q.size() >= Sim::kMaxFrames) {
          s.robot.sensors()[i]->recycle(std::move(q.front().image));
          q.pop_front();
        }
        q.push_back(std::move(f));
      }
    for (const duet::OdometryMsg& m : s.robot.chassis().take_odometry()) {
      if (s.odometry.size() >= Sim::kMaxOdometry) s.odometry.pop_front();
      s.odometry.push_back(m);
    }
  });
}

DUET_API size_t duet_sim_get_sensor_count(duet_sim sim) {
  size_t n = 0;
  with_sim(sim, "duet_sim_get_sensor_count", [&](Sim& s) { n = s.profile.sensors.size(); });
  return n;
}

DUET_API void duet_sim_get_sensor_info(duet_sim sim, size_t sensor, duet_runtime_sensor_info* out) {
  with_sim(sim, "duet_sim_get_sensor_info", [&](Sim& s) {
    check_not_null(out, "out");
    *out = sensor_info(s.profile, sensor);
  });
}

DUET_API size_t duet_sim_get_frames_waiting(duet_sim sim, size_t sensor) {
  size_t n = 0;
  with_sim(sim, "duet_sim_get_frames_waiting", [&](Sim& s) {
    (void)sensor_of(s.profile, sensor);  // checks the index
    n = s.frames[sensor].size();
  });
  return n;
}

DUET_API int duet_sim_take_frame(duet_sim sim, size_t sensor, double* stamp_s, uint16_t* depth, size_t depth_row_stride,
                                 uint8_t* rgb, size_t rgb_row_stride, int width, int height) {
  int taken = 0;
  with_sim(sim, "duet_sim_take_frame", [&](Sim& s) {
    const auto& in = sensor_of(s.profile, sensor).intrinsics;
    if (width != in.width || height != in.height)
      invalid_argument("width x height is " + std::to_string(width) + " x " + std::to_string(height) + ", the sensor's is " +
                       std::to_string(in.width) + " x " + std::to_string(in.height));
    check_not_null(stamp_s, "stamp_s");
    check_not_null(depth, "depth");
    const std::size_t w = static_cast<std::size_t>(width), h = static_cast<std::size_t>(height);
    const std::size_t ds = depth_row_stride == 0 ? 2 * w : depth_row_stride;
    if (ds < 2 * w || ds % 2 != 0 || reinterpret_cast<std::uintptr_t>(depth) % 2 != 0)
      invalid_argument("depth_row_stride " + std::to_string(depth_row_stride) + " (or depth) is misaligned or shorter than a row");
    const std::size_t cs = rgb_row_stride == 0 ? 3 * w : rgb_row_stride;
    if (rgb != nullptr && cs < 3 * w) invalid_argument("rgb_row_stride " + std::to_string(rgb_row_stride) + " is shorter than a row");
    auto& q = s.frames[sensor];
    if (q.empty()) return;
    duet::StampedRgbd f = std::move(q.front());
    q.pop_front();
    *stamp_s = f.stamp_s;
    auto* dp = reinterpret_cast<std::byte*>(depth);
    for (std::size_t y = 0; y < h; ++y) std::memcpy(dp + y * ds, f.image.depth.data() + y * w, 2 * w);
    if (rgb != nullptr) {
      for (std::size_t y = 0; y < h; ++y) {
        if (f.image.rgb.size() == w * h * 3) std::memcpy(rgb + y * cs, f.image.rgb.data() + y * w * 3, 3 * w);
        else std::memset(rgb + y * cs, 0, 3 * w);
      }
    }
    s.robot.sensors()[sensor]->recycle(std::move(f.image));
    taken = 1;
  });
  return taken;
}

DUET_API size_t duet_sim_take_odometry(duet_sim sim, double* stamps_s, duet_pose2* poses, duet_twist* twists, size_t capacity) {
  size_t n = 0;
  with_sim(sim, "duet_sim_take_odometry", [&](Sim& s) {
    n = std::min(capacity, s.odometry.size());
    for (size_t i = 0; i < n; ++i) {
      const duet::OdometryMsg& m = s.odometry[i];
      if (stamps_s) stamps_s[i] = m.stamp_s;
      if (poses) poses[i] = duet_pose2{m.pose.x, m.pose.y, m.pose.theta};
      if (twists) twists[i] = duet_twist{m.twist.v, m.twist.omega};
    }
    s.odometry.erase(s.odometry.begin(), s.odometry.begin() + static_cast<std::ptrdiff_t>(n));
  });
  return n;
}

DUET_API duet_pose2 duet_sim_get_true_pose(duet_sim sim) {
  duet_pose2 p{std::nanf(""), std::nanf(""), std::nanf("")};
  with_sim(sim, "duet_sim_get_true_pose", [&](Sim& s) {
    const duet::Pose2 t = s.robot.sim_chassis().true_pose();
    p = duet_pose2{t.x, t.y, t.theta};
  });
  return p;
}

DUET_API size_t duet_sim_get_collisions(duet_sim sim) {
  size_t n = 0;
  with_sim(sim, "duet_sim_get_collisions", [&](Sim& s) { n = s.robot.sim_chassis().collisions(); });
  return n;
}

DUET_API void duet_sim_score(duet_sim sim, duet_grid grid, double* coverage, double* explored_m2) {
  auto g = resolve<Grid>(grid, "duet_sim_score", "grid");
  if (!g) return;
  with_sim(sim, "duet_sim_score", [&](Sim& s) {
    std::shared_lock lock(g->mutex);
    const duet::sim::CoverageMeasure m = duet::sim::measure_coverage(g->grid, s.profile.exploration.cells, s.truth, s.reachable);
    if (coverage) *coverage = m.coverage;
    if (explored_m2) *explored_m2 = m.area_m2;
  });
}

}  // extern "C"
