/// @file latency.cpp
/// LatencyStats: exact samples, then a bounded histogram (see latency.hpp).
#include <duet/runtime/robot/latency.hpp>

#include <algorithm>
#include <cmath>

namespace duet {

namespace {
const double kLogRatio = std::log(LatencyStats::kBinRatio);
const std::size_t kBins = static_cast<std::size_t>(std::ceil(std::log(LatencyStats::kMaxS / LatencyStats::kMinS) / kLogRatio)) + 1;

/// The nearest rank (1-based, at least 1) of quantile q among n samples.
std::size_t nearest_rank(double q, std::size_t n) {
  const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(n)));
  return std::clamp<std::size_t>(k, 1, n);
}
}  // namespace

std::size_t LatencyStats::bin_of(double s) {
  if (!(s >= kMinS)) return 0;
  if (s >= kMaxS) return kBins - 1;
  return std::min(kBins - 1, static_cast<std::size_t>(std::log(s / kMinS) / kLogRatio));
}

double LatencyStats::bin_value(std::size_t bin) { return kMinS * std::exp((static_cast<double>(bin) + 0.5) * kLogRatio); }

void LatencyStats::add(double s) {
  if (!(std::isfinite(s) && s >= 0.0)) return;
  min_ = count_ == 0 ? s : std::min(min_, s);
  max_ = count_ == 0 ? s : std::max(max_, s);
  sum_ += s;
  ++count_;
  if (bins_.empty()) {
    samples_.push_back(s);
    if (samples_.size() > kExactSamples) to_histogram();
  } else {
    ++bins_[bin_of(s)];
  }
}

void LatencyStats::to_histogram() {
  bins_.assign(kBins, 0);
  for (const double s : samples_) ++bins_[bin_of(s)];
  samples_.clear();
  samples_.shrink_to_fit();
}

LatencySummary LatencyStats::summary() const {
  LatencySummary r;
  r.count = count_;
  if (count_ == 0) return r;
  r.max_s = max_;
  r.mean_s = sum_ / static_cast<double>(count_);
  if (bins_.empty()) {
    std::vector<double> v = samples_;
    std::sort(v.begin(), v.end());
    r.p50_s = v[nearest_rank(0.50, v.size()) - 1];
    r.p99_s = v[nearest_rank(0.99, v.size()) - 1];
    return r;
  }
  auto rank = [&](double q) {
    const std::size_t k = nearest_rank(q, count_);
    std::size_t seen = 0;
    for (std::size_t b = 0; b < bins_.size(); ++b) {
      seen += bins_[b];
      if (seen >= k) return std::clamp(bin_value(b), min_, max_);
    }
    return max_;
  };
  r.p50_s = rank(0.50);
  r.p99_s = rank(0.99);
  return r;
}

std::size_t LatencyStats::count_above(double t) const {
  if (bins_.empty())
    return static_cast<std::size_t>(std::count_if(samples_.begin(), samples_.end(), [t](double x) { return x > t; }));
  if (!(t < max_)) return 0;
  // Whole bins above t's bin, and t's bin by where t lies in it (within the bin: approximate).
  const std::size_t tb = bin_of(t);
  std::size_t n = 0;
  for (std::size_t b = tb + 1; b < bins_.size(); ++b) n += static_cast<std::size_t>(bins_[b]);
  if (t >= kMinS && t < kMaxS) {
    const double lo = kMinS * std::exp(static_cast<double>(tb) * kLogRatio);
    const double frac = std::clamp(std::log(t / lo) / kLogRatio, 0.0, 1.0);
    n += static_cast<std::size_t>(std::llround((1.0 - frac) * static_cast<double>(bins_[tb])));
  }
  return n;
}

}  // namespace duet
