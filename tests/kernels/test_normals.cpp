// estimate_normals vs a brute-force reference (brute-force kNN + own eigen decomposition of the
// Eq. (2) covariance, smallest eigenvalue) and vs pcl::NormalEstimation on real data; planes,
// viewpoint flipping, NaN handling, bad input, thread-count independence.
#include "kernel_test_util.hpp"

#include <duet/kernels/error.hpp>
#include <duet/kernels/kdtree.hpp>
#include <duet/kernels/normals.hpp>
#include <duet/kernels/voxel_filter.hpp>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <optional>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#ifdef DUET_HAVE_PCL
#include <pcl/features/normal_3d.h>
#include <pcl/filters/filter.h>
#include <pcl/search/kdtree.h>
#endif

namespace duet {
namespace test_normals {

using test::kInf;
using test::kNaN;

// ---- reference -----------------------------------------------------------------------------------

struct RefNormal {
  Eigen::Vector3d n = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  double curvature = std::numeric_limits<double>::quiet_NaN();
  double gap = 0.0;  // (l1 - l0) / trace: how well defined the normal is
};

// Brute-force k nearest finite points (ties by the smaller index), the point itself included.
std::vector<std::uint32_t> brute_knn(const std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3f& q, int k) {
  std::vector<std::pair<float, std::uint32_t>> d;
  d.reserve(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (is_finite(pts[i])) d.emplace_back((pts[i] - q).squaredNorm(), static_cast<std::uint32_t>(i));
  const std::size_t kk = std::min(d.size(), static_cast<std::size_t>(k));
  std::partial_sort(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(kk), d.end());
  std::vector<std::uint32_t> out(kk);
  for (std::size_t j = 0; j < kk; ++j) out[j] = d[j].second;
  return out;
}

// Eq. (2) with the smallest eigenvalue, by an iterative (QR) symmetric eigen solver in double.
RefNormal reference_normal(const std::vector<Eigen::Vector3f>& pts, const std::vector<std::uint32_t>& nb,
                           const Eigen::Vector3f& p, const Eigen::Vector3f& viewpoint) {
  RefNormal r;
  if (nb.size() < 3) return r;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto i : nb) mean += pts[i].cast<double>();
  mean /= static_cast<double>(nb.size());
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (const auto i : nb) {
    const Eigen::Vector3d d = pts[i].cast<double>() - mean;
    C += d * d.transpose();
  }
  C /= static_cast<double>(nb.size());
  if (!(C.trace() > 0.0)) return r;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
  const Eigen::Vector3d ev = es.eigenvalues();
  // Collinear neighbourhoods (rank-1 covariance: two zero eigenvalues) have no normal: degenerate,
  // as the header says (PCL gives NaN there too).
  if (ev[1] <= 1e-10 * C.trace()) return r;
  r.n = es.eigenvectors().col(0).normalized();
  if ((viewpoint - p).cast<double>().dot(r.n) < 0.0) r.n = -r.n;
  r.curvature = std::max(0.0, ev[0]) / (std::max(0.0, ev[0]) + ev[1] + ev[2]);
  r.gap = (ev[1] - ev[0]) / C.trace();
  return r;
}

double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / std::numbers::pi;
}

// Compares estimate_normals with the reference at every `every`-th point.
void compare_with_reference(const std::vector<Eigen::Vector3f>& pts, int k, const Eigen::Vector3f& vp, std::size_t every = 1,
                            const char* name = "", const KdTreeSettings& tree_settings = {}) {
  SCOPED_TRACE(std::string(name) + " k " + std::to_string(k) + " leaf " + std::to_string(tree_settings.max_leaf_size));
  const KdTree tree(pts, tree_settings);
  std::vector<Eigen::Vector3f> normals(pts.size());
  std::vector<float> curv(pts.size());
  NormalSettings s;
  s.k = k;
  s.viewpoint = vp;
  estimate_normals(pts, tree, s, normals, curv);
  std::size_t checked = 0, bad = 0;
  for (std::size_t i = 0; i < pts.size(); i += every) {
    if (!is_finite(pts[i])) {
      EXPECT_TRUE(std::isnan(normals[i].x()) && std::isnan(curv[i])) << "non-finite point " << i;
      continue;
    }
    const auto nb = brute_knn(pts, pts[i], k);
    const RefNormal r = reference_normal(pts, nb, pts[i], vp);
    if (std::isnan(r.n.x())) {
      EXPECT_TRUE(std::isnan(normals[i].x()) && std::isnan(curv[i])) << "point " << i;
      continue;
    }
    ASSERT_TRUE(is_finite(normals[i])) << "point " << i;
    EXPECT_NEAR(normals[i].norm(), 1.0f, 1e-5f);
    EXPECT_NEAR(curv[i], r.curvature, 1e-5) << "point " << i;
    if (r.gap < 1e-4) continue;  // (nearly) repeated smallest eigenvalue: the normal is not unique
    ++checked;
    const Eigen::Vector3d n = normals[i].cast<double>();
    const double toward = (vp - pts[i]).cast<double>().normalized().dot(r.n);
    // Where the viewpoint lies (almost) in the tangent plane the flip is a coin toss: compare up to sign.
    const double a = std::abs(toward) < 1e-4 ? std::min(angle_deg(n, r.n), angle_deg(-n, r.n)) : angle_deg(n, r.n);
    if (!(a < 0.01) && ++bad <= 5)
      ADD_FAILURE() << "point " << i << ": normal (" << n.transpose() << ") vs reference (" << r.n.transpose() << "), " << a
                    << " deg, gap " << r.gap;
  }
  EXPECT_EQ(bad, 0u);
  EXPECT_GT(checked, 0u);
}

std::vector<Eigen::Vector3f> noisy_sphere(std::size_t n, std::uint32_t seed, float radius, float noise) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0.0f, 1.0f);
  std::vector<Eigen::Vector3f> p(n);
  for (auto& q : p) {
    const Eigen::Vector3f d = Eigen::Vector3f(g(rng), g(rng), g(rng)).normalized();
    q = d * (radius + noise * g(rng)) + Eigen::Vector3f(0.3f, -0.2f, 2.0f);
  }
  return p;
}

