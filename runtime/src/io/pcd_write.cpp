/// @file pcd_write.cpp
/// PCD writer (see cloud_io.hpp): ascii, binary and binary_compressed, the fields PCL reads back.
#include <duet/kernels/error.hpp>
#include "io/cloud_io_detail.hpp"
#include "io/file_util.hpp"
#include <duet/runtime/io/cloud_io.hpp>

#include <lzf.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

namespace duet {
namespace {

using detail::fail_file;
using detail::write_file_atomically;
using namespace detail::cloud_io;  // the shared helpers (cloud_io_detail.hpp)

namespace fs = std::filesystem;
using u64 = std::uint64_t;

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

}  // namespace

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

}  // namespace duet
