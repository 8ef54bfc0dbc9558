// voxel_filter vs a std::map reference using PCL's voxel formula, and vs pcl::VoxelGrid on real
// clouds; NaN, empty, one point, huge coordinates, min_points_per_voxel, in-place, strided input,
// thread-count independence.
#include "kernel_test_util.hpp"

#include <duet/kernels/error.hpp>
#include <duet/kernels/voxel_filter.hpp>

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <limits>

#include <array>
#include <atomic>
#include <chrono>
#include <thread>
#include <cstdio>
#include <cstring>
#include <map>
#include <random>
#include <vector>

#ifdef DUET_HAVE_PCL
#include <pcl/filters/voxel_grid.h>
#endif

namespace duet {
namespace test_voxel_filter {

using test::kInf;
using test::kNaN;

// ---- reference -----------------------------------------------------------------------------------

// Serial reference: voxel of p = floor(p * (1 / leaf)) per axis in float (pcl::VoxelGrid), voxels in
// (z, y, x) order via std::map, centroid from double sums in input order, rounded mean colour.
PointCloud reference_voxel(PointsView pts, ColorsView cols, float leaf, std::uint32_t min_points = 1) {
  struct Acc {
    double x = 0, y = 0, z = 0;
    std::uint64_t r = 0, g = 0, b = 0, n = 0;
  };
  const float inv = 1.0f / leaf;
  std::map<std::array<std::int64_t, 3>, Acc> voxels;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector3f p = pts[i];
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z())) continue;
    const float fx = p.x() * inv, fy = p.y() * inv, fz = p.z() * inv;
    const std::array<std::int64_t, 3> key{static_cast<std::int64_t>(std::floor(fz)), static_cast<std::int64_t>(std::floor(fy)),
                                          static_cast<std::int64_t>(std::floor(fx))};
    Acc& a = voxels[key];
    a.x += p.x();
    a.y += p.y();
    a.z += p.z();
    if (!cols.empty()) {
      const Rgb8 c = cols[i];
      a.r += c.r;
      a.g += c.g;
      a.b += c.b;
    }
    ++a.n;
  }
  PointCloud out;
  for (const auto& [key, a] : voxels) {
    if (a.n < min_points) continue;
    const double n = static_cast<double>(a.n);
    out.points.emplace_back(static_cast<float>(a.x / n), static_cast<float>(a.y / n), static_cast<float>(a.z / n));
    if (!cols.empty())
      out.colors.push_back(Rgb8{static_cast<std::uint8_t>((a.r + a.n / 2) / a.n), static_cast<std::uint8_t>((a.g + a.n / 2) / a.n),
                                static_cast<std::uint8_t>((a.b + a.n / 2) / a.n)});
  }
  return out;
}

// Expects identical voxel sets and order; centroids to float round-off, colours exactly.
void expect_matches_reference(const PointCloud& got, const PointCloud& ref) {
  ASSERT_EQ(got.size(), ref.size());
  ASSERT_EQ(got.colors.size(), ref.colors.size());
  EXPECT_TRUE(got.normals.empty());
  EXPECT_TRUE(got.curvature.empty());
  std::size_t bad = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const float tol = 1e-6f * (1.0f + ref.points[i].cwiseAbs().maxCoeff());
    const bool ok = (got.points[i] - ref.points[i]).cwiseAbs().maxCoeff() <= tol &&
                    (ref.colors.empty() || got.colors[i] == ref.colors[i]);
    if (!ok && ++bad <= 5)
      ADD_FAILURE() << "voxel " << i << ": got (" << got.points[i].transpose() << "), expected (" << ref.points[i].transpose() << ")";
  }
  EXPECT_EQ(bad, 0u);
}

PointCloud filter(PointsView p, ColorsView c, float leaf, std::uint32_t min_points = 1) {
  VoxelFilterSettings s;
  s.leaf_size_m = leaf;
  s.min_points_per_voxel = min_points;
  PointCloud out;
  voxel_filter(p, c, s, out);
  return out;
}

