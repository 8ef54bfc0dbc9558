// euclidean_clusters vs a BFS reference (brute force for small clouds, a plain hashed grid for
// large ones) on both internal paths (sparse: <= 12 points per tolerance cell, dense: > 12), and vs
// pcl::EuclideanClusterExtraction on real data; size limits, subsets, empty, NaN, huge
// coordinates, bad settings, thread-count independence.
#include "kernel_test_util.hpp"
#include "reference_clustering.hpp"

#include <duet/kernels/clustering.hpp>
#include <duet/kernels/error.hpp>
#include <duet/kernels/voxel_filter.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <deque>
#include <map>
#include <random>
#include <set>
#include <unordered_map>
#include <vector>

#ifdef DUET_HAVE_PCL
#include <pcl/filters/filter.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
#endif

namespace duet {
namespace test_clustering {

using test::kInf;
using test::kNaN;
using test::Clusters;
using test::reference_clusters;

// ---- reference -----------------------------------------------------------------------------------

// Mean number of finite points per occupied tolerance cell: the kernel switches to its dense
// (clique cell) path above 12.
double points_per_cell(PointsView pts, float tol) {
  std::set<std::array<std::int64_t, 3>> cells;
  std::size_t m = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector3f p = pts[i];
    if (!is_finite(p)) continue;
    ++m;
    cells.insert({static_cast<std::int64_t>(std::floor(static_cast<double>(p.x()) / tol)),
                  static_cast<std::int64_t>(std::floor(static_cast<double>(p.y()) / tol)),
                  static_cast<std::int64_t>(std::floor(static_cast<double>(p.z()) / tol))});
  }
  return cells.empty() ? 0.0 : static_cast<double>(m) / static_cast<double>(cells.size());
}

Clusters run(PointsView pts, float tol, std::uint32_t min_size = 1, std::uint32_t max_size = 0xFFFFFFFFu,
             std::span<const std::uint32_t> subset = {}) {
  ClusteringSettings s;
  s.tolerance_m = tol;
  s.min_size = min_size;
  s.max_size = max_size;
  return euclidean_clusters(pts, subset, s);
}

::testing::AssertionResult same_clusters(const Clusters& got, const Clusters& want) {
  if (got == want) return ::testing::AssertionSuccess();
  auto f = ::testing::AssertionFailure();
  f << "got " << got.size() << " clusters, expected " << want.size();
  for (std::size_t i = 0; i < std::min(got.size(), want.size()); ++i)
    if (got[i] != want[i]) {
      f << "; first difference at cluster " << i << " (sizes " << got[i].size() << " vs " << want[i].size() << ")";
      break;
    }
  return f;
}

// Well separated blobs (Gaussian, sigma) plus uniform background, some NaN.
std::vector<Eigen::Vector3f> blobs(std::size_t per_blob, int nblobs, float sigma, std::size_t background, float box,
                                   std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0.0f, sigma);
  std::uniform_real_distribution<float> u(-box, box);
  std::vector<Eigen::Vector3f> p;
  for (int b = 0; b < nblobs; ++b) {
    const Eigen::Vector3f c(u(rng), u(rng), u(rng));
    for (std::size_t i = 0; i < per_blob; ++i) p.push_back(c + Eigen::Vector3f(g(rng), g(rng), g(rng)));
  }
  for (std::size_t i = 0; i < background; ++i) p.emplace_back(u(rng), u(rng), u(rng));
  std::shuffle(p.begin(), p.end(), rng);
  for (std::size_t i = 0; i < p.size(); i += 97) p[i].y() = kNaN;
  return p;
}

// ---- tests: reference ----------------------------------------------------------------------------

