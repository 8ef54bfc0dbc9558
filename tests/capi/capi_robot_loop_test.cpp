// bindings_c/examples/robot_loop.c - the robot program on duet.h alone - run as a user would:
// it explores the lab and, in lockstep, drives exactly the trajectory the C++ simulator run
// (what `duet explore` runs) drives for the same seed.
#include <duet/runtime/config/profile.hpp>
#include <duet/sim/sim_explore.hpp>
#include <duet/sim/world.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

std::string run(const std::string& command, int& status) {
  std::string out;
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (p == nullptr) return out;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  status = pclose(p);
  return out;
}

double value_after(const std::string& text, const std::string& key) {
  const auto at = text.find(key);
  return at == std::string::npos ? std::nan("") : std::atof(text.c_str() + at + key.size());
}

TEST(CapiRobotLoop, ExploresTheLabExactlyAsTheSimulatorRun) {
  const double seconds = 40.0;
  const auto dir = std::filesystem::temp_directory_path() / ("duet_robot_loop_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  int status = -1;
  const std::string out = run("ROBOT_LOOP_QUIET=1 " DUET_ROBOT_LOOP " lab 1 " + std::to_string(seconds) + " " + dir.string(), status);
  ASSERT_EQ(status, 0) << out;
  EXPECT_EQ(out.find("DUET_ERROR"), std::string::npos) << out;
  EXPECT_EQ(value_after(out, "collisions: "), 0.0) << out;
  EXPECT_GT(value_after(out, "coverage: "), 0.1) << out;  // ~0.20 of the lab after its first 40 s

  // The same run in C++ (SimExplore: the simulator and the runtime in process, as duet explore -
  // with the profile's runtime settings, as duet explore and the C API take them).
  const duet::Profile profile = duet::builtin_profile("dual");
  duet::sim::ExploreSettings s;
  s.runtime = profile.runtime;
  s.seed = 1;
  s.max_time_s = seconds;
  duet::sim::SimExplore sim(duet::sim::builtin_world("lab"), profile, s);
  sim.run();
  EXPECT_NEAR(value_after(out, "coverage: "), sim.summary().coverage, 5e-5) << out;
  std::vector<std::string> expected;
  char line[256];
  const auto& traj = sim.estimated_trajectory();
  for (std::size_t i = 1; i < traj.size(); ++i) {  // the C++ run also records the start at t = 0
    const double h = 0.5 * traj[i].pose.theta;
    std::snprintf(line, sizeof line, "%.3f %.4f %.4f 0 0 0 %.6f %.6f", traj[i].t_s, static_cast<double>(traj[i].pose.x),
                  static_cast<double>(traj[i].pose.y), std::sin(h), std::cos(h));
    expected.emplace_back(line);
  }
  std::ifstream tum(dir / "trajectory.tum");
  std::vector<std::string> got;
  for (std::string l; std::getline(tum, l);)
    if (!l.empty() && l[0] != '#') got.push_back(l);
  ASSERT_EQ(got.size(), expected.size());
  for (std::size_t i = 0; i < got.size(); ++i) ASSERT_EQ(got[i], expected[i]) << "control period " << i;
  std::filesystem::remove_all(dir);
}

TEST(CapiRobotLoop, ABadWorldIsAnErrorMessage) {
  int status = -1;
  const std::string out = run("ROBOT_LOOP_QUIET=1 " DUET_ROBOT_LOOP " /nonexistent/world.yaml 1 10", status);
  EXPECT_NE(status, 0);
  EXPECT_NE(out.find("/nonexistent/world.yaml"), std::string::npos) << out;
}

}  // namespace
