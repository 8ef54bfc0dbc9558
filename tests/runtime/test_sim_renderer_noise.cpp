// Simulated RGB-D sensors (issue 4, part 2): the Kinect noise model's statistics against Nguyen et
// al.'s axial and angular terms, disparity quantisation, dropout at grazing angles.
#include "sim_renderer_test_util.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace test_sim_renderer_noise {

using namespace duet_test::render;

// ---- noise model ------------------------------------------------------------------------------------

TEST(SimRendererNoise, GrazingAngleDropout) {
  World w = empty_world();
  w.solids.push_back(wall_at_x(2.5f));
  duet::sim::validate(w);
  RenderSettings rs;
  rs.noise.axial_a_m = rs.noise.axial_b_per_m = rs.noise.axial_angular_m = 0.0f;
  rs.noise.quantisation_per_m = 0.0f;
  rs.noise.dropout_rate = 0.0f;
  rs.noise.max_incidence_deg = 60.0f;
  const auto s = kinect(320, 240);
  // Yawed 45 deg to the wall, looking down at the floor a little: incidence 20-75 deg on the wall.
  const Eigen::Isometry3f T = camera({0.0f, 0.0f, 0.6f}, 0.8f, 0.1f);
  const RgbdImage img = render(w, rs, s, T);
  std::size_t dropped = 0, kept = 0, checked = 0;
  for (int v = 0; v < 240; ++v)
    for (int u = 0; u < 320; ++u) {
      const Ray r = pixel_ray(s, T, u, v);
      const RefHit h = cast(w, r);
      if (!std::isfinite(h.t) || h.t < 0.55 || h.t > 4.9) continue;
      const double inc = std::acos(std::abs(h.n.dot(r.d.normalized()))) / kDeg;
      if (std::abs(inc - 60.0) < 0.2) continue;
      const bool zero = img.depth[static_cast<std::size_t>(v * 320 + u)] == 0;
      ASSERT_EQ(zero, inc > 60.0) << u << "," << v << " incidence " << inc;
      ++checked;
      (zero ? dropped : kept)++;
    }
  EXPECT_GT(dropped, 1000u);
  EXPECT_GT(kept, 1000u);
  EXPECT_GT(checked, 30000u);
}

// Depths (m) of the wall pixels of a fronto-parallel wall at z0 (every pixel's true depth is z0).
std::vector<double> wall_depths(const KinectNoiseSettings& ns, float z0, std::uint64_t seed, std::size_t* zeros = nullptr) {
  World w = empty_world();
  w.solids.push_back(wall_at_x(z0, 8.0f));
  duet::sim::validate(w);
  RenderSettings rs;
  rs.noise = ns;
  const auto s = kinect();
  const RgbdImage img = render(w, rs, s, camera({0.0f, 0.0f, 2.0f}, 0.0f), seed);
  std::vector<double> d;
  std::size_t z = 0;
  for (int v = 0; v < 200; ++v)  // above the horizon: wall only
    for (int u = 0; u < 640; ++u) {
      const std::uint16_t raw = img.depth[static_cast<std::size_t>(v * 640 + u)];
      if (raw == 0)
        ++z;
      else
        d.push_back(raw / 1000.0);
    }
  if (zeros) *zeros = z;
  return d;
}

TEST(SimRendererNoise, AxialNoiseStatisticsFollowNguyen) {
  KinectNoiseSettings ns;
  ns.quantisation_per_m = 0.0f;
  ns.dropout_rate = 0.0f;
  ns.axial_angular_m = 0.0f;
  for (const float z0 : {1.0f, 2.5f, 4.0f}) {
    const std::vector<double> d = wall_depths(ns, z0, 11);
    ASSERT_EQ(d.size(), 200u * 640u);
    const Stats st = stats(d);
    const double sigma = 0.0012 + 0.0019 * (z0 - 0.4) * (z0 - 0.4);
    const double expected_std = std::sqrt(sigma * sigma + 1e-6 / 12.0);  // + 1 mm rounding
    EXPECT_NEAR(st.mean, z0, 4.0 * expected_std / std::sqrt(static_cast<double>(st.n)) + 1e-5) << "z0 = " << z0;
    EXPECT_NEAR(st.stddev / expected_std, 1.0, 0.03) << "z0 = " << z0 << " std " << st.stddev << " expected " << expected_std;
    if (z0 < 2.0f) continue;  // 1 mm raw units are too coarse for the shape test at 1 m
    // Gaussian-shaped: about 68 % within one sigma.
    const double within = static_cast<double>(std::count_if(d.begin(), d.end(), [&](double x) { return std::abs(x - z0) <= expected_std; })) /
                          static_cast<double>(d.size());
    EXPECT_NEAR(within, 0.683, 0.02) << "z0 = " << z0;
  }
}

