// Simulated RGB-D sensors (issue 4, part 2): determinism (seeds, thread count), texture features,
// colour and shading, the SSE2 texture path against the scalar one, and packets of rays that see
// several faces. The same bytes on every machine: test_sim_renderer_isa.cpp.
#include "sim_renderer_test_util.hpp"

#if defined(__SSE2__)
#include "../../runtime/sim/src/texture_simd.hpp"  // internal: the renderer's SSE2 texture path
#endif

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <set>
#include <span>
#include <vector>

namespace test_sim_renderer_image {

using namespace duet_test::render;

// ---- determinism ------------------------------------------------------------------------------------

TEST(SimRendererDeterminism, SameSeedSameImageDifferentSeedDifferentNoise) {
  const World w = textured_room();
  const RgbdRenderer r(w, RenderSettings{});
  const auto s = kinect(320, 240);
  const Eigen::Isometry3f T = camera({0.0f, 0.0f, 0.5f}, 0.3f);
  RgbdImage a, b, c;
  r.render(s, T, 42, a);
  r.render(s, T, 42, b);
  r.render(s, T, 43, c);
  EXPECT_EQ(a.depth, b.depth);
  EXPECT_EQ(a.rgb, b.rgb);
  std::size_t differ = 0, valid = 0;
  for (std::size_t p = 0; p < a.depth.size(); ++p) {
    valid += a.depth[p] > 0 ? 1 : 0;
    differ += a.depth[p] != c.depth[p] ? 1 : 0;
  }
  EXPECT_GT(valid, 40000u);
  EXPECT_GT(differ, valid / 4);
  EXPECT_EQ(a.rgb, c.rgb);  // colour has no noise
}

TEST(SimRendererDeterminism, OneAndTwoThreadsGiveIdenticalImages) {
  const World w = textured_room();
  const RgbdRenderer r(w, RenderSettings{});
  const auto s = kinect();
  const Eigen::Isometry3f T = camera({-0.5f, 0.3f, 0.4f}, -0.4f, 0.05f);
  RgbdImage one, two;
  tbb::task_arena a1(1), a2(2);
  a1.execute([&] { r.render(s, T, 9, one); });
  a2.execute([&] { r.render(s, T, 9, two); });
  EXPECT_EQ(one.depth, two.depth);
  EXPECT_EQ(one.rgb, two.rgb);
  // A reused output buffer gives the same image as a fresh one.
  a2.execute([&] { r.render(s, camera({0.0f, 0.0f, 1.0f}, 1.0f), 3, two); });
  a2.execute([&] { r.render(s, T, 9, two); });
  EXPECT_EQ(one.depth, two.depth);
  EXPECT_EQ(one.rgb, two.rgb);
}

// ---- colour -----------------------------------------------------------------------------------------

cv::Mat gray(const RgbdImage& img) {
  cv::Mat rgb(img.height, img.width, CV_8UC3, const_cast<std::uint8_t*>(img.rgb.data()));
  cv::Mat g;
  cv::cvtColor(rgb, g, cv::COLOR_RGB2GRAY);
  return g;
}

TEST(SimRendererColour, TexturedWallsHaveManyCorners) {
  // ORB (features2d) is not linked into test_runtime: count Shi-Tomasi corners instead, with
  // the quality level a feature tracker would use.
  const auto s = kinect();
  auto corners = [&](Texture tex) {
    World w = empty_world();
    w.solids.push_back(wall_at_x(2.0f, 5.0f, tex));
    duet::sim::validate(w);
    const RgbdImage img = render(w, RenderSettings{}, s, camera({0.0f, 0.0f, 1.2f}, 0.3f, -0.1f));
    std::vector<cv::Point2f> pts;
    cv::goodFeaturesToTrack(gray(img), pts, 2000, 0.01, 8.0);
    return pts.size();
  };
  for (const Texture t : {Texture::kNoise, Texture::kBricks, Texture::kPosters, Texture::kChecker})
    EXPECT_GE(corners(t), 200u) << "texture " << static_cast<int>(t);
  // A plain wall (and plain floor) has (almost) none: the count above comes from the texture.
  World plain = empty_world();
  plain.floor_surface.texture = Texture::kPlain;
  plain.solids.push_back(wall_at_x(2.0f, 5.0f, Texture::kPlain));
  duet::sim::validate(plain);
  const RgbdImage img = render(plain, RenderSettings{}, s, camera({0.0f, 0.0f, 1.2f}, 0.3f, -0.1f));
  std::vector<cv::Point2f> pts;
  cv::goodFeaturesToTrack(gray(img), pts, 2000, 0.01, 8.0);
  EXPECT_LT(pts.size(), 30u);
}

TEST(SimRendererColour, TextureIsAnchoredToTheWorld) {
  // Moving the camera parallel to a fronto-parallel wall by exactly 8 pixels' worth shifts the
  // image by 8 pixels: the same wall point has the same colour from both views.
  World w = empty_world();
  w.solids.push_back(wall_at_x(2.0f, 5.0f, Texture::kNoise));
  w.solids.back().surface.texture_scale_m = 0.05f;
  duet::sim::validate(w);
  const auto s = kinect(320, 240);
  const float shift_m = 8.0f * 2.0f / s.intrinsics.fx;  // 8 px at 2 m
  const RgbdImage a = render(w, RenderSettings{}, s, camera({0.0f, 0.0f, 2.0f}, 0.0f));
  // Optical x is right = world -y: moving the camera to -y shifts the view right.
  const RgbdImage b = render(w, RenderSettings{}, s, camera({0.0f, -shift_m, 2.0f}, 0.0f));
  std::size_t same = 0, n = 0, nonuniform = 0;
  for (int v = 0; v < 100; ++v)
    for (int u = 0; u + 8 < 320; ++u) {
      const std::size_t pa = static_cast<std::size_t>(v * 320 + u + 8), pb = static_cast<std::size_t>(v * 320 + u);
      ++n;
      same += (a.rgb[3 * pa] == b.rgb[3 * pb] && a.rgb[3 * pa + 1] == b.rgb[3 * pb + 1] && a.rgb[3 * pa + 2] == b.rgb[3 * pb + 2]) ? 1 : 0;
      nonuniform += a.rgb[3 * pa] != a.rgb[3 * pb] ? 1 : 0;
    }
  EXPECT_GT(static_cast<double>(same) / static_cast<double>(n), 0.97);
  EXPECT_GT(nonuniform, n / 10);  // the comparison is not trivially true on a flat colour
}

TEST(SimRendererColour, LambertShadingFromTheFixedLight) {
  // Two plain walls facing -x and +x under a light from +x: the one facing +x is brighter.
  World w = empty_world();
  w.solids.push_back(wall_at_x(2.0f, 5.0f, Texture::kPlain));   // face at x = 2 faces -x
  w.solids.push_back(prism({{-2.2f, -15}, {-2.0f, -15}, {-2.0f, 15}, {-2.2f, 15}}, 0, 5, Texture::kPlain, "behind"));
  duet::sim::validate(w);
  RenderSettings rs;
  rs.light_direction = Eigen::Vector3f(1.0f, 0.0f, 0.0f);
  rs.ambient = 0.4f;
  const auto s = kinect(32, 24);
  const RgbdImage front = render(w, rs, s, camera({0.0f, 0.0f, 1.5f}, 0.0f));
  const RgbdImage back = render(w, rs, s, camera({0.0f, 0.0f, 1.5f}, static_cast<float>(std::numbers::pi)));
  // Plain surfaces: colour = 180 * shade; shade 0.4 (facing away) and 1.0 (facing the light).
  EXPECT_NEAR(front.rgb[3 * 2], 180.0 * 0.4, 1.0);
  EXPECT_NEAR(back.rgb[3 * 2], 180.0, 1.0);
}

// ---- SSE2 texture path ----------------------------------------------------------------------------

#if defined(__SSE2__)
bool same_float(float a, float b) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  return std::memcmp(&a, &b, sizeof(float)) == 0;  // also tells -0 from +0
}