// ---- tests: reference ----------------------------------------------------------------------------

TEST(Normals, MatchBruteForceReferenceOnSyntheticClouds) {
  auto sphere = noisy_sphere(test::full_or<std::size_t>(1200, 700), 1, 0.5f, 0.002f);
  compare_with_reference(sphere, 10, Eigen::Vector3f::Zero(), 1, "sphere");
  compare_with_reference(sphere, 3, Eigen::Vector3f(5, 5, 5), 1, "sphere");
  compare_with_reference(sphere, 25, Eigen::Vector3f::Zero(), 1, "sphere");
  // Random cube with duplicates and NaNs.
  auto cube = test::random_points(test::full_or<std::size_t>(1200, 700), 2, -1.0f, 1.0f);
  for (std::size_t i = 0; i < cube.size(); i += 9) cube[i] = cube[i / 3];
  for (std::size_t i = 4; i < cube.size(); i += 50) cube[i].z() = kNaN;
  compare_with_reference(cube, 10, Eigen::Vector3f(0, 0, -3), 1, "cube");
}

TEST(Normals, MatchBruteForceReferenceWithAnyLeafSize) {
  // The normals come from the tree's leaf batches (KdTree::knn_leaf): leaves of one point (every
  // batch's home is an ancestor), of fewer points than k, and larger than the cloud part they
  // cover must all give the reference's neighbourhoods.
  auto sphere = noisy_sphere(test::full_or<std::size_t>(900, 500), 11, 0.5f, 0.002f);
  sphere[17] = Eigen::Vector3f(kNaN, 0, 0);
  for (const int leaf : {1, 7, 200, 1024}) {
    KdTreeSettings ts;
    ts.max_leaf_size = leaf;
    compare_with_reference(sphere, 10, Eigen::Vector3f::Zero(), 1, "sphere", ts);
    compare_with_reference(sphere, 3, Eigen::Vector3f(5, 5, 5), 3, "sphere", ts);
  }
  // Fewer points than k: every point's neighbourhood is the whole cloud.
  const auto tiny = test::random_points(6, 12, -1.0f, 1.0f);
  compare_with_reference(tiny, 10, Eigen::Vector3f::Zero(), 1, "tiny");
}

