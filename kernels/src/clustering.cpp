#include <duet/kernels/clustering.hpp>
#include <duet/kernels/error.hpp>

#include "parallel.hpp"
#include "radix_sort.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <string>

namespace duet {

void validate(const ClusteringSettings& s) {
  if (!(s.tolerance_m > 0.0f) || !std::isfinite(s.tolerance_m))
    fail(ErrorCode::kInvalidArgument, "ClusteringSettings.tolerance_m must be finite and > 0 m, got " +
                                          std::to_string(s.tolerance_m));
  if (s.min_size > s.max_size)
    fail(ErrorCode::kInvalidArgument, "ClusteringSettings.min_size (" + std::to_string(s.min_size) +
                                          ") must be <= max_size (" + std::to_string(s.max_size) + ")");
}

namespace {

constexpr std::uint32_t kNoLabel = std::numeric_limits<std::uint32_t>::max();
constexpr std::uint64_t kEmpty = std::numeric_limits<std::uint64_t>::max();
constexpr std::size_t kBlock = 1 << 14;

// Lock-free union-find; a set's root is always its smallest member, so the final forest does not
// depend on the order of the unions (and hence not on the thread count).
struct UnionFind {
  std::uint32_t* parent;
  std::uint32_t load(std::uint32_t x) const {
    return std::atomic_ref<std::uint32_t>(parent[x]).load(std::memory_order_relaxed);
  }
  std::uint32_t find(std::uint32_t x) const {
    while (true) {
      const std::uint32_t p = load(x);
      if (p == x) return x;
      const std::uint32_t gp = load(p);
      if (gp != p) std::atomic_ref<std::uint32_t>(parent[x]).store(gp, std::memory_order_relaxed);  // halving
      x = gp;
    }
  }
  void unite(std::uint32_t a, std::uint32_t b) const {
    while (true) {
      a = find(a);
      b = find(b);
      if (a == b) return;
      if (a < b) std::swap(a, b);  // link the larger root under the smaller
      std::uint32_t expected = a;
      if (std::atomic_ref<std::uint32_t>(parent[a]).compare_exchange_weak(expected, b, std::memory_order_relaxed))
        return;
    }
  }
};

struct CellHash {
  std::vector<std::uint64_t> keys;
  std::vector<std::uint32_t> cells;
  std::uint64_t mask = 0;
  int shift = 64;
  void build(const std::vector<std::uint64_t>& cell_keys) {
    const std::size_t cap = std::bit_ceil(std::max<std::size_t>(16, cell_keys.size() * 2));
    keys.assign(cap, kEmpty);
    cells.resize(cap);
    mask = cap - 1;
    shift = 64 - std::countr_zero(cap);
    for (std::size_t c = 0; c < cell_keys.size(); ++c) {
      std::uint64_t h = (cell_keys[c] * 0x9E3779B97F4A7C15ull) >> shift;
      while (keys[h] != kEmpty) h = (h + 1) & mask;
      keys[h] = cell_keys[c];
      cells[h] = static_cast<std::uint32_t>(c);
    }
  }
  std::uint32_t find(std::uint64_t key) const {
    std::uint64_t h = (key * 0x9E3779B97F4A7C15ull) >> shift;
    while (true) {
      const std::uint64_t k = keys[h];
      if (k == key) return cells[h];
      if (k == kEmpty) return kNoLabel;
      h = (h + 1) & mask;
    }
  }
};

}  // namespace

std::vector<std::vector<std::uint32_t>> euclidean_clusters(PointsView points, std::span<const std::uint32_t> subset,
                                                           const ClusteringSettings& settings,
                                                           ClusteringWorkspace& ws) {
  validate(settings);
  const std::size_t n = points.size();
  if (n >= kNoLabel) fail(ErrorCode::kInvalidArgument, "euclidean_clusters: more than 2^32-2 points");
  // Gather the selected finite points: local index -> input index.
  std::vector<std::uint32_t> src;
  if (subset.empty()) {
    src.reserve(n);
    for (std::size_t i = 0; i < n; ++i)
      if (is_finite(points[i])) src.push_back(static_cast<std::uint32_t>(i));
  } else {
    src.reserve(subset.size());
    for (const std::uint32_t i : subset) {
      if (i >= n)
        fail(ErrorCode::kInvalidArgument, "euclidean_clusters: subset index " + std::to_string(i) + " >= " +
                                              std::to_string(n) + " points");
      if (is_finite(points[i])) src.push_back(i);
    }
    // A point listed twice is one point (as in PCL, which marks points processed).
    std::sort(src.begin(), src.end());
    src.erase(std::unique(src.begin(), src.end()), src.end());
  }
  const std::size_t m = src.size();
  if (m == 0) return {};
  const float tol = settings.tolerance_m;
  const float tol2 = tol * tol;

  Eigen::Vector3f lo = points[src[0]], hi = lo;
  for (const std::uint32_t i : src) {
    const Eigen::Vector3f p = points[i];
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }

  // Cells of size `cell`. Sparse clouds: cell = tolerance, 26 neighbours, all pairs checked.
  // Dense clouds: cell = tolerance/sqrt(3), so a cell is a clique (its diagonal is <= tolerance)
  // and two cells need only one close pair to be joined.
  // The extent, in tolerances, must fit 20 bits per axis (in the dense path's smaller cells it
  // then fits 21): the three cell indices are packed into one 63-bit key.
  for (int a = 0; a < 3; ++a) {
    const double lo_t = static_cast<double>(lo[a]) / tol, hi_t = static_cast<double>(hi[a]) / tol;
    if (!(std::fabs(lo_t) < 1e15) || !(std::fabs(hi_t) < 1e15) || !(hi_t - lo_t < 1048575.0))
      fail(ErrorCode::kOutOfRange, "euclidean_clusters: coordinate range [" + std::to_string(lo[a]) + ", " +
                                       std::to_string(hi[a]) + "] m on axis " + "xyz"[a] + " is too large: more than 2^20 tolerances of " +
                                       std::to_string(tol) + " m");
  }
  auto bin = [&](float cell, std::int64_t* cmin, int* bits) -> std::uint64_t {
    for (int a = 0; a < 3; ++a) {
      const double l = std::floor(static_cast<double>(lo[a]) / cell), h = std::floor(static_cast<double>(hi[a]) / cell);
      cmin[a] = static_cast<std::int64_t>(l);
      bits[a] = std::max(1, static_cast<int>(std::bit_width(static_cast<std::uint64_t>(static_cast<std::int64_t>(h) - cmin[a]))));
    }
    ws.cell_keys.resize(m);
    ws.order.resize(m);
    detail::for_blocks(m, kBlock, [&](std::size_t, std::size_t b, std::size_t e) {
      for (std::size_t j = b; j < e; ++j) {
        const Eigen::Vector3f p = points[src[j]];
        const auto x = static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(static_cast<double>(p.x()) / cell)) - cmin[0]);
        const auto y = static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(static_cast<double>(p.y()) / cell)) - cmin[1]);
        const auto z = static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(static_cast<double>(p.z()) / cell)) - cmin[2]);
        ws.cell_keys[j] = x | (y << bits[0]) | (z << (bits[0] + bits[1]));
        ws.order[j] = static_cast<std::uint32_t>(j);
      }
    });
    const std::uint64_t max_key = (std::uint64_t{1} << (bits[0] + bits[1] + bits[2])) - 1;
    detail::radix_sort_pairs(ws.cell_keys, ws.order, ws.keys_tmp, ws.order_tmp, max_key);
    std::size_t cells = 0;
    for (std::size_t j = 0; j < m; ++j) cells += (j == 0 || ws.cell_keys[j] != ws.cell_keys[j - 1]);
    return cells;
  };

  std::int64_t cmin[3];
  int bits[3];
  float cell = tol;
  std::size_t ncells = bin(cell, cmin, bits);
  const bool clique = static_cast<double>(m) / static_cast<double>(ncells) > 12.0;
  if (clique) {
    cell = tol / std::sqrt(3.0f) * (1.0f - 1e-5f);  // strictly: any two points of a cell are < tol apart
    ncells = bin(cell, cmin, bits);
  }

  // Cell table: unique keys, begin offsets into the sorted order.
  std::vector<std::uint64_t> ukeys;
  ukeys.reserve(ncells);
  ws.cell_begin.clear();
  ws.cell_begin.reserve(ncells + 1);
  for (std::size_t j = 0; j < m; ++j)
    if (j == 0 || ws.cell_keys[j] != ws.cell_keys[j - 1]) {
      ukeys.push_back(ws.cell_keys[j]);
      ws.cell_begin.push_back(static_cast<std::uint32_t>(j));
    }
  ws.cell_begin.push_back(static_cast<std::uint32_t>(m));
  CellHash table;
  table.build(ukeys);
  ws.sorted_pts.resize(m);
  detail::for_blocks(m, kBlock, [&](std::size_t, std::size_t b, std::size_t e) {
    for (std::size_t j = b; j < e; ++j) ws.sorted_pts[j] = points[src[ws.order[j]]];
  });

  // Forward neighbour offsets (half of the neighbourhood) whose cells can hold points within tol.
  struct Off {
    int dx, dy, dz;
  };
  std::vector<Off> offs;
  const int r = clique ? 2 : 1;
  for (int dz = 0; dz <= r; ++dz)
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) {
        if (dz == 0 && (dy < 0 || (dy == 0 && dx <= 0))) continue;
        auto gap = [&](int d) { return static_cast<double>(std::max(std::abs(d) - 1, 0)) * cell; };
        if (gap(dx) * gap(dx) + gap(dy) * gap(dy) + gap(dz) * gap(dz) <= static_cast<double>(tol2)) offs.push_back({dx, dy, dz});
      }
  const std::uint64_t fx = (std::uint64_t{1} << bits[0]) - 1, fy = (std::uint64_t{1} << bits[1]) - 1,
                      fz = (std::uint64_t{1} << bits[2]) - 1;

  // Union-find over sorted positions; in clique mode every cell starts as one set.
  ws.parent.resize(m);
  detail::for_blocks(ncells, 4096, [&](std::size_t, std::size_t b, std::size_t e) {
    for (std::size_t c = b; c < e; ++c)
      for (std::uint32_t j = ws.cell_begin[c]; j < ws.cell_begin[c + 1]; ++j)
        ws.parent[j] = clique ? ws.cell_begin[c] : j;
  });
  const UnionFind uf{ws.parent.data()};
  const Eigen::Vector3f* P = ws.sorted_pts.data();
  detail::for_blocks(ncells, 512, [&](std::size_t, std::size_t b, std::size_t e) {
    for (std::size_t c = b; c < e; ++c) {
      const std::uint32_t a0 = ws.cell_begin[c], a1 = ws.cell_begin[c + 1];
      const std::uint64_t key = ukeys[c];
      const auto x = static_cast<std::int64_t>(key & fx), y = static_cast<std::int64_t>((key >> bits[0]) & fy),
                 z = static_cast<std::int64_t>((key >> (bits[0] + bits[1])) & fz);
      if (!clique) {  // pairs inside the cell
        for (std::uint32_t i = a0; i < a1; ++i)
          for (std::uint32_t j = i + 1; j < a1; ++j)
            if ((P[i] - P[j]).squaredNorm() <= tol2) uf.unite(i, j);
      }
      for (const Off& o : offs) {
        const std::int64_t nx = x + o.dx, ny = y + o.dy, nz = z + o.dz;
        if (nx < 0 || ny < 0 || nz < 0 || nx > static_cast<std::int64_t>(fx) || ny > static_cast<std::int64_t>(fy) ||
            nz > static_cast<std::int64_t>(fz))
          continue;
        const std::uint32_t nc = table.find(static_cast<std::uint64_t>(nx) | (static_cast<std::uint64_t>(ny) << bits[0]) |
                                            (static_cast<std::uint64_t>(nz) << (bits[0] + bits[1])));
        if (nc == kNoLabel) continue;
        const std::uint32_t b0 = ws.cell_begin[nc], b1 = ws.cell_begin[nc + 1];
        if (clique) {
          if (uf.find(a0) == uf.find(b0)) continue;
          bool joined = false;
          for (std::uint32_t i = a0; i < a1 && !joined; ++i)
            for (std::uint32_t j = b0; j < b1; ++j)
              if ((P[i] - P[j]).squaredNorm() <= tol2) {
                uf.unite(a0, b0);
                joined = true;
                break;
              }
        } else {
          for (std::uint32_t i = a0; i < a1; ++i)
            for (std::uint32_t j = b0; j < b1; ++j)
              if ((P[i] - P[j]).squaredNorm() <= tol2) uf.unite(i, j);
        }
      }
    }
  });

  // Components -> clusters of input indices (canonical order, see header).
  ws.label.assign(m, kNoLabel);
  std::vector<std::uint32_t> size_of_root(m, 0);
  for (std::uint32_t j = 0; j < m; ++j) ++size_of_root[uf.find(j)];
  std::vector<std::vector<std::uint32_t>> clusters;
  for (std::uint32_t j = 0; j < m; ++j) {
    const std::uint32_t root = uf.find(j);
    const std::uint32_t s = size_of_root[root];
    if (s < settings.min_size || s > settings.max_size) continue;
    if (ws.label[root] == kNoLabel) {
      ws.label[root] = static_cast<std::uint32_t>(clusters.size());
      clusters.emplace_back();
      clusters.back().reserve(s);
    }
    clusters[ws.label[root]].push_back(src[ws.order[j]]);
  }
  for (auto& c : clusters) std::sort(c.begin(), c.end());
  std::sort(clusters.begin(), clusters.end(), [](const auto& a, const auto& b) {
    return a.size() != b.size() ? a.size() > b.size() : a.front() < b.front();
  });
  return clusters;
}

std::vector<std::vector<std::uint32_t>> euclidean_clusters(PointsView points, std::span<const std::uint32_t> subset,
                                                           const ClusteringSettings& settings) {
  ClusteringWorkspace ws;
  return euclidean_clusters(points, subset, settings, ws);
}

}  // namespace duet
