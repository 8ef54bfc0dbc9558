// Fault injection (issue 19, part 3): fault specs, the stream faults of FaultInjector on a
// scripted source, the runtime's input guard (what it drops, absorbs, restarts), and fault
// scenarios on short simulated runs: each fault acts, the runtime reacts as documented, the run
// goes on without a collision.
#include <duet/kernels/error.hpp>
#include <duet/runtime/robot/faults.hpp>
#include <duet/runtime/robot/input_guard.hpp>
#include <duet/sim/sim_explore.hpp>

#include <gtest/gtest.h>

#include "scripted_robot.hpp"

#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace {

using duet::Fault;
using duet::FaultKind;

// ---- specs ---------------------------------------------------------------------------------------

TEST(FaultSpec, ParsesKindsSensorsTimesAndAmounts) {
  const Fault a = duet::parse_fault("camera_stop:1@60+10", 2);
  EXPECT_EQ(a.kind, FaultKind::kCameraStop);
  EXPECT_EQ(a.sensor, 1);
  EXPECT_EQ(a.start_s, 60.0);
  EXPECT_EQ(a.duration_s, 10.0);
  EXPECT_TRUE(a.active(60.0));
  EXPECT_TRUE(a.active(69.99));
  EXPECT_FALSE(a.active(70.0));
  EXPECT_FALSE(a.active(59.0));
  const Fault b = duet::parse_fault("extrinsics:2@0", 2);
  EXPECT_EQ(b.amount, 2.0);  // the default
  EXPECT_TRUE(std::isinf(b.duration_s));
  EXPECT_TRUE(b.active(1e5));
  EXPECT_EQ(duet::parse_fault("wheel_slip@5+2=1.3", 2).amount, 1.3);
  EXPECT_EQ(duet::parse_fault("stamp_late:0@1+2=0.25", 1).sensor, 0);
  EXPECT_EQ(duet::parse_fault("kidnap@30=-0.4", 1).amount, -0.4);
  EXPECT_EQ(std::string(duet::to_string(duet::parse_fault("clock_back@3", 1).kind)), "clock_back");
}

TEST(FaultSpec, BadSpecsNameTheSpecAndTheProblem) {
  const auto bad = [](const char* spec, std::size_t sensors, const char* needle) {
    try {
      (void)duet::parse_fault(spec, sensors);
      ADD_FAILURE() << spec << " was accepted";
    } catch (const duet::Error& e) {
      const std::string m = e.what();
      EXPECT_EQ(e.code(), duet::ErrorCode::kInvalidArgument);
      EXPECT_NE(m.find(spec), std::string::npos) << m;
      EXPECT_NE(m.find(needle), std::string::npos) << m;
    }
  };
  bad("camera_stop:1", 2, "expected KIND");
  bad("camera_fail:1@3", 2, "known: camera_stop");
  bad("camera_stop:3@3", 2, "sensor must be 1..2");
  bad("camera_stop@3", 2, "needs a sensor");
  bad("wheel_slip:1@3", 2, "takes no sensor");
  bad("stamp_late@3", 2, "needs a stream");
  bad("odom_jump@3+2", 2, "no duration");
  bad("camera_stop:1@3=2", 2, "takes no amount");
  bad("extrinsics:1@3=90", 2, "amount must be in");
  bad("camera_stop:1@-3", 2, "start must be");
  bad("camera_stop:1@nan", 2, "not a finite number");
  bad("camera_stop:1@3+0", 2, "duration must be > 0");
  bad("camera_stop:1.5@3", 2, "sensor must be");
}

