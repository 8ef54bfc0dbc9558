// Simulated chassis: paper Eq. (4) in closed form with slip and noise off, the velocity and
// acceleration limits, odometry equal to the truth without errors and drifting with them as the
// slip model predicts, determinism, odometry at 50 Hz, collisions with a wall (stop, one count,
// outside the wall, backing out) and invalid settings.
#include <duet/kernels/error.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/sim/chassis.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace test_sim_chassis {

using duet::Pose2;
using duet::Twist;
using duet::sim::ChassisBody;
using duet::sim::ChassisSimSettings;
using duet::sim::OdometryMsg;
using duet::sim::SimChassis;
using duet::sim::World;

namespace {

constexpr double kPi = 3.14159265358979323846;

std::shared_ptr<const World> open_world(float half = 20.0f) {
  World w;
  w.name = "open";
  w.floor.min = {-half, -half};
  w.floor.max = {half, half};
  duet::sim::validate(w);
  return std::make_shared<const World>(std::move(w));
}

// A wall x in [1.0, 1.2], y in [-2, 2], 2.5 m high, in a 10 x 10 m room.
std::shared_ptr<const World> wall_world() {
  World w;
  w.name = "wall";
  w.floor.min = {-5.0f, -5.0f};
  w.floor.max = {5.0f, 5.0f};
  duet::sim::Solid wall;
  wall.name = "wall";
  wall.polygon = {{1.0f, -2.0f}, {1.2f, -2.0f}, {1.2f, 2.0f}, {1.0f, 2.0f}};
  wall.z_min_m = 0.0f;
  wall.z_max_m = 2.5f;
  w.solids.push_back(wall);
  duet::sim::validate(w);
  return std::make_shared<const World>(std::move(w));
}

// No slip, no bias, no encoder noise.
ChassisSimSettings ideal() {
  ChassisSimSettings s;
  s.wheel_slip_std = 0.0f;
  s.wheel_base_bias = 0.0f;
  s.encoder_noise_m = 0.0f;
  return s;
}

// Eq. (4) for a constant twist from p over t, in double precision.
Pose2 closed_form(const Pose2& p, double v, double w, double t) {
  const double th = p.theta;
  if (w == 0.0) return {static_cast<float>(p.x + v * t * std::cos(th)), static_cast<float>(p.y + v * t * std::sin(th)), p.theta};
  return {static_cast<float>(p.x - v / w * std::sin(th) + v / w * std::sin(th + w * t)),
          static_cast<float>(p.y + v / w * std::cos(th) - v / w * std::cos(th + w * t)),
          static_cast<float>(std::remainder(th + w * t, 2.0 * kPi))};
}

void expect_pose_near(const Pose2& a, const Pose2& b, double tol, const std::string& what = "") {
  EXPECT_NEAR(a.x, b.x, tol) << what;
  EXPECT_NEAR(a.y, b.y, tol) << what;
  EXPECT_NEAR(std::remainder(static_cast<double>(a.theta) - b.theta, 2.0 * kPi), 0.0, tol) << what;
}

void expect_invalid(auto&& f, const std::string& part) {
  try {
    f();
    ADD_FAILURE() << "no error, expected one naming " << part;
  } catch (const duet::Error& e) {
    EXPECT_EQ(e.code(), duet::ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(SimChassis, StraightDriveAndTurnMatchEq4InClosedForm) {
  ChassisSimSettings s = ideal();
  s.max_linear_accel_mps2 = 1e4f;  // full speed within the first step: no ramp to account for
  s.max_angular_accel_radps2 = 1e4f;
  {
    SimChassis c(open_world(), s, Pose2{0.0f, 0.0f, 0.0f});
    c.command({0.5f, 0.0f});
    c.advance(2.0);
    expect_pose_near(c.true_pose(), {1.0f, 0.0f, 0.0f}, 1e-4, "straight");
    expect_pose_near(c.odometry_pose(), c.true_pose(), 1e-6, "odometry");
    EXPECT_NEAR(c.true_twist().v, 0.5f, 1e-6);
  }
  {
    const Pose2 start{1.0f, 2.0f, 0.3f};
    SimChassis c(open_world(), s, start);
    c.command({0.3f, 0.5f});
    c.advance(3.0);
    expect_pose_near(c.true_pose(), closed_form(start, 0.3, 0.5, 3.0), 1e-4, "arc");
    c.command({0.0f, -1.0f});  // turn in place
    const Pose2 before = c.true_pose();
    c.advance(1.0);
    expect_pose_near(c.true_pose(), {before.x, before.y, before.theta - 1.0f}, 1e-4, "in place");
    // Reverse along a heading of 135 deg.
    SimChassis r(open_world(), s, Pose2{0.0f, 0.0f, static_cast<float>(0.75 * kPi)});
    r.command({-0.4f, 0.0f});
    r.advance(2.5);
    expect_pose_near(r.true_pose(), closed_form({0.0f, 0.0f, static_cast<float>(0.75 * kPi)}, -0.4, 0.0, 2.5), 1e-4,
                     "reverse");
  }
}

TEST(SimChassis, AccelerationLimitsRampTheSpeed) {
  const ChassisSimSettings s = ideal();  // 1.0 m/s^2, 3.5 rad/s^2, h = 5 ms
  SimChassis c(open_world(), s, Pose2{});
  c.command({0.5f, 2.0f});
  for (int k = 1; k <= 200; ++k) {
    const Twist before = c.true_twist();
    c.advance(0.005);
    const Twist t = c.true_twist();
    EXPECT_NEAR(t.v, std::min(k * 1.0 * 0.005, 0.5), 1e-5) << "step " << k;
    EXPECT_NEAR(t.omega, std::min(k * 3.5 * 0.005, 2.0), 1e-5) << "step " << k;
    EXPECT_LE(t.v - before.v, 1.0f * 0.005f + 1e-6f);
    EXPECT_LE(t.omega - before.omega, 3.5f * 0.005f + 1e-6f);
  }
  // Braking ramps down at the same rate, and the robot does not stop at once.
  c.command({0.0f, 0.0f});
  c.advance(0.1);
  EXPECT_NEAR(c.true_twist().v, 0.5 - 0.1, 1e-5);
  EXPECT_NEAR(c.true_twist().omega, 2.0 - 0.35, 1e-5);
  c.advance(1.0);
  EXPECT_EQ(c.true_twist().v, 0.0f);
  EXPECT_EQ(c.true_twist().omega, 0.0f);

  // Distance of a straight run from rest: each step first raises the speed by a h, then moves,
  // so x(T) = v T - v^2 / (2 a) + v h / 2 once at speed.
  SimChassis d(open_world(), s, Pose2{});
  d.command({0.5f, 0.0f});
  d.advance(2.0);
  EXPECT_NEAR(d.true_pose().x, 0.5 * 2.0 - 0.25 / 2.0 + 0.5 * 0.005 / 2.0, 1e-4);
}

TEST(SimChassis, VelocityIsClampedToTheLimits) {
  for (const float sign : {1.0f, -1.0f}) {
    SimChassis c(open_world(), ideal(), Pose2{});
    c.command({sign * 5.0f, sign * 100.0f});
    c.advance(2.0);
    EXPECT_NEAR(c.true_twist().v, sign * 0.7f, 1e-6);
    EXPECT_NEAR(c.true_twist().omega, sign * kPi, 1e-5);
  }
  ChassisSimSettings s = ideal();
  s.max_linear_speed_mps = 0.3f;
  s.max_angular_speed_radps = 1.0f;
  SimChassis c(open_world(), s, Pose2{});
  c.command({0.5f, -2.0f});
  c.advance(1.0);
  EXPECT_NEAR(c.true_twist().v, 0.3f, 1e-6);
  EXPECT_NEAR(c.true_twist().omega, -1.0f, 1e-6);
}

TEST(SimChassis, OdometryEqualsTruthWithoutSlipAndNoise) {
  SimChassis c(open_world(), ideal(), Pose2{0.5f, -0.5f, 1.0f});
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::size_t messages = 0;
  for (int k = 0; k < 400; ++k) {  // 20 s of random commands at 20 Hz
    c.command({0.5f * u(rng), 2.0f * u(rng)});
    for (int j = 0; j < 5; ++j) {
      c.advance(0.01);
      for (const OdometryMsg& m : c.take_odometry()) {
        ++messages;
        if (m.stamp_s == 0.0) continue;
        EXPECT_NEAR(m.stamp_s, c.physics_time_s(), 1e-9);
        // The same numbers: same wheel speeds, same Eq. (4) steps.
        EXPECT_EQ(m.pose.x, c.physics_pose().x);
        EXPECT_EQ(m.pose.y, c.physics_pose().y);
        EXPECT_EQ(m.pose.theta, c.physics_pose().theta);
      }
    }
  }
  EXPECT_EQ(messages, 1u + 1000u);
  EXPECT_EQ(c.collisions(), 0u);
  // At a constant speed the reported twist is the true twist.
  c.command({0.3f, 0.4f});
  c.advance(3.0);
  const auto msgs = c.take_odometry();
  ASSERT_FALSE(msgs.empty());
  EXPECT_NEAR(msgs.back().twist.v, 0.3f, 1e-5);
  EXPECT_NEAR(msgs.back().twist.omega, 0.4f, 1e-5);
}

// With slip and encoder noise the odometry drifts. Model prediction for a straight run (omega = 0
// commanded, no wheel base bias): the heading error is
//   sum_k h u_k (s_r,k - s_l,k) / b   (truth, from the slip, an AR(1) process per wheel)
// - sum_k (n_r,k - n_l,k) / b        (odometry, from the encoder noise),
// whose variance we compute here exactly from the speed profile. Over 32 seeds the RMS error must
// be within [0.6, 1.5] of the prediction (a chi-square with 32 degrees of freedom is inside with
// probability > 0.999), every seed within 5 sigma; the lateral error of a random-walk heading is
// about v T sigma / sqrt(3), also bounded at 5 sigma.
TEST(SimChassis, OdometryDriftsWithSlipAndNoiseWithinTheModelsBound) {
  ChassisSimSettings s;  // defaults: 1 % slip over 50 ms, 25 um encoder noise per 20 ms
  s.wheel_base_bias = 0.0f;
  const double T = 20.0, v = 0.5, h = s.physics_step_s, b = s.wheel_base_m;
  const int steps = static_cast<int>(std::lround(T / h));
  const double phi = std::exp(-h / s.wheel_slip_correlation_s);
  // var(sum w_k s_k) for a stationary AR(1) of variance sigma^2: sigma^2 sum_k sum_m w_k w_m phi^|k-m|.
  double quad = 0.0, run = 0.0, prev_w = 0.0;
  for (int k = 1; k <= steps; ++k) {
    const double w = std::min(k * s.max_linear_accel_mps2 * h, v) * h;  // u_k h
    run = phi * (run + prev_w);                                          // sum_{m<k} w_m phi^(k-m)
    quad += w * (w + 2.0 * run);
    prev_w = w;
  }
  const double sigma = s.wheel_slip_std;
  const double enc_step = s.encoder_noise_m / std::sqrt(4.0);
  const double var = 2.0 * sigma * sigma * quad / (b * b) + steps * 2.0 * enc_step * enc_step / (b * b);
  const double sd = std::sqrt(var);
  EXPECT_GT(sd, 0.02);  // the model's drift is not negligible (about 2.5 deg) ...
  EXPECT_LT(sd, 0.08);  // ... nor absurd for wheel odometry
  const double lateral_sd = v * T * sd / std::sqrt(3.0);

  double sum_sq = 0.0, sum_pos = 0.0;
  const int seeds = 32;
  for (int seed = 1; seed <= seeds; ++seed) {
    s.seed = static_cast<std::uint64_t>(seed);
    SimChassis c(open_world(), s, Pose2{-8.0f, 0.0f, 0.0f});
    c.command({static_cast<float>(v), 0.0f});
    c.advance(T);
    const double err = std::remainder(static_cast<double>(c.odometry_pose().theta) - c.true_pose().theta, 2.0 * kPi);
    const double pos = std::hypot(c.odometry_pose().x - c.true_pose().x, c.odometry_pose().y - c.true_pose().y);
    EXPECT_LT(std::fabs(err), 5.0 * sd) << "seed " << seed;
    EXPECT_LT(pos, 5.0 * lateral_sd) << "seed " << seed;
    EXPECT_NEAR(c.true_pose().x, -8.0 + v * T - 0.125, 0.05) << "seed " << seed;  // mostly forward
    sum_sq += err * err;
    sum_pos += pos;
  }
  const double rms = std::sqrt(sum_sq / seeds);
  EXPECT_GT(rms, 0.6 * sd);
  EXPECT_LT(rms, 1.5 * sd);
  EXPECT_GT(sum_pos / seeds, 0.05) << "odometry must drift from the truth";
}

// The gyro's white noise (ChassisSimSettings::gyro_noise_density): a robot standing still with the
// gyro heading and no bias sees its odometry's heading do an angle random walk of std
// density * sqrt(t). Over 32 seeds and 100 s the RMS heading error must be within [0.6, 1.5] of
// that (a chi-square with 32 degrees of freedom is inside with probability > 0.999). Without the
// noise it stays exactly 0; the true motion (driving) is the same with and without it.
TEST(SimChassis, GyroNoiseIsAnAngleRandomWalk) {
  constexpr float kDensity = 3e-4f;  // rad/s/sqrt(Hz)
  constexpr double kT = 100.0;
  double sum2 = 0.0;
  constexpr int kSeeds = 32;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    ChassisSimSettings s = ideal();
    s.gyro_heading = true;
    s.gyro_bias_std_radps = 0.0f;
    s.gyro_noise_density = kDensity;
    s.seed = static_cast<std::uint64_t>(seed);
    SimChassis c(open_world(), s, Pose2{0.0f, 0.0f, 0.0f});
    c.advance(kT);
    const auto msgs = c.take_odometry();
    ASSERT_FALSE(msgs.empty());
    const double e = std::remainder(static_cast<double>(msgs.back().pose.theta), 2.0 * kPi);
    EXPECT_EQ(c.true_pose().theta, 0.0f);
    sum2 += e * e;
  }
  const double rms = std::sqrt(sum2 / kSeeds);
  const double predicted = kDensity * std::sqrt(kT);  // 3 mrad = 0.17 deg
  EXPECT_GT(rms, 0.6 * predicted);
  EXPECT_LT(rms, 1.5 * predicted);
  // No noise: exactly still.
  ChassisSimSettings quiet = ideal();
  quiet.gyro_heading = true;
  quiet.gyro_bias_std_radps = 0.0f;
  SimChassis still(open_world(), quiet, Pose2{0.0f, 0.0f, 0.0f});
  still.advance(kT);
  EXPECT_EQ(still.take_odometry().back().pose.theta, 0.0f);
  // Driving: the truth does not depend on the gyro's noise (its own generator), the odometry does.
  ChassisSimSettings noisy = ChassisSimSettings{};
  noisy.gyro_heading = true;
  ChassisSimSettings loud = noisy;
  loud.gyro_noise_density = kDensity;
  SimChassis a(open_world(), noisy, Pose2{0.0f, 0.0f, 0.0f}), b(open_world(), loud, Pose2{0.0f, 0.0f, 0.0f});
  for (SimChassis* c : {&a, &b}) {
    c->command({0.3f, 0.2f});
    c->advance(20.0);
  }
  EXPECT_EQ(a.true_pose().x, b.true_pose().x);
  EXPECT_EQ(a.true_pose().theta, b.true_pose().theta);
  EXPECT_NE(a.take_odometry().back().pose.theta, b.take_odometry().back().pose.theta);
  // Out of range: the error names the setting.
  for (const float bad : {-1e-4f, 0.02f, std::numeric_limits<float>::quiet_NaN()}) {
    ChassisSimSettings bs;
    bs.gyro_noise_density = bad;
    expect_invalid([&] { SimChassis(open_world(), bs, Pose2{}); }, "gyro_noise_density");
  }
}

TEST(SimChassis, WheelBaseBiasScalesEveryRotationOfTheOdometry) {
  ChassisSimSettings s = ideal();
  s.wheel_base_bias = 0.005f;
  SimChassis c(open_world(), s, Pose2{});
  c.command({0.0f, 1.0f});
  c.advance(2.0);
  const double odom = c.odometry_pose().theta, truth = c.true_pose().theta;
  ASSERT_GT(truth, 1.5);
  EXPECT_NEAR(odom / truth, 1.005, 1e-4);
  EXPECT_EQ(c.odometry_pose().x, 0.0f);  // a turn in place stays in place
}

TEST(SimChassis, SameSeedGivesIdenticalOdometryWhateverTheAdvanceSteps) {
  auto run = [](std::uint64_t seed, bool split) {
    ChassisSimSettings s;
    s.seed = seed;
    SimChassis c(open_world(), s, Pose2{});
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<OdometryMsg> all;
    for (int k = 0; k < 200; ++k) {
      c.command({0.4f * u(rng), 1.5f * u(rng)});
      if (split) {
        c.advance(0.013);
        c.advance(0.017);
        c.advance(0.02);
      } else {
        c.advance(0.05);
      }
      for (const auto& m : c.take_odometry()) all.push_back(m);
    }
    return all;
  };
  const auto a = run(42, false), b = run(42, true), other = run(43, false);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.size(), other.size());
  bool differs = false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].stamp_s, b[i].stamp_s);
    EXPECT_EQ(a[i].pose.x, b[i].pose.x);
    EXPECT_EQ(a[i].pose.y, b[i].pose.y);
    EXPECT_EQ(a[i].pose.theta, b[i].pose.theta);
    EXPECT_EQ(a[i].twist.v, b[i].twist.v);
    EXPECT_EQ(a[i].twist.omega, b[i].twist.omega);
    differs |= a[i].pose.x != other[i].pose.x || a[i].pose.y != other[i].pose.y;
  }
  EXPECT_TRUE(differs) << "another seed must give other noise";
}

