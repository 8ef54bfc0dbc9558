#include <duet/kernels/error.hpp>
#include <duet/kernels/orb.hpp>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <string>

namespace duet {
namespace {

void bad(const std::string& what) { fail(ErrorCode::kInvalidArgument, "orb settings: " + what); }

std::size_t row_bytes(const ColorImageView& v) {
  const std::size_t tight = static_cast<std::size_t>(v.width) * static_cast<std::size_t>(v.channels);
  return v.row_stride_bytes == 0 ? tight : v.row_stride_bytes;
}

void check_view(const ColorImageView& v) {
  if (v.data == nullptr) return;
  if (v.width <= 0 || v.height <= 0)
    fail(ErrorCode::kInvalidArgument, "extract_orb: image size " + std::to_string(v.width) + "x" +
                                          std::to_string(v.height) + " must be positive");
  if (v.channels != 3 && v.channels != 4)
    fail(ErrorCode::kInvalidArgument, "extract_orb: channels must be 3 or 4, got " + std::to_string(v.channels));
  if (v.row_stride_bytes != 0 && v.row_stride_bytes < static_cast<std::size_t>(v.width) * v.channels)
    fail(ErrorCode::kInvalidArgument, "extract_orb: row stride " + std::to_string(v.row_stride_bytes) +
                                          " is below the row's " + std::to_string(v.width * v.channels) + " bytes");
}

Descriptor256 to_descriptor(const std::uint8_t* row) {
  Descriptor256 d{};
  std::memcpy(d.data(), row, 32);
  return d;
}

}  // namespace

void validate(const OrbSettings& s) {
  if (s.max_features < 1 || s.max_features > 100000) bad("max_features must be in [1, 100000], got " + std::to_string(s.max_features));
  if (!(s.scale_factor > 1.0f && s.scale_factor <= 2.0f)) bad("scale_factor must be in (1, 2], got " + std::to_string(s.scale_factor));
  if (s.levels < 1 || s.levels > 16) bad("levels must be in [1, 16], got " + std::to_string(s.levels));
  if (s.fast_threshold < 1 || s.fast_threshold > 255) bad("fast_threshold must be in [1, 255], got " + std::to_string(s.fast_threshold));
  if (s.min_fast_threshold < 1 || s.min_fast_threshold > s.fast_threshold)
    bad("min_fast_threshold must be in [1, fast_threshold], got " + std::to_string(s.min_fast_threshold));
  if (s.edge_threshold < 3 || s.edge_threshold > 100) bad("edge_threshold must be in [3, 100], got " + std::to_string(s.edge_threshold));
  if (s.grid_cols < 1 || s.grid_cols > 64) bad("grid_cols must be in [1, 64], got " + std::to_string(s.grid_cols));
  if (s.grid_rows < 1 || s.grid_rows > 64) bad("grid_rows must be in [1, 64], got " + std::to_string(s.grid_rows));
}

void OrbFeatures::clear() noexcept {
  pixels.clear();
  descriptors.clear();
  responses.clear();
  octaves.clear();
  width = height = 0;
}

void to_gray(const ColorImageView& image, std::vector<std::uint8_t>& out) {
  check_view(image);
  out.clear();
  if (image.data == nullptr) return;
  const std::size_t w = static_cast<std::size_t>(image.width), h = static_cast<std::size_t>(image.height);
  out.resize(w * h);
  const std::size_t stride = row_bytes(image);
  const int ri = image.bgr ? 2 : 0, bi = image.bgr ? 0 : 2, ch = image.channels;
  for (std::size_t y = 0; y < h; ++y) {
    const std::uint8_t* src = image.data + y * stride;
    std::uint8_t* dst = out.data() + y * w;
    for (std::size_t x = 0; x < w; ++x, src += ch)
      dst[x] = static_cast<std::uint8_t>((77u * src[ri] + 150u * src[1] + 29u * src[bi] + 128u) >> 8);
  }
}

void extract_orb(const ColorImageView& image, const OrbSettings& settings, OrbFeatures& out) {
  validate(settings);
  check_view(image);
  out.clear();
  if (image.data == nullptr) return;
  out.width = image.width;
  out.height = image.height;
  if (image.width < 2 * settings.edge_threshold + 1 || image.height < 2 * settings.edge_threshold + 1) return;

  thread_local std::vector<std::uint8_t> gray;
  to_gray(image, gray);
  const cv::Mat mat(image.height, image.width, CV_8UC1, gray.data());

  // Twice the budget from cv::ORB, then bucketing keeps the best spread of max_features.
  const int budget = 2 * settings.max_features;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  auto detect = [&](int fast_threshold) {
    keypoints.clear();
    descriptors.release();
    const auto orb = cv::ORB::create(budget, settings.scale_factor, settings.levels, settings.edge_threshold, 0, 2,
                                     cv::ORB::HARRIS_SCORE, 31, fast_threshold);
    orb->detectAndCompute(mat, cv::noArray(), keypoints, descriptors);
  };
  detect(settings.fast_threshold);
  if (static_cast<int>(keypoints.size()) < settings.max_features / 2 && settings.min_fast_threshold < settings.fast_threshold)
    detect(settings.min_fast_threshold);
  if (keypoints.empty()) return;

  // Strongest first; ties by position so the order never depends on OpenCV's internal order.
  std::vector<std::uint32_t> order(keypoints.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    const auto &ka = keypoints[a], &kb = keypoints[b];
    if (ka.response != kb.response) return ka.response > kb.response;
    if (ka.pt.y != kb.pt.y) return ka.pt.y < kb.pt.y;
    if (ka.pt.x != kb.pt.x) return ka.pt.x < kb.pt.x;
    return ka.octave < kb.octave;
  });

