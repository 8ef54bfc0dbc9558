// Results through the C API equal the C++ kernels' on the same inputs (fixed seeds), strided
// input equals packed input, and the device's thread count does not change any result.
#include "capi_helpers.hpp"

#include <duet/kernels/back_projection.hpp>
#include <duet/kernels/clustering.hpp>
#include <duet/kernels/grid.hpp>
#include <duet/kernels/normals.hpp>
#include <duet/kernels/segmentation.hpp>
#include <duet/kernels/voxel_filter.hpp>
#include <duet/kernels/scan_match.hpp>

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

using namespace duet_capi_test;

namespace {

duet::PointsView view_of(const std::vector<float>& xyz) {
  return duet::PointsView(xyz.data(), xyz.size() / 3);
}

std::vector<float> cloud_points(duet_cloud c) {
  std::vector<float> out(3 * duet_cloud_get_size(c));
  duet_cloud_copy_points(c, out.data(), 0, out.size() / 3);
  return out;
}

std::vector<float> flat(const std::vector<Eigen::Vector3f>& v) {
  std::vector<float> out;
  out.reserve(3 * v.size());
  for (const auto& p : v) out.insert(out.end(), {p.x(), p.y(), p.z()});
  return out;
}

std::vector<Record> to_records(const std::vector<float>& xyz, const std::vector<std::uint8_t>* rgb) {
  std::vector<Record> r(xyz.size() / 3);
  for (std::size_t i = 0; i < r.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      r[i].xyz[k] = xyz[3 * i + k];
      r[i].normal[k] = -7.0f;
      r[i].rgb[k] = rgb != nullptr ? (*rgb)[3 * i + k] : 0;
    }
    r[i].label = 0xEE;
    r[i].cluster = 0xDEADBEEF;
  }
  return r;
}

/// The C++ labels of euclidean_clusters as the C API encodes them.
std::vector<std::uint32_t> cpp_cluster_labels(const std::vector<float>& xyz,
                                              const duet::ClusteringSettings& s, std::size_t* count) {
  const auto clusters = duet::euclidean_clusters(view_of(xyz), {}, s);
  std::vector<std::uint32_t> labels(xyz.size() / 3, DUET_UNCLUSTERED);
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    for (auto i : clusters[c]) labels[i] = static_cast<std::uint32_t>(c);
  }
  *count = clusters.size();
  return labels;
}

}  // namespace

// ---- settings and helpers -------------------------------------------------------------------

