// estimate_motion on synthetic frames with known motion: 3D points seen by the paper's two
// cameras (Eq. 6 mounts), projected through the true motion with pixel noise, depth noise,
// outliers and shuffled order; each camera alone and both, with and without a good guess, guided
// matching, the fundamental filter on and off, determinism across thread counts, the failure
// statuses (blank views, too few matches), and named errors. Real frames: tests/runtime.
#include "kernels/kernel_test_util.hpp"

#include <duet/kernels/visual_odometry.hpp>

#include <numeric>
#include <random>

namespace duet {
namespace test_visual_odometry {

struct Scene {
  VisualFrame prev, curr;
  Eigen::Isometry3d motion;  // true T_prev_curr
};

PinholeIntrinsics kinect() { return {}; }

double rot_deg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd((a.linear().transpose() * b.linear())).angle() * 180.0 / 3.141592653589793;
}
double trans_m(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) { return (a.translation() - b.translation()).norm(); }

/// Points on the walls of a 6 x 6 m room around the robot, seen by `cams`; the current frame is
/// the same points after the robot moved by `motion`. `outliers` of the matches are wrong.
Scene make_scene(const std::vector<Eigen::Isometry3f>& cams, const Eigen::Isometry3d& motion, std::uint32_t seed,
                 double pixel_noise = 0.5, double outlier_share = 0.2, std::size_t per_camera = 400) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> px(0.0, pixel_noise), dz(0.0, 0.005);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  Scene sc;
  sc.motion = motion;
  const Eigen::Isometry3d X = motion.inverse();
  for (const auto& T_rc : cams) {
    VisualCamera p, c;
    p.intrinsics = c.intrinsics = kinect();
    p.T_robot_camera = c.T_robot_camera = T_rc;
    const Eigen::Isometry3d T_cr = T_rc.cast<double>().inverse();
    const PinholeIntrinsics K = kinect();
    auto project = [&](const Eigen::Vector3d& robot, Eigen::Vector2d& uv, double& z) {
      const Eigen::Vector3d r = T_cr * robot;
      z = r.z();
      uv = {K.fx * r.x() / r.z() + K.cx, K.fy * r.y() / r.z() + K.cy};
      return r.z() > 0.3 && uv.x() >= 0 && uv.x() < K.width && uv.y() >= 0 && uv.y() < K.height;
    };
    std::vector<std::size_t> order;
    std::size_t made = 0;
    while (made < per_camera) {
      // A random pixel of the previous view, at a random depth 1-5 m.
      const Eigen::Vector2d uv0(U(rng) * K.width, U(rng) * K.height);
      const double z0 = 1.0 + 4.0 * U(rng);
      const Eigen::Vector3d pc((uv0.x() - K.cx) * z0 / K.fx, (uv0.y() - K.cy) * z0 / K.fy, z0);
      const Eigen::Vector3d P = T_rc.cast<double>() * pc;
      Eigen::Vector2d uv1;
      double z1;
      if (!project(X * P, uv1, z1)) continue;
      Descriptor256 d{rng(), rng(), rng(), rng()};
      const bool outlier = U(rng) < outlier_share;
      p.features.pixels.push_back(uv0.cast<float>());
      p.features.descriptors.push_back(d);
      p.points_robot.push_back(P.cast<float>());
      p.depths_m.push_back(static_cast<float>(z0));
      Descriptor256 d1 = d;
      for (int k = 0; k < 10; ++k) {
        const auto bit = rng() % 256;
        d1[bit / 64] ^= std::uint64_t{1} << (bit % 64);
      }
      Eigen::Vector2d obs = uv1 + Eigen::Vector2d(px(rng), px(rng));
      if (outlier) obs = {U(rng) * K.width, U(rng) * K.height};
      c.features.pixels.push_back(obs.cast<float>());
      c.features.descriptors.push_back(d1);
      const double zc = z1 + dz(rng);
      const Eigen::Vector3d qc((obs.x() - K.cx) * zc / K.fx, (obs.y() - K.cy) * zc / K.fy, zc);
      c.points_robot.push_back((T_rc.cast<double>() * qc).cast<float>());
      c.depths_m.push_back(static_cast<float>(zc));
      ++made;
    }
    for (auto* cam : {&p, &c}) {
      cam->features.responses.assign(cam->features.size(), 1.0f);
      cam->features.octaves.assign(cam->features.size(), 0);
      cam->features.width = K.width;
      cam->features.height = K.height;
    }
    // Shuffle the current frame so the match is not the index.
    std::vector<std::size_t> perm(c.features.size());
    std::iota(perm.begin(), perm.end(), 0);
    std::shuffle(perm.begin(), perm.end(), rng);
    VisualCamera s = c;
    for (std::size_t i = 0; i < perm.size(); ++i) {
      s.features.pixels[i] = c.features.pixels[perm[i]];
      s.features.descriptors[i] = c.features.descriptors[perm[i]];
      s.points_robot[i] = c.points_robot[perm[i]];
      s.depths_m[i] = c.depths_m[perm[i]];
    }
    sc.prev.cameras.push_back(std::move(p));
    sc.curr.cameras.push_back(std::move(s));
  }
  return sc;
}

