#pragma once
/// @file stall_detector.hpp
/// A controller behaviour: a contact the sensors cannot see. Commanded forward (>= 0.03 m/s)
/// while the odometry measures no motion (< 0.01 m/s) for stall_timeout_s, the robot is pushing
/// against something: the contact is placed just ahead of the body.
#include <duet/kernels/motion_model.hpp>

#include <Eigen/Core>

#include <optional>

namespace duet {

class StallDetector {
 public:
  /// timeout_s: ExplorerSettings::stall_timeout_s; ahead_m: from the robot's centre to the contact.
  StallDetector(double timeout_s, float ahead_m) : timeout_s_(timeout_s), ahead_m_(ahead_m) {}
  /// One control period: the contact point (map frame) when a stall is detected now, else nothing.
  std::optional<Eigen::Vector2f> update(const Twist& last_command, const Twist& measured, const Pose2& robot, double now_s);

 private:
  double timeout_s_;
  float ahead_m_;
  double since_s_ = -1.0;  ///< when the stall began (< 0: not stalled)
};

}  // namespace duet
