/// @file kdtree.cpp
/// KdTree queries: knn (from the root or near a hint), knn_leaf batches and radius search.
#include <duet/kernels/kdtree.hpp>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace duet {


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
  // Resumes a list of `count_` candidates already in key_/pos_ (no limit).
  KBest(int k_, int count_, std::uint64_t* key_, std::uint32_t* pos_, const std::uint32_t* ids_)
      : k(k_), count(count_), worst_d(std::numeric_limits<float>::infinity()), key(key_), pos(pos_), ids(ids_) {
    if (count == k) worst_d = std::bit_cast<float>(static_cast<std::uint32_t>(key[k - 1] >> 32));
  }
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
  // Drops the candidates farther than bound (known to hold k points: they cannot be among the
  // k nearest); the list then prunes at bound until it is full again.
  void trim(float bound) noexcept {
    const int before = count;
    while (count > 0 && std::bit_cast<float>(static_cast<std::uint32_t>(key[count - 1] >> 32)) > bound) --count;
    if (count < before) worst_d = bound;
  }
  int finish(float* dist2) const noexcept {
    for (int i = 0; i < count; ++i) dist2[i] = std::bit_cast<float>(static_cast<std::uint32_t>(key[i] >> 32));
    return count;
  }
};

// The best k candidates, unsorted, with the slot of the worst tracked: a candidate replaces the
// worst and the worst is found again (k compares, no shifting); sorted once in finish(). The
// same keys as KBest (distance bits above the input index), so the same set and order.
struct KSet {
  int k, count = 0;
  int worst_i = 0;  // slot of the largest key when count == k
  float worst_d;    // pruning distance: the k-th distance, or the limit while fewer than k
  std::uint64_t* key;
  std::uint32_t* pos;
  const std::uint32_t* ids;
  KSet(int k_, float limit, std::uint64_t* key_, std::uint32_t* pos_, const std::uint32_t* ids_)
      : k(k_), worst_d(limit), key(key_), pos(pos_), ids(ids_) {}
  // Resumes `count_` candidates already in key_/pos_ (no limit).
  KSet(int k_, int count_, std::uint64_t* key_, std::uint32_t* pos_, const std::uint32_t* ids_)
      : k(k_), count(count_), worst_d(std::numeric_limits<float>::infinity()), key(key_), pos(pos_), ids(ids_) {
    if (count == k) refresh();
  }
  [[nodiscard]] float worst() const noexcept { return worst_d; }
  void refresh() noexcept {
    std::uint64_t mk = key[0];
    int w = 0;
    for (int i = 1; i < k; ++i) {
      const bool gt = key[i] > mk;
      mk = gt ? key[i] : mk;
      w = gt ? i : w;
    }
    worst_i = w;
    worst_d = std::bit_cast<float>(static_cast<std::uint32_t>(mk >> 32));
  }
  void offer(float dist, std::uint32_t p) noexcept {
    const std::uint64_t kk = static_cast<std::uint64_t>(std::bit_cast<std::uint32_t>(dist)) << 32 | ids[p];
    if (count < k) {
      key[count] = kk;
      pos[count] = p;
      if (++count == k) refresh();
      return;
    }
    if (kk >= key[worst_i]) return;
    key[worst_i] = kk;
    pos[worst_i] = p;
    refresh();
  }
  // Drops the candidates farther than bound (known to hold k points: they cannot be among the
  // k nearest); the set then prunes at bound until it is full again.
  void trim(float bound) noexcept {
    int c = 0;
    for (int i = 0; i < count; ++i) {
      if (std::bit_cast<float>(static_cast<std::uint32_t>(key[i] >> 32)) <= bound) {
        key[c] = key[i];
        pos[c] = pos[i];
        ++c;
      }
    }
    if (c < count) {
      count = c;
      worst_d = bound;
    }
  }
  // Sorts the candidates nearest first (by key) if `sorted`, and writes their squared distances.
  int finish(float* dist2, bool sorted) noexcept {
    for (int i = 1; sorted && i < count; ++i) {
      const std::uint64_t kk = key[i];
      const std::uint32_t pp = pos[i];
      int j = i;
      while (j > 0 && key[j - 1] > kk) {
        key[j] = key[j - 1];
        pos[j] = pos[j - 1];
        --j;
      }
      key[j] = kk;
      pos[j] = pp;
    }
    for (int i = 0; i < count; ++i) dist2[i] = std::bit_cast<float>(static_cast<std::uint32_t>(key[i] >> 32));
    return count;
  }
};

