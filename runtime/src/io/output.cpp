/// @file output.cpp
/// write_text_file() and prepare_output_dir() (see output.hpp).
#include <duet/runtime/io/output.hpp>

#include "file_util.hpp"

#include <unistd.h>

#include <string>
#include <system_error>

namespace duet {

namespace fs = std::filesystem;

void write_text_file(const fs::path& path, std::string_view text) { detail::write_file_atomically(path, {text}); }

void prepare_output_dir(const fs::path& dir) {
  if (dir.empty()) fail(ErrorCode::kInvalidArgument, "output folder: the path is empty");
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    detail::fail_file(ErrorCode::kIo, dir, "the output folder is a file, not a folder");
  fs::create_directories(dir, ec);
  if (ec) detail::fail_file(ErrorCode::kIo, dir, "cannot create the output folder: " + ec.message());
  // The way every output is written: a temporary file renamed into place.
  const fs::path probe = dir / (".duet_write_probe." + std::to_string(::getpid()));
  try {
    detail::write_file_atomically(probe, {"probe\n"});
  } catch (const Error& e) {
    detail::fail_file(ErrorCode::kIo, dir, std::string("the output folder is not writable (") + e.what() + ")");
  }
  fs::remove(probe, ec);
}

}  // namespace duet
