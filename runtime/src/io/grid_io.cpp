/// @file grid_io.cpp
/// map_server YAML + image and PNG pictures of occupancy grids (see grid_io.hpp).
#include <duet/runtime/io/input_limits.hpp>
#include <duet/kernels/error.hpp>
#include "io/file_util.hpp"
#include <duet/runtime/io/grid_io.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace duet {
namespace {

using detail::fail_file;
using detail::read_whole_file;
using detail::write_file_atomically;

namespace fs = std::filesystem;
using u64 = std::uint64_t;

constexpr std::uint8_t kPgmOccupied = 0;
constexpr std::uint8_t kPgmFree = 254;
constexpr std::uint8_t kPgmUnknown = 205;
constexpr u64 kMaxPixels = u64{1} << 28;

std::string shortest(double v) {
  char buf[40];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, r.ptr);
  if (s.find_first_of(".en") == std::string::npos) s += ".0";  // keep it a YAML float
  return s;
}

std::string shortest(float v) {
  char buf[40];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, r.ptr);
  if (s.find_first_of(".en") == std::string::npos) s += ".0";
  return s;
}

/// `text` as a YAML scalar: plain when it is a safe file name, double-quoted otherwise.
std::string yaml_scalar(const std::string& text) {
  const bool plain = !text.empty() && std::all_of(text.begin(), text.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' ||
           c == '-' || c == '/';
  }) && text[0] != '-';
  if (plain) return text;
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", static_cast<unsigned>(static_cast<unsigned char>(c)));
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

/// p(occupied) of a log-odds value (NaN stays NaN).
inline double probability(float l) noexcept { return 1.0 - 1.0 / (1.0 + std::exp(static_cast<double>(l))); }

void check_grid(const OccupancyGrid& grid, const fs::path& path) {
  if (grid.width() <= 0 || grid.height() <= 0) {
    fail_file(ErrorCode::kInvalidArgument, path,
              "cannot write an empty grid (" + std::to_string(grid.width()) + "x" + std::to_string(grid.height()) +
                  " cells)");
  }
}

// ------------------------------------------------------------------------------------------
// Images: PGM (ours) and everything else (OpenCV).

/// An 8-bit image of 1 to 4 channels (the last is alpha for 2 and 4), row 0 at the top.
struct Image8 {
  int width = 0, height = 0, channels = 1;
  std::vector<std::uint8_t> data;  ///< row-major, interleaved
};

constexpr bool pgm_space(char c) noexcept { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; }

