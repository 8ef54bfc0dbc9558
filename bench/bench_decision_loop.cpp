// Decision/{duet,duet_1t}/{lab,willow}: the decision as the runtime takes it (issue 18, part 4):
// Navigator::decide() - every goal selection strategy (Procedure 1 with the concurrent frontier
// search, the frontier search, the relaxed grid, view goals), the standoff and the A* path - on
// states saved from real runs: the grid and the pose estimate every 15 simulated s of a lockstep
// run of the dual profile (seed 1) on the lab (first 90 s) and on the Willow Garage map (first
// 300 s; when ../shared/data is there). Each iteration takes the next state round-robin; the
// navigator's costmaps for it (update_map) are built outside the timing, as the runtime builds
// them at every map update before a decision. Items = decisions; the "goal" counter is the
// fraction of decisions that gave a goal; p50_ms, p99_ms and max_ms are the spread of single
// decisions' wall times over the states.
#include "bench_util.hpp"

#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/navigation/navigator.hpp>
#include <duet/sim/sim_explore.hpp>
#include <duet/sim/world.hpp>

#include <algorithm>
#include <chrono>
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

/// Runs the world in lockstep and keeps a state every period_s (2 threads: the recording is the
/// same for any thread count).
std::unique_ptr<LoopStates> record(sim::World world, double duration_s, double period_s) {
  auto out = std::make_unique<LoopStates>();
  out->profile = builtin_profile("dual");
  sim::ExploreSettings es;
  es.seed = 1;
  es.max_time_s = duration_s;
  arena(2).execute([&] {
    sim::SimExplore run(std::move(world), out->profile, es);
    double next = period_s;
    while (run.step())
      if (run.now_s() + 1e-9 >= next) {
        out->states.push_back({run.runtime().map_grid(), run.runtime().pose(), run.now_s()});
        next += period_s;
      }
  });
  return out;
}

const LoopStates* states(const std::string& name) {
  static std::unique_ptr<LoopStates> lab, willow;
  static bool willow_tried = false;
  if (name == "lab") {
    if (!lab) lab = record(sim::builtin_world("lab"), 90.0, 15.0);
    return lab.get();
  }
  if (!willow_tried) {
    willow_tried = true;
    const std::filesystem::path map = std::filesystem::path(DUET_BENCH_DATA_DIR) / "maps/willow-2010-02-18-0.10.yaml";
    if (std::filesystem::exists(map)) willow = record(sim::resolve_world(map.string()), 300.0, 15.0);
  }
  return willow.get();
}

}  // namespace

void register_decision_loop() {
  for (const char* world : {"lab", "willow"})
    for (const DuetImpl impl : kDuetImpls) {
      benchmark::RegisterBenchmark(bench_name("Decision", impl.name, world).c_str(), [impl, world](benchmark::State& state) {
        const LoopStates* s = states(world);
        if (!s || s->states.empty()) {
          state.SkipWithError("no states: ../shared/data/maps is absent");
          return;
        }
        std::size_t k = 0, goals = 0, decisions = 0;
        std::vector<double> ms;  // each decision's wall time: its spread over the states
        for (auto _ : state) {
          state.PauseTiming();
          const LoopState& st = s->states[k++ % s->states.size()];
          std::optional<Navigator> nav;
          arena(impl.threads).execute([&] {
            nav.emplace(s->profile, s->profile.runtime.explorer);
            nav->add_trail(Eigen::Vector2f(st.pose.x, st.pose.y));
            nav->update_map(st.grid, st.pose, st.t_s);
          });
          state.ResumeTiming();
          const auto t0 = std::chrono::steady_clock::now();
          arena(impl.threads).execute([&] { nav->decide(st.pose, st.t_s); });
          ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
          ++decisions;
          goals += nav->goal().has_value();
        }
        report(state, 1, static_cast<double>(s->states.size()));
        if (!ms.empty()) {
          std::sort(ms.begin(), ms.end());
          auto at = [&](double q) { return ms[std::min(ms.size() - 1, static_cast<std::size_t>(q * static_cast<double>(ms.size())))]; };
          state.counters["p50_ms"] = at(0.50);
          state.counters["p99_ms"] = at(0.99);
          state.counters["max_ms"] = ms.back();
        }
        state.counters["goal"] = decisions ? static_cast<double>(goals) / static_cast<double>(decisions) : 0.0;
        state.SetLabel(std::string(world) + ": " + std::to_string(s->states.size()) + " states of a real run");
      })->Unit(benchmark::kMillisecond)->UseRealTime();
    }
}

}  // namespace duet::bench