TEST(Clustering, MatchesBruteForceBfsOnSmallRandomClouds) {
  for (std::uint32_t seed = 1; seed <= 8; ++seed) {
    const std::size_t n = 50 + 120 * seed;
    auto pts = test::random_points(n, seed, -1.0f, 1.0f);
    for (std::size_t i = 0; i < n; i += 13) pts[i].x() = (seed % 2) ? kNaN : kInf;
    for (std::size_t i = 5; i < n; i += 17) pts[i] = pts[i / 2];  // duplicates
    for (const float tol : {0.05f, 0.1f, 0.2f}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + " tol " + std::to_string(tol));
      const Clusters want = reference_clusters(pts, {}, tol, 1, 0xFFFFFFFFu, true);
      EXPECT_TRUE(same_clusters(run(pts, tol), want));
      // Grid reference agrees with the brute-force one (checks the reference itself).
      EXPECT_TRUE(same_clusters(reference_clusters(pts, {}, tol, 1, 0xFFFFFFFFu, false), want));
    }
  }
}

TEST(Clustering, SparsePathMatchesReference) {
  for (const std::uint32_t seed : {21u, 22u}) {
    if (!test::kFullSize && seed == 22u) break;  // unoptimised build: one seed
    const auto pts = blobs(400, 20, 0.15f, 20000, 10.0f, seed);
    for (const float tol : {0.1f, 0.25f}) {
      const double ppc = points_per_cell(pts, tol);
      EXPECT_LT(ppc, 12.0) << "not the sparse path";
      const Clusters got = run(pts, tol);
      EXPECT_TRUE(same_clusters(got, reference_clusters(pts, {}, tol, 1, 0xFFFFFFFFu, false))) << "tol " << tol;
      EXPECT_GT(got.size(), 20u);
    }
  }
}

TEST(Clustering, DensePathMatchesReference) {
  for (const std::uint32_t seed : {31u, 32u}) {
    if (!test::kFullSize && seed == 32u) break;  // unoptimised build: one seed
    // Dense Gaussian blobs (sigma 2 cm, tolerance 3-5 cm) with a few sparse outliers around them.
    const auto pts = blobs(4000, 6, 0.02f, 400, 1.0f, seed);
    for (const float tol : {0.03f, 0.05f}) {
      const double ppc = points_per_cell(pts, tol);
      EXPECT_GT(ppc, 12.0) << "not the dense path";
      const Clusters got = run(pts, tol);
      EXPECT_TRUE(same_clusters(got, reference_clusters(pts, {}, tol, 1, 0xFFFFFFFFu, false))) << "tol " << tol;
      EXPECT_GT(got.size(), 6u);
    }
  }
}

TEST(Clustering, ExactToleranceIsConnectedOnBothPaths) {
  // A chain along x with spacing exactly tol (0.125: exact in float) is one cluster (<= tol);
  // a chain with a gap one ulp wider than tol breaks there.
  for (const int copies : {1, 20}) {  // 20 copies per point: > 12 per cell -> dense path
    std::vector<Eigen::Vector3f> p;
    for (int c = 0; c < copies; ++c)
      for (int i = 0; i < 50; ++i) p.emplace_back(0.125f * static_cast<float>(i), 0.0f, 0.0f);
    EXPECT_EQ(points_per_cell(p, 0.125f) > 12.0, copies > 1);
    const Clusters one = run(p, 0.125f);
    ASSERT_EQ(one.size(), 1u) << copies << " copies";
    EXPECT_EQ(one[0].size(), p.size());
    // Move points 25..49 right by 2^-20 (exact in float below x = 8): the 24-25 gap exceeds the
    // tolerance, every other gap is still exactly tol.
    for (auto& q : p)
      if (q.x() >= 3.125f) q.x() += 1.0f / 1048576.0f;
    const Clusters two = run(p, 0.125f);
    EXPECT_TRUE(same_clusters(two, reference_clusters(p, {}, 0.125f, 1, 0xFFFFFFFFu, true))) << copies << " copies";
    EXPECT_EQ(two.size(), 2u) << copies << " copies";
  }
}