TEST(FaultSpec, TheProfileCarriesFaultsAndNamesABadOne) {
  const std::string base = duet::to_yaml(duet::builtin_profile("dual"));
  const duet::Profile p = duet::parse_profile(base + "faults: [\"camera_stop:2@10+5\", \"kidnap@20\"]\n", "f.yaml");
  ASSERT_EQ(p.faults.size(), 2u);
  EXPECT_EQ(p.faults[1], "kidnap@20");
  EXPECT_EQ(duet::parse_profile(duet::to_yaml(p), "again.yaml").faults, p.faults);  // written and read back
  try {
    (void)duet::parse_profile(base + "faults: [\"kidnap@20\", \"camera_stop:5@1\"]\n", "f.yaml");
    ADD_FAILURE() << "a fault for sensor 5 of 2 was accepted";
  } catch (const duet::Error& e) {
    EXPECT_NE(std::string(e.what()).find("faults[1]"), std::string::npos) << e.what();
  }
}

// ---- the injector on a scripted source -----------------------------------------------------------

// A source driving straight along x at 0.4 m/s: odometry at 50 Hz, one frame per sensor per second.
struct StraightSource : duet::RobotSource {
  duet::Profile profile = duet::builtin_profile("dual");
  duet_test::ScriptedChassis chassis_;
  duet_test::ScriptedSensor s1, s2;
  duet::RgbdSensorInterface* ifaces[2] = {&s1, &s2};
  double t = 0.0;
  duet::ChassisInterface& chassis() override { return chassis_; }
  std::span<duet::RgbdSensorInterface* const> sensors() override { return ifaces; }
  void advance(double now_s) override {
    for (; t + 0.02 <= now_s + 1e-9;) {
      t += 0.02;
      const double k = std::round(t / 0.02) * 0.02;
      chassis_.pending.push_back({k, {static_cast<float>(0.4 * k), 0.0f, 0.0f}, {0.4f, 0.0f}});
      if (std::fabs(k - std::round(k)) < 1e-6) {
        auto f1 = duet_test::wall_frame(profile.sensors[0], k);
        f1.image.rgb.assign(f1.image.depth.size() * 3, 200);
        s1.pending.push_back(std::move(f1));
        s2.pending.push_back(duet_test::wall_frame(profile.sensors[1], k));
      }
    }
  }
};

struct Taken {
  std::vector<duet::OdometryMsg> odom;
  std::vector<duet::StampedRgbd> f1, f2;
};

Taken drive(const std::vector<std::string>& specs, double until) {
  StraightSource src;
  duet::FaultInjector inj(src, duet::parse_faults(specs, 2), 7);
  Taken out;
  for (double t = 0.05; t <= until + 1e-9; t += 0.05) {
    inj.advance(t);
    for (auto& m : inj.chassis().take_odometry()) out.odom.push_back(m);
    for (auto& f : inj.sensors()[0]->take_frames()) out.f1.push_back(std::move(f));
    for (auto& f : inj.sensors()[1]->take_frames()) out.f2.push_back(std::move(f));
  }
  return out;
}

TEST(FaultInjector, WithoutFaultsEverythingPassesUnchanged) {
  const Taken t = drive({}, 5.0);
  ASSERT_EQ(t.odom.size(), 250u);
  EXPECT_EQ(t.f1.size(), 5u);
  EXPECT_NEAR(t.odom.back().pose.x, 2.0f, 1e-4f);
  EXPECT_EQ(t.odom.back().stamp_s, 5.0);
}

TEST(FaultInjector, SensorFaultsActInTheirWindowOnly) {
  const Taken stop = drive({"camera_stop:1@2+2"}, 6.0);
  std::vector<double> stamps;
  for (const auto& f : stop.f1) stamps.push_back(f.stamp_s);
  EXPECT_EQ(stamps, (std::vector<double>{1, 4, 5, 6}));  // 2 and 3 dropped; the window ends before 4
  EXPECT_EQ(stop.f2.size(), 6u);
  const Taken zero = drive({"depth_zero:2@2+1", "color_black:1@3+1", "depth_noise:1@5+1"}, 6.0);
  for (const auto& f : zero.f2) {
    const bool all_zero = std::all_of(f.image.depth.begin(), f.image.depth.end(), [](std::uint16_t d) { return d == 0; });
    EXPECT_EQ(all_zero, f.stamp_s == 2.0) << f.stamp_s;
  }
  for (const auto& f : zero.f1) {
    const bool black = std::all_of(f.image.rgb.begin(), f.image.rgb.end(), [](std::uint8_t c) { return c == 0; });
    EXPECT_EQ(black, f.stamp_s == 3.0) << f.stamp_s;
    const bool wall = std::all_of(f.image.depth.begin(), f.image.depth.end(), [](std::uint16_t d) { return d == 2000; });
    EXPECT_EQ(wall, f.stamp_s != 5.0) << f.stamp_s;  // noise at 5
  }
}

