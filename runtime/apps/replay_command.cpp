// `duet replay DIR` (or RUN.bag): maps a recording again - mapping and localisation on recorded input, no
// robot to drive (runtime/io/recording.hpp, docs/recording.md). A duet recording (`duet explore
// --record`, duet_runtime_record) runs through the same runtime as the run that recorded it and,
// in lockstep, gives the same grid and cloud bit for bit; --poses vision turns the visual
// odometry on (localization.visual_odometry: vision and wheels fused). A TUM RGB-D folder
// (rgb.txt, depth.txt; groundtruth.txt optional) is one hand-held camera with no odometry: its
// poses come from the visual odometer (--poses vision, the default; localization/
// visual_odometer.hpp) - no ground truth needed - or from groundtruth.txt (--poses groundtruth),
// and it is mapped as `duet map` maps a posed folder. trajectory.tum is written either way, for
// `duet eval-traj`.
#include "commands.hpp"
#include "stop_signals.hpp"

#include <duet/kernels/error.hpp>
#include <duet/runtime/io/output.hpp>
#include <duet/runtime/io/recording.hpp>
#include <duet/runtime/io/rgbd_dataset.hpp>
#include <duet/runtime/io/runtime_outputs.hpp>
#include <duet/runtime/io/trajectory_io.hpp>
#include <duet/runtime/localization/visual_odometer.hpp>
#include <duet/runtime/robot/clock.hpp>

#include <tbb/task_arena.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <unistd.h>
#include <vector>
#include <filesystem>