TEST(Clustering, MinMaxSizeDropWholeClusters) {
  // Groups of known sizes, 1 m apart (tolerance 0.1).
  const std::vector<std::uint32_t> sizes{1, 5, 10, 20, 50, 5};
  std::vector<Eigen::Vector3f> p;
  for (std::size_t g = 0; g < sizes.size(); ++g)
    for (std::uint32_t i = 0; i < sizes[g]; ++i) p.emplace_back(static_cast<float>(g), 0.01f * static_cast<float>(i % 5), 0.01f * static_cast<float>(i / 5));
  std::reverse(p.begin(), p.end());
  auto sizes_of = [](const Clusters& c) {
    std::vector<std::size_t> s;
    for (const auto& x : c) s.push_back(x.size());
    return s;
  };
  EXPECT_EQ(sizes_of(run(p, 0.1f)), (std::vector<std::size_t>{50, 20, 10, 5, 5, 1}));
  EXPECT_EQ(sizes_of(run(p, 0.1f, 5, 20)), (std::vector<std::size_t>{20, 10, 5, 5}));  // the 50 is dropped, not split
  EXPECT_EQ(sizes_of(run(p, 0.1f, 6, 49)), (std::vector<std::size_t>{20, 10}));
  EXPECT_EQ(sizes_of(run(p, 0.1f, 51)), (std::vector<std::size_t>{}));
  EXPECT_EQ(sizes_of(run(p, 0.1f, 10, 10)), (std::vector<std::size_t>{10}));
  // Equal sizes: the cluster holding the smaller index comes first.
  const Clusters c = run(p, 0.1f, 5, 5);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_LT(c[0].front(), c[1].front());
  for (const auto& x : c) EXPECT_TRUE(std::is_sorted(x.begin(), x.end()));
  // Against the reference with limits, on a random cloud.
  const auto r = blobs(300, 10, 0.05f, 3000, 3.0f, 41);
  EXPECT_TRUE(same_clusters(run(r, 0.1f, 20, 250), reference_clusters(r, {}, 0.1f, 20, 250, false)));
}

TEST(Clustering, SubsetSelection) {
  auto pts = blobs(500, 8, 0.1f, 4000, 3.0f, 51);
  std::mt19937 rng(52);
  std::vector<std::uint32_t> subset;
  for (std::uint32_t i = 0; i < pts.size(); ++i)
    if (rng() % 3 == 0) subset.push_back(i);
  std::shuffle(subset.begin(), subset.end(), rng);  // any order
  const Clusters got = run(pts, 0.15f, 1, 0xFFFFFFFFu, subset);
  EXPECT_TRUE(same_clusters(got, reference_clusters(pts, subset, 0.15f, 1, 0xFFFFFFFFu, false)));
  const std::set<std::uint32_t> in(subset.begin(), subset.end());
  std::size_t total = 0;
  for (const auto& c : got)
    for (const auto i : c) {
      EXPECT_TRUE(in.count(i)) << i << " is not in the subset";
      EXPECT_TRUE(is_finite(pts[i]));
      ++total;
    }
  std::size_t finite_in_subset = 0;
  for (const auto i : subset) finite_in_subset += is_finite(pts[i]) ? 1 : 0;
  EXPECT_EQ(total, finite_in_subset);
  // A subset index out of range is an error.
  subset.push_back(static_cast<std::uint32_t>(pts.size()));
  EXPECT_DUET_ERROR(run(pts, 0.15f, 1, 0xFFFFFFFFu, subset), ErrorCode::kInvalidArgument, "subset index");
}

TEST(Clustering, SubsetWithRepeatedIndices) {
  // pcl::EuclideanClusterExtraction marks points processed, so an index given twice in the
  // subset appears once in one cluster; sizes count distinct points.
  std::vector<Eigen::Vector3f> p;
  for (int i = 0; i < 10; ++i) p.emplace_back(0.01f * static_cast<float>(i), 0.0f, 0.0f);
  const std::vector<std::uint32_t> subset{1, 1, 2, 2, 3, 7, 7, 7};
  EXPECT_EQ(run(p, 0.1f, 1, 0xFFFFFFFFu, subset), (Clusters{{1, 2, 3, 7}}));
  EXPECT_EQ(run(p, 0.1f, 1, 4, subset), (Clusters{{1, 2, 3, 7}})) << "4 distinct points must pass max_size 4";
}

