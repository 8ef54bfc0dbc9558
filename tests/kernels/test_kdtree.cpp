// KdTree knn / radius vs brute force (duplicates, exact ties broken by the smaller index), k larger
// than the cloud, empty tree, NaN points never returned, tree order, thread-count independence.
#include "kernel_test_util.hpp"

#include <duet/kernels/error.hpp>
#include <duet/kernels/kdtree.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <random>
#include <vector>

namespace duet {
namespace test_kdtree {

using test::kInf;
using test::kNaN;

// ---- reference -----------------------------------------------------------------------------------

struct Hit {
  float d2;
  std::uint32_t i;
  bool operator<(const Hit& o) const { return d2 != o.d2 ? d2 < o.d2 : i < o.i; }
};

std::vector<Hit> brute_all(const std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3f& q) {
  std::vector<Hit> h;
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (is_finite(pts[i])) h.push_back({(pts[i] - q).squaredNorm(), static_cast<std::uint32_t>(i)});
  std::sort(h.begin(), h.end());
  return h;
}

std::vector<Hit> brute_knn(const std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3f& q, int k) {
  auto h = brute_all(pts, q);
  if (h.size() > static_cast<std::size_t>(k)) h.resize(static_cast<std::size_t>(k));
  return h;
}

std::vector<Hit> brute_radius(const std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3f& q, float r) {
  auto h = brute_all(pts, q);
  const float r2 = r * r;
  h.erase(std::remove_if(h.begin(), h.end(), [&](const Hit& x) { return !(x.d2 <= r2); }), h.end());
  return h;
}

// Points on a 1/8 m lattice (squared distances are exact in float, so ties are real ties), with
// many duplicates, plus some NaN/inf points.
std::vector<Eigen::Vector3f> lattice_cloud(std::size_t n, std::uint32_t seed, int extent = 16) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> c(-extent, extent);
  std::uniform_int_distribution<int> pick(0, 19);
  std::vector<Eigen::Vector3f> p(n);
  for (std::size_t i = 0; i < n; ++i) {
    p[i] = Eigen::Vector3f(static_cast<float>(c(rng)), static_cast<float>(c(rng)), static_cast<float>(c(rng))) / 8.0f;
    const int k = pick(rng);
    if (k == 0 && i > 0) p[i] = p[i / 2];  // duplicate of an earlier point
    if (k == 1) p[i].z() = kNaN;
    if (k == 2) p[i].x() = kInf;
  }
  return p;
}

// `all` = brute_all(pts, q), computed once per query for several k.
void check_knn(const KdTree& tree, const std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3f& q, int k,
               const std::vector<Hit>* all = nullptr) {
  std::vector<Hit> want;
  if (all) {
    want.assign(all->begin(), all->begin() + static_cast<std::ptrdiff_t>(std::min(all->size(), static_cast<std::size_t>(std::max(k, 0)))));
  } else {
    want = brute_knn(pts, q, k);
  }
  std::vector<std::uint32_t> idx(static_cast<std::size_t>(std::max(k, 1)), 0xDEADBEEF);
  std::vector<float> d2(static_cast<std::size_t>(std::max(k, 1)), -1.0f);
  const int c = tree.knn(q, k, idx.data(), d2.data());
  ASSERT_EQ(c, static_cast<int>(want.size())) << "k " << k << " query " << q.transpose();
  for (int j = 0; j < c; ++j) {
    ASSERT_EQ(idx[j], want[j].i) << "rank " << j << " of k " << k << " query " << q.transpose() << " (d2 " << d2[j]
                                 << " vs " << want[j].d2 << ")";
    ASSERT_EQ(d2[j], want[j].d2);
  }
  // knn_tree gives tree positions of the same points.
  std::vector<std::uint32_t> pos(idx.size());
  std::vector<float> d2t(idx.size());
  ASSERT_EQ(tree.knn_tree(q, k, pos.data(), d2t.data()), c);
  for (int j = 0; j < c; ++j) {
    ASSERT_LT(pos[j], tree.indexed_size());
    EXPECT_EQ(tree.order()[pos[j]], idx[j]);
    EXPECT_EQ(tree.tree_points()[pos[j]], pts[idx[j]]);
    EXPECT_EQ(d2t[j], d2[j]);
  }
}

void check_radius(const KdTree& tree, const std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3f& q, float r) {
  const auto want = brute_radius(pts, q, r);
  std::vector<std::uint32_t> idx{42u};  // appended to
  std::vector<float> d2{-1.0f};
  const std::size_t c = tree.radius(q, r, idx, &d2);
  ASSERT_EQ(c, want.size()) << "radius " << r << " query " << q.transpose();
  ASSERT_EQ(idx.size(), want.size() + 1);
  ASSERT_EQ(d2.size(), want.size() + 1);
  EXPECT_EQ(idx[0], 42u);
  for (std::size_t j = 0; j < c; ++j) {
    ASSERT_EQ(idx[j + 1], want[j].i) << "rank " << j << " radius " << r;
    ASSERT_EQ(d2[j + 1], want[j].d2);
  }
  std::vector<std::uint32_t> only;
  EXPECT_EQ(tree.radius(q, r, only), c);  // without distances
  EXPECT_TRUE(std::equal(only.begin(), only.end(), idx.begin() + 1));
}

// ---- tests -----------------------------------------------------------------------------------------

TEST(KdTree, KnnMatchesBruteForceOnLatticeWithTiesAndDuplicates) {
  for (const int leaf : {1, 3, 12, 64}) {
    const auto pts = lattice_cloud(3000, 100 + static_cast<std::uint32_t>(leaf));
    KdTreeSettings s;
    s.max_leaf_size = leaf;
    const KdTree tree(pts, s);
    EXPECT_EQ(tree.size(), pts.size());
    EXPECT_EQ(tree.indexed_size(), test::finite_only(pts).size());
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> c(-20, 20);
    for (int qi = 0; qi < 150; ++qi) {
      // Queries on the lattice (exact ties), at data points and at half-lattice offsets.
      Eigen::Vector3f q = Eigen::Vector3f(static_cast<float>(c(rng)), static_cast<float>(c(rng)), static_cast<float>(c(rng))) / 8.0f;
      if (qi % 3 == 1) q = pts[static_cast<std::size_t>(qi) * 7 % pts.size()];
      if (qi % 3 == 2) q += Eigen::Vector3f(1, 1, 1) / 16.0f;
      if (!is_finite(q)) continue;
      const auto all = brute_all(pts, q);
      for (const int k : {1, 2, 10, 33}) check_knn(tree, pts, q, k, &all);
    }
  }
}

TEST(KdTree, KnnMatchesBruteForceOnRandomClouds) {
  for (const std::uint32_t seed : {1u, 2u}) {
    auto pts = test::random_points(4000, seed, -2.0f, 2.0f);
    // A dense cluster and a line of identical x (degenerate splits).
    for (std::size_t i = 0; i < 500; ++i) pts[i] = pts[i] * 0.001f + Eigen::Vector3f(0.5f, 0.5f, 0.5f);
    for (std::size_t i = 500; i < 900; ++i) pts[i].x() = 0.25f;
    const KdTree tree(pts);
    const auto queries = test::random_points(150, seed + 10, -2.5f, 2.5f);
    for (std::size_t qi = 0; qi < queries.size(); ++qi) {
      const Eigen::Vector3f q = qi % 4 == 0 ? pts[qi] : queries[qi];
      const auto all = brute_all(pts, q);
      for (const int k : {1, 10, 50}) check_knn(tree, pts, q, k, &all);
    }
  }
}

TEST(KdTree, BoundedKnnIsTheKnnWithinTheBound) {
  // knn_tree(q, k, max_dist2): the k nearest among the points with d2 <= max_dist2; with a bound
  // that holds k points it equals the unbounded search (also on lattice ties at the bound).
  const auto pts = lattice_cloud(3000, 41);
  const KdTree tree(pts);
  std::mt19937 rng(43);
  std::uniform_int_distribution<int> c(-20, 20);
  std::uint32_t pos[40];
  float d2[40];
  for (int qi = 0; qi < 120; ++qi) {
    const Eigen::Vector3f q = Eigen::Vector3f(static_cast<float>(c(rng)), static_cast<float>(c(rng)), static_cast<float>(c(rng))) / 8.0f;
    const auto all = brute_all(pts, q);
    for (const int k : {1, 10, 33}) {
      for (const float bound : {0.0f, all[5].d2, all[static_cast<std::size_t>(k) - 1].d2, all[40].d2, kInf}) {
        std::vector<Hit> want;
        for (const Hit& h : all)
          if (h.d2 <= bound && want.size() < static_cast<std::size_t>(k)) want.push_back(h);
        const int got = tree.knn_tree(q, k, bound, pos, d2);
        ASSERT_EQ(got, static_cast<int>(want.size())) << "k " << k << " bound " << bound;
        for (int j = 0; j < got; ++j) {
          ASSERT_EQ(tree.order()[pos[j]], want[static_cast<std::size_t>(j)].i) << "rank " << j;
          ASSERT_EQ(d2[j], want[static_cast<std::size_t>(j)].d2);
        }
      }
    }
  }
  EXPECT_EQ(tree.knn_tree(Eigen::Vector3f::Zero(), 5, kNaN, pos, d2), 0);
  EXPECT_EQ(tree.knn_tree(Eigen::Vector3f::Zero(), 5, -1.0f, pos, d2), 0);
}

TEST(KdTree, HintedKnnEqualsKnn) {
  // knn_tree_near: the same result as knn_tree for any hint - the query's own position (its
  // ancestor cell usually holds the answer), a far point (the search must go on to the rest of
  // the tree), an invalid position (ignored); on lattice ties and split-plane duplicates too.
  for (const int leaf : {1, 4, 32}) {
    auto pts = lattice_cloud(5000, 60 + static_cast<std::uint32_t>(leaf));
    const auto rnd = test::random_points(3000, 61, -1.0f, 1.0f);
    pts.insert(pts.end(), rnd.begin(), rnd.end());
    KdTreeSettings s;
    s.max_leaf_size = leaf;
    const KdTree tree(pts, s);
    const auto tp = tree.tree_points();
    std::mt19937 rng(62);
    std::uniform_int_distribution<std::uint32_t> pick(0, static_cast<std::uint32_t>(tp.size() - 1));
    std::uint32_t pos_a[33], pos_b[33];
    float d_a[33], d_b[33];
    for (int qi = 0; qi < 400; ++qi) {
      const std::uint32_t j = pick(rng);
      const Eigen::Vector3f q = qi % 2 == 0 ? tp[j] : tp[j] + Eigen::Vector3f(0.01f, -0.02f, 0.005f);
      for (const int k : {1, 10, 33}) {
        const int want = tree.knn_tree(q, k, pos_a, d_a);
        for (const std::uint32_t hint : {j, pick(rng), 0xFFFFFFF0u}) {
          for (const float bound : {kInf, d_a[want - 1]}) {
            ASSERT_EQ(tree.knn_tree_near(q, k, bound, hint, pos_b, d_b), want) << "k " << k << " hint " << hint;
            for (int r = 0; r < want; ++r) {
              ASSERT_EQ(pos_b[r], pos_a[r]) << "rank " << r << " k " << k << " hint " << hint;
              ASSERT_EQ(d_b[r], d_a[r]);
            }
          }
        }
      }
    }
  }
}

TEST(KdTree, RadiusMatchesBruteForce) {
  const auto pts = lattice_cloud(4000, 5);
  const KdTree tree(pts);
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> c(-20, 20);
  for (int qi = 0; qi < 100; ++qi) {
    Eigen::Vector3f q = Eigen::Vector3f(static_cast<float>(c(rng)), static_cast<float>(c(rng)), static_cast<float>(c(rng))) / 8.0f;
    if (qi % 2) q = pts[static_cast<std::size_t>(qi) * 13 % pts.size()];
    if (!is_finite(q)) continue;
    // Radii exactly on lattice distances (boundary points are included: dist <= radius).
    for (const float r : {0.0f, 0.125f, 0.25f, 0.375f, 0.5f, 1.0f}) check_radius(tree, pts, q, r);
  }
  const auto rnd = test::random_points(3000, 6, -1.0f, 1.0f);
  const KdTree t2(rnd);
  for (std::size_t qi = 0; qi < 100; ++qi)
    for (const float r : {0.01f, 0.1f, 0.3f}) check_radius(t2, rnd, rnd[qi * 17], r);
  // Negative / NaN radius: nothing.
  std::vector<std::uint32_t> idx;
  EXPECT_EQ(t2.radius(Eigen::Vector3f::Zero(), -1.0f, idx), 0u);
  EXPECT_EQ(t2.radius(Eigen::Vector3f::Zero(), kNaN, idx), 0u);
  EXPECT_TRUE(idx.empty());
}

TEST(KdTree, KLargerThanCloudAndKZero) {
  const auto pts = test::random_points(7, 3);
  const KdTree tree(pts);
  check_knn(tree, pts, Eigen::Vector3f(0.1f, 0.2f, 0.3f), 7);
  check_knn(tree, pts, Eigen::Vector3f(0.1f, 0.2f, 0.3f), 100);
  std::uint32_t idx[1];
  float d2[1];
  EXPECT_EQ(tree.knn(Eigen::Vector3f::Zero(), 0, idx, d2), 0);
  EXPECT_EQ(tree.knn(Eigen::Vector3f::Zero(), -3, idx, d2), 0);
}

TEST(KdTree, EmptyTreeOnePointAndAllNaN) {
  std::uint32_t idx[4];
  float d2[4];
  std::vector<std::uint32_t> ri;
  const KdTree empty;
  EXPECT_EQ(empty.size(), 0u);
  EXPECT_EQ(empty.knn(Eigen::Vector3f::Zero(), 4, idx, d2), 0);
  EXPECT_EQ(empty.radius(Eigen::Vector3f::Zero(), 100.0f, ri), 0u);
  const KdTree built_empty{PointsView()};
  EXPECT_EQ(built_empty.knn(Eigen::Vector3f::Zero(), 4, idx, d2), 0);

  const std::vector<Eigen::Vector3f> nan(50, Eigen::Vector3f(kNaN, 0, 0));
  const KdTree all_nan(nan);
  EXPECT_EQ(all_nan.size(), 50u);
  EXPECT_EQ(all_nan.indexed_size(), 0u);
  EXPECT_EQ(all_nan.knn(Eigen::Vector3f::Zero(), 4, idx, d2), 0);
  EXPECT_EQ(all_nan.radius(Eigen::Vector3f::Zero(), 1e30f, ri), 0u);

  std::vector<Eigen::Vector3f> one = nan;
  one[17] = Eigen::Vector3f(1, 2, 3);
  const KdTree t1(one);
  ASSERT_EQ(t1.knn(Eigen::Vector3f::Zero(), 4, idx, d2), 1);
  EXPECT_EQ(idx[0], 17u);
  EXPECT_EQ(d2[0], 14.0f);
  EXPECT_EQ(t1.radius(Eigen::Vector3f(1, 2, 3), 0.0f, ri), 1u);
  EXPECT_EQ(ri, std::vector<std::uint32_t>{17u});
}

TEST(KdTree, NaNPointsNeverReturned) {
  auto pts = test::random_points(2000, 12);
  for (std::size_t i = 0; i < pts.size(); i += 3) pts[i] = Eigen::Vector3f(kNaN, kNaN, kNaN);
  for (std::size_t i = 1; i < pts.size(); i += 7) pts[i].y() = -kInf;
  const KdTree tree(pts);
  std::vector<std::uint32_t> idx(2000);
  std::vector<float> d2(2000);
  const int c = tree.knn(Eigen::Vector3f::Zero(), 2000, idx.data(), d2.data());
  EXPECT_EQ(static_cast<std::size_t>(c), tree.indexed_size());
  for (int j = 0; j < c; ++j) {
    EXPECT_TRUE(is_finite(pts[idx[j]]));
    EXPECT_TRUE(std::isfinite(d2[j]));
  }
  std::vector<std::uint32_t> ri;
  tree.radius(Eigen::Vector3f::Zero(), 1e30f, ri);
  EXPECT_EQ(ri.size(), tree.indexed_size());
  for (const auto i : ri) EXPECT_TRUE(is_finite(pts[i]));
  for (const auto& p : tree.tree_points()) EXPECT_TRUE(is_finite(p));
}

TEST(KdTree, NonFiniteQueryReturnsNothing) {
  // A NaN/inf query has no nearest neighbours; radius() already returns 0 for it, knn() must too
  // (not k arbitrary points with NaN distances).
  const auto pts = test::random_points(100, 13);
  const KdTree tree(pts);
  std::uint32_t idx[5];
  float d2[5];
  std::vector<std::uint32_t> ri;
  for (const Eigen::Vector3f& q : {Eigen::Vector3f(kNaN, 0, 0), Eigen::Vector3f(0, kInf, 0), Eigen::Vector3f(0, 0, -kInf)}) {
    const int c = tree.knn(q, 5, idx, d2);
    EXPECT_EQ(c, 0) << "query (" << q.transpose() << "): first result index " << idx[0] << " at squared distance " << d2[0];
    EXPECT_EQ(tree.radius(q, 1.0f, ri), 0u);
  }
}

TEST(KdTree, HugeCoordinates) {
  std::vector<Eigen::Vector3f> pts = test::random_points(500, 4, -1.0f, 1.0f);
  for (std::size_t i = 0; i < 100; ++i) pts[i] = pts[i] * 1e15f;
  pts[100] = Eigen::Vector3f(1e18f, -1e18f, 1e18f);
  const KdTree tree(pts);
  for (std::size_t qi = 0; qi < 50; ++qi) check_knn(tree, pts, pts[qi * 9], 5);
}

TEST(KdTree, RebuildAndStridedInput) {
  struct Rec {
    double t;
    float xyz[3];
    std::uint32_t tag;
  };
  const auto pts = lattice_cloud(2000, 8);
  std::vector<Rec> recs(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) recs[i] = Rec{1.0, {pts[i].x(), pts[i].y(), pts[i].z()}, 7u};
  KdTree tree(test::random_points(100, 1));
  tree.build(PointsView(recs[0].xyz, recs.size(), sizeof(Rec)));  // rebuild over other points
  EXPECT_EQ(tree.size(), pts.size());
  for (std::size_t qi = 0; qi < 60; ++qi)
    if (is_finite(pts[qi * 31])) check_knn(tree, pts, pts[qi * 31], 12);
}

TEST(KdTree, BadSettingsThrow) {
  KdTreeSettings s;
  s.max_leaf_size = 0;
  EXPECT_DUET_ERROR(KdTree(test::random_points(10, 1), s), ErrorCode::kInvalidArgument, "max_leaf_size");
  s.max_leaf_size = 100000;
  EXPECT_DUET_ERROR(KdTree(test::random_points(10, 1), s), ErrorCode::kInvalidArgument, "max_leaf_size");
}

TEST(KdTree, IdenticalWithOneAndTwoThreads) {
  auto pts = test::random_points(60000, 77, -5.0f, 5.0f);  // > 16384: the parallel build
  for (std::size_t i = 0; i < pts.size(); i += 11) pts[i] = pts[i / 2];  // duplicates
  const auto build = [&] {
    KdTree t(pts);
    return t;
  };
  const KdTree a = test::in_arena(1, build);
  const KdTree b = test::in_arena(2, build);
  const std::vector<std::uint32_t> oa(a.order().begin(), a.order().end()), ob(b.order().begin(), b.order().end());
  EXPECT_TRUE(test::bitwise_equal(oa, ob));
  const auto queries = test::random_points(2000, 78, -5.0f, 5.0f);
  for (const auto& q : queries) {
    std::uint32_t ia[10], ib[10];
    float da[10], db[10];
    ASSERT_EQ(a.knn(q, 10, ia, da), 10);
    ASSERT_EQ(b.knn(q, 10, ib, db), 10);
    ASSERT_TRUE(std::equal(ia, ia + 10, ib));
    ASSERT_TRUE(std::equal(da, da + 10, db));
  }
  for (std::size_t qi = 0; qi < 5; ++qi) check_knn(a, pts, queries[qi], 10);
}

// knn_leaf against knn_tree for every indexed point: the same neighbours in the same order (sorted)
// or the same set (unsorted), for every leaf of the tree.
void check_knn_leaf(const KdTree& tree, int k, const char* what) {
  SCOPED_TRACE(std::string(what) + " k " + std::to_string(k));
  ASSERT_EQ(tree.leaf_count() == 0, tree.indexed_size() == 0);
  std::uint32_t next = 0;  // the leaves cover [0, indexed_size()) in order
  KdTree::LeafKnn ws, wu;
  const auto tp = tree.tree_points();
  const std::size_t ku = static_cast<std::size_t>(std::max(k, 0));
  std::vector<std::uint32_t> want_pos(std::max<std::size_t>(ku, 1));
  std::vector<float> want_d2(std::max<std::size_t>(ku, 1));
  for (std::size_t l = 0; l < tree.leaf_count(); ++l) {
    ASSERT_EQ(tree.leaf_begin(l), next);
    ASSERT_GT(tree.leaf_end(l), tree.leaf_begin(l));
    next = tree.leaf_end(l);
    const std::uint32_t m = tree.knn_leaf(l, k, ws);
    ASSERT_EQ(tree.knn_leaf(l, k, wu, /*sorted=*/false), m);
    ASSERT_EQ(m, tree.leaf_end(l) - tree.leaf_begin(l));
    for (std::uint32_t i = 0; i < m; ++i) {
      const std::uint32_t j = tree.leaf_begin(l) + i;
      const int want = tree.knn_tree(tp[j], k, want_pos.data(), want_d2.data());
      ASSERT_EQ(ws.count[i], want) << "leaf " << l << " query " << j;
      ASSERT_EQ(wu.count[i], want) << "leaf " << l << " query " << j;
      for (int r = 0; r < want; ++r) {
        ASSERT_EQ(ws.pos[i * ku + static_cast<std::size_t>(r)], want_pos[static_cast<std::size_t>(r)])
            << "leaf " << l << " query " << j << " rank " << r;
        ASSERT_EQ(ws.dist2[i * ku + static_cast<std::size_t>(r)], want_d2[static_cast<std::size_t>(r)]);
      }
      // Unsorted: the same set, each with its own distance.
      std::vector<std::pair<float, std::uint32_t>> got;
      for (int r = 0; r < want; ++r)
        got.emplace_back(wu.dist2[i * ku + static_cast<std::size_t>(r)], wu.pos[i * ku + static_cast<std::size_t>(r)]);
      for (const auto& [d, p] : got) ASSERT_EQ(d, (tp[p] - tp[j]).squaredNorm());
      std::vector<std::uint32_t> gp, wp(want_pos.begin(), want_pos.begin() + want);
      for (const auto& g : got) gp.push_back(g.second);
      std::sort(gp.begin(), gp.end());
      std::sort(wp.begin(), wp.end());
      ASSERT_EQ(gp, wp) << "leaf " << l << " query " << j;
    }
  }
  ASSERT_EQ(next, tree.indexed_size());
}

// A noisy surface (a wavy sheet, as depth data: points on a 2D manifold with density changes).
std::vector<Eigen::Vector3f> wavy_sheet(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::normal_distribution<float> g(0.0f, 0.002f);
  std::vector<Eigen::Vector3f> p(n);
  for (auto& q : p) {
    const float x = u(rng), y = u(rng) * (x > 0.0f ? 0.3f : 1.0f);  // denser where x > 0
    q = Eigen::Vector3f(x, y, 0.1f * std::sin(4.0f * x) * std::cos(3.0f * y) + g(rng));
  }
  return p;
}

TEST(KdTree, LeafBatchKnnEqualsKnn) {
  // knn_leaf (the batch used by the normals) gives exactly knn_tree's result for every point:
  // lattice ties and duplicates, NaN points, random clouds, a dense surface; leaf sizes from 1
  // (homes are ancestors) to larger than k; k from 1 to more than a leaf holds.
  const auto lattice = lattice_cloud(3000, 91);
  const auto random = test::random_points(2500, 92, -1.0f, 1.0f);
  const auto sheet = wavy_sheet(4000, 93);
  for (const int leaf : {1, 3, 8, 32, 48, 200}) {
    KdTreeSettings s;
    s.max_leaf_size = leaf;
    const KdTree tl(lattice, s), tr(random, s), ts(sheet, s);
    for (const int k : {1, 3, 10, 33}) {
      check_knn_leaf(tl, k, ("lattice leaf " + std::to_string(leaf)).c_str());
      check_knn_leaf(tr, k, ("random leaf " + std::to_string(leaf)).c_str());
      check_knn_leaf(ts, k, ("sheet leaf " + std::to_string(leaf)).c_str());
    }
  }
}

TEST(KdTree, LeafBatchKnnEdgeCases) {
  // Empty tree, all NaN, one point, fewer points than k (the home is the root), k = 0,
  // coordinates whose squared distances overflow to infinity (ties at inf, broken by index).
  const KdTree empty;
  EXPECT_EQ(empty.leaf_count(), 0u);
  const std::vector<Eigen::Vector3f> nan(40, Eigen::Vector3f(kNaN, 0, 0));
  const KdTree all_nan(nan);
  EXPECT_EQ(all_nan.leaf_count(), 0u);
  std::vector<Eigen::Vector3f> one = nan;
  one[7] = Eigen::Vector3f(1, 2, 3);
  const KdTree t1(one);
  ASSERT_EQ(t1.leaf_count(), 1u);
  KdTree::LeafKnn ws;
  ASSERT_EQ(t1.knn_leaf(0, 10, ws), 1u);
  EXPECT_EQ(ws.count[0], 1);
  EXPECT_EQ(ws.pos[0], 0u);
  EXPECT_EQ(ws.dist2[0], 0.0f);
  ASSERT_EQ(t1.knn_leaf(0, 0, ws), 1u);
  EXPECT_EQ(ws.count[0], 0);
  const auto few = test::random_points(7, 94);
  for (const int leaf : {1, 2, 32}) {
    KdTreeSettings s;
    s.max_leaf_size = leaf;
    const KdTree t(few, s);
    for (const int k : {1, 6, 7, 8, 50}) check_knn_leaf(t, k, "few");
  }
  std::vector<Eigen::Vector3f> huge = test::random_points(300, 95, -1.0f, 1.0f);
  for (std::size_t i = 0; i < huge.size(); i += 3) huge[i] *= 1e25f;
  for (const int leaf : {4, 48}) {
    KdTreeSettings s;
    s.max_leaf_size = leaf;
    const KdTree t(huge, s);
    check_knn_leaf(t, 10, "huge");
    // knn() itself against brute force there (a split-plane distance of inf - inf once pruned
    // whole subtrees).
    for (std::size_t qi = 0; qi < huge.size(); qi += 10) check_knn(t, huge, huge[qi], 10);
  }
  // Near the float maximum: box extents overflow to inf too.
  std::vector<Eigen::Vector3f> extreme = test::random_points(200, 97, -1.0f, 1.0f);
  for (std::size_t i = 0; i < extreme.size(); i += 4) extreme[i] *= 3e38f;
  KdTreeSettings s8;
  s8.max_leaf_size = 8;
  const KdTree te(extreme, s8);
  check_knn_leaf(te, 10, "extreme");
  for (std::size_t qi = 0; qi < extreme.size(); qi += 10) check_knn(te, extreme, extreme[qi], 10);
}

TEST(KdTree, LeafBatchKnnIdenticalWithOneAndTwoThreads) {
  // knn_leaf itself is serial; the tree it reads must be the same when built with 1 or 2 threads
  // (> 16384 points: the parallel build), so the batch results are too.
  const auto pts = wavy_sheet(40000, 96);
  const auto build = [&] {
    KdTree t(pts);
    return t;
  };
  const KdTree a = test::in_arena(1, build);
  const KdTree b = test::in_arena(2, build);
  ASSERT_EQ(a.leaf_count(), b.leaf_count());
  KdTree::LeafKnn wa, wb;
  for (std::size_t l = 0; l < a.leaf_count(); l += 7) {
    ASSERT_EQ(a.leaf_begin(l), b.leaf_begin(l));
    const std::uint32_t m = a.knn_leaf(l, 10, wa, false);
    ASSERT_EQ(b.knn_leaf(l, 10, wb, false), m);
    for (std::uint32_t i = 0; i < m; ++i) {
      ASSERT_EQ(wa.count[i], wb.count[i]);
      for (std::size_t r = 0; r < 10; ++r) ASSERT_EQ(wa.pos[i * 10 + r], wb.pos[i * 10 + r]);
    }
  }
}

}  // namespace test_kdtree
}  // namespace duet

