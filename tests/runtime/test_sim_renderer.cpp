// Simulated RGB-D sensors (issue 4, part 2): the Embree renderer's mesh and depths against depths
// computed analytically (ray / plane / prism intersections in double, sim_renderer_test_util.hpp),
// out-of-range and empty scenes, and rays aimed at the triangles' shared edges.
#include "sim_renderer_test_util.hpp"

#include <duet/kernels/error.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <vector>

namespace test_sim_renderer {

using namespace duet_test::render;

TEST(SimRendererMesh, TrianglesCoverEverySurfaceWithOutwardNormals) {
  World w = empty_world(5.0f);
  w.ceiling_height_m = 2.6f;
  // An L-shaped (concave) solid floating above the floor, and a box standing on it.
  w.solids.push_back(prism({{0, 0}, {2, 0}, {2, 0.5f}, {0.5f, 0.5f}, {0.5f, 2}, {0, 2}}, 0.3f, 1.0f, Texture::kNoise, "L"));
  w.solids.push_back(rotated_box({-2.0f, -2.0f}, 1.0f, 0.4f, 0.0f, 0.8f));
  duet::sim::validate(w);
  const duet::sim::WorldMesh m = duet::sim::build_world_mesh(w);
  ASSERT_EQ(m.triangles.size(), m.triangle_surface.size());
  ASSERT_EQ(m.surfaces.size(), 4u);
  // floor 2 + ceiling 2 + L: 6 sides * 2 + top 4 + bottom 4 + box: 4 sides * 2 + top 2 (no bottom at z = 0).
  EXPECT_EQ(m.triangles.size(), 2u + 2u + 12u + 4u + 4u + 8u + 2u);
  std::vector<double> area(m.surfaces.size(), 0.0);
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const auto& tri = m.triangles[t];
    const Eigen::Vector3d a = m.vertices[tri[0]].cast<double>(), b = m.vertices[tri[1]].cast<double>(), c = m.vertices[tri[2]].cast<double>();
    const Eigen::Vector3d n = (b - a).cross(c - a);
    area[m.triangle_surface[t]] += 0.5 * n.norm();
    const std::uint32_t s = m.triangle_surface[t];
    const Eigen::Vector3d centroid = (a + b + c) / 3.0;
    if (s == 0) {
      EXPECT_GT(n.z(), 0.0);
    }
    if (s == 1) {
      EXPECT_LT(n.z(), 0.0);
    }
    if (s >= 2) {
      // Outward: a point just outside along the normal is outside the prism.
      const Solid& so = w.solids[s - 2];
      const Eigen::Vector3d p = centroid + 1e-3 * n.normalized();
      const bool inside = inside_polygon(so.polygon, p.x(), p.y()) && p.z() > so.z_min_m && p.z() < so.z_max_m;
      EXPECT_FALSE(inside) << "triangle " << t << " of " << so.name << " faces inwards";
    }
  }
  EXPECT_NEAR(area[0], 100.0, 1e-3);
  EXPECT_NEAR(area[1], 100.0, 1e-3);
  const double l_area = 2.0 * 0.5 + 0.5 * 1.5;  // footprint of the L
  const double l_perimeter = 2 + 0.5 + 1.5 + 1.5 + 0.5 + 2;
  EXPECT_NEAR(area[2], 2.0 * l_area + l_perimeter * 0.7, 1e-4);
  EXPECT_NEAR(area[3], 1.0 + 4.0 * 0.8, 1e-4);
}

TEST(SimRendererMesh, EmptyFloorThrows) {
  World w = empty_world();
  w.floor.max = w.floor.min;
  EXPECT_THROW((void)duet::sim::build_world_mesh(w), duet::Error);
  EXPECT_THROW(RgbdRenderer(w, RenderSettings{}), duet::Error);
}

// ---- depth against analytic references --------------------------------------------------------------