TEST(Normals, HeavyDuplicatesMatchTheReferenceAndStayLinear) {
  // Most points identical (a stuck sensor, a zero-depth frame back-projected to one point): the
  // identical ones share one leaf no split separates. Exact against brute force on a small cloud,
  // and 200k identical points (over a minute before the uniform leaves; issue 19) give NaN normals.
  auto cloud = noisy_sphere(1200, 13, 0.5f, 0.002f);
  for (std::size_t i = 0; i < 1000; ++i) cloud[(i * 7) % cloud.size()] = cloud[3];
  compare_with_reference(cloud, 10, Eigen::Vector3f::Zero(), 1, "sphere with 1000 duplicates");
  PointCloud same;
  same.points.assign(test::full_or<std::size_t>(200000, 50000), Eigen::Vector3f(0.1f, 0.2f, 1.5f));
  for (int i = 0; i < 500; ++i)  // and a plane beside them
    same.points.emplace_back(0.01f * static_cast<float>(i % 25), 0.01f * static_cast<float>(i / 25) + 1.0f, 2.0f);
  estimate_normals(same, {});
  const std::size_t dups = same.size() - 500;
  std::size_t nan = 0, plane_ok = 0;
  for (std::size_t i = 0; i < dups; ++i) nan += std::isnan(same.normals[i].x()) && std::isnan(same.curvature[i]) ? 1 : 0;
  for (std::size_t i = dups; i < same.size(); ++i) plane_ok += std::abs(std::abs(same.normals[i].z()) - 1.0f) < 1e-4f ? 1 : 0;
  EXPECT_EQ(nan, dups);
  EXPECT_EQ(plane_ok, 500u);
}

TEST(Normals, MatchBruteForceReferenceOnRealData) {
  if (test::have_data("rgbd/slambook2_ch5/depth/1.pgm")) {
    const PointCloud raw = test::slambook_cloud(1);
    PointCloud c;
    VoxelFilterSettings vs;
    vs.leaf_size_m = 0.1f;
    voxel_filter(raw.points_view(), {}, vs, c);
    compare_with_reference(c.points, 10, Eigen::Vector3f::Zero(), test::full_or<std::size_t>(7, 23), "slambook frame 1 voxel 0.1");
  }
#ifdef DUET_HAVE_PCL
  if (test::have_data("pcl/bun0.pcd")) {
    const PointCloud bun = test::load_pcd("pcl/bun0.pcd", false);
    compare_with_reference(bun.points, 10, Eigen::Vector3f::Zero(), 1, "bun0");
  }
#endif
  if (!test::have_data("rgbd/slambook2_ch5/depth/1.pgm")) GTEST_SKIP() << "../shared/data absent: real-data part skipped";
}

