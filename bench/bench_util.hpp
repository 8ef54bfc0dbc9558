#pragma once
/// @file bench_util.hpp
/// Small helpers shared by the benchmark files of duet_bench.
#include "common.hpp"

#include <benchmark/benchmark.h>

#include <cstdint>
#include <string>

namespace duet::bench {

/// Items = input elements per iteration (points or pixels); "out" = output size of the last
/// iteration (voxels, clusters, finite normals, ...) so contenders can be cross-checked.
inline void report(benchmark::State& state, std::size_t items, double out) {
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(items));
  state.counters["points"] = static_cast<double>(items);
  state.counters["out"] = out;
  state.SetLabel(data().source);
}

inline std::string bench_name(const char* kernel, const char* impl, const std::string& size) {
  return std::string(kernel) + "/" + impl + "/" + size;
}

/// duet contenders: {name, threads}.
struct DuetImpl {
  const char* name;
  int threads;
};
inline constexpr DuetImpl kDuetImpls[] = {{"duet", 2}, {"duet_1t", 1}};

}  // namespace duet::bench