TEST(CapiSettings, InitFunctionsMirrorTheCppDefaults) {
  duet_back_projection_settings bp;
  duet_back_projection_settings_init(&bp);
  const duet::BackProjectionSettings cbp;
  EXPECT_EQ(bp.min_depth_m, cbp.min_depth_m);
  EXPECT_EQ(bp.max_depth_m, cbp.max_depth_m);
  EXPECT_EQ(bp.pixel_step, cbp.pixel_step);

  duet_scan_match_settings sm;
  duet_scan_match_settings_init(&sm);
  const duet::ScanMatchSettings csm;
  EXPECT_EQ(sm.linear_window_m, csm.linear_window_m);
  EXPECT_EQ(sm.angular_window_deg, csm.angular_window_deg);
  EXPECT_EQ(sm.linear_step_m, csm.linear_step_m);
  EXPECT_EQ(sm.angular_step_deg, csm.angular_step_deg);
  EXPECT_EQ(sm.sigma_m, csm.sigma_m);
  EXPECT_EQ(sm.max_distance_m, csm.max_distance_m);
  EXPECT_EQ(sm.prior_sigma_m, csm.prior_sigma_m);
  EXPECT_EQ(sm.prior_sigma_deg, csm.prior_sigma_deg);
  EXPECT_EQ(sm.min_points, csm.min_points);
  EXPECT_EQ(sm.min_score, csm.min_score);

  duet_voxel_filter_settings vf;
  duet_voxel_filter_settings_init(&vf);
  EXPECT_EQ(vf.leaf_size_m, duet::VoxelFilterSettings{}.leaf_size_m);
  EXPECT_EQ(vf.min_points_per_voxel, duet::VoxelFilterSettings{}.min_points_per_voxel);

  duet_normal_settings ns;
  duet_normal_settings_init(&ns);
  EXPECT_EQ(ns.k, duet::NormalSettings{}.k);
  EXPECT_EQ(ns.viewpoint[2], duet::NormalSettings{}.viewpoint.z());

  duet_clustering_settings cs;
  duet_clustering_settings_init(&cs);
  EXPECT_EQ(cs.tolerance_m, duet::ClusteringSettings{}.tolerance_m);
  EXPECT_EQ(cs.min_size, duet::ClusteringSettings{}.min_size);
  EXPECT_EQ(cs.max_size, duet::ClusteringSettings{}.max_size);

  duet_segmentation_settings ss;
  duet_segmentation_settings_init(&ss);
  const duet::SegmentationSettings css;
  EXPECT_EQ(ss.floor_z_m, css.floor_z_m);
  EXPECT_EQ(ss.max_floor_tilt_deg, css.max_floor_tilt_deg);
  EXPECT_EQ(ss.floor_height_threshold_m, css.floor_height_threshold_m);
  EXPECT_EQ(ss.min_height_m, css.min_height_m);
  EXPECT_EQ(ss.max_height_m, css.max_height_m);
  EXPECT_EQ(ss.clustering.tolerance_m, css.clustering.tolerance_m);
  EXPECT_EQ(ss.clustering.min_size, css.clustering.min_size);
  EXPECT_EQ(ss.clustering.max_size, css.clustering.max_size);

  duet_grid_update_settings gs;
  duet_grid_update_settings_init(&gs);
  const duet::GridUpdateSettings cgs;
  EXPECT_EQ(gs.hit_logodds, cgs.hit_logodds);
  EXPECT_EQ(gs.miss_logodds, cgs.miss_logodds);
  EXPECT_EQ(gs.min_logodds, cgs.min_logodds);
  EXPECT_EQ(gs.max_logodds, cgs.max_logodds);
  EXPECT_EQ(gs.clear_along_rays, cgs.clear_along_rays ? 1 : 0);
  EXPECT_EQ(gs.max_ray_length_m, cgs.max_ray_length_m);
  EXPECT_EQ(gs.grow_margin_cells, cgs.grow_margin_cells);

  duet_sensor_frame f;
  duet_sensor_frame_init(&f);
  const duet::SensorFrame cf;
  EXPECT_EQ(f.width, 0);  // the size must be set (issue 20: 640x480 was over-read when forgotten)
  EXPECT_EQ(f.height, 0);
  EXPECT_EQ(f.fx, cf.intrinsics.fx);
  EXPECT_EQ(f.cy, cf.intrinsics.cy);
  EXPECT_EQ(f.depth_units_per_m, cf.depth.depth_units_per_m);
  EXPECT_EQ(f.depth, nullptr);
  EXPECT_EQ(f.color, nullptr);
  for (int i = 0; i < 16; ++i) EXPECT_EQ(f.T_robot_camera[i], (i % 5 == 0) ? 1.0f : 0.0f) << i;
}

TEST(CapiSettings, CameraMountMatrixFollowsEq6) {
  float m[16];
  // Sensor 1: facing forward. Optical z = robot x, optical x = -robot y, optical y = -robot z.
  duet_camera_mount_matrix(-0.118f, 0.0f, 0.271f, 0.0f, 0.0f, 0.0f, m);
  const float s1[16] = {0, -1, 0, 0, /**/ 0, 0, -1, 0, /**/ 1, 0, 0, 0, /**/ -0.118f, 0, 0.271f, 1};
  for (int i = 0; i < 16; ++i) EXPECT_NEAR(m[i], s1[i], 1e-6f) << i;
  // Sensor 2: yawed -90 deg, facing right (-y): optical z = -robot y, optical x = -robot x.
  duet_camera_mount_matrix(-0.118f, 0.0f, 0.481f, static_cast<float>(-M_PI / 2), 0.0f, 0.0f, m);
  const float s2[16] = {-1, 0, 0, 0, /**/ 0, 0, -1, 0, /**/ 0, -1, 0, 0, /**/ -0.118f, 0, 0.481f, 1};
  for (int i = 0; i < 16; ++i) EXPECT_NEAR(m[i], s2[i], 1e-6f) << i;
  // A pitched-down camera (pitch about +y tilts forward axis down): optical z gains -z.
  duet_camera_mount_matrix(0, 0, 1, 0, 0.3f, 0, m);
  EXPECT_NEAR(m[8], std::cos(0.3f), 1e-6f);
  EXPECT_NEAR(m[10], -std::sin(0.3f), 1e-6f);
  duet_camera_mount_matrix(0, 0, 0, 0, 0, 0, nullptr);  // ignored, no crash
}

