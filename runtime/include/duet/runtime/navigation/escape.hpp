#pragma once
/// @file escape.hpp
/// Controller behaviours for a robot the dynamic window cannot move:
///  - Escape: nothing admissible (the robot sits inside the window's margin, or is cornered):
///    turn towards the largest clearance among the cells two cells away, then creep forward at
///    0.1 m/s (both sensors look forward and right: reversing is blind);
///  - CorneredWatch: the robot has stayed within 0.1 m of one spot for cornered_after_s (at the
///    edge of the traversable band every forward motion reachable from the spin leaves it).
/// turn_in_place() is the rotation both use, within the paper's motion constraint.
#include <duet/kernels/dwa.hpp>
#include <duet/kernels/inflation.hpp>

#include <Eigen/Core>

#include <limits>
#include <optional>

namespace duet {

/// Rotation in place towards a heading error `err` [rad], within the paper's bounded |omega| and
/// |domega/dt| (the dynamic window's mapping limits).
[[nodiscard]] Twist turn_in_place(float err, const Twist& current, const DwaSettings& ds);

/// `a` wrapped to [-pi, pi].
[[nodiscard]] float wrap_angle(float a);

class Escape {
 public:
  /// The escape twist on grid `g`; nothing when no cell two cells away has more clearance than
  /// the robot's cell, or (not `cornered`) the robot is outside the dynamic window's margin.
  [[nodiscard]] static std::optional<Twist> step(const Pose2& robot, const Twist& current, const InflatedGrid& g, bool cornered,
                                                 const DwaSettings& ds);
};

class CorneredWatch {
 public:
  explicit CorneredWatch(float cornered_after_s) : after_s_(cornered_after_s) {}
  /// One control period of dt_s at `here` (map frame): true when cornered (never when
  /// cornered_after_s <= 0).
  bool update(const Eigen::Vector2f& here, float dt_s);
  void reset() { seconds_ = 0.0f; }
  /// The map frame moved by D (loop closure).
  void shift(const Pose2& D);

 private:
  static constexpr float kRadius = 0.10f;  ///< "one spot" [m]
  float after_s_;
  float seconds_ = 0.0f;
  Eigen::Vector2f at_{std::numeric_limits<float>::infinity(), 0.0f};
};

}  // namespace duet