TEST(Clustering, EmptyOnePointAndAllNaN) {
  EXPECT_TRUE(run(PointsView(), 0.1f).empty());
  const std::vector<Eigen::Vector3f> nan(30, Eigen::Vector3f(kNaN, 0, 0));
  EXPECT_TRUE(run(nan, 0.1f).empty());
  std::vector<Eigen::Vector3f> one = nan;
  one[11] = Eigen::Vector3f(5, 6, 7);
  EXPECT_EQ(run(one, 0.1f), (Clusters{{11}}));
  EXPECT_TRUE(run(one, 0.1f, 2).empty());
  const std::vector<std::uint32_t> only_nan{0, 1, 2};
  EXPECT_TRUE(run(one, 0.1f, 1, 0xFFFFFFFFu, only_nan).empty());
}

TEST(Clustering, HugeCoordinates) {
  const auto kOut = ErrorCode::kOutOfRange;
  std::vector<Eigen::Vector3f> p{{0, 0, 0}, {1e6f, 0, 0}};
  EXPECT_DUET_ERROR(run(p, 0.1f), kOut, "too large");
  p = {{0, 0, -1e30f}};
  EXPECT_DUET_ERROR(run(p, 0.1f), kOut, "axis z");
  p = {{3e38f, -3e38f, 0}};
  EXPECT_DUET_ERROR(run(p, 1.0f), kOut, "too large");
  // Far from the origin but representable (|p / tol| < 2^20): exact.
  auto q = blobs(300, 5, 0.05f, 1000, 2.0f, 61);
  for (auto& x : q) x += Eigen::Vector3f(5e4f, -5e4f, 100.0f);
  EXPECT_TRUE(same_clusters(run(q, 0.1f), reference_clusters(q, {}, 0.1f, 1, 0xFFFFFFFFu, false)));
  // A large tolerance makes large coordinates fine.
  p = {{1e6f, 0, 0}, {1e6f + 50.0f, 0, 0}, {-1e6f, 0, 0}};
  EXPECT_EQ(run(p, 100.0f), (Clusters{{0, 1}, {2}}));
}

TEST(Clustering, DensePathAcceptsTheHeaderCoordinateRange) {
  // The header's limit is |p / tolerance| < 2^20 on both paths: a dense cloud (dense path) at
  // 7e4 m with tolerance 0.1 m (|p / tol| = 7e5) must be clustered, not rejected.
  auto dense_far = blobs(3000, 3, 0.05f, 0, 0.5f, 62);
  for (auto& x : dense_far) x += Eigen::Vector3f(7e4f, 0.0f, 0.0f);
  ASSERT_GT(points_per_cell(dense_far, 0.1f), 12.0);
  try {
    EXPECT_TRUE(same_clusters(run(dense_far, 0.1f), reference_clusters(dense_far, {}, 0.1f, 1, 0xFFFFFFFFu, false)));
  } catch (const Error& e) {
    ADD_FAILURE() << "dense cloud at |p / tol| = 7e5 < 2^20 rejected: " << e.what();
  }
}

TEST(Clustering, BadSettingsThrow) {
  const auto p = test::random_points(10, 1);
  const auto kInv = ErrorCode::kInvalidArgument;
  for (const float t : {0.0f, -0.1f, kNaN, kInf}) EXPECT_DUET_ERROR(run(p, t), kInv, "tolerance_m");
  EXPECT_DUET_ERROR(run(p, 0.1f, 10, 5), kInv, "min_size");
}

