#pragma once
/// @file orb.hpp
/// ORB features of one colour image (Rublee et al. 2011: FAST corners on an image pyramid,
/// Harris-ranked, oriented by the intensity centroid, rotated BRIEF 256-bit descriptors): the
/// first step of the visual front end (paper §2.1, "ORB feature points and corresponding
/// descriptors are obtained from the RGB images").
///
/// Detection and description are OpenCV's cv::ORB (features2d) - the reference implementation,
/// and measured the best tool here (bench `Orb/*`). What duet adds around it:
///  - the input is a strided RGB / BGR / RGBA view of caller memory (no OpenCV types in the API);
///  - features are spread over the image: the image is cut into grid_cols x grid_rows cells and
///    each cell keeps at most ceil(max_features / cells) of its strongest corners (corners of
///    other cells fill up what a textureless cell leaves), so one poster cannot take every
///    feature (ORB-SLAM's bucketing, Mur-Artal et al. 2015 §III-A, done by response);
///  - the result is plain arrays: level-0 pixel positions, pyramid octave, response and the
///    256-bit descriptor as four 64-bit words (descriptor_match.hpp).
///
/// Determinism: the same image and settings give the same features in the same order (sorted
/// by response, ties by position) on every run and thread count.
/// Thread safety: reentrant; any number of threads may extract from different images at once.
#include <duet/kernels/back_projection.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace duet {

/// A 256-bit binary descriptor (rBRIEF), bit i of byte k at word k / 8.
using Descriptor256 = std::array<std::uint64_t, 4>;

struct OrbSettings {
  int max_features = 1000;     ///< kept per image, [1, 100000]
  float scale_factor = 1.2f;   ///< pyramid decimation ratio, (1, 2]
  int levels = 8;              ///< pyramid levels, [1, 16]
  int fast_threshold = 20;     ///< FAST intensity threshold, [1, 255]
  int min_fast_threshold = 7;  ///< retried with this where the image gives too few corners, [1, fast_threshold]
  int edge_threshold = 19;     ///< border without features [px], [3, 100] (also the BRIEF patch radius)
  int grid_cols = 8;           ///< bucketing cells across, [1, 64]
  int grid_rows = 6;           ///< bucketing cells down, [1, 64]
};
/// Throws duet::Error(kInvalidArgument) naming the bad field.
void validate(const OrbSettings& s);

/// The features of one image. All arrays have size() entries.
struct OrbFeatures {
  std::vector<Eigen::Vector2f> pixels;      ///< level-0 position (u right, v down) [px]
  std::vector<Descriptor256> descriptors;   ///< rBRIEF
  std::vector<float> responses;             ///< Harris response (larger = stronger)
  std::vector<std::uint8_t> octaves;        ///< pyramid level the corner was found on
  int width = 0, height = 0;                ///< the image's size [px]

  [[nodiscard]] std::size_t size() const noexcept { return pixels.size(); }
  [[nodiscard]] bool empty() const noexcept { return pixels.empty(); }
  void clear() noexcept;
};

/// Extracts ORB features of `image` into `out` (replaced). An image with no colour data (data
/// null) or smaller than 2 * edge_threshold + 1 in either side gives no features (not an error:
/// a camera that sees nothing). Throws duet::Error(kInvalidArgument) for a bad view (size <= 0
/// with data, stride below the row, channels not 3 or 4) or bad settings.
void extract_orb(const ColorImageView& image, const OrbSettings& settings, OrbFeatures& out);

/// The 8-bit grey image extract_orb() reads: (77 R + 150 G + 29 B + 128) >> 8 per pixel, rows
/// of `image.width` bytes. Exposed for tests and the peers' benchmarks.
void to_gray(const ColorImageView& image, std::vector<std::uint8_t>& out);

}  // namespace duet
