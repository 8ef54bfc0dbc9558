#pragma once
/// @file fuzz_util.hpp
/// Shared pieces of the fuzz targets (issue 19, part 2): a per-process scratch folder the
/// readers' files are written to (the readers take paths: they check regular files and sizes),
/// the split of one input into several files, and a small byte reader for the C API harness.
///
/// A target's contract: every input either succeeds or throws duet::Error; anything else (a
/// crash, a sanitizer report, another exception, a hang) is a finding.
#include <duet/kernels/error.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include <unistd.h>

namespace duet::fuzz {

/// The scratch folder of this process (created on first use, removed at exit).
inline const std::filesystem::path& scratch() {
  struct Dir {
    std::filesystem::path path;
    Dir() {
      const char* base = std::getenv("TMPDIR");
      std::string dir = std::string(base && *base ? base : "/tmp") + "/duet_fuzz_XXXXXX";  // mkdtemp fills in the Xs
      if (!::mkdtemp(dir.data())) std::abort();
      path = dir;
    }
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const Dir dir;
  return dir.path;
}

/// Writes bytes to scratch()/name (folders created), replacing the file.
inline std::filesystem::path put(const std::string& name, std::string_view bytes) {
  const std::filesystem::path p = scratch() / name;
  std::filesystem::create_directories(p.parent_path());
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!f) std::abort();
  return p;
}

/// Empties the scratch folder (the previous input's files must not leak into this one).
inline void clear_scratch() {
  for (const auto& e : std::filesystem::directory_iterator(scratch())) std::filesystem::remove_all(e.path());
}

/// One input as several files: the parts between lines "--duet-fuzz-part--". Missing parts
/// are empty.
inline std::vector<std::string_view> split_parts(const std::uint8_t* data, std::size_t size, std::size_t parts) {
  constexpr std::string_view kSep = "\n--duet-fuzz-part--\n";
  std::string_view rest(reinterpret_cast<const char*>(data), size);
  std::vector<std::string_view> out;
  while (out.size() + 1 < parts) {
    const std::size_t at = rest.find(kSep);
    if (at == std::string_view::npos) break;
    out.push_back(rest.substr(0, at));
    rest.remove_prefix(at + kSep.size());
  }
  out.push_back(rest);
  out.resize(parts);
  return out;
}

/// The scoring raster's resolution for a fuzzed world: 0.1 m, or coarser so that the raster
/// has at most 2^14 cells. rasterize() allows 2^28 (a unit test covers that limit); a fuzzer
/// soon finds floors near it, and rasterizing them took most of the run (2^20 cells: 61-67
/// inputs/s, perf: rasterize 94 %) - the code paths are the same at any size.
inline float raster_resolution(const Eigen::Vector2f& floor_min, const Eigen::Vector2f& floor_max) {
  const double area = static_cast<double>(floor_max.x() - floor_min.x()) * static_cast<double>(floor_max.y() - floor_min.y());
  const double r = std::sqrt(std::max(area, 0.0) / static_cast<double>(1u << 14));
  return std::isfinite(r) ? std::max(0.1f, static_cast<float>(r)) : 0.1f;
}

/// With DUET_FUZZ_VERBOSE set (the replay of a corpus), says whether each input was read or
/// refused and why - to check that the seeds are valid files, not only error paths.
inline bool verbose() {
  static const bool v = std::getenv("DUET_FUZZ_VERBOSE") != nullptr;
  return v;
}
inline void accepted(const char* what) {
  if (verbose()) std::fprintf(stderr, "  accepted: %s\n", what);
}
inline void refused(const duet::Error& e) {
  if (verbose()) std::fprintf(stderr, "  refused: %s\n", e.what());
}

/// Reads typed values from the input, front to back; zeros once it is used up.
class Bytes {
 public:
  Bytes(const std::uint8_t* data, std::size_t size) : p_(data), n_(size) {}
  [[nodiscard]] bool empty() const noexcept { return n_ == 0; }
  template <class T>
  T get() {
    T v{};
    const std::size_t k = std::min(sizeof(T), n_);
    if (k > 0) std::memcpy(&v, p_, k);
    p_ += k;
    n_ -= k;
    return v;
  }
  /// An integer in [lo, hi].
  std::int64_t range(std::int64_t lo, std::int64_t hi) {
    const auto span = static_cast<std::uint64_t>(hi - lo) + 1u;
    return lo + static_cast<std::int64_t>(get<std::uint32_t>() % (span == 0 ? 1u : span));
  }
  /// A float that is usually ordinary (a small value or a scaled one) and sometimes
  /// special: NaN, +-inf, 0, -0, the extremes, a denormal, or raw bits.
  float value(float typical_scale = 1.0f) {
    switch (get<std::uint8_t>() % 12) {
      case 0: return std::numeric_limits<float>::quiet_NaN();
      case 1: return std::numeric_limits<float>::infinity();
      case 2: return -std::numeric_limits<float>::infinity();
      case 3: return 0.0f;
      case 4: return std::numeric_limits<float>::max();
      case 5: return std::numeric_limits<float>::denorm_min();
      case 6: return get<float>();  // raw bits
      case 7: return static_cast<float>(get<std::int16_t>()) * typical_scale * 1e-3f * 1e4f;  // large
      default: return static_cast<float>(get<std::int16_t>()) / 32768.0f * typical_scale;
    }
  }

 private:
  const std::uint8_t* p_;
  std::size_t n_;
};

}  // namespace duet::fuzz
