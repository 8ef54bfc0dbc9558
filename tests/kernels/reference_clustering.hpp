#pragma once
// Reference Euclidean clustering for the kernel tests: breadth-first search over "distance <=
// tolerance", written independently of the kernel (no union-find, no radix sort).
#include <duet/kernels/types.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <span>
#include <unordered_map>
#include <vector>

namespace duet::test {

using Clusters = std::vector<std::vector<std::uint32_t>>;

// Canonical order of the header: largest first, ties by smallest index; indices ascending.
inline void canonical(Clusters& c) {
  for (auto& x : c) std::sort(x.begin(), x.end());
  std::sort(c.begin(), c.end(), [](const auto& a, const auto& b) { return a.size() != b.size() ? a.size() > b.size() : a.front() < b.front(); });
}

// Connected components of "distance <= tol" by breadth-first search. Neighbour candidates come from
// all points (brute force) or from a hashed grid with cells slightly larger than tol; a visited
// point leaves its cell's candidate list.
struct KeyHash {
  std::size_t operator()(const std::array<std::int64_t, 3>& k) const noexcept {
    return static_cast<std::size_t>(k[0] * 73856093LL ^ k[1] * 19349663LL ^ k[2] * 83492791LL);
  }
};

inline Clusters reference_clusters(PointsView pts, std::span<const std::uint32_t> subset, float tol, std::uint32_t min_size,
                            std::uint32_t max_size, bool brute) {
  std::vector<std::uint32_t> ids;
  if (subset.empty()) {
    for (std::uint32_t i = 0; i < pts.size(); ++i)
      if (is_finite(pts[i])) ids.push_back(i);
  } else {
    for (const auto i : subset)
      if (is_finite(pts[i])) ids.push_back(i);
  }
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  const float tol2 = tol * tol;
  const double cell = 1.01 * static_cast<double>(tol);
  using Key = std::array<std::int64_t, 3>;
  auto key_of = [&](const Eigen::Vector3f& p) {
    return Key{static_cast<std::int64_t>(std::floor(p.x() / cell)), static_cast<std::int64_t>(std::floor(p.y() / cell)),
               static_cast<std::int64_t>(std::floor(p.z() / cell))};
  };
  std::unordered_map<Key, std::vector<std::uint32_t>, KeyHash> grid;
  if (!brute)
    for (const auto i : ids) grid[key_of(pts[i])].push_back(i);
  std::vector<std::uint8_t> visited(pts.size(), 0);
  Clusters out;
  for (const auto seed : ids) {
    if (visited[seed]) continue;
    std::vector<std::uint32_t> comp{seed};
    visited[seed] = 1;
    std::deque<std::uint32_t> q{seed};
    while (!q.empty()) {
      const std::uint32_t i = q.front();
      q.pop_front();
      const Eigen::Vector3f p = pts[i];
      auto close = [&](std::uint32_t j) { return (pts[j] - p).squaredNorm() <= tol2; };
      auto visit = [&](std::uint32_t j) {
        visited[j] = 1;
        comp.push_back(j);
        q.push_back(j);
      };
      if (brute) {
        for (const auto j : ids)
          if (!visited[j] && close(j)) visit(j);
      } else {
        const Key k = key_of(p);
        for (int dz = -1; dz <= 1; ++dz)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const auto it = grid.find(Key{k[0] + dx, k[1] + dy, k[2] + dz});
              if (it == grid.end()) continue;
              auto& v = it->second;
              std::size_t keep = 0;
              for (std::size_t t = 0; t < v.size(); ++t) {
                const std::uint32_t j = v[t];
                if (visited[j]) continue;
                if (close(j)) visit(j);
                else v[keep++] = j;
              }
              v.resize(keep);
            }
      }
    }
    if (comp.size() >= min_size && comp.size() <= max_size) out.push_back(std::move(comp));
  }
  canonical(out);
  return out;
}

}  // namespace duet::test
