// PoseEkf: dead reckoning on the wheels against the exact arc, the visual update against a
// reference Kalman update with a numeric Jacobian, a biased wheel corrected by vision, the gate
// rejecting an injected 1 m jump (state unchanged, counted), the gyro, the wheels carrying on
// without vision, and named settings errors.
#include <duet/kernels/error.hpp>
#include <duet/runtime/localization/pose_ekf.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace duet {
namespace test_pose_ekf {

constexpr double kDt = 0.02;  // 50 Hz wheels

/// The increment from pose a to pose b in a's frame.
Eigen::Vector3d between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double c = std::cos(a(2)), s = std::sin(a(2)), dx = b(0) - a(0), dy = b(1) - a(1);
  return {c * dx + s * dy, -s * dx + c * dy, std::remainder(b(2) - a(2), 2.0 * std::numbers::pi)};
}

/// Exact unicycle motion over dt.
Eigen::Vector3d move(const Eigen::Vector3d& p, double v, double w, double dt) {
  if (std::abs(w) < 1e-12) return {p(0) + v * std::cos(p(2)) * dt, p(1) + v * std::sin(p(2)) * dt, p(2)};
  return {p(0) + v / w * (std::sin(p(2) + w * dt) - std::sin(p(2))), p(1) - v / w * (std::cos(p(2) + w * dt) - std::cos(p(2))),
          p(2) + w * dt};
}

TEST(PoseEkf, WheelsAloneFollowTheArc) {
  PoseEkf ekf;
  Eigen::Vector3d truth(0, 0, 0);
  for (int k = 0; k < 500; ++k) {  // 10 s at 0.4 m/s, 0.3 rad/s
    truth = move(truth, 0.4, 0.3, kDt);
    ekf.predict(kDt, 0.4, 0.3);
  }
  const Pose2 p = ekf.pose();
  // Euler steps of 20 ms on a 1.3 m radius: millimetres.
  EXPECT_NEAR(p.x, truth(0), 0.01);
  EXPECT_NEAR(p.y, truth(1), 0.01);
  EXPECT_NEAR(std::remainder(p.theta - truth(2), 2 * std::numbers::pi), 0.0, 1e-6);
  EXPECT_NEAR(ekf.twist().v, 0.4, 1e-6);
  EXPECT_NEAR(ekf.twist().omega, 0.3, 1e-6);
  EXPECT_EQ(ekf.wheel_scale(), 1.0);  // unobservable without vision: untouched
  EXPECT_EQ(ekf.wheel_bias(), 0.0);
}

TEST(PoseEkf, VisualUpdateEqualsAReferenceKalmanUpdate) {
  // A state with nonzero covariance everywhere, then one visual update, against the textbook
  // update with H from central differences of h(x).
  PoseEkf ekf;
  ekf.reset({1.0f, -2.0f, 0.7f});
  for (int k = 0; k < 50; ++k) {
    ekf.predict(kDt, 0.3, 0.2);
  }
  ekf.clone();
  for (int k = 0; k < 40; ++k) {
    ekf.predict(kDt, 0.3, 0.2);
  }
  const PoseEkf::State x = ekf.state();
  const PoseEkf::Covariance P = ekf.covariance();
  auto h = [](const PoseEkf::State& s) {
    return between(Eigen::Vector3d(s(5), s(6), s(7)), Eigen::Vector3d(s(0), s(1), s(2)));
  };
  Eigen::Matrix<double, 3, PoseEkf::kN> H;
  for (int i = 0; i < PoseEkf::kN; ++i) {
    PoseEkf::State a = x, b = x;
    a(i) += 1e-6;
    b(i) -= 1e-6;
    H.col(i) = (h(a) - h(b)) / 2e-6;
  }
  const Eigen::Vector3d z = h(x) + Eigen::Vector3d(0.01, -0.005, 0.004);
  Eigen::Matrix3d R = Eigen::Vector3d(4e-4, 4e-4, 1e-4).asDiagonal();
  const Eigen::Matrix3d S = H * P * H.transpose() + R;
  const Eigen::Matrix<double, PoseEkf::kN, 3> K = P * H.transpose() * S.inverse();
  const PoseEkf::State want = x + K * (z - h(x));
  const PoseEkf::Covariance want_P = (PoseEkf::Covariance::Identity() - K * H) * P;
  ASSERT_TRUE(ekf.update_visual(z, R));
  EXPECT_LT((ekf.state() - want).norm(), 1e-7) << (ekf.state() - want).transpose();
  EXPECT_LT((ekf.covariance() - want_P).norm(), 1e-7);
  EXPECT_EQ(ekf.visual_accepted(), 1u);
}

