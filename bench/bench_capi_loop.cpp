// RobotLoop/{cpp,capi}/lab30s: the overhead of the C API's robot loop (issue 20 target: <= 2 %). The
// same lockstep run - the lab, the dual profile, seed 1, the first 30 simulated s (600 control
// periods, 31 map updates) - once in C++ (SimRobot -> ExplorationRuntime, what `duet explore`
// runs) and once through duet.h alone (duet_sim -> copies of every frame and odometry message ->
// duet_runtime, what bindings_c/examples/robot_loop.c runs). Both drive the same trajectory
// bit for bit (tests/capi/capi_robot_loop_test.cpp), so the difference is the API's copies,
// conversions, locks and published state. Building the world, the renderer and the runtime is
// outside the timing. 2 threads. Items = control periods. The closed loop copies every frame
// twice more than the C++ one (the simulator's API out, the runtime's API in).
//
// RuntimeApi/{cpp,capi}/lab30s: the runtime's side alone. The inputs of the same 30 s run (every
// frame and odometry message, with the control period that took it) are captured once; then the
// same runtime takes them per period through C++ (a RobotSource handing the buffers over, no
// copy) or through duet_runtime_push_* (one copy per frame, as a driver's callback makes) and
// duet_runtime_spin_once/get_command. Both produce the same commands (lockstep).
#include "bench_util.hpp"

#include <duet.h>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/robot/exploration_runtime.hpp>
#include <duet/sim/sim_robot.hpp>
#include <duet/sim/world.hpp>

#include <memory>
#include <span>
#include <utility>
#include <vector>

namespace duet::bench {
namespace {

constexpr double kSeconds = 30.0;

void RobotLoopCpp(benchmark::State& state) {
  std::size_t periods = 0;
  for (auto _ : state) {
    state.PauseTiming();
    const Profile profile = with_run_seed(builtin_profile("dual"), 1);
    sim::SimRobotSettings rs;
    rs.seed = 1;
    rs.sensor_rate_hz = 1.0;
    auto world = std::make_shared<const sim::World>(sim::builtin_world("lab"));
    auto robot = std::make_unique<sim::SimRobot>(world, profile, rs);
    RuntimeSettings s = profile.runtime;
    s.sensor_rate_hz = 1.0;
    auto rt = std::make_unique<ExplorationRuntime>(profile, robot->chassis(), robot->sensors(), s);
    state.ResumeTiming();
    arena(2).execute([&] {
      const double dt = 1.0 / s.control_rate_hz;
      double t = 0.0;
      while (t + 1e-9 < kSeconds) {
        t = t + dt;
        robot->advance(t);
        rt->tick(t);
        ++periods;
      }
    });
    state.PauseTiming();
    rt.reset();
    robot.reset();
    state.ResumeTiming();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(periods));
}

void RobotLoopCapi(benchmark::State& state) {
  std::size_t periods = 0;
  duet_device d = duet_device_new("threads=2");
  const char* sets[] = {"runtime.sensor_rate_hz=1"};
  for (auto _ : state) {
    state.PauseTiming();
    duet_sim sim = duet_sim_new(d, "lab", DUET_PROFILE_NAME_OR_FILE, "dual", sets, 1, 1);
    duet_runtime rt = duet_runtime_new(d, DUET_PROFILE_NAME_OR_FILE, "dual", sets, 1, 1);
    duet_runtime_set_time_origin(rt, 0.0);
    std::vector<duet_runtime_sensor_info> info(duet_runtime_get_sensor_count(rt));
    std::vector<std::vector<std::uint16_t>> depth;
    std::vector<std::vector<std::uint8_t>> rgb;
    for (std::size_t i = 0; i < info.size(); ++i) {
      duet_runtime_get_sensor_info(rt, i, &info[i]);
      depth.emplace_back(static_cast<std::size_t>(info[i].width) * info[i].height);
      rgb.emplace_back(static_cast<std::size_t>(info[i].width) * info[i].height * 3);
    }
    state.ResumeTiming();
    const double dt = duet_runtime_get_control_period(rt);
    double t = 0.0;
    duet_twist cmd{0.0f, 0.0f};
    double st[64];
    duet_pose2 p[64];
    duet_twist tw[64];
    while (t + 1e-9 < kSeconds) {
      duet_sim_step(sim, cmd, dt);
      t = t + dt;
      std::size_t n;
      while ((n = duet_sim_take_odometry(sim, st, p, tw, 64)) > 0)
        for (std::size_t k = 0; k < n; ++k) duet_runtime_push_odometry(rt, st[k], p[k], tw[k]);
      for (std::size_t i = 0; i < info.size(); ++i) {
        double stamp;
        while (duet_sim_take_frame(sim, i, &stamp, depth[i].data(), 0, rgb[i].data(), 0, info[i].width, info[i].height)) {
          duet_rgbd_image im;
          duet_rgbd_image_init(&im);
          im.stamp_s = stamp;
          im.depth = depth[i].data();
          im.width = info[i].width;
          im.height = info[i].height;
          im.depth_units_per_m = info[i].depth_units_per_m;
          im.color = rgb[i].data();
          duet_runtime_push_rgbd(rt, i, &im);
        }
      }
      duet_runtime_spin_once(rt, t);
      cmd = duet_runtime_get_command(rt);
      ++periods;
    }
    state.PauseTiming();
    if (duet_device_get_error(d) != DUET_ERROR_NONE) state.SkipWithError(duet_device_get_error_message(d));
    duet_runtime_release(rt);
    duet_sim_release(sim);
    state.ResumeTiming();
  }
  duet_device_release(d);
  state.SetItemsProcessed(static_cast<std::int64_t>(periods));
}

/// The inputs of the run, per control period.
struct Captured {
  struct Period {
    std::vector<OdometryMsg> odometry;
    std::vector<std::vector<StampedRgbd>> frames;  ///< per sensor
  };
  Profile profile;
  RuntimeSettings settings;
  std::vector<Period> periods;
};

/// A RobotSource that hands over the captured inputs of period k at advance().
class CapturedSource final : public RobotSource {
 public:
  explicit CapturedSource(std::vector<Captured::Period> periods) : periods_(std::move(periods)) {
    for (std::size_t i = 0; i < periods_.front().frames.size(); ++i) {
      sensors_.push_back(std::make_unique<Sensor>());
      ifaces_.push_back(sensors_.back().get());
    }
  }
  ChassisInterface& chassis() override { return chassis_; }
  std::span<RgbdSensorInterface* const> sensors() override { return ifaces_; }
  void advance(double) override {
    Captured::Period& p = periods_[k_++];
    chassis_.out = std::move(p.odometry);
    for (std::size_t i = 0; i < sensors_.size(); ++i) sensors_[i]->out = std::move(p.frames[i]);
  }