TEST(Normals, NormalFromNeighbours) {
  Eigen::Vector3f n;
  float c;
  const std::vector<Eigen::Vector3f> two{{0, 0, 0}, {1, 0, 0}};
  EXPECT_FALSE(normal_from_neighbours(two, n, c));
  EXPECT_TRUE(std::isnan(n.x()) && std::isnan(n.y()) && std::isnan(n.z()) && std::isnan(c));
  EXPECT_FALSE(normal_from_neighbours({}, n, c));
  const std::vector<Eigen::Vector3f> same(10, Eigen::Vector3f(1, 2, 3));
  EXPECT_FALSE(normal_from_neighbours(same, n, c));
  EXPECT_TRUE(std::isnan(n.x()) && std::isnan(c));
  const std::vector<Eigen::Vector3f> nan{{0, 0, 0}, {1, 0, 0}, {kNaN, 0, 1}};
  EXPECT_FALSE(normal_from_neighbours(nan, n, c));
  // Three points: the normal of their plane, curvature 0.
  const std::vector<Eigen::Vector3f> tri{{0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  ASSERT_TRUE(normal_from_neighbours(tri, n, c));
  EXPECT_NEAR(std::abs(n.z()), 1.0f, 1e-6f);
  EXPECT_NEAR(c, 0.0f, 1e-6f);
  // Isotropic (cube corners): curvature 1/3.
  std::vector<Eigen::Vector3f> cube;
  for (int i = 0; i < 8; ++i) cube.emplace_back(static_cast<float>(i & 1), static_cast<float>((i >> 1) & 1), static_cast<float>((i >> 2) & 1));
  ASSERT_TRUE(normal_from_neighbours(cube, n, c));
  EXPECT_NEAR(c, 1.0f / 3.0f, 1e-6f);
  // Far from the origin, tiny neighbourhood (the double precision path): still exact.
  std::vector<Eigen::Vector3f> far;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) far.emplace_back(1000.0f + 0.01f * static_cast<float>(i), -2000.0f + 0.01f * static_cast<float>(j), 500.0f);
  ASSERT_TRUE(normal_from_neighbours(far, n, c));
  EXPECT_NEAR(std::abs(n.z()), 1.0f, 1e-5f);
  EXPECT_NEAR(c, 0.0f, 1e-6f);
}

TEST(Normals, CollinearNeighbourhoodsAreDegenerate) {
  // Points on a line have no surface normal: the header's "degenerate" case (NaN, false), as
  // pcl::NormalEstimation (NaN). Kinect clouds have such rows at depth edges (office1.pcd has dozens).
  std::vector<Eigen::Vector3f> line;
  for (int i = 0; i < 10; ++i) line.emplace_back(0.1f * static_cast<float>(i), 0.5f, 2.0f);
  Eigen::Vector3f n;
  float c;
  EXPECT_FALSE(normal_from_neighbours(line, n, c)) << "normal (" << n.transpose() << ") for collinear points";
  EXPECT_TRUE(std::isnan(n.x()) && std::isnan(c));
  PointCloud cloud;
  cloud.points = line;
  for (int i = 0; i < 40; ++i) cloud.points.emplace_back(0.03f * static_cast<float>(i), -0.2f + 0.01f * static_cast<float>(i), 3.0f);
  estimate_normals(cloud, {});
  std::size_t finite = 0;
  for (const auto& x : cloud.normals) finite += is_finite(x) ? 1 : 0;
  EXPECT_EQ(finite, 0u) << "of " << cloud.size() << " points on two lines";
}

TEST(Normals, PlanesGiveThePlaneNormal) {
  const Eigen::Vector3f normal = Eigen::Vector3f(0.3f, -0.5f, 0.8f).normalized();
  const Eigen::Vector3f u = normal.unitOrthogonal(), v = normal.cross(u);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> j(-0.002f, 0.002f);
  std::vector<Eigen::Vector3f> pts;
  for (int a = 0; a < 40; ++a)
    for (int b = 0; b < 40; ++b)
      pts.push_back(Eigen::Vector3f(1, 2, 3) + (0.02f * static_cast<float>(a) + j(rng)) * u + (0.02f * static_cast<float>(b) + j(rng)) * v);
  const Eigen::Vector3f vp = Eigen::Vector3f(1, 2, 3) + 10.0f * normal;  // in front of the plane
  PointCloud c;
  c.points = pts;
  NormalSettings s;
  s.viewpoint = vp;
  estimate_normals(c, s);
  ASSERT_EQ(c.normals.size(), pts.size());
  ASSERT_EQ(c.curvature.size(), pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    EXPECT_GT(c.normals[i].dot(normal), 0.999999f) << i;  // exactly planar: exact normal, facing vp
    EXPECT_LT(c.curvature[i], 1e-6f) << i;
  }
  // Viewpoint behind the plane: every normal flips.
  s.viewpoint = Eigen::Vector3f(1, 2, 3) - 10.0f * normal;
  estimate_normals(c, s);
  for (std::size_t i = 0; i < pts.size(); ++i) EXPECT_LT(c.normals[i].dot(normal), -0.999999f) << i;
}

TEST(Normals, HugeCoordinates) {
  // A plane z = 5e5 m sampled every metre around (1e6, -1e6): exactly representable, so the
  // normal is vertical to round-off (double-precision covariance) and faces the viewpoint.
  PointCloud c;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) c.points.emplace_back(1e6f + static_cast<float>(i), -1e6f + static_cast<float>(j), 5e5f);
  NormalSettings s;
  s.viewpoint = Eigen::Vector3f(1e6f, -1e6f, 1e6f);
  estimate_normals(c, s);
  for (std::size_t i = 0; i < c.size(); ++i) {
    EXPECT_GT(c.normals[i].z(), 1.0f - 1e-6f) << i;
    EXPECT_LT(c.curvature[i], 1e-9f) << i;
  }
  // Coordinates whose squared distances overflow float: no crash, unit normals or NaN.
  PointCloud h;
  h.points = test::random_points(200, 9, -1e25f, 1e25f);
  estimate_normals(h, {});
  for (const auto& n : h.normals)
    if (is_finite(n)) {
      EXPECT_NEAR(n.norm(), 1.0f, 1e-5f);
    }
}

