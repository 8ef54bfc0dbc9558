// Global path search and inflation (maps: built in bench_frontier.cpp, see its header comment:
// synthetic indoor 400x400 and 2000x2000 at 0.05 m, fixed seed, and the Willow map when present).
//
// Path/duet/{400x400,2000x2000,willow}: plan_path (A*, default PathSettings: clearance cost on)
//   from the robot to the reachable cell farthest from it by path length (across the map). Serial.
// Inflation/{duet,duet_1t}/{...}: inflate() (classification + exact Euclidean distance transform +
//   traversability, default InflationSettings), 2 threads / 1 thread.
// Items = grid cells.
#include "bench_util.hpp"

#include <duet/kernels/inflation.hpp>
#include <duet/kernels/path.hpp>

#include <string>

namespace duet::bench {

// Defined in bench_frontier.cpp.
std::size_t plan_map_count();
const std::string& plan_map_name(std::size_t i);
GridView plan_map_view(std::size_t i);
const InflatedGrid& plan_map_inflated(std::size_t i);
Eigen::Vector2f plan_map_robot(std::size_t i);
Eigen::Vector2f plan_map_far(std::size_t i);

void register_path() {
  for (std::size_t i = 0; i < plan_map_count(); ++i) {
    const std::string& name = plan_map_name(i);
    const std::size_t cells = plan_map_view(i).cell_count();
    benchmark::RegisterBenchmark(bench_name("Path", "duet", name).c_str(), [i, cells](benchmark::State& state) {
      const InflatedGrid& g = plan_map_inflated(i);
      const Eigen::Vector2f a = plan_map_robot(i), b = plan_map_far(i);
      PathWorkspace ws;
      PathResult r;
      run_guarded(state, [&] {
        for (auto _ : state) {
          r = plan_path(g, a, b, PathSettings{}, ws);
          benchmark::DoNotOptimize(r.waypoints.data());
        }
      });
      state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(cells));
      state.counters["expanded"] = static_cast<double>(r.expanded);
      state.counters["length_m"] = r.length_m;
      state.SetLabel(to_string(r.status));
    });
    for (const DuetImpl impl : kDuetImpls) {
      benchmark::RegisterBenchmark(bench_name("Inflation", impl.name, name).c_str(), [i, impl, cells](benchmark::State& state) {
        const GridView v = plan_map_view(i);
        InflatedGrid out;
        run_guarded(state, [&] {
          for (auto _ : state) {
            arena(impl.threads).execute([&] { inflate(v, InflationSettings{}, out); });
            benchmark::DoNotOptimize(out.clearance_m.data());
          }
        });
        state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(cells));
        state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(cells * sizeof(float)));
      });
    }
  }
}

}  // namespace duet::bench
