// Dynamic window (dwa.hpp) against a brute-force reference DWA written plainly here from the
// header's definition (same sampling and scoring, rollout by repeated motion_step with sin/cos,
// no early exit, path geometry recomputed independently), on hand-made grids whose clearance is
// built by brute force (distance between cell centres to every blocked cell). Also scenarios
// (corridor, corner, boxed in, dead end, oscillation, goal, no path), closed-loop runs, the
// paper's motion constraint, errors, thread counts, workspace reuse.
#include "kernel_test_util.hpp"

#include <duet/kernels/dwa.hpp>
#include <duet/kernels/error.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <vector>

namespace duet {
namespace test_dwa {

using test::kInf;
using test::kNaN;
using V2 = Eigen::Vector2f;
constexpr float kPi = std::numbers::pi_v<float>;

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
TestGrid corridor(float length, float width, bool close_start, bool close_end) {
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

struct RefGeometry {
  V2 L;
  std::vector<V2> local;  // P ... L
};

RefGeometry ref_geometry(const std::vector<V2>& path, V2 p, float lookahead) {
  // closest point: first segment wins a tie
  int seg = 0;
  V2 P = path[0];
  if (path.size() > 1) {
    double best = 1e300;
    for (std::size_t s = 0; s + 1 < path.size(); ++s) {
      const V2 a = path[s], b = path[s + 1];
      const V2 d = b - a;
      float t = 0.0f;
      if (d.squaredNorm() > 0.0f) t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0f, 1.0f);
      const V2 q = a + t * d;
      if ((q - p).squaredNorm() < best) {
        best = (q - p).squaredNorm();
        seg = static_cast<int>(s);
        P = q;
      }
    }
  }
  RefGeometry g;
  g.local.push_back(P);
  float left = lookahead;
  V2 cur = P;
  for (std::size_t s = static_cast<std::size_t>(seg); s + 1 < path.size(); ++s) {
    const float len = (path[s + 1] - cur).norm();
    if (len >= left) {
      g.local.push_back(cur + (path[s + 1] - cur) * (left / len));
      g.L = g.local.back();
      return g;
    }
    left -= len;
    cur = path[s + 1];
    g.local.push_back(cur);
  }
  g.L = g.local.back();
  return g;
}

float ref_dist_polyline(const std::vector<V2>& pl, V2 p) {
  if (pl.size() == 1) return (p - pl[0]).norm();
  float best = kInf;
  for (std::size_t s = 0; s + 1 < pl.size(); ++s) {
    const V2 a = pl[s], d = pl[s + 1] - pl[s];
    float t = 0.0f;
    if (d.squaredNorm() > 0.0f) t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0f, 1.0f);
    best = std::min(best, (a + t * d - p).norm());
  }
  return best;
}

struct RefWindow {
  float v_lo, v_hi, w_lo, w_hi;
};

RefWindow ref_window(const DwaSettings& s, const Twist& c) {
  const float dv = s.limits.max_accel_mps2 * s.control_period_s;
  const float dw = std::min(s.limits.max_alpha_rps2, s.mapping_max_alpha_rps2) * s.control_period_s;
  const float W = std::min(s.limits.max_omega_rps, s.mapping_max_omega_rps);
  RefWindow r;
  r.v_lo = std::max(s.limits.min_v_mps, c.v - dv);
  r.v_hi = std::min(s.limits.max_v_mps, c.v + dv);
  if (r.v_lo > r.v_hi) r.v_lo = r.v_hi = (c.v > s.limits.max_v_mps ? c.v - dv : c.v + dv);  // one reachable value
  r.w_lo = std::max(-W, c.omega - dw);
  r.w_hi = std::min(W, c.omega + dw);
  if (r.w_lo > r.w_hi) r.w_lo = r.w_hi = (c.omega > W ? c.omega - dw : c.omega + dw);
  // Never beyond the chassis limits, whatever the measured twist.
  const float wh = s.limits.max_omega_rps;
  r.v_lo = std::clamp(r.v_lo, s.limits.min_v_mps, s.limits.max_v_mps);
  r.v_hi = std::clamp(r.v_hi, s.limits.min_v_mps, s.limits.max_v_mps);
  r.w_lo = std::clamp(r.w_lo, -wh, wh);
  r.w_hi = std::clamp(r.w_hi, -wh, wh);
  return r;
}

float ref_sample(float lo, float hi, int n, int i) {
  return n == 1 ? 0.5f * (lo + hi) : lo + (hi - lo) * (static_cast<float>(i) / static_cast<float>(n - 1));
}

/// Plain rollout: motion_step (sin/cos) every step, no early exit. nullopt = inadmissible.
std::optional<float> ref_score(const ClearanceView& view, const Pose2& pose, float v, float w, const RefGeometry& g,
                               const DwaSettings& s) {
  const float thr = s.robot_radius_m + s.safety_margin_m;
  const float dt = s.sim_time_s / static_cast<float>(s.steps);
  Pose2 p = pose;
  float cmin = kInf;
  bool ok = true;
  for (int k = 0; k < s.steps; ++k) {
    p = motion_step(p, Twist{v, w}, dt);
    const float c = view.at(p.x, p.y);
    if (!(c > thr)) ok = false;
    cmin = std::min(cmin, c);
  }
  if (!ok) return std::nullopt;
  const V2 e(p.x, p.y), p0(pose.x, pose.y);
  const float progress = (p0 - g.L).norm() - (e - g.L).norm();
  return s.w_progress * progress - s.w_path * ref_dist_polyline(g.local, e) +
         s.w_clearance * std::min(cmin - thr, s.clearance_cap_m) + s.w_speed * v;
}

struct RefBest {
  bool any = false;
  float v = 0, w = 0, score = -kInf;
  int valid = 0;
};

RefBest ref_dwa(const ClearanceView& view, const Pose2& pose, const Twist& cur, const std::vector<V2>& path,
                const DwaSettings& s) {
  const RefGeometry g = ref_geometry(path, V2(pose.x, pose.y), s.lookahead_m);
  const RefWindow win = ref_window(s, cur);
  RefBest b;
  for (int i = 0; i < s.v_samples; ++i)
    for (int j = 0; j < s.omega_samples; ++j) {
      const float v = ref_sample(win.v_lo, win.v_hi, s.v_samples, i);
      const float w = ref_sample(win.w_lo, win.w_hi, s.omega_samples, j);
      const auto sc = ref_score(view, pose, v, w, g, s);
      if (!sc) continue;
      ++b.valid;
      if (!b.any || *sc > b.score) b = RefBest{true, v, w, *sc, b.valid};
    }
  return b;
}

/// The plain collision check of a command: motion_step rollout over the horizon.
bool ref_collision_free(const ClearanceView& view, Pose2 p, const Twist& u, const DwaSettings& s) {
  const float dt = s.sim_time_s / static_cast<float>(s.steps);
  for (int k = 0; k < s.steps; ++k) {
    p = motion_step(p, u, dt);
    if (!(view.at(p.x, p.y) > s.robot_radius_m + s.safety_margin_m)) return false;
  }
  return true;
}

::testing::AssertionResult in_window(const DwaSettings& s, const Twist& cur, const Twist& cmd) {
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

// ---- random cases --------------------------------------------------------------------------------

struct RandomCase {
  TestGrid grid{1, 1, 0.05f, V2::Zero()};
  Pose2 pose;
  Twist cur;
  std::vector<V2> path;
  DwaSettings s;
};

RandomCase random_case(std::mt19937& rng, bool vary_settings) {
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  auto uni = [&](float a, float b) { return a + (b - a) * u01(rng); };
  RandomCase c;
  const float res = u01(rng) < 0.7f ? 0.05f : 0.04f;
  const int n = 40 + static_cast<int>(u01(rng) * 16.0f);
  c.grid = TestGrid(n, n, res, V2(uni(-2.0f, 1.0f), uni(-2.0f, 1.0f)));
  const float size = n * res;
  const V2 o = c.grid.origin;
  const int n_obs = 2 + static_cast<int>(u01(rng) * 7.0f);
  for (int k = 0; k < n_obs; ++k) {
    const float x = o.x() + uni(0.0f, size), y = o.y() + uni(0.0f, size);
    const float ex = uni(0.02f, 0.4f), ey = uni(0.02f, 0.4f);
    c.grid.block_rect(x, y, x + ex, y + ey);
  }
  c.grid.build();
  const ClearanceView view = c.grid.view();
  if (vary_settings) {
    const int pick = static_cast<int>(u01(rng) * 6.0f);
    if (pick == 0) {
      c.s.v_samples = 1;
      c.s.omega_samples = 1;
      c.s.steps = 1;
    } else if (pick == 1) {
      c.s.v_samples = 7;
      c.s.omega_samples = 11;
      c.s.steps = 13;
      c.s.sim_time_s = 2.0f;
    } else if (pick == 2) {
      c.s.mapping_max_omega_rps = 2.5f;  // chassis and mapping limits swap roles
      c.s.mapping_max_alpha_rps2 = 5.0f;
      c.s.limits.max_omega_rps = 1.2f;
      c.s.limits.max_alpha_rps2 = 2.0f;
      c.s.control_period_s = 0.2f;
    } else if (pick == 3) {
      c.s.w_path = 2.0f;
      c.s.w_clearance = 1.0f;
      c.s.w_speed = 0.0f;
      c.s.lookahead_m = 0.4f;
    }
  }
  const float thr = c.s.robot_radius_m + c.s.safety_margin_m;
  // Pose: mostly where the robot fits (rejection sampling), sometimes anywhere.
  const bool anywhere = u01(rng) < 0.15f;
  for (int tries = 0; tries < 100; ++tries) {
    c.pose = Pose2{o.x() + uni(0.0f, size), o.y() + uni(0.0f, size), uni(-kPi, kPi)};
    if (anywhere || view.at(c.pose.x, c.pose.y) > thr) break;
  }
  const float W = std::min(c.s.limits.max_omega_rps, c.s.mapping_max_omega_rps);
  c.cur = Twist{uni(c.s.limits.min_v_mps, c.s.limits.max_v_mps), uni(-W, W)};
  if (u01(rng) < 0.05f) c.cur = Twist{c.s.limits.max_v_mps + 0.2f, 1.5f * W};  // beyond the limits
  if (u01(rng) < 0.2f) c.cur = Twist{};
  const int np = 1 + static_cast<int>(u01(rng) * 5.0f);
  for (int k = 0; k < np; ++k) c.path.push_back(V2(o.x() + uni(0.0f, size), o.y() + uni(0.0f, size)));
  if (u01(rng) < 0.5f) c.path.insert(c.path.begin(), V2(c.pose.x, c.pose.y));
  return c;
}

// ---- property test against the reference ---------------------------------------------------------

TEST(Dwa, MatchesReferenceOnRandomGrids) {
  std::mt19937 rng(20190722);
  const int cases = test::full_or(400, 120);
  int ok_cases = 0, none_cases = 0, goal_cases = 0;
  for (int t = 0; t < cases; ++t) {
    SCOPED_TRACE("case " + std::to_string(t));
    const RandomCase c = random_case(rng, true);
    const ClearanceView view = c.grid.view();
    DwaState state;
    DwaWorkspace ws;
    const DwaResult r = dwa_step(view, c.pose, c.cur, c.path, c.s, state, ws);
    if (r.status == DwaStatus::kGoalReached) {
      ++goal_cases;
      EXPECT_LE((V2(c.pose.x, c.pose.y) - c.path.back()).norm(), c.s.goal_tolerance_m);
      continue;
    }
    EXPECT_GT((V2(c.pose.x, c.pose.y) - c.path.back()).norm(), c.s.goal_tolerance_m);
    const RefBest ref = ref_dwa(view, c.pose, c.cur, c.path, c.s);
    EXPECT_EQ(r.evaluated_trajectories, c.s.v_samples * c.s.omega_samples);
    EXPECT_EQ(r.valid_trajectories, ref.valid);
    const RefGeometry g = ref_geometry(c.path, V2(c.pose.x, c.pose.y), c.s.lookahead_m);
    EXPECT_LT((r.lookahead - g.L).norm(), 1e-5f);
    if (r.status == DwaStatus::kOk) {
      ++ok_cases;
      ASSERT_TRUE(ref.any) << "kernel found an admissible trajectory the reference did not";
      EXPECT_TRUE(ref_collision_free(view, c.pose, r.cmd, c.s)) << "v " << r.cmd.v << " omega " << r.cmd.omega;
      EXPECT_TRUE(in_window(c.s, c.cur, r.cmd));
      const auto sc = ref_score(view, c.pose, r.cmd.v, r.cmd.omega, g, c.s);
      ASSERT_TRUE(sc.has_value());
      const bool same = r.cmd.v == ref.v && r.cmd.omega == ref.w;
      EXPECT_TRUE(same || *sc >= ref.score - 1e-5f)
          << "kernel (" << r.cmd.v << ", " << r.cmd.omega << ") scores " << *sc << ", reference best (" << ref.v
          << ", " << ref.w << ") " << ref.score;
      EXPECT_NEAR(r.score, *sc, 1e-4f);
    } else {
      ++none_cases;
      EXPECT_FALSE(ref.any) << "reference found (" << ref.v << ", " << ref.w << ") but kernel says " << to_string(r.status);
      switch (r.status) {
        case DwaStatus::kRotateInPlace:
          EXPECT_EQ(r.cmd.v, 0.0f);
          EXPECT_GT(view.at(c.pose.x, c.pose.y), c.s.robot_radius_m);
          // omega reachable in a period, or the chassis limit (v is 0 by design: the check takes
          // the measured v within the limits for it)
          EXPECT_TRUE(in_window(c.s, c.cur, Twist{std::clamp(c.cur.v, c.s.limits.min_v_mps, c.s.limits.max_v_mps), r.cmd.omega}));
          break;
        case DwaStatus::kBackOff:
          EXPECT_LT(r.cmd.v, 0.0f);
          for (float d = 0.0f; d <= c.s.backoff_distance_m; d += 0.005f)
            EXPECT_GT(view.at(c.pose.x - d * std::cos(c.pose.theta), c.pose.y - d * std::sin(c.pose.theta)),
                      c.s.robot_radius_m - 1e-6f);
          break;
        case DwaStatus::kNoValidTrajectory:
          EXPECT_EQ(r.cmd.v, 0.0f);
          EXPECT_EQ(r.cmd.omega, 0.0f);
          break;
        default: ADD_FAILURE() << "unexpected status " << to_string(r.status);
      }
    }
  }
  // The random cases must exercise both outcomes (otherwise this test could not fail usefully).
  EXPECT_GT(ok_cases, cases / 3);
  EXPECT_GT(none_cases, 3);
  RecordProperty("ok_cases", ok_cases);
  RecordProperty("none_cases", none_cases);
  RecordProperty("goal_cases", goal_cases);
}

// ---- scenarios -----------------------------------------------------------------------------------

struct LoopStats {
  bool reached = false;
  int steps = 0;
  float min_clearance = kInf;
  float max_abs_omega = 0.0f, max_domega = 0.0f, max_dv = 0.0f;
  int oscillations = 0;
  float max_omega_seen = -kInf;
  Pose2 final_pose;
};

/// Closed loop: the chassis follows each command exactly for one control period (motion_step).
LoopStats closed_loop(const ClearanceView& view, Pose2 pose, const std::vector<V2>& path, const DwaSettings& s,
                      int max_steps) {
  LoopStats st;
  DwaState state;
  DwaWorkspace ws;
  Twist cur;
  for (int k = 0; k < max_steps; ++k) {
    const DwaResult r = dwa_step(view, pose, cur, path, s, state, ws);
    if (r.status == DwaStatus::kGoalReached) {
      st.reached = true;
      break;
    }
    if (r.oscillation) ++st.oscillations;
    st.max_abs_omega = std::max(st.max_abs_omega, std::fabs(r.cmd.omega));
    st.max_omega_seen = std::max(st.max_omega_seen, r.cmd.omega);
    st.max_domega = std::max(st.max_domega, std::fabs(r.cmd.omega - cur.omega));
    st.max_dv = std::max(st.max_dv, std::fabs(r.cmd.v - cur.v));
    pose = motion_step(pose, r.cmd, s.control_period_s);
    cur = r.cmd;
    st.min_clearance = std::min(st.min_clearance, view.at(pose.x, pose.y));
    st.steps = k + 1;
  }
  st.final_pose = pose;
  return st;
}

TEST(Dwa, FreeCorridorDrivesForwardAlongThePath) {
  const TestGrid g = corridor(4.0f, 1.0f, true, true);
  const ClearanceView view = g.view();
  const DwaSettings s;
  const std::vector<V2> path{V2(0.5f, 0.5f), V2(2.0f, 0.5f), V2(3.5f, 0.5f)};
  DwaState state;
  DwaWorkspace ws;
  const DwaResult r = dwa_step(view, Pose2{0.5f, 0.5f, 0.0f}, Twist{}, path, s, state, ws);
  ASSERT_EQ(r.status, DwaStatus::kOk);
  EXPECT_GT(r.cmd.v, 0.04f);  // top of the window [-0.05, 0.05]
  EXPECT_LT(std::fabs(r.cmd.omega), 0.01f);
  EXPECT_EQ(r.valid_trajectories, r.evaluated_trajectories);  // nothing near
  // Moving already: keeps accelerating to the speed limit.
  const DwaResult r2 = dwa_step(view, Pose2{1.0f, 0.5f, 0.0f}, Twist{0.48f, 0.0f}, path, s, state, ws);
  ASSERT_EQ(r2.status, DwaStatus::kOk);
  EXPECT_FLOAT_EQ(r2.cmd.v, 0.5f);

  const LoopStats st = closed_loop(view, Pose2{0.5f, 0.5f, 0.0f}, path, s, 400);
  EXPECT_TRUE(st.reached);
  EXPECT_LT(st.steps, 200);  // 3 m at up to 0.5 m/s: well under 10 s
  EXPECT_GT(st.min_clearance, s.robot_radius_m + s.safety_margin_m);
  EXPECT_LE(st.max_abs_omega, s.mapping_max_omega_rps + 1e-6f);
  EXPECT_LE(st.max_domega, s.mapping_max_alpha_rps2 * s.control_period_s + 1e-5f);
  EXPECT_LE(st.max_dv, s.limits.max_accel_mps2 * s.control_period_s + 1e-5f);
  EXPECT_EQ(st.oscillations, 0);
  EXPECT_LT(std::fabs(st.final_pose.y - 0.5f), 0.1f);
}

/// L-shaped corridor: along +x from (0, 0)-(2, 1), then up along x in [1, 2] to y = 4.
TestGrid l_corridor() {
  TestGrid g(50, 90, 0.05f, V2(-0.25f, -0.25f));
  g.block_rect(-1.0f, -1.0f, 100.0f, -0.001f);   // floor wall
  g.block_rect(-1.0f, -1.0f, -0.001f, 100.0f);   // left end
  g.block_rect(2.001f, -1.0f, 100.0f, 100.0f);   // right wall (ahead of the robot)
  g.block_rect(-1.0f, 1.001f, 0.999f, 100.0f);   // top of the horizontal leg, left of the vertical leg
  g.block_rect(-1.0f, 4.001f, 100.0f, 100.0f);   // far end
  g.build();
  return g;
}

TEST(Dwa, WallAheadAndPathTurningTurns) {
  const TestGrid g = l_corridor();
  const ClearanceView view = g.view();
  const DwaSettings s;
  const std::vector<V2> path{V2(0.3f, 0.5f), V2(1.5f, 0.5f), V2(1.5f, 3.6f)};
  // One step: 0.65 m from the wall ahead at 0.3 m/s, the path turning left.
  DwaState state;
  DwaWorkspace ws;
  const Twist cur{0.3f, 0.0f};
  const DwaResult r = dwa_step(view, Pose2{1.35f, 0.5f, 0.0f}, cur, path, s, state, ws);
  ASSERT_EQ(r.status, DwaStatus::kOk);
  EXPECT_LT(r.valid_trajectories, r.evaluated_trajectories);  // straight on at 0.35 m/s is inadmissible
  EXPECT_FALSE(ref_collision_free(view, Pose2{1.35f, 0.5f, 0.0f}, Twist{0.35f, 0.0f}, s));
  EXPECT_GT(r.cmd.omega, 0.04f);  // turns left as hard as the window allows (0.05)
  EXPECT_TRUE(in_window(s, cur, r.cmd));

  const LoopStats st = closed_loop(view, Pose2{0.3f, 0.5f, 0.0f}, path, s, 600);
  EXPECT_TRUE(st.reached);
  EXPECT_GT(st.min_clearance, s.robot_radius_m + s.safety_margin_m);
  EXPECT_GT(st.max_omega_seen, 0.3f);  // it really turned
  EXPECT_LE(st.max_abs_omega, s.mapping_max_omega_rps + 1e-6f);
  EXPECT_NEAR(st.final_pose.x, 1.5f, 0.15f);
}

TEST(Dwa, MappingConstraintBoundsOmegaAndAlpha) {
  const TestGrid g = corridor(4.0f, 3.0f, false, false);
  const ClearanceView view = g.view();
  // Path straight behind the robot: the best command turns as fast as allowed.
  const std::vector<V2> path{V2(1.0f, 1.5f), V2(1.0f, 2.5f)};
  DwaSettings s;
  DwaState state;
  DwaWorkspace ws;
  const DwaResult r = dwa_step(view, Pose2{1.0f, 1.0f, 0.0f}, Twist{0.0f, 0.78f}, path, s, state, ws);
  ASSERT_EQ(r.status, DwaStatus::kOk);
  EXPECT_FLOAT_EQ(r.cmd.omega, 0.8f);  // capped by mapping_max_omega_rps, not by the chassis' pi
  // Above the mapping bound (e.g. a command of another controller): decelerate by A*T only.
  const DwaResult r2 = dwa_step(view, Pose2{1.0f, 1.0f, 0.0f}, Twist{0.0f, 2.0f}, path, s, state, ws);
  ASSERT_EQ(r2.status, DwaStatus::kOk);
  EXPECT_FLOAT_EQ(r2.cmd.omega, 2.0f - 1.0f * 0.05f);
  // Without the mapping constraint the chassis' alpha gives a wider window.
  s.mapping_max_alpha_rps2 = 100.0f;
  s.mapping_max_omega_rps = 100.0f;
  const DwaResult r3 = dwa_step(view, Pose2{1.0f, 1.0f, 0.0f}, Twist{0.0f, 0.78f}, path, s, state, ws);
  EXPECT_FLOAT_EQ(r3.cmd.omega, 0.78f + 3.0f * 0.05f);
}

TEST(Dwa, CommandStaysWithinTheLimitsWhenTheMeasuredTwistIsBeyondThem) {
  // An odometry glitch of 100 m/s and 100 rad/s (or a push): the window follows the measured
  // twist, the command must not (it gave 99.95 m/s with status OK before).
  const TestGrid g = corridor(4.0f, 3.0f, false, false);
  const ClearanceView view = g.view();
  const std::vector<V2> path{V2(1.0f, 1.5f), V2(3.5f, 1.5f)};
  const DwaSettings s;
  for (const Twist glitch : {Twist{100.0f, 0.0f}, Twist{-100.0f, 0.0f}, Twist{0.0f, 100.0f}, Twist{0.3f, -100.0f}, Twist{1e30f, 1e30f}}) {
    DwaState state;
    DwaWorkspace ws;
    for (const V2& at : {V2(1.0f, 1.5f), V2(1.0f, 0.2f)}) {  // free, and near the wall (recovery)
      const DwaResult r = dwa_step(view, Pose2{at.x(), at.y(), 0.0f}, glitch, path, s, state, ws);
      EXPECT_GE(r.cmd.v, s.limits.min_v_mps) << glitch.v << " " << glitch.omega;
      EXPECT_LE(r.cmd.v, s.limits.max_v_mps) << glitch.v << " " << glitch.omega;
      EXPECT_LE(std::fabs(r.cmd.omega), s.limits.max_omega_rps) << glitch.v << " " << glitch.omega;
    }
  }
}

TEST(Dwa, BoxedInWithoutRoomGivesNoValidTrajectory) {
  // A ring of blocked cells 0.15 m around the robot: the footprint already touches.
  TestGrid g(40, 40, 0.05f, V2(-1.0f, -1.0f));
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x) {
      const float r = g.center(x, y).norm();
      if (r > 0.15f && r < 0.25f) g.block(x, y);
    }
  g.build();
  const ClearanceView view = g.view();
  const DwaSettings s;
  DwaState state;
  DwaWorkspace ws;
  const std::vector<V2> path{V2(0.0f, 0.0f), V2(0.8f, 0.0f)};
  const DwaResult r = dwa_step(view, Pose2{0.025f, 0.025f, 0.0f}, Twist{0.2f, 0.1f}, path, s, state, ws);
  EXPECT_EQ(r.status, DwaStatus::kNoValidTrajectory);
  EXPECT_EQ(r.cmd.v, 0.0f);
  EXPECT_EQ(r.cmd.omega, 0.0f);
  EXPECT_EQ(r.valid_trajectories, 0);
  EXPECT_EQ(r.evaluated_trajectories, 800);
}

TEST(Dwa, DeadEndBacksOffThenRotates) {
  // 0.56 m wide dead end closed at x = 2: the robot is inside the safety margin of the end wall.
  const TestGrid g = corridor(2.0f, 0.56f, true, true);
  const ClearanceView view = g.view();
  DwaSettings s;
  s.safety_margin_m = 0.06f;  // clearance of the pose's cell: 0.25 m (cell centres 0.25 m from the end wall)
  const Pose2 pose{1.78f, 0.28f, 0.0f};
  const float c0 = view.at(pose.x, pose.y);
  ASSERT_GT(c0, s.robot_radius_m);
  ASSERT_LE(c0, s.robot_radius_m + s.safety_margin_m);
  {  // Stale path straight through the end wall: aligned, so back off.
    const std::vector<V2> path{V2(1.0f, 0.28f), V2(3.0f, 0.28f)};
    DwaState state;
    DwaWorkspace ws;
    Pose2 p = pose;
    Twist cur;
    DwaResult r = dwa_step(view, p, cur, path, s, state, ws);
    ASSERT_EQ(r.status, DwaStatus::kBackOff);
    EXPECT_EQ(r.valid_trajectories, 0);
    EXPECT_FALSE(r.oscillation);
    EXPECT_FLOAT_EQ(r.cmd.v, -0.05f);  // ramps at max_accel * T toward -backoff_speed
    // The phase continues while the robot reverses, and ends after backoff_distance_m.
    int calls = 1;
    while (r.status == DwaStatus::kBackOff && calls < 200) {
      p = motion_step(p, r.cmd, s.control_period_s);
      cur = r.cmd;
      r = dwa_step(view, p, cur, path, s, state, ws);
      ++calls;
      if (r.status == DwaStatus::kBackOff) {
        EXPECT_GE(r.cmd.v, -s.backoff_speed_mps - 1e-6f);
      }
    }
    EXPECT_GE(pose.x - p.x, s.backoff_distance_m - 0.01f);
    EXPECT_LE(pose.x - p.x, s.backoff_distance_m + 0.01f);
    EXPECT_LE(calls, s.recovery_max_calls + 1);
    EXPECT_EQ(r.status, DwaStatus::kOk);  // out of the margin: the window works again
  }
  {  // Path behind: rotate toward it in place.
    const std::vector<V2> path{V2(1.8f, 0.28f), V2(0.3f, 0.28f)};
    DwaState state;
    DwaWorkspace ws;
    const DwaResult r = dwa_step(view, pose, Twist{}, path, s, state, ws);
    ASSERT_EQ(r.status, DwaStatus::kRotateInPlace);
    EXPECT_EQ(r.cmd.v, 0.0f);
    EXPECT_NE(r.cmd.omega, 0.0f);
    EXPECT_LE(std::fabs(r.cmd.omega), s.mapping_max_alpha_rps2 * s.control_period_s + 1e-6f);
  }
  {  // Closed behind too (a 0.5 m long pocket): no room to back off, aligned -> no valid trajectory.
    TestGrid pocket(60, 30, 0.05f, V2(-0.1f, -0.1f));
    pocket.block_rect(-1.0f, -1.0f, 100.0f, -0.001f);
    pocket.block_rect(-1.0f, 0.561f, 100.0f, 100.0f);
    pocket.block_rect(-1.0f, -1.0f, 1.499f, 100.0f);
    pocket.block_rect(2.001f, -1.0f, 100.0f, 100.0f);
    pocket.build();
    const ClearanceView pv = pocket.view();
    ASSERT_GT(pv.at(pose.x, pose.y), s.robot_radius_m);
    const std::vector<V2> path{V2(1.6f, 0.28f), V2(3.0f, 0.28f)};
    DwaState state;
    DwaWorkspace ws;
    const DwaResult r = dwa_step(pv, pose, Twist{}, path, s, state, ws);
    EXPECT_EQ(r.status, DwaStatus::kNoValidTrajectory);
    EXPECT_EQ(r.cmd.v, 0.0f);
    EXPECT_EQ(r.cmd.omega, 0.0f);
  }
}

/// Alternating poses A, B (no progress) while the controller commands motion: recovery after
/// exactly oscillation_window_calls counted calls, for at most recovery_max_calls calls.
void oscillation_scenario(const Pose2& a, const Pose2& b, DwaStatus expected_recovery) {
  const TestGrid g = corridor(4.0f, 1.0f, true, true);
  const ClearanceView view = g.view();
  DwaSettings s;
  s.oscillation_window_calls = 10;
  s.recovery_max_calls = 8;
  const std::vector<V2> path{V2(0.5f, 0.5f), V2(3.5f, 0.5f)};
  DwaState state;
  DwaWorkspace ws;
  int first_trigger = -1, recovery_calls = 0, triggers = 0;
  int back_to_ok = -1;
  for (int k = 0; k < 60; ++k) {
    const Pose2& p = (k % 2 == 0) ? a : b;
    const DwaResult r = dwa_step(view, p, Twist{0.1f, 0.0f}, path, s, state, ws);
    if (r.oscillation) {
      ++triggers;
      if (first_trigger < 0) first_trigger = k;
    }
    if (first_trigger >= 0 && back_to_ok < 0) {
      if (r.status == DwaStatus::kOk) back_to_ok = k;
      else {
        EXPECT_EQ(r.status, expected_recovery);
        ++recovery_calls;
      }
    }
    if (first_trigger < 0) {
      EXPECT_EQ(r.status, DwaStatus::kOk) << "call " << k;
    }
  }
  // Call 0 sets the anchor; calls 1..10 count: the 10th counted call triggers.
  EXPECT_EQ(first_trigger, s.oscillation_window_calls);
  EXPECT_EQ(recovery_calls, s.recovery_max_calls);  // the robot never moves: the time bound ends it
  EXPECT_EQ(back_to_ok, first_trigger + s.recovery_max_calls);
  EXPECT_GE(triggers, 2);  // and it re-arms after the window
}

TEST(Dwa, OscillationTriggersBoundedBackOff) {
  oscillation_scenario(Pose2{1.0f, 0.5f, 0.0f}, Pose2{1.03f, 0.5f, 0.02f}, DwaStatus::kBackOff);
}

TEST(Dwa, OscillationTriggersBoundedRotation) {
  oscillation_scenario(Pose2{1.0f, 0.5f, 0.8f}, Pose2{1.03f, 0.5f, 0.75f}, DwaStatus::kRotateInPlace);
}

TEST(Dwa, ProgressDoesNotTriggerOscillation) {
  const TestGrid g = corridor(4.0f, 1.0f, true, true);
  const ClearanceView view = g.view();
  DwaSettings s;
  s.oscillation_window_calls = 5;
  const std::vector<V2> path{V2(0.5f, 0.5f), V2(3.5f, 0.5f)};
  DwaState state;
  DwaWorkspace ws;
  for (int k = 0; k < 100; ++k) {  // 2.5 cm per call: progress of 0.1 m every 4 calls
    const DwaResult r = dwa_step(view, Pose2{0.5f + 0.025f * k, 0.5f, 0.0f}, Twist{0.5f, 0.0f}, path, s, state, ws);
    EXPECT_EQ(r.status, DwaStatus::kOk) << k;
    EXPECT_FALSE(r.oscillation);
  }
}

TEST(Dwa, GoalReachedAndNoPath) {
  const TestGrid g = corridor(4.0f, 1.0f, true, true);
  const ClearanceView view = g.view();
  const DwaSettings s;
  DwaState state;
  DwaWorkspace ws;
  const std::vector<V2> path{V2(0.5f, 0.5f), V2(2.0f, 0.5f)};
  DwaResult r = dwa_step(view, Pose2{1.9f, 0.45f, 1.0f}, Twist{0.3f, 0.2f}, path, s, state, ws);
  EXPECT_EQ(r.status, DwaStatus::kGoalReached);
  EXPECT_EQ(r.cmd.v, 0.0f);
  EXPECT_EQ(r.cmd.omega, 0.0f);
  r = dwa_step(view, Pose2{1.8f, 0.5f, 0.0f}, Twist{}, path, s, state, ws);  // 0.2 m: not yet
  EXPECT_EQ(r.status, DwaStatus::kOk);
  r = dwa_step(view, Pose2{1.0f, 0.5f, 0.0f}, Twist{0.3f, 0.2f}, {}, s, state, ws);
  EXPECT_EQ(r.status, DwaStatus::kNoPath);
  EXPECT_EQ(r.cmd.v, 0.0f);
  EXPECT_EQ(r.cmd.omega, 0.0f);
  // One-point path: the goal is the lookahead.
  const std::vector<V2> one{V2(3.0f, 0.5f)};
  r = dwa_step(view, Pose2{1.0f, 0.5f, 0.0f}, Twist{}, one, s, state, ws);
  EXPECT_EQ(r.status, DwaStatus::kOk);
  EXPECT_EQ(r.lookahead, one[0]);
  EXPECT_STREQ(to_string(DwaStatus::kBackOff), "back_off");
  EXPECT_STREQ(to_string(DwaStatus::kNoValidTrajectory), "no_valid_trajectory");
}

TEST(Dwa, EmptyGridAndHugeCoordinates) {
  const DwaSettings s;
  DwaState state;
  DwaWorkspace ws;
  const std::vector<V2> path{V2(0.0f, 0.0f), V2(5.0f, 0.0f)};
  ClearanceView empty;  // 0 x 0: everything is outside, clearance 0
  DwaResult r = dwa_step(empty, Pose2{}, Twist{}, path, s, state, ws);
  EXPECT_EQ(r.status, DwaStatus::kNoValidTrajectory);
  EXPECT_EQ(r.valid_trajectories, 0);
  const TestGrid g = corridor(4.0f, 1.0f, true, true);
  const std::vector<V2> far{V2(1e7f, 1e7f), V2(2e7f, 1e7f)};
  state.reset();
  r = dwa_step(g.view(), Pose2{1e7f, 1e7f, 0.3f}, Twist{}, far, s, state, ws);
  EXPECT_EQ(r.status, DwaStatus::kNoValidTrajectory);
  EXPECT_EQ(r.cmd.v, 0.0f);
}

TEST(Dwa, InvalidInputsThrow) {
  const TestGrid g = corridor(4.0f, 1.0f, true, true);
  const ClearanceView view = g.view();
  const std::vector<V2> path{V2(0.5f, 0.5f), V2(2.0f, 0.5f)};
  DwaState st;
  DwaWorkspace ws;
  const DwaSettings ok;
  const auto inv = ErrorCode::kInvalidArgument;
  EXPECT_DUET_ERROR(dwa_step(view, Pose2{kNaN, 0.5f, 0.0f}, Twist{}, path, ok, st, ws), inv, "pose");
  DwaSettings heavy;  // each count within its range, the product over the work budget
  heavy.v_samples = heavy.omega_samples = 1000;
  EXPECT_DUET_ERROR(dwa_step(view, Pose2{1.0f, 0.5f, 0.0f}, Twist{}, path, heavy, st, ws), inv, "rollout steps per call");
  heavy.steps = 1;  // 1e6: exactly the budget
  EXPECT_NO_THROW(dwa_step(view, Pose2{1.0f, 0.5f, 0.0f}, Twist{}, path, heavy, st, ws));
  EXPECT_DUET_ERROR(dwa_step(view, Pose2{1.0f, 0.5f, kInf}, Twist{}, path, ok, st, ws), inv, "pose");
  EXPECT_DUET_ERROR(dwa_step(view, Pose2{1.0f, 0.5f, 0.0f}, Twist{kNaN, 0.0f}, path, ok, st, ws), inv, "twist");
  const std::vector<V2> bad_path{V2(0.5f, 0.5f), V2(kNaN, 0.5f)};
  EXPECT_DUET_ERROR(dwa_step(view, Pose2{1.0f, 0.5f, 0.0f}, Twist{}, bad_path, ok, st, ws), inv, "waypoint 1");
  ClearanceView bad_view = view;
  bad_view.width += 1;
  EXPECT_DUET_ERROR(dwa_step(bad_view, Pose2{1.0f, 0.5f, 0.0f}, Twist{}, path, ok, st, ws), inv, "width * height");
  bad_view = view;
  bad_view.resolution_m = 0.0f;
  EXPECT_DUET_ERROR(dwa_step(bad_view, Pose2{1.0f, 0.5f, 0.0f}, Twist{}, path, ok, st, ws), inv, "resolution_m");

  auto expect_bad = [&](auto mutate, const char* field) {
    DwaSettings s;
    mutate(s);
    EXPECT_DUET_ERROR(validate(s), inv, field);
    EXPECT_DUET_ERROR(dwa_step(view, Pose2{1.0f, 0.5f, 0.0f}, Twist{}, path, s, st, ws), inv, field);
  };
  expect_bad([](DwaSettings& s) { s.mapping_max_omega_rps = 0.0f; }, "mapping_max_omega_rps");
  expect_bad([](DwaSettings& s) { s.mapping_max_alpha_rps2 = kNaN; }, "mapping_max_alpha_rps2");
  expect_bad([](DwaSettings& s) { s.control_period_s = -0.05f; }, "control_period_s");
  expect_bad([](DwaSettings& s) { s.v_samples = 0; }, "v_samples");
  expect_bad([](DwaSettings& s) { s.omega_samples = 1001; }, "omega_samples");
  expect_bad([](DwaSettings& s) { s.steps = 0; }, "steps");
  expect_bad([](DwaSettings& s) { s.sim_time_s = 0.0f; }, "sim_time_s");
  expect_bad([](DwaSettings& s) { s.robot_radius_m = -0.1f; }, "robot_radius_m");
  expect_bad([](DwaSettings& s) { s.safety_margin_m = kInf; }, "safety_margin_m");
  expect_bad([](DwaSettings& s) { s.w_progress = -1.0f; }, "w_progress");
  expect_bad([](DwaSettings& s) { s.w_path = kNaN; }, "w_path");
  expect_bad([](DwaSettings& s) { s.w_clearance = -1.0f; }, "w_clearance");
  expect_bad([](DwaSettings& s) { s.w_speed = kInf; }, "w_speed");
  expect_bad([](DwaSettings& s) { s.lookahead_m = 0.0f; }, "lookahead_m");
  expect_bad([](DwaSettings& s) { s.goal_tolerance_m = -0.1f; }, "goal_tolerance_m");
  expect_bad([](DwaSettings& s) { s.oscillation_window_calls = 0; }, "oscillation_window_calls");
  expect_bad([](DwaSettings& s) { s.oscillation_min_turn_rad = 4.0f; }, "oscillation_min_turn_rad");
  expect_bad([](DwaSettings& s) { s.recovery_max_calls = 0; }, "recovery_max_calls");
  expect_bad([](DwaSettings& s) { s.rotate_omega_rps = 0.0f; }, "rotate_omega_rps");
  expect_bad([](DwaSettings& s) { s.backoff_distance_m = 11.0f; }, "backoff_distance_m");
  expect_bad([](DwaSettings& s) { s.backoff_speed_mps = 0.0f; }, "backoff_speed_mps");
  expect_bad([](DwaSettings& s) { s.limits.max_v_mps = 0.0f; }, "max_v_mps");
  EXPECT_NO_THROW(validate(ok));
}

bool same_result(const DwaResult& a, const DwaResult& b) {
  return a.status == b.status && std::memcmp(&a.cmd, &b.cmd, sizeof(Twist)) == 0 &&
         std::memcmp(&a.score, &b.score, sizeof(float)) == 0 && a.valid_trajectories == b.valid_trajectories &&
         a.evaluated_trajectories == b.evaluated_trajectories && a.oscillation == b.oscillation &&
         a.lookahead == b.lookahead;
}

TEST(Dwa, ThreadCountDoesNotChangeTheResult) {
  std::mt19937 rng(77);
  const int cases = test::full_or(60, 15);
  for (int t = 0; t < cases; ++t) {
    RandomCase c = random_case(rng, false);
    if (t % 2 == 1) {  // large enough for the parallel path
      c.s.v_samples = 101;
      c.s.omega_samples = 99;
    }
    const ClearanceView view = c.grid.view();
    auto run = [&](int threads) {
      return test::in_arena(threads, [&] {
        DwaState st;
        DwaWorkspace ws;
        return dwa_step(view, c.pose, c.cur, c.path, c.s, st, ws);
      });
    };
    const DwaResult r1 = run(1), r2 = run(2);
    EXPECT_TRUE(same_result(r1, r2)) << "case " << t;
  }
}

TEST(Dwa, WorkspaceIsReusedWithoutReallocation) {
  const TestGrid g = corridor(4.0f, 1.0f, true, true);
  const ClearanceView view = g.view();
  const DwaSettings s;
  const std::vector<V2> path{V2(0.5f, 0.5f), V2(2.0f, 0.5f), V2(3.5f, 0.5f)};
  DwaState state;
  DwaWorkspace ws;
  const DwaResult r1 = dwa_step(view, Pose2{0.6f, 0.5f, 0.0f}, Twist{0.2f, 0.0f}, path, s, state, ws);
  const float* ox = ws.off_x.data();
  const auto* rows = ws.rows.data();
  const auto* lp = ws.local_path.data();
  const DwaResult r2 = dwa_step(view, Pose2{0.7f, 0.5f, 0.0f}, Twist{0.2f, 0.0f}, path, s, state, ws);
  EXPECT_EQ(ox, ws.off_x.data());
  EXPECT_EQ(rows, ws.rows.data());
  EXPECT_EQ(lp, ws.local_path.data());
  EXPECT_EQ(r1.status, DwaStatus::kOk);
  EXPECT_EQ(r2.status, DwaStatus::kOk);
  // A dirty workspace (other sizes before) gives the same result as a fresh one.
  DwaSettings big = s;
  big.v_samples = 33;
  big.steps = 50;
  DwaState st2, st3;
  DwaWorkspace dirty, fresh;
  (void)dwa_step(view, Pose2{0.6f, 0.5f, 0.0f}, Twist{}, path, big, st2, dirty);
  st2.reset();
  EXPECT_TRUE(same_result(dwa_step(view, Pose2{0.7f, 0.5f, 0.0f}, Twist{0.2f, 0.0f}, path, s, st2, dirty),
                          dwa_step(view, Pose2{0.7f, 0.5f, 0.0f}, Twist{0.2f, 0.0f}, path, s, st3, fresh)));
}

}  // namespace test_dwa
}  // namespace duet
