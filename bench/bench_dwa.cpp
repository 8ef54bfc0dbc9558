// DWA/{duet,duet_1t,naive}/800x30: one dynamic-window control step (dwa.hpp) with the default
// settings (20 v x 40 omega samples = 800 trajectories, 30 rollout steps over 1.5 s) on a
// synthetic cluttered 0.05 m grid (12 m x 12 m, random boxes and pillars, fixed seed), the robot
// moving at (0.3 m/s, 0.2 rad/s) through the clutter along a wiggly 40-waypoint path.
// naive = the same sampling and scoring written plainly here: motion_step (sin/cos) for every step
// of every trajectory, no early exit, the path geometry recomputed plainly.
// Items = trajectories per step; "out" = admissible trajectories (same for every contender).
// The state is reset every iteration so that the oscillation detector never switches to recovery.
#include "bench_util.hpp"

#include <duet/kernels/dwa.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <utility>
#include <vector>

namespace duet::bench {
namespace {

struct DwaInput {
  int w = 240, h = 240;
  float res = 0.05f;
  Eigen::Vector2f origin{-6.0f, -6.0f};
  std::vector<float> clearance;
  std::vector<Eigen::Vector2f> path;
  Pose2 pose;
  Twist current{0.3f, 0.2f};
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

const DwaInput& dwa_input() {
  static const DwaInput in = [] {
    DwaInput d;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<char> blocked(static_cast<std::size_t>(d.w * d.h), 0);
    auto block = [&](int x, int y) {
      if (x >= 0 && y >= 0 && x < d.w && y < d.h) blocked[static_cast<std::size_t>(y * d.w + x)] = 1;
    };
    for (int k = 0; k < 90; ++k) {  // boxes 0.1-0.6 m and thin walls
      const int x0 = static_cast<int>(u(rng) * d.w), y0 = static_cast<int>(u(rng) * d.h);
      const int ex = 2 + static_cast<int>(u(rng) * 10), ey = 2 + static_cast<int>(u(rng) * 10);
      for (int y = y0; y < y0 + ey; ++y)
        for (int x = x0; x < x0 + ex; ++x) block(x, y);
    }
    for (int x = 0; x < d.w; ++x) block(x, 0), block(x, d.h - 1);
    for (int y = 0; y < d.h; ++y) block(0, y), block(d.w - 1, y);
    // Clearance: distance between cell centres to the nearest blocked cell within 1.5 m (capped).
    constexpr int R = 30;
    d.clearance.assign(blocked.size(), R * d.res);
    for (int y = 0; y < d.h; ++y)
      for (int x = 0; x < d.w; ++x) {
        int best = R * R;
        for (int dy = -R; dy <= R; ++dy)
          for (int dx = -R; dx <= R; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= d.w || yy >= d.h || !blocked[static_cast<std::size_t>(yy * d.w + xx)]) continue;
            best = std::min(best, dx * dx + dy * dy);
          }
        d.clearance[static_cast<std::size_t>(y * d.w + x)] = std::sqrt(static_cast<float>(best)) * d.res;
      }
    // Robot: in the clutter, heading +x - the free cell (clearance >= 0.3 m) nearest the centre
    // from which 40-70 % of the 800 trajectories are admissible (the rest hit obstacles).
    const ClearanceView v = d.view();
    std::vector<std::pair<float, Eigen::Vector2f>> cand;
    for (int y = 0; y < d.h; ++y)
      for (int x = 0; x < d.w; ++x) {
        const Eigen::Vector2f c = d.origin + Eigen::Vector2f((x + 0.5f) * d.res, (y + 0.5f) * d.res);
        if (v.at(c.x(), c.y()) >= 0.3f) cand.emplace_back(c.norm(), c);
      }
    std::stable_sort(cand.begin(), cand.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    const DwaSettings s;
    DwaWorkspace ws;
    for (const auto& [dist, c] : cand) {
      d.pose = Pose2{c.x(), c.y(), 0.0f};
      d.path.clear();
      for (int k = 0; k < 40; ++k)
        d.path.emplace_back(d.pose.x + 0.12f * static_cast<float>(k), d.pose.y + 0.4f * std::sin(0.3f * static_cast<float>(k)));
      DwaState st;
      const DwaResult r = dwa_step(v, d.pose, d.current, d.path, s, st, ws);
      if (r.status == DwaStatus::kOk && r.valid_trajectories >= 320 && r.valid_trajectories <= 560) break;
    }
    return d;
  }();
  return in;
}

// ---- naive: the same DWA written plainly ----------------------------------------------------------

float naive_dist_polyline(const std::vector<Eigen::Vector2f>& pl, const Eigen::Vector2f& p) {
  if (pl.size() == 1) return (p - pl[0]).norm();
  float best = std::numeric_limits<float>::infinity();
  for (std::size_t s = 0; s + 1 < pl.size(); ++s) {
    const Eigen::Vector2f a = pl[s], d = pl[s + 1] - pl[s];
    float t = 0.0f;
    if (d.squaredNorm() > 0.0f) t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0f, 1.0f);
    best = std::min(best, (a + t * d - p).norm());
  }
  return best;
}

struct NaiveOut {
  Twist cmd;
  int valid = 0;
};

NaiveOut naive_dwa(const ClearanceView& view, const Pose2& pose, const Twist& cur, const std::vector<Eigen::Vector2f>& path,
                   const DwaSettings& s) {
  const Eigen::Vector2f p0(pose.x, pose.y);
  // closest point and lookahead
  int seg = 0;
  Eigen::Vector2f P = path[0];
  float bestd = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const Eigen::Vector2f a = path[i], d = path[i + 1] - path[i];
    float t = 0.0f;
    if (d.squaredNorm() > 0.0f) t = std::clamp((p0 - a).dot(d) / d.squaredNorm(), 0.0f, 1.0f);
    const Eigen::Vector2f q = a + t * d;
    if ((q - p0).squaredNorm() < bestd) {
      bestd = (q - p0).squaredNorm();
      seg = static_cast<int>(i);
      P = q;
    }
  }
  std::vector<Eigen::Vector2f> local{P};
  float left = s.lookahead_m;
  Eigen::Vector2f c = P;
  for (std::size_t i = static_cast<std::size_t>(seg); i + 1 < path.size(); ++i) {
    const float len = (path[i + 1] - c).norm();
    if (len >= left) {
      local.push_back(c + (path[i + 1] - c) * (left / len));
      break;
    }
    left -= len;
    c = path[i + 1];
    local.push_back(c);
  }
  const Eigen::Vector2f L = local.back();
  const float dv = s.limits.max_accel_mps2 * s.control_period_s;
  const float dw = std::min(s.limits.max_alpha_rps2, s.mapping_max_alpha_rps2) * s.control_period_s;
  const float W = std::min(s.limits.max_omega_rps, s.mapping_max_omega_rps);
  const float v_lo = std::max(s.limits.min_v_mps, cur.v - dv), v_hi = std::min(s.limits.max_v_mps, cur.v + dv);
  const float w_lo = std::max(-W, cur.omega - dw), w_hi = std::min(W, cur.omega + dw);
  const float thr = s.robot_radius_m + s.safety_margin_m, dt = s.sim_time_s / static_cast<float>(s.steps);
  NaiveOut out;
  float best = -std::numeric_limits<float>::infinity();
  for (int i = 0; i < s.v_samples; ++i)
    for (int j = 0; j < s.omega_samples; ++j) {
      const float v = v_lo + (v_hi - v_lo) * (static_cast<float>(i) / static_cast<float>(s.v_samples - 1));
      const float w = w_lo + (w_hi - w_lo) * (static_cast<float>(j) / static_cast<float>(s.omega_samples - 1));
      Pose2 p = pose;
      float cmin = std::numeric_limits<float>::infinity();
      bool ok = true;
      for (int k = 0; k < s.steps; ++k) {
        p = motion_step(p, Twist{v, w}, dt);
        const float cl = view.at(p.x, p.y);
        if (!(cl > thr)) ok = false;
        cmin = std::min(cmin, cl);
      }
      if (!ok) continue;
      ++out.valid;
      const Eigen::Vector2f e(p.x, p.y);
      const float score = s.w_progress * ((p0 - L).norm() - (e - L).norm()) - s.w_path * naive_dist_polyline(local, e) +
                          s.w_clearance * std::min(cmin - thr, s.clearance_cap_m) + s.w_speed * v;
      if (score > best) {
        best = score;
        out.cmd = Twist{v, w};
      }
    }
  return out;
}

void set_label(benchmark::State& state, const Twist& cmd) {
  state.counters["v"] = cmd.v;
  state.counters["omega"] = cmd.omega;
  state.SetLabel("synthetic cluttered 12x12 m grid at 0.05 m, seed 7");
}

}  // namespace

