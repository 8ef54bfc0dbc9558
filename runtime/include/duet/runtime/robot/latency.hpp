#pragma once
/// @file latency.hpp
/// Latency samples of a run (DESIGN.md §3: measured, not assumed) and their summary: p50, p99,
/// max, mean. Memory is bounded whatever the run's length (a robot runs for days): the first
/// kExactSamples samples are kept and their percentiles are exact; past that, the samples go
/// into a histogram of logarithmic bins 1 % wide (kBins bins over [kMinS, kMaxS); 20 KiB), and
/// percentiles and count_above() are exact to within a bin (0.5 % of the value). count, max
/// and mean are exact always.
/// Thread safety: one thread at a time.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace duet {

struct LatencySummary {
  std::size_t count = 0;
  double p50_s = 0.0, p99_s = 0.0, max_s = 0.0, mean_s = 0.0;
};

class LatencyStats {
 public:
  static constexpr std::size_t kExactSamples = 1u << 16;  ///< 55 min at 20 Hz
  static constexpr double kMinS = 1e-7;                   ///< below: the first bin [s]
  static constexpr double kMaxS = 1e4;                    ///< at or above: the last bin [s]
  static constexpr double kBinRatio = 1.01;               ///< each bin's upper edge / lower edge

  /// Adds one sample [s]; non-finite or negative samples are ignored.
  void add(double seconds);
  /// Percentiles by the nearest rank of the sorted samples; all 0 with no sample.
  [[nodiscard]] LatencySummary summary() const;
  /// Samples above `threshold_s`.
  [[nodiscard]] std::size_t count_above(double threshold_s) const;
  [[nodiscard]] std::size_t size() const noexcept { return count_; }
  /// True while every sample is kept (percentiles exact).
  [[nodiscard]] bool exact() const noexcept { return bins_.empty(); }

 private:
  void to_histogram();
  [[nodiscard]] static std::size_t bin_of(double s);
  [[nodiscard]] static double bin_value(std::size_t bin);  ///< the bin's geometric middle [s]

  std::vector<double> samples_;        ///< while exact()
  std::vector<std::uint64_t> bins_;    ///< once past kExactSamples
  std::size_t count_ = 0;
  double sum_ = 0.0, max_ = 0.0, min_ = 0.0;
};

}  // namespace duet
