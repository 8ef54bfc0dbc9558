// Dynamic window approach with the paper's motion constraint (see dwa.hpp for the semantics).
//
// Fast rollout: for a constant omega the heading after step k does not depend on v, and by
// Eq. (4) each step moves the robot by v * c * d_k with c = 2 sin(omega dt / 2) / omega (dt in
// the straight limit) and d_k the unit vector of the step's mean heading. So the position after
// step k is p_0 + v * S_k with S_k = c * (d_0 + ... + d_{k-1}), computed once per omega sample
// (d_{k+1} = d_k * e^{i omega dt}: one complex multiply per step, two sin/cos per omega sample)
// and shared by all v samples. A trajectory then costs one multiply-add pair and one clearance
// lookup per step (cell indices computed 16 steps at a time, vectorised), and stops at its
// first inadmissible step. The offsets are float sums, so positions differ from repeated
// motion_step calls by a few ulp (the tests compare against motion_step rollouts).
#include <duet/kernels/dwa.hpp>
#include <duet/kernels/error.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

namespace duet {
namespace {

/// From this many rollout steps in total (v_samples * omega_samples * steps) the rows (v samples)
/// run in parallel. At the default 800 x 30 = 24000 a step takes ~50 us on one core and the
/// 2-thread arena still gains ~10-30 % on the shared 2-core machine (bench_dwa.cpp); below
/// ~10000 the parallel_for overhead eats the gain. Rows are independent and reduced in order,
/// so the result is the same either way.
constexpr long long kParallelMinSteps = 10000;

constexpr float kPi = std::numbers::pi_v<float>;

/// Rollout steps whose cell indices are computed together (vectorised) before the lookups.
constexpr int kChunk = 16;

float wrap_angle(float a) { return std::remainder(a, 2.0f * kPi); }

[[noreturn]] void bad(const char* key, double v, const char* range) {
  fail(ErrorCode::kInvalidArgument,
       std::string("DwaSettings.") + key + " = " + std::to_string(v) + " is outside " + range);
}

void check_range(const char* key, float v, float lo, float hi, bool lo_open, const char* range) {
  const bool ok = std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi;
  if (!ok) bad(key, v, range);
}

void check_int(const char* key, int v, int lo, int hi, const char* range) {
  if (v < lo || v > hi) bad(key, v, range);
}

float sample(float lo, float hi, int n, int i) {
  if (n == 1) return 0.5f * (lo + hi);
  return lo + (hi - lo) * (static_cast<float>(i) / static_cast<float>(n - 1));
}

/// Window [lo, hi] on one axis: current +- delta, within [min, max]; if current is outside them,
/// the single reachable value nearest them (decelerate as hard as allowed). Always within the
/// hard limits [hard_lo, hard_hi] (the chassis'): a measured velocity beyond those by more than
/// one period's change (an odometry glitch, a push) gives the limit itself, never a command
/// beyond it.
void axis_window(float cur, float delta, float mn, float mx, float hard_lo, float hard_hi, float& lo, float& hi) {
  lo = std::max(mn, cur - delta);
  hi = std::min(mx, cur + delta);
  if (lo > hi) {
    if (cur > mx) hi = lo;  // above the limit: decelerate as hard as allowed
    else lo = hi;           // below the limit
  }
  lo = std::clamp(lo, hard_lo, hard_hi);
  hi = std::clamp(hi, hard_lo, hard_hi);
}

float dist_to_polyline(const std::vector<Eigen::Vector2f>& pl, float px, float py) {
  float best = std::numeric_limits<float>::infinity();
  if (pl.size() == 1) {
    const float ex = px - pl[0].x(), ey = py - pl[0].y();
    return std::sqrt(ex * ex + ey * ey);
  }
  for (std::size_t s = 0; s + 1 < pl.size(); ++s) {
    const float ax = pl[s].x(), ay = pl[s].y();
    const float dx = pl[s + 1].x() - ax, dy = pl[s + 1].y() - ay;
    const float len2 = dx * dx + dy * dy;
    float t = 0.0f;
    if (len2 > 0.0f) t = std::clamp(((px - ax) * dx + (py - ay) * dy) / len2, 0.0f, 1.0f);
    const float ex = ax + t * dx - px, ey = ay + t * dy - py;
    best = std::min(best, ex * ex + ey * ey);
  }
  return std::sqrt(best);
}

void validate_view(const ClearanceView& c) {
  if (c.width < 0 || c.height < 0)
    fail(ErrorCode::kInvalidArgument, "dwa_step: clearance view has a negative size");
  if (c.clearance_m.size() != static_cast<std::size_t>(c.width) * static_cast<std::size_t>(c.height))
    fail(ErrorCode::kInvalidArgument, "dwa_step: clearance view: clearance_m.size() != width * height");
  if (static_cast<std::size_t>(c.width) * static_cast<std::size_t>(c.height) >
      static_cast<std::size_t>(std::numeric_limits<int>::max()))
    fail(ErrorCode::kOutOfRange, "dwa_step: clearance view has more than 2^31 - 1 cells");
  if (!std::isfinite(c.resolution_m) || !(c.resolution_m > 0.0f))
    fail(ErrorCode::kInvalidArgument, "dwa_step: clearance view: resolution_m must be finite and > 0");
  if (!std::isfinite(c.origin.x()) || !std::isfinite(c.origin.y()))
    fail(ErrorCode::kInvalidArgument, "dwa_step: clearance view: origin must be finite");
}

struct Derived {
  float dv, domega;    // acceleration window half-widths
  float w_max;         // W
  float w_hard;        // the chassis' angular speed limit: no command beyond it
  float thr;           // radius + margin
  float backoff_speed; // effective
};

Derived derive(const DwaSettings& s) {
  Derived d;
  d.dv = s.limits.max_accel_mps2 * s.control_period_s;
  d.domega = std::min(s.limits.max_alpha_rps2, s.mapping_max_alpha_rps2) * s.control_period_s;
  d.w_max = std::min(s.limits.max_omega_rps, s.mapping_max_omega_rps);
  d.w_hard = s.limits.max_omega_rps;
  d.thr = s.robot_radius_m + s.safety_margin_m;
  d.backoff_speed = std::min(s.backoff_speed_mps, -s.limits.min_v_mps);
  return d;
}

/// omega moved toward `target` within the window of the paper's constraint (as the samples).
float ramp_omega(float cur, float target, const Derived& d) {
  float lo, hi;
  axis_window(cur, d.domega, -d.w_max, d.w_max, -d.w_hard, d.w_hard, lo, hi);
  return std::clamp(target, lo, hi);
}

bool rotation_free(const ClearanceView& c, const Pose2& p, const DwaSettings& s) {
  return c.at(p.x, p.y) > s.robot_radius_m;
}

bool backoff_clear(const ClearanceView& c, const Pose2& p, const DwaSettings& s) {
  if (!(s.limits.min_v_mps < 0.0f) || !(s.backoff_distance_m > 0.0f)) return false;
  const float h = 0.5f * c.resolution_m;
  const int n = static_cast<int>(std::ceil(s.backoff_distance_m / h));
  const float cx = std::cos(p.theta), cy = std::sin(p.theta);
  for (int m = 1; m <= n; ++m) {
    const float d = std::min(static_cast<float>(m) * h, s.backoff_distance_m);
    if (!(c.at(p.x - d * cx, p.y - d * cy) > s.robot_radius_m)) return false;
  }
  return true;
}

DwaResult zero_result(DwaStatus st) {
  DwaResult r;
  r.status = st;
  r.score = -std::numeric_limits<float>::infinity();
  return r;
}

/// Everything one row (v sample) of the rollout reads, copied by value so that the compiler
/// keeps it in registers (no aliasing with the index buffer).
struct RowInput {
  const float* ox;
  const float* oy;
  const float* vs;
  const std::vector<Eigen::Vector2f>* local_path;
  const float* cl;
  int stride, ns, nw, width;
  float px, py, org_x, org_y, res, gw, gh, thr, d0, lx, ly;
  float w_progress, w_path, w_clearance, w_speed, cap;
};

DwaWorkspace::RowBest evaluate_row(const RowInput in, int i) {
  const float v = in.vs[i];
  const float px = in.px, py = in.py, org_x = in.org_x, org_y = in.org_y, res = in.res, gw = in.gw, gh = in.gh;
  const float thr = in.thr;
  const int width = in.width, ns = in.ns;
  const float* const cl = in.cl;
  DwaWorkspace::RowBest best{-std::numeric_limits<float>::infinity(), -1, 0};
  for (int j = 0; j < in.nw; ++j) {
    const float* ox = in.ox + static_cast<std::size_t>(j) * static_cast<std::size_t>(in.stride);
    const float* oy = in.oy + static_cast<std::size_t>(j) * static_cast<std::size_t>(in.stride);
    float cmin = std::numeric_limits<float>::infinity();
    bool ok = true;
    for (int k0 = 0; k0 < ns && ok; k0 += kChunk) {
      // Cell indices of a chunk of steps, branch-free (vectorised): exactly ClearanceView::at's
      // arithmetic ((x - origin) / resolution, IEEE-rounded in SIMD as in scalar), -1 outside.
      alignas(64) int idx[kChunk];
      for (int k = 0; k < kChunk; ++k) {
        const float fx = (px + v * ox[k0 + k] - org_x) / res;
        const float fy = (py + v * oy[k0 + k] - org_y) / res;
        const bool inside = (fx >= 0.0f) & (fy >= 0.0f) & (fx < gw) & (fy < gh);
        const int ix = static_cast<int>(inside ? fx : 0.0f), iy = static_cast<int>(inside ? fy : 0.0f);
        idx[k] = inside ? iy * width + ix : -1;
      }
      const int n = std::min(kChunk, ns - k0);
      for (int k = 0; k < n; ++k) {  // early exit at the first inadmissible step
        const float c = idx[k] < 0 ? 0.0f : cl[idx[k]];
        if (!(c > thr)) {
          ok = false;
          break;
        }
        cmin = std::min(cmin, c);
      }
    }
    if (!ok) continue;
    ++best.valid;
    const float ex = px + v * ox[ns - 1], ey = py + v * oy[ns - 1];
    const float progress = in.d0 - std::sqrt((in.lx - ex) * (in.lx - ex) + (in.ly - ey) * (in.ly - ey));
    const float dpath = dist_to_polyline(*in.local_path, ex, ey);
    const float clr = std::min(cmin - thr, in.cap);
    float score = in.w_progress * progress;
    score -= in.w_path * dpath;
    score += in.w_clearance * clr;
    score += in.w_speed * v;
    if (score > best.score || best.index < 0) {
      best.score = score;
      best.index = i * in.nw + j;
    }
  }
  return best;
}

}  // namespace

void validate(const DwaSettings& s) {
  validate(s.limits);
  constexpr float kInf = std::numeric_limits<float>::infinity();
  check_range("mapping_max_omega_rps", s.mapping_max_omega_rps, 0.0f, kInf, true, "(0, inf)");
  check_range("mapping_max_alpha_rps2", s.mapping_max_alpha_rps2, 0.0f, kInf, true, "(0, inf)");
  check_range("control_period_s", s.control_period_s, 0.0f, 10.0f, true, "(0, 10]");
  check_int("v_samples", s.v_samples, 1, 1000, "[1, 1000]");
  check_int("omega_samples", s.omega_samples, 1, 1000, "[1, 1000]");
  check_int("steps", s.steps, 1, 1000, "[1, 1000]");
  // Work budget: the rollout steps of one call.
  const double rollout_steps = static_cast<double>(s.v_samples) * s.omega_samples * s.steps;
  if (!(rollout_steps <= kMaxDwaRolloutSteps))
    fail(ErrorCode::kInvalidArgument, "DwaSettings: v_samples * omega_samples * steps = " + std::to_string(static_cast<long long>(rollout_steps)) +
                                          ", more than the budget of " + std::to_string(static_cast<long long>(kMaxDwaRolloutSteps)) +
                                          " rollout steps per call");
  check_range("sim_time_s", s.sim_time_s, 0.0f, 60.0f, true, "(0, 60]");
  check_range("robot_radius_m", s.robot_radius_m, 0.0f, kInf, false, "[0, inf)");
  check_range("safety_margin_m", s.safety_margin_m, 0.0f, kInf, false, "[0, inf)");
  check_range("w_progress", s.w_progress, 0.0f, kInf, false, "[0, inf)");
  check_range("w_path", s.w_path, 0.0f, kInf, false, "[0, inf)");
  check_range("w_clearance", s.w_clearance, 0.0f, kInf, false, "[0, inf)");
  check_range("w_speed", s.w_speed, 0.0f, kInf, false, "[0, inf)");
  check_range("clearance_cap_m", s.clearance_cap_m, 0.0f, kInf, false, "[0, inf)");
  check_range("lookahead_m", s.lookahead_m, 0.0f, kInf, true, "(0, inf)");
  check_range("goal_tolerance_m", s.goal_tolerance_m, 0.0f, kInf, false, "[0, inf)");
  check_int("oscillation_window_calls", s.oscillation_window_calls, 1, 1000000, "[1, 1000000]");
  check_range("oscillation_min_progress_m", s.oscillation_min_progress_m, 0.0f, kInf, false, "[0, inf)");
  check_range("oscillation_min_turn_rad", s.oscillation_min_turn_rad, 0.0f, kPi, false, "[0, pi]");
  check_int("recovery_max_calls", s.recovery_max_calls, 1, 1000000, "[1, 1000000]");
  check_range("rotate_omega_rps", s.rotate_omega_rps, 0.0f, kInf, true, "(0, inf)");
  check_range("rotate_tolerance_rad", s.rotate_tolerance_rad, 0.0f, kPi, false, "[0, pi]");
  check_range("backoff_distance_m", s.backoff_distance_m, 0.0f, 10.0f, false, "[0, 10]");
  check_range("backoff_speed_mps", s.backoff_speed_mps, 0.0f, kInf, true, "(0, inf)");
}

const char* to_string(DwaStatus s) {
  switch (s) {
    case DwaStatus::kOk: return "ok";
    case DwaStatus::kGoalReached: return "goal_reached";
    case DwaStatus::kRotateInPlace: return "rotate_in_place";
    case DwaStatus::kBackOff: return "back_off";
    case DwaStatus::kNoValidTrajectory: return "no_valid_trajectory";
    case DwaStatus::kNoPath: return "no_path";
  }
  return "unknown";
}

PathProjection project_on_path(std::span<const Eigen::Vector2f> path, const Eigen::Vector2f& p) {
  PathProjection r;
  if (path.empty()) return r;
  r.point = path[0];
  if (path.size() == 1) return r;
  float best = std::numeric_limits<float>::infinity();
  for (std::size_t s = 0; s + 1 < path.size(); ++s) {
    const Eigen::Vector2f a = path[s], d = path[s + 1] - path[s];
    const float len2 = d.squaredNorm();
    float t = 0.0f;
    if (len2 > 0.0f) t = std::clamp((p - a).dot(d) / len2, 0.0f, 1.0f);
    const Eigen::Vector2f q = a + t * d;
    const float e = (q - p).squaredNorm();
    if (e < best) {
      best = e;
      r.segment = static_cast<int>(s);
      r.point = q;
    }
  }
  return r;
}

DwaResult dwa_step(const ClearanceView& clearance, const Pose2& pose, const Twist& current,
                   std::span<const Eigen::Vector2f> path, const DwaSettings& s, DwaState& state,
                   DwaWorkspace& ws) {
  validate(s);
  validate_view(clearance);
  if (!std::isfinite(pose.x) || !std::isfinite(pose.y) || !std::isfinite(pose.theta))
    fail(ErrorCode::kInvalidArgument, "dwa_step: pose must be finite");
  if (!std::isfinite(current.v) || !std::isfinite(current.omega))
    fail(ErrorCode::kInvalidArgument, "dwa_step: current twist must be finite");
  for (std::size_t i = 0; i < path.size(); ++i)
    if (!path[i].allFinite())
      fail(ErrorCode::kInvalidArgument, "dwa_step: path waypoint " + std::to_string(i) + " is not finite");

  // 1-2. No path, goal reached.
  if (path.empty()) {
    state.reset();
    return zero_result(DwaStatus::kNoPath);
  }
  const Eigen::Vector2f p0(pose.x, pose.y);
  if ((p0 - path.back()).norm() <= s.goal_tolerance_m) {
    state.reset();
    DwaResult r = zero_result(DwaStatus::kGoalReached);
    r.lookahead = path.back();
    return r;
  }

  // 3. Path geometry: closest point P, lookahead L, local path P..L.
  const PathProjection proj = project_on_path(path, p0);
  ws.local_path.clear();
  ws.local_path.push_back(proj.point);
  {
    float remaining = s.lookahead_m;
    Eigen::Vector2f cur = proj.point;
    for (std::size_t seg = static_cast<std::size_t>(proj.segment); seg + 1 < path.size(); ++seg) {
      const Eigen::Vector2f end = path[seg + 1];
      const float len = (end - cur).norm();
      if (len >= remaining) {
        ws.local_path.push_back(cur + (end - cur) * (remaining / len));
        break;
      }
      remaining -= len;
      cur = end;
      ws.local_path.push_back(end);
    }
    // Loop ran out: the path ended within the lookahead, L = its last point (already pushed).
  }
  const Eigen::Vector2f L = ws.local_path.back();
  const Derived d = derive(s);
  const Eigen::Vector2f to_l = L - p0;
  const float heading_error =
      to_l.squaredNorm() > 0.0f ? wrap_angle(std::atan2(to_l.y(), to_l.x()) - pose.theta) : 0.0f;

  auto rotate_result = [&] {
    DwaResult r = zero_result(DwaStatus::kRotateInPlace);
    const float target = std::copysign(std::min(s.rotate_omega_rps, d.w_max), heading_error);
    r.cmd = Twist{0.0f, ramp_omega(current.omega, target, d)};
    r.lookahead = L;
    return r;
  };
  auto backoff_result = [&] {
    DwaResult r = zero_result(DwaStatus::kBackOff);
    r.cmd = Twist{std::max(-d.backoff_speed, std::min(current.v, 0.0f) - d.dv), ramp_omega(current.omega, 0.0f, d)};
    r.lookahead = L;
    return r;
  };
  auto end_phase = [&] {
    state.phase = DwaState::Phase::kNone;
    state.phase_calls = 0;
    state.anchor = pose;
    state.anchor_valid = true;
    state.stuck_calls = 0;
  };
  // Starts a recovery phase if one is possible; returns false if neither is.
  auto start_recovery = [&](DwaResult& out) {
    if (std::fabs(heading_error) > s.rotate_tolerance_rad && rotation_free(clearance, pose, s)) {
      state.phase = DwaState::Phase::kRotate;
      state.phase_calls = 1;
      state.phase_start = pose;
      out = rotate_result();
      return true;
    }
    if (backoff_clear(clearance, pose, s)) {
      state.phase = DwaState::Phase::kBackOff;
      state.phase_calls = 1;
      state.phase_start = pose;
      out = backoff_result();
      return true;
    }
    return false;
  };

  // 4. An active recovery phase continues or ends.
  if (state.phase == DwaState::Phase::kRotate) {
    if (state.phase_calls < s.recovery_max_calls && std::fabs(heading_error) > s.rotate_tolerance_rad &&
        rotation_free(clearance, pose, s)) {
      ++state.phase_calls;
      state.last_cmd_moving = false;
      return rotate_result();
    }
    end_phase();
  } else if (state.phase == DwaState::Phase::kBackOff) {
    const float travelled = std::hypot(pose.x - state.phase_start.x, pose.y - state.phase_start.y);
    if (state.phase_calls < s.recovery_max_calls && travelled < s.backoff_distance_m &&
        backoff_clear(clearance, pose, s)) {
      ++state.phase_calls;
      state.last_cmd_moving = false;
      return backoff_result();
    }
    end_phase();
  }

  // 5. Oscillation detector (move_base style: progress = translation or turn from the anchor).
  if (!state.anchor_valid) {
    state.anchor = pose;
    state.anchor_valid = true;
    state.stuck_calls = 0;
  } else if (std::hypot(pose.x - state.anchor.x, pose.y - state.anchor.y) >= s.oscillation_min_progress_m ||
             std::fabs(wrap_angle(pose.theta - state.anchor.theta)) >= s.oscillation_min_turn_rad) {
    state.anchor = pose;
    state.stuck_calls = 0;
  } else if (state.last_cmd_moving) {
    ++state.stuck_calls;
  }
  if (state.stuck_calls >= s.oscillation_window_calls) {
    DwaResult r;
    if (start_recovery(r)) {
      r.oscillation = true;
      state.last_cmd_moving = false;
      return r;
    }
    end_phase();  // no recovery possible: restart the detector, use the window
  }

  // 6. Samples and per-omega unit-speed offsets S_k (Eq. 4, incremental rotation).
  const int nv = s.v_samples, nw = s.omega_samples, ns = s.steps;
  float v_lo, v_hi, w_lo, w_hi;
  axis_window(current.v, d.dv, s.limits.min_v_mps, s.limits.max_v_mps, s.limits.min_v_mps, s.limits.max_v_mps, v_lo, v_hi);
  axis_window(current.omega, d.domega, -d.w_max, d.w_max, -d.w_hard, d.w_hard, w_lo, w_hi);
  ws.vs.resize(static_cast<std::size_t>(nv));
  ws.omegas.resize(static_cast<std::size_t>(nw));
  for (int i = 0; i < nv; ++i) ws.vs[static_cast<std::size_t>(i)] = sample(v_lo, v_hi, nv, i);
  for (int j = 0; j < nw; ++j) ws.omegas[static_cast<std::size_t>(j)] = sample(w_lo, w_hi, nw, j);
  const int stride = (ns + kChunk - 1) / kChunk * kChunk;  // padded with the last offset
  const std::size_t n_off = static_cast<std::size_t>(nw) * static_cast<std::size_t>(stride);
  ws.off_x.resize(n_off);
  ws.off_y.resize(n_off);
  const float dt = s.sim_time_s / static_cast<float>(ns);
  for (int j = 0; j < nw; ++j) {
    const float w = ws.omegas[static_cast<std::size_t>(j)];
    const float dth = w * dt;
    float c, dx, dy, rc, rs;
    // Eq. (4) in chord form (motion_step): continuous through w = 0.
    c = dt * sinc(0.5f * dth);
    const float mid = pose.theta + 0.5f * dth;
    dx = std::cos(mid);
    dy = std::sin(mid);
    rc = std::cos(dth);
    rs = std::sin(dth);
    float sx = 0.0f, sy = 0.0f;
    float* ox = ws.off_x.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(stride);
    float* oy = ws.off_y.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(stride);
    for (int k = 0; k < ns; ++k) {
      sx += c * dx;
      sy += c * dy;
      ox[k] = sx;
      oy[k] = sy;
      const float ndx = dx * rc - dy * rs;
      dy = dx * rs + dy * rc;
      dx = ndx;
    }
    for (int k = ns; k < stride; ++k) {
      ox[k] = sx;
      oy[k] = sy;
    }
  }

  // 6-7. Roll out and score, one v sample (row) at a time.
  ws.rows.resize(static_cast<std::size_t>(nv));
  RowInput in;
  in.ox = ws.off_x.data();
  in.oy = ws.off_y.data();
  in.vs = ws.vs.data();
  in.local_path = &ws.local_path;
  in.cl = clearance.clearance_m.data();
  in.stride = stride;
  in.ns = ns;
  in.nw = nw;
  in.width = clearance.width;
  in.px = pose.x;
  in.py = pose.y;
  in.org_x = clearance.origin.x();
  in.org_y = clearance.origin.y();
  in.res = clearance.resolution_m;
  in.gw = static_cast<float>(clearance.width);
  in.gh = static_cast<float>(clearance.height);
  in.thr = d.thr;
  in.d0 = to_l.norm();
  in.lx = L.x();
  in.ly = L.y();
  in.w_progress = s.w_progress;
  in.w_path = s.w_path;
  in.w_clearance = s.w_clearance;
  in.w_speed = s.w_speed;
  in.cap = s.clearance_cap_m;
  auto eval_row = [&ws, in](int i) { ws.rows[static_cast<std::size_t>(i)] = evaluate_row(in, i); };
  const long long total = static_cast<long long>(nv) * nw * ns;
  if (total >= kParallelMinSteps && nv > 1) {
    tbb::parallel_for(tbb::blocked_range<int>(0, nv, 1), [&](const tbb::blocked_range<int>& r) {
      for (int i = r.begin(); i != r.end(); ++i) eval_row(i);
    });
  } else {
    for (int i = 0; i < nv; ++i) eval_row(i);
  }
  DwaWorkspace::RowBest best{-std::numeric_limits<float>::infinity(), -1, 0};
  int valid = 0;
  for (int i = 0; i < nv; ++i) {  // rows in order: ties keep the smaller index
    const auto& r = ws.rows[static_cast<std::size_t>(i)];
    valid += r.valid;
    if (r.index >= 0 && (best.index < 0 || r.score > best.score)) best = r;
  }

  if (best.index >= 0) {
    DwaResult r;
    r.status = DwaStatus::kOk;
    r.cmd = Twist{ws.vs[static_cast<std::size_t>(best.index / nw)], ws.omegas[static_cast<std::size_t>(best.index % nw)]};
    r.score = best.score;
    r.valid_trajectories = valid;
    r.evaluated_trajectories = nv * nw;
    r.lookahead = L;
    state.last_cmd_moving = r.cmd.v != 0.0f || r.cmd.omega != 0.0f;
    return r;
  }

  // 8. Nothing admissible: recovery.
  DwaResult r;
  state.last_cmd_moving = false;
  if (!start_recovery(r)) {
    r = zero_result(DwaStatus::kNoValidTrajectory);
    r.lookahead = L;
  }
  r.evaluated_trajectories = nv * nw;
  return r;
}

}  // namespace duet