TEST(Normals, ViewpointFlipping) {
  // Sphere around (0.3, -0.2, 2): viewpoint at the centre -> every normal points inward;
  // viewpoint far outside -> the near half points outward, the far half inward.
  const auto sphere = noisy_sphere(3000, 4, 0.5f, 0.0f);
  const Eigen::Vector3f centre(0.3f, -0.2f, 2.0f);
  PointCloud c;
  c.points = sphere;
  NormalSettings s;
  s.viewpoint = centre;
  estimate_normals(c, s);
  for (std::size_t i = 0; i < sphere.size(); ++i) {
    EXPECT_GE((s.viewpoint - sphere[i]).dot(c.normals[i]), 0.0f) << i;
    EXPECT_LT(c.normals[i].dot((sphere[i] - centre).normalized()), -0.98f) << i;
  }
  s.viewpoint = centre + Eigen::Vector3f(0, 0, -100);
  estimate_normals(c, s);
  for (std::size_t i = 0; i < sphere.size(); ++i) EXPECT_GE((s.viewpoint - sphere[i]).dot(c.normals[i]), 0.0f) << i;
}

TEST(Normals, NaNHandling) {
  auto pts = noisy_sphere(1500, 5, 1.0f, 0.001f);
  std::vector<Eigen::Vector3f> clean = pts;
  // Insert NaN / inf points at every 4th position.
  std::vector<Eigen::Vector3f> dirty;
  std::vector<std::size_t> where;
  for (std::size_t i = 0; i < clean.size(); ++i) {
    if (i % 4 == 0) dirty.push_back(i % 8 == 0 ? Eigen::Vector3f(kNaN, kNaN, kNaN) : Eigen::Vector3f(1, kInf, 0));
    where.push_back(dirty.size());
    dirty.push_back(clean[i]);
  }
  PointCloud a, b;
  a.points = clean;
  b.points = dirty;
  estimate_normals(a, {});
  estimate_normals(b, {});
  for (std::size_t i = 0; i < dirty.size(); ++i)
    if (!is_finite(dirty[i])) { EXPECT_TRUE(std::isnan(b.normals[i].x()) && std::isnan(b.curvature[i])) << i; }
  // The finite points get exactly the normals of the clean cloud (same neighbourhoods).
  for (std::size_t i = 0; i < clean.size(); ++i) {
    EXPECT_EQ(a.normals[i], b.normals[where[i]]) << i;
    EXPECT_EQ(a.curvature[i], b.curvature[where[i]]) << i;
  }
  // Fewer than 3 finite points: all NaN. All-NaN and empty clouds work.
  PointCloud few;
  few.points = {{0, 0, 0}, {kNaN, 0, 0}, {1, 0, 0}};
  estimate_normals(few, {});
  for (std::size_t i = 0; i < 3; ++i) EXPECT_TRUE(std::isnan(few.normals[i].x()) && std::isnan(few.curvature[i]));
  PointCloud nan;
  nan.points.assign(20, Eigen::Vector3f(kNaN, 1, 1));
  estimate_normals(nan, {});
  for (std::size_t i = 0; i < 20; ++i) EXPECT_TRUE(std::isnan(nan.normals[i].x()));
  PointCloud empty;
  EXPECT_NO_THROW(estimate_normals(empty, {}));
  EXPECT_TRUE(empty.normals.empty());
  // Three identical points: degenerate, NaN.
  PointCloud dup;
  dup.points.assign(3, Eigen::Vector3f(1, 1, 1));
  estimate_normals(dup, {});
  EXPECT_TRUE(std::isnan(dup.normals[0].x()));
}