 private:
  struct Chassis final : ChassisInterface {
    void command(const Twist&) override {}
    std::vector<OdometryMsg> take_odometry() override { return std::exchange(out, {}); }
    std::vector<OdometryMsg> out;
  };
  struct Sensor final : RgbdSensorInterface {
    std::vector<StampedRgbd> take_frames() override { return std::exchange(out, {}); }
    std::vector<StampedRgbd> out;
  };
  std::vector<Captured::Period> periods_;
  std::size_t k_ = 0;
  Chassis chassis_;
  std::vector<std::unique_ptr<Sensor>> sensors_;
  std::vector<RgbdSensorInterface*> ifaces_;
};

/// Records a RobotSource's deliveries per period.
class Tap final : public RobotSource {
 public:
  Tap(RobotSource& inner, Captured& out) : inner_(inner), out_(out), chassis_(*this) {
    for (std::size_t i = 0; i < inner.sensors().size(); ++i) {
      sensors_.push_back(std::make_unique<Sensor>(*this, i));
      ifaces_.push_back(sensors_.back().get());
    }
  }
  ChassisInterface& chassis() override { return chassis_; }
  std::span<RgbdSensorInterface* const> sensors() override { return ifaces_; }
  void advance(double t) override {
    inner_.advance(t);
    out_.periods.emplace_back();
    out_.periods.back().frames.resize(sensors_.size());
  }

