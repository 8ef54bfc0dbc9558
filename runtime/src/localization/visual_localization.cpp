#include <duet/kernels/error.hpp>
#include <duet/runtime/localization/visual_localization.hpp>

#include <chrono>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

namespace duet {
namespace {

Eigen::Isometry3d to_iso(const Pose2& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(p.theta, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(p.x, p.y, 0.0);
  return T;
}

/// a^-1 * b for planar poses (motion_model.hpp).
Pose2 between(const Pose2& a, const Pose2& b) { return compose(inverse(a), b); }

Eigen::Vector3d compose(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double c = std::cos(a(2)), s = std::sin(a(2));
  return {a(0) + c * b(0) - s * b(1), a(1) + s * b(0) + c * b(1), std::remainder(a(2) + b(2), 2.0 * std::numbers::pi)};
}
Eigen::Vector3d vec(const Pose2& p) { return {p.x, p.y, p.theta}; }
Eigen::Vector3d inverse(const Eigen::Vector3d& a) {
  const double c = std::cos(a(2)), s = std::sin(a(2));
  return {-(c * a(0) + s * a(1)), -(-s * a(0) + c * a(1)), -a(2)};
}

double wall_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

}  // namespace

const char* to_string(LocalizationHealth h) noexcept {
  switch (h) {
    case LocalizationHealth::kGood: return "good";
    case LocalizationHealth::kDegraded: return "degraded";
    case LocalizationHealth::kLost: return "lost";
  }
  return "unknown";
}

void validate(const VisualLocalizationSettings& s) {
  validate(s.odometer);
  validate(s.ekf);
  const std::string w = "visual localization settings: ";
  if (s.fuse_min_inliers < 0 || s.fuse_min_inliers > 100000)
    fail(ErrorCode::kInvalidArgument, w + "fuse_min_inliers must be in [0, 100000], got " + std::to_string(s.fuse_min_inliers));
  if (s.learn_wheels_min_inliers < 0 || s.learn_wheels_min_inliers > 100000)
    fail(ErrorCode::kInvalidArgument, w + "learn_wheels_min_inliers must be in [0, 100000], got " + std::to_string(s.learn_wheels_min_inliers));
  if (s.good_min_inliers < 0 || s.good_min_inliers > 100000)
    fail(ErrorCode::kInvalidArgument, w + "good_min_inliers must be in [0, 100000], got " + std::to_string(s.good_min_inliers));
  if (!(s.degraded_after_s > 0.0 && s.degraded_after_s <= 3600.0))
    fail(ErrorCode::kInvalidArgument, w + "degraded_after_s must be in (0, 3600], got " + std::to_string(s.degraded_after_s));
  if (!(s.rate_hz > 0.0 && s.rate_hz <= 1000.0))
    fail(ErrorCode::kInvalidArgument, w + "rate_hz must be in (0, 1000], got " + std::to_string(s.rate_hz));
  if (!(s.lost_after_s >= s.degraded_after_s && s.lost_after_s <= 3600.0))
    fail(ErrorCode::kInvalidArgument, w + "lost_after_s must be in [degraded_after_s, 3600], got " + std::to_string(s.lost_after_s));
}

VisualLocalization::VisualLocalization(const VisualLocalizationSettings& settings)
    : settings_((validate(settings), settings)), odometer_(settings.odometer), ekf_(settings.ekf) {}

Pose2 VisualLocalization::pose_at(double t) const {
  if (history_.empty()) return ekf_.pose();
  if (t <= history_.front().first) return history_.front().second;
  if (t >= history_.back().first) return history_.back().second;
  for (std::size_t k = 1; k < history_.size(); ++k) {
    const auto& [ta, a] = history_[k - 1];
    const auto& [tb, b] = history_[k];
    if (t > tb) continue;
    const float u = tb > ta ? static_cast<float>((t - ta) / (tb - ta)) : 0.0f;
    const Pose2 d = between(a, b);
    return compose(a, Pose2{u * d.x, u * d.y, u * d.theta});
  }
  return history_.back().second;
}

Pose2 VisualLocalization::odometry(const OdometryMsg& m) {
  auto remember = [&] {
    history_.emplace_back(m.stamp_s, ekf_.pose());
    while (history_.size() > 64) history_.pop_front();  // > 1 s at 50 Hz: longer than any set's lag
  };
  if (!last_odom_) {
    ekf_.reset(m.pose);
    last_odom_ = m;
    if (start_s_ < 0.0) start_s_ = m.stamp_s;
    remember();
    return ekf_.pose();
  }
  const double dt = m.stamp_s - last_odom_->stamp_s;
  if (dt > 0.0) {
    // The wheels' increment in the previous robot frame, as a speed and a yaw rate over dt.
    const Pose2& a = last_odom_->pose;
    const float c = std::cos(a.theta), s = std::sin(a.theta);
    const double dx = c * (m.pose.x - a.x) + s * (m.pose.y - a.y);
    const double dth = std::remainder(m.pose.theta - a.theta, 2.0f * std::numbers::pi_v<float>);
    ekf_.predict(dt, dx / dt, dth / dt, settings_.odometry_heading_from_gyro);
    last_odom_ = m;
    remember();
  }
  return ekf_.pose();
}

void VisualLocalization::frames(std::span<const SensorFrame> frames, double t) {
  const Job job = begin(t);
  finish(job, track(frames, job));
}

VisualLocalization::Job VisualLocalization::begin(double t) {
  if (start_s_ < 0.0) start_s_ = t;
  Job job;
  job.t = t;
  job.at_frames = pose_at(t);  // the fused pose when the frames were taken
  if (tracking_) job.guess = to_iso(last_track_pose_).inverse() * to_iso(job.at_frames);
  last_track_pose_ = job.at_frames;
  tracking_ = true;
  return job;
}

VisualLocalization::Tracked VisualLocalization::track(std::span<const SensorFrame> frames, const Job& job) {
  const double w0 = wall_s();
  Tracked out;
  out.step = odometer_.track(frames, job.guess);
  out.has_keyframe = odometer_.has_keyframe();
  out.time_s = wall_s() - w0;
  return out;
}

void VisualLocalization::finish(const Job& job, const Tracked& tracked) {
  const VisualOdometer::Step& step = tracked.step;
  const Pose2 lag = between(job.at_frames, ekf_.pose());  // the EKF's motion since the frames were taken
  ++stats_.sets;
  stats_.time_s += tracked.time_s;
  if (!tracked.has_keyframe) {  // nothing to track from yet (a blank first view)
    ++stats_.failed;
    ++stats_.too_few_features;
    return;
  }
  if (step.first) {
    ekf_.clone();
    clone_lag_ = lag;
    ++stats_.location_points;
    return;
  }
  stats_.last_inliers = step.result.inliers;
  if (step.result.status != VisualOdometryStatus::kOk) {
    ++stats_.failed;
    switch (step.result.status) {
      case VisualOdometryStatus::kTooFewFeatures: ++stats_.too_few_features; break;
      case VisualOdometryStatus::kTooFewMatches: ++stats_.too_few_matches; break;
      default: ++stats_.too_few_inliers; break;
    }
  } else {
    const Eigen::Isometry3d& M = step.result.motion;  // T_key_curr (3D), between the frames' stamps
    const Eigen::Vector3d z(M.translation().x(), M.translation().y(), std::atan2(M.linear()(1, 0), M.linear()(0, 0)));
    // Carried to the clone's and the EKF's times: z' = lag_clone^-1 * z * lag_now.
    const Eigen::Vector3d d = compose(compose(inverse(vec(clone_lag_)), z), vec(lag));
    const int inliers = static_cast<int>(step.result.inliers);
    // Not fused: between location points (fuse_every_set false), or too few inliers to trust
    // (fuse_min_inliers) - the wheels carry on, and the set still counts for the health.
    const bool fuse = (settings_.fuse_every_set || step.new_keyframe) && inliers >= settings_.fuse_min_inliers;
    bool kept = true;
    if (!fuse) {
      ++stats_.tracked_not_fused;
    } else if (ekf_.update_visual(d, planar_covariance(M, step.result.covariance), inliers >= settings_.learn_wheels_min_inliers)) {
      ++stats_.accepted;
      stats_.wheel_scale = ekf_.wheel_scale();
      stats_.wheel_scale_min = std::min(stats_.wheel_scale_min, stats_.wheel_scale);
      stats_.wheel_scale_max = std::max(stats_.wheel_scale_max, stats_.wheel_scale);
      stats_.wheel_bias = ekf_.wheel_bias();
      stats_.mean_nis += (ekf_.last_visual_chi2() - stats_.mean_nis) / static_cast<double>(stats_.accepted);
    } else {
      ++stats_.gated;
      last_gated_s_ = job.t;
      kept = false;
    }
    if (kept && inliers >= settings_.good_min_inliers) last_ok_s_ = job.t;
  }
  if (step.new_keyframe) {
    ekf_.clone();
    clone_lag_ = lag;
    ++stats_.location_points;
    stats_.resets += step.reset ? 1 : 0;
    if (step.reset) last_reset_s_ = job.t;
  }
}

bool VisualLocalization::confirms_odometry(double now_s) const noexcept {
  const auto long_ago = [&](double t) { return t < 0.0 || now_s - t > settings_.lost_after_s; };
  return health(now_s) == LocalizationHealth::kGood && long_ago(last_gated_s_) && long_ago(last_reset_s_);
}

LocalizationHealth VisualLocalization::health(double now_s) const noexcept {
  const double since = last_ok_s_ >= 0.0 ? now_s - last_ok_s_ : (start_s_ >= 0.0 ? now_s - start_s_ : 0.0);
  if (since > settings_.lost_after_s) return LocalizationHealth::kLost;
  if (since > settings_.degraded_after_s) return LocalizationHealth::kDegraded;
  return LocalizationHealth::kGood;
}

}  // namespace duet
