// associate / absolute_trajectory_error / relative_pose_error on synthetic trajectories with known
// answers: a rigidly moved copy aligns to zero, a known offset in time or noise gives the
// expected figures, association follows associate.py's greedy rule, RPE per frame / second /
// metre picks the documented pairs; empty, tiny, NaN and bad arguments. The real-file check
// against an independent numpy re-write of the TUM scripts is tests/python/eval_traj_reference.py.
#include "kernels/kernel_test_util.hpp"

#include <duet/kernels/trajectory_eval.hpp>

#include <random>

namespace duet {
namespace test_trajectory_eval {

std::vector<StampedPose> helix(std::size_t n, double dt = 0.1) {
  std::vector<StampedPose> t(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double s = static_cast<double>(i) * dt;
    t[i].stamp_s = 100.0 + s;
    t[i].pose.linear() = (Eigen::AngleAxisd(0.3 * s, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.1 * std::sin(s), Eigen::Vector3d::UnitX())).toRotationMatrix();
    t[i].pose.translation() = Eigen::Vector3d(std::cos(0.3 * s) * 2.0, std::sin(0.3 * s) * 2.0, 0.05 * s);
  }
  return t;
}

Eigen::Isometry3d some_transform() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())).toRotationMatrix();
  T.translation() = Eigen::Vector3d(3.0, -1.0, 0.5);
  return T;
}

TEST(TrajectoryEval, RigidlyMovedCopyHasZeroAte) {
  const auto gt = helix(200);
  auto est = gt;
  for (auto& p : est) p.pose = some_transform() * p.pose;
  const auto r = absolute_trajectory_error(est, gt);
  EXPECT_EQ(r.translation.count, 200u);
  EXPECT_LT(r.translation.rmse, 1e-9);
  EXPECT_TRUE(r.alignment.isApprox(some_transform().inverse(), 1e-9));
  // Not aligned: the error is the transform's effect.
  AteSettings raw;
  raw.align = false;
  EXPECT_GT(absolute_trajectory_error(est, gt, raw).translation.rmse, 1.0);
  // RPE does not depend on the world frame.
  const auto rpe = relative_pose_error(est, gt);
  EXPECT_EQ(rpe.pairs, 199u);
  EXPECT_LT(rpe.translation.max, 1e-9);
  EXPECT_LT(rpe.rotation.max, 1e-5);
}

TEST(TrajectoryEval, ScaledCopyNeedsSim3) {
  const auto gt = helix(100);
  auto est = gt;
  for (auto& p : est) p.pose.translation() *= 0.5;
  AteSettings s;
  s.with_scale = true;
  const auto r = absolute_trajectory_error(est, gt, s);
  EXPECT_NEAR(r.scale, 2.0, 1e-9);
  EXPECT_LT(r.translation.rmse, 1e-9);
  EXPECT_GT(absolute_trajectory_error(est, gt).translation.rmse, 0.1);
}

TEST(TrajectoryEval, NoiseGivesItsRmse) {
  // Isotropic 1 cm noise per axis: ATE rmse ~ sqrt(3) cm (alignment absorbs a tiny part).
  const auto gt = helix(4000, 0.01);
  auto est = gt;
  std::mt19937 rng(5);
  std::normal_distribution<double> N(0.0, 0.01);
  for (auto& p : est) p.pose.translation() += Eigen::Vector3d(N(rng), N(rng), N(rng));
  const auto r = absolute_trajectory_error(est, gt);
  EXPECT_NEAR(r.translation.rmse, std::sqrt(3.0) * 0.01, 0.0007);
  EXPECT_LE(r.translation.min, r.translation.median);
  EXPECT_LE(r.translation.median, r.translation.max);
  // RPE of independent noise: the difference of two draws, sqrt(6) cm rms.
  const auto rpe = relative_pose_error(est, gt);
  EXPECT_NEAR(rpe.translation.rmse, std::sqrt(6.0) * 0.01, 0.001);
}