Eigen::Isometry3d planar(double x, double y, double theta_deg) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(theta_deg * 3.141592653589793 / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, 0.0);
  return T;
}

TEST(VisualOdometry, RecoversKnownMotionWithEachCameraAndBoth) {
  const std::vector<std::vector<Eigen::Isometry3f>> rigs = {
      {test::paper_sensor1()}, {test::paper_sensor2()}, {test::paper_sensor1(), test::paper_sensor2()}};
  const std::vector<Eigen::Isometry3d> motions = {planar(0.10, 0.0, 0.0), planar(0.05, 0.02, 8.0), planar(0.0, 0.0, -15.0),
                                                  planar(0.3, -0.1, 20.0)};
  std::uint32_t seed = 1;
  for (std::size_t r = 0; r < rigs.size(); ++r)
    for (const auto& M : motions) {
      const Scene sc = make_scene(rigs[r], M, seed++);
      VisualOdometrySettings s;
      const auto res = estimate_motion(sc.prev, sc.curr, Eigen::Isometry3d::Identity(), s);
      ASSERT_EQ(res.status, VisualOdometryStatus::kOk) << "rig " << r;
      EXPECT_LT(trans_m(res.motion, M), 0.01) << "rig " << r << " motion " << M.translation().transpose();
      EXPECT_LT(rot_deg(res.motion, M), 0.2) << "rig " << r;
      // ~80 % of 400 per camera are true matches.
      EXPECT_GT(res.inliers, 250u * rigs[r].size());
      EXPECT_LT(res.inliers, 360u * rigs[r].size());
      EXPECT_LT(res.rms_px, 1.5);
      ASSERT_EQ(res.camera_inliers.size(), rigs[r].size());
      EXPECT_TRUE(res.covariance.allFinite());
      EXPECT_GT(res.covariance.determinant(), 0.0);
      // The planar covariance is positive and small for this many inliers.
      const Eigen::Matrix3d P = planar_covariance(res.motion, res.covariance);
      EXPECT_GT(P(0, 0), 0.0);
      EXPECT_LT(std::sqrt(P(0, 0)), 0.01);
      EXPECT_LT(std::sqrt(P(2, 2)), 0.005);
    }
}

TEST(VisualOdometry, CovarianceMatchesTheSpreadOverNoiseDraws) {
  // 40 noise draws of the same motion: the spread of x should agree with the reported sigma
  // within a factor of two (a first-order covariance of a well-conditioned problem).
  const auto M = planar(0.1, 0.03, 5.0);
  std::vector<double> xs;
  double sigma_sum = 0.0;
  for (std::uint32_t k = 0; k < 40; ++k) {
    const Scene sc = make_scene({test::paper_sensor1(), test::paper_sensor2()}, M, 1000 + k, 1.0, 0.1);
    const auto res = estimate_motion(sc.prev, sc.curr, Eigen::Isometry3d::Identity(), {});
    ASSERT_EQ(res.status, VisualOdometryStatus::kOk);
    xs.push_back(res.motion.translation().x());
    sigma_sum += std::sqrt(planar_covariance(res.motion, res.covariance)(0, 0));
  }
  double mean = 0.0, var = 0.0;
  for (double x : xs) mean += x / xs.size();
  for (double x : xs) var += (x - mean) * (x - mean) / (xs.size() - 1);
  const double spread = std::sqrt(var), reported = sigma_sum / xs.size();
  EXPECT_GT(reported, spread / 2.0) << "reported " << reported << " spread " << spread;
  EXPECT_LT(reported, spread * 2.0) << "reported " << reported << " spread " << spread;
}

