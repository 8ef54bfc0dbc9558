#pragma once
// Helpers shared by the runtime tests: a temporary directory per test, whole-file bytes, error messages.
#include <duet/kernels/error.hpp>

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <exception>
#include <functional>
#include <initializer_list>
#include <sstream>
#include <string>
#include <system_error>

namespace duet_test {

namespace fs = std::filesystem;

// A directory per test under the build tree (named after the suite and test), removed at the end.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = fs::path(DUET_BINARY_DIR) / "test_tmp" /
            (std::string(info->test_suite_name()) + "_" + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  [[nodiscard]] fs::path operator/(const std::string& name) const { return path_ / name; }
  [[nodiscard]] const fs::path& path() const { return path_; }
  /// Writes `text` to the file `name` in the directory; returns its path.
  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path p = path_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }

 private:
  fs::path path_;
};

inline std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void spit(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// The message of the duet::Error `fn` throws ("" if it throws none).
// Expects `fn` to throw duet::Error with `code` and a message containing every one of `parts`.
template <class Fn>
void expect_error(Fn&& fn, duet::ErrorCode code, std::initializer_list<std::string> parts) {
  try {
    fn();
    ADD_FAILURE() << "no duet::Error thrown";
  } catch (const duet::Error& e) {
    EXPECT_EQ(static_cast<int>(e.code()), static_cast<int>(code)) << e.what();
    for (const std::string& part : parts) EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not a duet::Error: " << e.what();
  }
}

inline std::string error_of(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const duet::Error& e) {
    return e.what();
  }
  return {};
}

}  // namespace duet_test
