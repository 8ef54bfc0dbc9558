#include <duet/kernels/error.hpp>
#include <duet/runtime/localization/pose_ekf.hpp>

#include <Eigen/Cholesky>

#include <cmath>
#include <numbers>
#include <string>

namespace duet {
namespace {

double wrap(double a) { return std::remainder(a, 2.0 * std::numbers::pi); }

void check(bool ok, const char* field, double v, const char* range) {
  if (!ok) fail(ErrorCode::kInvalidArgument, std::string("pose EKF settings: ") + field + " must be in " + range + ", got " + std::to_string(v));
}

}  // namespace

void validate(const PoseEkfSettings& s) {
  check(s.wheel_speed_sigma > 0.0f && s.wheel_speed_sigma <= 10.0f, "wheel_speed_sigma", s.wheel_speed_sigma, "(0, 10]");
  check(s.wheel_yaw_rate_sigma > 0.0f && s.wheel_yaw_rate_sigma <= 10.0f, "wheel_yaw_rate_sigma", s.wheel_yaw_rate_sigma, "(0, 10]");
  check(s.gyro_sigma > 0.0f && s.gyro_sigma <= 10.0f, "gyro_sigma", s.gyro_sigma, "(0, 10]");
  check(s.wheel_scale_sigma > 0.0f && s.wheel_scale_sigma <= 1.0f, "wheel_scale_sigma", s.wheel_scale_sigma, "(0, 1]");
  check(s.wheel_bias_sigma > 0.0f && s.wheel_bias_sigma <= 1.0f, "wheel_bias_sigma", s.wheel_bias_sigma, "(0, 1]");
  check(s.wheel_scale_walk >= 0.0f && s.wheel_scale_walk <= 1.0f, "wheel_scale_walk", s.wheel_scale_walk, "[0, 1]");
  check(s.wheel_bias_walk >= 0.0f && s.wheel_bias_walk <= 1.0f, "wheel_bias_walk", s.wheel_bias_walk, "[0, 1]");
  check(s.visual_min_sigma_m >= 0.0f && s.visual_min_sigma_m <= 1.0f, "visual_min_sigma_m", s.visual_min_sigma_m, "[0, 1]");
  check(s.visual_min_sigma_deg >= 0.0f && s.visual_min_sigma_deg <= 10.0f, "visual_min_sigma_deg", s.visual_min_sigma_deg, "[0, 10]");
  check(s.gate_chi2 > 0.0f && s.gate_chi2 <= 1000.0f, "gate_chi2", s.gate_chi2, "(0, 1000]");
}

PoseEkf::PoseEkf(const PoseEkfSettings& settings, const Pose2& start) : settings_((validate(settings), settings)) { reset(start); }

void PoseEkf::reset(const Pose2& p) {
  x_ << p.x, p.y, wrap(p.theta), 1.0, 0.0, p.x, p.y, wrap(p.theta);
  P_.setZero();
  const double ss = settings_.wheel_scale_sigma, sb = settings_.wheel_bias_sigma;
  P_.diagonal() << 1e-8, 1e-8, 1e-8, ss * ss, sb * sb, 1e-8, 1e-8, 1e-8;
  twist_ = {};
}

void PoseEkf::predict(double dt, double v_in, double w_in, bool gyro) {
  if (!(dt > 0.0) || !std::isfinite(dt) || !std::isfinite(v_in) || !std::isfinite(w_in)) return;
  const double th = x_(2), k = x_(3), c = std::cos(th), s = std::sin(th);
  const double v = k * v_in, w = gyro ? w_in : w_in - x_(4);
  x_(0) += v * c * dt;
  x_(1) += v * s * dt;
  x_(2) = wrap(th + w * dt);
  twist_ = {static_cast<float>(v), static_cast<float>(w)};
  Covariance F = Covariance::Identity();
  F(0, 2) = -v * s * dt;
  F(0, 3) = v_in * c * dt;
  F(1, 2) = v * c * dt;
  F(1, 3) = v_in * s * dt;
  if (!gyro) F(2, 4) = -dt;
  P_ = F * P_ * F.transpose();
  // The inputs' noise: speed along the heading, the yaw rate on theta.
  const double sv = settings_.wheel_speed_sigma * dt, sw = (gyro ? settings_.gyro_sigma : settings_.wheel_yaw_rate_sigma) * dt;
  P_(0, 0) += sv * sv * c * c;
  P_(0, 1) += sv * sv * c * s;
  P_(1, 0) += sv * sv * c * s;
  P_(1, 1) += sv * sv * s * s;
  P_(2, 2) += sw * sw;
  P_(3, 3) += static_cast<double>(settings_.wheel_scale_walk) * settings_.wheel_scale_walk * dt;
  P_(4, 4) += static_cast<double>(settings_.wheel_bias_walk) * settings_.wheel_bias_walk * dt;
}

bool PoseEkf::update_visual(const Eigen::Vector3d& d, const Eigen::Matrix3d& covariance, bool learn_wheels) {
  if (!d.allFinite() || !covariance.allFinite()) {
    ++rejected_;
    return false;
  }
  const double dx = x_(0) - x_(5), dy = x_(1) - x_(6), c = std::cos(x_(7)), s = std::sin(x_(7));
  const double h0 = c * dx + s * dy, h1 = -s * dx + c * dy;
  Eigen::Matrix<double, 3, kN> H = Eigen::Matrix<double, 3, kN>::Zero();
  H(0, 0) = c, H(0, 1) = s, H(0, 5) = -c, H(0, 6) = -s, H(0, 7) = h1;
  H(1, 0) = -s, H(1, 1) = c, H(1, 5) = s, H(1, 6) = -c, H(1, 7) = -h0;
  H(2, 2) = 1.0, H(2, 7) = -1.0;
  const Eigen::Vector3d y(d(0) - h0, d(1) - h1, wrap(d(2) - wrap(x_(2) - x_(7))));
  Eigen::Matrix3d R = 0.5 * (covariance + covariance.transpose());
  const double sm = settings_.visual_min_sigma_m, sr = settings_.visual_min_sigma_deg * std::numbers::pi / 180.0;
  R(0, 0) = std::max(R(0, 0), sm * sm);
  R(1, 1) = std::max(R(1, 1), sm * sm);
  R(2, 2) = std::max(R(2, 2), sr * sr);
  const Eigen::Matrix3d S = H * P_ * H.transpose() + R;
  const Eigen::LLT<Eigen::Matrix3d> llt(S);
  last_chi2_ = llt.info() == Eigen::Success ? y.dot(llt.solve(y)) : INFINITY;
  if (!std::isfinite(last_chi2_) || last_chi2_ > settings_.gate_chi2) {
    ++rejected_;
    return false;
  }
  Eigen::Matrix<double, kN, 3> K = P_ * H.transpose() * llt.solve(Eigen::Matrix3d::Identity());
  if (!learn_wheels) K.middleRows<2>(3).setZero();  // Schmidt: k and b considered, not estimated
  x_ += K * y;
  x_(2) = wrap(x_(2));
  x_(7) = wrap(x_(7));
  const Covariance IKH = Covariance::Identity() - K * H;
  P_ = IKH * P_ * IKH.transpose() + K * R * K.transpose();
  P_ = 0.5 * (P_ + P_.transpose());
  ++accepted_;
  return true;
}

void PoseEkf::clone() {
  // The new location point starts k's memory: its correlations are dropped (k alone in its
  // block, P stays positive semi-definite: a principal block and k's variance). Kept, it holds every
  // metre driven since start-up, and one weak increment that reads the scale a few per cent off
  // moves the whole past with it - a 2 cm innovation over 6 cm moved the pose 13-17 cm back in
  // the blank corridor. Dropped, k is still learnt from the motion since the location point (the
  // correlation the predictions build from here on), and a correction moves the pose by about
  // what the increment disagrees with the wheels.
  const double kk = P_(3, 3);
  P_.row(3).setZero();
  P_.col(3).setZero();
  P_(3, 3) = kk;
  x_.segment<3>(5) = x_.head<3>();
  P_.block<3, kN>(5, 0) = P_.block<3, kN>(0, 0);
  P_.block<kN, 3>(0, 5) = P_.block<kN, 3>(0, 0);
  P_.block<3, 3>(5, 5) = P_.block<3, 3>(0, 0);
}

Pose2 PoseEkf::pose() const noexcept {
  return {static_cast<float>(x_(0)), static_cast<float>(x_(1)), static_cast<float>(x_(2))};
}
Pose2 PoseEkf::clone_pose() const noexcept {
  return {static_cast<float>(x_(5)), static_cast<float>(x_(6)), static_cast<float>(x_(7))};
}

}  // namespace duet
