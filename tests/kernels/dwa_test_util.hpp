#pragma once
// Shared by the dynamic window's tests (test_dwa.cpp: scenarios, closed loops, errors, workspace;
// test_dwa_reference.cpp: against the brute-force reference, thread counts): hand-made grids whose
// clearance is built by brute force, the plain collision check of a command, the window's
// limits, and bitwise equality of two results.
#include "kernel_test_util.hpp"

#include <duet/kernels/dwa.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <vector>

namespace duet {
namespace dwa_test {

using test::kInf;
using test::kNaN;
using V2 = Eigen::Vector2f;
inline constexpr float kPi = std::numbers::pi_v<float>;

// ---- hand-made grids -------------------------------------------------------------------------

struct TestGrid {
  int w = 0, h = 0;
  float res = 0.05f;
  V2 origin{0.0f, 0.0f};
  std::vector<char> blocked;
  std::vector<float> clearance;

  TestGrid(int w_, int h_, float res_, V2 o) : w(w_), h(h_), res(res_), origin(o), blocked(static_cast<std::size_t>(w_ * h_), 0) {}
  V2 center(int x, int y) const { return origin + V2((x + 0.5f) * res, (y + 0.5f) * res); }
  void block(int x, int y) {
    if (x >= 0 && y >= 0 && x < w && y < h) blocked[static_cast<std::size_t>(y * w + x)] = 1;
  }
  /// Blocks every cell whose centre lies in the world rectangle [x0, x1] x [y0, y1].
  void block_rect(float x0, float y0, float x1, float y1) {
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const V2 c = center(x, y);
        if (c.x() >= x0 && c.x() <= x1 && c.y() >= y0 && c.y() <= y1) block(x, y);
      }
  }
  /// Brute force: distance between cell centres to the nearest blocked cell (10 m if none).
  void build() {
    std::vector<V2> b;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        if (blocked[static_cast<std::size_t>(y * w + x)]) b.push_back(center(x, y));
    clearance.assign(static_cast<std::size_t>(w * h), 10.0f);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const V2 c = center(x, y);
        float best = 10.0f;
        for (const V2& q : b) best = std::min(best, (q - c).norm());
        clearance[static_cast<std::size_t>(y * w + x)] = best;
      }
  }
  ClearanceView view() const {
    ClearanceView v;
    v.clearance_m = clearance;
    v.width = w;
    v.height = h;
    v.resolution_m = res;
    v.origin = origin;
    return v;
  }
};

/// A corridor along x: walls below y = y0 and above y = y1, closed at x0 and x1 when asked.
inline TestGrid corridor(float length, float width, bool close_start, bool close_end) {
  const float res = 0.05f;
  const int w = static_cast<int>(std::lround((length + 0.2f) / res)), h = static_cast<int>(std::lround((width + 0.2f) / res));
  TestGrid g(w, h, res, V2(-0.1f, -0.1f));
  g.block_rect(-1.0f, -1.0f, 100.0f, -0.001f);
  g.block_rect(-1.0f, width + 0.001f, 100.0f, 100.0f);
  if (close_start) g.block_rect(-1.0f, -1.0f, -0.001f, 100.0f);
  if (close_end) g.block_rect(length + 0.001f, -1.0f, 100.0f, 100.0f);
  g.build();
  return g;
}

// ---- reference DWA, written plainly from the header ------------------------------------------

/// The plain collision check of a command: motion_step rollout over the horizon.
inline bool ref_collision_free(const ClearanceView& view, Pose2 p, const Twist& u, const DwaSettings& s) {
  const float dt = s.sim_time_s / static_cast<float>(s.steps);
  for (int k = 0; k < s.steps; ++k) {
    p = motion_step(p, u, dt);
    if (!(view.at(p.x, p.y) > s.robot_radius_m + s.safety_margin_m)) return false;
  }
  return true;
}

inline ::testing::AssertionResult in_window(const DwaSettings& s, const Twist& cur, const Twist& cmd) {
  const float eps = 1e-5f;
  const float dv = s.limits.max_accel_mps2 * s.control_period_s;
  const float dw = std::min(s.limits.max_alpha_rps2, s.mapping_max_alpha_rps2) * s.control_period_s;
  const float W = std::min(s.limits.max_omega_rps, s.mapping_max_omega_rps);
  const float wh = s.limits.max_omega_rps;
  // Always within the chassis limits.
  if (cmd.v > s.limits.max_v_mps + eps || cmd.v < s.limits.min_v_mps - eps)
    return ::testing::AssertionFailure() << "v = " << cmd.v << " outside the chassis limits";
  if (std::fabs(cmd.omega) > wh + eps) return ::testing::AssertionFailure() << "omega = " << cmd.omega << " beyond the chassis limit " << wh;
  // Reachable in one period from the measured twist - or, where that is beyond the chassis
  // limits by more than a period's change, the limit itself.
  const bool v_reachable = cur.v <= s.limits.max_v_mps + dv && cur.v >= s.limits.min_v_mps - dv;
  if (v_reachable && std::fabs(cmd.v - cur.v) > dv + eps)
    return ::testing::AssertionFailure() << "|dv| = " << std::fabs(cmd.v - cur.v) << " > " << dv;
  if (!v_reachable && cmd.v != (cur.v > s.limits.max_v_mps ? s.limits.max_v_mps : s.limits.min_v_mps))
    return ::testing::AssertionFailure() << "v = " << cmd.v << " is not the limit nearest " << cur.v;
  const bool w_reachable = std::fabs(cur.omega) <= wh + dw;
  if (w_reachable && std::fabs(cmd.omega - cur.omega) > dw + eps)
    return ::testing::AssertionFailure() << "|domega| = " << std::fabs(cmd.omega - cur.omega) << " > " << dw;
  if (!w_reachable && cmd.omega != std::copysign(wh, cur.omega))
    return ::testing::AssertionFailure() << "omega = " << cmd.omega << " is not the limit nearest " << cur.omega;
  const bool cur_in = cur.v <= s.limits.max_v_mps && cur.v >= s.limits.min_v_mps && std::fabs(cur.omega) <= W;
  if (cur_in && std::fabs(cmd.omega) > W + eps) return ::testing::AssertionFailure() << "omega = " << cmd.omega << " > " << W;
  return ::testing::AssertionSuccess();
}


inline bool same_result(const DwaResult& a, const DwaResult& b) {
  return a.status == b.status && std::memcmp(&a.cmd, &b.cmd, sizeof(Twist)) == 0 &&
         std::memcmp(&a.score, &b.score, sizeof(float)) == 0 && a.valid_trajectories == b.valid_trajectories &&
         a.evaluated_trajectories == b.evaluated_trajectories && a.oscillation == b.oscillation &&
         a.lookahead == b.lookahead;
}

}  // namespace dwa_test
}  // namespace duet