// A cloud of `n` random points in a box with some NaN/inf points and quantised (voxel-boundary)
// coordinates mixed in.
PointCloud random_cloud(std::size_t n, std::uint32_t seed, float lo, float hi, float leaf) {
  PointCloud c;
  c.points = test::random_points(n, seed, lo, hi);
  c.colors = test::random_colors(n, seed + 1);
  std::mt19937 rng(seed + 2);
  std::uniform_int_distribution<int> pick(0, 9);
  for (std::size_t i = 0; i < n; ++i) {
    const int k = pick(rng);
    if (k == 0) c.points[i].y() = kNaN;
    if (k == 1) c.points[i].x() = (i % 2) ? kInf : -kInf;
    if (k == 2)  // exactly on a voxel boundary (as far as float allows)
      c.points[i] = (c.points[i] / leaf).array().round().matrix() * leaf;
    if (k == 3 && i > 0) c.points[i] = c.points[i - 1];  // duplicates
  }
  return c;
}

// ---- tests: reference ----------------------------------------------------------------------------

TEST(VoxelFilter, MatchesReferenceOnRandomClouds) {
  struct Case {
    std::size_t n;
    float lo, hi, leaf;
  };
  for (const Case& k : {Case{1000, -1.0f, 1.0f, 0.05f}, Case{50000, -3.0f, 7.0f, 0.05f}, Case{50000, -0.5f, 0.5f, 0.1f},
                        Case{20000, 100.0f, 110.0f, 0.01f}, Case{30000, -20.0f, 20.0f, 0.37f},
                        Case{100000, -2.0f, 2.0f, 0.02f}}) {
    SCOPED_TRACE("n " + std::to_string(k.n) + " leaf " + std::to_string(k.leaf) + " box " + std::to_string(k.lo));
    const PointCloud c = random_cloud(k.n, static_cast<std::uint32_t>(k.n) + 7, k.lo, k.hi, k.leaf);
    expect_matches_reference(filter(c.points_view(), c.colors_view(), k.leaf),
                             reference_voxel(c.points_view(), c.colors_view(), k.leaf));
    // Without colour.
    const PointCloud nc = filter(c.points_view(), {}, k.leaf);
    EXPECT_TRUE(nc.colors.empty());
    expect_matches_reference(nc, reference_voxel(c.points_view(), {}, k.leaf));
  }
}

TEST(VoxelFilter, MinPointsPerVoxel) {
  const PointCloud c = random_cloud(40000, 11, -1.0f, 1.0f, 0.1f);
  for (const std::uint32_t m : {1u, 2u, 3u, 10u, 40u, 1000000u}) {
    SCOPED_TRACE("min_points_per_voxel " + std::to_string(m));
    const PointCloud got = filter(c.points_view(), c.colors_view(), 0.1f, m);
    expect_matches_reference(got, reference_voxel(c.points_view(), c.colors_view(), 0.1f, m));
    if (m == 1000000u) { EXPECT_TRUE(got.empty()); }
  }
}

TEST(VoxelFilter, EmptyAllNaNAndOnePoint) {
  PointCloud out;
  out.points.assign(2, Eigen::Vector3f::Ones());
  out.colors.assign(2, Rgb8{9, 9, 9});
  out.normals.assign(2, Eigen::Vector3f::UnitX());
  out.curvature.assign(2, 1.0f);
  VoxelFilterSettings s;
  voxel_filter(PointsView(), ColorsView(), s, out);
  EXPECT_TRUE(out.empty());
  EXPECT_TRUE(out.colors.empty());
  EXPECT_TRUE(out.normals.empty());
  EXPECT_TRUE(out.curvature.empty());

  const std::vector<Eigen::Vector3f> nan(100, Eigen::Vector3f(kNaN, kNaN, kNaN));
  const std::vector<Eigen::Vector3f> mixed{{kNaN, 0, 0}, {0, kInf, 0}, {0, 0, -kInf}};
  const std::vector<Rgb8> cols(100, Rgb8{1, 2, 3});
  out.points.assign(2, Eigen::Vector3f::Ones());
  voxel_filter(nan, cols, s, out);
  EXPECT_TRUE(out.empty());
  voxel_filter(mixed, {}, s, out);
  EXPECT_TRUE(out.empty());

  const std::vector<Eigen::Vector3f> one{{1.23456f, -7.5f, 0.049999f}};
  const std::vector<Rgb8> one_c{{10, 20, 30}};
  voxel_filter(one, one_c, s, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out.points[0], one[0]);
  EXPECT_EQ(out.colors[0], one_c[0]);
  // One finite point among NaNs.
  std::vector<Eigen::Vector3f> some = nan;
  some[57] = Eigen::Vector3f(-3.0f, 2.0f, 1.0f);
  voxel_filter(some, cols, s, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out.points[0], some[57]);
}

