#pragma once
// Running the `duet` program as a user would (tests/app): its exit code and output, the shared
// data folder, and a fresh folder per test.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>
#include <sys/wait.h>

namespace duet::test {

struct CliRun {
  int code;
  std::string output;  // stdout + stderr
};

inline CliRun run(const std::string& args) {
  const std::string cmd = std::string(DUET_CLI) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return {-1, "popen failed"};
  std::string out;
  std::array<char, 4096> buf{};
  while (std::fgets(buf.data(), buf.size(), p)) out += buf.data();
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

inline std::filesystem::path data_dir() { return std::filesystem::path(DUET_DATA_DIR); }

inline std::filesystem::path temp_dir(const std::string& name) {
  const std::filesystem::path d = std::filesystem::path(DUET_BINARY_DIR) / "test-app" / name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

}  // namespace duet::test

#define REQUIRE_DATA(sub)                                                           \
  if (!std::filesystem::exists(duet::test::data_dir() / (sub)))                     \
  GTEST_SKIP() << "shared data not found: " << (duet::test::data_dir() / (sub))