TEST(VisualOdometry, GuidedAndUnfilteredVariantsAgree) {
  const auto M = planar(0.12, -0.02, 6.0);
  const Scene sc = make_scene({test::paper_sensor1(), test::paper_sensor2()}, M, 77);
  for (const float radius : {0.0f, 40.0f})
    for (const bool filter : {true, false}) {
      VisualOdometrySettings s;
      s.guided_radius_px = radius;
      s.fundamental_filter = filter;
      // Guided matching needs a guess near the truth (the wheels): 2 cm and 1 degree off.
      const Eigen::Isometry3d guess = radius > 0.0f ? M * planar(0.02, 0.0, 1.0) : Eigen::Isometry3d::Identity();
      const auto res = estimate_motion(sc.prev, sc.curr, guess, s);
      ASSERT_EQ(res.status, VisualOdometryStatus::kOk) << radius << " " << filter;
      EXPECT_LT(trans_m(res.motion, M), 0.01) << radius << " " << filter;
      EXPECT_LT(rot_deg(res.motion, M), 0.2) << radius << " " << filter;
      if (filter) {
        EXPECT_LT(res.fundamental_inliers, res.matches) << "the filter removed no outlier";
      }
    }
}

TEST(VisualOdometry, SameResultForAnyThreadCountAndRun) {
  const Scene sc = make_scene({test::paper_sensor1(), test::paper_sensor2()}, planar(0.1, 0.0, 10.0), 5, 0.8, 0.4);
  auto run = [&](int threads) { return test::in_arena(threads, [&] { return estimate_motion(sc.prev, sc.curr, Eigen::Isometry3d::Identity(), {}); }); };
  const auto a = run(1), b = run(2), c = run(8), d = run(1);
  for (const auto* r : {&b, &c, &d}) {
    EXPECT_EQ(r->inliers, a.inliers);
    EXPECT_EQ(r->hypotheses, a.hypotheses);
    EXPECT_EQ(std::memcmp(r->motion.matrix().data(), a.motion.matrix().data(), 16 * sizeof(double)), 0);
  }
}

TEST(VisualOdometry, FailuresKeepTheGuessWithAStatus) {
  const auto M = planar(0.1, 0.0, 3.0);
  const Eigen::Isometry3d guess = planar(0.09, 0.0, 2.0);
  Scene sc = make_scene({test::paper_sensor1()}, M, 9);
  // A blank current view: no features.
  VisualFrame blank = sc.curr;
  blank.cameras[0] = VisualCamera{};
  auto r = estimate_motion(sc.prev, blank, guess, {});
  EXPECT_EQ(r.status, VisualOdometryStatus::kTooFewFeatures);
  EXPECT_TRUE(r.motion.isApprox(guess));
  EXPECT_EQ(r.inliers, 0u);
  // No depth in the previous frame: no 3D points.
  VisualFrame nodepth = sc.prev;
  for (auto& d : nodepth.cameras[0].depths_m) d = test::kNaN;
  for (auto& p : nodepth.cameras[0].points_robot) p.setConstant(test::kNaN);
  r = estimate_motion(nodepth, sc.curr, guess, {});
  EXPECT_EQ(r.status, VisualOdometryStatus::kTooFewFeatures);
  // Unrelated descriptors: nothing matches.
  VisualFrame other = sc.curr;
  std::mt19937_64 rng(3);
  for (auto& d : other.cameras[0].features.descriptors) d = {rng(), rng(), rng(), rng()};
  r = estimate_motion(sc.prev, other, guess, {});
  EXPECT_NE(r.status, VisualOdometryStatus::kOk);
  EXPECT_TRUE(r.motion.isApprox(guess));
  // Every match an outlier (pixels scrambled): too few inliers.
  Scene junk = make_scene({test::paper_sensor1()}, M, 10, 0.5, 1.0);
  r = estimate_motion(junk.prev, junk.curr, guess, {});
  EXPECT_NE(r.status, VisualOdometryStatus::kOk);
  EXPECT_TRUE(r.motion.isApprox(guess));
  // One camera blank, the other fine: the good one carries it.
  Scene two = make_scene({test::paper_sensor1(), test::paper_sensor2()}, M, 11);
  two.curr.cameras[1] = VisualCamera{};
  two.curr.cameras[1].intrinsics = kinect();
  two.curr.cameras[1].T_robot_camera = test::paper_sensor2();
  r = estimate_motion(two.prev, two.curr, Eigen::Isometry3d::Identity(), {});
  ASSERT_EQ(r.status, VisualOdometryStatus::kOk);
  EXPECT_LT(trans_m(r.motion, M), 0.01);
  EXPECT_EQ(r.camera_inliers[1], 0u);
}