TEST(VoxelFilter, KnownCentroidsAndColours) {
  // Two points in voxel (0,0,0), three in voxel (1,0,0) at leaf 1; order z, y, x.
  const std::vector<Eigen::Vector3f> p{{1.5f, 0.5f, 0.5f}, {0.2f, 0.2f, 0.2f}, {1.1f, 0.1f, 0.9f}, {0.4f, 0.6f, 0.8f},
                                       {1.9f, 0.3f, 0.1f}, {0.5f, 0.5f, -0.5f}};
  const std::vector<Rgb8> c{{0, 0, 0}, {100, 0, 255}, {1, 1, 1}, {101, 255, 0}, {2, 2, 3}, {7, 7, 7}};
  const PointCloud out = filter(p, c, 1.0f);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out.points[0], Eigen::Vector3f(0.5f, 0.5f, -0.5f));  // z index -1 first
  EXPECT_TRUE(out.points[1].isApprox(Eigen::Vector3f(0.3f, 0.4f, 0.5f)));
  EXPECT_TRUE(out.points[2].isApprox(Eigen::Vector3f(1.5f, 0.3f, 0.5f)));
  EXPECT_EQ(out.colors[1], (Rgb8{101, 128, 128}));  // (100+101)/2 = 100.5 -> 101, 127.5 -> 128
  EXPECT_EQ(out.colors[2], (Rgb8{1, 1, 1}));        // (0+1+2)/3 = 1, (0+1+3)/3 = 1.33 -> 1
}

TEST(VoxelFilter, HugeCoordinatesThrowOutOfRange) {
  VoxelFilterSettings s;
  PointCloud out;
  const auto kOut = ErrorCode::kOutOfRange;
  std::vector<Eigen::Vector3f> p{{0, 0, 0}, {1e30f, 0, 0}};
  EXPECT_DUET_ERROR(voxel_filter(p, {}, s, out), kOut, "too large");
  p = {{0, 0, 0}, {0, 0, -1e30f}};
  EXPECT_DUET_ERROR(voxel_filter(p, {}, s, out), kOut, "axis z");
  p = {{3.4e38f, 3.4e38f, 3.4e38f}};
  EXPECT_DUET_ERROR(voxel_filter(p, {}, s, out), kOut, "voxel");
  s.leaf_size_m = 0.01f;
  p = {{1e8f, 0, 0}};  // 1e10 voxels from the origin
  EXPECT_DUET_ERROR(voxel_filter(p, {}, s, out), kOut, "leaf");
  p = {{0, -1e8f, 0}, {0, 0, 0}};
  EXPECT_DUET_ERROR(voxel_filter(p, {}, s, out), kOut, "axis y");
  // Each coordinate fits, but the bounding box holds ~8e27 > 2^63 voxels.
  p = {{-1e7f, -1e7f, -1e7f}, {1e7f, 1e7f, 1e7f}};
  EXPECT_DUET_ERROR(voxel_filter(p, {}, s, out), kOut, "2^63");
  // A tiny leaf makes ordinary coordinates overflow too.
  s.leaf_size_m = 1e-9f;
  p = {{5.0f, 0, 0}};
  EXPECT_DUET_ERROR(voxel_filter(p, {}, s, out), kOut, "voxel");
}

TEST(VoxelFilter, PartlyNaNPointWithAHugeCoordinateIsSkippedNotAnError) {
  // The point is skipped (it is not finite), so its huge y must not trigger the range error.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<Eigen::Vector3f> p{{nan, 1e30f, 0.0f}, {0.01f, 0.01f, 0.01f}, {0.02f, 0.02f, 0.02f},
                                       {0.0f, -1e30f, nan}, {-std::numeric_limits<float>::infinity(), 0, 0}};
  PointCloud out;
  voxel_filter(p, {}, {}, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_NEAR(out.points[0].x(), 0.015f, 1e-7f);
}

