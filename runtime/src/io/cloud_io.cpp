/// @file cloud_io.cpp
/// PCD and PLY readers and writers (see cloud_io.hpp). The whole file is read into memory and
/// parsed with explicit bounds checks; declared counts are checked against the bytes actually
/// present before any allocation that depends on them.
#include <duet/kernels/error.hpp>
#include "io/file_util.hpp"
#include <duet/runtime/io/cloud_io.hpp>

#include <lzf.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <atomic>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <new>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <vector>

namespace duet {
namespace {

using detail::fail_file;
using detail::read_whole_file;
using detail::write_file_atomically;

namespace fs = std::filesystem;
using u64 = std::uint64_t;

// ------------------------------------------------------------------------------------------
// Shared helpers: errors, whole-file read, atomic write, tokens and numbers.

/// A token as it may appear in an error message: non-printable bytes escaped, long ones cut.
std::string quote_token(std::string_view s) {
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

void check_cloud(const fs::path& path, const PointCloud& cloud) {
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

void split_tokens(std::string_view line, std::vector<std::string_view>& out) {
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
std::string_view next_line(std::string_view text, std::size_t& pos) {
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

void append_real(std::string& out, float v) {
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

// ------------------------------------------------------------------------------------------
// PCD

struct PcdField {
  std::string name;
  std::uint32_t size = 4;  ///< bytes per element
  char type = 'F';         ///< I, U or F
  u64 count = 1;           ///< elements
  u64 record_offset = 0;   ///< byte offset inside a binary record
  u64 first_token = 0;     ///< index of its first value on an ascii line
  [[nodiscard]] u64 bytes() const noexcept { return size * count; }
};

struct PcdHeader {
  std::vector<PcdField> fields;
  u64 record_size = 0;       ///< bytes per point
  u64 tokens_per_point = 0;  ///< values per ascii line
  PcdInfo info;
  u64 points = 0;
  std::size_t data_offset = 0;  ///< first byte after the DATA line
  std::size_t data_line = 0;    ///< line number of the first data line
  // Role field indices (-1: absent).
  int x = -1, y = -1, z = -1, rgb = -1, nx = -1, ny = -1, nz = -1, curvature = -1;
};

std::string header_line(std::size_t n) { return "header line " + std::to_string(n) + ": "; }

PcdHeader parse_pcd_header(const fs::path& path, std::string_view file) {
  PcdHeader h;
  std::vector<std::string_view> tok;
  std::vector<std::string> names;
  std::vector<u64> sizes, counts;
  std::vector<char> types;
  std::size_t fields_line = 0, size_line = 0, type_line = 0, count_line = 0, width_line = 0,
              height_line = 0, points_line = 0, viewpoint_line = 0;
  bool have_width = false, have_height = false, have_points = false, have_data = false;
  std::size_t pos = 0, line_no = 0;

  const auto bad = [&](const std::string& what) {
    fail_file(ErrorCode::kParse, path, header_line(line_no) + what);
  };
  const auto once = [&](std::size_t& seen_line, std::string_view kw) {
    if (seen_line != 0) {
      bad(std::string(kw) + " appears twice (first on line " + std::to_string(seen_line) + ")");
    }
    seen_line = line_no;
  };
  const auto one_uint = [&](std::string_view kw) -> u64 {
    if (tok.size() != 2) {
      bad(std::string(kw) + " needs exactly one value, has " + std::to_string(tok.size() - 1));
    }
    u64 v = 0;
    if (!parse_int(tok[1], v)) bad(std::string(kw) + " value " + quote_token(tok[1]) + " is not a non-negative integer");
    return v;
  };

  while (pos < file.size() && !have_data) {
    const std::string_view line = next_line(file, pos);
    ++line_no;
    split_tokens(line, tok);
    if (tok.empty() || tok[0][0] == '#') continue;
    const std::string_view kw = tok[0];
    if (kw == "VERSION") {
      continue;
    } else if (kw == "FIELDS" || kw == "COLUMNS") {
      once(fields_line, "FIELDS");
      if (tok.size() < 2) bad("FIELDS has no entries");
      for (std::size_t i = 1; i < tok.size(); ++i) names.emplace_back(tok[i]);
    } else if (kw == "SIZE") {
      once(size_line, "SIZE");
      for (std::size_t i = 1; i < tok.size(); ++i) {
        u64 v = 0;
        if (!parse_int(tok[i], v) || (v != 1 && v != 2 && v != 4 && v != 8)) {
          bad("SIZE entry " + std::to_string(i) + " is " + quote_token(tok[i]) + " (allowed: 1, 2, 4, 8)");
        }
        sizes.push_back(v);
      }
    } else if (kw == "TYPE") {
      once(type_line, "TYPE");
      for (std::size_t i = 1; i < tok.size(); ++i) {
        if (tok[i].size() != 1 || (tok[i][0] != 'F' && tok[i][0] != 'I' && tok[i][0] != 'U')) {
          bad("TYPE entry " + std::to_string(i) + " is " + quote_token(tok[i]) + " (allowed: F, I, U)");
        }
        types.push_back(tok[i][0]);
      }
    } else if (kw == "COUNT") {
      once(count_line, "COUNT");
      for (std::size_t i = 1; i < tok.size(); ++i) {
        u64 v = 0;
        if (!parse_int(tok[i], v) || v == 0 || v > (u64{1} << 30)) {
          bad("COUNT entry " + std::to_string(i) + " is " + quote_token(tok[i]) + " (allowed: 1 to 2^30)");
        }
        counts.push_back(v);
      }
    } else if (kw == "WIDTH") {
      once(width_line, "WIDTH");
      h.info.width = one_uint("WIDTH");
      have_width = true;
    } else if (kw == "HEIGHT") {
      once(height_line, "HEIGHT");
      h.info.height = one_uint("HEIGHT");
      have_height = true;
    } else if (kw == "POINTS") {
      once(points_line, "POINTS");
      h.points = one_uint("POINTS");
      have_points = true;
    } else if (kw == "VIEWPOINT") {
      once(viewpoint_line, "VIEWPOINT");
      if (tok.size() != 8) {
        bad("VIEWPOINT needs 7 values (tx ty tz qw qx qy qz), has " + std::to_string(tok.size() - 1));
      }
      for (std::size_t i = 0; i < 7; ++i) {
        if (!parse_real(tok[i + 1], h.info.viewpoint[i]) || !std::isfinite(h.info.viewpoint[i])) {
          bad("VIEWPOINT value " + std::to_string(i + 1) + " " + quote_token(tok[i + 1]) + " is not a finite number");
        }
      }
    } else if (kw == "DATA") {
      if (tok.size() != 2) bad("DATA needs one value (ascii, binary or binary_compressed)");
      if (tok[1] == "ascii") {
        h.info.encoding = PcdEncoding::kAscii;
      } else if (tok[1] == "binary") {
        h.info.encoding = PcdEncoding::kBinary;
      } else if (tok[1] == "binary_compressed") {
        h.info.encoding = PcdEncoding::kBinaryCompressed;
      } else {
        bad("DATA is " + quote_token(tok[1]) + " (allowed: ascii, binary, binary_compressed)");
      }
      have_data = true;
      h.data_offset = pos;
      h.data_line = line_no + 1;
    } else {
      bad("unknown keyword " + quote_token(kw));
    }
  }
  if (!have_data) {
    fail_file(ErrorCode::kParse, path,
              line_no == 0 ? std::string("empty file, not a PCD file")
                           : "header has no DATA line (read " + std::to_string(line_no) + " lines)");
  }
  const auto missing = [&](const char* kw) {
    fail_file(ErrorCode::kParse, path, std::string("header has no ") + kw + " line");
  };
  const auto mismatch = [&](std::size_t at, const char* kw, std::size_t n) {
    fail_file(ErrorCode::kParse, path,
              header_line(at) + kw + " has " + std::to_string(n) + " entries, FIELDS has " +
                  std::to_string(names.size()));
  };
  if (fields_line == 0) missing("FIELDS");
  if (size_line == 0) missing("SIZE");
  if (type_line == 0) missing("TYPE");
  if (sizes.size() != names.size()) mismatch(size_line, "SIZE", sizes.size());
  if (types.size() != names.size()) mismatch(type_line, "TYPE", types.size());
  if (count_line == 0) counts.assign(names.size(), 1);
  if (counts.size() != names.size()) mismatch(count_line, "COUNT", counts.size());

  h.fields.resize(names.size());
  for (std::size_t i = 0; i < names.size(); ++i) {
    PcdField& f = h.fields[i];
    f.name = names[i];
    f.size = static_cast<std::uint32_t>(sizes[i]);
    f.type = types[i];
    f.count = counts[i];
    if (f.type == 'F' && f.size != 4 && f.size != 8) {
      fail_file(ErrorCode::kParse, path,
                header_line(type_line) + "field " + quote_token(f.name) + " is TYPE F with SIZE " +
                    std::to_string(f.size) + " (F needs SIZE 4 or 8)");
    }
    if (h.record_size > (u64{1} << 40)) {
      fail_file(ErrorCode::kParse, path, header_line(count_line) + "points larger than 2^40 bytes");
    }
    f.record_offset = h.record_size;
    f.first_token = h.tokens_per_point;
    h.record_size += f.bytes();  // <= 2^33 per field: no overflow for any line length
    h.tokens_per_point += f.count;
  }

  // Points, width, height (PCL: WIDTH x HEIGHT must equal POINTS).
  if (!have_points && !have_width) missing("POINTS");
  if (!have_height) h.info.height = 1;
  if (!have_width) h.info.width = h.info.height == 0 ? 0 : h.points / h.info.height;
  u64 wh = 0;
  if (__builtin_mul_overflow(h.info.width, h.info.height, &wh)) {
    fail_file(ErrorCode::kParse, path,
              header_line(height_line) + "WIDTH x HEIGHT = " + std::to_string(h.info.width) + " x " +
                  std::to_string(h.info.height) + " overflows");
  }
  if (!have_points) h.points = wh;
  if (wh != h.points) {
    fail_file(ErrorCode::kParse, path,
              header_line(points_line) + "WIDTH x HEIGHT = " + std::to_string(h.info.width) + " x " +
                  std::to_string(h.info.height) + " = " + std::to_string(wh) + ", POINTS is " +
                  std::to_string(h.points));
  }

  // Fields duet reads.
  const auto role = [&](int& slot, std::string_view name) {
    for (std::size_t i = 0; i < h.fields.size(); ++i) {
      if (h.fields[i].name != name) continue;
      if (slot >= 0) {
        fail_file(ErrorCode::kParse, path, header_line(fields_line) + "field " + quote_token(name) + " appears twice");
      }
      slot = static_cast<int>(i);
    }
  };
  role(h.x, "x");
  role(h.y, "y");
  role(h.z, "z");
  role(h.nx, "normal_x");
  role(h.ny, "normal_y");
  role(h.nz, "normal_z");
  role(h.curvature, "curvature");
  int rgb = -1, rgba = -1;
  role(rgb, "rgb");
  role(rgba, "rgba");
  h.rgb = rgb >= 0 ? rgb : rgba;
  if (h.x < 0 || h.y < 0 || h.z < 0) {
    fail_file(ErrorCode::kParse, path, header_line(fields_line) + "FIELDS lacks x, y or z");
  }
  if (h.nx < 0 || h.ny < 0 || h.nz < 0) h.nx = h.ny = h.nz = -1;  // partial normals: ignored
  for (const int idx : {h.x, h.y, h.z, h.nx, h.ny, h.nz, h.curvature, h.rgb}) {
    if (idx < 0) continue;
    const PcdField& f = h.fields[static_cast<std::size_t>(idx)];
    if (f.count != 1) {
      fail_file(ErrorCode::kParse, path,
                header_line(count_line) + "field " + quote_token(f.name) + " has COUNT " +
                    std::to_string(f.count) + ", expected 1");
    }
  }
  if (h.rgb >= 0 && h.fields[static_cast<std::size_t>(h.rgb)].size != 4) {
    fail_file(ErrorCode::kParse, path,
              header_line(size_line) + "field " + quote_token(h.fields[static_cast<std::size_t>(h.rgb)].name) +
                  " has SIZE " + std::to_string(h.fields[static_cast<std::size_t>(h.rgb)].size) +
                  ", packed colour needs 4");
  }
  return h;
}

/// Value of one element at p, converted to float.
inline float load_as_float(const char* p, char type, std::uint32_t size) noexcept {
  switch (type) {
    case 'F':
      if (size == 4) {
        float v;
        std::memcpy(&v, p, 4);
        return v;
      } else {
        double v;
        std::memcpy(&v, p, 8);
        return static_cast<float>(v);
      }
    case 'I':
      switch (size) {
        case 1: return static_cast<float>(static_cast<std::int8_t>(*p));
        case 2: { std::int16_t v; std::memcpy(&v, p, 2); return static_cast<float>(v); }
        case 4: { std::int32_t v; std::memcpy(&v, p, 4); return static_cast<float>(v); }
        default: { std::int64_t v; std::memcpy(&v, p, 8); return static_cast<float>(v); }
      }
    default:
      switch (size) {
        case 1: return static_cast<float>(static_cast<std::uint8_t>(*p));
        case 2: { std::uint16_t v; std::memcpy(&v, p, 2); return static_cast<float>(v); }
        case 4: { std::uint32_t v; std::memcpy(&v, p, 4); return static_cast<float>(v); }
        default: { std::uint64_t v; std::memcpy(&v, p, 8); return static_cast<float>(v); }
      }
  }
}

/// Reads the role fields of `n` points from memory where element i of field f is at
/// base + offset[f] + i * stride[f].
void decode_pcd_binary(const PcdHeader& h, const char* base, const std::vector<u64>& offset,
                       const std::vector<u64>& stride, const fs::path& path, PointCloud& cloud) {
  const std::size_t n = static_cast<std::size_t>(h.points);
  resize_or_fail(path, cloud.points, n);
  const auto field = [&](int idx) -> const PcdField& { return h.fields[static_cast<std::size_t>(idx)]; };
  const auto read_column = [&](int idx, auto&& store) {
    const PcdField& f = field(idx);
    const char* p = base + offset[static_cast<std::size_t>(idx)];
    const u64 s = stride[static_cast<std::size_t>(idx)];
    if (f.type == 'F' && f.size == 4) {
      for (std::size_t i = 0; i < n; ++i, p += s) {
        float v;
        std::memcpy(&v, p, 4);
        store(i, v);
      }
    } else {
      for (std::size_t i = 0; i < n; ++i, p += s) store(i, load_as_float(p, f.type, f.size));
    }
  };
  read_column(h.x, [&](std::size_t i, float v) { cloud.points[i].x() = v; });
  read_column(h.y, [&](std::size_t i, float v) { cloud.points[i].y() = v; });
  read_column(h.z, [&](std::size_t i, float v) { cloud.points[i].z() = v; });
  if (h.nx >= 0) {
    resize_or_fail(path, cloud.normals, n);
    read_column(h.nx, [&](std::size_t i, float v) { cloud.normals[i].x() = v; });
    read_column(h.ny, [&](std::size_t i, float v) { cloud.normals[i].y() = v; });
    read_column(h.nz, [&](std::size_t i, float v) { cloud.normals[i].z() = v; });
  }
  if (h.curvature >= 0) {
    resize_or_fail(path, cloud.curvature, n);
    read_column(h.curvature, [&](std::size_t i, float v) { cloud.curvature[i] = v; });
  }
  if (h.rgb >= 0) {
    resize_or_fail(path, cloud.colors, n);
    const char* p = base + offset[static_cast<std::size_t>(h.rgb)];
    const u64 s = stride[static_cast<std::size_t>(h.rgb)];
    for (std::size_t i = 0; i < n; ++i, p += s) {
      std::uint32_t v;
      std::memcpy(&v, p, 4);
      cloud.colors[i] = unpack_rgb(v);
    }
  }
}

void read_pcd_ascii(const PcdHeader& h, std::string_view file, const fs::path& path, PointCloud& cloud) {
  const std::size_t remaining = file.size() - h.data_offset;
  // A point takes at least 2 bytes per value (the value and a separator) minus one.
  const u64 max_points = remaining / std::max<u64>(1, 2 * h.tokens_per_point - 1) + 1;
  const std::size_t cap = static_cast<std::size_t>(std::min(h.points, max_points));
  reserve_or_fail(path, cloud.points, cap);
  if (h.nx >= 0) reserve_or_fail(path, cloud.normals, cap);
  if (h.curvature >= 0) reserve_or_fail(path, cloud.curvature, cap);
  if (h.rgb >= 0) reserve_or_fail(path, cloud.colors, cap);

  std::vector<std::string_view> tok;
  std::size_t pos = h.data_offset;
  std::size_t line_no = h.data_line - 1;
  u64 got = 0;
  const auto bad = [&](const std::string& what) {
    fail_file(ErrorCode::kParse, path, "line " + std::to_string(line_no) + ": " + what);
  };
  const auto value = [&](int idx) -> float {
    const PcdField& f = h.fields[static_cast<std::size_t>(idx)];
    const std::string_view t = tok[static_cast<std::size_t>(f.first_token)];
    float v = 0.0f;
    bool ok = false;
    if (f.type == 'F' && f.size == 4) {
      ok = parse_real(t, v);
    } else if (f.type == 'F') {
      double d = 0.0;
      ok = parse_real(t, d);
      v = static_cast<float>(d);
    } else {
      std::int64_t i = 0;
      std::uint64_t u = 0;
      double d = 0.0;
      if (f.type == 'I' && parse_int(t, i)) {
        v = static_cast<float>(i), ok = true;
      } else if (f.type == 'U' && parse_int(t, u)) {
        v = static_cast<float>(u), ok = true;
      } else if (parse_real(t, d)) {
        v = static_cast<float>(d), ok = true;
      }
    }
    if (!ok) bad(quote_token(t) + " is not a number (field " + quote_token(f.name) + ")");
    return v;
  };
  const auto packed_colour = [&]() -> std::uint32_t {
    const PcdField& f = h.fields[static_cast<std::size_t>(h.rgb)];
    const std::string_view t = tok[static_cast<std::size_t>(f.first_token)];
    // PCL writes the packed colour of an F field as its uint32 bit pattern in decimal; older
    // writers printed the float. Digits only -> bit pattern; anything else -> a float.
    std::uint32_t u = 0;
    if (parse_int(t, u)) return u;
    std::int64_t i = 0;
    if (f.type == 'I' && parse_int(t, i) && i >= std::numeric_limits<std::int32_t>::min() &&
        i <= std::numeric_limits<std::int32_t>::max()) {
      return static_cast<std::uint32_t>(static_cast<std::int32_t>(i));
    }
    float fv = 0.0f;
    if (f.type == 'F' && parse_real(t, fv)) return std::bit_cast<std::uint32_t>(fv);
    fail_file(ErrorCode::kParse, path,
              "line " + std::to_string(line_no) + ": " + quote_token(t) + " is not a packed colour (field " +
                  quote_token(f.name) + ")");
  };

  while (got < h.points && pos < file.size()) {
    const std::string_view line = next_line(file, pos);
    ++line_no;
    split_tokens(line, tok);
    if (tok.empty()) continue;
    if (tok.size() != h.tokens_per_point) {
      bad("expected " + std::to_string(h.tokens_per_point) + " values, got " + std::to_string(tok.size()));
    }
    cloud.points.emplace_back(value(h.x), value(h.y), value(h.z));
    if (h.nx >= 0) cloud.normals.emplace_back(value(h.nx), value(h.ny), value(h.nz));
    if (h.curvature >= 0) cloud.curvature.push_back(value(h.curvature));
    if (h.rgb >= 0) cloud.colors.push_back(unpack_rgb(packed_colour()));
    ++got;
  }
  if (got < h.points) {
    fail_file(ErrorCode::kParse, path,
              "data truncated: expected " + std::to_string(h.points) + " points, got " + std::to_string(got));
  }
}

PointCloud read_pcd_impl(const fs::path& path, PcdInfo* info) {
  const std::string file = read_whole_file(path);
  const PcdHeader h = parse_pcd_header(path, file);
  PointCloud cloud;
  const std::size_t remaining = file.size() - h.data_offset;
  const std::size_t nf = h.fields.size();
  std::vector<u64> offset(nf), stride(nf);

  switch (h.info.encoding) {
    case PcdEncoding::kAscii:
      read_pcd_ascii(h, file, path, cloud);
      break;
    case PcdEncoding::kBinary: {
      if (h.points > remaining / h.record_size) {
        fail_file(ErrorCode::kParse, path,
                  "data truncated: expected " + std::to_string(h.points) + " points, got " +
                      std::to_string(remaining / h.record_size) + " (" + std::to_string(remaining) +
                      " bytes of " + std::to_string(h.record_size) + "-byte points)");
      }
      for (std::size_t f = 0; f < nf; ++f) {
        offset[f] = h.fields[f].record_offset;
        stride[f] = h.record_size;
      }
      decode_pcd_binary(h, file.data() + h.data_offset, offset, stride, path, cloud);
      break;
    }
    case PcdEncoding::kBinaryCompressed: {
      if (remaining < 8) {
        fail_file(ErrorCode::kParse, path,
                  "data truncated: binary_compressed data needs 8 bytes of sizes, file has " +
                      std::to_string(remaining) + " after the header");
      }
      std::uint32_t compressed = 0, uncompressed = 0;
      std::memcpy(&compressed, file.data() + h.data_offset, 4);
      std::memcpy(&uncompressed, file.data() + h.data_offset + 4, 4);
      if (compressed > remaining - 8) {
        fail_file(ErrorCode::kParse, path,
                  "compressed size " + std::to_string(compressed) + " exceeds file size (" +
                      std::to_string(remaining - 8) + " bytes follow the size fields)");
      }
      if (h.points > std::numeric_limits<std::uint32_t>::max() / h.record_size) {
        fail_file(ErrorCode::kParse, path,
                  "POINTS " + std::to_string(h.points) + " x " + std::to_string(h.record_size) +
                      " bytes exceeds the 4 GiB limit of binary_compressed");
      }
      const u64 expected = h.points * h.record_size;
      if (uncompressed != expected) {
        fail_file(ErrorCode::kParse, path,
                  "uncompressed size " + std::to_string(uncompressed) + " does not match POINTS x point size = " +
                      std::to_string(h.points) + " x " + std::to_string(h.record_size) + " = " +
                      std::to_string(expected));
      }
      if (h.points == 0) break;
      // LZF expands at most 88x (a 3-byte back reference yields 264 bytes).
      if (u64{uncompressed} > u64{compressed} * 88) {
        fail_file(ErrorCode::kParse, path,
                  "uncompressed size " + std::to_string(uncompressed) + " cannot come from " +
                      std::to_string(compressed) + " LZF bytes: data truncated or corrupt");
      }
      std::vector<char> buf;
      resize_or_fail(path, buf, uncompressed);
      const unsigned got = lzf_decompress(file.data() + h.data_offset + 8, compressed, buf.data(), uncompressed);
      if (got != uncompressed) {
        fail_file(ErrorCode::kParse, path,
                  "corrupt LZF data: decompressed " + std::to_string(got) + " of " +
                      std::to_string(uncompressed) + " bytes");
      }
      // Field-by-field planes in header order (PCL's layout).
      u64 plane = 0;
      for (std::size_t f = 0; f < nf; ++f) {
        offset[f] = plane;
        stride[f] = h.fields[f].bytes();
        plane += h.fields[f].bytes() * h.points;
      }
      decode_pcd_binary(h, buf.data(), offset, stride, path, cloud);
      break;
    }
  }
  if (info != nullptr) *info = h.info;
  return cloud;
}

std::string pcd_header(const PointCloud& cloud, std::string_view data) {
  std::string fields = "x y z", sizes = "4 4 4", types = "F F F", counts = "1 1 1";
  const auto add = [&](const char* name, const char* type = " F") {
    fields += ' ';
    fields += name;
    sizes += " 4";
    types += type;
    counts += " 1";
  };
  // PCL (>= 1.10) declares the packed colour TYPE U, so that its readers keep the bits.
  if (cloud.has_colors()) add("rgb", " U");
  if (cloud.has_normals()) {
    add("normal_x");
    add("normal_y");
    add("normal_z");
  }
  if (!cloud.curvature.empty()) add("curvature");
  const std::string n = std::to_string(cloud.size());
  return "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS " + fields + "\nSIZE " + sizes +
         "\nTYPE " + types + "\nCOUNT " + counts + "\nWIDTH " + n + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " +
         n + "\nDATA " + std::string(data) + "\n";
}

/// Number of float-sized fields written for `cloud`.
std::size_t pcd_field_count(const PointCloud& cloud) {
  return 3 + (cloud.has_colors() ? 1 : 0) + (cloud.has_normals() ? 3 : 0) + (cloud.curvature.empty() ? 0 : 1);
}

/// Calls put(value_bits_as_float_or_u32) for each written field of point i, in header order.
template <class Put>
void for_each_pcd_value(const PointCloud& cloud, std::size_t i, Put&& put) {
  put(cloud.points[i].x());
  put(cloud.points[i].y());
  put(cloud.points[i].z());
  if (cloud.has_colors()) put(pack_rgb(cloud.colors[i]));
  if (cloud.has_normals()) {
    put(cloud.normals[i].x());
    put(cloud.normals[i].y());
    put(cloud.normals[i].z());
  }
  if (!cloud.curvature.empty()) put(cloud.curvature[i]);
}

// ------------------------------------------------------------------------------------------
// PLY

enum class PlyType : std::uint8_t { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };
enum class PlyFormat : std::uint8_t { kAscii, kBinaryLe, kBinaryBe };

constexpr std::size_t ply_size(PlyType t) noexcept {
  switch (t) {
    case PlyType::kInt8:
    case PlyType::kUint8: return 1;
    case PlyType::kInt16:
    case PlyType::kUint16: return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32: return 4;
    case PlyType::kFloat64: return 8;
  }
  return 1;
}

bool parse_ply_type(std::string_view s, PlyType& t) {
  if (s == "char" || s == "int8") t = PlyType::kInt8;
  else if (s == "uchar" || s == "uint8") t = PlyType::kUint8;
  else if (s == "short" || s == "int16") t = PlyType::kInt16;
  else if (s == "ushort" || s == "uint16") t = PlyType::kUint16;
  else if (s == "int" || s == "int32") t = PlyType::kInt32;
  else if (s == "uint" || s == "uint32") t = PlyType::kUint32;
  else if (s == "float" || s == "float32") t = PlyType::kFloat32;
  else if (s == "double" || s == "float64") t = PlyType::kFloat64;
  else return false;
  return true;
}

constexpr bool ply_is_float(PlyType t) noexcept { return t == PlyType::kFloat32 || t == PlyType::kFloat64; }

enum class PlyRole : std::uint8_t { kNone, kX, kY, kZ, kRed, kGreen, kBlue, kNx, kNy, kNz, kCurvature };
constexpr std::size_t kPlyRoles = 11;

PlyRole ply_role(std::string_view name) {
  if (name == "x") return PlyRole::kX;
  if (name == "y") return PlyRole::kY;
  if (name == "z") return PlyRole::kZ;
  if (name == "red" || name == "r" || name == "diffuse_red") return PlyRole::kRed;
  if (name == "green" || name == "g" || name == "diffuse_green") return PlyRole::kGreen;
  if (name == "blue" || name == "b" || name == "diffuse_blue") return PlyRole::kBlue;
  if (name == "nx" || name == "normal_x") return PlyRole::kNx;
  if (name == "ny" || name == "normal_y") return PlyRole::kNy;
  if (name == "nz" || name == "normal_z") return PlyRole::kNz;
  if (name == "curvature") return PlyRole::kCurvature;
  return PlyRole::kNone;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;  ///< scalar type, or item type of a list
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;
  PlyRole role = PlyRole::kNone;
};

struct PlyElement {
  std::string name;
  u64 count = 0;
  std::vector<PlyProperty> props;
  std::size_t line = 0;
  /// Fewest bytes (binary) one instance can take.
  [[nodiscard]] u64 min_bytes() const noexcept {
    u64 b = 0;
    for (const PlyProperty& p : props) b += p.is_list ? ply_size(p.count_type) : ply_size(p.type);
    return b;
  }
};

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  std::size_t data_offset = 0;
  std::size_t data_line = 0;
};

PlyHeader parse_ply_header(const fs::path& path, std::string_view file) {
  PlyHeader h;
  std::size_t pos = 0, line_no = 1;
  std::vector<std::string_view> tok;
  {
    std::string_view first = next_line(file, pos);
    if (!first.empty() && first.back() == '\r') first.remove_suffix(1);
    if (first != "ply") fail_file(ErrorCode::kParse, path, "not a PLY file (first line is not 'ply')");
  }
  bool have_format = false, have_end = false;
  const auto bad = [&](const std::string& what) {
    fail_file(ErrorCode::kParse, path, header_line(line_no) + what);
  };
  while (pos < file.size()) {
    const std::string_view line = next_line(file, pos);
    ++line_no;
    split_tokens(line, tok);
    if (tok.empty()) continue;
    const std::string_view kw = tok[0];
    if (kw == "comment" || kw == "obj_info") continue;
    if (kw == "format") {
      if (have_format) bad("format appears twice");
      if (tok.size() != 3) bad("format needs 2 values (encoding and version)");
      if (tok[1] == "ascii") h.format = PlyFormat::kAscii;
      else if (tok[1] == "binary_little_endian") h.format = PlyFormat::kBinaryLe;
      else if (tok[1] == "binary_big_endian") h.format = PlyFormat::kBinaryBe;
      else bad("format " + quote_token(tok[1]) + " (allowed: ascii, binary_little_endian, binary_big_endian)");
      if (tok[2] != "1.0" && tok[2] != "1") bad("format version " + quote_token(tok[2]) + " (supported: 1.0)");
      have_format = true;
    } else if (kw == "element") {
      if (tok.size() != 3) bad("element needs a name and a count");
      PlyElement e;
      e.name = tok[1];
      e.line = line_no;
      if (!parse_int(tok[2], e.count)) bad("element count " + quote_token(tok[2]) + " is not a non-negative integer");
      h.elements.push_back(std::move(e));
    } else if (kw == "property") {
      if (h.elements.empty()) bad("property before any element");
      PlyProperty p;
      if (tok.size() >= 2 && tok[1] == "list") {
        if (tok.size() != 5) bad("list property needs count type, item type and name");
        if (!parse_ply_type(tok[2], p.count_type)) bad("unknown type " + quote_token(tok[2]));
        if (!parse_ply_type(tok[3], p.type)) bad("unknown type " + quote_token(tok[3]));
        if (ply_is_float(p.count_type)) bad("list count type " + quote_token(tok[2]) + " is not an integer type");
        p.is_list = true;
        p.name = tok[4];
      } else {
        if (tok.size() != 3) bad("property needs a type and a name");
        if (!parse_ply_type(tok[1], p.type)) bad("unknown type " + quote_token(tok[1]));
        p.name = tok[2];
      }
      h.elements.back().props.push_back(std::move(p));
    } else if (kw == "end_header") {
      have_end = true;
      break;
    } else {
      bad("unknown keyword " + quote_token(kw));
    }
  }
  if (!have_end) fail_file(ErrorCode::kParse, path, "header has no end_header line");
  if (!have_format) fail_file(ErrorCode::kParse, path, "header has no format line");
  h.data_offset = pos;
  h.data_line = line_no + 1;
  return h;
}

/// Reads binary scalars with bounds checks and optional byte swapping.
struct PlyBinaryCursor {
  const char* p;
  const char* end;
  bool swap;

  [[nodiscard]] std::size_t left() const noexcept { return static_cast<std::size_t>(end - p); }

  /// Reads one scalar as double; false when the data ends.
  bool read(PlyType t, double& out) noexcept {
    const std::size_t n = ply_size(t);
    if (left() < n) return false;
    unsigned char b[8];
    std::memcpy(b, p, n);
    if (swap) std::reverse(b, b + n);
    p += n;
    switch (t) {
      case PlyType::kInt8: out = static_cast<std::int8_t>(b[0]); break;
      case PlyType::kUint8: out = b[0]; break;
      case PlyType::kInt16: { std::int16_t v; std::memcpy(&v, b, 2); out = v; break; }
      case PlyType::kUint16: { std::uint16_t v; std::memcpy(&v, b, 2); out = v; break; }
      case PlyType::kInt32: { std::int32_t v; std::memcpy(&v, b, 4); out = v; break; }
      case PlyType::kUint32: { std::uint32_t v; std::memcpy(&v, b, 4); out = v; break; }
      case PlyType::kFloat32: { float v; std::memcpy(&v, b, 4); out = v; break; }
      case PlyType::kFloat64: { double v; std::memcpy(&v, b, 8); out = v; break; }
    }
    return true;
  }
};

/// Reads whitespace-separated tokens, counting lines for error messages.
struct PlyTextCursor {
  const char* p;
  const char* end;
  std::size_t line;

  bool next(std::string_view& tok) noexcept {
    while (p < end && is_space(*p)) {
      if (*p == '\n') ++line;
      ++p;
    }
    if (p == end) return false;
    const char* start = p;
    while (p < end && !is_space(*p)) ++p;
    tok = std::string_view(start, static_cast<std::size_t>(p - start));
    return true;
  }
};

/// Reads every instance of the elements up to and including `vertex`, storing vertex values.
class PlyDataReader {
 public:
  PlyDataReader(const fs::path& path, const PlyHeader& h, std::string_view file)
      : path_(path), h_(h), bin_{file.data() + h.data_offset, file.data() + file.size(), h.format == PlyFormat::kBinaryBe},
        text_{file.data() + h.data_offset, file.data() + file.size(), h.data_line} {}

  PointCloud read(std::size_t vertex_index) {
    for (std::size_t e = 0; e < vertex_index; ++e) skip_element(h_.elements[e]);
    return read_vertices(h_.elements[vertex_index]);
  }

 private:
  [[noreturn]] void truncated(const PlyElement& e, u64 got) const {
    fail_file(ErrorCode::kParse, path_,
              "data truncated: expected " + std::to_string(e.count) + " " + e.name + " elements, got " +
                  std::to_string(got) + (h_.format == PlyFormat::kAscii ? " (line " + std::to_string(text_.line) + ")" : ""));
  }

  [[noreturn]] void bad_value(std::string_view tok, const PlyProperty& prop) const {
    fail_file(ErrorCode::kParse, path_,
              "line " + std::to_string(text_.line) + ": " + quote_token(tok) + " is not a number (property " +
                  quote_token(prop.name) + ")");
  }

  /// One scalar; false when the data ends.
  bool scalar(PlyType t, const PlyProperty& prop, double& out) {
    if (h_.format != PlyFormat::kAscii) return bin_.read(t, out);
    std::string_view tok;
    if (!text_.next(tok)) return false;
    if (ply_is_float(t)) {
      if (!parse_real(tok, out)) bad_value(tok, prop);
    } else {
      std::int64_t i = 0;
      if (parse_int(tok, i)) {
        out = static_cast<double>(i);
      } else if (!parse_real(tok, out)) {
        bad_value(tok, prop);
      }
    }
    return true;
  }

  /// Skips (or, when `values` is set, reads) one instance; false when the data ends.
  bool instance(const PlyElement& e, double* values) {
    for (const PlyProperty& prop : e.props) {
      if (prop.is_list) {
        double n = 0.0;
        if (!scalar(prop.count_type, prop, n)) return false;
        if (!(n >= 0.0) || n != std::floor(n) || n > 1e18) {
          fail_file(ErrorCode::kParse, path_,
                    "element " + quote_token(e.name) + ": list " + quote_token(prop.name) + " has count " + std::to_string(n));
        }
        const u64 items = static_cast<u64>(n);
        if (h_.format != PlyFormat::kAscii) {
          if (items > bin_.left() / ply_size(prop.type)) return false;
          bin_.p += items * ply_size(prop.type);
        } else {
          std::string_view tok;
          for (u64 k = 0; k < items; ++k) {
            if (!text_.next(tok)) return false;
          }
        }
      } else if (values != nullptr && prop.role != PlyRole::kNone) {
        if (!scalar(prop.type, prop, values[static_cast<std::size_t>(prop.role)])) return false;
      } else if (h_.format != PlyFormat::kAscii) {
        if (bin_.left() < ply_size(prop.type)) return false;
        bin_.p += ply_size(prop.type);
      } else {
        std::string_view tok;
        if (!text_.next(tok)) return false;
      }
    }
    return true;
  }

  void skip_element(const PlyElement& e) {
    if (e.props.empty()) return;
    const bool fixed = std::none_of(e.props.begin(), e.props.end(), [](const PlyProperty& p) { return p.is_list; });
    if (h_.format != PlyFormat::kAscii && fixed) {
      const u64 rec = e.min_bytes();
      if (e.count > bin_.left() / rec) truncated(e, bin_.left() / rec);
      bin_.p += e.count * rec;
      return;
    }
    for (u64 i = 0; i < e.count; ++i) {
      if (!instance(e, nullptr)) truncated(e, i);
    }
  }

  PointCloud read_vertices(const PlyElement& e) {
    bool has[kPlyRoles] = {};
    for (const PlyProperty& p : e.props) {
      if (!p.is_list) has[static_cast<std::size_t>(p.role)] = true;
    }
    const auto has_role = [&](PlyRole r) { return has[static_cast<std::size_t>(r)]; };
    if (!has_role(PlyRole::kX) || !has_role(PlyRole::kY) || !has_role(PlyRole::kZ)) {
      fail_file(ErrorCode::kParse, path_, header_line(e.line) + "element 'vertex' lacks property x, y or z");
    }
    const bool colors = has_role(PlyRole::kRed) && has_role(PlyRole::kGreen) && has_role(PlyRole::kBlue);
    const bool normals = has_role(PlyRole::kNx) && has_role(PlyRole::kNy) && has_role(PlyRole::kNz);
    const bool curvature = has_role(PlyRole::kCurvature);
    PlyType color_type = PlyType::kUint8;
    for (const PlyProperty& p : e.props) {
      if (p.role == PlyRole::kRed) color_type = p.type;
    }

    // Bound the allocation by the bytes present.
    u64 cap = e.count;
    if (h_.format != PlyFormat::kAscii) {
      const u64 rec = e.min_bytes();
      if (e.count > bin_.left() / rec) truncated(e, bin_.left() / rec);
    } else {
      cap = std::min<u64>(cap, bin_.left() / (2 * e.props.size() - 1) + 1);
    }
    PointCloud cloud;
    const std::size_t n = static_cast<std::size_t>(cap);
    reserve_or_fail(path_, cloud.points, n);
    if (colors) reserve_or_fail(path_, cloud.colors, n);
    if (normals) reserve_or_fail(path_, cloud.normals, n);
    if (curvature) reserve_or_fail(path_, cloud.curvature, n);

    const auto to_u8 = [&](double v) -> std::uint8_t {
      if (ply_is_float(color_type)) v *= 255.0;  // float colours are in [0, 1]
      if (!(v > 0.0)) return 0;
      if (v >= 255.0) return 255;
      return static_cast<std::uint8_t>(std::lround(v));
    };
    double v[kPlyRoles] = {};
    for (u64 i = 0; i < e.count; ++i) {
      if (!instance(e, v)) truncated(e, i);
      using R = PlyRole;
      const auto f = [&](R r) { return static_cast<float>(v[static_cast<std::size_t>(r)]); };
      cloud.points.emplace_back(f(R::kX), f(R::kY), f(R::kZ));
      if (colors) {
        cloud.colors.push_back({to_u8(v[static_cast<std::size_t>(R::kRed)]), to_u8(v[static_cast<std::size_t>(R::kGreen)]),
                                to_u8(v[static_cast<std::size_t>(R::kBlue)])});
      }
      if (normals) cloud.normals.emplace_back(f(R::kNx), f(R::kNy), f(R::kNz));
      if (curvature) cloud.curvature.push_back(f(R::kCurvature));
    }
    return cloud;
  }

  const fs::path& path_;
  const PlyHeader& h_;
  PlyBinaryCursor bin_;
  PlyTextCursor text_;
};

PointCloud read_ply_impl(const fs::path& path) {
  const std::string file = read_whole_file(path);
  PlyHeader h = parse_ply_header(path, file);
  std::size_t vertex = h.elements.size();
  for (std::size_t e = 0; e < h.elements.size(); ++e) {
    if (h.elements[e].name == "vertex") {
      vertex = e;
      break;
    }
  }
  if (vertex == h.elements.size()) fail_file(ErrorCode::kParse, path, "header has no 'vertex' element");
  // First occurrence of each role wins; later duplicates are skipped.
  bool taken[kPlyRoles] = {};
  for (PlyProperty& p : h.elements[vertex].props) {
    if (p.is_list) continue;
    const PlyRole r = ply_role(p.name);
    if (r != PlyRole::kNone && !taken[static_cast<std::size_t>(r)]) {
      p.role = r;
      taken[static_cast<std::size_t>(r)] = true;
    }
  }
  PlyDataReader reader(path, h, file);
  return reader.read(vertex);
}

std::string lower_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

}  // namespace

// ------------------------------------------------------------------------------------------

PointCloud read_pcd(const fs::path& path, PcdInfo* info) { return read_pcd_impl(path, info); }

void write_pcd(const fs::path& path, const PointCloud& cloud, PcdEncoding encoding) {
  check_cloud(path, cloud);
  const std::size_t n = cloud.size();
  const std::size_t nf = pcd_field_count(cloud);
  std::string data;
  try {
    switch (encoding) {
      case PcdEncoding::kAscii: {
        data.reserve(n * nf * 12);
        for (std::size_t i = 0; i < n; ++i) {
          bool first = true;
          for_each_pcd_value(cloud, i, [&](auto v) {
            if (!first) data += ' ';
            first = false;
            if constexpr (std::is_same_v<decltype(v), std::uint32_t>) {
              append_int(data, v);  // packed colour as its bit pattern, as PCL writes it
            } else {
              append_real(data, v);
            }
          });
          data += '\n';
        }
        write_file_atomically(path, {pcd_header(cloud, "ascii"), data});
        return;
      }
      case PcdEncoding::kBinary: {
        data.reserve(n * nf * 4);
        for (std::size_t i = 0; i < n; ++i) for_each_pcd_value(cloud, i, [&](auto v) { append_raw(data, v); });
        write_file_atomically(path, {pcd_header(cloud, "binary"), data});
        return;
      }
      case PcdEncoding::kBinaryCompressed: {
        const u64 raw_size = u64{n} * nf * 4;
        if (raw_size > std::numeric_limits<std::uint32_t>::max()) {
          fail_file(ErrorCode::kUnsupported, path,
                    "cloud of " + std::to_string(raw_size) + " bytes exceeds the 4 GiB limit of binary_compressed");
        }
        // Field-by-field planes: all x, then all y, ... (PCL's layout, compresses better).
        std::vector<std::uint32_t> planes(n * nf);
        for (std::size_t i = 0; i < n; ++i) {
          std::size_t f = 0;
          for_each_pcd_value(cloud, i, [&](auto v) {
            std::uint32_t bits;
            std::memcpy(&bits, &v, 4);
            planes[f * n + i] = bits;
            ++f;
          });
        }
        const auto raw = static_cast<unsigned>(raw_size);
        std::string block(8 + raw + raw / 16 + 64, '\0');
        unsigned compressed = 0;
        if (raw > 0) {
          compressed = lzf_compress(planes.data(), raw, block.data() + 8, static_cast<unsigned>(block.size() - 8));
          if (compressed == 0) fail_file(ErrorCode::kInternal, path, "LZF compression failed");
        }
        std::memcpy(block.data(), &compressed, 4);
        std::memcpy(block.data() + 4, &raw, 4);
        block.resize(8 + compressed);
        write_file_atomically(path, {pcd_header(cloud, "binary_compressed"), block});
        return;
      }
    }
  } catch (const std::bad_alloc&) {
    fail_file(ErrorCode::kOutOfMemory, path, "not enough memory to encode " + std::to_string(n) + " points");
  }
  fail_file(ErrorCode::kInvalidArgument, path, "unknown PCD encoding");
}

PointCloud read_ply(const fs::path& path) { return read_ply_impl(path); }

void write_ply(const fs::path& path, const PointCloud& cloud, PlyEncoding encoding) {
  check_cloud(path, cloud);
  const bool ascii = encoding == PlyEncoding::kAscii;
  if (!ascii && encoding != PlyEncoding::kBinaryLittleEndian) {
    fail_file(ErrorCode::kInvalidArgument, path, "unknown PLY encoding");
  }
  const std::size_t n = cloud.size();
  std::string header = "ply\nformat ";
  header += ascii ? "ascii 1.0\n" : "binary_little_endian 1.0\n";
  header += "comment written by duet\nelement vertex " + std::to_string(n) +
            "\nproperty float x\nproperty float y\nproperty float z\n";
  if (cloud.has_colors()) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (cloud.has_normals()) header += "property float nx\nproperty float ny\nproperty float nz\n";
  if (!cloud.curvature.empty()) header += "property float curvature\n";
  header += "end_header\n";

  std::string data;
  try {
    data.reserve(n * (ascii ? 64 : 31));
    for (std::size_t i = 0; i < n; ++i) {
      const auto put_float = [&](float v, bool first = false) {
        if (ascii) {
          if (!first) data += ' ';
          append_real(data, v);
        } else {
          if constexpr (std::endian::native == std::endian::little) {
            append_raw(data, v);
          } else {
            std::uint32_t b;
            std::memcpy(&b, &v, 4);
            b = __builtin_bswap32(b);
            data.append(reinterpret_cast<const char*>(&b), 4);
          }
        }
      };
      put_float(cloud.points[i].x(), true);
      put_float(cloud.points[i].y());
      put_float(cloud.points[i].z());
      if (cloud.has_colors()) {
        const Rgb8 c = cloud.colors[i];
        if (ascii) {
          for (const std::uint8_t u : {c.r, c.g, c.b}) {
            data += ' ';
            append_int(data, unsigned{u});
          }
        } else {
          data += static_cast<char>(c.r);
          data += static_cast<char>(c.g);
          data += static_cast<char>(c.b);
        }
      }
      if (cloud.has_normals()) {
        put_float(cloud.normals[i].x());
        put_float(cloud.normals[i].y());
        put_float(cloud.normals[i].z());
      }
      if (!cloud.curvature.empty()) put_float(cloud.curvature[i]);
      if (ascii) data += '\n';
    }
  } catch (const std::bad_alloc&) {
    fail_file(ErrorCode::kOutOfMemory, path, "not enough memory to encode " + std::to_string(n) + " points");
  }
  write_file_atomically(path, {header, data});
}

PointCloud read_cloud(const fs::path& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".pcd") return read_pcd(path);
  if (ext == ".ply") return read_ply(path);
  fail_file(ErrorCode::kUnsupported, path, "unknown cloud file extension " + quote_token(ext) + " (known: .pcd, .ply)");
}

void write_cloud(const fs::path& path, const PointCloud& cloud) {
  const std::string ext = lower_extension(path);
  if (ext == ".pcd") return write_pcd(path, cloud, PcdEncoding::kBinaryCompressed);
  if (ext == ".ply") return write_ply(path, cloud, PlyEncoding::kBinaryLittleEndian);
  fail_file(ErrorCode::kUnsupported, path, "unknown cloud file extension " + quote_token(ext) + " (known: .pcd, .ply)");
}

}  // namespace duet