/// Parses PGM P2 (ascii) or P5 (binary), 8 or 16 bit (scaled to 0..255).
Image8 read_pgm(const fs::path& path, std::string_view file) {
  std::size_t pos = 2;
  const bool binary = file[1] == '5';
  const auto bad = [&](const std::string& what) { fail_file(ErrorCode::kParse, path, "PGM: " + what); };
  const auto skip_space_and_comments = [&]() {
    for (;;) {
      while (pos < file.size() && pgm_space(file[pos])) ++pos;
      if (pos < file.size() && file[pos] == '#') {
        while (pos < file.size() && file[pos] != '\n') ++pos;
        continue;
      }
      return;
    }
  };
  const auto header_number = [&](const char* what) -> u64 {
    skip_space_and_comments();
    const std::size_t start = pos;
    u64 v = 0;
    while (pos < file.size() && file[pos] >= '0' && file[pos] <= '9') {
      v = v * 10 + static_cast<u64>(file[pos] - '0');
      if (v > (u64{1} << 32)) bad(std::string(what) + " is too large");
      ++pos;
    }
    if (pos == start) bad(std::string("header ends before its ") + what + " (byte " + std::to_string(pos) + ")");
    return v;
  };
  if (file.size() > 2 && !pgm_space(file[2])) bad("magic number is not followed by white space");
  const u64 w = header_number("width"), h = header_number("height"), maxval = header_number("maxval");
  if (w == 0 || h == 0) bad("image is " + std::to_string(w) + "x" + std::to_string(h) + " pixels");
  if (maxval == 0 || maxval > 65535) bad("maxval is " + std::to_string(maxval) + " (allowed: 1 to 65535)");
  if (w > static_cast<u64>(std::numeric_limits<int>::max()) || h > static_cast<u64>(std::numeric_limits<int>::max()) ||
      w * h > kMaxPixels) {
    bad("image of " + std::to_string(w) + "x" + std::to_string(h) + " pixels exceeds the limit of 2^28 pixels");
  }
  const std::size_t n = static_cast<std::size_t>(w * h);
  const std::size_t bytes_per = maxval > 255 ? 2 : 1;
  Image8 img;
  img.width = static_cast<int>(w);
  img.height = static_cast<int>(h);
  const auto scale = [&](u64 v) -> std::uint8_t {
    if (v > maxval) bad("pixel value " + std::to_string(v) + " exceeds maxval " + std::to_string(maxval));
    return maxval == 255 ? static_cast<std::uint8_t>(v)
                         : static_cast<std::uint8_t>((v * 255 + maxval / 2) / maxval);
  };
  if (binary) {
    if (pos >= file.size() || !pgm_space(file[pos])) bad("header is not followed by a single white space");
    ++pos;
    const std::size_t remaining = file.size() - pos;
    if (n > remaining / bytes_per) {
      bad("data truncated: expected " + std::to_string(n) + " pixels, got " + std::to_string(remaining / bytes_per));
    }
    img.data.resize(n);
    const auto* p = reinterpret_cast<const unsigned char*>(file.data() + pos);
    for (std::size_t i = 0; i < n; ++i) {
      const u64 v = bytes_per == 1 ? p[i] : (u64{p[2 * i]} << 8) | p[2 * i + 1];
      img.data[i] = scale(v);
    }
  } else {
    // Each value takes at least 2 bytes (a digit and a separator) minus one.
    if (n > (file.size() - pos) / 2 + 1) {
      bad("data truncated: expected " + std::to_string(n) + " pixels, the file is too short");
    }
    img.data.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      skip_space_and_comments();
      if (pos >= file.size()) bad("data truncated: expected " + std::to_string(n) + " pixels, got " + std::to_string(i));
      const std::size_t start = pos;
      u64 v = 0;
      while (pos < file.size() && file[pos] >= '0' && file[pos] <= '9' && v <= 65535) {
        v = v * 10 + static_cast<u64>(file[pos] - '0');
        ++pos;
      }
      if (pos == start || (pos < file.size() && !pgm_space(file[pos]) && file[pos] != '#')) {
        bad("pixel " + std::to_string(i) + " at byte " + std::to_string(start) + " is not a number");
      }
      img.data[i] = scale(v);
    }
  }
  return img;
}