TEST(VoxelFilter, LargeButRepresentableCoordinatesAreExact) {
  // |p / leaf| up to 2e9 (< 2^31) with a 2e9-voxel spread on x: must match the reference.
  std::vector<Eigen::Vector3f> p{{-1e7f, 0.0f, 0.0f}, {1e7f, 0.5f, 0.0f}, {1e7f, 0.5f, 0.001f}, {-1e7f, 0.0f, 0.009f},
                                 {2e7f, 3.0f, -4.0f}, {0.0f, 0.0f, 0.0f}};
  const std::vector<Rgb8> c = test::random_colors(p.size(), 3);
  const PointCloud got = filter(p, c, 0.01f);
  expect_matches_reference(got, reference_voxel(p, c, 0.01f));
  EXPECT_EQ(got.size(), 4u);
  // Far from the origin with a normal leaf: a cloud around (1e5, -1e5, 50) m.
  std::vector<Eigen::Vector3f> q = test::random_points(20000, 5, -2.0f, 2.0f);
  for (auto& x : q) x += Eigen::Vector3f(1e5f, -1e5f, 50.0f);
  expect_matches_reference(filter(q, {}, 0.05f), reference_voxel(q, {}, 0.05f));
}

TEST(VoxelFilter, InPlaceCall) {
  PointCloud c = random_cloud(30000, 21, -2.0f, 2.0f, 0.05f);
  const PointCloud expected = filter(c.points_view(), c.colors_view(), 0.05f);
  VoxelFilterSettings s;
  VoxelFilterWorkspace ws;
  voxel_filter(c.points_view(), c.colors_view(), s, ws, c);  // out is the viewed cloud
  EXPECT_TRUE(test::bitwise_equal(c, expected));
  // In place without colour, and viewing only a tail part of the cloud.
  PointCloud d = random_cloud(30000, 22, -2.0f, 2.0f, 0.05f);
  d.colors.clear();
  const PointsView tail(d.points[1000].data(), d.size() - 1000, sizeof(Eigen::Vector3f));
  const PointCloud expected_tail = reference_voxel(tail, {}, 0.05f);
  voxel_filter(tail, {}, s, ws, d);
  expect_matches_reference(d, expected_tail);
}

TEST(VoxelFilter, StridedInputInsideA32ByteStruct) {
  struct alignas(16) Rec {
    float x, y, z, intensity;
    std::uint8_t rgb[3];
    std::uint8_t pad[13];
  };
  static_assert(sizeof(Rec) == 32);
  const PointCloud c = random_cloud(20000, 31, -1.0f, 1.0f, 0.05f);
  std::vector<Rec> recs(c.size());
  for (std::size_t i = 0; i < c.size(); ++i) {
    recs[i] = Rec{c.points[i].x(), c.points[i].y(), c.points[i].z(), 99.0f, {c.colors[i].r, c.colors[i].g, c.colors[i].b}, {}};
    std::memset(recs[i].pad, 0xAB, sizeof(recs[i].pad));
  }
  const PointsView pv(&recs[0].x, recs.size(), sizeof(Rec));
  const ColorsView cv(recs[0].rgb, recs.size(), sizeof(Rec));
  const PointCloud got = filter(pv, cv, 0.05f);
  EXPECT_TRUE(test::bitwise_equal(got, filter(c.points_view(), c.colors_view(), 0.05f)));
  expect_matches_reference(got, reference_voxel(c.points_view(), c.colors_view(), 0.05f));
}

