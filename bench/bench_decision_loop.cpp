// Decision/{duet,duet_1t}/{lab,willow}: the decision as the runtime takes it (issue 18, part 4):
// Navigator::decide() - every goal selection strategy (Procedure 1 with the concurrent frontier
// search, the frontier search, the relaxed grid, view goals), the standoff and the A* path - on
// states saved from real runs at the moments the loop itself decided: the grid and the pose
// estimate after a lockstep step of the dual profile (seed 1) in which the navigator took a
// decision - every one of the lab's first 90 s, and every 8th of the first 1200 s on the Willow
// Garage map (when ../shared/data is there; the run the in-loop target is measured on).
// Until stop 61 the states were taken every 15 simulated s (Willow: the first 300 s); the loop
// decides where the robot has just reached a goal, near unknown space, where the simulated
// rays pass more unknown cells, so those states gave shorter decisions than the loop's (23.3 ms
// against 27.3 ms on Willow at stop 61; their recording also used the default runtime
// settings, not the profile's). One iteration decides once on every state; its (manual) time is
// the mean decision's wall time, so "Time" is the mean over all the states. The navigator's
// costmaps for a state (update_map) are built outside the timing, as the runtime builds them at
// every map update before a decision. Three passes; "decisions": their count; "goal": the
// fraction of decisions that gave a goal; p50_ms, p99_ms and max_ms: the spread of single
// decisions' wall times; "cores_busy": the process's CPU time over the wall time while deciding
// (2 = both threads of Decision/duet busy throughout).
//
// DistanceFields/{duet,duet_1t}/{lab,willow}: the three exact distance transforms of the whole
// grid the runtime computes at every map update, on the same states: the planning costmap's
// inflation (unknown space does not block), the local costmap's (it does) and the pose
// corrector's distance to occupied cells (scan_match.hpp's occupied_distance). Time: their sum
// per state (mean over the states). At stop 64 they were ~40 % of a late Willow run's CPU time
// at -j 1 (perf).
#include "bench_util.hpp"

#include <duet/kernels/inflation.hpp>
#include <duet/kernels/scan_match.hpp>

#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/navigation/navigator.hpp>
#include <duet/sim/sim_explore.hpp>
#include <duet/sim/world.hpp>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <filesystem>
#include <memory>
#include <optional>

