// ScanMatch/{duet,duet_1t,naive}/{400x400,2000x2000,willow}: one scan-to-map match
// (scan_match.hpp, default settings: +-0.15 m, +-1.5 deg, coarse 7 x 7 x 7 then 7 x 7 x 7 refined)
// on the planning benchmark maps of bench_frontier.cpp, from their robot cell. The scan: 2D rays
// over two Kinect-like 57 deg fans (front and right, 0.25 deg apart) to the first occupied cell
// within 5 m (its centre), in the robot frame; the prior is the truth + (0.07 m, -0.05 m, 0.8 deg).
// naive = the same two lattices scored plainly: scan_match_score() (bilinear over cell-centre
// likelihoods, one point at a time) for every candidate, no field window precomputed, and
// without duet's last step (the quadratic fitted to the 27 scores around the best: 28 more
// candidates, so duet's result is off the lattice and its err differs).
// LoopMatch/duet/...: the same scan with loop closure's wide window (runtime/loop_closure.hpp).
// Items = candidates x points; "err_mm" / "err_mdeg" = distance of the result from the truth.
#include "bench_util.hpp"

#include <duet/kernels/scan_match.hpp>
#include <duet/runtime/localization/loop_closure.hpp>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

namespace duet::bench {

std::size_t plan_map_count();
const std::string& plan_map_name(std::size_t i);
GridView plan_map_view(std::size_t i);
Eigen::Vector2f plan_map_robot(std::size_t i);

namespace {

constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;

struct MatchInput {
  std::string name;
  InflatedGrid field;  // distance to the nearest occupied cell
  std::vector<Eigen::Vector2f> points;
  Pose2 truth, prior;
};

std::vector<MatchInput>& inputs() {
  static std::vector<MatchInput> in = [] {
    std::vector<MatchInput> v;
    for (std::size_t i = 0; i < plan_map_count(); ++i) {
      MatchInput m;
      m.name = plan_map_name(i);
      const GridView g = plan_map_view(i);
      arena(2).execute([&] { occupied_distance(g, CellThresholds{}, m.field); });
      const Eigen::Vector2f r = plan_map_robot(i);
      m.truth = Pose2{r.x(), r.y(), 0.3f};
      m.prior = Pose2{r.x() + 0.07f, r.y() - 0.05f, 0.3f + 0.8f * kDeg};
      const float step = 0.5f * g.resolution_m;
      for (const float fan : {0.0f, -90.0f * kDeg})
        for (float a = -28.5f * kDeg; a <= 28.5f * kDeg; a += 0.25f * kDeg) {
          const float dir = m.truth.theta + fan + a;
          for (float d = 0.5f; d <= 5.0f; d += step) {
            const float x = r.x() + d * std::cos(dir), y = r.y() + d * std::sin(dir);
            const int cx = static_cast<int>(std::floor((x - g.origin.x()) / g.resolution_m));
            const int cy = static_cast<int>(std::floor((y - g.origin.y()) / g.resolution_m));
            if (cx < 0 || cy < 0 || cx >= g.width || cy >= g.height) break;
            if (m.field.state[m.field.index(cx, cy)] == CellState::kOccupied) {
              // The hit cell's centre, in the robot frame (the truth then scores 1).
              const Eigen::Vector2f c = g.origin + g.resolution_m * Eigen::Vector2f(cx + 0.5f, cy + 0.5f) - r;
              const float ct = std::cos(m.truth.theta), st = std::sin(m.truth.theta);
              m.points.emplace_back(ct * c.x() + st * c.y(), -st * c.x() + ct * c.y());
              break;
            }
          }
        }
      v.push_back(std::move(m));
    }
    return v;
  }();
  return in;
}

void set_counters(benchmark::State& state, const MatchInput& m, const Pose2& p, std::size_t candidates) {
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(candidates * m.points.size()));
  state.counters["points"] = static_cast<double>(m.points.size());
  state.counters["candidates"] = static_cast<double>(candidates);
  state.counters["err_mm"] = 1e3 * std::hypot(p.x - m.truth.x, p.y - m.truth.y);
  state.counters["err_mdeg"] = 1e3 * std::fabs(p.theta - m.truth.theta) / kDeg;
}

/// The lattice of scan_match() (coarse, then refined around the best) scored with
/// scan_match_score() one candidate at a time.
Pose2 naive_match(const MatchInput& m, const ScanMatchSettings& s, std::size_t& candidates) {
  const ClearanceView d = m.field.clearance();
  const float sa = s.prior_sigma_deg * kDeg;
  auto weight = [&](const Pose2& p) {
    const float dx = p.x - m.prior.x, dy = p.y - m.prior.y;
    const float dt = std::remainder(p.theta - m.prior.theta, 2.0f * std::numbers::pi_v<float>);
    return scan_match_score(d, m.points, p, s) *
           std::exp(-(dx * dx + dy * dy) / (2 * s.prior_sigma_m * s.prior_sigma_m) - dt * dt / (2 * sa * sa));
  };
  candidates = 0;
  auto search = [&](const Pose2& c, int nl, float dl, int na, float da) {
    Pose2 best = c;
    float bw = -1.0f;
    for (int k = -na; k <= na; ++k)
      for (int j = -nl; j <= nl; ++j)
        for (int i = -nl; i <= nl; ++i) {
          const Pose2 p{c.x + i * dl, c.y + j * dl, c.theta + k * da};
          const float w = weight(p);
          ++candidates;
          if (w > bw) {
            bw = w;
            best = p;
          }
        }
    return best;
  };
  const int nl = static_cast<int>(std::floor(s.linear_window_m / s.linear_step_m + 1e-4f));
  const int na = static_cast<int>(std::floor(s.angular_window_deg / s.angular_step_deg + 1e-4f));
  const Pose2 coarse = search(m.prior, nl, s.linear_step_m, na, s.angular_step_deg * kDeg);
  return search(coarse, 3, s.linear_step_m / 4, 3, s.angular_step_deg * kDeg / 4);
}

}  // namespace

