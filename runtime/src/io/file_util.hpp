#pragma once
// Internal file helpers shared by the runtime's readers and writers (not installed).
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>

#include <duet/kernels/error.hpp>

namespace duet::detail {

/// Throws duet::Error(code, "<path>: <what>").
[[noreturn]] void fail_file(ErrorCode code, const std::filesystem::path& path, const std::string& what);

/// Checks what every reader accepts (input_limits.hpp): a regular file of at most max_bytes;
/// else kIo naming the file, what it is (`what`: "PCD file", "profile", ...) and the limit. Returns its size.
std::uintmax_t check_input_file(const std::filesystem::path& path, std::uintmax_t max_bytes, const char* what);

/// The whole file after check_input_file() (and never more than max_bytes of it, should it grow
/// while read); kIo naming the file when it cannot be read, kOutOfMemory when it does not fit.
std::string read_whole_file(const std::filesystem::path& path, std::uintmax_t max_bytes, const char* what);

/// Writes the concatenation of `parts` to a temporary sibling of `path`, then renames it into
/// place: an existing file is replaced whole or not at all.
void write_file_atomically(const std::filesystem::path& path, std::initializer_list<std::string_view> parts);

}  // namespace duet::detail