TEST(VoxelFilter, LongRunsAcrossChunkAndBlockBoundaries) {
  // Organised-like input: long runs of consecutive points in one voxel (as neighbouring pixels
  // give), runs that cross the 2048-point chunks and 32768-point blocks, voxels revisited
  // after other voxels, single-point runs, and NaN points inside runs.
  std::mt19937 rng(77);
  std::uniform_real_distribution<float> jitter(0.0f, 0.049f);
  std::uniform_int_distribution<int> run_len(1, 5000), cell(-3, 3);
  std::vector<Eigen::Vector3f> p;
  while (p.size() < 120000) {
    const Eigen::Vector3f base(0.05f * static_cast<float>(cell(rng)), 0.05f * static_cast<float>(cell(rng)),
                               0.05f * static_cast<float>(cell(rng)));
    const int len = p.size() % 3 == 0 ? 1 : run_len(rng);
    for (int i = 0; i < len; ++i) {
      p.push_back(base + Eigen::Vector3f(jitter(rng), jitter(rng), jitter(rng)) * 0.5f + Eigen::Vector3f::Constant(0.001f));
      if (i % 997 == 5) p.emplace_back(kNaN, 0.0f, 0.0f);
    }
  }
  const std::vector<Rgb8> c = test::random_colors(p.size(), 78);
  expect_matches_reference(filter(p, c, 0.05f), reference_voxel(p, c, 0.05f));
}

TEST(VoxelFilter, OverlappingAndZeroStrides) {
  // Strides below 12 bytes (overlapping points) and 0 (one point repeated): the 16-byte vector
  // loads must stay inside the view, and the result must match the reference.
  std::vector<float> raw(4000);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (auto& v : raw) v = u(rng);
  for (const std::size_t stride : {std::size_t{0}, std::size_t{4}, std::size_t{8}, std::size_t{12}}) {
    const std::size_t n = stride == 0 ? 500 : (raw.size() * sizeof(float) - 12) / stride + 1;
    // A copy of exactly the bytes the view covers, so reading past them would be caught by ASan.
    const std::size_t bytes = (n - 1) * stride + 12;
    std::vector<float> exact(bytes / sizeof(float));
    std::memcpy(exact.data(), raw.data(), bytes);
    const PointsView pv(exact.data(), n, stride);
    expect_matches_reference(filter(pv, {}, 0.1f), reference_voxel(pv, {}, 0.1f));
  }
}

TEST(VoxelFilter, IndexRangeLimitIsTwoToThe31) {
  // |p / leaf| up to the largest float below 2^31 is a valid voxel index; 2^31 is not.
  VoxelFilterSettings s;
  s.leaf_size_m = 1.0f;
  PointCloud out;
  const std::vector<Eigen::Vector3f> ok{{2147483520.0f, 0, 0}, {-2147483520.0f, 1.5f, 0}};
  voxel_filter(ok, {}, s, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out.points[0], ok[0]);  // (y, x) order: y = 0 first
  EXPECT_EQ(out.points[1], ok[1]);
  const std::vector<Eigen::Vector3f> bad{{0, 0, 0}, {0, 2147483648.0f, 0}};
  EXPECT_DUET_ERROR(voxel_filter(bad, {}, s, out), ErrorCode::kOutOfRange, "axis y");
  const std::vector<Eigen::Vector3f> bad_neg{{0, 0, -2147483648.0f}};
  EXPECT_DUET_ERROR(voxel_filter(bad_neg, {}, s, out), ErrorCode::kOutOfRange, "axis z");
}

TEST(VoxelFilter, WorkspaceReuse) {
  VoxelFilterWorkspace ws;
  VoxelFilterSettings s;
  for (std::uint32_t seed = 40; seed < 44; ++seed) {
    const PointCloud c = random_cloud(5000 + 7000 * (seed % 3), seed, -1.0f, 1.0f + static_cast<float>(seed % 2), 0.05f);
    PointCloud a, b;
    voxel_filter(c.points_view(), c.colors_view(), s, ws, a);
    voxel_filter(c.points_view(), c.colors_view(), s, b);
    EXPECT_TRUE(test::bitwise_equal(a, b));
  }
}

TEST(VoxelFilter, BadInputThrowsInvalidArgument) {
  const std::vector<Eigen::Vector3f> p = test::random_points(10, 1);
  const std::vector<Rgb8> c = test::random_colors(9, 1);
  PointCloud out;
  const auto kInv = ErrorCode::kInvalidArgument;
  EXPECT_DUET_ERROR(voxel_filter(p, c, {}, out), kInv, "colours");
  VoxelFilterSettings s;
  for (const float leaf : {0.0f, -0.05f, kNaN, kInf}) {
    s.leaf_size_m = leaf;
    EXPECT_DUET_ERROR(voxel_filter(p, {}, s, out), kInv, "leaf_size_m");
  }
  s = {};
  s.min_points_per_voxel = 0;
  EXPECT_DUET_ERROR(voxel_filter(p, {}, s, out), kInv, "min_points_per_voxel");
  EXPECT_DUET_ERROR(validate(s), kInv, "min_points_per_voxel");
}

