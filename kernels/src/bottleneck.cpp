/// @file bottleneck.cpp
/// widest_passage(): a maximin (widest path) Dijkstra on the clearance (see bottleneck.hpp).
#include <duet/kernels/bottleneck.hpp>
#include <duet/kernels/error.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <queue>
#include <string>
#include <utility>

namespace duet {

void widest_passage(const InflatedGrid& g, const Eigen::Vector2f& start_xy, std::vector<float>& out) {
  const std::size_t n = g.cell_count();
  if (g.width < 0 || g.height < 0 || g.state.size() != n || g.clearance_m.size() != n)
    fail(ErrorCode::kInvalidArgument, "widest_passage: the InflatedGrid's buffers (" + std::to_string(g.state.size()) + " states, " +
                                          std::to_string(g.clearance_m.size()) + " clearances) do not match its " +
                                          std::to_string(g.width) + " x " + std::to_string(g.height) + " cells");
  out.assign(n, 0.0f);
  if (n == 0 || !std::isfinite(start_xy.x()) || !std::isfinite(start_xy.y())) return;
  const Eigen::Vector2i s = g.cell_of(start_xy);
  if (!g.in_bounds(s.x(), s.y())) return;
  auto free = [&](int x, int y) { return g.in_bounds(x, y) && g.state[g.index(x, y)] == CellState::kFree; };
  if (!free(s.x(), s.y())) return;

  // Max-heap on the bottleneck value; a cell is settled the first time it is popped with the
  // value it holds (later, smaller entries of it are stale).
  using Entry = std::pair<float, std::uint32_t>;
  std::priority_queue<Entry> heap;
  std::vector<std::uint8_t> settled(n, 0);
  const std::size_t s_idx = g.index(s.x(), s.y());
  out[s_idx] = g.clearance_m[s_idx];
  heap.emplace(out[s_idx], static_cast<std::uint32_t>(s_idx));
  constexpr int kDx[8] = {1, -1, 0, 0, 1, 1, -1, -1};
  constexpr int kDy[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  while (!heap.empty()) {
    const auto [v, cell] = heap.top();
    heap.pop();
    if (settled[cell] || v < out[cell]) continue;
    settled[cell] = 1;
    const int x = static_cast<int>(cell % static_cast<std::uint32_t>(g.width));
    const int y = static_cast<int>(cell / static_cast<std::uint32_t>(g.width));
    for (int k = 0; k < 8; ++k) {
      const int nx = x + kDx[k], ny = y + kDy[k];
      if (!free(nx, ny)) continue;
      if (k >= 4 && !(free(x + kDx[k], y) && free(x, y + kDy[k]))) continue;  // no corner cutting
      const std::size_t ni = g.index(nx, ny);
      if (settled[ni]) continue;
      const float w = std::min(v, g.clearance_m[ni]);
      if (w > out[ni]) {
        out[ni] = w;
        heap.emplace(w, static_cast<std::uint32_t>(ni));
      }
    }
  }
}

}  // namespace duet