void register_dwa() {
  const DwaSettings s;
  const std::string size = std::to_string(s.v_samples * s.omega_samples) + "x" + std::to_string(s.steps);
  for (const DuetImpl impl : kDuetImpls) {
    benchmark::RegisterBenchmark(bench_name("DWA", impl.name, size).c_str(), [impl](benchmark::State& state) {
      const DwaInput& in = dwa_input();
      const ClearanceView view = in.view();
      const DwaSettings st;
      DwaState ds;
      DwaWorkspace ws;
      DwaResult r;
      run_guarded(state, [&] {
        for (auto _ : state) {
          ds.reset();
          arena(impl.threads).execute([&] { r = dwa_step(view, in.pose, in.current, in.path, st, ds, ws); });
          benchmark::DoNotOptimize(r);
        }
      });
      report(state, static_cast<std::size_t>(st.v_samples * st.omega_samples), r.valid_trajectories);
      set_label(state, r.cmd);
    });
  }
  benchmark::RegisterBenchmark(bench_name("DWA", "naive", size).c_str(), [](benchmark::State& state) {
    const DwaInput& in = dwa_input();
    const ClearanceView view = in.view();
    const DwaSettings st;
    NaiveOut r;
    for (auto _ : state) {
      r = naive_dwa(view, in.pose, in.current, in.path, st);
      benchmark::DoNotOptimize(r);
    }
    report(state, static_cast<std::size_t>(st.v_samples * st.omega_samples), r.valid);
    set_label(state, r.cmd);
  });
}

}  // namespace duet::bench