 private:
  struct Chassis final : ChassisInterface {
    explicit Chassis(Tap& tap) : t_(tap) {}
    void command(const Twist& c) override { t_.inner_.chassis().command(c); }
    std::vector<OdometryMsg> take_odometry() override {
      auto v = t_.inner_.chassis().take_odometry();
      t_.out_.periods.back().odometry = v;
      return v;
    }
    Tap& t_;
  };
  struct Sensor final : RgbdSensorInterface {
    Sensor(Tap& tap, std::size_t index) : t_(tap), i_(index) {}
    std::vector<StampedRgbd> take_frames() override {
      auto v = t_.inner_.sensors()[i_]->take_frames();
      t_.out_.periods.back().frames[i_] = v;
      return v;
    }
    Tap& t_;
    std::size_t i_;
  };
  RobotSource& inner_;
  Captured& out_;
  Chassis chassis_;
  std::vector<std::unique_ptr<Sensor>> sensors_;
  std::vector<RgbdSensorInterface*> ifaces_;
};

const Captured& captured() {
  static const Captured c = [] {
    Captured out;
    out.profile = with_run_seed(builtin_profile("dual"), 1);
    out.profile.runtime.sensor_rate_hz = 1.0;
    out.settings = out.profile.runtime;
    sim::SimRobotSettings rs;
    rs.seed = 1;
    rs.sensor_rate_hz = 1.0;
    auto world = std::make_shared<const sim::World>(sim::builtin_world("lab"));
    sim::SimRobot robot(world, out.profile, rs);
    Tap tap(robot, out);
    ExplorationRuntime rt(out.profile, tap.chassis(), tap.sensors(), out.settings);
    arena(2).execute([&] {
      double t = 0.0;
      while (t + 1e-9 < kSeconds) {
        t = t + 1.0 / out.settings.control_rate_hz;
        tap.advance(t);
        rt.tick(t);
      }
    });
    return out;
  }();
  return c;
}

void RuntimeApiCpp(benchmark::State& state) {
  const Captured& c = captured();
  std::size_t periods = 0;
  Twist last{};
  for (auto _ : state) {
    state.PauseTiming();
    auto src = std::make_unique<CapturedSource>(c.periods);  // a copy per iteration, outside the timing
    auto rt = std::make_unique<ExplorationRuntime>(c.profile, src->chassis(), src->sensors(), c.settings);
    state.ResumeTiming();
    arena(2).execute([&] {
      double t = 0.0;
      for (std::size_t k = 0; k < c.periods.size(); ++k) {
        t = t + 1.0 / c.settings.control_rate_hz;
        src->advance(t);
        rt->tick(t);
        last = rt->last_command();
        ++periods;
      }
    });
    state.PauseTiming();
    rt.reset();
    src.reset();
    state.ResumeTiming();
  }
  state.counters["last_v"] = last.v;
  state.SetItemsProcessed(static_cast<std::int64_t>(periods));
}

void RuntimeApiCapi(benchmark::State& state) {
  const Captured& c = captured();
  std::size_t periods = 0;
  duet_twist last{};
  duet_device d = duet_device_new("threads=2");
  const char* sets[] = {"runtime.sensor_rate_hz=1"};
  for (auto _ : state) {
    state.PauseTiming();
    duet_runtime rt = duet_runtime_new(d, DUET_PROFILE_NAME_OR_FILE, "dual", sets, 1, 1);
    duet_runtime_set_time_origin(rt, 0.0);
    state.ResumeTiming();
    double t = 0.0;
    for (const Captured::Period& p : c.periods) {
      t = t + 1.0 / c.settings.control_rate_hz;
      for (const OdometryMsg& m : p.odometry)
        duet_runtime_push_odometry(rt, m.stamp_s, duet_pose2{m.pose.x, m.pose.y, m.pose.theta}, duet_twist{m.twist.v, m.twist.omega});
      for (std::size_t i = 0; i < p.frames.size(); ++i)
        for (const StampedRgbd& f : p.frames[i]) {
          duet_rgbd_image im;
          duet_rgbd_image_init(&im);
          im.stamp_s = f.stamp_s;
          im.depth = f.image.depth.data();
          im.width = f.image.width;
          im.height = f.image.height;
          im.depth_units_per_m = c.profile.sensors[i].depth_units_per_m;
          im.color = f.image.rgb.empty() ? nullptr : f.image.rgb.data();
          duet_runtime_push_rgbd(rt, i, &im);
        }
      duet_runtime_spin_once(rt, t);
      last = duet_runtime_get_command(rt);
      ++periods;
    }
    state.PauseTiming();
    if (duet_device_get_error(d) != DUET_ERROR_NONE) state.SkipWithError(duet_device_get_error_message(d));
    duet_runtime_release(rt);
    state.ResumeTiming();
  }
  duet_device_release(d);
  state.counters["last_v"] = last.v;
  state.SetItemsProcessed(static_cast<std::int64_t>(periods));
}

BENCHMARK(RuntimeApiCpp)->Name("RuntimeApi/cpp/lab30s")->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();
BENCHMARK(RuntimeApiCapi)->Name("RuntimeApi/capi/lab30s")->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();
BENCHMARK(RobotLoopCpp)->Name("RobotLoop/cpp/lab30s")->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();
BENCHMARK(RobotLoopCapi)->Name("RobotLoop/capi/lab30s")->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

}  // namespace
}  // namespace duet::bench
