// BackProjection/{duet,duet_1t,naive}/{dual,accum}: depth (+ colour) images -> coloured cloud.
// Items = pixels read.
#include "bench_util.hpp"

namespace duet::bench {

void register_back_projection() {
  for (const Input* in : {&data().dual, &data().accum}) {
    std::size_t pixels = 0;
    for (const auto& f : in->frames) pixels += std::size_t(f.depth.width) * std::size_t(f.depth.height);
    for (const DuetImpl impl : kDuetImpls) {
      benchmark::RegisterBenchmark(bench_name("BackProjection", impl.name, in->name).c_str(),
                                   [in, impl, pixels](benchmark::State& state) {
                                     PointCloud out;
                                     std::vector<std::size_t> offsets;
                                     run_guarded(state, [&] {
                                       for (auto _ : state) {
                                         arena(impl.threads).execute(
                                             [&] { back_project(in->frames, in->bp_settings, out, &offsets); });
                                         benchmark::DoNotOptimize(out.points.data());
                                         benchmark::ClobberMemory();
                                       }
                                     });
                                     report(state, pixels, double(out.size()));
                                   });
    }
    benchmark::RegisterBenchmark(bench_name("BackProjection", "naive", in->name).c_str(),
                                 [in, pixels](benchmark::State& state) {
                                   PointCloud out;
                                   for (auto _ : state) {
                                     naive_back_project(in->frames, in->bp_settings, out);
                                     benchmark::DoNotOptimize(out.points.data());
                                     benchmark::ClobberMemory();
                                   }
                                   report(state, pixels, double(out.size()));
                                 });
  }
}

}  // namespace duet::bench
