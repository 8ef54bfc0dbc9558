#include <duet/kernels/error.hpp>
#include <duet/kernels/kdtree.hpp>

#include "parallel.hpp"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <limits>
#include <string>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace duet {

struct KdTree::Item {
  Eigen::Vector3f p;
  std::uint32_t id;
};

namespace {

// Cells are pruned only when their distance exceeds the k-th distance by this factor: the
// incrementally computed cell distance may round up by a few ulps, and a point exactly at the
// k-th distance (a tie, or a point at max_dist2) must still be found.
constexpr float kPruneSlack = 1.00001f;

// Sorted fixed-capacity list of the best k candidates. Each candidate is one 64-bit key:
// the bits of its squared distance (a non-negative float: its bits sort as the value) above
// its input index, so "nearer, then smaller index" is a single integer comparison.
struct KBest {
  int k, count = 0;
  float worst_d;  // pruning distance: the k-th distance, or the limit while fewer than k
  std::uint64_t* key;
  std::uint32_t* pos;
  const std::uint32_t* ids;
  KBest(int k_, float limit, std::uint64_t* key_, std::uint32_t* pos_, const std::uint32_t* ids_)
      : k(k_), worst_d(limit), key(key_), pos(pos_), ids(ids_) {}
  [[nodiscard]] float worst() const noexcept { return worst_d; }
  void offer(float dist, std::uint32_t p) noexcept {
    const std::uint64_t kk = static_cast<std::uint64_t>(std::bit_cast<std::uint32_t>(dist)) << 32 | ids[p];
    if (count == k) {
      if (kk >= key[k - 1]) return;
    } else {
      ++count;
    }
    int j = count - 1;
    while (j > 0 && key[j - 1] > kk) {
      key[j] = key[j - 1];
      pos[j] = pos[j - 1];
      --j;
    }
    key[j] = kk;
    pos[j] = p;
    if (count == k) worst_d = std::bit_cast<float>(static_cast<std::uint32_t>(key[k - 1] >> 32));
  }
  int finish(float* dist2) const noexcept {
    for (int i = 0; i < count; ++i) dist2[i] = std::bit_cast<float>(static_cast<std::uint32_t>(key[i] >> 32));
    return count;
  }
};

}  // namespace

void KdTree::build(PointsView points, const KdTreeSettings& settings) {
  if (settings.max_leaf_size < 1 || settings.max_leaf_size > 1024)
    fail(ErrorCode::kInvalidArgument, "KdTreeSettings.max_leaf_size must be in [1, 1024], got " +
                                          std::to_string(settings.max_leaf_size));
  if (points.size() >= std::numeric_limits<std::int32_t>::max())
    fail(ErrorCode::kInvalidArgument, "KdTree: more than 2^31-2 points");
  leaf_size_ = settings.max_leaf_size;
  n_input_ = points.size();
  std::vector<Item> items;
  items.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f p = points[i];
    if (is_finite(p)) items.push_back({p, static_cast<std::uint32_t>(i)});
  }
  const auto m = static_cast<std::uint32_t>(items.size());
  nodes_.clear();
  // Splits leave at least a quarter of a node's points on each side, so leaves hold at least
  // ceil(leaf/4) points (unless the input is smaller): at most 2m/ceil(leaf/4) + 1 nodes.
  const std::size_t quarter = static_cast<std::size_t>((leaf_size_ + 3) / 4);
  nodes_.resize(2 * (static_cast<std::size_t>(m) / quarter) + 3);
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
        return idx;
      }
      node.dim = -1;
      node.a = begin;
      node.b = end;
      return idx;
    }
  };
  if (m > 0) {
    Eigen::Vector3f lo = items[0].p, hi = lo;
    for (const Item& it : items) {
      lo = lo.cwiseMin(it.p);
      hi = hi.cwiseMax(it.p);
    }
    Builder{*this, items.data(), next, static_cast<std::uint32_t>(quarter)}(0, m, lo, hi);
  }
  nodes_.resize(next.load());
  node_count_ = next.load();
  index_leaf_starts(m);
  pts_.resize(m);
  ids_.resize(m);
  xs_.assign(m + kPad, 0.0f);
  ys_.assign(m + kPad, 0.0f);
  zs_.assign(m + kPad, 0.0f);
  for (std::uint32_t i = 0; i < m; ++i) {
    pts_[i] = items[i].p;
    ids_[i] = items[i].id;
    xs_[i] = items[i].p.x();
    ys_[i] = items[i].p.y();
    zs_[i] = items[i].p.z();
  }
}

