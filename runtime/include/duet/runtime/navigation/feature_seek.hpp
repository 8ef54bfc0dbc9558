#pragma once
/// @file feature_seek.hpp
/// A controller behaviour for places with few visual features (paper §2.3: "A robot may pass by
/// a region with few visual features ... the mobile robot can execute autonomous motion ...
/// this changes the FoV of the dual RGB-D sensors in order to obtain more environment
/// information"). Fed the visual localisation's health every period (localization_health.hpp;
/// nothing when vision is off, and then the behaviour never acts):
///  - degraded or lost: the top speed is capped at few_features_speed_mps. The wheels carry the
///    pose meanwhile: slower is less drift before vision returns, and more overlap between views;
///  - not good for seek_after_s: one turn in place towards the nearest direction, at least
///    seek_min_turn_rad away from the current heading, in which the planning grid shows an
///    obstacle between seek_min_range_m and seek_range_m - surfaces at a depth the cameras
///    measure, where features can be (the view ahead shows none). No such direction: a quarter
///    turn to the left. The turn ends as soon as the health is good again or the heading is
///    reached; then seek_cooldown_s passes before the next one (the robot goes on, slowly, on its
///    wheels: it is never held in place).
/// A turn in place keeps the round footprint where it is: it cannot collide.
/// Frames: map frame. Thread safety: one thread at a time. Never blocks (one fan of 24 rays).
#include <duet/kernels/dwa.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/runtime/localization/localization_health.hpp>
#include <duet/runtime/navigation/explorer_settings.hpp>

#include <optional>

namespace duet {

class FeatureSeek {
 public:
  explicit FeatureSeek(const ExplorerSettings& s) : s_(s) {}

  /// The localisation's health now (nothing: vision is off).
  void set_health(std::optional<LocalizationHealth> h, double now_s) noexcept;
  /// The top speed [m/s]: v_max, or the cap while the health is not good.
  [[nodiscard]] float speed_limit(float v_max) const noexcept;
  /// The turn to make this period, or nothing (follow the plan).
  [[nodiscard]] std::optional<Twist> step(const Pose2& robot, const Twist& current, const InflatedGrid& planning,
                                          const DwaSettings& ds, double now_s);
  /// Turns started so far.
  [[nodiscard]] int seeks() const noexcept { return seeks_; }
  /// True while a turn is under way.
  [[nodiscard]] bool turning() const noexcept { return target_.has_value(); }

  /// The heading [rad, map frame] a seek from `robot` would turn to (see above).
  [[nodiscard]] float seek_heading(const Pose2& robot, const InflatedGrid& planning) const;

 private:
  ExplorerSettings s_;
  std::optional<LocalizationHealth> health_;
  double not_good_since_s_ = -1.0;
  double last_seek_end_s_ = -1e300;
  std::optional<float> target_;  ///< the heading of the turn under way
  int seeks_ = 0;
};

}  // namespace duet
