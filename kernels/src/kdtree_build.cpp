/// @file kdtree_build.cpp
/// KdTree::build (parallel, sampled-median splits) and the leaf start cells of hinted searches.
#include <duet/kernels/error.hpp>
#include <duet/kernels/kdtree.hpp>

#include "parallel.hpp"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace duet {

void KdTree::build(PointsView points, const KdTreeSettings& settings) {
  if (settings.max_leaf_size < 1 || settings.max_leaf_size > 1024)
    fail(ErrorCode::kInvalidArgument, "KdTreeSettings.max_leaf_size must be in [1, 1024], got " +
                                          std::to_string(settings.max_leaf_size));
  if (points.size() >= std::numeric_limits<std::int32_t>::max())
    fail(ErrorCode::kInvalidArgument, "KdTree: more than 2^31-2 points");
  leaf_size_ = settings.max_leaf_size;
  n_input_ = points.size();
  // The finite points in input order, by blocks in parallel (a count, then the copy at each
  // block's offset: the same order for any thread count). items_ is kept between builds.
  constexpr std::size_t kBlock = 16384;
  const std::size_t nblocks = detail::block_count(points.size(), kBlock);
  std::vector<std::uint32_t> block_start(nblocks + 1, 0);
  detail::for_blocks(points.size(), kBlock, [&](std::size_t b, std::size_t begin, std::size_t end) {
    std::uint32_t c = 0;
    for (std::size_t i = begin; i < end; ++i) c += is_finite(points[i]) ? 1u : 0u;
    block_start[b + 1] = c;
  });
  for (std::size_t b = 0; b < nblocks; ++b) block_start[b + 1] += block_start[b];
  items_.resize(block_start[nblocks]);
  Item* items = items_.data();
  detail::for_blocks(points.size(), kBlock, [&](std::size_t b, std::size_t begin, std::size_t end) {
    std::uint32_t o = block_start[b];
    for (std::size_t i = begin; i < end; ++i) {
      const Eigen::Vector3f p = points[i];
      if (is_finite(p)) items[o++] = {p, static_cast<std::uint32_t>(i)};
    }
  });
  const auto m = static_cast<std::uint32_t>(items_.size());
  nodes_.clear();
  // Splits leave at least a quarter of a node's points on each side, so leaves hold at least
  // ceil(leaf/4) points (unless the input is smaller): at most 2m/ceil(leaf/4) + 1 nodes.
  const std::size_t quarter = static_cast<std::size_t>((leaf_size_ + 3) / 4);
  const std::size_t max_nodes = 2 * (static_cast<std::size_t>(m) / quarter) + 3;
  nodes_.resize(max_nodes);
  boxes_.resize(max_nodes);
  parent_.resize(max_nodes);
  std::atomic<std::uint32_t> next{0};

  // Recursive build; node numbers come from an atomic counter (their order may vary between
  // runs, the tree's geometry and point order do not). Each node is split on the axis of its
  // box's largest extent at the median of a fixed sample of its points, by one partition pass
  // that also yields the two children's boxes (an exact median by nth_element only when the
  // sample's is too lopsided: less than a quarter, or than ceil(leaf/4) points, on a side).
  struct Builder {
    KdTree& t;
    Item* items;
    std::atomic<std::uint32_t>& next;
    std::uint32_t min_leaf;  // ceil(leaf/4) >= 1: each side of a split gets at least this many
    std::uint32_t operator()(std::uint32_t begin, std::uint32_t end, Eigen::Vector3f lo, Eigen::Vector3f hi) const {
      const std::uint32_t idx = next.fetch_add(1, std::memory_order_relaxed);
      Node& node = t.nodes_[idx];
      t.boxes_[idx] = {lo, begin, hi, end};
      const std::uint32_t count = end - begin;
      int dim;
      if (count > static_cast<std::uint32_t>(t.leaf_size_) && (hi - lo).maxCoeff(&dim) > 0.0f) {
        constexpr std::uint32_t kSample = 31;
        float sample[kSample];
        const std::uint32_t ns = std::min(kSample, count);
        for (std::uint32_t i = 0; i < ns; ++i) sample[i] = items[begin + static_cast<std::uint32_t>((std::uint64_t{count} * (2 * i + 1)) / (2 * ns))].p[dim];
        std::nth_element(sample, sample + ns / 2, sample + ns);
        float split = sample[ns / 2];
        // Partition: p[dim] < split left, the rest right; the children's boxes on the way.
        const float inf = std::numeric_limits<float>::infinity();
        Eigen::Vector3f llo = Eigen::Vector3f::Constant(inf), lhi = -llo, rlo = llo, rhi = -llo;
        std::uint32_t i = begin, j = end;
        while (true) {
          while (i < j && items[i].p[dim] < split) {
            llo = llo.cwiseMin(items[i].p);
            lhi = lhi.cwiseMax(items[i].p);
            ++i;
          }
          while (i < j && !(items[j - 1].p[dim] < split)) {
            rlo = rlo.cwiseMin(items[j - 1].p);
            rhi = rhi.cwiseMax(items[j - 1].p);
            --j;
          }
          if (i >= j) break;
          std::swap(items[i], items[j - 1]);
        }
        std::uint32_t mid = i;
        const std::uint32_t min_side = std::max(min_leaf, count / 4);
        if (mid - begin < min_side || end - mid < min_side) {  // lopsided: exact median
          mid = begin + count / 2;
          std::nth_element(items + begin, items + mid, items + end,
                           [dim](const Item& a, const Item& b) { return a.p[dim] < b.p[dim]; });
          split = items[mid].p[dim];
          llo = rlo = Eigen::Vector3f::Constant(inf);
          lhi = rhi = -llo;
          for (std::uint32_t k = begin; k < mid; ++k) {
            llo = llo.cwiseMin(items[k].p);
            lhi = lhi.cwiseMax(items[k].p);
          }
          for (std::uint32_t k = mid; k < end; ++k) {
            rlo = rlo.cwiseMin(items[k].p);
            rhi = rhi.cwiseMax(items[k].p);
          }
        }
        node.split = split;
        std::uint32_t l = 0, r = 0;
        if (count > 16384) {
          tbb::parallel_invoke([&] { l = (*this)(begin, mid, llo, lhi); }, [&] { r = (*this)(mid, end, rlo, rhi); });
        } else {
          l = (*this)(begin, mid, llo, lhi);
          r = (*this)(mid, end, rlo, rhi);
        }
        node.dim = dim;
        node.a = l;
        node.b = r;
        t.parent_[l] = idx;
        t.parent_[r] = idx;
        return idx;
      }
      node.dim = -1;
      if (count > static_cast<std::uint32_t>(t.leaf_size_)) {  // all identical (zero extent)
        std::sort(items + begin, items + end, [](const Item& x, const Item& y) { return x.id < y.id; });
        node.dim = kUniformLeaf;
      }
      node.a = begin;
      node.b = end;
      return idx;
    }
  };
  if (m > 0) {
    // Bounding box by blocks (min / max are exact: any grouping gives the same box).
    const std::size_t mb = detail::block_count(m, kBlock);
    std::vector<Eigen::Vector3f> blo(mb), bhi(mb);
    detail::for_blocks(m, kBlock, [&](std::size_t b, std::size_t begin, std::size_t end) {
      Eigen::Vector3f l = items[begin].p, h = l;
      for (std::size_t i = begin; i < end; ++i) {
        l = l.cwiseMin(items[i].p);
        h = h.cwiseMax(items[i].p);
      }
      blo[b] = l;
      bhi[b] = h;
    });
    Eigen::Vector3f lo = blo[0], hi = bhi[0];
    for (std::size_t b = 1; b < mb; ++b) {
      lo = lo.cwiseMin(blo[b]);
      hi = hi.cwiseMax(bhi[b]);
    }
    Builder{*this, items, next, static_cast<std::uint32_t>(quarter)}(0, m, lo, hi);
    parent_[0] = kNoHint;
  }
  nodes_.resize(next.load());
  boxes_.resize(next.load());
  parent_.resize(next.load());
  node_count_ = next.load();
  index_leaf_starts(m);
  pts_.resize(m);
  ids_.resize(m);
  xs_.resize(m + kPad);
  ys_.resize(m + kPad);
  zs_.resize(m + kPad);
  for (std::size_t i = m; i < m + kPad; ++i) xs_[i] = ys_[i] = zs_[i] = 0.0f;
  detail::for_blocks(m, kBlock, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      pts_[i] = items[i].p;
      ids_[i] = items[i].id;
      xs_[i] = items[i].p.x();
      ys_[i] = items[i].p.y();
      zs_[i] = items[i].p.z();
    }
  });
}

