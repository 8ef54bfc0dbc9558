#include "file_util.hpp"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <new>
#include <system_error>

namespace duet::detail {

namespace fs = std::filesystem;

[[noreturn]] void fail_file(ErrorCode code, const fs::path& path, const std::string& what) {
  fail(code, path.string() + ": " + what);
}

namespace {
const char* kind_of(fs::file_type t) {
  switch (t) {
    case fs::file_type::directory: return "a directory";
    case fs::file_type::fifo: return "a FIFO (named pipe)";
    case fs::file_type::character: return "a character device";
    case fs::file_type::block: return "a block device";
    case fs::file_type::socket: return "a socket";
    default: return "not a regular file";
  }
}

std::string mib(std::uintmax_t bytes) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.1f MiB", static_cast<double>(bytes) / static_cast<double>(std::uintmax_t{1} << 20));
  return buf;
}
}  // namespace

std::uintmax_t check_input_file(const fs::path& path, std::uintmax_t max_bytes, const char* what) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);  // follows symbolic links
  if (ec || st.type() == fs::file_type::not_found) {
    if (st.type() == fs::file_type::not_found) fail_file(ErrorCode::kIo, path, std::string("cannot open the ") + what + ": no such file");
    fail_file(ErrorCode::kIo, path, std::string("cannot open the ") + what + ": " + ec.message());
  }
  if (st.type() != fs::file_type::regular)
    fail_file(ErrorCode::kIo, path, std::string("the ") + what + " is " + kind_of(st.type()) + ", not a regular file");
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) fail_file(ErrorCode::kIo, path, std::string("cannot read the size of the ") + what + ": " + ec.message());
  if (size > max_bytes)
    fail_file(ErrorCode::kIo, path, std::string("the ") + what + " is " + mib(size) + "; the limit is " + mib(max_bytes));
  return size;
}

std::string read_whole_file(const fs::path& path, std::uintmax_t max_bytes, const char* what) {
  const std::uintmax_t size = check_input_file(path, max_bytes, what);
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) {
    fail_file(ErrorCode::kIo, path, std::string("cannot open for reading: ") + std::strerror(errno));
  }
  std::string data;
  bool too_big = false;
  try {
    char buf[1 << 16];
    data.reserve(static_cast<std::size_t>(size));
    for (;;) {
      const std::size_t got = std::fread(buf, 1, sizeof buf, f);
      data.append(buf, got);
      if (data.size() > max_bytes) {  // grew while read
        too_big = true;
        break;
      }
      if (got < sizeof buf) break;
    }
  } catch (const std::bad_alloc&) {
    std::fclose(f);
    fail_file(ErrorCode::kOutOfMemory, path, "file does not fit in memory");
  }
  const bool bad = std::ferror(f) != 0;
  const int err = errno;
  std::fclose(f);
  if (too_big) fail_file(ErrorCode::kIo, path, std::string("the ") + what + " grew beyond the limit of " + mib(max_bytes) + " while read");
  if (bad) fail_file(ErrorCode::kIo, path, std::string("read error: ") + std::strerror(err));
  return data;
}

/// Writes the concatenation of `parts` to a temporary sibling of `path`, then renames it into
/// place: an existing file is replaced whole or not at all.
void write_file_atomically(const fs::path& path, std::initializer_list<std::string_view> parts) {
  static std::atomic<unsigned> counter{0};
  fs::path tmp = path;
  tmp += ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter.fetch_add(1));
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (f == nullptr) {
    fail_file(ErrorCode::kIo, path, std::string("cannot open for writing: ") + std::strerror(errno));
  }
  bool ok = true;
  int err = 0;
  for (const std::string_view part : parts) {
    if (!part.empty() && std::fwrite(part.data(), 1, part.size(), f) != part.size()) {
      ok = false;
      err = errno;
      break;
    }
  }
  if (std::fclose(f) != 0 && ok) {
    ok = false;
    err = errno;
  }
  std::error_code ec;
  if (!ok) {
    fs::remove(tmp, ec);
    fail_file(ErrorCode::kIo, path, std::string("write failed: ") + std::strerror(err));
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ec2;
    fs::remove(tmp, ec2);
    fail_file(ErrorCode::kIo, path, "cannot move the written file into place: " + ec.message());
  }
}

}  // namespace duet::detail