TEST(VoxelFilter, IdenticalWithOneAndTwoThreads) {
  PointCloud c = random_cloud(300000, 51, -4.0f, 4.0f, 0.05f);
  if (test::have_data("rgbd/slambook2_ch5/depth/3.pgm")) c = test::slambook_cloud(3);
  for (const std::uint32_t m : {1u, 3u}) {
    VoxelFilterSettings s;
    s.min_points_per_voxel = m;
    const PointCloud a = test::in_arena(1, [&] {
      PointCloud o;
      voxel_filter(c.points_view(), c.colors_view(), s, o);
      return o;
    });
    const PointCloud b = test::in_arena(2, [&] {
      PointCloud o;
      voxel_filter(c.points_view(), c.colors_view(), s, o);
      return o;
    });
    EXPECT_GT(a.size(), 1000u);
    EXPECT_TRUE(test::bitwise_equal(a, b));
  }
}

// oneTBB gives an arena with a reserved slot at least two slots, the second for a worker that
// runs work enqueued into it: a call into a one-thread arena whose one thread is busy runs on
// that worker, at thread index 1, although max_concurrency() is 1. The C API met this (a
// device of threads=1: duet_runtime_save while another thread converted a grid): the
// per-thread tables were sized by max_concurrency() and index 1 wrote past them (a SIGSEGV in
// the ROS node under ThreadSanitizer, CI stop 50).
TEST(VoxelFilter, RunsOnTheSecondSlotOfAOneThreadArena) {
  const PointCloud c = random_cloud(100000, 61, -2.0f, 2.0f, 0.05f);
  const VoxelFilterSettings s;
  PointCloud expected;
  voxel_filter(c.points_view(), c.colors_view(), s, expected);
  tbb::task_arena arena(1);
  std::atomic<bool> inside{false}, release{false}, done{false};
  std::thread busy([&] {
    arena.execute([&] {
      inside = true;
      while (!release) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    });
  });
  while (!inside) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  int index = -1;
  PointCloud out;
  VoxelFilterWorkspace ws;  // fresh: its tables are sized by this call
  std::thread caller([&] {
    arena.execute([&] {
      index = tbb::this_task_arena::current_thread_index();
      voxel_filter(c.points_view(), c.colors_view(), s, ws, out);
    });
    done = true;
  });
  // The busy thread is let go after 20 s at the latest, should the call wait for it after all.
  for (int i = 0; i < 20000 && !done; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  const bool ran_beside_busy = done.load();
  release = true;
  caller.join();
  busy.join();
  EXPECT_TRUE(ran_beside_busy) << "the call waited for the arena's busy thread";
  EXPECT_EQ(index, 1) << "the call ran at thread index " << index << ", not the arena's second slot";
  EXPECT_GT(out.size(), 1000u);
  EXPECT_TRUE(test::bitwise_equal(out, expected));
}

TEST(VoxelFilter, RealSlambookFrameMatchesReference) {
  DUET_REQUIRE_DATA("rgbd/slambook2_ch5/depth/1.pgm");
  const PointCloud c = test::slambook_cloud(1);
  for (const float leaf : {0.01f, 0.05f}) {
    const PointCloud got = filter(c.points_view(), c.colors_view(), leaf);
    expect_matches_reference(got, reference_voxel(c.points_view(), c.colors_view(), leaf));
  }
}

// ---- tests: PCL ----------------------------------------------------------------------------------

#ifdef DUET_HAVE_PCL
// Runs pcl::VoxelGrid<PointXYZRGB> and duet (reading the PCL cloud in place, 32-byte stride) and
// compares: same voxel count, same order, centroids within 1e-5 m, colours within +-1.
void compare_with_pcl(const pcl::PointCloud<pcl::PointXYZRGB>::Ptr& in, const char* name, float leaf = 0.05f,
                      std::uint32_t min_points = 1) {
  pcl::VoxelGrid<pcl::PointXYZRGB> vg;
  vg.setInputCloud(in);
  vg.setLeafSize(leaf, leaf, leaf);
  vg.setMinimumPointsNumberPerVoxel(min_points);
  pcl::PointCloud<pcl::PointXYZRGB> ref;
  vg.filter(ref);

  // PCL's rgb is packed as b, g, r bytes: give duet a plain colour array.
  std::vector<Rgb8> cols(in->size());
  for (std::size_t i = 0; i < in->size(); ++i) cols[i] = Rgb8{(*in)[i].r, (*in)[i].g, (*in)[i].b};
  const PointsView pv(&(*in)[0].x, in->size(), sizeof(pcl::PointXYZRGB));
  const PointCloud got = filter(pv, cols, leaf, min_points);

  ASSERT_EQ(got.size(), ref.size()) << name;
  float max_diff = 0.0f;
  int max_cdiff = 0;
  std::size_t far = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const Eigen::Vector3f r(ref[i].x, ref[i].y, ref[i].z);
    const float d = (got.points[i] - r).cwiseAbs().maxCoeff();
    max_diff = std::max(max_diff, d);
    if (!(d <= 1e-5f) && ++far <= 5)
      ADD_FAILURE() << name << " voxel " << i << ": duet (" << got.points[i].transpose() << ") pcl (" << r.transpose() << ")";
    max_cdiff = std::max({max_cdiff, std::abs(got.colors[i].r - ref[i].r), std::abs(got.colors[i].g - ref[i].g),
                          std::abs(got.colors[i].b - ref[i].b)});
  }
  EXPECT_EQ(far, 0u) << name;
  EXPECT_LE(max_cdiff, 1) << name;
  std::printf("[ pcl      ] VoxelGrid %s leaf %.2f min %u: %zu -> %zu voxels (same count and order), max centroid diff %.3g m, "
              "max colour diff %d\n",
              name, static_cast<double>(leaf), min_points, in->size(), ref.size(), static_cast<double>(max_diff), max_cdiff);
}