namespace duet {
namespace test_kdtree {

// Degenerate inputs (issue 19): all points identical, most identical plus a few others, several
// heavy clusters of duplicates, all in one millimetre voxel, collinear. Identical points end in
// leaves that no split separates; the searches stay exact (brute force, ties by index) and the
// leaf batch equals knn_tree.
std::vector<std::vector<Eigen::Vector3f>> degenerate_clouds() {
  std::vector<std::vector<Eigen::Vector3f>> c;
  c.emplace_back(3000, Eigen::Vector3f(0.5f, -1.25f, 2.0f));
  auto most = test::random_points(3200, 201, -1.0f, 1.0f);
  for (std::size_t i = 0; i < 3000; ++i) most[(i * 7919) % most.size()] = Eigen::Vector3f(0.25f, 0.25f, 0.25f);
  c.push_back(most);
  std::vector<Eigen::Vector3f> clusters;
  for (int i = 0; i < 3000; ++i) clusters.emplace_back(static_cast<float>(i % 5) * 0.125f, 0.0f, static_cast<float>(i % 3) * 0.5f);
  c.push_back(clusters);
  auto voxel = test::random_points(3000, 202, 0.0f, 1e-3f);
  c.push_back(voxel);
  std::vector<Eigen::Vector3f> line;
  for (int i = 0; i < 3000; ++i) line.emplace_back(static_cast<float>(i % 700) * 0.01f, 0.0f, 0.0f);
  c.push_back(line);
  return c;
}

TEST(KdTree, DegenerateInputsStayExact) {
  const auto clouds = degenerate_clouds();
  for (std::size_t ci = 0; ci < clouds.size(); ++ci) {
    const auto& pts = clouds[ci];
    for (const int leaf : {1, 8, 48}) {
      KdTreeSettings s;
      s.max_leaf_size = leaf;
      const KdTree tree(pts, s);
      const std::string what = "cloud " + std::to_string(ci) + " leaf " + std::to_string(leaf);
      SCOPED_TRACE(what);
      for (std::size_t qi = 0; qi < pts.size(); qi += 97) {
        const auto all = brute_all(pts, pts[qi]);
        for (const int k : {1, 10, 33}) check_knn(tree, pts, pts[qi], k, &all);
      }
      const Eigen::Vector3f off(0.3f, -0.2f, 0.1f);
      for (const int k : {1, 10, 100}) check_knn(tree, pts, pts[0] + off, k);
      for (const int k : {1, 10, 33}) check_knn_leaf(tree, k, what.c_str());
    }
  }
}

}  // namespace test_kdtree
}  // namespace duet