void KdTree::index_leaf_starts(std::uint32_t m) {
  // For every leaf: the ancestor kStartUp levels above it (or the root) and that ancestor's
  // cell (the region its splits bound; unbounded sides are infinite).
  constexpr int kStartUp = 3;
  leaf_start_.clear();
  leaf_node_.clear();
  leaf_of_.assign(m, 0);
  if (m == 0) return;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  struct Visit {
    std::uint32_t node;
    int depth;
    Eigen::Vector3f lo, hi;
  };
  std::vector<Visit> path;  // current root-to-node path (explicit DFS keeps cells)
  std::vector<Visit> pending{{0, 0, Eigen::Vector3f::Constant(-kInf), Eigen::Vector3f::Constant(kInf)}};
  while (!pending.empty()) {
    const Visit it = pending.back();
    pending.pop_back();
    while (!path.empty() && path.back().depth >= it.depth) path.pop_back();
    path.push_back(it);
    const Node& nd = nodes_[it.node];
    if (nd.dim < 0) {
      const Visit& anc = path[path.size() > kStartUp ? path.size() - 1 - kStartUp : 0];
      const auto leaf = static_cast<std::uint32_t>(leaf_start_.size());
      leaf_start_.push_back({anc.node, anc.lo, anc.hi});
      leaf_node_.push_back(it.node);
      for (std::uint32_t j = nd.a; j < nd.b; ++j) leaf_of_[j] = leaf;
      continue;
    }
    Visit l = it, r = it;
    l.node = nd.a;
    r.node = nd.b;
    l.depth = r.depth = it.depth + 1;
    l.hi[nd.dim] = nd.split;
    r.lo[nd.dim] = nd.split;
    pending.push_back(r);
    pending.push_back(l);
  }
}

}  // namespace duet
