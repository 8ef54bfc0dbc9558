#pragma once
/// @file descriptor_match.hpp
/// Matching of 256-bit binary descriptors (ORB, orb.hpp) by Hamming distance: the second step
/// of the visual front end (paper §2.1: the current frame's features against the last location
/// point's).
///
/// For each query descriptor, the train descriptor at the smallest Hamming distance (ties: the
/// lowest train index) is its match when all of these hold:
///  - distance <= max_distance;
///  - ratio test (Lowe 2004): best < ratio * second best (ratio 1 turns it off; a query with a
///    single candidate passes);
///  - cross check: the query is also the train descriptor's nearest query (ties: lowest index).
/// Guided matching restricts the candidates of query i to the train features within radius_px
/// of its predicted pixel (a prediction from the wheel odometry); a query whose prediction is
/// not finite has no candidates. The cross check is then taken within the same windows.
///
/// The distance is computed with the CPU's popcount instruction where it has one (runtime
/// dispatch; bench `DescriptorMatch/*` against OpenCV's BFMatcher), else a portable bit count;
/// both give the same result.
/// Determinism: the result (sorted by query index) does not depend on the thread count.
/// Thread safety: reentrant; parallel inside (TBB) in the caller's task arena.
#include <duet/kernels/orb.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace duet {

struct DescriptorMatchSettings {
  int max_distance = 64;   ///< larger Hamming distances never match [bits], [0, 256]
  float ratio = 0.8f;      ///< best must be below ratio * second best, (0, 1]; 1 = no ratio test
  bool cross_check = true; ///< keep only mutual nearest neighbours
};
/// Throws duet::Error(kInvalidArgument) naming the bad field.
void validate(const DescriptorMatchSettings& s);

struct DescriptorMatch {
  std::uint32_t query = 0;
  std::uint32_t train = 0;
  std::uint32_t distance = 0;  ///< Hamming distance [bits]
  friend bool operator==(const DescriptorMatch&, const DescriptorMatch&) = default;
};

/// Number of differing bits, [0, 256].
[[nodiscard]] int hamming_distance(const Descriptor256& a, const Descriptor256& b) noexcept;

/// Brute-force matching of every query against every train descriptor (`out` replaced, sorted
/// by query). Empty inputs give no matches.
void match_descriptors(std::span<const Descriptor256> query, std::span<const Descriptor256> train,
                       const DescriptorMatchSettings& settings, std::vector<DescriptorMatch>& out);

/// Guided matching: query i only against train features whose pixel is within radius_px of
/// predicted[i]. Throws duet::Error(kInvalidArgument) when predicted.size() != query.size(),
/// train_pixels.size() != train.size() or radius_px is not > 0.
void match_descriptors_guided(std::span<const Descriptor256> query, std::span<const Eigen::Vector2f> predicted,
                              std::span<const Descriptor256> train, std::span<const Eigen::Vector2f> train_pixels,
                              float radius_px, const DescriptorMatchSettings& settings,
                              std::vector<DescriptorMatch>& out);

}  // namespace duet