// Texture coordinates [cells] that exercise every branch: random values, integers and their
// neighbouring floats (lattice and cell edges), mortar / poster thresholds, large values,
// values beyond the +-1e9 clamp, zeros, a denormal, infinities and NaN.
std::vector<float> texture_coordinates() {
  std::vector<float> c;
  std::mt19937 rng(1234);
  std::uniform_real_distribution<float> small(-40.0f, 40.0f), big(-2e5f, 2e5f);
  for (int i = 0; i < 60; ++i) c.push_back(small(rng));
  for (int i = 0; i < 10; ++i) c.push_back(big(rng));
  for (const float k : {-5.0f, -1.0f, 0.0f, 1.0f, 2.0f, 3.0f, 4.0f, 7.0f}) {
    c.push_back(k);
    c.push_back(std::nextafter(k, -1e30f));
    c.push_back(std::nextafter(k, 1e30f));
    c.push_back(k + 0.1f);
    c.push_back(k + 1.0f / 3.0f);
    c.push_back(k + 0.25f);
  }
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  for (const float v : {-0.0f, 1e-40f, 1e6f, -1e6f, 9.9e8f, 1e9f, -1e9f, 3e9f, -3e9f, 1e30f, inf, -inf, nan}) c.push_back(v);
  return c;
}

