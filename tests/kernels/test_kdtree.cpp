// KdTree knn / radius vs brute force (duplicates, exact ties broken by the smaller index), k larger
// than the cloud, empty tree, NaN points never returned, tree order, thread-count independence.
#include "kernel_test_util.hpp"

#include <duet/kernels/error.hpp>
#include <duet/kernels/kdtree.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace duet {
namespace {

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

}  // namespace
}  // namespace duet
