/// @file ply_io.cpp
/// PLY reader and writer (see cloud_io.hpp): header parsing, ascii and binary (either byte order) data.
#include <duet/runtime/io/input_limits.hpp>
#include <duet/kernels/error.hpp>
#include "io/cloud_io_detail.hpp"
#include "io/file_util.hpp"
#include <duet/runtime/io/cloud_io.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <new>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace duet {
namespace {

using detail::fail_file;
using detail::read_whole_file;
using detail::write_file_atomically;
using namespace detail::cloud_io;  // the shared helpers (cloud_io_detail.hpp)

namespace fs = std::filesystem;
using u64 = std::uint64_t;

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
  const std::string file = read_whole_file(path, input_limits::kCloudBytes, "PLY file");
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

}  // namespace

// ------------------------------------------------------------------------------------------

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

}  // namespace duet
