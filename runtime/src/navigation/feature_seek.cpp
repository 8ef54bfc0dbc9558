/// @file feature_seek.cpp
/// FeatureSeek: slow down and turn towards surfaces where vision sees nothing (feature_seek.hpp).
#include <duet/runtime/navigation/escape.hpp>
#include <duet/runtime/navigation/feature_seek.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace duet {

void FeatureSeek::set_health(std::optional<LocalizationHealth> h, double now_s) noexcept {
  health_ = h;
  if (!h || *h == LocalizationHealth::kGood) {
    not_good_since_s_ = -1.0;
    if (target_) {  // features in view again: the turn has done its job
      target_.reset();
      last_seek_end_s_ = now_s;
    }
  } else if (not_good_since_s_ < 0.0) {
    not_good_since_s_ = now_s;
  }
}

float FeatureSeek::speed_limit(float v_max) const noexcept {
  if (!health_ || *health_ == LocalizationHealth::kGood || s_.few_features_speed_mps <= 0.0f) return v_max;
  return std::min(v_max, s_.few_features_speed_mps);
}

float FeatureSeek::seek_heading(const Pose2& robot, const InflatedGrid& g) const {
  constexpr int kRays = 24;  // every 15 deg
  const float two_pi = 2.0f * std::numbers::pi_v<float>;
  float best_turn = std::numeric_limits<float>::infinity(), best = robot.theta + 0.5f * std::numbers::pi_v<float>;
  const float step = 0.5f * g.resolution_m;
  for (int k = 0; k < kRays; ++k) {
    const float a = wrap_angle(two_pi * static_cast<float>(k) / kRays);  // relative to the heading
    if (std::fabs(a) < s_.seek_min_turn_rad) continue;
    const float th = robot.theta + a, c = std::cos(th), sn = std::sin(th);
    for (float r = s_.seek_min_range_m; r <= s_.seek_range_m; r += step) {
      Eigen::Vector2i cell;
      if (!g.cell_of(Eigen::Vector2f(robot.x + r * c, robot.y + r * sn), cell)) break;
      const CellState st = g.state[g.index(cell.x(), cell.y())];
      if (st == CellState::kOccupied) {
        if (std::fabs(a) < best_turn) {  // the smallest turn; ties: the left one (k ascending, a > 0 first)
          best_turn = std::fabs(a);
          best = th;
        }
        break;
      }
    }
  }
  return wrap_angle(best);
}

std::optional<Twist> FeatureSeek::step(const Pose2& robot, const Twist& current, const InflatedGrid& planning,
                                       const DwaSettings& ds, double now_s) {
  if (s_.seek_after_s <= 0.0f || not_good_since_s_ < 0.0) return std::nullopt;
  if (!target_) {
    if (now_s - not_good_since_s_ < s_.seek_after_s || now_s - last_seek_end_s_ < s_.seek_cooldown_s) return std::nullopt;
    target_ = seek_heading(robot, planning);
    ++seeks_;
  }
  const float err = wrap_angle(*target_ - robot.theta);
  if (std::fabs(err) < 0.1f) {
    target_.reset();
    last_seek_end_s_ = now_s;
    return std::nullopt;
  }
  return turn_in_place(err, current, ds);
}

}  // namespace duet