// Offers the points at tree positions [a, b) to best. Eight distances at a time, then the few
// candidates within the current k-th distance offered (one mostly-not-taken branch per eight
// points). The SoA arrays are padded by KdTree::kPad entries, so the loads past b stay inside
// them; those lanes are masked. Distances are dx^2 + (dy^2 + dz^2), the order of Eigen's
// squaredNorm: identical values to (p - q).squaredNorm().
template <class Best>
inline void scan_points(const float* xs, const float* ys, const float* zs, std::uint32_t a, std::uint32_t b,
                        const Eigen::Vector3f& q, Best& best) {
#if defined(__SSE2__)
  const __m128 qx = _mm_set1_ps(q.x()), qy = _mm_set1_ps(q.y()), qz = _mm_set1_ps(q.z());
  for (std::uint32_t j0 = a; j0 < b; j0 += 8) {
    alignas(16) float d[8];
    for (int h = 0; h < 2; ++h) {
      const __m128 dx = _mm_sub_ps(_mm_loadu_ps(xs + j0 + 4 * h), qx);
      const __m128 dy = _mm_sub_ps(_mm_loadu_ps(ys + j0 + 4 * h), qy);
      const __m128 dz = _mm_sub_ps(_mm_loadu_ps(zs + j0 + 4 * h), qz);
      _mm_store_ps(d + 4 * h, _mm_add_ps(_mm_mul_ps(dx, dx), _mm_add_ps(_mm_mul_ps(dy, dy), _mm_mul_ps(dz, dz))));
    }
    const __m128 w = _mm_set1_ps(best.worst());
    unsigned mask = static_cast<unsigned>(_mm_movemask_ps(_mm_cmple_ps(_mm_load_ps(d), w))) |
                    static_cast<unsigned>(_mm_movemask_ps(_mm_cmple_ps(_mm_load_ps(d + 4), w))) << 4;
    if (b - j0 < 8) mask &= (1u << (b - j0)) - 1u;
    while (mask != 0) {
      const std::uint32_t t = static_cast<std::uint32_t>(std::countr_zero(mask));
      mask &= mask - 1;
      if (d[t] <= best.worst()) best.offer(d[t], j0 + t);
    }
  }
#else
  for (std::uint32_t j = a; j < b; ++j) {
    const float dx = xs[j] - q.x(), dy = ys[j] - q.y(), dz = zs[j] - q.z();
    const float d = dx * dx + (dy * dy + dz * dz);
    if (d <= best.worst()) best.offer(d, j);
  }
#endif
}

// Squared distance from q to the box [lo, hi] (0 inside), summed in the order of scan_points:
// as rounding is monotone, it is never above the computed distance of a point in the box.
inline float box_dist2(const Eigen::Vector3f& q, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  const float ox = std::max({lo.x() - q.x(), q.x() - hi.x(), 0.0f});
  const float oy = std::max({lo.y() - q.y(), q.y() - hi.y(), 0.0f});
  const float oz = std::max({lo.z() - q.z(), q.z() - hi.z(), 0.0f});
  return ox * ox + (oy * oy + oz * oz);
}

// Squared distance between the boxes [alo, ahi] and [blo, bhi]: never above the computed
// distance of a point in one to a point in the other (as box_dist2).
inline float box_box_dist2(const Eigen::Vector3f& alo, const Eigen::Vector3f& ahi, const Eigen::Vector3f& blo,
                           const Eigen::Vector3f& bhi) {
  const float ox = std::max({blo.x() - ahi.x(), alo.x() - bhi.x(), 0.0f});
  const float oy = std::max({blo.y() - ahi.y(), alo.y() - bhi.y(), 0.0f});
  const float oz = std::max({blo.z() - ahi.z(), alo.z() - bhi.z(), 0.0f});
  return ox * ox + (oy * oy + oz * oz);
}

