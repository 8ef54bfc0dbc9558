#include <duet/kernels/error.hpp>
#include <duet/runtime/localization/visual_odometer.hpp>

#include <cmath>
#include <string>
#include <utility>

namespace duet {

void validate(const VisualOdometerSettings& s) {
  validate(s.frame);
  validate(s.odometry);
  const std::string w = "visual odometer settings: ";
  if (!(s.keyframe_translation_m > 0.0f && s.keyframe_translation_m <= 10.0f))
    fail(ErrorCode::kInvalidArgument, w + "keyframe_translation_m must be in (0, 10], got " + std::to_string(s.keyframe_translation_m));
  if (!(s.keyframe_rotation_deg > 0.0f && s.keyframe_rotation_deg <= 180.0f))
    fail(ErrorCode::kInvalidArgument, w + "keyframe_rotation_deg must be in (0, 180], got " + std::to_string(s.keyframe_rotation_deg));
  if (!(s.keyframe_inlier_ratio >= 0.0f && s.keyframe_inlier_ratio <= 1.0f))
    fail(ErrorCode::kInvalidArgument, w + "keyframe_inlier_ratio must be in [0, 1], got " + std::to_string(s.keyframe_inlier_ratio));
  if (s.reset_after_failures < 1 || s.reset_after_failures > 1000)
    fail(ErrorCode::kInvalidArgument, w + "reset_after_failures must be in [1, 1000], got " + std::to_string(s.reset_after_failures));
}

VisualOdometer::VisualOdometer(const VisualOdometerSettings& settings) : settings_((validate(settings), settings)) {}

void VisualOdometer::reset() {
  has_key_ = false;
  key_.cameras.clear();
  pose_ = key_pose_ = key_to_last_ = Eigen::Isometry3d::Identity();
  key_reference_inliers_ = 0;
  failures_in_row_ = 0;
}

VisualOdometer::Step VisualOdometer::track(std::span<const SensorFrame> frames, const Eigen::Isometry3d& guess) {
  if (has_key_ && frames.size() != key_.cameras.size())
    fail(ErrorCode::kInvalidArgument, "visual odometer: " + std::to_string(frames.size()) + " frames, the location point has " +
                                          std::to_string(key_.cameras.size()) + " cameras");
  make_visual_frame(frames, settings_.frame, current_);
  Step step;
  step.increment = guess;
  if (!has_key_) {
    if (current_.features_with_depth() < 2 * static_cast<std::size_t>(settings_.odometry.min_inliers)) {
      ++failed_;  // nothing to track from: the next frame gets its chance to be the first
      step.result.status = VisualOdometryStatus::kTooFewFeatures;
      return step;
    }
    std::swap(key_, current_);
    has_key_ = true;
    step.first = step.new_keyframe = true;
    step.result.status = VisualOdometryStatus::kOk;
    step.increment = Eigen::Isometry3d::Identity();
    ++keyframes_;
    return step;
  }
  const Eigen::Isometry3d key_guess = key_to_last_ * guess;  // T_key_curr from the wheels
  step.result = estimate_motion(key_, current_, key_guess, settings_.odometry);
  if (step.result.status != VisualOdometryStatus::kOk) {
    ++failed_;
    ++failures_in_row_;
    key_to_last_ = key_guess;
    pose_ = key_pose_ * key_to_last_;
    const double moved = key_guess.translation().norm();
    const double turned = Eigen::AngleAxisd(key_guess.linear()).angle() * 180.0 / 3.14159265358979323846;
    const bool gone = failures_in_row_ >= settings_.reset_after_failures || moved >= settings_.keyframe_translation_m ||
                      turned >= settings_.keyframe_rotation_deg;
    if (gone && current_.features_with_depth() >= 2 * static_cast<std::size_t>(settings_.odometry.min_inliers)) {
      std::swap(key_, current_);
      key_pose_ = pose_;
      key_to_last_ = Eigen::Isometry3d::Identity();
      key_reference_inliers_ = 0;
      failures_in_row_ = 0;
      step.new_keyframe = step.reset = true;
      ++keyframes_;
      ++resets_;
    }
    return step;
  }
  failures_in_row_ = 0;
  ++tracked_;
  const Eigen::Isometry3d& key_curr = step.result.motion;
  step.increment = key_to_last_.inverse() * key_curr;
  key_to_last_ = key_curr;
  pose_ = key_pose_ * key_curr;
  if (key_reference_inliers_ == 0) key_reference_inliers_ = step.result.inliers;
  const double moved = key_curr.translation().norm();
  const double turned = Eigen::AngleAxisd(key_curr.linear()).angle() * 180.0 / 3.14159265358979323846;
  const bool weak = static_cast<double>(step.result.inliers) <
                    static_cast<double>(settings_.keyframe_inlier_ratio) * static_cast<double>(key_reference_inliers_);
  if (moved >= settings_.keyframe_translation_m || turned >= settings_.keyframe_rotation_deg || weak) {
    std::swap(key_, current_);
    key_pose_ = pose_;
    key_to_last_ = Eigen::Isometry3d::Identity();
    key_reference_inliers_ = 0;
    step.new_keyframe = true;
    ++keyframes_;
  }
  return step;
}

}  // namespace duet