// learn_wheels = false (a Schmidt consider update): the pose moves as the reference gain says,
// k and b keep their values, and the covariance is the Joseph form's for that gain - still
// symmetric positive definite and no smaller than the full update's.
TEST(PoseEkf, AConsiderUpdateCorrectsThePoseButNotTheWheels) {
  PoseEkf ekf, full;
  for (PoseEkf* e : {&ekf, &full}) {
    e->reset({0.5f, 0.2f, -0.3f});
    for (int k = 0; k < 50; ++k) e->predict(kDt, 0.4, 0.1);
    e->clone();
    for (int k = 0; k < 50; ++k) e->predict(kDt, 0.4, -0.2);
  }
  const PoseEkf::State x = ekf.state();
  const PoseEkf::Covariance P = ekf.covariance();
  const double cc = std::cos(x(7)), sc = std::sin(x(7)), dx = x(0) - x(5), dy = x(1) - x(6);
  const Eigen::Vector3d h(cc * dx + sc * dy, -sc * dx + cc * dy, std::remainder(x(2) - x(7), 2.0 * std::numbers::pi));
  Eigen::Matrix<double, 3, PoseEkf::kN> H = Eigen::Matrix<double, 3, PoseEkf::kN>::Zero();
  H(0, 0) = cc, H(0, 1) = sc, H(0, 5) = -cc, H(0, 6) = -sc, H(0, 7) = h(1);
  H(1, 0) = -sc, H(1, 1) = cc, H(1, 5) = sc, H(1, 6) = -cc, H(1, 7) = -h(0);
  H(2, 2) = 1.0, H(2, 7) = -1.0;
  const Eigen::Matrix3d R = Eigen::Vector3d(1e-4, 1e-4, 3e-5).asDiagonal();
  Eigen::Matrix<double, PoseEkf::kN, 3> K = P * H.transpose() * (H * P * H.transpose() + R).inverse();
  K.middleRows<2>(3).setZero();
  const Eigen::Vector3d z = h + Eigen::Vector3d(-0.03, 0.01, 0.01);  // the wheels ran 3 cm long
  const PoseEkf::Covariance IKH = PoseEkf::Covariance::Identity() - K * H;
  const PoseEkf::State want = x + K * (z - h);
  const PoseEkf::Covariance want_P = IKH * P * IKH.transpose() + K * R * K.transpose();
  ASSERT_TRUE(ekf.update_visual(z, R, false));
  ASSERT_TRUE(full.update_visual(z, R, true));
  EXPECT_LT((ekf.state() - want).norm(), 1e-9) << (ekf.state() - want).transpose();
  EXPECT_LT((ekf.covariance() - want_P).norm(), 1e-9);
  EXPECT_EQ(ekf.wheel_scale(), 1.0);
  EXPECT_EQ(ekf.wheel_bias(), 0.0);
  EXPECT_LT(full.wheel_scale(), 1.0);  // the full update learns the long wheels
  EXPECT_NEAR(ekf.pose().x, full.pose().x, 0.01);  // the pose is corrected either way
  EXPECT_NE(ekf.pose().x, static_cast<float>(x(0)));
  const Eigen::SelfAdjointEigenSolver<PoseEkf::Covariance> eig(ekf.covariance());
  EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
  EXPECT_LE(full.covariance().trace(), ekf.covariance().trace());
}