// ---- kernels ----------------------------------------------------------------------------------

TEST_F(DeviceTest, BackProjectionEqualsCpp) {
  constexpr int kW = 64, kH = 48;
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> depth_mm(300, 6000);  // some outside [0.5, 5] m
  // Frame 0: uint16 mm with padded rows and RGB colour; frame 1: float metres with BGRA colour.
  const std::size_t row0 = kW + 5;  // uint16 elements per row
  std::vector<std::uint16_t> d0(row0 * kH);
  for (auto& v : d0) v = static_cast<std::uint16_t>(depth_mm(rng) % 7 == 0 ? 0 : depth_mm(rng));
  std::vector<float> d1(static_cast<std::size_t>(kW) * kH);
  for (auto& v : d1) v = depth_mm(rng) / 1000.0f;
  d1[5] = NAN;
  d1[6] = INFINITY;
  std::vector<std::uint8_t> c0 = random_colors(static_cast<std::size_t>(kW) * kH, 12);
  std::vector<std::uint8_t> c1 = random_colors(static_cast<std::size_t>(kW) * kH * 4 / 3 + 1, 13);

  duet_sensor_frame f[2];
  for (auto& x : f) {
    duet_sensor_frame_init(&x);
    x.width = kW;
    x.height = kH;
    x.fx = 50.0f;
    x.fy = 51.0f;
    x.cx = 31.5f;
    x.cy = 23.0f;
  }
  f[0].depth = d0.data();
  f[0].depth_row_stride = row0 * sizeof(std::uint16_t);
  f[0].color = c0.data();
  duet_camera_mount_matrix(-0.118f, 0.0f, 0.271f, 0.0f, 0.0f, 0.0f, f[0].T_robot_camera);
  f[1].depth = d1.data();
  f[1].depth_format = DUET_DEPTH_F32;
  f[1].color = c1.data();
  f[1].color_channels = 4;
  f[1].color_bgr = 1;
  duet_camera_mount_matrix(-0.118f, 0.0f, 0.481f, static_cast<float>(-M_PI / 2), 0.0f, 0.0f,
                           f[1].T_robot_camera);
  duet_back_projection_settings bp;
  duet_back_projection_settings_init(&bp);
  bp.pixel_step = 2;

  duet_cloud c = duet_cloud_new(device_);
  std::size_t offsets[3] = {9, 9, 9};
  duet_back_project(c, f, 2, &bp, offsets);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();

  std::vector<duet::SensorFrame> cf(2);
  for (int i = 0; i < 2; ++i) {
    cf[i].depth = {f[i].depth, kW, kH, f[i].depth_row_stride,
                   i == 0 ? duet::DepthFormat::kU16 : duet::DepthFormat::kF32, 1000.0f};
    cf[i].color = {f[i].color, kW, kH, 0, f[i].color_channels, f[i].color_bgr != 0};
    cf[i].intrinsics = {kW, kH, 50.0f, 51.0f, 31.5f, 23.0f};
    cf[i].T_robot_camera.matrix() = Eigen::Map<const Eigen::Matrix4f>(f[i].T_robot_camera);
  }
  duet::BackProjectionSettings cbp;
  cbp.pixel_step = 2;
  duet::PointCloud expected;
  std::vector<std::size_t> expected_offsets;
  duet::back_project(cf, cbp, expected, &expected_offsets);

  ASSERT_GT(expected.size(), 100u);
  ASSERT_EQ(duet_cloud_get_size(c), expected.size());
  const auto pts = cloud_points(c);
  EXPECT_TRUE(same_floats(pts.data(), flat(expected.points).data(), pts.size()));
  ASSERT_EQ(duet_cloud_has_colors(c), 1);
  const std::uint8_t* colors = nullptr;
  std::size_t stride = 0;
  duet_cloud_get_colors(c, &colors, &stride);
  ASSERT_EQ(stride, 3u);
  EXPECT_EQ(std::memcmp(colors, expected.colors.data(), 3 * expected.size()), 0);
  ASSERT_EQ(expected_offsets.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(offsets[i], expected_offsets[i]) << i;
  EXPECT_EQ(duet_cloud_has_normals(c), 0);
  duet_cloud_release(c);
}

TEST_F(DeviceTest, VoxelFilterEqualsCppPackedAndStrided) {
  for (std::uint32_t seed : {1u, 2u, 3u}) {
    SCOPED_TRACE(seed);
    const std::size_t n = 20000;
    const auto xyz = random_points(n, seed, 2.0f, true);
    const auto rgb = random_colors(n, seed + 100);
    duet_voxel_filter_settings vf;
    duet_voxel_filter_settings_init(&vf);
    vf.leaf_size_m = 0.1f;
    vf.min_points_per_voxel = 2;

    duet::VoxelFilterSettings cs;
    cs.leaf_size_m = 0.1f;
    cs.min_points_per_voxel = 2;
    duet::PointCloud expected;
    duet::voxel_filter(view_of(xyz), duet::ColorsView(rgb.data(), n), cs, expected);
    ASSERT_GT(expected.size(), 0u);

    duet_cloud packed = duet_cloud_new(device_);
    duet_voxel_filter(packed, xyz.data(), 0, rgb.data(), 0, n, &vf);
    const auto records = to_records(xyz, &rgb);
    duet_cloud strided = duet_cloud_new(device_);
    duet_voxel_filter(strided, records[0].xyz, sizeof(Record), records[0].rgb, sizeof(Record), n, &vf);
    ASSERT_EQ(take(), DUET_ERROR_NONE) << message();

    for (duet_cloud c : {packed, strided}) {
      ASSERT_EQ(duet_cloud_get_size(c), expected.size());
      const auto pts = cloud_points(c);
      EXPECT_TRUE(same_floats(pts.data(), flat(expected.points).data(), pts.size()));
      std::vector<std::uint8_t> col(3 * expected.size());
      duet_cloud_copy_colors(c, col.data(), 0, expected.size());
      EXPECT_EQ(std::memcmp(col.data(), expected.colors.data(), col.size()), 0);
    }
    // Filtering a cloud in place through its own borrowed storage.
    const float* p = nullptr;
    std::size_t s = 0;
    duet_cloud_get_points(packed, &p, &s);
    duet_voxel_filter(packed, p, s, nullptr, 0, duet_cloud_get_size(packed), &vf);
    ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
    duet::PointCloud twice;
    duet::voxel_filter(duet::PointsView(expected.points), {}, cs, twice);
    ASSERT_EQ(duet_cloud_get_size(packed), twice.size());
    EXPECT_TRUE(same_floats(cloud_points(packed).data(), flat(twice.points).data(), 3 * twice.size()));
    EXPECT_EQ(duet_cloud_has_colors(packed), 0);
    duet_cloud_release(packed);
    duet_cloud_release(strided);
  }
}

TEST_F(DeviceTest, NormalsEqualCppPackedStridedAndOnACloud) {
  const auto xyz = room_points(5000, 21);
  const std::size_t n = xyz.size() / 3;
  duet_normal_settings ns;
  duet_normal_settings_init(&ns);
  ns.k = 12;
  ns.viewpoint[0] = -0.1f;
  ns.viewpoint[2] = 0.4f;

  duet::PointCloud expected;
  for (std::size_t i = 0; i < n; ++i) expected.points.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
  duet::NormalSettings cs;
  cs.k = 12;
  cs.viewpoint = Eigen::Vector3f(-0.1f, 0.0f, 0.4f);
  duet::estimate_normals(expected, cs);
  const auto en = flat(expected.normals);

  // Packed buffers.
  std::vector<float> normals(3 * n), curvature(n);
  duet_estimate_normals(device_, xyz.data(), 0, n, &ns, normals.data(), 0, curvature.data(), 0);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  EXPECT_TRUE(same_floats(normals.data(), en.data(), en.size()));
  EXPECT_TRUE(same_floats(curvature.data(), expected.curvature.data(), n));

  // Strided: read xyz from, and write normals into, the same 32-byte records.
  auto records = to_records(xyz, nullptr);
  duet_estimate_normals(device_, records[0].xyz, sizeof(Record), n, &ns, records[0].normal,
                        sizeof(Record), nullptr, 0);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  for (std::size_t i = 0; i < n; ++i) {
    ASSERT_TRUE(same_floats(records[i].normal, &en[3 * i], 3)) << i;
    ASSERT_EQ(records[i].xyz[0], xyz[3 * i]);  // input untouched
    ASSERT_EQ(records[i].label, 0xEE);         // neighbours untouched
  }

  // On a cloud.
  duet_cloud c = duet_cloud_new(device_);
  duet_cloud_set_points(c, xyz.data(), 0, nullptr, 0, n);
  duet_cloud_estimate_normals(c, &ns);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  ASSERT_EQ(duet_cloud_has_normals(c), 1);
  std::vector<float> cn(3 * n), cc(n);
  duet_cloud_copy_normals(c, cn.data(), 0, n);
  duet_cloud_copy_curvature(c, cc.data(), 0, n);
  EXPECT_TRUE(same_floats(cn.data(), en.data(), en.size()));
  EXPECT_TRUE(same_floats(cc.data(), expected.curvature.data(), n));
  const float* borrowed = nullptr;
  std::size_t stride = 0;
  duet_cloud_get_normals(c, &borrowed, &stride);
  EXPECT_EQ(stride, 12u);
  EXPECT_TRUE(same_floats(borrowed, en.data(), en.size()));
  duet_cloud_get_curvature(c, &borrowed, &stride);
  EXPECT_EQ(stride, 4u);
  EXPECT_TRUE(same_floats(borrowed, expected.curvature.data(), n));
  duet_cloud_release(c);
}

TEST_F(DeviceTest, EuclideanClustersEqualCppPackedAndStrided) {
  for (std::uint32_t seed : {5u, 6u}) {
    SCOPED_TRACE(seed);
    // Sparse random points: many small components.
    const auto xyz = random_points(3000, seed, 1.5f, true);
    const std::size_t n = xyz.size() / 3;
    duet_clustering_settings cs;
    duet_clustering_settings_init(&cs);
    cs.tolerance_m = 0.12f;
    cs.min_size = 3;
    cs.max_size = 200;
    duet::ClusteringSettings ccs{0.12f, 3, 200};
    std::size_t expected_count = 0;
    const auto expected = cpp_cluster_labels(xyz, ccs, &expected_count);
    ASSERT_GT(expected_count, 1u);

    std::vector<std::uint32_t> labels(n);
    std::size_t count = 0;
    duet_euclidean_clusters(device_, xyz.data(), 0, n, &cs, labels.data(), 0, &count);
    ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
    EXPECT_EQ(count, expected_count);
    EXPECT_EQ(labels, expected);
    EXPECT_EQ(labels[3], DUET_UNCLUSTERED);  // the NaN point

    auto records = to_records(xyz, nullptr);
    duet_euclidean_clusters(device_, records[0].xyz, sizeof(Record), n, &cs, &records[0].cluster,
                            sizeof(Record), &count);
    ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
    EXPECT_EQ(count, expected_count);
    for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(records[i].cluster, expected[i]) << i;
  }
}

TEST_F(DeviceTest, SegmentationEqualsCppPackedAndStrided) {
  const auto xyz = room_points(8000, 31);
  const std::size_t n = xyz.size() / 3;
  duet::PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) cloud.points.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
  duet::estimate_normals(cloud, duet::NormalSettings{});
  cloud.normals[10] = Eigen::Vector3f::Constant(NAN);

  duet::SegmentationSettings css;
  css.clustering.min_size = 10;
  std::vector<duet::PointLabel> expected(n);
  duet::segment(cloud.points_view(), cloud.normals, css, expected);
  std::size_t kinds[3] = {0, 0, 0};
  for (auto l : expected) ++kinds[static_cast<int>(l)];
  ASSERT_GT(kinds[0], 0u);
  ASSERT_GT(kinds[1], 0u);

  duet_segmentation_settings ss;
  duet_segmentation_settings_init(&ss);
  ss.clustering.min_size = 10;
  const auto normals = flat(cloud.normals);
  std::vector<std::uint8_t> labels(n, 0xFF);
  duet_segment(device_, xyz.data(), 0, normals.data(), 0, n, &ss, labels.data(), 0);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(labels[i], static_cast<std::uint8_t>(expected[i])) << i;
  EXPECT_EQ(labels[10], DUET_LABEL_IGNORED);

  auto records = to_records(xyz, nullptr);
  for (std::size_t i = 0; i < n; ++i) std::memcpy(records[i].normal, &normals[3 * i], 12);
  duet_segment(device_, records[0].xyz, sizeof(Record), records[0].normal, sizeof(Record), n, &ss,
               &records[0].label, sizeof(Record));
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  for (std::size_t i = 0; i < n; ++i) {
    ASSERT_EQ(records[i].label, static_cast<std::uint8_t>(expected[i])) << i;
    ASSERT_EQ(records[i].cluster, 0xDEADBEEFu);
  }
}