TEST(SimRendererTexture, Sse2HelpersMatchScalar) {
  namespace d = duet::sim::detail;
  const std::vector<float> c = texture_coordinates();
  for (std::size_t i = 0; i + 4 <= c.size(); ++i) {
    alignas(16) std::int32_t fl[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(fl), d::fast_floor4(_mm_loadu_ps(&c[i])));
    for (int k = 0; k < 4; ++k) {
      if (std::isnan(c[i + k])) continue;  // the scalar conversion of NaN is undefined behaviour in C++
      ASSERT_EQ(fl[k], d::fast_floor(c[i + k])) << c[i + k];
    }
  }
  std::mt19937 rng(99);
  for (int n = 0; n < 2000; ++n) {
    alignas(16) std::int32_t x[4], y[4];
    alignas(16) std::uint32_t h[4];
    for (int k = 0; k < 4; ++k) {
      x[k] = static_cast<std::int32_t>(rng());
      y[k] = n < 4 ? std::numeric_limits<std::int32_t>::min() + k : static_cast<std::int32_t>(rng());
    }
    const std::uint32_t seed = rng();
    _mm_store_si128(reinterpret_cast<__m128i*>(h),
                    d::lattice_hash4(_mm_load_si128(reinterpret_cast<const __m128i*>(x)), _mm_load_si128(reinterpret_cast<const __m128i*>(y)),
                                     _mm_set1_epi32(static_cast<int>(seed))));
    for (int k = 0; k < 4; ++k) ASSERT_EQ(h[k], d::lattice_hash(x[k], y[k], seed));
  }
}