int KdTree::knn_tree(const Eigen::Vector3f& q, int k, std::uint32_t* tree_pos, float* dist2) const {
  return knn_tree(q, k, std::numeric_limits<float>::infinity(), tree_pos, dist2);
}

int KdTree::knn_tree(const Eigen::Vector3f& q, int k, float max_dist2, std::uint32_t* tree_pos, float* dist2) const {
  return knn_impl(q, k, max_dist2, kNoHint, tree_pos, dist2);
}

int KdTree::knn_tree_near(const Eigen::Vector3f& q, int k, float max_dist2, std::uint32_t hint_pos,
                          std::uint32_t* tree_pos, float* dist2) const {
  return knn_impl(q, k, max_dist2, hint_pos < pts_.size() ? hint_pos : kNoHint, tree_pos, dist2);
}

int KdTree::knn_impl(const Eigen::Vector3f& q, int k, float max_dist2, std::uint32_t hint, std::uint32_t* tree_pos,
                     float* dist2) const {
  if (k <= 0 || pts_.empty() || !is_finite(q) || !(max_dist2 >= 0.0f)) return 0;
  std::uint64_t local_keys[64];
  std::vector<std::uint64_t> heap_keys;
  std::uint64_t* keys = local_keys;
  if (k > 64) {
    heap_keys.resize(static_cast<std::size_t>(k));
    keys = heap_keys.data();
  }
  KBest best(k, max_dist2, keys, tree_pos, ids_.data());
  // Depth-first search, nearer child first; off[] holds the squared distance components from q
  // to the current cell, so mindist is the exact squared distance from q to that cell.
  struct Frame {
    std::uint32_t node;
    float mindist;
    float off[3];
  };
  Frame stack[128];
  int top = 0;
  // Searches the subtree of start (q's squared distance components to its cell in off), never
  // entering the subtree of skip.
  auto search = [&](std::uint32_t start, const float (&start_off)[3], std::uint32_t skip) {
    stack[top++] = {start, start_off[0] + start_off[1] + start_off[2], {start_off[0], start_off[1], start_off[2]}};
    while (top > 0) {
      const Frame f = stack[--top];
      if (f.mindist > best.worst() * kPruneSlack || f.node == skip) continue;
      std::uint32_t ni = f.node;
      float mindist = f.mindist;
      float off[3] = {f.off[0], f.off[1], f.off[2]};
      while (true) {
        const Node& nd = nodes_[ni];
        if (nd.dim < 0) {
          // Eight distances at a time, then the few candidates within the current k-th distance
          // offered (one mostly-not-taken branch per eight points). The SoA arrays are padded by
          // kPad entries, so the loads past the leaf's end stay inside them; those lanes are masked.
#if defined(__SSE2__)
          const __m128 qx = _mm_set1_ps(q.x()), qy = _mm_set1_ps(q.y()), qz = _mm_set1_ps(q.z());
          for (std::uint32_t j0 = nd.a; j0 < nd.b; j0 += 8) {
            alignas(16) float d[8];
            for (int h = 0; h < 2; ++h) {
              const __m128 dx = _mm_sub_ps(_mm_loadu_ps(xs_.data() + j0 + 4 * h), qx);
              const __m128 dy = _mm_sub_ps(_mm_loadu_ps(ys_.data() + j0 + 4 * h), qy);
              const __m128 dz = _mm_sub_ps(_mm_loadu_ps(zs_.data() + j0 + 4 * h), qz);
              // dx^2 + (dy^2 + dz^2): the order of Eigen's squaredNorm, identical values
              _mm_store_ps(d + 4 * h, _mm_add_ps(_mm_mul_ps(dx, dx), _mm_add_ps(_mm_mul_ps(dy, dy), _mm_mul_ps(dz, dz))));
            }
            const __m128 w = _mm_set1_ps(best.worst());
            unsigned mask = static_cast<unsigned>(_mm_movemask_ps(_mm_cmple_ps(_mm_load_ps(d), w))) |
                            static_cast<unsigned>(_mm_movemask_ps(_mm_cmple_ps(_mm_load_ps(d + 4), w))) << 4;
            if (nd.b - j0 < 8) mask &= (1u << (nd.b - j0)) - 1u;
            while (mask != 0) {
              const std::uint32_t t = static_cast<std::uint32_t>(std::countr_zero(mask));
              mask &= mask - 1;
              if (d[t] <= best.worst()) best.offer(d[t], j0 + t);
            }
          }
#else
          for (std::uint32_t j = nd.a; j < nd.b; ++j) {
            const float dx = xs_[j] - q.x(), dy = ys_[j] - q.y(), dz = zs_[j] - q.z();
            const float d = dx * dx + (dy * dy + dz * dz);
            if (d <= best.worst()) best.offer(d, j);
          }
#endif
          break;
        }
        const float diff = q[nd.dim] - nd.split;
        const std::uint32_t near = diff < 0.0f ? nd.a : nd.b;
        const std::uint32_t far = diff < 0.0f ? nd.b : nd.a;
        const float d2 = diff * diff;
        const float far_min = mindist - off[nd.dim] + d2;
        if (far_min <= best.worst() * kPruneSlack && top < 128) {
          Frame g{far, far_min, {off[0], off[1], off[2]}};
          g.off[nd.dim] = d2;
          stack[top++] = g;
        }
        if (near == skip) break;
        ni = near;
      }
    }
  };
  constexpr float kZero[3] = {0.0f, 0.0f, 0.0f};
  if (hint == kNoHint) {
    search(0, kZero, kNoHint);
    return best.finish(dist2);
  }
  // From the hint's neighbourhood: search the subtree of an ancestor of its leaf first. If q's
  // k-th distance then lies strictly inside that subtree's cell, nothing outside can be nearer
  // (points outside the cell are at least the boundary distance away; a point exactly on a split
  // plane may sit in either child, hence "strictly"). Otherwise the rest of the tree follows.
  const LeafStart& ls = leaf_start_[leaf_of_[hint]];
  float off[3];
  float inside = std::numeric_limits<float>::infinity();  // distance from q to the cell's boundary
  for (int d = 0; d < 3; ++d) {
    const float below = ls.lo[d] - q[d], above = q[d] - ls.hi[d];
    const float out = std::max({0.0f, below, above});
    off[d] = out * out;
    inside = std::min(inside, std::min(-below, -above));
  }
  search(ls.node, off, kNoHint);
  if (best.count == k && inside > 0.0f && inside * inside > best.worst() * 1.0001f) return best.finish(dist2);  // margin: float round-off
  search(0, kZero, ls.node);
  return best.finish(dist2);
}