TEST(Clustering, WorkspaceReuseAndStridedInput) {
  ClusteringWorkspace ws;
  ClusteringSettings s;
  s.tolerance_m = 0.05f;
  for (std::uint32_t seed = 70; seed < 74; ++seed) {
    const auto p = seed % 2 ? blobs(3000, 4, 0.02f, 500, 1.0f, seed) : blobs(100, 30, 0.1f, 3000, 3.0f, seed);
    EXPECT_EQ(euclidean_clusters(p, {}, s, ws), euclidean_clusters(p, {}, s));
  }
  struct Rec {
    std::uint16_t tag;
    float xyz[3];
  };
  const auto p = blobs(200, 10, 0.05f, 1000, 2.0f, 75);
  std::vector<Rec> recs(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) recs[i] = Rec{1, {p[i].x(), p[i].y(), p[i].z()}};
  EXPECT_EQ(euclidean_clusters(PointsView(recs[0].xyz, recs.size(), sizeof(Rec)), {}, s), euclidean_clusters(p, {}, s));
}

TEST(Clustering, RawKinectFrameDensePath) {
  DUET_REQUIRE_DATA("rgbd/slambook2_ch5/depth/1.pgm");
  // The central 320 x 240 pixels of a raw frame: the full frame's density, a quarter of its points.
  const PointCloud c = test::kFullSize ? test::slambook_cloud_roi(1, 160, 120, 320, 240) : test::slambook_cloud_roi(1, 240, 180, 160, 120);
  for (const float tol : {0.1f, 0.05f}) {
    const double ppc = points_per_cell(c.points, tol);
    std::printf("[ info     ] raw slambook2 frame 1 (central ROI, %zu points), tol %.2f: %.1f points per tolerance cell (%s path)\n", c.size(), static_cast<double>(tol), ppc,
                ppc > 12.0 ? "dense" : "sparse");
    if (tol == 0.1f) {
      EXPECT_GT(ppc, 12.0) << "a raw Kinect frame should take the dense path";
    }
    const Clusters got = run(c.points, tol, 20);
    EXPECT_TRUE(same_clusters(got, reference_clusters(c.points, {}, tol, 20, 0xFFFFFFFFu, false))) << "tol " << tol;
  }
}

TEST(Clustering, IdenticalWithOneAndTwoThreads) {
  const std::size_t f = test::full_or<std::size_t>(4, 1);
  std::vector<std::vector<Eigen::Vector3f>> clouds{blobs(2000 * f, 5, 0.02f, 500 * f, 1.0f, 81), blobs(25 * f, 100, 0.1f, 5000 * f, 8.0f, 82)};
  if (test::have_data("rgbd/slambook2_ch5/depth/5.pgm"))
    clouds.push_back(test::slambook_cloud_roi(5, 0, 0, test::full_or(320, 160), test::full_or(480, 240)).points);
  for (const auto& p : clouds) {
    for (const float tol : {0.02f, 0.1f}) {
      const Clusters a = test::in_arena(1, [&] { return run(p, tol); });
      const Clusters b = test::in_arena(2, [&] { return run(p, tol); });
      EXPECT_EQ(a, b) << "tol " << tol;
    }
  }
}

// ---- tests: PCL ----------------------------------------------------------------------------------

