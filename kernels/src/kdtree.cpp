#include <duet/kernels/error.hpp>
#include <duet/kernels/kdtree.hpp>

#include "parallel.hpp"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <atomic>
#include <limits>
#include <string>

namespace duet {

struct KdTree::Item {
  Eigen::Vector3f p;
  std::uint32_t id;
};

namespace {

// Sorted (by distance, then input index) fixed-capacity list of the best k candidates.
struct KBest {
  int k, count = 0;
  float* d;
  std::uint32_t* pos;
  const std::uint32_t* ids;
  [[nodiscard]] float worst() const noexcept {
    return count < k ? std::numeric_limits<float>::infinity() : d[k - 1];
  }
  void offer(float dist, std::uint32_t p) noexcept {
    if (count == k) {
      if (dist > d[k - 1] || (dist == d[k - 1] && ids[p] >= ids[pos[k - 1]])) return;
    } else {
      ++count;
    }
    int j = count - 1;
    while (j > 0 && (d[j - 1] > dist || (d[j - 1] == dist && ids[pos[j - 1]] > ids[p]))) {
      d[j] = d[j - 1];
      pos[j] = pos[j - 1];
      --j;
    }
    d[j] = dist;
    pos[j] = p;
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
  // Median splits give leaves of at least ceil(leaf/2) points (unless the input is smaller):
  // at most 2m/ceil(leaf/2) + 1 nodes.
  const std::size_t half = static_cast<std::size_t>((leaf_size_ + 1) / 2);
  nodes_.resize(2 * (static_cast<std::size_t>(m) / half) + 3);
  std::atomic<std::uint32_t> next{0};

  // Recursive build; node numbers come from an atomic counter (their order may vary between
  // runs, the tree's geometry and point order do not).
  struct Builder {
    KdTree& t;
    Item* items;
    std::atomic<std::uint32_t>& next;
    std::uint32_t operator()(std::uint32_t begin, std::uint32_t end) const {
      const std::uint32_t idx = next.fetch_add(1, std::memory_order_relaxed);
      Node& node = t.nodes_[idx];
      const std::uint32_t count = end - begin;
      if (count > static_cast<std::uint32_t>(t.leaf_size_)) {
        Eigen::Vector3f lo = items[begin].p, hi = lo;
        for (std::uint32_t i = begin + 1; i < end; ++i) {
          lo = lo.cwiseMin(items[i].p);
          hi = hi.cwiseMax(items[i].p);
        }
        int dim;
        const float extent = (hi - lo).maxCoeff(&dim);
        if (extent > 0.0f) {
          const std::uint32_t mid = begin + count / 2;
          std::nth_element(items + begin, items + mid, items + end, [dim](const Item& a, const Item& b) {
            return a.p[dim] < b.p[dim] || (a.p[dim] == b.p[dim] && a.id < b.id);
          });
          node.split = items[mid].p[dim];  // before the children reorder items[mid]
          std::uint32_t l = 0, r = 0;
          if (count > 16384) {
            tbb::parallel_invoke([&] { l = (*this)(begin, mid); }, [&] { r = (*this)(mid, end); });
          } else {
            l = (*this)(begin, mid);
            r = (*this)(mid, end);
          }
          node.dim = dim;
          node.a = l;
          node.b = r;
          return idx;
        }
      }
      node.dim = -1;
      node.a = begin;
      node.b = end;
      return idx;
    }
  };
  if (m > 0) Builder{*this, items.data(), next}(0, m);
  nodes_.resize(next.load());
  node_count_ = next.load();
  pts_.resize(m);
  ids_.resize(m);
  xs_.resize(m);
  ys_.resize(m);
  zs_.resize(m);
  for (std::uint32_t i = 0; i < m; ++i) {
    pts_[i] = items[i].p;
    ids_[i] = items[i].id;
    xs_[i] = items[i].p.x();
    ys_[i] = items[i].p.y();
    zs_[i] = items[i].p.z();
  }
}

int KdTree::knn_tree(const Eigen::Vector3f& q, int k, std::uint32_t* tree_pos, float* dist2) const {
  if (k <= 0 || pts_.empty() || !is_finite(q)) return 0;
  KBest best{k, 0, dist2, tree_pos, ids_.data()};
  // Depth-first search, nearer child first; off[] holds the squared distance components from q
  // to the current cell, so mindist is the exact squared distance from q to that cell.
  struct Frame {
    std::uint32_t node;
    float mindist;
    float off[3];
  };
  Frame stack[128];
  int top = 0;
  stack[top++] = {0, 0.0f, {0.0f, 0.0f, 0.0f}};
  while (top > 0) {
    const Frame f = stack[--top];
    if (f.mindist > best.worst()) continue;
    std::uint32_t ni = f.node;
    float mindist = f.mindist;
    float off[3] = {f.off[0], f.off[1], f.off[2]};
    while (true) {
      const Node& nd = nodes_[ni];
      if (nd.dim < 0) {
        // Distances of a whole leaf in one vectorisable loop, then the few candidates offered.
        constexpr std::uint32_t kChunk = 32;
        float d[kChunk];
        for (std::uint32_t j0 = nd.a; j0 < nd.b; j0 += kChunk) {
          const std::uint32_t m = std::min(kChunk, nd.b - j0);
          const float* xs = xs_.data() + j0;
          const float* ys = ys_.data() + j0;
          const float* zs = zs_.data() + j0;
          for (std::uint32_t t = 0; t < m; ++t) {
            const float dx = xs[t] - q.x(), dy = ys[t] - q.y(), dz = zs[t] - q.z();
            d[t] = dx * dx + (dy * dy + dz * dz);  // the order of Eigen's squaredNorm: identical values
          }
          for (std::uint32_t t = 0; t < m; ++t)
            if (d[t] <= best.worst()) best.offer(d[t], j0 + t);
        }
        break;
      }
      const float diff = q[nd.dim] - nd.split;
      const std::uint32_t near = diff < 0.0f ? nd.a : nd.b;
      const std::uint32_t far = diff < 0.0f ? nd.b : nd.a;
      const float d2 = diff * diff;
      const float far_min = mindist - off[nd.dim] + d2;
      if (far_min <= best.worst() && top < 128) {
        Frame g{far, far_min, {off[0], off[1], off[2]}};
        g.off[nd.dim] = d2;
        stack[top++] = g;
      }
      ni = near;
    }
  }
  return best.count;
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
    if (far_min <= r2) {
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