TEST_F(DeviceTest, GridUpdateEqualsCppPackedAndStrided) {
  const auto xyz = room_points(6000, 41);
  const std::size_t n = xyz.size() / 3;
  duet::PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) cloud.points.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
  duet::estimate_normals(cloud, duet::NormalSettings{});
  std::vector<duet::PointLabel> cl(n);
  duet::segment(cloud.points_view(), cloud.normals, duet::SegmentationSettings{}, cl);
  std::vector<std::uint8_t> labels(n);
  for (std::size_t i = 0; i < n; ++i) labels[i] = static_cast<std::uint8_t>(cl[i]);

  // Two scans from two positions; the second with other settings.
  duet::GridUpdateSettings s1;
  duet::GridUpdateSettings s2;
  s2.clear_along_rays = false;
  s2.hit_logodds = 1.2f;
  duet::OccupancyGrid expected(0.05f);
  duet::GridUpdateWorkspace ws;
  duet::update_grid(expected, {-0.118f, 0.0f}, cloud.points_view(), cl, s1, ws);
  duet::update_grid(expected, {0.5f, 0.3f}, cloud.points_view(), cl, s2, ws);

  duet_grid_update_settings g2;
  duet_grid_update_settings_init(&g2);
  g2.clear_along_rays = 0;
  g2.hit_logodds = 1.2f;
  auto records = to_records(xyz, nullptr);
  for (std::size_t i = 0; i < n; ++i) records[i].label = labels[i];

  duet_grid packed = duet_grid_new(device_, 0.05f);
  duet_grid_update(packed, -0.118f, 0.0f, xyz.data(), 0, labels.data(), 0, n, nullptr);
  duet_grid_update(packed, 0.5f, 0.3f, xyz.data(), 0, labels.data(), 0, n, &g2);
  duet_grid strided = duet_grid_new(device_, 0.05f);
  duet_grid_update(strided, -0.118f, 0.0f, records[0].xyz, sizeof(Record), &records[0].label,
                   sizeof(Record), n, nullptr);
  duet_grid_update(strided, 0.5f, 0.3f, records[0].xyz, sizeof(Record), &records[0].label,
                   sizeof(Record), n, &g2);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();

  const std::size_t cells = expected.cell_count();
  ASSERT_GT(cells, 0u);
  std::vector<float> ep(cells);
  expected.to_probabilities(ep);
  std::vector<std::int8_t> er(cells);
  expected.to_ros_trinary(er, 0.6f, 0.3f);
  for (duet_grid g : {packed, strided}) {
    EXPECT_EQ(duet_grid_get_width(g), expected.width());
    EXPECT_EQ(duet_grid_get_height(g), expected.height());
    EXPECT_EQ(duet_grid_get_resolution(g), 0.05f);
    float ox = 0, oy = 0;
    duet_grid_get_origin(g, &ox, &oy);
    EXPECT_EQ(ox, expected.origin().x());
    EXPECT_EQ(oy, expected.origin().y());
    EXPECT_EQ(duet_grid_get_known_cells(g), expected.known_cells());
    std::vector<float> l(cells), p(cells);
    std::vector<std::int8_t> r(cells);
    duet_grid_copy_logodds(g, l.data(), cells);
    duet_grid_copy_probabilities(g, p.data(), cells);
    duet_grid_copy_ros(g, r.data(), cells, 0.6f, 0.3f);
    ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
    EXPECT_TRUE(same_floats(l.data(), expected.logodds().data(), cells));
    EXPECT_TRUE(same_floats(p.data(), ep.data(), cells));
    EXPECT_EQ(r, er);
  }
  duet_grid_release(packed);
  duet_grid_release(strided);
}