TEST(Normals, OptionalCurvatureAndBadInput) {
  const auto pts = noisy_sphere(300, 6, 1.0f, 0.01f);
  const KdTree tree(pts);
  std::vector<Eigen::Vector3f> n1(pts.size()), n2(pts.size());
  std::vector<float> c(pts.size());
  estimate_normals(pts, tree, {}, n1, c);
  estimate_normals(pts, tree, {}, n2, {});  // curvature may be empty
  EXPECT_TRUE(test::bitwise_equal(n1, n2));
  const auto kInv = ErrorCode::kInvalidArgument;
  NormalSettings s;
  for (const int k : {2, 0, -1, 257}) {
    s.k = k;
    EXPECT_DUET_ERROR(estimate_normals(pts, tree, s, n1, c), kInv, "NormalSettings.k");
  }
  s = {};
  s.viewpoint.y() = kNaN;
  EXPECT_DUET_ERROR(estimate_normals(pts, tree, s, n1, c), kInv, "viewpoint");
  std::vector<Eigen::Vector3f> short_n(pts.size() - 1);
  EXPECT_DUET_ERROR(estimate_normals(pts, tree, {}, short_n, c), kInv, "normals");
  std::vector<float> short_c(5);
  EXPECT_DUET_ERROR(estimate_normals(pts, tree, {}, n1, short_c), kInv, "curvature");
  const KdTree other(test::random_points(10, 1));
  EXPECT_DUET_ERROR(estimate_normals(pts, other, {}, n1, c), kInv, "tree");
}

TEST(Normals, IdenticalWithOneAndTwoThreads) {
  PointCloud c;
  if (test::have_data("rgbd/slambook2_ch5/depth/2.pgm")) {
    const PointCloud raw = test::kFullSize ? test::slambook_cloud(2) : test::slambook_cloud_roi(2, 0, 0, 640, 240);
    voxel_filter(raw.points_view(), {}, {}, c);
  } else {
    c.points = noisy_sphere(60000, 8, 2.0f, 0.01f);
  }
  c.points.push_back(Eigen::Vector3f(kNaN, 0, 0));
  const auto run = [&] {
    PointCloud o;
    o.points = c.points;
    estimate_normals(o, {});
    return o;
  };
  const PointCloud a = test::in_arena(1, run);
  const PointCloud b = test::in_arena(2, run);
  EXPECT_GT(a.size(), 5000u);
  EXPECT_TRUE(test::bitwise_equal(a, b));
}

// ---- tests: PCL ----------------------------------------------------------------------------------

