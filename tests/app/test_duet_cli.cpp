// The `duet` program run as a user runs it: exit codes, outputs, and error messages.
#include <duet/runtime/io/cloud_io.hpp>
#include <duet/runtime/io/grid_io.hpp>

#include "cli_run.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <sys/wait.h>
#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <iterator>
#include <thread>
#include <vector>

namespace fs = std::filesystem;

namespace {

using duet::test::CliRun;
using duet::test::data_dir;
using duet::test::run;
using duet::test::temp_dir;

void expect_map_outputs(const fs::path& out, std::size_t min_points) {
  for (const char* f : {"cloud.pcd", "cloud.ply", "grid.yaml", "grid.pgm", "grid.png", "summary.json"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  const duet::PointCloud pcd = duet::read_pcd(out / "cloud.pcd");
  const duet::PointCloud ply = duet::read_ply(out / "cloud.ply");
  EXPECT_GE(pcd.size(), min_points);
  EXPECT_EQ(pcd.size(), ply.size());
  EXPECT_TRUE(pcd.has_colors());
  const duet::OccupancyGrid grid = duet::read_map_server(out / "grid.yaml");
  EXPECT_GT(grid.known_cells(), 1000u);
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(summary["frames"].get<int>(), 5);
  EXPECT_EQ(summary["cloud_points"].get<std::size_t>(), pcd.size());
  EXPECT_GT(summary["grid"]["occupied_cells"].get<int>(), 100);
  EXPECT_GT(summary["grid"]["free_cells"].get<int>(), 100);
}

}  // namespace

TEST(DuetCli, HelpAndVersion) {
  const CliRun h = run("--help");
  EXPECT_EQ(h.code, 0);
  EXPECT_NE(h.output.find("map"), std::string::npos);
  const CliRun v = run("--version");
  EXPECT_EQ(v.code, 0);
  EXPECT_FALSE(v.output.empty());
}

TEST(DuetCli, MapsSlambookFrames) {
  REQUIRE_DATA("rgbd/slambook2_ch5");
  const fs::path out = temp_dir("slambook");
  const CliRun r = run("map " + (data_dir() / "rgbd/slambook2_ch5").string() + " -o " + out.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("[5/5]"), std::string::npos) << r.output;  // progress line
  expect_map_outputs(out, 10000);
}

TEST(DuetCli, Maps3DMatchFramesWithGivenUp) {
  REQUIRE_DATA("rgbd/3dmatch_seq01");
  const fs::path out = temp_dir("3dmatch");
  const CliRun r = run("map " + (data_dir() / "rgbd/3dmatch_seq01").string() + " --up +y -j 1 -o " + out.string());
  ASSERT_EQ(r.code, 0) << r.output;
  expect_map_outputs(out, 10000);
}

TEST(DuetCli, SameResultWithOneAndTwoThreads) {
  REQUIRE_DATA("rgbd/slambook2_ch5");
  const fs::path a = temp_dir("t1"), b = temp_dir("t2");
  const std::string in = (data_dir() / "rgbd/slambook2_ch5").string();
  ASSERT_EQ(run("map " + in + " -q -j 1 -o " + a.string()).code, 0);
  ASSERT_EQ(run("map " + in + " -q -j 2 -o " + b.string()).code, 0);
  const auto ca = duet::read_pcd(a / "cloud.pcd"), cb = duet::read_pcd(b / "cloud.pcd");
  ASSERT_EQ(ca.size(), cb.size());
  for (std::size_t i = 0; i < ca.size(); ++i) ASSERT_EQ(ca.points[i], cb.points[i]) << i;
  const auto ga = duet::read_map_server(a / "grid.yaml"), gb = duet::read_map_server(b / "grid.yaml");
  ASSERT_EQ(ga.width(), gb.width());
  ASSERT_EQ(ga.height(), gb.height());
  for (std::size_t i = 0; i < ga.cell_count(); ++i) {
    const float x = ga.logodds()[i], y = gb.logodds()[i];
    ASSERT_TRUE((std::isnan(x) && std::isnan(y)) || x == y) << i;
  }
}

TEST(DuetCli, MissingFrameIsAClearError) {
  REQUIRE_DATA("rgbd/slambook2_ch5");
  const fs::path in = temp_dir("missing-frame");
  fs::copy(data_dir() / "rgbd/slambook2_ch5", in, fs::copy_options::recursive);
  fs::permissions(in, fs::perms::owner_all, fs::perm_options::add);
  for (const auto& e : fs::recursive_directory_iterator(in))
    fs::permissions(e.path(), fs::perms::owner_all, fs::perm_options::add);
  fs::remove(in / "depth" / "3.pgm");
  const CliRun r = run("map " + in.string() + " -o " + (in / "out").string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("3.pgm"), std::string::npos) << r.output;
}

TEST(DuetCli, MalformedPoseIsAClearError) {
  REQUIRE_DATA("rgbd/slambook2_ch5");
  const fs::path in = temp_dir("bad-pose");
  fs::copy(data_dir() / "rgbd/slambook2_ch5", in, fs::copy_options::recursive);
  for (const auto& e : fs::recursive_directory_iterator(in))
    fs::permissions(e.path(), fs::perms::owner_all, fs::perm_options::add);
  fs::permissions(in, fs::perms::owner_all, fs::perm_options::add);
  {
    std::ifstream f(in / "pose.txt");
    std::string all, line;
    int n = 0;
    while (std::getline(f, line)) all += (++n == 2 ? std::string("1 2 three 4 5 6 7") : line) + "\n";
    f.close();
    std::ofstream(in / "pose.txt") << all;
  }
  const CliRun r = run("map " + in.string() + " -o " + (in / "out").string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("pose.txt"), std::string::npos) << r.output;
}

TEST(DuetCli, BadArgumentsAreClearErrors) {
  const CliRun missing = run("map /nonexistent/folder");
  EXPECT_NE(missing.code, 0);
  EXPECT_NE(missing.output.find("/nonexistent/folder"), std::string::npos) << missing.output;
  REQUIRE_DATA("rgbd/slambook2_ch5");
  const CliRun up = run("map " + (data_dir() / "rgbd/slambook2_ch5").string() + " --up sideways -o " +
                     temp_dir("bad-up").string());
  EXPECT_NE(up.code, 0);
  EXPECT_NE(up.output.find("--up"), std::string::npos) << up.output;
  const CliRun floor = run("map " + (data_dir() / "rgbd/slambook2_ch5").string() + " --floor-z low -o " +
                        temp_dir("bad-floor").string());
  EXPECT_NE(floor.code, 0);
  EXPECT_NE(floor.output.find("--floor-z"), std::string::npos) << floor.output;
}

TEST(DuetCli, ProfileCommand) {
  const CliRun dual = run("profile dual");
  EXPECT_EQ(dual.code, 0) << dual.output;
  EXPECT_NE(dual.output.find("-0.118"), std::string::npos) << dual.output;
  const fs::path bad = temp_dir("bad-profile") / "broken.yaml";
  std::ofstream(bad) << "name: x\nchassis: [1, 2\n";
  const CliRun r = run("profile " + bad.string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("broken.yaml"), std::string::npos) << r.output;
  // The printed tree loads back (and prints the same), with overlays applied.
  const fs::path tree = temp_dir("profile-tree") / "tree.yaml";
  const CliRun set = run("profile dual --set exploration.view_range_m=3 --set runtime.execution=background");
  ASSERT_EQ(set.code, 0) << set.output;
  EXPECT_NE(set.output.find("view_range_m: 3\n"), std::string::npos) << set.output;
  EXPECT_NE(set.output.find("execution: background"), std::string::npos) << set.output;
  std::ofstream(tree) << set.output;
  const CliRun again = run("profile " + tree.string());
  EXPECT_EQ(again.code, 0) << again.output;
  EXPECT_EQ(again.output, set.output);
  const CliRun check = run("profile " + tree.string() + " --check");
  EXPECT_EQ(check.code, 0) << check.output;
  EXPECT_NE(check.output.find("OK"), std::string::npos) << check.output;
}

// ---- duet explore / duet compare -----------------------------------------------------------

namespace {

const char* kRoomWorld = R"(name: room
floor: {min: [0, 0], max: [4.2, 3.2]}
start: [1.0, 1.0, 0.0]
walls:
  - {points: [[0.05, 0.05], [4.15, 0.05], [4.15, 3.15], [0.05, 3.15]], closed: true}
boxes:
  - {name: crate, centre: [2.8, 2.0], size: [0.5, 0.5], height_m: 0.8}
)";

fs::path write_file(const fs::path& dir, const std::string& name, const std::string& text) {
  std::ofstream(dir / name) << text;
  return dir / name;
}

}  // namespace

TEST(DuetCli, ExploresAWorldAndWritesEveryOutput) {
  const fs::path dir = temp_dir("explore");
  const fs::path world = write_file(dir, "room.yaml", kRoomWorld);
  const CliRun r = run("explore --world " + world.string() + " --max-time 30 --seed 2 --out " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("coverage"), std::string::npos) << r.output;  // the progress line
  EXPECT_NE(r.output.find("real time"), std::string::npos) << r.output;
  const fs::path out = dir / "out";
  for (const char* f : {"cloud.pcd", "cloud.ply", "grid.yaml", "grid.pgm", "grid.png", "trajectory.tum",
                        "trajectory_true.tum", "curve.csv", "curve.png", "summary.json", "log.json"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  const auto s = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(s["world"], "room");
  EXPECT_EQ(s["profile"], "dual_kinect_kobuki");
  EXPECT_EQ(s["seed"], 2);
  EXPECT_EQ(s["collisions"], 0);
  EXPECT_GT(s["coverage"].get<double>(), 0.5);
  EXPECT_GT(s["explored_area_m2"].get<double>(), 4.0);
  EXPECT_GT(s["path_length_m"].get<double>(), 0.5);
  EXPECT_GT(s["decisions"]["count"].get<int>(), 0);
  for (const char* k : {"t90_s", "t_31m2_s", "target_region_entered_s", "stop_reason", "explorer_status", "wall_time_s"})
    EXPECT_TRUE(s.contains(k)) << k;
  EXPECT_GT(duet::read_pcd(out / "cloud.pcd").size(), 1000u);
  EXPECT_GT(duet::read_map_server(out / "grid.yaml").known_cells(), 1000u);
  // TUM trajectories: one pose per control period (20 Hz), 8 columns.
  std::ifstream tum(out / "trajectory.tum");
  std::string line;
  int poses = 0;
  while (std::getline(tum, line)) {
    if (line.empty() || line[0] == '#') continue;
    ++poses;
    double v[8];
    EXPECT_EQ(std::sscanf(line.c_str(), "%lf %lf %lf %lf %lf %lf %lf %lf", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &v[6], &v[7]), 8)
        << line;
  }
  // The run lasts up to the 30 s limit (the explorer may finish the room sooner): a pose at t = 0
  // and one per 50 ms control period after it.
  const double sim_time = s["sim_time_s"].get<double>();
  EXPECT_GT(sim_time, 5.0);
  EXPECT_LE(sim_time, 30.0 + 1e-6);
  EXPECT_NEAR(poses, 1 + 20.0 * sim_time, 1.0);
}

// --realtime paces the simulation by the wall clock: the run never gets ahead of it (a lower
// bound on wall time; being slower than real time on a loaded machine is allowed).
TEST(DuetCli, RealtimeExploreNeverRunsAheadOfTheWallClock) {
  const fs::path dir = temp_dir("explore-realtime");
  const fs::path world = write_file(dir, "room.yaml", kRoomWorld);
  const CliRun r = run("explore -q --realtime --world " + world.string() + " --max-time 3 --seed 1 --out " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const auto s = nlohmann::json::parse(std::ifstream(dir / "out" / "summary.json"));
  const double sim = s["sim_time_s"].get<double>();
  EXPECT_NEAR(sim, 3.0, 0.06);
  EXPECT_GE(s["wall_time_s"].get<double>(), sim - 0.06);  // the last period may end a tick early
  EXPECT_LE(s["speed_vs_real_time"].get<double>(), 1.03);
  EXPECT_EQ(s["stop_reason"], "time_limit");
}

TEST(DuetCli, ExploreErrorsNameTheFileAndTheProblem) {
  const fs::path dir = temp_dir("explore-errors");
  const fs::path bad_world = write_file(dir, "bad_world.yaml", "name: x\nfloor: {min: [0, 0], max: [4, 3]}\nstart: [1, 1]\n");
  CliRun r = run("explore -q --world " + bad_world.string() + " --out " + (dir / "o").string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("bad_world.yaml"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("start"), std::string::npos) << r.output;
  const fs::path world = write_file(dir, "room.yaml", kRoomWorld);
  const fs::path bad_profile = write_file(dir, "bad_profile.yaml", "name: p\nchassis: 3\n");
  r = run("explore -q --world " + world.string() + " --profile " + bad_profile.string() + " --out " + (dir / "o").string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("bad_profile.yaml"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("chassis"), std::string::npos) << r.output;
  r = run("explore -q --world no_such_world --out " + (dir / "o").string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("no_such_world"), std::string::npos) << r.output;
  r = run("explore -q --world lab --sensor-rate fast --out " + (dir / "o").string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("--sensor-rate"), std::string::npos) << r.output;
  r = run("explore -q --world lab --set exploration.recent_obstacles_s=-1 --out " + (dir / "o").string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("--set exploration.recent_obstacles_s=-1: exploration.recent_obstacles_s"), std::string::npos) << r.output;
  r = run("explore -q --world lab --set control.cornered_after_s=-2 --out " + (dir / "o").string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("cornered_after_s"), std::string::npos) << r.output;
  r = run("explore -q --world lab --strategy greedy --out " + (dir / "o").string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("--strategy"), std::string::npos) << r.output;
  r = run("explore -q --world lab --gyro-bias 0.5 --out " + (dir / "o").string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("--gyro-bias"), std::string::npos) << r.output;
  for (const char* cmd : {"explore", "compare"}) {
    r = run(std::string(cmd) + " -q --world lab --stop-at-coverage 150 --out " + (dir / "o").string());
    EXPECT_NE(r.code, 0) << cmd;
    EXPECT_NE(r.output.find("--stop-at-coverage"), std::string::npos) << cmd << ": " << r.output;
  }
  EXPECT_FALSE(fs::exists(dir / "o" / "summary.json"));
}

TEST(DuetCli, CompareRunsBothProfilesAndPlotsThem) {
  const fs::path dir = temp_dir("compare");
  const fs::path world = write_file(dir, "room.yaml", kRoomWorld);
  const CliRun r = run("compare -q --world " + world.string() + " --seeds 1 --max-time 15 --out " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(fs::exists(dir / "out" / "compare.png"));
  EXPECT_TRUE(fs::exists(dir / "out" / "compare.csv"));
  const auto j = nlohmann::json::parse(std::ifstream(dir / "out" / "compare.json"));
  ASSERT_EQ(j["runs"].size(), 2u);
  EXPECT_EQ(j["runs"][0]["profile"], "dual_kinect_kobuki");
  EXPECT_EQ(j["runs"][1]["profile"], "single_kinect_kobuki");
  EXPECT_EQ(j["mean"]["dual"]["runs"], 1);
  EXPECT_EQ(j["mean"]["single"]["runs"], 1);
  EXPECT_EQ(j["world"], "room");
  EXPECT_TRUE(fs::exists(dir / "out" / "compare.md"));
}


// `duet run`: the robot loop on a source by name; the simulator is one source among others.
TEST(DuetCli, RunsTheLoopOnARobotSourceByName) {
  const fs::path dir = temp_dir("run");
  const fs::path world = write_file(dir, "room.yaml", kRoomWorld);
  const CliRun r = run("run -q --robot sim:" + world.string() + " --max-time 20 --out " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const fs::path out = dir / "out";
  for (const char* f : {"grid.yaml", "grid.pgm", "grid.png", "cloud.pcd", "summary.json"}) EXPECT_TRUE(fs::exists(out / f)) << f;
  const auto s = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(s["robot"], "sim:" + world.string());
  EXPECT_GT(s["time_s"].get<double>(), 5.0);
  EXPECT_LE(s["time_s"].get<double>(), 20.0 + 1e-6);
  EXPECT_GT(s["sets_integrated"].get<int>(), 5);
  EXPECT_GT(s["runtime"]["decision"]["count"].get<int>(), 0);
  EXPECT_GT(duet::read_map_server(out / "grid.yaml").known_cells(), 1000u);
  // An unknown source names the known ones; a bad world names the file.
  const CliRun bad = run("run -q --robot kobuki --max-time 1 --out " + (dir / "bad").string());
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.output.find("unknown robot source 'kobuki'"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("known: sim"), std::string::npos) << bad.output;
  const CliRun missing = run("run -q --robot sim:" + (dir / "nope.yaml").string() + " --max-time 1 --out " + (dir / "bad").string());
  EXPECT_NE(missing.code, 0);
  EXPECT_NE(missing.output.find("nope.yaml"), std::string::npos) << missing.output;
}

// `duet run --fault` (and a profile's faults:) injects the stream faults between the source and
// the runtime and reports what they did and what the input guard did; the faults that move the
// simulated world are refused with a pointer to `duet explore`.
TEST(DuetCli, RunInjectsStreamFaultsAndRefusesWorldFaults) {
  const fs::path dir = temp_dir("run_faults");
  const fs::path world = write_file(dir, "room.yaml", kRoomWorld);
  const CliRun r = run("run -q --robot sim:" + world.string() + " --max-time 20 --fault camera_stop:1@5+5 --fault stamp_duplicate:0@3+2" +
                       " --set 'faults=[\"depth_noise:2@8+2\"]' --out " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const auto s = nlohmann::json::parse(std::ifstream(dir / "out" / "summary.json"));
  ASSERT_EQ(s["faults"].size(), 3u) << s.dump();
  EXPECT_EQ(s["faults"][0]["spec"], "depth_noise:2@8+2");  // the profile's first
  EXPECT_EQ(s["faults"][1]["spec"], "camera_stop:1@5+5");
  for (const auto& f : s["faults"]) EXPECT_GT(f["injected"].get<int>(), 0) << f.dump();
  EXPECT_GT(s["input"]["odometry_out_of_order"].get<int>(), 0) << s["input"].dump();
  EXPECT_GT(s["input"]["sensor_silences"].get<int>() + s["input"]["sets_with_missing_frames"].get<int>(), 0) << s["input"].dump();
  EXPECT_GT(s["input"]["frames_garbled"].get<int>(), 0) << s["input"].dump();
  for (const char* world_fault : {"kidnap@5", "extrinsics:1@0"}) {
    const CliRun bad = run("run -q --robot sim:" + world.string() + " --max-time 5 --fault " + world_fault + " --out " + (dir / "bad").string());
    EXPECT_NE(bad.code, 0) << world_fault;
    EXPECT_NE(bad.output.find("duet explore --fault"), std::string::npos) << bad.output;
    EXPECT_FALSE(fs::exists(dir / "bad" / "summary.json"));
  }
}

namespace {

/// Starts `duet ARGS...` (output to log), waits until `ready` exists (the output folder: the
/// command has installed its stop handlers by then) and delay_ms more, sends `sig` and waits for
/// the exit.
/// Returns the exit status as waitpid() gives it; -1 if it did not stop within `limit_s`.
int run_and_signal(const std::vector<std::string>& args, const fs::path& ready, int sig, const fs::path& log, int delay_ms,
                   double limit_s = 600.0) {
  const pid_t pid = ::fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      ::dup2(fd, 1);
      ::dup2(fd, 2);
    }
    std::vector<char*> argv{const_cast<char*>(DUET_CLI)};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(DUET_CLI, argv.data());
    ::_exit(127);
  }
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  int status = 0;
  while (!fs::exists(ready) && elapsed() < limit_s) {
    if (::waitpid(pid, &status, WNOHANG) == pid) return status;  // ended early
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
  ::kill(pid, sig);
  while (elapsed() < limit_s) {
    if (::waitpid(pid, &status, WNOHANG) == pid) return status;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, &status, 0);
  return -1;
}

std::string slurp_text(const fs::path& p) {
  std::ifstream f(p);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

}  // namespace

TEST(DuetCli, SigintSavesTheExplorationSoFar) {
  const fs::path dir = temp_dir("sigint");
  const fs::path out = dir / "out";
  const int status = run_and_signal({"explore", "-q", "-j", "1", "--max-time", "3000", "--out", out.string()}, out, SIGINT, dir / "log.txt", 300);
  const std::string log = slurp_text(dir / "log.txt");
  ASSERT_TRUE(WIFEXITED(status)) << "status " << status << "\n" << log;
  EXPECT_EQ(WEXITSTATUS(status), 128 + SIGINT) << log;
  EXPECT_NE(log.find("SIGINT at t = "), std::string::npos) << log;
  EXPECT_NE(log.find("the run so far was saved"), std::string::npos) << log;
  for (const char* f : {"cloud.pcd", "cloud.ply", "grid.yaml", "grid.pgm", "grid.png", "trajectory.tum", "trajectory_true.tum",
                        "curve.csv", "curve.png", "log.json", "summary.json"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  const auto s = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(s["stop_reason"], "interrupted");
  EXPECT_NE(s["stop_detail"].get<std::string>().find("SIGINT"), std::string::npos);
  EXPECT_LT(s["sim_time_s"].get<double>(), 3000.0);
  EXPECT_GT(duet::read_map_server(out / "grid.yaml").known_cells(), 100u);
  EXPECT_GT(duet::read_pcd(out / "cloud.pcd").size(), 100u);
  // The trajectory has a pose per control period up to the stop.
  std::ifstream tum(out / "trajectory.tum");
  std::size_t lines = 0;
  for (std::string l; std::getline(tum, l);) lines += !l.empty() && l[0] != '#';
  EXPECT_GE(lines, static_cast<std::size_t>(s["sim_time_s"].get<double>() / 0.05 - 1.0));
  for (const auto& e : fs::directory_iterator(out)) EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos);
}

TEST(DuetCli, SigtermKeepsTheComparisonsFinishedRuns) {
  const fs::path dir = temp_dir("sigterm");
  const fs::path out = dir / "out";
  // The first run explores the room and stops by itself; SIGTERM as soon as its results are
  // written stops the second.
  const fs::path world = write_file(dir, "room.yaml", kRoomWorld);
  const int status = run_and_signal({"compare", "-q", "-j", "1", "--world", world.string(), "--profiles", "dual", "--seeds", "2",
                                     "--max-time", "3000", "--out", out.string()},
                                    out / "compare.json", SIGTERM, dir / "log.txt", 0);
  const std::string log = slurp_text(dir / "log.txt");
  ASSERT_TRUE(WIFEXITED(status)) << "status " << status << "\n" << log;
  EXPECT_EQ(WEXITSTATUS(status), 128 + SIGTERM) << log;
  const auto j = nlohmann::json::parse(std::ifstream(out / "compare.json"));
  ASSERT_TRUE(j.contains("interrupted")) << j.dump(1);
  EXPECT_NE(j["interrupted"].get<std::string>().find("SIGTERM"), std::string::npos);
  ASSERT_EQ(j["runs"].size(), 2u);  // the finished first run and the interrupted second one
  EXPECT_EQ(j["runs"][0]["stop_reason"], "explorer_done");
  EXPECT_EQ(j["runs"][1]["stop_reason"], "interrupted");
  EXPECT_EQ(j["mean"]["dual"]["runs"].get<int>(), 2);
  EXPECT_NE(slurp_text(out / "compare.csv").find("dual,dual,paper,2,"), std::string::npos);
}

TEST(DuetCli, SigintSavesTheRobotLoopsMapsSoFar) {
  const fs::path dir = temp_dir("sigint_run");
  const fs::path out = dir / "out";
  const int status =
      run_and_signal({"run", "-q", "-j", "1", "--robot", "sim:lab", "--max-time", "3000", "--out", out.string()}, out, SIGINT, dir / "log.txt", 1500);
  const std::string log = slurp_text(dir / "log.txt");
  ASSERT_TRUE(WIFEXITED(status)) << "status " << status << "\n" << log;
  EXPECT_EQ(WEXITSTATUS(status), 128 + SIGINT) << log;
  const auto s = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_TRUE(s["interrupted"].get<bool>());
  EXPECT_NE(s["stop_detail"].get<std::string>().find("SIGINT at t = "), std::string::npos) << s.dump(1);
  EXPECT_LT(s["time_s"].get<double>(), 3000.0);
  EXPECT_GT(duet::read_map_server(out / "grid.yaml").known_cells(), 100u);
  EXPECT_TRUE(fs::exists(out / "cloud.pcd"));
}

namespace {

std::string file_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(DuetReplay, AnExploreRecordingReplaysToTheSameMaps) {
  const fs::path d = temp_dir("replay-lab");
  const CliRun e = run("explore -s 4 -t 10 -q -o " + (d / "run").string() + " --record " + (d / "rec").string());
  ASSERT_EQ(e.code, 0) << e.output;
  const CliRun again = run("explore -s 4 -t 10 -q -o " + (d / "run2").string() + " --record " + (d / "rec").string());
  EXPECT_NE(again.code, 0) << again.output;  // a recording never overwrites another
  EXPECT_NE(again.output.find("empty or new folder"), std::string::npos) << again.output;
  const CliRun r = run("replay -q " + (d / "rec").string() + " -o " + (d / "replay").string());
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* f : {"grid.pgm", "grid.yaml", "cloud.pcd"})
    EXPECT_TRUE(file_bytes(d / "run" / f) == file_bytes(d / "replay" / f)) << f << " differs";
  const auto s = nlohmann::json::parse(std::ifstream(d / "replay" / "summary.json"));
  EXPECT_EQ(s["sets_integrated"].get<int>(), 11);
}

TEST(DuetReplay, AFolderThatIsNeitherIsAnError) {
  const fs::path d = temp_dir("replay-nothing");
  const CliRun r = run("replay -q " + d.string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("neither a duet recording"), std::string::npos) << r.output;
}

}  // namespace

// Several worlds: a row per world and variant, the means over the worlds (each world weighs the
// same), the T_90 ratio, one plot per world; a world named twice or missing is an error.
TEST(DuetCli, CompareAcrossWorldsTabulatesEachAndTheirMean) {
  const fs::path dir = temp_dir("compare_worlds");
  const fs::path a = write_file(dir, "room.yaml", kRoomWorld);
  std::string other = kRoomWorld;
  other.replace(other.find("name: room"), 10, "name: hall");
  other.replace(other.find("[4.2, 3.2]"), 10, "[5.2, 3.2]");
  other.replace(other.find("[4.15, 0.05], [4.15, 3.15]"), 26, "[5.15, 0.05], [5.15, 3.15]");
  const fs::path b = write_file(dir, "hall.yaml", other);
  const CliRun r = run("compare -q --world " + a.string() + "," + b.string() + " --profiles dual --strategies paper,nearest_frontier --seeds 1 --max-time 40 --out " +
                       (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const auto j = nlohmann::json::parse(std::ifstream(dir / "out" / "compare.json"));
  ASSERT_EQ(j["runs"].size(), 4u);
  EXPECT_EQ(j["worlds"], nlohmann::json::array({"room", "hall"}));
  EXPECT_TRUE(j["world"].is_null());
  for (const char* w : {"room", "hall"})
    for (const char* v : {"paper", "nearest_frontier"}) EXPECT_EQ(j["per_world"][w][v]["runs"], 1) << w << " " << v;
  const double mean_cov = j["mean_over_worlds"]["paper"]["coverage"].get<double>();
  EXPECT_NEAR(mean_cov, 0.5 * (j["per_world"]["room"]["paper"]["coverage"].get<double>() + j["per_world"]["hall"]["paper"]["coverage"].get<double>()), 1e-12);
  EXPECT_EQ(j["mean_over_worlds"]["paper"]["worlds"], 2);
  ASSERT_TRUE(j.contains("t90_ratio"));
  EXPECT_TRUE(j["t90_ratio"].contains("nearest_frontier / paper"));
  for (const char* f : {"compare_room.png", "compare_hall.png", "compare.csv", "compare.md"}) EXPECT_TRUE(fs::exists(dir / "out" / f)) << f;
  const std::string md = slurp_text(dir / "out" / "compare.md");
  EXPECT_NE(md.find("| room | paper |"), std::string::npos) << md;
  EXPECT_NE(md.find("| hall | nearest_frontier |"), std::string::npos) << md;
  EXPECT_NE(md.find("mean over 2 worlds"), std::string::npos) << md;
  EXPECT_NE(slurp_text(dir / "out" / "compare.csv").find("hall,nearest_frontier,dual,nearest_frontier,1,"), std::string::npos);
  CliRun bad = run("compare -q --world " + a.string() + "," + a.string() + " --seeds 1 --max-time 5 --out " + (dir / "o2").string());
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.output.find("names room twice"), std::string::npos) << bad.output;
  bad = run("compare -q --world " + a.string() + "," + (dir / "none.yaml").string() + " --seeds 1 --max-time 5 --out " + (dir / "o3").string());
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.output.find("none.yaml"), std::string::npos) << bad.output;
  EXPECT_FALSE(fs::exists(dir / "o3" / "compare.json"));
}