// duet_grid_scan_match == inflate (occupied cells only) + scan_match on the same grid, packed and
// strided points, default and custom settings; and the C++ result moves towards the truth.
TEST_F(DeviceTest, GridScanMatchEqualsCppPackedAndStrided) {
  // A 4 x 3 m room (walls at 0.5 m height, obstacle points) seen from its middle.
  std::vector<float> xyz;
  auto wall = [&](float x0, float y0, float x1, float y1) {
    for (float t = 0.0f; t <= 1.0f; t += 0.005f) {
      xyz.push_back(x0 + t * (x1 - x0));
      xyz.push_back(y0 + t * (y1 - y0));
      xyz.push_back(0.5f);
    }
  };
  wall(-2.0f, -1.5f, 2.0f, -1.5f);
  wall(2.0f, -1.5f, 2.0f, 1.5f);
  wall(2.0f, 1.5f, -2.0f, 1.5f);
  wall(-2.0f, 1.5f, -2.0f, -1.5f);
  wall(0.5f, 0.3f, 1.2f, 0.3f);  // a box edge
  const std::size_t n = xyz.size() / 3;
  std::vector<std::uint8_t> labels(n, DUET_LABEL_OBSTACLE);
  std::vector<duet::PointLabel> cl(n, duet::PointLabel::kObstacle);
  duet::OccupancyGrid expected(0.05f);
  duet::GridUpdateWorkspace ws;
  duet::update_grid(expected, {0.0f, 0.0f}, duet::PointsView(xyz.data(), n), cl,
                    duet::GridUpdateSettings{}, ws);
  duet_grid g = duet_grid_new(device_, 0.05f);
  duet_grid_update(g, 0.0f, 0.0f, xyz.data(), 0, labels.data(), 0, n, nullptr);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  // The scan: the wall points seen from `truth`, in the robot frame.
  const duet::Pose2 truth{0.1f, -0.05f, 0.02f};
  const float c = std::cos(truth.theta), sn = std::sin(truth.theta);
  std::vector<float> xy;
  struct Rec {
    float xy[2];
    double pad;
  };
  std::vector<Rec> recs;
  std::vector<Eigen::Vector2f> pts;
  for (std::size_t i = 0; i < n; i += 3) {
    const float dx = xyz[3 * i] - truth.x, dy = xyz[3 * i + 1] - truth.y;
    const Eigen::Vector2f p(c * dx + sn * dy, -sn * dx + c * dy);
    pts.push_back(p);
    xy.push_back(p.x());
    xy.push_back(p.y());
    recs.push_back(Rec{{p.x(), p.y()}, 0.0});
  }
  const duet::Pose2 prior{truth.x + 0.06f, truth.y - 0.04f, truth.theta + 0.01f};
  duet::InflatedGrid field;
  duet::occupied_distance(duet::GridView(expected), duet::CellThresholds{}, field);
  duet::ScanMatchSettings custom;
  custom.prior_sigma_deg = 10.0f;
  custom.linear_window_m = 0.2f;
  duet_scan_match_settings cs;
  duet_scan_match_settings_init(&cs);
  cs.prior_sigma_deg = 10.0f;
  cs.linear_window_m = 0.2f;
  for (const bool use_custom : {false, true}) {
    const duet::ScanMatchResult want = duet::scan_match(field.clearance(), pts, prior, use_custom ? custom : duet::ScanMatchSettings{});
    EXPECT_EQ(want.status, duet::ScanMatchStatus::kMatched);
    EXPECT_LT(std::hypot(want.pose.x - truth.x, want.pose.y - truth.y), std::hypot(prior.x - truth.x, prior.y - truth.y));
    for (const bool strided : {false, true}) {
      duet_scan_match_result got{};
      duet_grid_scan_match(g, strided ? recs[0].xy : xy.data(), strided ? sizeof(Rec) : 0, pts.size(),
                           duet_pose2{prior.x, prior.y, prior.theta}, use_custom ? &cs : nullptr, &got);
      ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
      EXPECT_EQ(got.status, DUET_SCAN_MATCH_MATCHED);
      EXPECT_EQ(got.pose.x, want.pose.x);
      EXPECT_EQ(got.pose.y, want.pose.y);
      EXPECT_EQ(got.pose.theta, want.pose.theta);
      EXPECT_EQ(got.score, want.score);
      EXPECT_EQ(got.prior_score, want.prior_score);
      EXPECT_EQ(got.candidates, want.candidates);
    }
  }
  // No points: the prior, TOO_FEW_POINTS (not an error).
  duet_scan_match_result none{};
  duet_grid_scan_match(g, nullptr, 0, 0, duet_pose2{1.0f, 2.0f, 0.5f}, nullptr, &none);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
  EXPECT_EQ(none.status, DUET_SCAN_MATCH_TOO_FEW_POINTS);
  EXPECT_EQ(none.pose.x, 1.0f);
  EXPECT_EQ(none.pose.theta, 0.5f);
  duet_grid_release(g);
}

