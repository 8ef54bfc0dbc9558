#pragma once
/// @file input_limits.hpp
/// What duet's readers accept (issue 19: limits as contracts). Every file reader - PCD, PLY,
/// map_server PGM/PNG + YAML, world and profile YAML, RGB-D folders (images, pose and list
/// files) - reads only a regular file (not a FIFO, a device such as /dev/zero, a socket or a
/// folder: those could block forever or never end) of at most the size below, and says which
/// file, what it is and the limit otherwise (duet::Error, ErrorCode::kIo). The limits are far
/// above any real input and keep one read within memory and time a robot can spare.
#include <cstdint>

namespace duet::input_limits {

inline constexpr std::uintmax_t kMiB = std::uintmax_t{1} << 20;
inline constexpr std::uintmax_t kCloudBytes = 4096 * kMiB;  ///< a PCD or PLY file (about 100 M points of XYZRGB)
inline constexpr std::uintmax_t kImageBytes = 512 * kMiB;   ///< an image: a map_server PGM/PNG, a depth or colour frame
inline constexpr std::uintmax_t kYamlBytes = 16 * kMiB;     ///< a YAML file: profile, overlay, world, map_server map
inline constexpr std::uintmax_t kTextBytes = 256 * kMiB;    ///< a text list: poses, associations, TUM files

}  // namespace duet::input_limits
