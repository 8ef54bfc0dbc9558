#pragma once
/// @file output.hpp
/// Writing a run's outputs so that nothing is lost on a stop (issue 19, part 4):
///  - every file is written under a temporary name in its folder and renamed into place, so a
///    reader - or a process killed with SIGKILL in the middle of a write - sees the previous file
///    or the new one whole, never a part of one (the library's writers - PCD, PLY, map_server,
///    PNG - all write this way);
///  - the output folder is checked before a run starts, so a run learns at once, not after
///    hours of exploring, that its outputs cannot be written.
/// Errors are duet::Error (ErrorCode::kIo) naming the path. Thread safety: concurrent calls on
/// different paths are safe.
#include <filesystem>
#include <string_view>

namespace duet {

/// Writes `text` to `path` (atomically replacing it, see above).
void write_text_file(const std::filesystem::path& path, std::string_view text);

/// Creates `dir` and its parents if needed and checks that a file can be created, written and
/// renamed in it (the probe is removed). Fails naming `dir` when it is a file, cannot be created
/// or is not writable.
void prepare_output_dir(const std::filesystem::path& dir);

}  // namespace duet
