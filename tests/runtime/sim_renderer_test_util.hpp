#pragma once
// Helpers shared by the simulated RGB-D renderer's tests (test_sim_renderer*.cpp): a Kinect-like
// sensor, camera poses, small test worlds, and a reference ray caster in double precision that the
// renderer's depths are checked against.
#include <duet/kernels/back_projection.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/sim/renderer.hpp>
#include <duet/sim/world.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numbers>
#include <vector>

namespace duet_test::render {

using duet::sim::KinectNoiseSettings;
using duet::sim::RenderSettings;
using duet::sim::RgbdImage;
using duet::sim::RgbdRenderer;
using duet::sim::Solid;
using duet::sim::Texture;
using duet::sim::World;

inline constexpr double kDeg = std::numbers::pi / 180.0;

inline duet::SensorProfile kinect(int w = 640, int h = 480) {
  duet::SensorProfile s;
  s.name = "test_kinect";
  s.intrinsics.width = w;
  s.intrinsics.height = h;
  s.intrinsics.fx = static_cast<float>(0.5 * w / std::tan(0.5 * 57.0 * kDeg));
  s.intrinsics.fy = static_cast<float>(0.5 * h / std::tan(0.5 * 43.0 * kDeg));
  s.intrinsics.cx = 0.5f * static_cast<float>(w - 1);
  s.intrinsics.cy = 0.5f * static_cast<float>(h - 1);
  s.min_depth_m = 0.5f;
  s.max_depth_m = 5.0f;
  s.depth_units_per_m = 1000.0f;
  return s;
}

// Camera body (x forward, z up) at `pos`, yawed about z then pitched (positive = looking down).
inline Eigen::Isometry3f camera(const Eigen::Vector3f& pos, float yaw_rad, float pitch_down_rad = 0.0f) {
  Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
  T.translate(pos);
  T.rotate(Eigen::AngleAxisf(yaw_rad, Eigen::Vector3f::UnitZ()));
  T.rotate(Eigen::AngleAxisf(pitch_down_rad, Eigen::Vector3f::UnitY()));
  return T * duet::T_body_optical();
}

inline RenderSettings noise_free() {
  RenderSettings s;
  s.noise.enabled = false;
  return s;
}

inline World empty_world(float half = 20.0f) {
  World w;
  w.name = "test";
  w.floor.min = Eigen::Vector2f(-half, -half);
  w.floor.max = Eigen::Vector2f(half, half);
  w.start = duet::Pose2{0.0f, 0.0f, 0.0f};
  return w;
}

inline Solid prism(std::vector<Eigen::Vector2f> poly, float z0, float z1, Texture tex = Texture::kNoise, const char* name = "solid") {
  Solid s;
  s.name = name;
  s.polygon = std::move(poly);
  s.z_min_m = z0;
  s.z_max_m = z1;
  s.surface.texture = tex;
  return s;
}

// A wall whose near face is the plane x = d (facing -x), 0.2 m thick, spanning y in [-15, 15].
inline Solid wall_at_x(float d, float height = 5.0f, Texture tex = Texture::kNoise) {
  return prism({{d, -15.0f}, {d + 0.2f, -15.0f}, {d + 0.2f, 15.0f}, {d, 15.0f}}, 0.0f, height, tex, "wall");
}

// A rotated square box (side `a`, centre c, yaw) - CCW.
inline Solid rotated_box(const Eigen::Vector2f& c, float a, float yaw, float z0, float z1) {
  std::vector<Eigen::Vector2f> poly;
  const Eigen::Rotation2Df R(yaw);
  for (const auto& p : {Eigen::Vector2f(-1, -1), Eigen::Vector2f(1, -1), Eigen::Vector2f(1, 1), Eigen::Vector2f(-1, 1)})
    poly.push_back(c + R * (0.5f * a * p));
  return prism(poly, z0, z1, Texture::kBricks, "box");
}

// ---- reference ray casting (double) --------------------------------------------------------------

struct Ray {
  Eigen::Vector3d o, d;  // d has optical z = 1, so t = depth
};

inline Ray pixel_ray(const duet::SensorProfile& s, const Eigen::Isometry3f& T, int u, int v) {
  const auto& in = s.intrinsics;
  const Eigen::Vector3d dopt((u - static_cast<double>(in.cx)) / in.fx, (v - static_cast<double>(in.cy)) / in.fy, 1.0);
  return {T.translation().cast<double>(), T.linear().cast<double>() * dopt};
}

struct RefHit {
  double t = std::numeric_limits<double>::infinity();
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  int face = -1;  // the plane hit: -3 floor, -2 ceiling, 1000 * solid + (edge index | 998 top | 999 bottom)
};

inline bool inside_polygon(const std::vector<Eigen::Vector2f>& poly, double x, double y) {
  bool in = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const double xi = poly[i].x(), yi = poly[i].y(), xj = poly[j].x(), yj = poly[j].y();
    if ((yi > y) != (yj > y) && x < (xj - xi) * (y - yi) / (yj - yi) + xi) in = !in;
  }
  return in;
}

inline void hit_plane_z(const Ray& r, double z, const std::function<bool(double, double)>& inside, const Eigen::Vector3d& n, RefHit& best,
                 int face = -1) {
  if (r.d.z() == 0.0) return;
  const double t = (z - r.o.z()) / r.d.z();
  if (t <= 0.0 || t >= best.t) return;
  const Eigen::Vector3d p = r.o + t * r.d;
  if (inside(p.x(), p.y())) best = {t, n, face};
}

