#pragma once
/// @file controller.hpp
/// The control half of the explorer: at the control rate (20 Hz) it follows the goal and the
/// path the Navigator (navigator.hpp) publishes with the dynamic window (dwa.hpp), and tells the
/// goal life cycle what happened through a GoalLink. Its behaviours are separate pieces
/// (stall_detector.hpp, slow_zone.hpp, escape.hpp), tried in this order each period:
///  - stall: commanded forward, the odometry measures no motion for stall_timeout_s - a
///    contact the sensors cannot see: GoalLink::stall() with a contact point just ahead;
///  - no goal: ask for a decision (GoalLink::decide), zero twist until there is a goal - or,
///    while the navigator finds the robot blocked, creep along its way out to the nearest
///    traversable cell (blocked_escape.hpp), else towards more clearance (escape.hpp);
///  - time limit: the goal's deadline passed - GoalLink::abandon(kTimeout);
///  - feature seeking: where vision sees too few features the top speed is capped, and the
///    robot turns in place towards surfaces that can show some (feature_seek.hpp);
///  - slow zone: the top speed falls with the clearance on the planning grid;
///  - dynamic window on the local grid, falling back to the planning grid when hemmed in by
///    unseen cells;
///  - goal reached: turn to the goal's heading within the paper's motion constraint, then
///    GoalLink::goal_reached(); a goal with a handoff distance (NavPlanState::handoff_m) is
///    reached on the move, within that distance, keeping the window's command;
///  - escape: nothing admissible on either grid (inside the margin) - turn towards more
///    clearance and creep forward (both sensors look forward/right: reversing is blind);
///    still nothing for stuck_timeout_s - GoalLink::abandon(kStuck);
///  - cornered: kept within 0.1 m of one spot for cornered_after_s - escape likewise.
/// Never blocks: the most expensive call is one dynamic window step (~0.1 ms).
/// Frames: map frame. Thread safety: one thread at a time.
#include <duet/kernels/dwa.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/navigation/blocked_escape.hpp>
#include <duet/runtime/navigation/escape.hpp>
#include <duet/runtime/navigation/feature_seek.hpp>
#include <duet/runtime/navigation/navigator.hpp>
#include <duet/runtime/navigation/slow_zone.hpp>
#include <duet/runtime/navigation/stall_detector.hpp>

#include <limits>
#include <optional>

namespace duet {

/// The controller's side of the goal life cycle: the Explorer links it to a Navigator on the
/// same thread; the runtime links it to a Navigator running in the background.
class GoalLink {
 public:
  virtual ~GoalLink() = default;
  /// The plan to follow now (valid until the next call on this link).
  [[nodiscard]] virtual NavPlanView plan() = 0;
  virtual void trail(const Eigen::Vector2f& robot_xy) = 0;
  virtual void stall(const Eigen::Vector2f& contact, double now_s) = 0;
  /// There is no goal: decide one (at once, or as soon as it can; plan() tells).
  virtual void decide(const Pose2& robot, double now_s) = 0;
  virtual void goal_reached(std::uint64_t goal_id, double now_s) = 0;
  virtual void abandon(std::uint64_t goal_id, AbandonReason why, double now_s) = 0;
};

/// Counters of the controller's behaviours (merged into ExplorerStats).
struct ControllerStats {
  int stalls = 0;            ///< stalls detected (contacts passed to GoalLink::stall)
  int local_fallbacks = 0;   ///< periods the dynamic window fell back to the planning grid
  int escapes = 0;           ///< periods spent escaping the dynamic window's margin
  int cornered_escapes = 0;  ///< periods spent escaping a spot (cornered_after_s)
  int blocked_escapes = 0;   ///< periods spent climbing out while blocked (no goal: NavPlanState::blocked)
  int slowed = 0;            ///< periods the slow zone lowered the top speed
  int few_feature_periods = 0;  ///< periods the top speed was capped for vision
  int feature_seeks = 0;        ///< turns towards surfaces with features
};

class Controller {
 public:
  explicit Controller(const Profile& profile, const ExplorerSettings& settings = {});

  /// One control period: `robot` is the pose estimate (map frame), `current` the chassis'
  /// measured twist, now_s the runtime clock. Returns the command (zero when idle or done).
  Twist control(const Pose2& robot, const Twist& current, double now_s, GoalLink& link);

  /// The visual localisation's health (nothing: vision is off), before control() each period.
  void set_localization_health(std::optional<LocalizationHealth> h, double now_s) noexcept { seek_.set_health(h, now_s); }

  /// The map frame moved by D (loop closure).
  void shift(const Pose2& D);

  [[nodiscard]] const ControllerStats& stats() const noexcept { return stats_; }
  [[nodiscard]] const Twist& last_command() const noexcept { return last_cmd_; }

 private:
  Twist follow(const Pose2& robot, const Twist& current, double now_s, GoalLink& link);

  Profile profile_;
  ExplorerSettings settings_;
  StallDetector stall_;
  SlowZone slow_zone_;
  CorneredWatch cornered_;
  FeatureSeek seek_;
  Twist last_cmd_;
  double stuck_since_s_ = -1.0;
  std::uint64_t goal_id_ = 0;  ///< the goal the state below belongs to
  DwaState dwa_state_;
  DwaWorkspace dwa_ws_;
  ControllerStats stats_;
};

}  // namespace duet
