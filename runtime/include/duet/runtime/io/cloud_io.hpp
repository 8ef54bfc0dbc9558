#pragma once
/// @file cloud_io.hpp
/// Point cloud files (DESIGN.md §5): PCD v0.7 (PCL's format: ascii, binary and LZF
/// binary_compressed) and PLY (ascii, binary little and big endian), read into and written
/// from duet::PointCloud.
///
/// What is read: positions (x y z), colour (PCD: packed `rgb` / `rgba`, 4 bytes, F or U as PCL
/// writes them; PLY: red green blue), normals (PCD: normal_x normal_y normal_z; PLY: nx ny nz)
/// and curvature, each attribute only when the file has it. Every other field, property or
/// element (PCD padding `_`, PLY faces, ...) is skipped. Points are kept in file order,
/// including NaN points of organized clouds: the caller filters them.
///
/// What is written: exactly what the cloud has, as 32-bit floats (colour as PCL's packed
/// `rgb`, TYPE U as PCL >= 1.10 writes it, alpha byte 0), unorganized (HEIGHT 1), loadable by
/// pcl::io::loadPCDFile and pcl::io::loadPLYFile. A file is written to a temporary sibling and renamed into place, so
/// an existing file is never left half-written.
///
/// Errors: duet::Error naming the file, what is wrong and where ("x.pcd: header line 5: TYPE
/// has 3 entries, FIELDS has 4"); ErrorCode::kIo when the file cannot be opened, read or
/// written, kParse for malformed content, kUnsupported for an unknown extension,
/// kInvalidArgument for an inconsistent cloud, kOutOfMemory when a valid file does not fit.
/// Declared sizes are checked against the file size before anything is allocated, and no
/// input, however corrupt, is read out of bounds.
///
/// Thread safety: every function is reentrant; calls on different files may run
/// concurrently. Writing a file while another thread reads or writes the same path is a race
/// on the file system, not on memory.
#include <duet/kernels/types.hpp>

#include <array>
#include <cstdint>
#include <filesystem>

namespace duet {

enum class PcdEncoding {
  kAscii,             ///< text, one point per line
  kBinary,            ///< raw little-endian records (array of structures)
  kBinaryCompressed,  ///< field-by-field planes compressed with LZF, as PCL writes them
};

enum class PlyEncoding {
  kAscii,               ///< text, one vertex per line
  kBinaryLittleEndian,  ///< raw little-endian records
};

/// Header facts of a PCD file that duet::PointCloud does not hold.
struct PcdInfo {
  std::uint64_t width = 0;   ///< WIDTH: points per row (organized) or point count
  std::uint64_t height = 0;  ///< HEIGHT: rows (1 = unorganized)
  /// VIEWPOINT: sensor origin tx ty tz [m] and orientation qw qx qy qz.
  std::array<double, 7> viewpoint{0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0};
  PcdEncoding encoding = PcdEncoding::kBinary;  ///< DATA
};

/// Reads a PCD file (v0.5-v0.7 header; DATA ascii, binary or binary_compressed). Fields x y z
/// are required; any SIZE/TYPE/COUNT is accepted for them and for normals and curvature
/// (converted to float). When `info` is not null it receives the header facts.
[[nodiscard]] PointCloud read_pcd(const std::filesystem::path& path, PcdInfo* info = nullptr);

/// Writes `cloud` as PCD v0.7. Throws kInvalidArgument when an attribute has the wrong length,
/// kUnsupported when binary_compressed data would exceed 4 GiB (the format's limit).
void write_pcd(const std::filesystem::path& path, const PointCloud& cloud,
               PcdEncoding encoding = PcdEncoding::kBinaryCompressed);

/// Reads the `vertex` element of a PLY file (ascii, binary_little_endian or
/// binary_big_endian). Properties x y z are required (any scalar type).
[[nodiscard]] PointCloud read_ply(const std::filesystem::path& path);

/// Writes `cloud` as the vertex element of a PLY file (float x y z, uchar red green blue,
/// float nx ny nz, float curvature - each when the cloud has it).
void write_ply(const std::filesystem::path& path, const PointCloud& cloud,
               PlyEncoding encoding = PlyEncoding::kBinaryLittleEndian);

/// read_pcd or read_ply by extension (`.pcd`, `.ply`, any case); kUnsupported otherwise.
[[nodiscard]] PointCloud read_cloud(const std::filesystem::path& path);

/// write_pcd (binary_compressed) or write_ply (binary_little_endian) by extension.
void write_cloud(const std::filesystem::path& path, const PointCloud& cloud);

}  // namespace duet
