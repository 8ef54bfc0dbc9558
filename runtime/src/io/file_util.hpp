#pragma once
// Internal file helpers shared by the runtime's readers and writers (not installed).
#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>

#include <duet/kernels/error.hpp>

namespace duet::detail {

/// Throws duet::Error(code, "<path>: <what>").
[[noreturn]] void fail_file(ErrorCode code, const std::filesystem::path& path, const std::string& what);

/// The whole file; kIo naming the file when it cannot be read, kOutOfMemory when it does not fit.
std::string read_whole_file(const std::filesystem::path& path);

/// Writes the concatenation of `parts` to a temporary sibling of `path`, then renames it into
/// place: an existing file is replaced whole or not at all.
void write_file_atomically(const std::filesystem::path& path, std::initializer_list<std::string_view> parts);

}  // namespace duet::detail