TEST(SimChassis, OdometryIsStampedAt50Hz) {
  SimChassis c(open_world(), ChassisSimSettings{}, Pose2{});
  EXPECT_EQ(c.now_s(), 0.0);
  c.advance(0.0);
  auto first = c.take_odometry();
  ASSERT_EQ(first.size(), 1u);  // t = 0: the start pose
  EXPECT_EQ(first[0].stamp_s, 0.0);
  c.command({0.2f, 0.1f});
  c.advance(1.0);
  const auto msgs = c.take_odometry();
  ASSERT_EQ(msgs.size(), 50u);
  for (std::size_t k = 0; k < msgs.size(); ++k) EXPECT_NEAR(msgs[k].stamp_s, 0.02 * static_cast<double>(k + 1), 1e-12);
  EXPECT_TRUE(c.take_odometry().empty());
  c.advance(0.019);
  EXPECT_TRUE(c.take_odometry().empty());
  c.advance(0.001);
  const auto one = c.take_odometry();
  ASSERT_EQ(one.size(), 1u);
  EXPECT_NEAR(one[0].stamp_s, 1.02, 1e-12);
  EXPECT_NEAR(c.now_s(), 1.02, 1e-12);
  // Between physics steps the true pose is carried on with the current twist.
  c.advance(0.0025);
  EXPECT_NEAR(c.physics_time_s(), 1.02, 1e-12);
  const Pose2 p = c.physics_pose(), q = c.true_pose();
  EXPECT_NEAR(std::hypot(q.x - p.x, q.y - p.y), c.true_twist().v * 0.0025, 1e-7);
  EXPECT_NEAR(c.true_twist().v, 0.2, 0.01);

  // Another rate: 30 Hz from a profile gets a physics step that divides its period.
  duet::ChassisProfile profile;
  profile.odometry_rate_hz = 30.0f;
  const ChassisSimSettings s30 = ChassisSimSettings::from_profile(profile);
  EXPECT_LE(s30.physics_step_s, 0.005);
  SimChassis c30(open_world(), s30, Pose2{});
  c30.advance(1.0);
  const auto m30 = c30.take_odometry();
  ASSERT_EQ(m30.size(), 31u);
  EXPECT_NEAR(m30.back().stamp_s, 1.0, 1e-9);
}

