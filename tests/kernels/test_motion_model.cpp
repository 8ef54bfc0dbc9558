// The motion model Eq. (4) (motion_model.hpp) against the paper's formula in double, its
// omega -> 0 limit, heading wrap, and the chassis limits.
#include <duet/kernels/error.hpp>
#include <duet/kernels/motion_model.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace duet {
namespace test_motion_model {

constexpr double kPi = 3.14159265358979323846;

// Eq. (4) exactly as printed, in double (valid for omega != 0).
void eq4(double x, double y, double th, double v, double w, double dt, double& xo, double& yo, double& tho) {
  xo = x - v / w * std::sin(th) + v / w * std::sin(th + w * dt);
  yo = y + v / w * std::cos(th) - v / w * std::cos(th + w * dt);
  tho = th + w * dt;
}

double wrap(double a) { return std::remainder(a, 2.0 * kPi); }

TEST(MotionModel, MatchesEq4OnRandomCommands) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> pos(-20.0f, 20.0f), ang(-3.1f, 3.1f), v(-0.7f, 0.7f), w(-3.1f, 3.1f),
      dt(0.01f, 2.0f);
  for (int i = 0; i < 10000; ++i) {
    const Pose2 p{pos(rng), pos(rng), ang(rng)};
    Twist u{v(rng), w(rng)};
    if (std::fabs(u.omega) < 0.01f) u.omega = 0.01f;  // Eq. (4) itself is singular at 0
    const float t = dt(rng);
    double xo, yo, tho;
    eq4(p.x, p.y, p.theta, u.v, u.omega, t, xo, yo, tho);
    const Pose2 q = motion_step(p, u, t);
    EXPECT_NEAR(q.x, xo, 2e-5 + 2e-6 * std::fabs(xo)) << i;
    EXPECT_NEAR(q.y, yo, 2e-5 + 2e-6 * std::fabs(yo)) << i;
    EXPECT_NEAR(wrap(q.theta - tho), 0.0, 1e-5) << i;
    EXPECT_GT(q.theta, -kPi - 1e-6);
    EXPECT_LE(q.theta, kPi + 1e-6);
  }
}

// The omega -> 0 limit: a straight line, reached continuously.
TEST(MotionModel, StraightLineLimitIsContinuous) {
  const Pose2 p{1.0f, 2.0f, 0.7f};
  const Pose2 s = motion_step(p, Twist{0.5f, 0.0f}, 2.0f);
  EXPECT_NEAR(s.x, 1.0 + 1.0 * std::cos(0.7), 1e-6);
  EXPECT_NEAR(s.y, 2.0 + 1.0 * std::sin(0.7), 1e-6);
  EXPECT_FLOAT_EQ(s.theta, 0.7f);
  for (const float w : {1e-7f, 1e-5f, 1e-4f, 9.9e-4f, 1.01e-3f, 1e-2f}) {  // across the series threshold
    double xo, yo, tho;
    eq4(p.x, p.y, p.theta, 0.5, static_cast<double>(w), 2.0, xo, yo, tho);
    const Pose2 q = motion_step(p, Twist{0.5f, w}, 2.0f);
    EXPECT_NEAR(q.x, xo, 2e-6) << w;
    EXPECT_NEAR(q.y, yo, 2e-6) << w;
  }
  // Turning in place: position unchanged.
  const Pose2 r = motion_step(p, Twist{0.0f, 1.0f}, 1.0f);
  EXPECT_FLOAT_EQ(r.x, p.x);
  EXPECT_FLOAT_EQ(r.y, p.y);
  EXPECT_NEAR(r.theta, 1.7f, 1e-6f);
  // A full circle returns to the start.
  Pose2 c = p;
  for (int i = 0; i < 100; ++i) c = motion_step(c, Twist{0.3f, 2.0f * static_cast<float>(kPi) / 10.0f}, 0.1f);
  EXPECT_NEAR(c.x, p.x, 1e-4f);
  EXPECT_NEAR(c.y, p.y, 1e-4f);
  EXPECT_NEAR(wrap(c.theta - p.theta), 0.0, 1e-4);
  // dt = 0 changes nothing.
  const Pose2 z = motion_step(p, Twist{0.5f, 1.0f}, 0.0f);
  EXPECT_FLOAT_EQ(z.x, p.x);
  EXPECT_FLOAT_EQ(z.y, p.y);
}

TEST(MotionModel, ChassisLimits) {
  ChassisLimits l;
  EXPECT_NO_THROW(validate(l));
  const Twist c = clamp_twist(Twist{2.0f, -10.0f}, l);
  EXPECT_FLOAT_EQ(c.v, l.max_v_mps);
  EXPECT_FLOAT_EQ(c.omega, -l.max_omega_rps);
  const Twist r = clamp_twist(Twist{-5.0f, 0.1f}, l);
  EXPECT_FLOAT_EQ(r.v, l.min_v_mps);
  EXPECT_FLOAT_EQ(r.omega, 0.1f);
  auto bad = [](auto mutate) {
    ChassisLimits b;
    mutate(b);
    EXPECT_THROW(validate(b), Error);
  };
  bad([](ChassisLimits& b) { b.max_v_mps = 0.0f; });
  bad([](ChassisLimits& b) { b.min_v_mps = 0.1f; });
  bad([](ChassisLimits& b) { b.max_omega_rps = std::nanf(""); });
  bad([](ChassisLimits& b) { b.max_accel_mps2 = -1.0f; });
  bad([](ChassisLimits& b) { b.max_alpha_rps2 = INFINITY; });
}

}  // namespace test_motion_model
}  // namespace duet
