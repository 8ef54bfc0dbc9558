/// @file latency.cpp
#include <duet/runtime/robot/latency.hpp>

#include <algorithm>
#include <cmath>

namespace duet {

void LatencyStats::add(double s) {
  if (std::isfinite(s) && s >= 0.0) samples_.push_back(s);
}

LatencySummary LatencyStats::summary() const {
  LatencySummary r;
  r.count = samples_.size();
  if (samples_.empty()) return r;
  std::vector<double> v = samples_;
  std::sort(v.begin(), v.end());
  auto rank = [&](double q) {
    const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
    return v[std::min(v.size() - 1, k == 0 ? 0 : k - 1)];
  };
  r.p50_s = rank(0.50);
  r.p99_s = rank(0.99);
  r.max_s = v.back();
  double sum = 0.0;
  for (const double x : v) sum += x;
  r.mean_s = sum / static_cast<double>(v.size());
  return r;
}

std::size_t LatencyStats::count_above(double t) const {
  return static_cast<std::size_t>(std::count_if(samples_.begin(), samples_.end(), [t](double x) { return x > t; }));
}

}  // namespace duet