TEST(PoseEkf, VisionCorrectsABiasedWheelAndTheGateRejectsAJump) {
  // The wheels report 8 % too much speed and a yaw rate off by 0.02 rad/s; vision measures the
  // true increment from the last location point every 0.2 s (1 cm, 0.3 deg noise).
  std::mt19937 rng(4);
  std::normal_distribution<double> n(0.0, 1.0);
  PoseEkf fused, wheels;
  Eigen::Vector3d truth(0, 0, 0), key = truth, chain = truth;  // chain: the increments alone, composed
  std::size_t rejected_jumps = 0;
  for (int k = 1; k <= 3000; ++k) {  // 60 s
    const double v = 0.3, w = 0.25 * std::sin(k * kDt * 0.3);
    truth = move(truth, v, w, kDt);
    for (PoseEkf* e : {&fused, &wheels}) e->predict(kDt, 1.08 * v, w + 0.02);
    if (k % 10 == 0) {
      const Eigen::Vector3d d = between(key, truth) + Eigen::Vector3d(0.005 * n(rng), 0.005 * n(rng), 0.002 * n(rng));
      const Eigen::Matrix3d R = Eigen::Vector3d(2.5e-5, 2.5e-5, 4e-6).asDiagonal();
      {
        const double c = std::cos(chain(2)), sn = std::sin(chain(2));
        chain = Eigen::Vector3d(chain(0) + c * d(0) - sn * d(1), chain(1) + sn * d(0) + c * d(1), chain(2) + d(2));
      }
      if (k % 500 == 0) {
        // An injected 1 m jump: rejected, the state untouched.
        const PoseEkf::State before = fused.state();
        EXPECT_FALSE(fused.update_visual(d + Eigen::Vector3d(1.0, 0.0, 0.0), R));
        EXPECT_GT(fused.last_visual_chi2(), 16.27);
        EXPECT_EQ(fused.state(), before);
        ++rejected_jumps;
      }
      EXPECT_TRUE(fused.update_visual(d, R)) << "step " << k << " chi2 " << fused.last_visual_chi2();
      fused.clone();
      key = truth;
    }
  }
  const double fused_err = std::hypot(fused.pose().x - truth(0), fused.pose().y - truth(1));
  const double wheel_err = std::hypot(wheels.pose().x - truth(0), wheels.pose().y - truth(1));
  const double chain_err = std::hypot(chain(0) - truth(0), chain(1) - truth(1));
  // Relative measurements cannot undo their own drift (the heading's random walk over 18 m):
  // the reference is the increments composed alone; the fused pose is no worse than that and an
  // order of magnitude better than the wheels.
  EXPECT_GT(wheel_err, 1.0);  // 18 m at 8 % plus a heading drift
  EXPECT_LT(fused_err, 0.1 * wheel_err) << "fused " << fused_err << " wheels " << wheel_err << " chain " << chain_err;
  // (0.40 m against 0.34 m with the default scale walk of 0.02/sqrt(s), which lets slip on a new
  // floor in within seconds and trusts the wheels' scale less in between.)
  EXPECT_LT(fused_err, 1.25 * chain_err + 0.05) << "fused " << fused_err << " chain " << chain_err;
  EXPECT_EQ(fused.visual_rejected(), rejected_jumps);
  EXPECT_EQ(fused.visual_accepted(), 300u);
  // Vision calibrated the wheels: they report 1.08 v (true = v / 1.08) and omega + 0.02.
  EXPECT_NEAR(fused.wheel_scale(), 1.0 / 1.08, 0.02);
  EXPECT_NEAR(fused.wheel_bias(), 0.02, 0.005);
}

