// Runs the C example program (bindings_c/examples/example.c, built as C99) and checks its exit
// code and what it reports about the synthetic room.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace {

struct ProcessResult {
  int exit_code = -1;
  std::string output;
};

ProcessResult run_command(const std::string& command) {
  ProcessResult r;
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (p == nullptr) return r;
  char buf[4096];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) r.output.append(buf, n);
  const int status = pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

/// The unsigned number that follows the first occurrence of `label` (0 if none).
std::size_t number_after(const std::string& text, const std::string& label) {
  std::size_t pos = text.find(label);
  if (pos == std::string::npos) return 0;
  pos += label.size();
  while (pos < text.size() && text[pos] == ' ') ++pos;
  std::size_t value = 0;
  while (pos < text.size() && text[pos] >= '0' && text[pos] <= '9') {
    value = value * 10 + static_cast<std::size_t>(text[pos++] - '0');
  }
  return value;
}

}  // namespace

TEST(CapiExample, RunsAndMapsTheRoom) {
  const ProcessResult r = run_command(DUET_EXAMPLE_C);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("\nok\n"), std::string::npos) << r.output;
  // Two full 640x480 frames: every pixel sees the floor or a wall within 5 m.
  EXPECT_EQ(number_after(r.output, "back-projected points:"), 2u * 640u * 480u) << r.output;
  EXPECT_EQ(number_after(r.output, "sensor 1:"), 640u * 480u) << r.output;
  const std::size_t filtered = number_after(r.output, "voxel-filtered points:");
  EXPECT_GT(filtered, 1000u) << r.output;
  EXPECT_LT(filtered, 20000u) << r.output;
  EXPECT_GT(number_after(r.output, "labels: floor"), 0u) << r.output;
  EXPECT_GT(number_after(r.output, ", obstacle"), 0u) << r.output;
  // The wall 2 m ahead spans about 2 x 2.12 tan(28.5 deg) = 2.3 m = 46 cells of 5 cm, the right
  // wall about 1.6 m: the obstacle cells must be of that order, with much more free floor.
  const std::size_t occupied = number_after(r.output, "cells: occupied");
  const std::size_t free_cells = number_after(r.output, ", free");
  EXPECT_GT(occupied, 50u) << r.output;
  EXPECT_LT(occupied, 400u) << r.output;
  EXPECT_GT(free_cells, occupied) << r.output;
  EXPECT_EQ(r.output.find("DUET_ERROR"), std::string::npos) << r.output;
}