TEST(CapiThreads, ResultsDoNotDependOnTheDeviceThreadCount) {
  const auto xyz = room_points(20000, 51);
  const std::size_t n = xyz.size() / 3;
  struct Result {
    std::vector<float> filtered, normals;
    std::vector<std::uint32_t> clusters;
    std::vector<std::uint8_t> labels;
    std::vector<float> grid;
  };
  auto run = [&](const char* config) {
    Result r;
    duet_device d = duet_device_new(config);
    EXPECT_NE(d, nullptr);
    duet_cloud c = duet_cloud_new(d);
    duet_voxel_filter_settings vf;
    duet_voxel_filter_settings_init(&vf);
    vf.leaf_size_m = 0.03f;
    duet_voxel_filter(c, xyz.data(), 0, nullptr, 0, n, &vf);
    duet_cloud_estimate_normals(c, nullptr);
    const std::size_t m = duet_cloud_get_size(c);
    r.filtered.resize(3 * m);
    r.normals.resize(3 * m);
    duet_cloud_copy_points(c, r.filtered.data(), 0, m);
    duet_cloud_copy_normals(c, r.normals.data(), 0, m);
    r.clusters.resize(m);
    duet_euclidean_clusters(d, r.filtered.data(), 0, m, nullptr, r.clusters.data(), 0, nullptr);
    r.labels.resize(m);
    duet_segment(d, r.filtered.data(), 0, r.normals.data(), 0, m, nullptr, r.labels.data(), 0);
    duet_grid g = duet_grid_new(d, 0.05f);
    duet_grid_update(g, 0.0f, 0.0f, r.filtered.data(), 0, r.labels.data(), 0, m, nullptr);
    r.grid.resize(static_cast<std::size_t>(duet_grid_get_width(g)) * duet_grid_get_height(g));
    duet_grid_copy_logodds(g, r.grid.data(), r.grid.size());
    EXPECT_EQ(duet_device_get_error(d), DUET_ERROR_NONE) << duet_device_get_error_message(d);
    duet_grid_release(g);
    duet_cloud_release(c);
    duet_device_release(d);
    return r;
  };
  const Result one = run("threads=1");
  const Result two = run("threads=2");
  const Result all = run("threads=0");
  for (const Result* r : {&two, &all}) {
    ASSERT_EQ(r->filtered.size(), one.filtered.size());
    EXPECT_TRUE(same_floats(r->filtered.data(), one.filtered.data(), one.filtered.size()));
    EXPECT_TRUE(same_floats(r->normals.data(), one.normals.data(), one.normals.size()));
    EXPECT_EQ(r->clusters, one.clusters);
    EXPECT_EQ(r->labels, one.labels);
    ASSERT_EQ(r->grid.size(), one.grid.size());
    EXPECT_TRUE(same_floats(r->grid.data(), one.grid.data(), one.grid.size()));
  }
}
