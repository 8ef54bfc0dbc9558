// Memory/stream: read and sum a 128 MiB array - the machine's streaming bandwidth, for reference
// (a kernel that streams its input once cannot beat this).
#include "bench_util.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <vector>

namespace duet::bench {
namespace {

constexpr std::size_t kFloats = std::size_t{32} << 20;  // 128 MiB

const std::vector<float>& stream_buffer() {
  static const std::vector<float> buf(kFloats, 1.0f);
  return buf;
}

float sum_serial(const float* p, std::size_t n) {
  float s0 = 0, s1 = 0, s2 = 0, s3 = 0, s4 = 0, s5 = 0, s6 = 0, s7 = 0;
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    s0 += p[i];
    s1 += p[i + 1];
    s2 += p[i + 2];
    s3 += p[i + 3];
    s4 += p[i + 4];
    s5 += p[i + 5];
    s6 += p[i + 6];
    s7 += p[i + 7];
  }
  for (; i < n; ++i) s0 += p[i];
  return ((s0 + s1) + (s2 + s3)) + ((s4 + s5) + (s6 + s7));
}

}  // namespace

void register_memory() {
  (void)stream_buffer();  // allocate and touch once, outside any timed loop
  for (const DuetImpl impl : kDuetImpls) {
    const std::string name = std::string("Memory/") + (impl.threads == 1 ? "stream_1t" : "stream") + "/128MiB";
    benchmark::RegisterBenchmark(name.c_str(), [impl](benchmark::State& state) {
      const auto& buf = stream_buffer();
      float total = 0;
      for (auto _ : state) {
        arena(impl.threads).execute([&] {
          total = tbb::parallel_reduce(
              tbb::blocked_range<std::size_t>(0, buf.size(), std::size_t{1} << 18), 0.0f,
              [&](const tbb::blocked_range<std::size_t>& r, float acc) {
                return acc + sum_serial(buf.data() + r.begin(), r.size());
              },
              [](float a, float b) { return a + b; });
        });
        benchmark::DoNotOptimize(total);
      }
      state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) *
                              static_cast<std::int64_t>(buf.size() * sizeof(float)));
      report(state, buf.size(), total);
      state.counters["bytes"] = static_cast<double>(buf.size() * sizeof(float));
    })->UseRealTime();  // with 2 threads the main thread's CPU time would overstate the rate
  }
}

}  // namespace duet::bench
