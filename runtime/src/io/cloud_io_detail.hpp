#pragma once
/// @file cloud_io_detail.hpp
/// Helpers shared by the PCD and PLY readers and writers (not installed): tokens, numbers, colours.
#include <duet/kernels/error.hpp>
#include "io/file_util.hpp"
#include <duet/runtime/io/cloud_io.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <new>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace duet::detail::cloud_io {

namespace fs = std::filesystem;

/// A token as it may appear in an error message: non-printable bytes escaped, long ones cut.
inline std::string quote_token(std::string_view s) {
  std::string out = "'";
  const std::size_t n = std::min<std::size_t>(s.size(), 40);
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    }
  }
  if (s.size() > n) out += "...";
  out += "'";
  return out;
}

inline void check_cloud(const fs::path& path, const PointCloud& cloud) {
  const auto check = [&](std::size_t n, const char* what) {
    if (n != 0 && n != cloud.points.size()) {
      fail_file(ErrorCode::kInvalidArgument, path,
                std::string("cannot write an inconsistent cloud: ") + what + " has " +
                    std::to_string(n) + " entries, points has " +
                    std::to_string(cloud.points.size()));
    }
  };
  check(cloud.colors.size(), "colors");
  check(cloud.normals.size(), "normals");
  check(cloud.curvature.size(), "curvature");
}

constexpr bool is_space(char c) noexcept {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

inline void split_tokens(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !is_space(line[i])) ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
}

/// Next line of `text` from `pos` (without '\n'), advancing pos past it.
inline std::string_view next_line(std::string_view text, std::size_t& pos) {
  const std::size_t eol = text.find('\n', pos);
  const std::size_t end = eol == std::string_view::npos ? text.size() : eol;
  std::string_view line = text.substr(pos, end - pos);
  pos = eol == std::string_view::npos ? text.size() : eol + 1;
  return line;
}

template <class T>
bool parse_int(std::string_view s, T& out) {
  if (!s.empty() && s[0] == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && p == s.data() + s.size();
}

/// Parses a float or double like strtod (nan, inf, exponents; out-of-range values become
/// +-inf or 0), without depending on the locale for ordinary numbers.
template <class T>
bool parse_real(std::string_view s, T& out) {
  if (!s.empty() && s[0] == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  if (ec == std::errc()) return p == s.data() + s.size();
  if (ec != std::errc::result_out_of_range || p != s.data() + s.size() || s.size() > 120) {
    return false;
  }
  char buf[128];
  std::memcpy(buf, s.data(), s.size());
  buf[s.size()] = '\0';
  out = static_cast<T>(std::strtod(buf, nullptr));
  return true;
}

inline void append_real(std::string& out, float v) {
  if (std::isnan(v)) {
    out += "nan";
    return;
  }
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

template <class T>
void append_int(std::string& out, T v) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

/// Appends the bytes of v in host order (PCD binary data is host order, as PCL writes it).
template <class T>
void append_raw(std::string& out, T v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

constexpr std::uint32_t pack_rgb(const Rgb8& c) noexcept {
  return (std::uint32_t{c.r} << 16) | (std::uint32_t{c.g} << 8) | std::uint32_t{c.b};
}
constexpr Rgb8 unpack_rgb(std::uint32_t v) noexcept {
  return {static_cast<std::uint8_t>((v >> 16) & 0xffu), static_cast<std::uint8_t>((v >> 8) & 0xffu),
          static_cast<std::uint8_t>(v & 0xffu)};
}

template <class T>
void reserve_or_fail(const fs::path& path, std::vector<T>& v, std::size_t n) {
  try {
    v.reserve(n);
  } catch (const std::bad_alloc&) {
    fail_file(ErrorCode::kOutOfMemory, path,
              "cannot allocate " + std::to_string(n) + " entries (the file declares them)");
  } catch (const std::length_error&) {
    fail_file(ErrorCode::kOutOfMemory, path,
              "cannot allocate " + std::to_string(n) + " entries (the file declares them)");
  }
}

template <class T>
void resize_or_fail(const fs::path& path, std::vector<T>& v, std::size_t n) {
  reserve_or_fail(path, v, n);
  v.resize(n);
}

inline std::string header_line(std::size_t n) { return "header line " + std::to_string(n) + ": "; }

}  // namespace duet::detail::cloud_io