Image8 read_image(const fs::path& path) {
  const std::string file = read_whole_file(path, input_limits::kImageBytes, "map image");
  if (file.size() >= 2 && file[0] == 'P' && (file[1] == '5' || file[1] == '2')) return read_pgm(path, file);
  if (file.empty()) fail_file(ErrorCode::kParse, path, "image file is empty");
  cv::Mat m;
  try {
    const cv::Mat raw(1, static_cast<int>(std::min<std::size_t>(file.size(), std::numeric_limits<int>::max())), CV_8UC1,
                      const_cast<char*>(file.data()));
    m = cv::imdecode(raw, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    fail_file(ErrorCode::kParse, path, std::string("cannot decode the image: ") + e.what());
  }
  if (m.empty()) fail_file(ErrorCode::kParse, path, "cannot decode the image (not a PGM P2/P5, PNG or other format OpenCV reads)");
  if (m.depth() == CV_16U) {
    m.convertTo(m, CV_8U, 1.0 / 257.0);
  } else if (m.depth() != CV_8U) {
    fail_file(ErrorCode::kParse, path, "image has an unsupported pixel depth (8 or 16 bit unsigned needed)");
  }
  if (m.channels() < 1 || m.channels() > 4) {
    fail_file(ErrorCode::kParse, path, "image has " + std::to_string(m.channels()) + " channels (1 to 4 allowed)");
  }
  if (static_cast<u64>(m.cols) * static_cast<u64>(m.rows) > kMaxPixels) {
    fail_file(ErrorCode::kParse, path, "image exceeds the limit of 2^28 pixels");
  }
  Image8 img;
  img.width = m.cols;
  img.height = m.rows;
  img.channels = m.channels();
  img.data.resize(static_cast<std::size_t>(m.cols) * static_cast<std::size_t>(m.rows) * static_cast<std::size_t>(m.channels()));
  const std::size_t row_bytes = static_cast<std::size_t>(m.cols) * static_cast<std::size_t>(m.channels());
  for (int r = 0; r < m.rows; ++r) std::memcpy(img.data.data() + static_cast<std::size_t>(r) * row_bytes, m.ptr(r), row_bytes);
  return img;
}

// ------------------------------------------------------------------------------------------
// YAML

enum class MapMode { kTrinary, kScale, kRaw };

struct MapYaml {
  fs::path image;
  double resolution = 0.0;
  double origin[3] = {0.0, 0.0, 0.0};
  bool negate = false;
  double occupied_thresh = 0.65;
  double free_thresh = 0.196;
  MapMode mode = MapMode::kTrinary;
};

std::string format_limit(float v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", static_cast<double>(v));
  return buf;
}

MapYaml parse_map_yaml(const fs::path& yaml_path) {
  YAML::Node root;
  const std::string yaml_text = read_whole_file(yaml_path, input_limits::kYamlBytes, "map YAML");
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    fail_file(ErrorCode::kParse, yaml_path,
              "line " + std::to_string(e.mark.line + 1) + ", column " + std::to_string(e.mark.column + 1) + ": " + e.msg);
  }
  if (!root.IsMap()) fail_file(ErrorCode::kParse, yaml_path, "not a YAML map of keys (image, resolution, origin, ...)");

  const auto key_error = [&](const std::string& key, const YAML::Node& node, const std::string& what) {
    const std::string where = node.Mark().is_null() ? std::string() : " (line " + std::to_string(node.Mark().line + 1) + ")";
    fail_file(ErrorCode::kParse, yaml_path, "key '" + key + "'" + where + ": " + what);
  };
  const auto scalar_text = [&](const std::string& key, const YAML::Node& node) -> std::string {
    if (!node.IsScalar()) key_error(key, node, "expected a single value");
    return node.Scalar();
  };
  const auto number = [&](const std::string& key, const YAML::Node& node) -> double {
    const std::string text = scalar_text(key, node);
    double v = 0.0;
    try {
      v = node.as<double>();
    } catch (const YAML::Exception&) {
      key_error(key, node, "expected a number, got '" + text + "'");
    }
    if (!std::isfinite(v)) key_error(key, node, "expected a finite number, got '" + text + "'");
    return v;
  };

  MapYaml y;
  bool have_image = false, have_resolution = false, have_origin = false;
  for (const auto& kv : root) {
    const YAML::Node key_node = kv.first;
    const YAML::Node v = kv.second;
    const std::string key = key_node.IsScalar() ? key_node.Scalar() : std::string("?");
    if (key == "image") {
      const std::string s = scalar_text(key, v);
      if (s.empty()) key_error(key, v, "is empty");
      y.image = fs::path(s);
      have_image = true;
    } else if (key == "resolution") {
      y.resolution = number(key, v);
      if (!(y.resolution >= kMinGridResolutionM && y.resolution <= kMaxGridResolutionM)) {  // grid.hpp's limits
        key_error(key, v, "must be in [" + format_limit(kMinGridResolutionM) + ", " + format_limit(kMaxGridResolutionM) +
                              "] m per cell, got " + scalar_text(key, v));
      }
      have_resolution = true;
    } else if (key == "origin") {
      if (!v.IsSequence() || v.size() != 3) key_error(key, v, "expected [x, y, yaw]");
      for (std::size_t i = 0; i < 3; ++i) {
        y.origin[i] = number(key, v[i]);
        if (i < 2 && !(std::abs(y.origin[i]) <= kMaxCoordinateM))
          key_error(key, v, "coordinate out of range (|x|, |y| <= " + format_limit(kMaxCoordinateM) + " m, the map frame's limit)");
      }
      if (y.origin[2] != 0.0) {
        fail_file(ErrorCode::kUnsupported, yaml_path,
                  "key 'origin': yaw " + shortest(y.origin[2]) + " rad: rotated maps are not supported (yaw must be 0)");
      }
      have_origin = true;
    } else if (key == "negate") {
      const std::string text = scalar_text(key, v);
      if (text == "0" || text == "false" || text == "False") {
        y.negate = false;
      } else if (text == "1" || text == "true" || text == "True") {
        y.negate = true;
      } else {
        key_error(key, v, "must be 0 or 1, got '" + text + "'");
      }
    } else if (key == "occupied_thresh" || key == "free_thresh") {
      const double t = number(key, v);
      if (t < 0.0 || t > 1.0) key_error(key, v, "must be in [0, 1], got " + scalar_text(key, v));
      (key == "occupied_thresh" ? y.occupied_thresh : y.free_thresh) = t;
    } else if (key == "mode") {
      const std::string text = scalar_text(key, v);
      if (text == "trinary") y.mode = MapMode::kTrinary;
      else if (text == "scale") y.mode = MapMode::kScale;
      else if (text == "raw") y.mode = MapMode::kRaw;
      else key_error(key, v, "must be trinary, scale or raw, got '" + text + "'");
    } else {
      key_error(key, key_node,
                "unknown key (allowed: image, resolution, origin, negate, occupied_thresh, free_thresh, mode)");
    }
  }
  if (!have_image) fail_file(ErrorCode::kParse, yaml_path, "key 'image' is missing");
  if (!have_resolution) fail_file(ErrorCode::kParse, yaml_path, "key 'resolution' is missing");
  if (!have_origin) fail_file(ErrorCode::kParse, yaml_path, "key 'origin' is missing");
  if (y.free_thresh > y.occupied_thresh) {
    fail_file(ErrorCode::kParse, yaml_path,
              "free_thresh " + shortest(y.free_thresh) + " is above occupied_thresh " + shortest(y.occupied_thresh));
  }
  if (y.image.is_relative()) y.image = yaml_path.parent_path() / y.image;
  return y;
}