TEST(TrajectoryEval, AssociationIsGreedyByTimeDifference) {
  // gt at 0, 1, 2; estimates at 0.004, 0.006, 1.5, 2.019, 2.03 with max_dt 0.02.
  std::vector<StampedPose> gt(3), est(5);
  for (int i = 0; i < 3; ++i) gt[static_cast<std::size_t>(i)].stamp_s = i;
  const double e[] = {0.006, 0.004, 1.5, 2.019, 2.03};
  for (int i = 0; i < 5; ++i) est[static_cast<std::size_t>(i)].stamp_s = e[i];
  const auto a = associate(est, gt);
  // 0.004 (index 1) takes gt 0, not 0.006; 1.5 and 2.03 are too far; 2.019 takes gt 2.
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a[0], std::make_pair(std::size_t{1}, std::size_t{0}));
  EXPECT_EQ(a[1], std::make_pair(std::size_t{3}, std::size_t{2}));
  // An offset moves the estimate's stamps.
  const auto b = associate(est, gt, {0.02, -0.5});
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(b[0].first, 2u);
  EXPECT_EQ(b[0].second, 1u);
  // NaN stamps are never associated; empty inputs give nothing.
  est[1].stamp_s = test::kNaN;
  EXPECT_EQ(associate(est, gt).front().first, 0u);
  EXPECT_TRUE(associate({}, gt).empty());
  EXPECT_TRUE(associate(est, {}).empty());
}

TEST(TrajectoryEval, RpeUnitsPickTheDocumentedPairs) {
  const auto gt = helix(101, 0.1);  // 10 s, ~0.6 m/s along the helix
  auto est = gt;
  // A 1 cm jump in x between frames 50 and 51, kept after: one pair per window sees it.
  for (std::size_t i = 51; i < est.size(); ++i) est[i].pose.translation().x() += 0.01;
  RpeSettings f;
  const auto r1 = relative_pose_error(est, gt, f);
  EXPECT_EQ(r1.pairs, 100u);
  EXPECT_NEAR(r1.translation.max, 0.01, 1e-9);
  EXPECT_LT(r1.translation.median, 1e-12);
  f.delta = 10;
  EXPECT_EQ(relative_pose_error(est, gt, f).pairs, 91u);
  RpeSettings s;
  s.unit = RpeUnit::kSeconds;
  s.delta = 1.0;
  EXPECT_EQ(relative_pose_error(est, gt, s).pairs, 91u);
  RpeSettings m;
  m.unit = RpeUnit::kMetres;
  m.delta = 1.0;
  const auto rm = relative_pose_error(est, gt, m);
  EXPECT_GT(rm.pairs, 70u);
  EXPECT_LT(rm.pairs, 100u);
  EXPECT_NEAR(rm.translation.max, 0.01, 1e-9);
}

TEST(TrajectoryEval, BadInputIsNamed) {
  const auto gt = helix(10);
  const auto expect = [](const std::function<void()>& fn, const std::string& what) { test::expect_error(fn, what); };
  expect([&] { (void)associate(gt, gt, {0.0, 0.0}); }, "max_dt_s");
  expect([&] { (void)associate(gt, gt, {test::kNaN, 0.0}); }, "max_dt_s");
  expect([&] { (void)absolute_trajectory_error(std::span(gt).first(2), gt); }, "need at least 3");
  expect([&] { (void)absolute_trajectory_error({}, gt); }, "0 associated poses");
  auto nan = gt;
  nan[4].pose.translation().x() = test::kNaN;
  expect([&] { (void)absolute_trajectory_error(nan, gt); }, "non-finite pose");
  expect([&] { (void)relative_pose_error(nan, gt); }, "non-finite pose");
  RpeSettings r;
  r.delta = 0.0;
  expect([&] { (void)relative_pose_error(gt, gt, r); }, "delta");
  r.delta = 1.5;
  expect([&] { (void)relative_pose_error(gt, gt, r); }, "whole number");
  r.delta = 100;
  expect([&] { (void)relative_pose_error(gt, gt, r); }, "no pose pair");
  // One pose, not aligned: its distance.
  AteSettings raw;
  raw.align = false;
  auto one = std::vector<StampedPose>(gt.begin(), gt.begin() + 1);
  one[0].pose.translation().y() += 0.25;
  EXPECT_NEAR(absolute_trajectory_error(one, gt, raw).translation.rmse, 0.25, 1e-12);
  const ErrorStats empty = error_stats({});
  EXPECT_EQ(empty.count, 0u);
  EXPECT_EQ(empty.rmse, 0.0);
}

}  // namespace test_trajectory_eval
}  // namespace duet
