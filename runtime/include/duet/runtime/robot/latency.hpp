#pragma once
/// @file latency.hpp
/// Latency samples of a run (DESIGN.md §3: measured, not assumed) and their summary: p50, p99,
/// max, mean. Samples are kept (8 bytes each: a 20 Hz series over an hour is 0.6 MB) so the
/// percentiles are exact.
/// Thread safety: one thread at a time.
#include <cstddef>
#include <vector>

namespace duet {

struct LatencySummary {
  std::size_t count = 0;
  double p50_s = 0.0, p99_s = 0.0, max_s = 0.0, mean_s = 0.0;
};

class LatencyStats {
 public:
  /// Adds one sample [s]; non-finite or negative samples are ignored.
  void add(double seconds);
  /// Percentiles by the nearest rank of the sorted samples; all 0 with no sample.
  [[nodiscard]] LatencySummary summary() const;
  /// Samples above `threshold_s`.
  [[nodiscard]] std::size_t count_above(double threshold_s) const;
  [[nodiscard]] std::size_t size() const noexcept { return samples_.size(); }

 private:
  std::vector<double> samples_;
};

}  // namespace duet