void cv_check_write(const fs::path& path, const std::vector<uchar>& png) {
  write_file_atomically(path, {std::string_view(reinterpret_cast<const char*>(png.data()), png.size())});
}

}  // namespace

// ------------------------------------------------------------------------------------------

void write_map_server(const OccupancyGrid& grid, const fs::path& yaml_path, const MapServerOptions& options) {
  check_grid(grid, yaml_path);
  constexpr double kUnknownP = 50.0 / 255.0;  // p of pixel 205
  constexpr double kFreeP = 1.0 / 255.0;      // p of pixel 254
  if (!(options.occupied_thresh > kUnknownP && options.occupied_thresh < 1.0f)) {
    fail_file(ErrorCode::kInvalidArgument, yaml_path,
              "MapServerOptions::occupied_thresh must be in (50/255, 1), got " + shortest(options.occupied_thresh));
  }
  if (!(options.free_thresh > kFreeP && options.free_thresh < kUnknownP)) {
    fail_file(ErrorCode::kInvalidArgument, yaml_path,
              "MapServerOptions::free_thresh must be in (1/255, 50/255), got " + shortest(options.free_thresh));
  }
  if (!(options.classify_free_p >= 0.0f && options.classify_free_p < options.classify_occupied_p &&
        options.classify_occupied_p <= 1.0f)) {
    fail_file(ErrorCode::kInvalidArgument, yaml_path,
              "MapServerOptions: need 0 <= classify_free_p < classify_occupied_p <= 1, got " +
                  shortest(options.classify_free_p) + " and " + shortest(options.classify_occupied_p));
  }
  if (yaml_path.filename().empty() || yaml_path.stem().empty()) {
    fail_file(ErrorCode::kInvalidArgument, yaml_path, "needs a file name");
  }
  const fs::path image_name = yaml_path.stem().string() + ".pgm";
  const fs::path image_path = yaml_path.parent_path() / image_name;
  const int w = grid.width(), h = grid.height();
  const std::string header = "P5\n# CREATOR: duet\n" + std::to_string(w) + " " + std::to_string(h) + "\n255\n";
  std::string pixels(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), static_cast<char>(kPgmUnknown));
  const auto cells = grid.logodds();
  for (int row = 0; row < h; ++row) {
    const int iy = h - 1 - row;  // image row 0 = highest y
    for (int ix = 0; ix < w; ++ix) {
      const float l = cells[grid.index(ix, iy)];
      if (std::isnan(l)) continue;
      const double p = probability(l);
      std::uint8_t v = kPgmUnknown;
      if (p >= options.classify_occupied_p) v = kPgmOccupied;
      else if (p <= options.classify_free_p) v = kPgmFree;
      pixels[static_cast<std::size_t>(row) * static_cast<std::size_t>(w) + static_cast<std::size_t>(ix)] = static_cast<char>(v);
    }
  }
  write_file_atomically(image_path, {header, pixels});
  const Eigen::Vector2f o = grid.origin();
  const std::string yaml = "image: " + yaml_scalar(image_name.string()) + "\nresolution: " + shortest(grid.resolution()) +
                           "\norigin: [" + shortest(o.x()) + ", " + shortest(o.y()) + ", 0.0]\nnegate: 0\noccupied_thresh: " +
                           shortest(options.occupied_thresh) + "\nfree_thresh: " + shortest(options.free_thresh) +
                           "\nmode: trinary\n";
  write_file_atomically(yaml_path, {yaml});
}

