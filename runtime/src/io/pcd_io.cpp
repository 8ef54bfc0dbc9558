/// @file pcd_io.cpp
/// PCD reader (see cloud_io.hpp): header parsing, ascii, binary and binary_compressed data; the writer is pcd_write.cpp.
#include <duet/runtime/io/input_limits.hpp>
#include <duet/kernels/error.hpp>
#include "io/cloud_io_detail.hpp"
#include "io/file_util.hpp"
#include <duet/runtime/io/cloud_io.hpp>

#include <lzf.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <new>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace duet {
namespace {

using detail::fail_file;
using detail::read_whole_file;
using namespace detail::cloud_io;  // the shared helpers (cloud_io_detail.hpp)

namespace fs = std::filesystem;
using u64 = std::uint64_t;

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
  const std::string file = read_whole_file(path, input_limits::kCloudBytes, "PCD file");
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

}  // namespace

// ------------------------------------------------------------------------------------------

PointCloud read_pcd(const fs::path& path, PcdInfo* info) { return read_pcd_impl(path, info); }

}  // namespace duet
