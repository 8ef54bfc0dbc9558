// `duet replay DIR`: maps a recording again - mapping and localisation on recorded input, no
// robot to drive (runtime/io/recording.hpp, docs/recording.md). A duet recording (`duet explore
// --record`, duet_runtime_record) runs through the same runtime as the run that recorded it and,
// in lockstep, gives the same grid and cloud bit for bit. A TUM RGB-D folder (rgb.txt,
// depth.txt, groundtruth.txt) is a one-sensor recording with no odometry: until visual odometry
// exists (issue 21) its poses come from groundtruth.txt (--poses groundtruth), mapped as
// `duet map` maps a posed folder.
#include "commands.hpp"
#include "stop_signals.hpp"

#include <duet/kernels/error.hpp>
#include <duet/runtime/io/output.hpp>
#include <duet/runtime/io/recording.hpp>
#include <duet/runtime/io/runtime_outputs.hpp>
#include <duet/runtime/robot/clock.hpp>

#include <tbb/task_arena.h>

#include <cstdio>
#include <filesystem>

namespace duet::app {
namespace {

struct ReplayOptions {
  std::string input;
  std::string out = "out/replay";
  std::string poses = "odometry";
  bool realtime = false;
  int threads = 0;
  bool quiet = false;
};

int replay_recording(const ReplayOptions& o) {
  const Recording rec = read_recording(o.input);
  const std::filesystem::path out(o.out);
  const StopSignals signals;
  prepare_output_dir(out);
  int stopped_by = 0;
  tbb::task_arena arena(o.threads > 0 ? o.threads : tbb::task_arena::automatic);
  arena.execute([&] {
    ReplaySource source(rec);
    ExplorationRuntime runtime(rec.profile, source.chassis(), source.sensors(), rec.profile.runtime);
    SteadyClock wall;
    const double dt = 1.0 / rec.profile.runtime.control_rate_hz, end = rec.end_s();
    Trajectory traj;
    double t = 0.0, next_print = 10.0;
    while (t + 1e-9 < end) {  // the control periods of the recorded run, at the same times
      t = t + dt;
      if (o.realtime) wall.sleep_until(t);
      source.advance(t);
      runtime.tick(t);
      traj.emplace_back(t, runtime.pose());
      if (!o.quiet && t >= next_print) {
        std::fprintf(stderr, "t = %6.1f / %.1f s\n", t, end);
        next_print += 10.0;
      }
      if ((stopped_by = StopSignals::received()) != 0) break;
    }
    runtime.drain();
    write_runtime_outputs(runtime, traj, out, {{"replayed_s", t}, {"recording_end_s", end}, {"interrupted", stopped_by != 0 ? 1.0 : 0.0}});
    if (!o.quiet || stopped_by)
      std::fprintf(stderr, "duet replay: %s %s at %.1f s (%zu map updates); wrote %s/{grid.yaml, grid.pgm, grid.png, cloud.pcd, trajectory.tum, summary.json}\n",
                   stopped_by ? "interrupted" : "replayed", o.input.c_str(), t, runtime.stats().sets_integrated, out.string().c_str());
  });
  return stopped_by ? StopSignals::exit_code(stopped_by) : 0;
}

int replay(const ReplayOptions& o) {
  const std::filesystem::path in(o.input);
  std::error_code ec;
  if (std::filesystem::is_regular_file(in / "recording.yaml", ec)) {
    if (o.poses != "odometry")
      fail(ErrorCode::kInvalidArgument, "--poses " + o.poses + ": a duet recording is replayed with its own odometry (--poses odometry)");
    return replay_recording(o);
  }
  if (std::filesystem::is_regular_file(in / "rgb.txt", ec) && std::filesystem::is_regular_file(in / "depth.txt", ec)) {
    if (o.poses != "groundtruth")
      fail(ErrorCode::kUnsupported, o.input + ": a TUM RGB-D folder has no wheel odometry and duet has no visual odometry yet "
                                              "(issue 21): replay it with --poses groundtruth (the poses of groundtruth.txt)");
    if (o.realtime) fail(ErrorCode::kInvalidArgument, "--realtime: a TUM RGB-D folder is mapped as fast as it can be");
    if (!o.quiet) std::fprintf(stderr, "duet replay: %s is a TUM RGB-D folder: mapping it with the poses of groundtruth.txt (no visual odometry yet)\n", o.input.c_str());
    return run_map_folder(o.input, o.out, "single", "tum", o.threads, o.quiet);
  }
  fail(ErrorCode::kIo, o.input + ": neither a duet recording (recording.yaml) nor a TUM RGB-D folder (rgb.txt, depth.txt, groundtruth.txt)");
}

}  // namespace

void add_replay_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<ReplayOptions>();
  CLI::App* cmd = app.add_subcommand("replay", "Map a recording again: a duet recording (duet explore --record) or a TUM RGB-D folder");
  cmd->add_option("input", o->input, "the recording's folder")->required();
  cmd->add_option("-o,--out", o->out, "output folder")->capture_default_str();
  cmd->add_option("--poses", o->poses, "odometry (a duet recording) or groundtruth (a TUM RGB-D folder: groundtruth.txt)")
      ->check(CLI::IsMember({"odometry", "groundtruth"}))
      ->capture_default_str();
  cmd->add_flag("--realtime", o->realtime, "replay at the recorded rate (default: as fast as it can)");
  cmd->add_option("-j,--threads", o->threads, "worker threads (0 = all cores)")->check(CLI::NonNegativeNumber)->capture_default_str();
  cmd->add_flag("-q,--quiet", o->quiet, "no progress output");
  cmd->callback([o, &exit_code] { exit_code = replay(*o); });
}

}  // namespace duet::app