void register_scan_match() {
  for (std::size_t i = 0; i < inputs().size(); ++i) {
    const MatchInput* m = &inputs()[i];
    for (const DuetImpl impl : kDuetImpls) {
      benchmark::RegisterBenchmark(bench_name("ScanMatch", impl.name, m->name).c_str(), [m, impl](benchmark::State& state) {
        ScanMatchResult r;
        run_guarded(state, [&] {
          for (auto _ : state) {
            r = arena(impl.threads).execute([&] { return scan_match(m->field.clearance(), m->points, m->prior); });
            benchmark::DoNotOptimize(r.pose.x);
          }
        });
        set_counters(state, *m, r.pose, r.candidates);
        state.SetLabel(r.status == ScanMatchStatus::kMatched ? "matched" : "not matched");
      })->UseRealTime();
    }
    benchmark::RegisterBenchmark(bench_name("ScanMatch", "naive", m->name).c_str(), [m](benchmark::State& state) {
      Pose2 p;
      std::size_t candidates = 0;
      for (auto _ : state) {
        p = naive_match(*m, ScanMatchSettings{}, candidates);
        benchmark::DoNotOptimize(p.x);
      }
      set_counters(state, *m, p, candidates);
    });
    // Loop closure's wide window (loop_match_defaults(): +-1.5 m, +-6 deg, 0.1 m / 1 deg, then a
    // quarter of that) from a prior 1 m off the truth: what one loop search costs per scan.
    benchmark::RegisterBenchmark(bench_name("LoopMatch", "duet", m->name).c_str(), [m](benchmark::State& state) {
      ScanMatchResult r;
      const Pose2 prior{m->truth.x + 0.8f, m->truth.y - 0.6f, m->truth.theta + 3.0f * kDeg};
      run_guarded(state, [&] {
        for (auto _ : state) {
          r = arena(2).execute([&] { return scan_match(m->field.clearance(), m->points, prior, loop_match_defaults()); });
          benchmark::DoNotOptimize(r.pose.x);
        }
      });
      set_counters(state, *m, r.pose, r.candidates);
      state.SetLabel(r.status == ScanMatchStatus::kMatched ? "matched" : "not matched");
    })->UseRealTime();
  }
}

}  // namespace duet::bench