// Squared distances from q to n4 (a multiple of 4) boxes stored as structure of arrays
// (lo x, y, z then hi x, y, z, n4 floats each) into out; the same values as box_dist2.
inline void box_dists(const float* soa, std::size_t n4, const Eigen::Vector3f& q, float* out) {
#if defined(__SSE2__)
  const __m128 zero = _mm_setzero_ps();
  __m128 qv[3] = {_mm_set1_ps(q.x()), _mm_set1_ps(q.y()), _mm_set1_ps(q.z())};
  for (std::size_t c = 0; c < n4; c += 4) {
    __m128 o2[3];
    for (int d = 0; d < 3; ++d) {
      const __m128 lo = _mm_loadu_ps(soa + static_cast<std::size_t>(d) * n4 + c);
      const __m128 hi = _mm_loadu_ps(soa + static_cast<std::size_t>(d + 3) * n4 + c);
      // max(lo - q, q - hi, 0), as std::max({...}) in box_dist2 (all operands finite or +-inf)
      const __m128 o = _mm_max_ps(_mm_max_ps(_mm_sub_ps(lo, qv[d]), _mm_sub_ps(qv[d], hi)), zero);
      o2[d] = _mm_mul_ps(o, o);
    }
    _mm_storeu_ps(out + c, _mm_add_ps(o2[0], _mm_add_ps(o2[1], o2[2])));
  }
#else
  for (std::size_t c = 0; c < n4; ++c) {
    const Eigen::Vector3f lo(soa[c], soa[n4 + c], soa[2 * n4 + c]), hi(soa[3 * n4 + c], soa[4 * n4 + c], soa[5 * n4 + c]);
    out[c] = box_dist2(q, lo, hi);
  }
#endif
}

}  // namespace

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
          scan_points(xs_.data(), ys_.data(), zs_.data(), nd.a, scan_end(nd, k), q, best);
          break;
        }
        const float diff = q[nd.dim] - nd.split;
        const std::uint32_t near = diff < 0.0f ? nd.a : nd.b;
        const std::uint32_t far = diff < 0.0f ? nd.b : nd.a;
        const float d2 = diff * diff;
        const float far_min = mindist - off[nd.dim] + d2;
        // "not beyond" rather than "within": a NaN (inf - inf, when squared distances overflow)
        // visits the cell instead of losing it.
        if (!(far_min > best.worst() * kPruneSlack) && top < 128) {
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

std::uint32_t KdTree::knn_leaf(std::size_t l, int k, LeafKnn& ws, bool sorted) const {
  const Box& lb = boxes_[leaf_node_[l]];
  const std::uint32_t begin = lb.begin, m = lb.end - lb.begin;
  ws.count.assign(m, 0);
  if (k <= 0) return m;
  const std::size_t ku = static_cast<std::size_t>(k);
  if (ws.keys.size() < m * ku) {
    ws.keys.resize(m * ku);
    ws.pos.resize(m * ku);
    ws.dist2.resize(m * ku);
  }
  const std::uint32_t* ids = ids_.data();
  const float *xs = xs_.data(), *ys = ys_.data(), *zs = zs_.data();
  // Home: the leaf, or its smallest ancestor with at least k points.
  std::uint32_t home = leaf_node_[l];
  while (boxes_[home].end - boxes_[home].begin < static_cast<std::uint32_t>(k) && parent_[home] != kNoHint)
    home = parent_[home];
  const Box& hb = boxes_[home];
  const std::uint32_t want = std::min(static_cast<std::uint32_t>(k), hb.end - hb.begin);
  // Phase 1: each query's k nearest among the home's points. The previous query's k neighbours
  // (home points too) bound its k-th distance, so the scan offers fewer candidates; the margin
  // covers a different rounding of the same distance. r2: the largest k-th distance.
  constexpr float kInf = std::numeric_limits<float>::infinity();
  // Query order: a serpentine over a 6 x 3 grid of the leaf box's two longest axes (a counting
  // sort), so consecutive queries are near each other and the previous one's neighbours bound
  // the next one's k-th distance tightly. Any order gives the same results.
  {
    int dims[3] = {0, 1, 2};
    const Eigen::Vector3f ext = lb.hi - lb.lo;
    std::sort(dims, dims + 3, [&](int a, int b) { return ext[a] > ext[b] || (ext[a] == ext[b] && a < b); });
    constexpr int kN1 = 6, kN2 = 3;
    const int d1 = dims[0], d2 = dims[1];
    const float s1 = ext[d1] > 0.0f ? kN1 / ext[d1] : 0.0f, s2 = ext[d2] > 0.0f ? kN2 / ext[d2] : 0.0f;
    std::uint32_t start[kN1 * kN2 + 1] = {};
    ws.bucket.resize(m);
    for (std::uint32_t i = 0; i < m; ++i) {
      const Eigen::Vector3f& p = pts_[begin + i];
      // t > 0 is false for NaN (inf * 0 when the box extent overflows): bucket 0, no UB cast.
      const float t1 = (p[d1] - lb.lo[d1]) * s1, t2 = (p[d2] - lb.lo[d2]) * s2;
      const int b1 = t1 > 0.0f ? static_cast<int>(std::min(t1, static_cast<float>(kN1 - 1))) : 0;
      int b2 = t2 > 0.0f ? static_cast<int>(std::min(t2, static_cast<float>(kN2 - 1))) : 0;
      if (b1 & 1) b2 = kN2 - 1 - b2;
      ws.bucket[i] = static_cast<std::uint8_t>(b1 * kN2 + b2);
      ++start[ws.bucket[i] + 1];
    }
    for (int b = 0; b < kN1 * kN2; ++b) start[b + 1] += start[b];
    ws.order.resize(m);
    for (std::uint32_t i = 0; i < m; ++i) ws.order[start[ws.bucket[i]]++] = i;
  }
  // The home's points, leaf by leaf (a uniform leaf offers only its first k).
  const auto scan_home = [&](const Eigen::Vector3f& q, KSet& best) {
    for (std::uint32_t p = hb.begin; p < hb.end;) {
      const Node& nd = nodes_[leaf_node_[leaf_of_[p]]];
      scan_points(xs, ys, zs, p, scan_end(nd, k), q, best);
      p = nd.b;
    }
  };
  float r2 = 0.0f;
  for (std::uint32_t oi = 0; oi < m; ++oi) {
    const std::uint32_t i = ws.order[oi];
    const Eigen::Vector3f& q = pts_[begin + i];
    std::uint64_t* key = ws.keys.data() + i * ku;
    std::uint32_t* pos = ws.pos.data() + i * ku;
    float bound = kInf;
    if (oi > 0 && ws.count[ws.order[oi - 1]] == k) {
      const std::uint32_t* prev = ws.pos.data() + ws.order[oi - 1] * ku;
      float far = 0.0f;
      for (int r = 0; r < k; ++r) far = std::max(far, (pts_[prev[r]] - q).squaredNorm());
      bound = far * 1.0001f + std::numeric_limits<float>::min();
    }
    KSet best(k, bound, key, pos, ids);
    scan_home(q, best);
    if (static_cast<std::uint32_t>(best.count) < want) {  // cannot happen (the bound holds k points); be safe
      best = KSet(k, kInf, key, pos, ids);
      scan_home(q, best);
    }
    ws.count[i] = best.count;
    r2 = std::max(r2, best.worst());
  }
  // Phase 2: the leaves outside home whose box is within r2 of this leaf's box may hold a nearer
  // point for some query (a point's distance is at least its box's distance); each query scans
  // those within its own k-th distance.
  ws.cand.clear();
  ws.stack.clear();
  if (home != 0) ws.stack.push_back(0);
  const float limit = r2 * kPruneSlack;
  while (!ws.stack.empty()) {
    const std::uint32_t n = ws.stack.back();
    ws.stack.pop_back();
    if (n == home) continue;
    const Box& b = boxes_[n];
    if (box_box_dist2(lb.lo, lb.hi, b.lo, b.hi) > limit) continue;
    const Node& nd = nodes_[n];
    if (nd.dim < 0) {
      ws.cand.push_back(n);
    } else {
      ws.stack.push_back(nd.b);
      ws.stack.push_back(nd.a);
    }
  }
  // The candidates' boxes as structure of arrays, padded to a multiple of 4 with empty boxes
  // (lo = +inf, hi = -inf: infinitely far): four box distances at a time.
  const std::size_t nc = ws.cand.size(), nc4 = (nc + 3) & ~std::size_t{3};
  ws.cbox.resize(7 * nc4 + 4);
  float* cb = ws.cbox.data();
  for (std::size_t c = 0; c < nc4; ++c) {
    for (int d = 0; d < 3; ++d) {
      cb[static_cast<std::size_t>(d) * nc4 + c] = c < nc ? boxes_[ws.cand[c]].lo[d] : kInf;
      cb[static_cast<std::size_t>(d + 3) * nc4 + c] = c < nc ? boxes_[ws.cand[c]].hi[d] : -kInf;
    }
  }
  float* cd = cb + 6 * nc4;
  bool prev_full = false;
  for (std::uint32_t oi = 0; oi < m; ++oi) {
    const std::uint32_t i = ws.order[oi];
    const Eigen::Vector3f& q = pts_[begin + i];
    std::uint64_t* key = ws.keys.data() + i * ku;
    std::uint32_t* pos = ws.pos.data() + i * ku;
    KSet best(k, ws.count[i], key, pos, ids);
    // The previous query's final k neighbours bound this one's k-th distance (as in phase 1).
    if (prev_full && best.count == k) {
      const std::uint32_t* prev = ws.pos.data() + ws.order[oi - 1] * ku;
      float far = 0.0f;
      for (int r = 0; r < k; ++r) far = std::max(far, (pts_[prev[r]] - q).squaredNorm());
      best.trim(far * 1.0001f + std::numeric_limits<float>::min());
    }
    box_dists(cb, nc4, q, cd);
    for (std::size_t c = 0; c < nc; ++c) {
      if (cd[c] > best.worst() * kPruneSlack) continue;
      scan_points(xs, ys, zs, boxes_[ws.cand[c]].begin, scan_end(nodes_[ws.cand[c]], k), q, best);
    }
    ws.count[i] = best.finish(ws.dist2.data() + i * ku, sorted);
    prev_full = ws.count[i] == k;
  }
  return m;
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
    if (!(far_min > r2 * kPruneSlack)) {  // NaN (overflowing squares): visit
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
