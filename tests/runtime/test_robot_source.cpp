// Robot sources by name (robot/robot_source.hpp) and the loop on any source (robot_loop.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/robot/robot_loop.hpp>
#include <duet/runtime/robot/robot_source.hpp>
#include <duet/sim/sim_robot.hpp>

#include <gtest/gtest.h>

#include "runtime_test_util.hpp"

#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace {

/// A robot that never moves and whose sensors see nothing: what a source must provide, no more.
class StillRobot final : public duet::RobotSource {
 public:
  explicit StillRobot(std::size_t sensors, std::string argument) : argument_(std::move(argument)) {
    for (std::size_t i = 0; i < sensors; ++i) {
      sensors_.push_back(std::make_unique<Blind>());
      ifaces_.push_back(sensors_.back().get());
    }
  }
  duet::ChassisInterface& chassis() override { return chassis_; }
  std::span<duet::RgbdSensorInterface* const> sensors() override { return ifaces_; }
  void advance(double now_s) override { advanced_to = now_s; }
  double advanced_to = -1.0;
  std::string argument_;

 private:
  struct Chassis final : duet::ChassisInterface {
    void command(const duet::Twist&) override {}
    std::vector<duet::OdometryMsg> take_odometry() override { return {}; }
  } chassis_;
  struct Blind final : duet::RgbdSensorInterface {
    std::vector<duet::StampedRgbd> take_frames() override { return {}; }
  };
  std::vector<std::unique_ptr<Blind>> sensors_;
  std::vector<duet::RgbdSensorInterface*> ifaces_;
};

duet::RobotSourceKind still_kind(std::size_t sensors) {
  return {"still", "a robot that never moves", [sensors](const duet::Profile&, const duet::RobotSourceRequest& r) {
            return std::unique_ptr<duet::RobotSource>(std::make_unique<StillRobot>(sensors, r.argument));
          }};
}

using duet_test::error_of;

}  // namespace

TEST(RobotSource, RegistryMakesSourcesBySpec) {
  const duet::Profile p = duet::builtin_profile("dual");
  duet::RobotSourceRegistry r;
  r.add(still_kind(p.sensors.size()));
  auto plain = r.make("still", p);
  ASSERT_TRUE(plain);
  EXPECT_EQ(static_cast<StillRobot&>(*plain).argument_, "");
  auto with_arg = r.make("still:a:b", p);  // the argument is everything after the first colon
  EXPECT_EQ(static_cast<StillRobot&>(*with_arg).argument_, "a:b");
  EXPECT_EQ(with_arg->sensors().size(), p.sensors.size());
}

TEST(RobotSource, BadNamesAndSpecsAreNamed) {
  const duet::Profile p = duet::builtin_profile("dual");
  duet::RobotSourceRegistry r;
  r.add(still_kind(p.sensors.size()));
  EXPECT_NE(error_of([&] { r.add(still_kind(2)); }).find("registered twice"), std::string::npos);
  auto bad_name = still_kind(2);
  bad_name.name = "Still Robot";
  EXPECT_NE(error_of([&] { r.add(bad_name); }).find("'Still Robot'"), std::string::npos);
  auto no_factory = still_kind(2);
  no_factory.name = "none";
  no_factory.make = nullptr;
  EXPECT_NE(error_of([&] { r.add(no_factory); }).find("no factory"), std::string::npos);
  const std::string unknown = error_of([&] { (void)r.make("kobuki:/dev/ttyUSB0", p); });
  EXPECT_NE(unknown.find("unknown robot source 'kobuki'"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("known: still"), std::string::npos) << unknown;
  // A source with another number of sensors than the profile is refused.
  duet::RobotSourceRegistry one;
  one.add(still_kind(1));
  EXPECT_NE(error_of([&] { (void)one.make("still", p); }).find("has 1 sensors"), std::string::npos);
}

// The loop on a source: advance(t), then the runtime's tick, every control period until the
// time limit; a robot that sees nothing never gets a map and never moves, and the loop ends.
TEST(RobotSource, LoopAdvancesTheSourceEveryPeriod) {
  const duet::Profile p = duet::builtin_profile("dual");
  StillRobot robot(p.sensors.size(), "");
  duet::ExplorationRuntime runtime(p, robot.chassis(), robot.sensors());
  duet::RobotRunSettings rs;
  rs.max_time_s = 2.0;
  int periods = 0;
  const duet::RobotRunResult r = duet::run_robot(robot, runtime, rs, [&](double) { return ++periods < 1000; });
  EXPECT_NEAR(r.time_s, 2.0, 1e-9);
  EXPECT_NEAR(robot.advanced_to, 2.0, 1e-9);
  EXPECT_EQ(periods, 40);  // 20 Hz
  EXPECT_FALSE(r.done);
  EXPECT_EQ(r.stats.sets_integrated, 0u);
  // The caller may stop it.
  const duet::RobotRunResult stopped = duet::run_robot(robot, runtime, rs, [](double t) { return t < 0.5; });
  EXPECT_NEAR(stopped.time_s, 0.5, 1e-9);
  rs.max_time_s = 0.0;
  EXPECT_THROW((void)duet::run_robot(robot, runtime, rs), duet::Error);
}

// The simulator as a source: the loop maps the lab and the robot moves.
TEST(RobotSource, SimulatorSourceExploresThroughTheLoop) {
  duet::Profile p = duet::builtin_profile("dual");
  duet::RobotSourceRegistry r;
  r.add(duet::sim::sim_robot_source());
  auto source = r.make("sim:lab", p, 3);
  const auto& chassis = static_cast<duet::sim::SimRobot&>(*source).sim_chassis();
  const duet::Pose2 start = chassis.true_pose();
  duet::ExplorationRuntime runtime(p, source->chassis(), source->sensors());
  duet::RobotRunSettings rs;
  rs.max_time_s = 20.0;
  const duet::RobotRunResult res = duet::run_robot(*source, runtime, rs);
  EXPECT_GT(res.stats.sets_integrated, 15u);  // 1 Hz map updates
  EXPECT_GT(runtime.map_grid().known_cells(), 3000u);
  const duet::Pose2 end = chassis.true_pose();
  EXPECT_GT(std::hypot(end.x - start.x, end.y - start.y) + std::abs(end.theta - start.theta), 0.3f);
  EXPECT_EQ(chassis.collisions(), 0u);
  EXPECT_NE(error_of([&] { (void)r.make("sim:no_such_world", p); }), "");
}
