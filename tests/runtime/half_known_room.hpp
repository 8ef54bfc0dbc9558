#pragma once
// A hand-made map shared by the navigation tests: a 5 x 3 m room (0.05 m cells) known free for
// x < 4 m and never observed (NaN) beyond - one straight frontier; and the profile whose decision
// there is the frontier goal (Procedure 1 off).
#include <duet/kernels/grid.hpp>
#include <duet/runtime/config/profile.hpp>

namespace duet_test {

inline constexpr float kRoomRes = 0.05f;

inline duet::OccupancyGrid half_known_room() {
  duet::OccupancyGrid g(kRoomRes, Eigen::Vector2f(0.0f, 0.0f), 100, 60);
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < 80; ++x) g.logodds()[g.index(x, y)] = -2.0f;
  return g;
}

inline duet::Profile frontier_only_profile() {
  duet::Profile p = duet::builtin_profile("dual_kinect_kobuki");
  p.exploration.strategy.use_simulation = false;  // the frontier goal: a cell that borders unknown space
  return p;
}

}  // namespace duet_test
