// `duet run`: the runtime on a robot source by name (robot_source.hpp) - the loop a robot runs,
// with no ground truth and no scoring (`duet explore` scores the simulator's runs). Writes the
// grid map, the cloud map and summary.json (the runtime's timing, why it stopped, the faults
// injected and what the runtime's input guard did).
#include "commands.hpp"
#include "stop_signals.hpp"

#include <duet/kernels/error.hpp>
#include <duet/runtime/io/cloud_io.hpp>
#include <duet/runtime/io/grid_io.hpp>
#include <duet/runtime/io/output.hpp>
#include <duet/runtime/robot/faults.hpp>
#include <duet/runtime/robot/robot_loop.hpp>

#include <nlohmann/json.hpp>
#include <tbb/task_arena.h>

#include <cstdio>
#include <filesystem>
#include <memory>

namespace duet::app {
namespace {

struct RunOptions {
  std::string robot = "sim:lab";
  std::string profile = "dual";
  std::vector<std::string> configs, sets;
  std::uint64_t seed = 1;
  double max_time = 600.0;
  bool realtime = false;
  std::string out = "out/run";
  int threads = 0;
  bool quiet = false;
  std::vector<std::string> faults;  // --fault, after the profile's faults:
};

/// The profile's faults and --fault: the stream faults only (extrinsics and kidnap move the
/// simulated world: `duet explore` applies those).
std::vector<Fault> stream_faults(const Profile& profile, const std::vector<std::string>& extra) {
  std::vector<std::string> specs = profile.faults;
  specs.insert(specs.end(), extra.begin(), extra.end());
  std::vector<Fault> faults = parse_faults(specs, profile.sensors.size());
  for (const Fault& f : faults)
    if (f.kind == FaultKind::kExtrinsics || f.kind == FaultKind::kKidnap)
      fail(ErrorCode::kInvalidArgument, "fault '" + f.spec + "': " + to_string(f.kind) +
                                            " changes the simulated world itself; `duet run` injects only the stream faults "
                                            "(use `duet explore --fault` for this one)");
  return faults;
}

int run(const RunOptions& o) {
  Profile profile = resolve_profile(o.profile, overlays(o.configs, o.sets));
  if (o.realtime) profile.runtime.execution = Execution::kBackground;  // control never waits on the wall clock
  RobotRunSettings rs;
  rs.max_time_s = o.max_time;
  rs.realtime = o.realtime;
  validate(rs);
  const std::filesystem::path out(o.out);
  const StopSignals signals;  // SIGINT / SIGTERM from here on: stop the loop, save the maps so far, say so
  const std::vector<Fault> faults = stream_faults(profile, o.faults);  // a bad fault is an error before the run
  prepare_output_dir(out);  // before the run, not after it
  int stopped_by = 0;
  tbb::task_arena arena(o.threads > 0 ? o.threads : tbb::task_arena::automatic);
  arena.execute([&] {
    std::unique_ptr<RobotSource> robot = robot_sources().make(o.robot, profile, o.seed);
    std::unique_ptr<FaultInjector> injector;
    if (!faults.empty()) injector = std::make_unique<FaultInjector>(*robot, faults, o.seed ^ 0xFA017ull);
    RobotSource* source = injector ? static_cast<RobotSource*>(injector.get()) : robot.get();
    ExplorationRuntime runtime(profile, source->chassis(), source->sensors());
    double next_print = 10.0;
    RobotRunResult r = run_robot(*source, runtime, rs, [&](double t) {
      if (!o.quiet && t + 1e-9 >= next_print) {
        std::fprintf(stderr, "t = %6.1f s  state %s\n", t, to_string(runtime.state()));
        next_print += 10.0;
      }
      stopped_by = StopSignals::received();
      return stopped_by == 0;
    });
    if (stopped_by) {
      char why[128];
      std::snprintf(why, sizeof why, "%s at t = %.1f s: the maps so far were saved", StopSignals::name(stopped_by), r.time_s);
      r.stop_detail = why;
    }
    const OccupancyGrid& grid = runtime.map_grid();
    if (grid.width() > 0 && grid.height() > 0) {
      write_map_server(grid, out / "grid.yaml");
      write_grid_png(grid, out / "grid.png");
    }
    write_pcd(out / "cloud.pcd", runtime.mapper().cloud(), PcdEncoding::kBinaryCompressed);
    nlohmann::json j;
    j["robot"] = o.robot;
    j["profile"] = profile.name;
    j["time_s"] = r.time_s;
    j["done"] = r.done;
    j["stop_detail"] = r.stop_detail;
    j["sets_integrated"] = r.stats.sets_integrated;
    j["runtime"] = timing_json(r.timing);
    j["runtime"]["execution"] = to_string(profile.runtime.execution);
    j["runtime"]["paced_by_wall_clock"] = o.realtime;
    j["interrupted"] = stopped_by != 0;
    j["faults"] = faults_json(injector ? injector->counts() : std::vector<FaultCount>{});
    j["input"] = input_json(r.stats.input, r.stats.sets_with_missing, r.stats.blind_holds, r.stats.relocalizations);
    write_text_file(out / "summary.json", j.dump(2) + "\n");
    if (!o.quiet || stopped_by)
      std::fprintf(stderr, "%s after %.1f s%s%s; wrote %s/{grid.yaml, grid.pgm, grid.png, cloud.pcd, summary.json}\n",
                   r.done ? "done" : "stopped", r.time_s, r.stop_detail.empty() ? "" : ": ", r.stop_detail.c_str(), out.string().c_str());
  });
  return stopped_by ? StopSignals::exit_code(stopped_by) : 0;
}

}  // namespace

void add_run_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<RunOptions>();
  std::string sources;
  for (const RobotSourceKind& k : robot_sources().kinds()) sources += "\n  " + k.name + ": " + k.help;
  CLI::App* cmd = app.add_subcommand("run", "Run the robot loop on a robot source (no ground truth, no scoring); sources:" + sources);
  cmd->add_option("-r,--robot", o->robot, "robot source: NAME or NAME:ARGUMENT")->capture_default_str();
  cmd->add_option("-p,--profile", o->profile, "robot profile: dual, single or a profile YAML")->capture_default_str();
  add_overlay_options(cmd, o->configs, o->sets);
  cmd->add_option("-s,--seed", o->seed, "seed for sources with randomness")->capture_default_str();
  cmd->add_option("-t,--max-time", o->max_time, "time limit on the runtime's clock [s]")->capture_default_str();
  cmd->add_flag("--realtime", o->realtime, "pace the loop by the wall clock (background execution)");
  cmd->add_option("-o,--out", o->out, "output folder")->capture_default_str();
  cmd->add_option("-j,--threads", o->threads, "worker threads (0 = all cores)")->check(CLI::NonNegativeNumber)->capture_default_str();
  cmd->add_flag("-q,--quiet", o->quiet, "no progress output");
  cmd->add_option("--fault", o->faults,
                  "inject a stream fault between the robot source and the runtime, KIND[:SENSOR]@START[+DURATION][=AMOUNT] "
                  "(repeatable; added to the profile's faults; kinds: camera_stop, depth_zero, depth_noise, color_black, "
                  "wheel_slip, odom_jump, stamp_disorder, stamp_duplicate, stamp_late, clock_back; see runtime/robot/faults.hpp)");
  cmd->callback([o, &exit_code] { exit_code = run(*o); });
}

}  // namespace duet::app