namespace duet::bench {
namespace {

struct LoopState {
  OccupancyGrid grid;
  Pose2 pose;
  double t_s = 0.0;
};

struct LoopStates {
  Profile profile;
  std::vector<LoopState> states;
};

/// Runs the world in lockstep and keeps the state after every every-th step that took a decision
/// (2 threads: the recording is the same for any thread count).
std::unique_ptr<LoopStates> record(sim::World world, double duration_s, std::size_t every) {
  auto out = std::make_unique<LoopStates>();
  out->profile = builtin_profile("dual");
  const sim::ExploreSettings es = sim::explore_settings(out->profile, 1, duration_s);  // as `duet explore` runs it
  arena(2).execute([&] {
    sim::SimExplore run(std::move(world), out->profile, es);
    std::size_t seen = 0;
    while (run.step()) {
      const std::size_t decided = run.runtime().explorer().navigator().decide_latency().size();
      if (decided == seen) continue;
      if (seen % every == 0) out->states.push_back({run.runtime().map_grid(), run.runtime().pose(), run.now_s()});
      seen = decided;
    }
  });
  return out;
}

const LoopStates* states(const std::string& name) {
  static std::unique_ptr<LoopStates> lab, willow;
  static bool willow_tried = false;
  if (name == "lab") {
    if (!lab) lab = record(sim::builtin_world("lab"), 90.0, 1);
    return lab.get();
  }
  if (!willow_tried) {
    willow_tried = true;
    const std::filesystem::path map = std::filesystem::path(DUET_BENCH_DATA_DIR) / "maps/willow-2010-02-18-0.10.yaml";
    if (std::filesystem::exists(map)) willow = record(sim::resolve_world(map.string()), 1200.0, 8);
  }
  return willow.get();
}

/// The world's states, or nullptr after marking the benchmark skipped (no shared data).
const LoopStates* states_or_skip(const std::string& world, benchmark::State& state) {
  const LoopStates* s = states(world);
  if (s && !s->states.empty()) return s;
  state.SkipWithError("no states: ../shared/data/maps is absent");
  return nullptr;
}

}  // namespace

void register_distance_fields() {
  for (const char* world : {"lab", "willow"})
    for (const DuetImpl impl : kDuetImpls) {
      benchmark::RegisterBenchmark(bench_name("DistanceFields", impl.name, world).c_str(), [impl, world](benchmark::State& state) {
        const LoopStates* s = states_or_skip(world, state);
        if (!s) return;
        InflationSettings planning = s->profile.exploration.inflation, local = planning;
        local.unknown_is_obstacle = true;
        InflatedGrid a, b, c;
        std::size_t cells = 0;
        for (auto _ : state) {
          for (const LoopState& st : s->states) {
            const GridView v(st.grid);
            arena(impl.threads).execute([&] {
              inflate(v, planning, a);
              inflate(v, local, b);
              occupied_distance(v, s->profile.exploration.cells, c);
            });
            cells += v.cell_count();
          }
          benchmark::DoNotOptimize(c.clearance_m.data());
        }
        state.SetItemsProcessed(static_cast<std::int64_t>(cells));
        state.counters["states"] = static_cast<double>(s->states.size());
        state.SetLabel(std::string(world) + ": " + std::to_string(s->states.size()) + " states of a real run; time per pass over all");
      })->Unit(benchmark::kMillisecond);
    }
}

void register_decision_loop() {
  register_distance_fields();
  for (const char* world : {"lab", "willow"})
    for (const DuetImpl impl : kDuetImpls) {
      benchmark::RegisterBenchmark(bench_name("Decision", impl.name, world).c_str(), [impl, world](benchmark::State& state) {
        const LoopStates* s = states_or_skip(world, state);
        if (!s) return;
        std::size_t goals = 0, decisions = 0;
        double cpu_s = 0.0, wall_s = 0.0;  // all decisions' process CPU time and wall time
        std::vector<double> ms;  // each decision's wall time: its spread over the states
        for (auto _ : state) {  // one iteration: every state once; its time: the mean decision
          double pass_s = 0.0;
          for (const LoopState& st : s->states) {
            std::optional<Navigator> nav;
            arena(impl.threads).execute([&] {
              nav.emplace(s->profile, s->profile.runtime.explorer);
              nav->add_trail(Eigen::Vector2f(st.pose.x, st.pose.y));
              nav->update_map(st.grid, st.pose, st.t_s);
            });
            timespec c0{}, c1{};
            clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
            const auto t0 = std::chrono::steady_clock::now();
            arena(impl.threads).execute([&] { nav->decide(st.pose, st.t_s); });
            const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
            cpu_s += static_cast<double>(c1.tv_sec - c0.tv_sec) + 1e-9 * static_cast<double>(c1.tv_nsec - c0.tv_nsec);
            pass_s += dt;
            ms.push_back(1e3 * dt);
            ++decisions;
            goals += nav->goal().has_value();
          }
          wall_s += pass_s;
          state.SetIterationTime(pass_s / static_cast<double>(s->states.size()));
        }
        state.counters["decisions"] = static_cast<double>(decisions);
        state.counters["states"] = static_cast<double>(s->states.size());
        state.counters["cores_busy"] = wall_s > 0.0 ? cpu_s / wall_s : 0.0;  // mean busy threads while deciding
        if (!ms.empty()) {
          std::sort(ms.begin(), ms.end());
          auto at = [&](double q) { return ms[std::min(ms.size() - 1, static_cast<std::size_t>(q * static_cast<double>(ms.size())))]; };
          state.counters["p50_ms"] = at(0.50);
          state.counters["p99_ms"] = at(0.99);
          state.counters["max_ms"] = ms.back();
        }
        state.counters["goal"] = decisions ? static_cast<double>(goals) / static_cast<double>(decisions) : 0.0;
        state.SetLabel(std::string(world) + ": " + std::to_string(s->states.size()) + " states of a real run");
      })->Unit(benchmark::kMillisecond)->UseManualTime()->Iterations(3);
    }
}

}  // namespace duet::bench