TEST(FaultInjector, OdometryFaultsSlipJumpAndStepTheClockBack) {
  const Taken slip = drive({"wheel_slip@1+1=2"}, 3.0);
  EXPECT_NEAR(slip.odom.back().pose.x, 1.2f + 0.4f, 1e-3f);  // the second metre of... 0.4 m reported twice
  EXPECT_EQ(slip.odom.back().pose.theta, 0.0f);
  const Taken jump = drive({"odom_jump@2=0.5"}, 3.0);
  for (const auto& m : jump.odom) EXPECT_NEAR(m.pose.x, 0.4 * m.stamp_s + (m.stamp_s >= 2.0 ? 0.5 : 0.0), 1e-3) << m.stamp_s;
  const Taken back = drive({"clock_back@2=1"}, 3.0);
  int steps_back = 0;
  for (std::size_t i = 1; i < back.odom.size(); ++i) {
    const double d = back.odom[i].stamp_s - back.odom[i - 1].stamp_s;
    if (d < 0.0) {
      ++steps_back;
      EXPECT_NEAR(d, -0.98, 1e-6) << i;  // 1.98 -> 2.00 - 1
    } else {
      EXPECT_NEAR(d, 0.02, 1e-6) << i;
    }
  }
  EXPECT_EQ(steps_back, 1);
}

TEST(FaultInjector, StampFaultsReorderDuplicateAndDelay) {
  const Taken dis = drive({"stamp_disorder:0@1+0.1"}, 2.0);
  int behind = 0;
  for (std::size_t i = 1; i < dis.odom.size(); ++i) behind += dis.odom[i].stamp_s < dis.odom[i - 1].stamp_s ? 1 : 0;
  EXPECT_GE(behind, 1);
  EXPECT_EQ(dis.odom.size(), 100u);  // nothing lost
  const Taken dup = drive({"stamp_duplicate:2@1+2"}, 4.0);
  EXPECT_EQ(dup.f2.size(), 6u);  // frames 1 and 2 twice
  const Taken late = drive({"stamp_late:1@1+2=0.5"}, 4.0);
  ASSERT_EQ(late.f1.size(), 4u);
  for (const auto& f : late.f1) EXPECT_EQ(std::fmod(f.stamp_s, 1.0), 0.0);  // stamps unchanged
}

// ---- the input guard -----------------------------------------------------------------------------

struct Guard {
  duet::Profile profile = duet::builtin_profile("dual");
  duet::InputGuard g{profile, 1.0};
  duet::InputGuard::Verdict odom(double t, float x) {
    duet::OdometryMsg m{t, {x, 0.0f, 0.0f}, {0.4f, 0.0f}};
    return g.odometry(m, t);
  }
};