namespace duet::app {
namespace {

struct ReplayOptions {
  std::string input;
  std::string out = "out/replay";
  std::string poses = "auto";
  bool realtime = false;
  int threads = 0;
  bool quiet = false;
  std::string profile = "dual";     ///< a bag's robot (a duet recording carries its own)
  std::vector<std::string> sets;    ///< a bag's profile overrides
};

int replay_recording(const ReplayOptions& o) {
  Recording rec = read_recording(o.input);
  if (o.poses == "vision") rec.profile.runtime.visual_odometry.enabled = true;
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

// The hand-held camera of a TUM folder tracked by the visual odometer (the "robot" is the
// camera's optical frame; the world is the first tracked frame's), then mapped with those poses.
int replay_tum_vision(const ReplayOptions& o) {
  RgbdDatasetOptions dopt;
  dopt.layout = "tum";
  dopt.require_poses = false;
  const RgbdDataset ds = RgbdDataset::open(o.input, dopt);
  std::vector<std::optional<Eigen::Isometry3f>> poses(ds.size());
  std::vector<StampedPose> traj;
  VisualOdometer vo;
  Eigen::Isometry3d velocity = Eigen::Isometry3d::Identity();  // the last increment: constant-velocity guess
  std::size_t ok = 0, failed = 0, blank = 0;
  double seconds = 0.0;
  tbb::task_arena arena(o.threads > 0 ? o.threads : tbb::task_arena::automatic);
  SteadyClock wall;
  arena.execute([&] {
    for (std::size_t i = 0; i < ds.size(); ++i) {
      if (StopSignals::received()) break;
      const RgbdFrame f = ds.load(i);
      const SensorFrame sf = f.sensor_frame();
      const double w0 = wall.now_s();
      const VisualOdometer::Step step = vo.track(std::span(&sf, 1), velocity);
      seconds += wall.now_s() - w0;
      if (!vo.has_keyframe()) {  // nothing to start from yet (a blank first view)
        ++blank;
        continue;
      }
      if (!step.first && step.result.status != VisualOdometryStatus::kOk) {
        ++failed;  // not mapped: its pose is only the guess
        velocity = Eigen::Isometry3d::Identity();
        continue;
      }
      ++ok;
      velocity = step.first ? Eigen::Isometry3d::Identity() : step.increment;
      poses[i] = vo.pose().cast<float>();
      traj.push_back(StampedPose{ds.stamp(i), vo.pose()});
    }
  });
  if (traj.empty()) fail(ErrorCode::kInvalidArgument, o.input + ": the visual odometry tracked no frame (" + std::to_string(blank) + " of " +
                                                          std::to_string(ds.size()) + " had too few features with depth)");
  if (!o.quiet)
    std::fprintf(stderr, "duet replay: %s is a TUM RGB-D folder: %zu of %zu frames tracked by visual odometry (%zu failed, %zu before the first "
                         "view with features), %zu location points, %.1f ms per frame\n",
                 o.input.c_str(), ok, ds.size(), failed, blank, vo.keyframes(), 1e3 * seconds / std::max<std::size_t>(1, ok + failed));
  nlohmann::json extra;
  extra["poses"] = "vision";
  extra["visual_odometry"] = {{"frames", ds.size()}, {"tracked", ok}, {"failed", failed}, {"before_first_view", blank},
                              {"location_points", vo.keyframes()}, {"resets", vo.resets()},
                              {"mean_ms", 1e3 * seconds / static_cast<double>(std::max<std::size_t>(1, ok + failed))}};
  const int rc = run_map_folder(o.input, o.out, "single", "tum", o.threads, o.quiet, &poses, extra);
  write_text_file(std::filesystem::path(o.out) / "trajectory.tum", tum_trajectory_text(traj));
  return rc;
}

// A ROS 1 bag is mapped by duet_ros_replay (ros/src/bag_replay.cpp), the ROS side's own binary:
// the CLI never links ROS. It sits beside `duet` (installed) or in the build tree's ros/.
int replay_bag(const ReplayOptions& o) {
  if (o.poses == "vision" || o.poses == "groundtruth")
    fail(ErrorCode::kInvalidArgument, "--poses " + o.poses + ": a bag is replayed with its odometry (set localization.visual_odometry.enabled=true "
                                      "with --set to fuse vision)");
  if (o.realtime) fail(ErrorCode::kInvalidArgument, "--realtime: a bag is mapped as fast as it can be");
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  std::filesystem::path tool;
  for (const auto& c : {self.parent_path() / "duet_ros_replay", self.parent_path() / "ros" / "duet_ros_replay"})
    if (!ec && std::filesystem::is_regular_file(c)) {
      tool = c;
      break;
    }
  if (tool.empty())
    fail(ErrorCode::kUnsupported, o.input + ": a ROS bag, but this duet was built without ROS 1 (duet_ros_replay is not beside " +
                                      (ec ? std::string("the duet binary") : self.string()) +
                                      "; scripts/setup.sh installs Debian's ROS packages, then rebuild)");
  std::vector<std::string> args{tool.string(), o.input, "-o", o.out, "--profile", o.profile};
  for (const auto& s : o.sets) args.insert(args.end(), {"--set", s});
  if (o.quiet) args.emplace_back("-q");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::fflush(stdout);
  std::fflush(stderr);
  ::execv(tool.c_str(), argv.data());
  fail(ErrorCode::kIo, tool.string() + ": cannot be run (" + std::strerror(errno) + ")");
}

int replay(const ReplayOptions& o) {
  const std::filesystem::path in(o.input);
  std::error_code ec;
  if (std::filesystem::is_regular_file(in, ec) && in.extension() == ".bag") return replay_bag(o);
  if (std::filesystem::is_regular_file(in / "recording.yaml", ec)) {
    if (o.poses == "groundtruth")
      fail(ErrorCode::kInvalidArgument, "--poses groundtruth: a duet recording has no ground truth; replay it with its odometry "
                                        "(--poses odometry) or with visual odometry fused in (--poses vision)");
    return replay_recording(o);
  }
  if (std::filesystem::is_regular_file(in / "rgb.txt", ec) && std::filesystem::is_regular_file(in / "depth.txt", ec)) {
    if (o.poses == "odometry")
      fail(ErrorCode::kInvalidArgument, "--poses odometry: a TUM RGB-D folder has no wheel odometry; replay it with --poses vision "
                                        "(visual odometry, the default) or --poses groundtruth (groundtruth.txt)");
    if (o.realtime) fail(ErrorCode::kInvalidArgument, "--realtime: a TUM RGB-D folder is mapped as fast as it can be");
    if (o.poses == "groundtruth") {
      if (!std::filesystem::is_regular_file(in / "groundtruth.txt", ec))
        fail(ErrorCode::kIo, (in / "groundtruth.txt").string() + ": missing (--poses groundtruth); --poses vision needs none");
      if (!o.quiet) std::fprintf(stderr, "duet replay: %s is a TUM RGB-D folder: mapping it with the poses of groundtruth.txt\n", o.input.c_str());
      return run_map_folder(o.input, o.out, "single", "tum", o.threads, o.quiet);
    }
    return replay_tum_vision(o);
  }
  fail(ErrorCode::kIo, o.input + ": neither a duet recording (recording.yaml), a TUM RGB-D folder (rgb.txt, depth.txt) nor a ROS 1 bag (.bag)");
}

}  // namespace

void add_replay_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<ReplayOptions>();
  CLI::App* cmd = app.add_subcommand("replay", "Map a recording again: a duet recording (duet explore --record), a TUM RGB-D folder or a ROS 1 bag");
  cmd->add_option("input", o->input, "the recording's folder, or a .bag of the ROS node's topics")->required();
  cmd->add_option("-o,--out", o->out, "output folder")->capture_default_str();
  cmd->add_option("--poses", o->poses,
                   "auto (a duet recording: odometry; a TUM RGB-D folder: vision), odometry (as recorded), vision (visual odometry; "
                   "fused with the wheels for a duet recording) or groundtruth (a TUM folder's groundtruth.txt)")
      ->check(CLI::IsMember({"auto", "odometry", "vision", "groundtruth"}))
      ->capture_default_str();
  cmd->add_flag("--realtime", o->realtime, "replay at the recorded rate (default: as fast as it can)");
  cmd->add_option("-j,--threads", o->threads, "worker threads (0 = all cores)")->check(CLI::NonNegativeNumber)->capture_default_str();
  cmd->add_flag("-q,--quiet", o->quiet, "no progress output");
  cmd->add_option("--profile", o->profile, "a bag's robot profile (a built-in name or a YAML file)")->capture_default_str();
  cmd->add_option("--set", o->sets, "a bag's profile override KEY=VALUE (repeatable)");
  cmd->callback([o, &exit_code] { exit_code = replay(*o); });
}

}  // namespace duet::app