void KdTree::index_leaf_starts(std::uint32_t m) {
  // For every leaf: the ancestor kStartUp levels above it (or the root) and that ancestor's
  // cell (the region its splits bound; unbounded sides are infinite).
  constexpr int kStartUp = 3;
  leaf_start_.clear();
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

int KdTree::knn(const Eigen::Vector3f& q, int k, std::uint32_t* idx, float* dist2) const {
  const int c = knn_tree(q, k, idx, dist2);
  for (int i = 0; i < c; ++i) idx[i] = ids_[idx[i]];
  return c;
}

std::size_t KdTree::radius(const Eigen::Vector3f& q, float radius, std::vector<std::uint32_t>& idx,
                           std::vector<float>* dist2) const {
  if (pts_.empty() || !(radius >= 0.0f) || !is_finite(q)) return 0;
  const float r2 = radius * radius;
  std::vector<std::pair<float, std::uint32_t>> found;
  struct Frame {
    std::uint32_t node;
    float mindist;
    float off[3];
  };
  std::vector<Frame> stack;
  stack.push_back({0, 0.0f, {0.0f, 0.0f, 0.0f}});
  while (!stack.empty()) {
    const Frame f = stack.back();
    stack.pop_back();
    const Node& nd = nodes_[f.node];
    if (nd.dim < 0) {
      for (std::uint32_t j = nd.a; j < nd.b; ++j) {
        const float d = (pts_[j] - q).squaredNorm();
        if (d <= r2) found.emplace_back(d, ids_[j]);
      }
      continue;
    }
    const float diff = q[nd.dim] - nd.split;
    const std::uint32_t near = diff < 0.0f ? nd.a : nd.b;
    const std::uint32_t far = diff < 0.0f ? nd.b : nd.a;
    const float d2 = diff * diff;
    const float far_min = f.mindist - f.off[nd.dim] + d2;
    if (far_min <= r2 * kPruneSlack) {
      Frame g = f;
      g.node = far;
      g.mindist = far_min;
      g.off[nd.dim] = d2;
      stack.push_back(g);
    }
    Frame n = f;
    n.node = near;
    stack.push_back(n);
  }
  std::sort(found.begin(), found.end());
  for (const auto& [d, i] : found) {
    idx.push_back(i);
    if (dist2) dist2->push_back(d);
  }
  return found.size();
}

}  // namespace duet