TEST(SimRendererDepth, WallAtKnownDistanceMatchesAnalyticDepth) {
  World w = empty_world();
  w.solids.push_back(wall_at_x(3.0f));
  duet::sim::validate(w);
  const auto s = kinect();
  const Eigen::Isometry3f T = camera({0.0f, 0.0f, 1.0f}, 0.0f);
  const RgbdImage img = render(w, noise_free(), s, T);
  ASSERT_EQ(img.width, 640);
  ASSERT_EQ(img.height, 480);
  ASSERT_EQ(img.depth.size(), 640u * 480u);
  ASSERT_EQ(img.rgb.size(), 3u * 640u * 480u);
  int wall = 0, floor = 0, max_err = 0;
  for (int v = 0; v < 480; ++v)
    for (int u = 0; u < 640; ++u) {
      // Wall: depth = 3 for every pixel (depth is optical z); floor below: t = 1 / (-d_z).
      const Ray r = pixel_ray(s, T, u, v);
      const double t_floor = r.d.z() < 0.0 ? -1.0 / r.d.z() : std::numeric_limits<double>::infinity();
      const double t = std::min(3.0, t_floor);
      (t_floor < 3.0 ? floor : wall)++;
      const int e = std::abs(static_cast<int>(img.depth[static_cast<std::size_t>(v * 640 + u)]) - expected_raw(s, t));
      max_err = std::max(max_err, e);
    }
  EXPECT_LE(max_err, 1);
  EXPECT_GT(wall, 200000);
  EXPECT_GT(floor, 10000);
  // The centre pixel sees the wall exactly.
  EXPECT_NEAR(img.depth[240 * 640 + 320], 3000, 1);
}

TEST(SimRendererDepth, RotatedBoxAtAnAngleMatchesReference) {
  World w = empty_world();
  w.ceiling_height_m = 2.5f;
  w.solids.push_back(rotated_box({3.0f, 0.4f}, 1.2f, 0.5f, 0.0f, 0.9f));
  w.solids.push_back(prism({{2.0f, -1.5f}, {2.6f, -1.5f}, {2.3f, -0.8f}}, 0.5f, 1.4f, Texture::kPosters, "floating triangle"));
  duet::sim::validate(w);
  const auto s = kinect();
  const Eigen::Isometry3f T = camera({0.0f, 0.0f, 1.2f}, 0.15f, 0.25f);
  const RgbdImage img = render(w, noise_free(), s, T);
  std::size_t mismatched = 0, solid_pixels = 0;
  for (int v = 0; v < 480; ++v)
    for (int u = 0; u < 640; ++u) {
      const RefHit h = cast(w, pixel_ray(s, T, u, v));
      solid_pixels += (std::isfinite(h.t) && std::abs(h.n.z()) < 0.5) ? 1 : 0;  // side faces
      const int e = std::abs(static_cast<int>(img.depth[static_cast<std::size_t>(v * 640 + u)]) - expected_raw(s, h.t));
      if (e > 1) ++mismatched;
    }
  EXPECT_GT(solid_pixels, 20000u);  // the box and the triangle fill a good part of the view
  // Only pixels whose ray grazes an edge may disagree (float vs double).
  EXPECT_LE(mismatched, 20u) << "of " << 640 * 480;
}

