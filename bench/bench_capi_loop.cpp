// RobotLoop/{cpp,capi}: the overhead of the C API's robot loop (issue 20 target: <= 2 %). The
// same lockstep run - the lab, the dual profile, seed 1, the first 30 simulated s (600 control
// periods, 31 map updates) - once in C++ (SimRobot -> ExplorationRuntime, what `duet explore`
// runs) and once through duet.h alone (duet_sim -> copies of every frame and odometry message ->
// duet_runtime, what bindings_c/examples/robot_loop.c runs). Both drive the same trajectory
// bit for bit (tests/capi/capi_robot_loop_test.cpp), so the difference is the API's copies,
// conversions, locks and published state. Building the world, the renderer and the runtime is
// outside the timing. 2 threads. Items = control periods.
#include "bench_util.hpp"

#include <duet.h>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/robot/exploration_runtime.hpp>
#include <duet/sim/sim_robot.hpp>
#include <duet/sim/world.hpp>

#include <memory>
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

BENCHMARK(RobotLoopCpp)->Name("RobotLoop/cpp/lab30s")->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();
BENCHMARK(RobotLoopCapi)->Name("RobotLoop/capi/lab30s")->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

}  // namespace
}  // namespace duet::bench
