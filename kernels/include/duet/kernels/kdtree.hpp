#pragma once
/// @file kdtree.hpp
/// Exact nearest-neighbour search over a static 3D point set: a bucket kd-tree whose points
/// are copied into tree order (cache locality), built in parallel with TBB.
/// Non-finite points are not indexed and are never returned.
///
/// Thread safety: build() is not thread-safe with concurrent queries. After build(), knn(),
/// knn_leaf() (with one LeafKnn per thread) and radius() are const and may be called from any
/// number of threads at once. Memory: ~56 bytes per point (points twice, ids, boxes, and the
/// build's scratch, kept so that rebuilds of the same size allocate nothing).
/// Ties (equal distances) are broken by the smaller point index, so results are unique.
#include <duet/kernels/types.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace duet {

struct KdTreeSettings {
  /// points per leaf bucket, >= 1. 48: the fastest of 16-96 for the k = 10 normals on the raw
  /// Kinect clouds (knn_leaf batches; 32 was best for the earlier per-query search).
  int max_leaf_size = 48;
};

class KdTree {
 public:
  KdTree() = default;
  explicit KdTree(PointsView points, const KdTreeSettings& settings = {}) { build(points, settings); }

  /// (Re)builds over `points` (copied). Throws duet::Error(kInvalidArgument) for more than
  /// 2^31-1 points or bad settings.
  void build(PointsView points, const KdTreeSettings& settings = {});

  [[nodiscard]] std::size_t size() const noexcept { return n_input_; }
  [[nodiscard]] std::size_t indexed_size() const noexcept { return pts_.size(); }

  /// The k nearest indexed points to q, nearest first. Writes min(k, indexed_size())
  /// entries to idx / dist2 (squared distances [m^2]) and returns that count.
  /// idx and dist2 must hold at least k entries.
  int knn(const Eigen::Vector3f& q, int k, std::uint32_t* idx, float* dist2) const;

  /// All indexed points within `radius` (dist <= radius) of q, sorted by distance, appended to
  /// idx (and dist2, if given). Returns the number appended.
  std::size_t radius(const Eigen::Vector3f& q, float radius, std::vector<std::uint32_t>& idx,
                     std::vector<float>* dist2 = nullptr) const;

  /// Tree order, for cache-friendly batch queries: tree_points()[j] is the indexed point at
  /// tree position j and order()[j] its input index.
  [[nodiscard]] std::span<const std::uint32_t> order() const noexcept { return ids_; }
  [[nodiscard]] std::span<const Eigen::Vector3f> tree_points() const noexcept { return pts_; }

  /// As knn(), but returns tree positions (indices into tree_points()) instead of input indices.
  int knn_tree(const Eigen::Vector3f& q, int k, std::uint32_t* tree_pos, float* dist2) const;

  /// As knn_tree(), but only points with squared distance <= max_dist2 [m^2] are considered
  /// (fewer than k are returned when fewer lie that close). A bound known to hold k points -
  /// e.g. the farthest of the previous query's neighbours, for queries in tree order - gives
  /// the same result as the unbounded search, with less work.
  int knn_tree(const Eigen::Vector3f& q, int k, float max_dist2, std::uint32_t* tree_pos, float* dist2) const;

  /// As knn_tree() with a bound, for a query near the indexed point at tree position hint_pos
  /// (e.g. the query is that point, as for normals): the search starts in the hint's part of the
  /// tree instead of at the root, and goes on to the rest only if the result could lie beyond
  /// it. The same result as knn_tree(); a hint far from q only costs time.
  int knn_tree_near(const Eigen::Vector3f& q, int k, float max_dist2, std::uint32_t hint_pos,
                    std::uint32_t* tree_pos, float* dist2) const;

  /// Leaf buckets, in tree order: leaf l holds the tree positions [leaf_begin(l), leaf_end(l));
  /// consecutive leaves are consecutive ranges covering [0, indexed_size()).
  [[nodiscard]] std::size_t leaf_count() const noexcept { return leaf_node_.size(); }
  [[nodiscard]] std::uint32_t leaf_begin(std::size_t l) const noexcept { return boxes_[leaf_node_[l]].begin; }
  [[nodiscard]] std::uint32_t leaf_end(std::size_t l) const noexcept { return boxes_[leaf_node_[l]].end; }