TEST(SimChassis, DrivingIntoAWallStopsCountsOnceAndBacksOut) {
  const auto world = wall_world();
  const ChassisBody body;  // radius 0.177
  // Without slip, so that the turn in place below is exactly in place (with slip the wheels'
  // unequal slip moves the centre a little, which the wall may refuse).
  SimChassis c(world, ideal(), Pose2{0.0f, 0.0f, 0.0f}, body);
  // The controller keeps sending "forward" at 20 Hz for 4 s.
  for (int k = 0; k < 80; ++k) {
    c.command({0.5f, 0.0f});
    c.advance(0.05);
    ASSERT_FALSE(duet::sim::collides(*world, {c.physics_pose().x, c.physics_pose().y}, body.radius_m))
        << "inside the wall at t = " << c.now_s();
  }
  EXPECT_EQ(c.collisions(), 1u);
  EXPECT_TRUE(c.in_contact());
  EXPECT_LE(c.true_pose().x, 1.0f - body.radius_m);
  EXPECT_GT(c.true_pose().x, 1.0f - body.radius_m - 0.004f);  // within one step of the wall
  EXPECT_NEAR(c.true_pose().y, 0.0f, 0.3f);

  // Without a new command it stays stopped: not a hair of motion.
  c.advance(0.05);  // the last command's attempt ends in the wall again
  ASSERT_TRUE(c.stopped_by_collision());
  const Pose2 stopped = c.physics_pose();
  const auto odom_before = c.odometry_pose();
  c.advance(1.0);
  EXPECT_EQ(c.physics_pose().x, stopped.x);
  EXPECT_EQ(c.physics_pose().y, stopped.y);
  EXPECT_EQ(c.true_twist().v, 0.0f);
  EXPECT_EQ(c.odometry_pose().x, odom_before.x);
  EXPECT_EQ(c.collisions(), 1u);

  // Turning in place against the wall is free (the body is a disc).
  const float heading = c.physics_pose().theta;
  c.command({0.0f, 1.0f});
  c.advance(0.5);
  EXPECT_EQ(c.collisions(), 1u);
  EXPECT_FALSE(c.stopped_by_collision());
  EXPECT_GT(c.physics_pose().theta - heading, 0.3f);
  c.command({0.0f, 0.0f});
  c.advance(0.5);

  // Backing out works and ends the contact without another collision.
  const float wall_x = c.physics_pose().x;
  c.command({-0.3f, 0.0f});
  c.advance(1.5);
  EXPECT_EQ(c.collisions(), 1u);
  EXPECT_FALSE(c.in_contact());
  EXPECT_LT(c.physics_pose().x, wall_x - 0.2f);

  // Driving into it again is a second collision.
  c.command({0.0f, 0.0f});
  c.advance(1.0);
  c.command({0.5f, 0.0f});
  c.advance(4.0);
  EXPECT_EQ(c.collisions(), 2u);
  EXPECT_TRUE(c.stopped_by_collision());
  EXPECT_FALSE(duet::sim::collides(*world, {c.physics_pose().x, c.physics_pose().y}, body.radius_m));

  // Leaving the floor counts too (the floor's edge is a boundary), with slip and noise on.
  SimChassis e(wall_world(), ChassisSimSettings{}, Pose2{0.0f, 4.0f, static_cast<float>(0.5 * kPi)}, body);
  e.command({0.5f, 0.0f});
  e.advance(3.0);
  EXPECT_EQ(e.collisions(), 1u);
  EXPECT_LE(e.physics_pose().y, 5.0f - body.radius_m);
}