TEST(SimRendererTexture, Sse2TextureIsBitIdenticalToScalar) {
  namespace d = duet::sim::detail;
  const std::vector<float> c = texture_coordinates();
  const d::Rgbf base{181.0f, 122.0f, 63.0f};
  std::size_t compared = 0, distinct_values = 0;
  for (const Texture tex : {Texture::kPlain, Texture::kNoise, Texture::kChecker, Texture::kBricks, Texture::kPosters}) {
    for (const std::uint32_t seed : {0u, 1u, 0xDEADBEEFu, 0x7F4A7C15u}) {
      std::set<float> values;
      for (std::size_t j = 0; j < c.size(); ++j)
        for (std::size_t i = 0; i + 4 <= c.size(); i += 4) {
          // Lanes: four u values, one v (and the same with u, v swapped).
          for (int swap = 0; swap < 2; ++swap) {
            const __m128 a = _mm_loadu_ps(&c[i]), b = _mm_set1_ps(c[j]);
            const d::Rgb4 got = swap ? d::evaluate_texture4(tex, base, b, a, seed) : d::evaluate_texture4(tex, base, a, b, seed);
            alignas(16) float r[4], g[4], bl[4];
            _mm_store_ps(r, got.r);
            _mm_store_ps(g, got.g);
            _mm_store_ps(bl, got.b);
            for (int k = 0; k < 4; ++k) {
              const float u = swap ? c[j] : c[i + static_cast<std::size_t>(k)], v = swap ? c[i + static_cast<std::size_t>(k)] : c[j];
              if (std::isnan(u) || std::isnan(v)) continue;  // scalar float -> int of NaN: undefined behaviour
              const d::Rgbf want = d::evaluate_texture(tex, base, u, v, seed);
              ASSERT_TRUE(same_float(r[k], want.r) && same_float(g[k], want.g) && same_float(bl[k], want.b))
                  << "texture " << static_cast<int>(tex) << " seed " << seed << " at (" << u << ", " << v << "): got (" << r[k] << ", "
                  << g[k] << ", " << bl[k] << "), scalar (" << want.r << ", " << want.g << ", " << want.b << ")";
              values.insert(want.r);
              ++compared;
            }
          }
        }
      if (tex != Texture::kPlain) {
        EXPECT_GT(values.size(), 1u) << "texture " << static_cast<int>(tex);  // not trivially equal
        distinct_values += values.size();
      }
    }
  }
  EXPECT_GT(compared, 100000u);
  EXPECT_GT(distinct_values, 1000u);
}
#endif  // __SSE2__

TEST(SimRendererColour, PacketsSpanningSeveralFacesMatchSinglePixelRenders) {
  // Every pixel of a 160x120 image against a 1x1 image looking along the same ray (its
  // principal point shifted by the pixel's offset): a one-lane packet sees one face, so this
  // checks the shader's face-by-face pass over mixed packets. The two ray directions are
  // computed with different roundings, so a pixel on a texture or silhouette edge may differ.
  const World w = posts_world();
  const RgbdRenderer r(w, noise_free());
  const auto s = kinect(160, 120);
  const Eigen::Isometry3f T = camera({0.0f, 0.0f, 0.7f}, 0.0f, 0.15f);
  RgbdImage big, one;
  r.render(s, T, 1, big);
  std::size_t equal = 0, mixed = 0, mixed_equal = 0;
  for (int v = 0; v < 120; ++v)
    for (int u = 0; u < 160; ++u) {
      auto s1 = kinect(1, 1);
      s1.intrinsics.fx = s.intrinsics.fx;
      s1.intrinsics.fy = s.intrinsics.fy;
      s1.intrinsics.cx = s.intrinsics.cx - static_cast<float>(u);
      s1.intrinsics.cy = s.intrinsics.cy - static_cast<float>(v);
      r.render(s1, T, 1, one);
      const std::size_t p = static_cast<std::size_t>(v * 160 + u);
      const bool same = std::equal(one.rgb.begin(), one.rgb.end(), big.rgb.begin() + static_cast<std::ptrdiff_t>(3 * p));
      equal += same ? 1 : 0;
      // Does this pixel's 4x4 packet see more than one plane (reference ray caster)?
      std::set<int> faces;
      for (int k = 0; k < 16; ++k) faces.insert(cast(w, pixel_ray(s, T, u / 4 * 4 + k % 4, v / 4 * 4 + k / 4)).face);
      if (faces.size() > 1) {
        ++mixed;
        mixed_equal += same ? 1 : 0;
      }
    }
  const double n = 160.0 * 120.0;
  EXPECT_GT(static_cast<double>(mixed) / n, 0.15);  // the scene does test mixed packets
  EXPECT_GT(static_cast<double>(equal) / n, 0.98);
  EXPECT_GT(static_cast<double>(mixed_equal) / static_cast<double>(mixed), 0.95);
}

}  // namespace test_sim_renderer_image