TEST(SimRendererDepth, BackProjectedPointsLieOnTheSurfaces) {
  World w = empty_world();
  w.solids.push_back(rotated_box({2.5f, 0.3f}, 1.0f, 0.7f, 0.0f, 1.0f));
  w.solids.push_back(wall_at_x(4.5f, 3.0f));
  duet::sim::validate(w);
  const auto s = kinect();
  const Eigen::Isometry3f T = camera({0.0f, 0.0f, 0.8f}, 0.05f, 0.2f);
  const RgbdImage img = render(w, noise_free(), s, T);
  // T_robot_camera = T_world_optical: the cloud comes out in the world frame.
  const duet::SensorFrame frame = duet::sim::frame_view(img, s, T);
  EXPECT_EQ(frame.depth.data, img.depth.data());
  EXPECT_EQ(frame.color.data, img.rgb.data());
  duet::PointCloud cloud;
  duet::back_project(std::span<const duet::SensorFrame>(&frame, 1), duet::BackProjectionSettings{}, cloud);
  ASSERT_GT(cloud.size(), 250000u);
  const Solid& box = w.solids[0];
  std::size_t on_box = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d p = cloud.points[i].cast<double>();
    double dist = std::abs(p.z());                    // floor
    dist = std::min(dist, std::abs(p.x() - 4.5));     // wall face
    // box: distance to the prism's surface (sides and top)
    double side = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < 4; ++k) {
      const Eigen::Vector2d a = box.polygon[k].cast<double>(), b = box.polygon[(k + 1) % 4].cast<double>();
      const Eigen::Vector2d q(p.x(), p.y());
      const double tt = std::clamp((q - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
      side = std::min(side, (a + tt * (b - a) - q).norm());
    }
    const bool in_xy = inside_polygon(box.polygon, p.x(), p.y());
    const double box_d = p.z() <= 1.0 ? (in_xy ? std::min(side, 1.0 - p.z()) : side)
                                      : (in_xy ? p.z() - 1.0 : std::hypot(side, p.z() - 1.0));
    if (box_d < 2e-3) ++on_box;
    dist = std::min(dist, box_d);
    worst = std::max(worst, dist);
  }
  // Raw units of 1 mm round the depth by <= 0.5 mm along a ray up to 1.25x longer than z.
  EXPECT_LT(worst, 1.5e-3);
  EXPECT_GT(on_box, 20000u);
}

TEST(SimRendererDepth, OutOfRangeGivesZeroButColourStays) {
  const auto s = kinect(160, 120);
  const Eigen::Isometry3f T = camera({0.0f, 0.0f, 1.0f}, 0.0f);
  for (const bool noisy : {false, true}) {
    RenderSettings rs;
    rs.noise.enabled = noisy;
    rs.noise.dropout_rate = 0.0f;
    for (const float d : {0.3f, 4.6f, 6.0f}) {
      World w = empty_world();
      w.solids.push_back(wall_at_x(d, 5.0f, Texture::kChecker));
      duet::sim::validate(w);
      const RgbdImage img = render(w, rs, s, T);
      // Rows above the horizon see only the wall.
      std::size_t zeros = 0, lit = 0, n = 0;
      for (int v = 0; v < 50; ++v)
        for (int u = 0; u < 160; ++u) {
          const std::size_t p = static_cast<std::size_t>(v * 160 + u);
          zeros += img.depth[p] == 0 ? 1 : 0;
          lit += (img.rgb[3 * p] + img.rgb[3 * p + 1] + img.rgb[3 * p + 2]) > 0 ? 1 : 0;
          ++n;
        }
      EXPECT_EQ(lit, n) << "the colour camera sees the wall at any distance (d = " << d << ")";
      if (d < 0.5f || d > 5.5f)
        EXPECT_EQ(zeros, n) << "d = " << d << " noisy = " << noisy;
      else
        EXPECT_EQ(zeros, 0u) << "d = " << d << " noisy = " << noisy;
    }
  }
}

TEST(SimRendererDepth, NothingHitGivesZeroDepthAndBlack) {
  World w = empty_world(3.0f);
  duet::sim::validate(w);
  const auto s = kinect(80, 60);
  // Looking up at the sky (no ceiling): nothing.
  const RgbdImage sky = render(w, RenderSettings{}, s, camera({0.0f, 0.0f, 1.0f}, 0.0f, -1.2f));
  for (std::size_t p = 0; p < sky.depth.size(); ++p) {
    ASSERT_EQ(sky.depth[p], 0) << p;
    ASSERT_EQ(sky.rgb[3 * p] + sky.rgb[3 * p + 1] + sky.rgb[3 * p + 2], 0) << p;
  }
  // With a ceiling at 2.5 m the same view sees it at depth (2.5 - 1) / d_z.
  w.ceiling_height_m = 2.5f;
  const Eigen::Isometry3f T = camera({0.0f, 0.0f, 1.0f}, 0.0f, -1.2f);
  const RgbdImage ceil = render(w, noise_free(), s, T);
  for (int v = 0; v < 60; ++v)
    for (int u = 0; u < 80; ++u) {
      const RefHit h = cast(w, pixel_ray(s, T, u, v));
      ASSERT_NEAR(ceil.depth[static_cast<std::size_t>(v * 80 + u)], expected_raw(s, h.t), 1) << u << "," << v;
    }
}

