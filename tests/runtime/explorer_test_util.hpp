#pragma once
// Shared by the explorer's tests (test_explorer.cpp, test_explorer_motion.cpp): the clearance the
// dynamic window needs, whether a goal fits it, and the explorer's first decision in half_known_room().
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/navigation/explorer.hpp>

#include "half_known_room.hpp"

namespace duet_test {

inline float needed_clearance(const duet::Profile& p) {
  return p.exploration.dwa.robot_radius_m + p.exploration.dwa.safety_margin_m;
}

// The goal's cell is traversable and clear of obstacles by more than `needed`.
inline bool fits(const duet::Explorer& e, const duet::Pose2& goal, float needed) {
  Eigen::Vector2i c;
  if (!e.inflated().cell_of(Eigen::Vector2f(goal.x, goal.y), c)) return false;
  const std::size_t i = e.inflated().index(c.x(), c.y());
  return e.inflated().traversable[i] != 0 && e.local_grid().clearance_m[i] > needed;
}

// The explorer's first decision in half_known_room(), from (1.0, 1.5) facing +x.
inline void decide_in_half_known_room(duet::Explorer& e) {
  const duet::Pose2 robot{1.0f, 1.5f, 0.0f};
  e.update_map(half_known_room(), robot, 0.0);
  (void)e.control(robot, duet::Twist{}, 0.0);
}

}  // namespace duet_test