TEST(VisualOdometry, BadArgumentsAreNamed) {
  const Scene sc = make_scene({test::paper_sensor1()}, planar(0.1, 0, 0), 12);
  const Scene two = make_scene({test::paper_sensor1(), test::paper_sensor2()}, planar(0.1, 0, 0), 13);
  const auto expect = [](const std::function<void()>& fn, const std::string& what) { test::expect_error(fn, what); };
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  expect([&] { (void)estimate_motion(sc.prev, two.curr, I, {}); }, "cameras");
  VisualOdometrySettings s;
  s.inlier_threshold_px = 0.0f;
  expect([&] { (void)estimate_motion(sc.prev, sc.curr, I, s); }, "inlier_threshold_px");
  s = {};
  s.confidence = 1.0f;
  expect([&] { (void)estimate_motion(sc.prev, sc.curr, I, s); }, "confidence");
  s = {};
  s.min_inliers = 2;
  expect([&] { (void)estimate_motion(sc.prev, sc.curr, I, s); }, "min_inliers");
  s = {};
  s.guided_radius_px = test::kNaN;
  expect([&] { (void)estimate_motion(sc.prev, sc.curr, I, s); }, "guided_radius_px");
  // make_visual_frame: sizes named per camera.
  std::vector<std::uint16_t> depth(640 * 480, 1000);
  std::vector<std::uint8_t> rgb(320 * 240 * 3, 0);
  SensorFrame f;
  f.depth.data = depth.data();
  f.depth.width = 640;
  f.depth.height = 480;
  f.intrinsics = kinect();
  f.color.data = rgb.data();
  f.color.width = 320;
  f.color.height = 240;
  VisualFrame out;
  expect([&] { make_visual_frame(std::span(&f, 1), {}, out); }, "colour image 320x240");
  f.color.data = nullptr;
  f.depth.width = 320;
  expect([&] { make_visual_frame(std::span(&f, 1), {}, out); }, "depth image 320x480");
  f.depth.width = 640;
  f.depth.data = nullptr;
  expect([&] { make_visual_frame(std::span(&f, 1), {}, out); }, "no depth image");
  VisualFrameSettings vs;
  vs.max_depth_m = 0.1f;
  f.depth.data = depth.data();
  expect([&] { make_visual_frame(std::span(&f, 1), vs, out); }, "max_depth_m");
}

TEST(VisualOdometry, FrameWithoutColourHasNoFeatures) {
  std::vector<std::uint16_t> depth(640 * 480, 1500);
  SensorFrame f;
  f.depth.data = depth.data();
  f.depth.width = 640;
  f.depth.height = 480;
  f.intrinsics = kinect();
  VisualFrame out;
  make_visual_frame(std::span(&f, 1), {}, out);
  ASSERT_EQ(out.cameras.size(), 1u);
  EXPECT_EQ(out.features(), 0u);
  make_visual_frame({}, {}, out);
  EXPECT_TRUE(out.cameras.empty());
}

}  // namespace test_visual_odometry
}  // namespace duet