TEST(SimRendererDepth, EmptyWorldFloorOnly) {
  World w = empty_world(4.0f);
  duet::sim::validate(w);
  const auto s = kinect(64, 48);
  const Eigen::Isometry3f T = camera({0.0f, 0.0f, 0.5f}, 0.3f, 0.35f);
  const RgbdImage img = render(w, noise_free(), s, T);
  std::size_t seen = 0;
  for (int v = 0; v < 48; ++v)
    for (int u = 0; u < 64; ++u) {
      const RefHit h = cast(w, pixel_ray(s, T, u, v));
      const std::size_t p = static_cast<std::size_t>(v * 64 + u);
      EXPECT_NEAR(img.depth[p], expected_raw(s, h.t), 1);
      seen += img.depth[p] > 0 ? 1 : 0;
      EXPECT_EQ(img.rgb[3 * p] > 0, std::isfinite(h.t)) << u << "," << v;
    }
  EXPECT_GT(seen, 1000u);
}

TEST(SimRendererDepth, DepthOnlyGivesTheSameDepthWithoutColour) {
  World w = empty_world();
  w.solids.push_back(rotated_box({2.0f, 0.0f}, 1.0f, 0.3f, 0.0f, 1.0f));
  w.solids.push_back(wall_at_x(5.3f));  // beyond max depth: only noise can bring it in range
  duet::sim::validate(w);
  const auto s = kinect(320, 240);
  const Eigen::Isometry3f T = camera({0.0f, 0.0f, 1.0f}, 0.0f);
  const RgbdRenderer r(w, RenderSettings{});
  RgbdImage full, depth_only;
  r.render(s, T, 77, full);
  r.render_depth_only(s, T, 77, depth_only);
  EXPECT_TRUE(depth_only.rgb.empty());
  EXPECT_EQ(depth_only.depth, full.depth);
  const duet::SensorFrame f = duet::sim::frame_view(depth_only, s, s.T_robot_optical());
  EXPECT_EQ(f.color.data, nullptr);
  // Reusing an image with colour for a depth-only frame drops the colour.
  r.render_depth_only(s, T, 77, full);
  EXPECT_TRUE(full.rgb.empty());
}

// ---- shared edges --------------------------------------------------------------------------------