inline RefHit cast(const World& w, const Ray& r) {
  RefHit best;
  hit_plane_z(r, 0.0, [&](double x, double y) { return x >= w.floor.min.x() && x <= w.floor.max.x() && y >= w.floor.min.y() && y <= w.floor.max.y(); },
              Eigen::Vector3d::UnitZ(), best, -3);
  if (w.ceiling_height_m > 0.0f)
    hit_plane_z(r, w.ceiling_height_m, [&](double x, double y) { return x >= w.floor.min.x() && x <= w.floor.max.x() && y >= w.floor.min.y() && y <= w.floor.max.y(); },
                -Eigen::Vector3d::UnitZ(), best, -2);
  for (std::size_t si = 0; si < w.solids.size(); ++si) {
    const Solid& s = w.solids[si];
    const int base_face = 1000 * static_cast<int>(si);
    const std::size_t n = s.polygon.size();
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector2d a = s.polygon[i].cast<double>(), b = s.polygon[(i + 1) % n].cast<double>();
      const Eigen::Vector2d e = b - a, d2(r.d.x(), r.d.y());
      const double den = d2.x() * e.y() - d2.y() * e.x();
      if (den == 0.0) continue;
      const Eigen::Vector2d ao = a - Eigen::Vector2d(r.o.x(), r.o.y());
      const double t = (ao.x() * e.y() - ao.y() * e.x()) / den;
      const double sp = (ao.x() * d2.y() - ao.y() * d2.x()) / den;
      if (t <= 0.0 || t >= best.t || sp < 0.0 || sp > 1.0) continue;
      const double z = r.o.z() + t * r.d.z();
      if (z < s.z_min_m || z > s.z_max_m) continue;
      best = {t, Eigen::Vector3d(e.y(), -e.x(), 0.0).normalized(), base_face + static_cast<int>(i)};
    }
    auto in = [&](double x, double y) { return inside_polygon(s.polygon, x, y); };
    hit_plane_z(r, s.z_max_m, in, Eigen::Vector3d::UnitZ(), best, base_face + 998);
    if (s.z_min_m > 0.0f) hit_plane_z(r, s.z_min_m, in, -Eigen::Vector3d::UnitZ(), best, base_face + 999);
  }
  return best;
}

// Expected noise-free raw depth of a reference hit.
inline int expected_raw(const duet::SensorProfile& s, double t) {
  if (!std::isfinite(t) || t < s.min_depth_m || t > s.max_depth_m) return 0;
  return static_cast<int>(std::lround(t * s.depth_units_per_m));
}

inline RgbdImage render(const World& world, const RenderSettings& settings, const duet::SensorProfile& s, const Eigen::Isometry3f& T,
                 std::uint64_t seed = 1) {
  const RgbdRenderer r(world, settings);
  RgbdImage img;
  r.render(s, T, seed, img);
  return img;
}

struct Stats {
  double mean = 0.0, stddev = 0.0;
  std::size_t n = 0;
};
inline Stats stats(const std::vector<double>& v) {
  Stats s;
  s.n = v.size();
  for (const double x : v) s.mean += x;
  s.mean /= static_cast<double>(v.size());
  for (const double x : v) s.stddev += (x - s.mean) * (x - s.mean);
  s.stddev = std::sqrt(s.stddev / static_cast<double>(v.size() - 1));
  return s;
}


// ---- test worlds ------------------------------------------------------------------------------------

inline World textured_room() {
  World w = empty_world(6.0f);
  w.ceiling_height_m = 2.6f;
  w.solids.push_back(wall_at_x(3.0f, 2.6f, Texture::kNoise));
  w.solids.push_back(prism({{-3, 2}, {3, 2}, {3, 2.2f}, {-3, 2.2f}}, 0.0f, 2.6f, Texture::kPosters, "left wall"));
  w.solids.push_back(prism({{-3, -2.2f}, {3, -2.2f}, {3, -2}, {-3, -2}}, 0.0f, 2.6f, Texture::kBricks, "right wall"));
  w.solids.push_back(rotated_box({1.8f, 0.5f}, 0.6f, 0.4f, 0.0f, 0.7f));
  duet::sim::validate(w);
  return w;
}

inline World posts_world() {
  // Thin posts of every texture in front of a textured wall: many 4x4 ray packets see two or
  // more faces (a post side and the wall, two sides of a post, a post and the floor).
  World w = empty_world();
  w.solids.push_back(wall_at_x(4.0f, 5.0f, Texture::kBricks));
  const Texture textures[] = {Texture::kNoise, Texture::kChecker, Texture::kBricks, Texture::kPosters, Texture::kPlain};
  for (int i = 0; i < 15; ++i) {
    const float x = 1.5f + 0.15f * static_cast<float>(i % 5), y = -1.4f + 0.2f * static_cast<float>(i);
    w.solids.push_back(rotated_box({x, y}, 0.04f + 0.01f * static_cast<float>(i % 3), 0.3f * static_cast<float>(i), 0.0f,
                                   0.8f + 0.1f * static_cast<float>(i % 4)));
    w.solids.back().surface.texture = textures[i % 5];
    w.solids.back().surface.texture_scale_m = 0.02f + 0.01f * static_cast<float>(i % 3);
    w.solids.back().surface.colour = {static_cast<std::uint8_t>(60 + 12 * i), 150, static_cast<std::uint8_t>(200 - 9 * i)};
  }
  duet::sim::validate(w);
  return w;
}

}  // namespace duet_test::render