TEST(SimChassis, SettingsFromTheKobukiProfile) {
  const duet::Profile p = duet::builtin_profile("dual_kinect_kobuki");
  const ChassisSimSettings s = ChassisSimSettings::from_profile(p.chassis);
  EXPECT_FLOAT_EQ(s.max_linear_speed_mps, 0.7f);
  EXPECT_NEAR(s.max_angular_speed_radps, kPi, 1e-6);
  EXPECT_FLOAT_EQ(s.wheel_base_m, 0.230f);
  EXPECT_FLOAT_EQ(s.odometry_rate_hz, 50.0f);
  EXPECT_NEAR(s.physics_step_s, 0.005, 1e-12);
  EXPECT_NO_THROW(duet::sim::validate(s));
  const ChassisBody body = ChassisBody::from_profile(p.chassis);
  EXPECT_FLOAT_EQ(body.radius_m, 0.177f);
}

TEST(SimChassis, InvalidSettingsAndArgumentsThrow) {
  const auto world = open_world();
  auto with = [](auto change) {
    ChassisSimSettings s;
    change(s);
    return s;
  };
  const float nan = std::numeric_limits<float>::quiet_NaN();
  auto make = [&](const ChassisSimSettings& s) { SimChassis c(world, s, Pose2{}); };
  expect_invalid([&] { make(with([](auto& s) { s.max_linear_speed_mps = 0.0f; })); }, "max_linear_speed_mps");
  expect_invalid([&] { make(with([&](auto& s) { s.max_linear_speed_mps = nan; })); }, "max_linear_speed_mps");
  expect_invalid([&] { make(with([](auto& s) { s.max_angular_speed_radps = -1.0f; })); }, "max_angular_speed_radps");
  expect_invalid([&] { make(with([](auto& s) { s.max_linear_accel_mps2 = 0.0f; })); }, "max_linear_accel_mps2");
  expect_invalid([&] { make(with([](auto& s) { s.max_angular_accel_radps2 = 1e9f; })); }, "max_angular_accel_radps2");
  expect_invalid([&] { make(with([](auto& s) { s.physics_step_s = 0.0; })); }, "physics_step_s");
  expect_invalid([&] { make(with([](auto& s) { s.physics_step_s = 0.5; })); }, "physics_step_s");
  expect_invalid([&] { make(with([](auto& s) { s.odometry_rate_hz = 0.0f; })); }, "odometry_rate_hz");
  expect_invalid([&] { make(with([](auto& s) { s.odometry_rate_hz = 30.0f; })); }, "integer multiple");
  expect_invalid([&] { make(with([](auto& s) { s.odometry_rate_hz = 500.0f; })); }, "integer multiple");
  expect_invalid([&] { make(with([](auto& s) { s.wheel_base_m = -0.2f; })); }, "wheel_base_m");
  expect_invalid([&] { make(with([](auto& s) { s.wheel_slip_std = 0.6f; })); }, "wheel_slip_std");
  expect_invalid([&] { make(with([&](auto& s) { s.wheel_slip_correlation_s = nan; })); }, "wheel_slip_correlation_s");
  expect_invalid([&] { make(with([](auto& s) { s.wheel_base_bias = 0.3f; })); }, "wheel_base_bias");
  expect_invalid([&] { make(with([](auto& s) { s.encoder_noise_m = -1e-5f; })); }, "encoder_noise_m");
  expect_invalid([&] { make(with([](auto& s) { s.contact_release_m = 2.0f; })); }, "contact_release_m");

  auto body = [](float r, float lo, float hi) {
    ChassisBody b;
    b.radius_m = r;
    b.z_low_m = lo;
    b.z_high_m = hi;
    return b;
  };
  expect_invalid([&] { SimChassis c(world, {}, Pose2{}, body(0.0f, 0.0f, 0.6f)); }, "radius_m");
  expect_invalid([&] { SimChassis c(world, {}, Pose2{}, body(0.2f, -0.1f, 0.6f)); }, "z_low_m");
  expect_invalid([&] { SimChassis c(world, {}, Pose2{}, body(0.2f, 0.5f, 0.5f)); }, "z_high_m");
  expect_invalid([&] { SimChassis c(nullptr, {}, Pose2{}); }, "world is null");
  expect_invalid([&] { SimChassis c(world, {}, Pose2{nan, 0.0f, 0.0f}); }, "not finite");
  expect_invalid([&] { SimChassis c(wall_world(), {}, Pose2{1.1f, 0.0f, 0.0f}); }, "collides");
  expect_invalid([&] { SimChassis c(wall_world(), {}, Pose2{4.9f, 0.0f, 0.0f}); }, "collides");  // off the floor

  SimChassis c(world, {}, Pose2{});
  expect_invalid([&] { c.advance(-0.1); }, "dt_s");
  expect_invalid([&] { c.advance(std::nan("")); }, "dt_s");
  expect_invalid([&] { c.advance(1e9); }, "dt_s");
  EXPECT_EQ(c.now_s(), 0.0);
  // A non-finite command is a stop command, counted.
  c.command({0.5f, 0.0f});
  c.advance(1.0);
  c.command({nan, 0.0f});
  EXPECT_EQ(c.invalid_commands(), 1u);
  c.advance(1.0);
  EXPECT_EQ(c.true_twist().v, 0.0f);
}