  // Bucketing: first pass takes up to `quota` per cell, the second fills with the rest by strength.
  const int cells = settings.grid_cols * settings.grid_rows;
  const int quota = (settings.max_features + cells - 1) / cells;
  std::vector<int> taken(static_cast<std::size_t>(cells), 0);
  std::vector<char> keep(keypoints.size(), 0);
  int kept = 0;
  const float cw = static_cast<float>(image.width) / static_cast<float>(settings.grid_cols);
  const float chh = static_cast<float>(image.height) / static_cast<float>(settings.grid_rows);
  for (const std::uint32_t i : order) {
    if (kept >= settings.max_features) break;
    const int cx = std::clamp(static_cast<int>(keypoints[i].pt.x / cw), 0, settings.grid_cols - 1);
    const int cy = std::clamp(static_cast<int>(keypoints[i].pt.y / chh), 0, settings.grid_rows - 1);
    int& t = taken[static_cast<std::size_t>(cy * settings.grid_cols + cx)];
    if (t < quota) {
      ++t;
      keep[i] = 1;
      ++kept;
    }
  }
  for (const std::uint32_t i : order) {
    if (kept >= settings.max_features) break;
    if (!keep[i]) {
      keep[i] = 1;
      ++kept;
    }
  }

  out.pixels.reserve(static_cast<std::size_t>(kept));
  out.descriptors.reserve(static_cast<std::size_t>(kept));
  out.responses.reserve(static_cast<std::size_t>(kept));
  out.octaves.reserve(static_cast<std::size_t>(kept));
  for (const std::uint32_t i : order) {
    if (!keep[i]) continue;
    const auto& k = keypoints[i];
    out.pixels.emplace_back(k.pt.x, k.pt.y);
    out.descriptors.push_back(to_descriptor(descriptors.ptr<std::uint8_t>(static_cast<int>(i))));
    out.responses.push_back(k.response);
    out.octaves.push_back(static_cast<std::uint8_t>(std::clamp(k.octave, 0, 255)));
  }
}

}  // namespace duet