OccupancyGrid read_map_server(const fs::path& yaml_path, const MapServerReadOptions& options) {
  if (!std::isfinite(options.occupied_logodds) || !std::isfinite(options.free_logodds) ||
      options.free_logodds > options.occupied_logodds) {
    fail_file(ErrorCode::kInvalidArgument, yaml_path,
              "MapServerReadOptions: log-odds must be finite with free_logodds <= occupied_logodds");
  }
  const MapYaml y = parse_map_yaml(yaml_path);
  Image8 img;
  try {
    img = read_image(y.image);
  } catch (const Error& e) {
    fail(e.code(), std::string(e.what()) + " (the image of " + yaml_path.string() + ")");
  }
  OccupancyGrid grid(static_cast<float>(y.resolution),
                     Eigen::Vector2f(static_cast<float>(y.origin[0]), static_cast<float>(y.origin[1])), img.width,
                     img.height);
  const bool has_alpha = img.channels == 2 || img.channels == 4;
  const int colour_channels = has_alpha ? img.channels - 1 : img.channels;
  const auto clamp_logodds = [&](double p) -> float {
    const double l = std::log(p / (1.0 - p));
    if (!(l < options.occupied_logodds)) return options.occupied_logodds;  // also p = 1
    if (!(l > options.free_logodds)) return options.free_logodds;          // also p = 0
    return static_cast<float>(l);
  };
  auto cells = grid.logodds();
  const std::size_t w = static_cast<std::size_t>(img.width);
  for (int row = 0; row < img.height; ++row) {
    const int iy = img.height - 1 - row;
    for (int ix = 0; ix < img.width; ++ix) {
      const std::uint8_t* px = img.data.data() + (static_cast<std::size_t>(row) * w + static_cast<std::size_t>(ix)) *
                                                     static_cast<std::size_t>(img.channels);
      double sum = 0.0;
      for (int c = 0; c < colour_channels; ++c) sum += px[c];
      double colour = sum / colour_channels;
      const int alpha = has_alpha ? px[img.channels - 1] : 255;
      if (y.negate) colour = 255.0 - colour;
      float l = OccupancyGrid::kUnknown;
      if (y.mode == MapMode::kRaw) {
        // map_server passes the value through: 0..100 occupancy percent, anything else unknown.
        const double v = std::round(colour);
        if (v <= 100.0) l = clamp_logodds(v / 100.0);
      } else {
        const double occ = (255.0 - colour) / 255.0;  // map_server's formula
        if (occ > y.occupied_thresh) {
          l = options.occupied_logodds;
        } else if (occ < y.free_thresh) {
          l = options.free_logodds;
        } else if (y.mode == MapMode::kScale && alpha > 0 && y.occupied_thresh > y.free_thresh) {
          const double ratio = (occ - y.free_thresh) / (y.occupied_thresh - y.free_thresh);
          l = clamp_logodds((1.0 + 98.0 * ratio) / 100.0);
        }
      }
      cells[grid.index(ix, iy)] = l;
    }
  }
  return grid;
}