// The gyro's bias (ChassisSimSettings::gyro_bias_std_radps) as SimChassis::gyro_bias() reports
// it - the truth summary.json's gyro_bias_true_radps gives: a robot standing still with the gyro
// heading and no noise sees its odometry's heading turn at exactly that rate; without the gyro
// heading, or with a std of 0, it is 0; the draw follows the seed.
TEST(SimChassis, GyroBiasIsTheRateTheStillOdometryTurnsAt) {
  ChassisSimSettings s = ideal();
  s.gyro_heading = true;
  s.gyro_bias_std_radps = 1e-3f;
  float first = 0.0f;
  for (std::uint64_t seed : {1u, 2u}) {
    s.seed = seed;
    SimChassis c(open_world(), s, Pose2{0.0f, 0.0f, 0.0f});
    ASSERT_NE(c.gyro_bias(), 0.0f);
    EXPECT_LT(std::fabs(c.gyro_bias()), 5e-3f);  // 5 std
    if (seed == 1) first = c.gyro_bias();
    else EXPECT_NE(c.gyro_bias(), first);  // another seed, another bias
    c.advance(10.0);
    EXPECT_NEAR(c.take_odometry().back().pose.theta, 10.0 * c.gyro_bias(), 1e-5);
    EXPECT_EQ(c.true_pose().theta, 0.0f);
  }
  s.gyro_bias_std_radps = 0.0f;
  EXPECT_EQ(SimChassis(open_world(), s, Pose2{}).gyro_bias(), 0.0f);
  ChassisSimSettings wheels = ideal();  // heading from the wheels: no gyro
  wheels.gyro_bias_std_radps = 1e-3f;
  EXPECT_EQ(SimChassis(open_world(), wheels, Pose2{}).gyro_bias(), 0.0f);
}

}  // namespace test_sim_chassis