TEST(SimRendererNoise, DisparityQuantisationAndDropout) {
  KinectNoiseSettings ns;  // defaults: quantisation and dropout on
  const float z0 = 3.0f;
  std::size_t zeros = 0;
  const std::vector<double> d = wall_depths(ns, z0, 5, &zeros);
  const double n = 200.0 * 640.0;
  // Dropout: binomial(n, 0.005); 6 sigma bounds.
  const double sd = std::sqrt(n * 0.005 * 0.995);
  EXPECT_NEAR(static_cast<double>(zeros), n * 0.005, 6.0 * sd);
  // Every value is a quantisation level 1 / (k q) (rounded to mm).
  std::set<int> levels;
  for (const double x : d) {
    const int raw = static_cast<int>(std::lround(x * 1000.0));
    levels.insert(raw);
    const double k = std::round(1.0 / (x * ns.quantisation_per_m));
    ASSERT_LE(std::abs(raw - std::lround(1000.0 / (k * ns.quantisation_per_m))), 1) << raw;
  }
  // Steps of ~ q z^2 = 26 mm at 3 m: few distinct values for sigma = 0.0135 m.
  EXPECT_LT(levels.size(), 15u);
  EXPECT_GT(levels.size(), 3u);
  const Stats st = stats(d);
  const double sigma = 0.0012 + 0.0019 * (z0 - 0.4) * (z0 - 0.4);
  const double step = ns.quantisation_per_m * z0 * z0;
  const double expected_std = std::sqrt(sigma * sigma + step * step / 12.0);
  EXPECT_NEAR(st.mean, z0, 0.1 * step);
  EXPECT_NEAR(st.stddev / expected_std, 1.0, 0.1);
}

TEST(SimRendererNoise, AngularTermAtObliqueIncidenceFollowsNguyen) {
  // A wall seen at 65-78 deg incidence: the residuals, normalised by Nguyen's sigma(z, theta)
  // (with its angular term), have unit spread; without the angular term in the renderer they
  // are clearly narrower than that model.
  World w = empty_world();
  w.solids.push_back(wall_at_x(0.6f, 5.0f));
  duet::sim::validate(w);
  const auto s = kinect();
  const Eigen::Isometry3f T = camera({0.0f, 0.0f, 1.5f}, 1.25f);
  auto normalised_std = [&](float angular) {
    RenderSettings rs;
    rs.noise.quantisation_per_m = 0.0f;
    rs.noise.dropout_rate = 0.0f;
    rs.noise.max_incidence_deg = 89.0f;
    rs.noise.axial_angular_m = angular;
    const RgbdImage img = render(w, rs, s, T, 21);
    std::vector<double> r;
    for (int v = 0; v < 480; ++v)
      for (int u = 0; u < 640; ++u) {
        const Ray ray = pixel_ray(s, T, u, v);
        const RefHit h = cast(w, ray);
        if (!std::isfinite(h.t) || std::abs(h.n.z()) > 0.5 || h.t < 0.6 || h.t > 4.5) continue;
        const double theta = std::acos(std::abs(h.n.dot(ray.d.normalized())));
        if (theta < 65.0 * kDeg || theta > 78.0 * kDeg) continue;
        const std::uint16_t raw = img.depth[static_cast<std::size_t>(v * 640 + u)];
        EXPECT_NE(raw, 0);
        const double z = h.t;
        const double sigma = 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4) +
                             0.0001 / std::sqrt(z) * theta * theta / ((std::numbers::pi / 2 - theta) * (std::numbers::pi / 2 - theta));
        r.push_back((raw / 1000.0 - z) / std::sqrt(sigma * sigma + 1e-6 / 12.0));
      }
    EXPECT_GT(r.size(), 20000u);
    return stats(r);
  };
  const Stats with = normalised_std(0.0001f);
  EXPECT_NEAR(with.mean, 0.0, 0.02);
  EXPECT_NEAR(with.stddev, 1.0, 0.04);
  const Stats without = normalised_std(0.0f);
  EXPECT_LT(without.stddev, 0.9);
}

}  // namespace test_sim_renderer_noise