#ifdef DUET_HAVE_PCL
// duet vs pcl::NormalEstimation<PointXYZ, Normal> (k = 10, viewpoint 0): at least 99.5 % of the
// normals within 1 degree up to sign; curvature close.
void compare_normals_with_pcl(const std::vector<Eigen::Vector3f>& pts, const char* name) {
  const auto cloud = test::to_pcl_xyz(pts);
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
  ne.setInputCloud(cloud);
  ne.setSearchMethod(pcl::search::KdTree<pcl::PointXYZ>::Ptr(new pcl::search::KdTree<pcl::PointXYZ>));
  ne.setKSearch(10);
  pcl::PointCloud<pcl::Normal> ref;
  ne.compute(ref);
  ASSERT_EQ(ref.size(), pts.size());

  PointCloud c;
  c.points = pts;
  NormalSettings s;
  s.k = 10;
  estimate_normals(c, s);
  std::optional<KdTree> diag_tree;  // built only to diagnose disagreements
  std::size_t mismatch = 0, only_pcl = 0, only_duet = 0;

  std::size_t within = 0, compared = 0, same_side = 0, curv_close = 0;
  double max_curv = 0.0;
  std::vector<double> angles;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector3d r(ref[i].normal_x, ref[i].normal_y, ref[i].normal_z);
    const bool pcl_ok = std::isfinite(r.x());
    const bool duet_ok = is_finite(c.normals[i]);
    if (pcl_ok != duet_ok) {
      // Diagnose: the eigenvalues of the neighbourhood duet used.
      if (!diag_tree) diag_tree.emplace(pts);
      const KdTree& t = *diag_tree;
      std::uint32_t nb[10];
      float d2[10];
      const int cnt = t.knn(pts[i], 10, nb, d2);
      std::vector<std::uint32_t> v(nb, nb + cnt);
      const RefNormal rn = reference_normal(pts, v, pts[i], Eigen::Vector3f::Zero());
      Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (const auto j : v) mean += pts[j].cast<double>();
      mean /= cnt;
      for (const auto j : v) C += (pts[j].cast<double>() - mean) * (pts[j].cast<double>() - mean).transpose();
      const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(C / cnt).eigenvalues();
      (pcl_ok ? only_pcl : only_duet) += 1;
      if (++mismatch <= 3)
        ADD_FAILURE() << name << " point " << i << ": PCL normal finite " << pcl_ok << ", duet " << duet_ok << "; neighbourhood eigenvalues "
                      << ev.transpose() << ", distinct points " << [&] {
                           std::set<std::tuple<float, float, float>> u;
                           for (const auto j : v) u.insert({pts[j].x(), pts[j].y(), pts[j].z()});
                           return u.size();
                         }() << ", gap " << rn.gap;
      continue;
    }
    if (!pcl_ok) continue;
    ++compared;
    const Eigen::Vector3d n = c.normals[i].cast<double>();
    const double a = std::min(angle_deg(n, r), angle_deg(-n, r));
    angles.push_back(a);
    within += a <= 1.0 ? 1 : 0;
    same_side += n.dot(r) > 0.0 ? 1 : 0;
    const double dc = std::abs(static_cast<double>(c.curvature[i]) - ref[i].curvature);
    max_curv = std::max(max_curv, dc);
    curv_close += dc <= 1e-3 ? 1 : 0;
  }
  ASSERT_GT(compared, 0u);
  EXPECT_EQ(mismatch, 0u) << name << ": points where exactly one of PCL and duet has a normal";
  std::sort(angles.begin(), angles.end());
  const double pct = 100.0 * static_cast<double>(within) / static_cast<double>(compared);
  const double curv_pct = 100.0 * static_cast<double>(curv_close) / static_cast<double>(compared);
  std::printf("[ pcl      ] NormalEstimation k=10 %s: %zu points, %.3f %% within 1 deg of PCL (up to sign), median %.2e deg, "
              "99th pct %.3f deg, max %.2f deg; same orientation %.3f %%; curvature within 1e-3: %.3f %% (max diff %.3g); "
              "%zu points with a normal only from duet (PCL: NaN), %zu only from PCL\n",
              name, compared, pct, angles[angles.size() / 2], angles[angles.size() * 99 / 100], angles.back(),
              100.0 * static_cast<double>(same_side) / static_cast<double>(compared), curv_pct, max_curv, only_duet, only_pcl);
  EXPECT_GE(pct, 99.5) << name;
  EXPECT_GE(curv_pct, 99.0) << name;
}

TEST(NormalsPcl, Office1WithoutNaNs) {
  DUET_REQUIRE_DATA("pcl/office1.pcd");
  pcl::PointCloud<pcl::PointXYZ> c;
  ASSERT_EQ(pcl::io::loadPCDFile(test::data_path("pcl/office1.pcd").string(), c), 0);
  ASSERT_EQ(c.width, 640u);
  // Unoptimised builds: the central 320 x 240 part of the organized cloud (see kFullSize).
  const auto roi = test::kFullSize ? test::organized_roi(640, 0, 0, 640, 480) : test::organized_roi(640, 160, 120, 320, 240);
  std::vector<Eigen::Vector3f> pts;
  for (const auto i : roi) {
    const auto& p = c[i];
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) pts.emplace_back(p.x, p.y, p.z);
  }
  ASSERT_GT(pts.size(), test::full_or<std::size_t>(200000, 40000));
  compare_normals_with_pcl(pts, test::kFullSize ? "office1.pcd (NaNs removed)" : "office1.pcd central 320x240 (NaNs removed)");
}

TEST(NormalsPcl, Bunny) {
  DUET_REQUIRE_DATA("pcl/bun0.pcd");
  compare_normals_with_pcl(test::load_pcd("pcl/bun0.pcd", false).points, "bun0.pcd");
}

TEST(NormalsPcl, VoxelFilteredSlambookFrame) {
  DUET_REQUIRE_DATA("rgbd/slambook2_ch5/depth/1.pgm");
  const PointCloud raw = test::slambook_cloud(1);
  PointCloud c;
  voxel_filter(raw.points_view(), {}, {}, c);  // 0.05 m
  compare_normals_with_pcl(c.points, "slambook2 frame 1, voxel 0.05");
}
#endif

}  // namespace test_normals
}  // namespace duet