// A long drive on the wheels alone (k's uncertainty walks up), then a location point and one
// short increment that reads 2 cm less than the wheels: the pose moves by about that much, not
// by k's change times the whole path (blank corridor: the pose moved 13-17 cm back on such an
// increment while k kept its correlation with the path driven since start-up). k still learns
// from the increment, and P stays positive semi-definite.
TEST(PoseEkf, AWeakIncrementAfterALongDriveMovesThePoseByItsInnovation) {
  PoseEkf ekf;
  ekf.reset({0, 0, 0});
  for (int k = 0; k < 3000; ++k) ekf.predict(kDt, 0.3, 0.0, true);  // 60 s, 18 m
  ekf.clone();
  for (int k = 0; k < 10; ++k) ekf.predict(kDt, 0.3, 0.0, true);   // 6 cm
  const Pose2 before = ekf.pose();
  const double k_before = ekf.wheel_scale();
  const Eigen::Vector3d d(0.04, 0.0, 0.0);  // vision: 4 cm
  const Eigen::Matrix3d R = Eigen::Vector3d(1e-4, 1e-4, 1e-6).asDiagonal();
  ASSERT_TRUE(ekf.update_visual(d, R)) << ekf.last_visual_chi2();
  const double moved = ekf.pose().x - before.x;
  EXPECT_LT(moved, 0.0);
  EXPECT_GT(moved, -0.025) << "the pose moved by more than the increment disagrees with the wheels";
  EXPECT_LT(ekf.wheel_scale(), k_before);  // the scale still learnt
  const Eigen::SelfAdjointEigenSolver<PoseEkf::Covariance> eig(ekf.covariance());
  EXPECT_GE(eig.eigenvalues().minCoeff(), -1e-12);
}

TEST(PoseEkf, GyroRateIsTakenAsIsAndWheelsCarryOnAlone) {
  PoseEkf ekf;
  ekf.reset({0, 0, 0});
  // A learnt wheel bias applies to the wheels' rate, not to a gyro's.
  for (int k = 0; k < 100; ++k) ekf.predict(kDt, 0.2, 0.3, true);
  EXPECT_NEAR(ekf.pose().theta, 0.6, 1e-6);
  EXPECT_NEAR(ekf.twist().omega, 0.3, 1e-6);
  // No vision for 10 s: the pose keeps moving on the wheels, nothing is rejected.
  const Pose2 before = ekf.pose();
  for (int k = 0; k < 500; ++k) ekf.predict(kDt, 0.2, 0.0);
  EXPECT_NEAR(std::hypot(ekf.pose().x - before.x, ekf.pose().y - before.y), 2.0, 1e-4);
  EXPECT_EQ(ekf.visual_rejected(), 0u);
  // The position's uncertainty grows without vision.
  EXPECT_GT(ekf.covariance()(0, 0) + ekf.covariance()(1, 1), 1e-4);
  // Bad numbers are ignored or rejected, never taken.
  const PoseEkf::State s = ekf.state();
  ekf.predict(kDt, std::nan(""), 0.0);
  ekf.predict(kDt, 0.1, INFINITY, true);
  ekf.predict(-1.0, 0.1, 0.1);
  EXPECT_EQ(ekf.state(), s);
  EXPECT_FALSE(ekf.update_visual(Eigen::Vector3d(std::nan(""), 0, 0), Eigen::Matrix3d::Identity()));
  EXPECT_EQ(ekf.state(), s);
}

TEST(PoseEkf, BadSettingsAreNamed) {
  auto expect = [](PoseEkfSettings s, const std::string& what) {
    try {
      PoseEkf ekf(s);
      ADD_FAILURE() << "no error for " << what;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  PoseEkfSettings s;
  s.wheel_speed_sigma = 0.0f;
  expect(s, "wheel_speed_sigma");
  s = {};
  s.gate_chi2 = std::nanf("");
  expect(s, "gate_chi2");
  s = {};
  s.wheel_yaw_rate_sigma = -1.0f;
  expect(s, "wheel_yaw_rate_sigma");
}

}  // namespace test_pose_ekf
}  // namespace duet