void write_grid_png(const OccupancyGrid& grid, const fs::path& path, const GridPngOptions& options) {
  check_grid(grid, path);
  const auto bad_option = [&](const std::string& what) {
    fail_file(ErrorCode::kInvalidArgument, path, "GridPngOptions::" + what);
  };
  if (options.scale < 1 || options.scale > 64) bad_option("scale must be in [1, 64], got " + std::to_string(options.scale));
  if (options.polyline_width_px < 1 || options.polyline_width_px > 64) {
    bad_option("polyline_width_px must be in [1, 64], got " + std::to_string(options.polyline_width_px));
  }
  if (options.dot_radius_px < 0 || options.dot_radius_px > 64) {
    bad_option("dot_radius_px must be in [0, 64], got " + std::to_string(options.dot_radius_px));
  }
  if (!(options.free_thresh >= 0.0f && options.free_thresh < options.occupied_thresh && options.occupied_thresh <= 1.0f)) {
    bad_option("thresholds must satisfy 0 <= free_thresh < occupied_thresh <= 1");
  }
  const int w = grid.width(), h = grid.height(), s = options.scale;
  const u64 pixels = static_cast<u64>(w) * static_cast<u64>(h) * static_cast<u64>(s) * static_cast<u64>(s);
  if (pixels > kMaxPixels) {
    fail_file(ErrorCode::kInvalidArgument, path,
              "picture of " + std::to_string(w * static_cast<u64>(s)) + "x" + std::to_string(h * static_cast<u64>(s)) +
                  " pixels exceeds the limit of 2^28 pixels (lower GridPngOptions::scale)");
  }
  const auto bgr = [](const Rgb8& c) { return cv::Vec3b(c.b, c.g, c.r); };
  const auto scalar = [](const Rgb8& c) { return cv::Scalar(c.b, c.g, c.r); };

  cv::Mat cells_img(h, w, CV_8UC3);
  const auto cells = grid.logodds();
  const double occ = options.occupied_thresh, fr = options.free_thresh;
  for (int row = 0; row < h; ++row) {
    auto* out = cells_img.ptr<cv::Vec3b>(row);
    const int iy = h - 1 - row;
    for (int ix = 0; ix < w; ++ix) {
      const float l = cells[grid.index(ix, iy)];
      if (std::isnan(l)) {
        out[ix] = bgr(options.unknown_color);
        continue;
      }
      const double p = probability(l);
      std::uint8_t g = 0;
      if (p <= fr) g = 255;
      else if (p < occ) g = static_cast<std::uint8_t>(std::lround(255.0 * (occ - p) / (occ - fr)));
      out[ix] = cv::Vec3b(g, g, g);
    }
  }
  cv::Mat img;
  try {
    if (s == 1) {
      img = cells_img;
    } else {
      cv::resize(cells_img, img, cv::Size(w * s, h * s), 0, 0, cv::INTER_NEAREST);
    }

    // World [m] -> pixel coordinates with 4 fractional bits (OpenCV's `shift`).
    constexpr int kShift = 4;
    constexpr double kOne = 1 << kShift;
    const Eigen::Vector2f o = grid.origin();
    const double px_per_m = s / static_cast<double>(grid.resolution());
    const auto to_px = [&](const Eigen::Vector2f& p) {
      const double u = (p.x() - o.x()) * px_per_m;
      const double v = (static_cast<double>(h) * s) - (p.y() - o.y()) * px_per_m;
      constexpr double kLim = 1 << 20;  // keeps shifted coordinates inside int
      return cv::Point(static_cast<int>(std::lround(std::clamp(u, -kLim, kLim) * kOne)),
                       static_cast<int>(std::lround(std::clamp(v, -kLim, kLim) * kOne)));
    };
    std::vector<cv::Point> run;
    const auto flush = [&]() {
      if (run.size() == 1) {
        cv::circle(img, run[0], static_cast<int>(options.polyline_width_px * kOne / 2), scalar(options.polyline_color),
                   cv::FILLED, cv::LINE_AA, kShift);
      } else if (run.size() > 1) {
        cv::polylines(img, run, false, scalar(options.polyline_color), options.polyline_width_px, cv::LINE_AA, kShift);
      }
      run.clear();
    };
    for (const Eigen::Vector2f& p : options.polyline) {
      if (!p.allFinite()) {
        flush();
        continue;
      }
      run.push_back(to_px(p));
    }
    flush();
    for (const Eigen::Vector2f& p : options.dots) {
      if (!p.allFinite()) continue;
      if (options.dot_radius_px == 0) {
        const cv::Point q = to_px(p);
        const int x = q.x >> kShift, y = q.y >> kShift;
        if (x >= 0 && y >= 0 && x < img.cols && y < img.rows) img.at<cv::Vec3b>(y, x) = bgr(options.dot_color);
      } else {
        cv::circle(img, to_px(p), static_cast<int>(options.dot_radius_px * kOne), scalar(options.dot_color), cv::FILLED,
                   cv::LINE_AA, kShift);
      }
    }
    std::vector<uchar> png;
    if (!cv::imencode(".png", img, png)) fail_file(ErrorCode::kInternal, path, "PNG encoding failed");
    cv_check_write(path, png);
  } catch (const cv::Exception& e) {
    fail_file(ErrorCode::kInternal, path, std::string("OpenCV failed: ") + e.what());
  } catch (const std::bad_alloc&) {
    fail_file(ErrorCode::kOutOfMemory, path, "not enough memory for the picture");
  }
}

}  // namespace duet