TEST(VoxelFilterPcl, Office1) {
  DUET_REQUIRE_DATA("pcl/office1.pcd");
  pcl::PointCloud<pcl::PointXYZRGB>::Ptr c(new pcl::PointCloud<pcl::PointXYZRGB>);
  ASSERT_EQ(pcl::io::loadPCDFile(test::data_path("pcl/office1.pcd").string(), *c), 0);
  ASSERT_FALSE(c->is_dense);  // has NaNs: they must be skipped by both
  compare_with_pcl(c, "office1.pcd");
  compare_with_pcl(c, "office1.pcd", 0.05f, 5);
  compare_with_pcl(c, "office1.pcd", 0.02f);
}

TEST(VoxelFilterPcl, TableSceneMug) {
  DUET_REQUIRE_DATA("pcl/table_scene_mug_stereo_textured.pcd");
  pcl::PointCloud<pcl::PointXYZRGB>::Ptr c(new pcl::PointCloud<pcl::PointXYZRGB>);
  ASSERT_EQ(pcl::io::loadPCDFile(test::data_path("pcl/table_scene_mug_stereo_textured.pcd").string(), *c), 0);
  compare_with_pcl(c, "table_scene_mug_stereo_textured.pcd");
  compare_with_pcl(c, "table_scene_mug_stereo_textured.pcd", 0.01f);
}

TEST(VoxelFilterPcl, BackProjectedSlambookFrame) {
  DUET_REQUIRE_DATA("rgbd/slambook2_ch5/depth/1.pgm");
  for (const int i : {1, 4}) {
    const test::RgbdFrame f = test::load_slambook_frame(i);
    PointCloud c = test::slambook_cloud(i);
    c.transform(f.T_world_camera);  // in the world frame, like the mapper's global cloud
    compare_with_pcl(test::to_pcl_rgb(c), ("slambook2 frame " + std::to_string(i)).c_str());
  }
}
#endif

}  // namespace test_voxel_filter
}  // namespace duet
