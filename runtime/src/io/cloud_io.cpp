/// @file cloud_io.cpp
/// read_cloud and write_cloud (see cloud_io.hpp): PCD or PLY by extension; the formats are in pcd_io.cpp and
/// ply_io.cpp. Readers read the whole file and check declared counts against the bytes present before allocating.
#include <duet/kernels/error.hpp>
#include "io/cloud_io_detail.hpp"
#include "io/file_util.hpp"
#include <duet/runtime/io/cloud_io.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

namespace duet {
namespace {

using detail::fail_file;
using namespace detail::cloud_io;  // the shared helpers (cloud_io_detail.hpp)

namespace fs = std::filesystem;

std::string lower_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

}  // namespace

// ------------------------------------------------------------------------------------------

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
