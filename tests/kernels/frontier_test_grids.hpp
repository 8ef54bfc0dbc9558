#pragma once
// Grids for the frontier tests (test_frontier.cpp: find_frontier; test_frontier_mask.cpp: the
// frontier cell): log-odds test grids, a random partly explored indoor-like grid, and the per-cell
// reference of frontier_mask().
#include "kernel_test_util.hpp"

#include <duet/kernels/frontier.hpp>
#include <duet/kernels/grid_view.hpp>

#include <algorithm>
#include <cstdint>
#include <random>
#include <span>
#include <vector>

namespace duet {
namespace detail {  // defined in kernels/src/frontier.cpp: allow_avx2 = false forces the SSE2 path
std::size_t frontier_mask_isa(const GridView& grid, const CellThresholds& t, std::span<std::uint8_t> mask, bool allow_avx2);
std::size_t frontier_mask_isa(std::span<const CellState> state, int width, int height, std::span<std::uint8_t> mask,
                              bool allow_avx2);
}  // namespace detail
namespace frontier_test {

using test::kNaN;

constexpr float kFree = -2.0f, kOcc = 3.0f, kMid = 0.1f;

using TestGrid = test::LogOddsTestGrid;

inline TestGrid blank(int w, int h, float v, float res = 0.05f) {
  TestGrid g;
  g.w = w;
  g.h = h;
  g.res = res;
  g.origin = {-3.0f, 1.0f};
  g.l.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), v);
  return g;
}

// Partly explored indoor-like grid: unknown everywhere, random free rectangles, wall segments and
// clutter, unknown specks.
inline TestGrid explored(int w, int h, std::uint32_t seed) {
  TestGrid g = blank(w, h, kNaN);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> ux(0, w - 1), uy(0, h - 1), us(4, std::max(5, w / 3));
  for (int k = 0; k < 8; ++k) {
    const int x = ux(rng), y = uy(rng);
    g.rect(x, y, x + us(rng), y + us(rng), kFree);
  }
  for (int k = 0; k < (w * h) / 150; ++k) {
    const int x = ux(rng), y = uy(rng), len = us(rng) / 2;
    if (rng() & 1) g.rect(x, y, x + len, y, kOcc);
    else g.rect(x, y, x, y + len, kOcc);
  }
  for (int k = 0; k < (w * h) / 80; ++k) g.set(ux(rng), uy(rng), (rng() % 3) ? kOcc : (rng() & 1 ? kNaN : kMid));
  return g;
}

inline std::vector<std::uint8_t> reference_mask(const std::vector<CellState>& st, int w, int h) {
  std::vector<std::uint8_t> m(st.size(), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (st[static_cast<std::size_t>(y * w + x)] != CellState::kFree) continue;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx >= 0 && ny >= 0 && nx < w && ny < h && st[static_cast<std::size_t>(ny * w + nx)] == CellState::kUnknown)
            m[static_cast<std::size_t>(y * w + x)] = 1;
        }
    }
  return m;
}

}  // namespace frontier_test
}  // namespace duet