#ifdef DUET_HAVE_PCL
// pcl::EuclideanClusterExtraction (pcl::search::KdTree) vs duet: identical clusters as sets of indices.
Clusters compare_clusters_with_pcl(const std::vector<Eigen::Vector3f>& pts, float tol, std::uint32_t min_size, const char* name) {
  const auto cloud = test::to_pcl_xyz(pts);
  pcl::EuclideanClusterExtraction<pcl::PointXYZ> ec;
  ec.setClusterTolerance(tol);
  ec.setMinClusterSize(min_size);
  ec.setMaxClusterSize(std::numeric_limits<pcl::uindex_t>::max());
  ec.setSearchMethod(pcl::search::KdTree<pcl::PointXYZ>::Ptr(new pcl::search::KdTree<pcl::PointXYZ>));
  ec.setInputCloud(cloud);
  std::vector<pcl::PointIndices> ref;
  ec.extract(ref);
  std::set<std::vector<std::uint32_t>> want;
  std::size_t want_points = 0;
  for (const auto& c : ref) {
    std::vector<std::uint32_t> v(c.indices.begin(), c.indices.end());
    std::sort(v.begin(), v.end());
    want_points += v.size();
    want.insert(std::move(v));
  }
  const Clusters got = run(pts, tol, min_size);
  const std::set<std::vector<std::uint32_t>> got_set(got.begin(), got.end());
  std::size_t common = 0;
  for (const auto& c : got_set) common += want.count(c);
  std::printf("[ pcl      ] EuclideanClusterExtraction %s: %zu points, tol %.2f, min %u: PCL %zu clusters (%zu points), duet %zu "
              "clusters, %zu identical -> %s\n",
              name, pts.size(), static_cast<double>(tol), min_size, want.size(), want_points, got.size(), common,
              got_set == want ? "IDENTICAL" : "DIFFERENT");
  EXPECT_TRUE(got_set == want) << name;
  EXPECT_EQ(got.size(), ref.size()) << name;
  EXPECT_GT(ref.size(), 0u) << name;
  return got;
}

std::vector<Eigen::Vector3f> voxelized(const std::vector<Eigen::Vector3f>& raw) {
  PointCloud c;
  voxel_filter(raw, {}, {}, c);  // 0.05 m, no NaN left
  return c.points;
}

TEST(ClusteringPcl, VoxelFilteredOffice1) {
  DUET_REQUIRE_DATA("pcl/office1.pcd");
  const auto pts = voxelized(test::load_pcd("pcl/office1.pcd", false).points);
  EXPECT_LT(points_per_cell(pts, 0.1f), 12.0);  // sparse path
  compare_clusters_with_pcl(pts, 0.1f, 20, "office1.pcd voxel 0.05");
  compare_clusters_with_pcl(pts, 0.06f, 5, "office1.pcd voxel 0.05");
}

TEST(ClusteringPcl, VoxelFilteredSlambookFrames) {
  DUET_REQUIRE_DATA("rgbd/slambook2_ch5/depth/1.pgm");
  for (const int i : {1, 3, 5}) {
    const auto pts = voxelized(test::slambook_cloud(i).points);
    compare_clusters_with_pcl(pts, 0.1f, 20, ("slambook2 frame " + std::to_string(i) + " voxel 0.05").c_str());
  }
}

TEST(ClusteringPcl, RawTableSceneMug) {
  DUET_REQUIRE_DATA("pcl/table_scene_mug_stereo_textured.pcd");
  PointCloud raw = test::load_pcd("pcl/table_scene_mug_stereo_textured.pcd", false);
  ASSERT_EQ(raw.size(), 640u * 480u);
  if (!test::kFullSize) {  // unoptimised builds: the central 320 x 240 part (see kFullSize)
    PointCloud part;
    for (const auto i : test::organized_roi(640, 160, 120, 320, 240)) part.points.push_back(raw.points[i]);
    raw = part;
  }
  const auto pts = test::finite_only(raw.points);  // PCL's kd-tree input must be finite
  EXPECT_GT(points_per_cell(pts, 0.02f), 12.0);    // dense path
  Clusters mapped = compare_clusters_with_pcl(
      pts, 0.02f, 20, test::kFullSize ? "table_scene_mug raw (NaNs removed)" : "table_scene_mug raw central 320x240 (NaNs removed)");
  // duet on the raw cloud with NaNs gives the same clusters, in the original indices.
  std::vector<std::uint32_t> finite_idx;
  for (std::uint32_t i = 0; i < raw.size(); ++i)
    if (is_finite(raw.points[i])) finite_idx.push_back(i);
  const Clusters with_nan = run(raw.points, 0.02f, 20);
  for (auto& c : mapped)
    for (auto& i : c) i = finite_idx[i];
  EXPECT_EQ(with_nan, mapped);
}
#endif

}  // namespace test_clustering
}  // namespace duet