TEST(SimRendererDepth, NoRaySlipsThroughTheDiagonalOfAWall) {
  // The wall face x = d is two triangles sharing the diagonal (d, 15, 0) - (d, -15, h). A
  // one-row camera whose row plane contains that diagonal aims every ray at the shared edge
  // (within the rounding of its direction): each must hit the wall at the analytic depth, in
  // the fast mode (grown triangles) and in Embree's robust mode.
  const float d = 3.0f, h = 5.0f;
  World w = empty_world();
  w.solids.push_back(wall_at_x(d, h, Texture::kPlain));
  duet::sim::validate(w);
  const Eigen::Vector3d a(d, 15.0, 0.0), b(d, -15.0, h);
  const Eigen::Vector3d along = (b - a).normalized();
  for (const bool robust : {false, true}) {
    RenderSettings rs = noise_free();
    rs.robust_intersection = robust;
    const RgbdRenderer r(w, rs);
    std::size_t rays = 0, misses = 0;
    for (int c = 0; c < 24; ++c) {
      const double dist = 0.6 + 0.17 * c;         // camera distance to the wall [m]
      const double s = 0.25 + 0.02 * c;           // where on the diagonal the camera looks
      const Eigen::Vector3d target = a + s * (b - a);
      Eigen::Matrix3f R;
      R.col(0) = along.cast<float>();                     // optical x along the diagonal
      R.col(2) = Eigen::Vector3f::UnitX();                // looking at the wall (+x)
      R.col(1) = R.col(2).cross(R.col(0)).normalized();   // right-handed
      Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
      T.linear() = R;
      T.translation() = (target - dist * Eigen::Vector3d::UnitX()).cast<float>();
      duet::SensorProfile sensor = kinect(4001, 1);
      sensor.intrinsics.fy = sensor.intrinsics.fx;
      sensor.max_depth_m = 9.0f;
      RgbdImage img;
      r.render(sensor, T, 1, img);
      for (int u = 0; u < 4001; ++u) {
        const Ray ray = pixel_ray(sensor, T, u, 0);
        const RefHit hit = cast(w, ray);
        if (!std::isfinite(hit.t) || hit.face != 3 || hit.t > 8.9) continue;  // only rays onto the face x = d
        ++rays;
        const int got = img.depth[static_cast<std::size_t>(u)];
        if (std::abs(got - expected_raw(sensor, hit.t)) > 1) ++misses;
      }
    }
    EXPECT_GT(rays, 40000u);
    EXPECT_EQ(misses, 0u) << (robust ? "robust" : "fast") << " mode: " << misses << " of " << rays << " rays slipped through";
  }
}

TEST(SimRendererDepth, FastAndRobustIntersectionAgreeAwayFromSilhouettes) {
  // The posts scene (many shared edges and silhouettes): the fast mode's grown triangles move
  // silhouettes by a few hundredths of a millimetre, so a ray passing that close to an edge may
  // hit the other surface. Any pixel whose depth differs by more than 1 cm must therefore lie
  // on a depth discontinuity of the robust image; colour differs only there or on texture
  // edges (the hit points differ by float rounding).
  const World w = posts_world();
  RenderSettings fast = noise_free(), robust = noise_free();
  robust.robust_intersection = true;
  const RgbdRenderer rf(w, fast), rr(w, robust);
  const auto s = kinect();
  std::size_t n = 0, far = 0, colour = 0, off_edge = 0;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Isometry3f T = camera({0.0f, -0.3f + 0.2f * static_cast<float>(k), 0.7f}, 0.1f * static_cast<float>(k) - 0.15f, 0.15f);
    RgbdImage a, b;
    rf.render(s, T, 1, a);
    rr.render(s, T, 1, b);
    for (int v = 0; v < 480; ++v)
      for (int u = 0; u < 640; ++u) {
        const std::size_t p = static_cast<std::size_t>(v * 640 + u);
        ++n;
        colour += (a.rgb[3 * p] != b.rgb[3 * p] || a.rgb[3 * p + 1] != b.rgb[3 * p + 1] || a.rgb[3 * p + 2] != b.rgb[3 * p + 2]) ? 1 : 0;
        if (std::abs(static_cast<int>(a.depth[p]) - static_cast<int>(b.depth[p])) <= 10) continue;
        ++far;
        int lo = 1 << 30, hi = -1;
        for (int dv = -1; dv <= 1; ++dv)
          for (int du = -1; du <= 1; ++du) {
            const int uu = std::clamp(u + du, 0, 639), vv = std::clamp(v + dv, 0, 479);
            const int z = b.depth[static_cast<std::size_t>(vv * 640 + uu)];
            lo = std::min(lo, z);
            hi = std::max(hi, z);
          }
        if (lo != 0 && hi - lo <= 10) ++off_edge;
      }
  }
  EXPECT_EQ(off_edge, 0u) << far << " pixels differ by > 1 cm";
  EXPECT_LT(static_cast<double>(far), 1e-3 * static_cast<double>(n));
  EXPECT_LT(static_cast<double>(colour), 1e-2 * static_cast<double>(n));
}

}  // namespace test_sim_renderer