TEST(InputGuard, DropsBadAndOutOfOrderOdometryAndRestartsOnAClockStep) {
  using V = duet::InputGuard::Verdict;
  Guard s;
  EXPECT_EQ(s.odom(1.0, 0.0f), V::kAccept);
  EXPECT_EQ(s.odom(1.02, 0.008f), V::kAccept);
  EXPECT_EQ(s.odom(std::nan(""), 0.0f), V::kDrop);
  EXPECT_EQ(s.odom(1.04, std::nanf("")), V::kDrop);
  EXPECT_EQ(s.odom(1.02, 0.008f), V::kDrop);  // repeated
  EXPECT_EQ(s.odom(1.04, 0.016f), V::kAccept);
  EXPECT_EQ(s.odom(1.03, 0.012f), V::kDrop);  // one behind: out of order
  EXPECT_EQ(s.odom(1.06, 0.024f), V::kAccept);
  EXPECT_EQ(s.g.stats().odometry_invalid, 2u);
  EXPECT_EQ(s.g.stats().odometry_out_of_order, 2u);
  // The clock steps back 1 s: three in a row behind, in order, are a new time base.
  EXPECT_EQ(s.odom(0.08, 0.032f), V::kDrop);
  EXPECT_EQ(s.odom(0.10, 0.040f), V::kDrop);
  EXPECT_EQ(s.odom(0.12, 0.048f), V::kRestart);
  EXPECT_EQ(s.g.stats().clock_restarts, 1u);
  EXPECT_EQ(s.odom(0.12, 0.048f), V::kAccept);  // passed again after the restart
  EXPECT_EQ(s.odom(0.14, 0.056f), V::kAccept);
  EXPECT_FALSE(s.g.events().empty());
}

TEST(InputGuard, AbsorbsAnOdometryJumpSoThePoseContinues) {
  Guard s;
  duet::OdometryMsg m{1.0, {0.0f, 0.0f, 0.0f}, {}};
  ASSERT_EQ(s.g.odometry(m, 1.0), duet::InputGuard::Verdict::kAccept);
  m = {1.02, {0.01f, 0.0f, 0.0f}, {}};
  (void)s.g.odometry(m, 1.02);
  m = {1.04, {0.52f, 0.0f, 0.0f}, {}};  // 0.51 m in 20 ms
  ASSERT_EQ(s.g.odometry(m, 1.04), duet::InputGuard::Verdict::kAccept);
  EXPECT_NEAR(m.pose.x, 0.01f, 1e-5f);  // continues the last pose
  m = {1.06, {0.53f, 0.0f, 0.0f}, {}};
  (void)s.g.odometry(m, 1.06);
  EXPECT_NEAR(m.pose.x, 0.02f, 1e-5f);  // and then follows the odometry's motion
  EXPECT_EQ(s.g.stats().odometry_jumps, 1u);
  // A fast but possible step (0.7 m/s top speed, factor 2: 28 mm + 50 mm in 20 ms) is motion.
  m = {1.08, {0.59f, 0.0f, 0.0f}, {}};
  (void)s.g.odometry(m, 1.08);
  EXPECT_NEAR(m.pose.x, 0.08f, 1e-5f);
  EXPECT_EQ(s.g.stats().odometry_jumps, 1u);
}

