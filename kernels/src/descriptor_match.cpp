#include <duet/kernels/descriptor_match.hpp>
#include <duet/kernels/error.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <bit>
#include <cmath>
#include <limits>
#include <string>

namespace duet {
namespace {

constexpr std::uint32_t kNoMatch = std::numeric_limits<std::uint32_t>::max();

/// Best and second-best distance and the best's index over the candidates of one descriptor.
struct Nearest {
  std::uint32_t best = 257, second = 257, index = kNoMatch;
};

/// Candidate filter: every train (brute force) or those within the window (guided).
struct AllCandidates {
  bool operator()(std::size_t, std::size_t) const noexcept { return true; }
};
struct WindowCandidates {
  WindowCandidates(std::span<const Eigen::Vector2f> pa, std::span<const Eigen::Vector2f> pb, float r2_)
      : a(reinterpret_cast<const float*>(pa.data())), b(reinterpret_cast<const float*>(pb.data())), r2(r2_) {}
  const float* a;  // a[i] vs b[j], as packed (x, y) floats
  const float* b;
  float r2;
  // (a[i] - b[j]).squaredNorm() <= r2 in plain floats (the same sum): called for every pair of
  // the brute-force loop, where Eigen's small expressions were not inlined in sanitized builds.
  bool operator()(std::size_t i, std::size_t j) const noexcept {
    const float dx = a[2 * i] - b[2 * j], dy = a[2 * i + 1] - b[2 * j + 1];
    return dx * dx + dy * dy <= r2;
  }
};
static_assert(sizeof(Eigen::Vector2f) == 2 * sizeof(float), "a pixel is two packed floats");

#define DUET_NEAREST_BODY                                                                 \
  Nearest n;                                                                              \
  const std::uint64_t q0 = q[0], q1 = q[1], q2 = q[2], q3 = q[3];                         \
  for (std::size_t j = 0; j < set.size(); ++j) {                                          \
    if (!accept(self, j)) continue;                                                       \
    const Descriptor256& t = set[j];                                                      \
    const auto d = static_cast<std::uint32_t>(__builtin_popcountll(q0 ^ t[0]) +           \
                                              __builtin_popcountll(q1 ^ t[1]) +           \
                                              __builtin_popcountll(q2 ^ t[2]) +           \
                                              __builtin_popcountll(q3 ^ t[3]));           \
    if (d < n.best) {                                                                     \
      n.second = n.best;                                                                  \
      n.best = d;                                                                         \
      n.index = static_cast<std::uint32_t>(j);                                            \
    } else if (d < n.second) {                                                            \
      n.second = d;                                                                       \
    }                                                                                     \
  }                                                                                       \
  return n;

template <class Accept>
__attribute__((target("popcnt"))) Nearest nearest_popcnt(const Descriptor256& q, std::size_t self,
                                                          std::span<const Descriptor256> set, const Accept& accept) {
  DUET_NEAREST_BODY
}
template <class Accept>
Nearest nearest_portable(const Descriptor256& q, std::size_t self, std::span<const Descriptor256> set,
                         const Accept& accept) {
  DUET_NEAREST_BODY
}
#undef DUET_NEAREST_BODY

bool has_popcnt() noexcept {
  static const bool yes = __builtin_cpu_supports("popcnt");
  return yes;
}

template <class Accept>
Nearest nearest(const Descriptor256& q, std::size_t self, std::span<const Descriptor256> set, const Accept& accept) {
  return has_popcnt() ? nearest_popcnt(q, self, set, accept) : nearest_portable(q, self, set, accept);
}

template <class AcceptQT, class AcceptTQ>
void match(std::span<const Descriptor256> query, std::span<const Descriptor256> train, const DescriptorMatchSettings& s,
           const AcceptQT& accept_qt, const AcceptTQ& accept_tq, std::vector<DescriptorMatch>& out) {
  validate(s);
  out.clear();
  if (query.empty() || train.empty()) return;
  std::vector<Nearest> forward(query.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, query.size(), 64), [&](const auto& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) forward[i] = nearest(query[i], i, train, accept_qt);
  });
  std::vector<std::uint32_t> backward;
  if (s.cross_check) {
    // Only trains some query chose need their own nearest query.
    backward.assign(train.size(), kNoMatch);
    std::vector<char> wanted(train.size(), 0);
    for (const auto& n : forward)
      if (n.index != kNoMatch) wanted[n.index] = 1;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, train.size(), 64), [&](const auto& r) {
      for (std::size_t j = r.begin(); j < r.end(); ++j)
        if (wanted[j]) backward[j] = nearest(train[j], j, query, accept_tq).index;
    });
  }
  const auto max_d = static_cast<std::uint32_t>(s.max_distance);
  for (std::size_t i = 0; i < query.size(); ++i) {
    const Nearest& n = forward[i];
    if (n.index == kNoMatch || n.best > max_d) continue;
    if (s.ratio < 1.0f && n.second <= 256 && !(static_cast<float>(n.best) < s.ratio * static_cast<float>(n.second))) continue;
    if (s.cross_check && backward[n.index] != i) continue;
    out.push_back({static_cast<std::uint32_t>(i), n.index, n.best});
  }
}

}  // namespace

void validate(const DescriptorMatchSettings& s) {
  if (s.max_distance < 0 || s.max_distance > 256)
    fail(ErrorCode::kInvalidArgument, "descriptor match settings: max_distance must be in [0, 256], got " + std::to_string(s.max_distance));
  if (!(s.ratio > 0.0f && s.ratio <= 1.0f))
    fail(ErrorCode::kInvalidArgument, "descriptor match settings: ratio must be in (0, 1], got " + std::to_string(s.ratio));
}

int hamming_distance(const Descriptor256& a, const Descriptor256& b) noexcept {
  return std::popcount(a[0] ^ b[0]) + std::popcount(a[1] ^ b[1]) + std::popcount(a[2] ^ b[2]) + std::popcount(a[3] ^ b[3]);
}

void match_descriptors(std::span<const Descriptor256> query, std::span<const Descriptor256> train,
                       const DescriptorMatchSettings& settings, std::vector<DescriptorMatch>& out) {
  match(query, train, settings, AllCandidates{}, AllCandidates{}, out);
}

void match_descriptors_guided(std::span<const Descriptor256> query, std::span<const Eigen::Vector2f> predicted,
                              std::span<const Descriptor256> train, std::span<const Eigen::Vector2f> train_pixels,
                              float radius_px, const DescriptorMatchSettings& settings,
                              std::vector<DescriptorMatch>& out) {
  if (predicted.size() != query.size())
    fail(ErrorCode::kInvalidArgument, "match_descriptors_guided: " + std::to_string(predicted.size()) +
                                          " predicted pixels for " + std::to_string(query.size()) + " queries");
  if (train_pixels.size() != train.size())
    fail(ErrorCode::kInvalidArgument, "match_descriptors_guided: " + std::to_string(train_pixels.size()) +
                                          " train pixels for " + std::to_string(train.size()) + " train descriptors");
  if (!(radius_px > 0.0f) || !std::isfinite(radius_px))
    fail(ErrorCode::kInvalidArgument, "match_descriptors_guided: radius_px must be > 0, got " + std::to_string(radius_px));
  const float r2 = radius_px * radius_px;
  // A NaN prediction fails every <= comparison: no candidates, as documented.
  match(query, train, settings, WindowCandidates{predicted, train_pixels, r2}, WindowCandidates{train_pixels, predicted, r2},
        out);
}

}  // namespace duet