  /// Results and scratch memory of knn_leaf(); one per thread, reused between calls.
  struct LeafKnn {
    /// Query i (tree position leaf_begin(l) + i): count[i] neighbours, nearest first, as tree
    /// positions pos[i*k + r] and squared distances dist2[i*k + r] [m^2], r < count[i].
    std::vector<std::uint32_t> pos;
    std::vector<float> dist2;
    std::vector<int> count;
    // scratch
    std::vector<std::uint64_t> keys;
    std::vector<std::uint32_t> cand;
    std::vector<std::uint32_t> stack;
    std::vector<float> cbox;
    std::vector<std::uint32_t> order;
    std::vector<std::uint8_t> bucket;
  };

  /// The k nearest indexed points of each point of leaf l (queries = the leaf's own indexed
  /// points), each exactly what knn_tree(tree_points()[j], k, ...) returns (same points, same
  /// order, same ties). A batch over one leaf: the leaf's (or, for fewer than k points, its
  /// smallest ancestor with k) points bound every query's k-th distance, one traversal collects
  /// the leaves that can hold a nearer point for any query of the leaf, and each query then
  /// scans only those whose bounding box is within its own current k-th distance.
  /// With sorted = false each query's neighbours come in an unspecified (but fixed: the same
  /// for any thread count) order instead - the same set, cheaper when the order is not needed.
  /// Returns the number of queries (leaf_end(l) - leaf_begin(l)). Thread-safe (const) with
  /// one LeafKnn per thread.
  std::uint32_t knn_leaf(std::size_t l, int k, LeafKnn& ws, bool sorted = true) const;

 private:
  struct Node {
    // Leaf: begin/end into pts_. Inner: split dimension and value, children indices.
    float split = 0.0f;
    std::int32_t dim = -1;  // -1 = leaf, kUniformLeaf = a leaf of identical points
    std::uint32_t a = 0;    // leaf: begin, inner: left child
    std::uint32_t b = 0;    // leaf: end,   inner: right child
  };
  struct Item {
    Eigen::Vector3f p;
    std::uint32_t id;
  };
  std::vector<Item> items_;  // build scratch (the points being partitioned), kept between builds
  struct LeafStart {
    std::uint32_t node;        // ancestor of the leaf where hinted searches start
    Eigen::Vector3f lo, hi;    // its cell
  };
  static constexpr std::uint32_t kNoHint = 0xFFFFFFFFu;
  // A leaf of more than max_leaf_size identical points (no split can separate them), sorted by
  // input index: their distances to any query are equal, so their k smallest keys (distance,
  // index) are the first k - a scan stops there, and knn stays O(k) per such leaf instead of
  // O(leaf) (48k duplicate points took 9 s of normals before; issue 19).
  static constexpr std::int32_t kUniformLeaf = -2;
  // End of the positions of leaf nd a k-nearest scan must offer.
  static std::uint32_t scan_end(const Node& nd, int k) noexcept {
    return nd.dim == kUniformLeaf && nd.b - nd.a > static_cast<std::uint32_t>(k) ? nd.a + static_cast<std::uint32_t>(k) : nd.b;
  }
  int knn_impl(const Eigen::Vector3f& q, int k, float max_dist2, std::uint32_t hint, std::uint32_t* tree_pos,
               float* dist2) const;
  void index_leaf_starts(std::uint32_t m);
  // Tight bounding box of each node's points (the min/max of their coordinates, not the cell its
  // splits bound) and the node's range of tree positions.
  struct Box {
    Eigen::Vector3f lo;
    std::uint32_t begin;
    Eigen::Vector3f hi;
    std::uint32_t end;
  };
  std::vector<Box> boxes_;                 // by node
  std::vector<std::uint32_t> parent_;      // by node (root: kNoHint)
  std::vector<std::uint32_t> leaf_node_;   // leaves in tree order -> node
  std::vector<LeafStart> leaf_start_;
  std::vector<std::uint32_t> leaf_of_;  // tree position -> leaf (index into leaf_start_)

  std::vector<Eigen::Vector3f> pts_;  // tree order
  static constexpr std::size_t kPad = 8;
  std::vector<float> xs_, ys_, zs_;   // the same, as structure of arrays (vectorised leaf scans), + kPad
  std::vector<std::uint32_t> ids_;    // tree order -> input index
  std::vector<Node> nodes_;
  std::size_t n_input_ = 0;
  int leaf_size_ = 12;
  std::uint32_t node_count_ = 0;
};

}  // namespace duet