TEST(InputGuard, TellsGarbledFromEmptyFromRealFramesAndFindsASilentSensor) {
  Guard s;
  const duet::SensorProfile& sp = s.profile.sensors[0];
  bool missing = false;
  auto wall = duet_test::wall_frame(sp, 1.0);  // a real (smooth) scene
  for (std::size_t k = 0; k < wall.image.depth.size(); ++k) wall.image.depth[k] = static_cast<std::uint16_t>(1500 + (k % 640));
  EXPECT_EQ(s.g.frame(0, wall, 1.0, missing), duet::InputGuard::Verdict::kAccept);
  EXPECT_FALSE(missing);
  auto noise = duet_test::wall_frame(sp, 2.0);
  std::mt19937 rng(3);
  for (auto& d : noise.image.depth) d = static_cast<std::uint16_t>(rng() & 0xFFFF);
  EXPECT_EQ(s.g.frame(0, noise, 2.0, missing), duet::InputGuard::Verdict::kAccept);
  EXPECT_TRUE(missing);
  auto zero = duet_test::wall_frame(sp, 3.0);
  std::fill(zero.image.depth.begin(), zero.image.depth.end(), std::uint16_t{0});
  EXPECT_EQ(s.g.frame(0, zero, 3.0, missing), duet::InputGuard::Verdict::kAccept);
  EXPECT_FALSE(missing);
  EXPECT_EQ(s.g.stats().frames_garbled, 1u);
  EXPECT_EQ(s.g.stats().frames_empty, 1u);
  auto small = duet_test::wall_frame(sp, 4.0);
  small.image.width = 10;
  EXPECT_EQ(s.g.frame(0, small, 4.0, missing), duet::InputGuard::Verdict::kDrop);
  EXPECT_EQ(s.g.frame(0, duet_test::wall_frame(sp, 3.0), 4.0, missing), duet::InputGuard::Verdict::kDrop);  // repeated stamp
  // Sensor 2 never spoke: after 2.5 frame periods of sensor 1 it is silent and gets missing frames.
  EXPECT_TRUE(s.g.silent_sensors(0, 3.0, 3.0).empty());
  EXPECT_EQ(s.g.silent_sensors(0, 4.0, 4.0), (std::vector<std::size_t>{1}));
  EXPECT_EQ(s.g.stats().sensor_silences, 1u);
  // It speaks again: no more missing frames.
  EXPECT_EQ(s.g.frame(1, duet_test::wall_frame(s.profile.sensors[1], 5.0), 5.0, missing), duet::InputGuard::Verdict::kAccept);
  EXPECT_TRUE(s.g.silent_sensors(0, 5.0, 5.0).empty());
}

// ---- scenarios on short runs ---------------------------------------------------------------------

duet::sim::ExploreSummary run_lab(const std::vector<std::string>& faults, double max_time) {
  duet::sim::ExploreSettings s;
  s.seed = 1;
  s.max_time_s = max_time;
  s.faults = faults;
  duet::sim::SimExplore run(duet::sim::resolve_world("lab"), duet::builtin_profile("dual"), s);
  run.run();
  return run.summary();
}

TEST(FaultScenarios, ACameraThatStopsIsMappedAroundAndNothingCollides) {
  const auto s = run_lab({"camera_stop:1@15+10"}, 45.0);
  ASSERT_EQ(s.faults.size(), 1u);
  EXPECT_GT(s.faults[0].injected, 5u);
  EXPECT_EQ(s.input.sensor_silences, 1u);
  EXPECT_GT(s.sets_with_missing, 3u);  // mapped with sensor 2 alone meanwhile
  EXPECT_EQ(s.collisions, 0u);
  EXPECT_GE(s.occupied_on_obstacles, 0.95);
}

TEST(FaultScenarios, GarbledDepthIsNotMapped) {
  const auto s = run_lab({"depth_noise:2@10+10"}, 30.0);
  EXPECT_GT(s.faults[0].injected, 5u);
  EXPECT_EQ(s.input.frames_garbled, s.faults[0].injected);
  EXPECT_GE(s.occupied_on_obstacles, 0.95);
  EXPECT_EQ(s.collisions, 0u);
}

TEST(FaultScenarios, AKidnappedRobotRelocalises) {
  const auto s = run_lab({"kidnap@20"}, 40.0);
  EXPECT_EQ(s.faults[0].injected, 1u);
  EXPECT_GE(s.relocalizations, 1u);
  EXPECT_LT(s.pose_error_m, 0.15);  // 0.5 m off without the wide re-match
  EXPECT_EQ(s.collisions, 0u);
}

TEST(FaultScenarios, OdometryJumpsAndClockStepsAreAbsorbed) {
  const auto s = run_lab({"odom_jump@10", "clock_back@20", "stamp_duplicate:0@25+2"}, 35.0);
  EXPECT_EQ(s.input.odometry_jumps, 1u);
  EXPECT_EQ(s.input.clock_restarts, 1u);
  EXPECT_GE(s.input.odometry_out_of_order, 100u);  // the duplicates
  EXPECT_LT(s.pose_error_max_m, 0.15);
  EXPECT_EQ(s.collisions, 0u);
}

}  // namespace
