// 2D pose-graph optimisation (kernels/pose_graph.hpp): recovers the truth from exact
// measurements, reaches a stationary point of the cost with inconsistent ones (checked against
// a finite-difference gradient), keeps the fixed node, down-weights a robust outlier, and names
// bad input.
#include <duet/kernels/error.hpp>
#include <duet/kernels/pose_graph.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

namespace duet {
namespace test_pose_graph {

constexpr float kPi = std::numbers::pi_v<float>;

PoseGraphEdge edge(std::uint32_t i, std::uint32_t j, const std::vector<Pose2>& truth, float sxy = 0.05f, float sth = 0.01f) {
  PoseGraphEdge e;
  e.from = i;
  e.to = j;
  e.measurement = compose(inverse(truth[i]), truth[j]);
  e.sigma_xy_m = sxy;
  e.sigma_theta_rad = sth;
  return e;
}

/// A loop: `n` poses around a 10 m x 6 m rectangle, heading along the way.
std::vector<Pose2> rectangle(int n) {
  std::vector<Pose2> p;
  const float per = 32.0f;
  for (int k = 0; k < n; ++k) {
    float s = per * static_cast<float>(k) / static_cast<float>(n);
    if (s < 10.0f) p.push_back({s, 0.0f, 0.0f});
    else if (s < 16.0f) p.push_back({10.0f, s - 10.0f, kPi / 2});
    else if (s < 26.0f) p.push_back({10.0f - (s - 16.0f), 6.0f, kPi});
    else p.push_back({0.0f, 6.0f - (s - 26.0f), -kPi / 2});
  }
  return p;
}

double total(const std::vector<Pose2>& x, const std::vector<PoseGraphEdge>& edges) {
  double c = 0.0;
  for (const auto& e : edges) c += pose_graph_edge_chi2(x, e);
  return c;
}

TEST(PoseGraph, RecoversTheTruthFromExactMeasurementsAndADriftedGuess) {
  const std::vector<Pose2> truth = rectangle(32);
  std::vector<PoseGraphEdge> edges;
  for (std::uint32_t k = 0; k + 1 < truth.size(); ++k) edges.push_back(edge(k, k + 1, truth));
  edges.push_back(edge(31, 0, truth));
  edges.push_back(edge(4, 20, truth));
  // Initial guess: the odometry with a heading drift of 0.5 deg per step.
  std::vector<Pose2> x(truth.size());
  x[0] = truth[0];
  for (std::size_t k = 1; k < truth.size(); ++k) {
    Pose2 z = edges[k - 1].measurement;
    z.theta += 0.5f * kPi / 180.0f;
    x[k] = compose(x[k - 1], z);
  }
  ASSERT_GT(std::hypot(x[31].x - truth[31].x, x[31].y - truth[31].y), 1.0f);
  const PoseGraphResult r = optimize_pose_graph(x, edges);
  EXPECT_GT(r.initial_cost, 1e3);
  EXPECT_LT(r.final_cost, 1e-6);
  for (std::size_t k = 0; k < truth.size(); ++k) {
    EXPECT_NEAR(x[k].x, truth[k].x, 1e-3) << k;
    EXPECT_NEAR(x[k].y, truth[k].y, 1e-3) << k;
    EXPECT_NEAR(std::remainder(x[k].theta - truth[k].theta, 2 * kPi), 0.0f, 1e-4) << k;
  }
}

TEST(PoseGraph, InconsistentMeasurementsEndAtAStationaryPointOfTheCost) {
  std::mt19937 rng(7);
  std::normal_distribution<float> n01(0.0f, 1.0f);
  const std::vector<Pose2> truth = rectangle(24);
  std::vector<PoseGraphEdge> edges;
  for (std::uint32_t k = 0; k + 1 < truth.size(); ++k) edges.push_back(edge(k, k + 1, truth, 0.05f, 0.01f));
  edges.push_back(edge(23, 0, truth, 0.03f, 0.005f));
  edges.push_back(edge(6, 18, truth, 0.03f, 0.005f));
  for (auto& e : edges) {
    e.measurement.x += 0.05f * n01(rng);
    e.measurement.y += 0.05f * n01(rng);
    e.measurement.theta += 0.01f * n01(rng);
  }
  std::vector<Pose2> x(truth.size());
  x[0] = truth[0];
  for (std::size_t k = 1; k < truth.size(); ++k) x[k] = compose(x[k - 1], edges[k - 1].measurement);
  const double before = total(x, edges);
  const PoseGraphResult r = optimize_pose_graph(x, edges);
  EXPECT_NEAR(r.final_cost, total(x, edges), 1e-2 * r.final_cost + 1e-3);
  EXPECT_LT(r.final_cost, 0.2 * before);
  EXPECT_EQ(x[0].x, truth[0].x);
  EXPECT_EQ(x[0].y, truth[0].y);
  // Reference: the cost does not fall by a finite step along any coordinate of any free node.
  const double c0 = total(x, edges);
  for (std::size_t k = 1; k < x.size(); ++k)
    for (int a = 0; a < 3; ++a)
      for (const float h : {-2e-3f, 2e-3f}) {
        std::vector<Pose2> y = x;
        (a == 0 ? y[k].x : a == 1 ? y[k].y : y[k].theta) += h * (a == 2 ? 0.2f : 1.0f);
        EXPECT_GE(total(y, edges), c0 - 1e-3 * c0 - 1e-4) << "node " << k << " axis " << a;
      }
  // The estimate is near the truth (noise of a few cm).
  for (std::size_t k = 0; k < truth.size(); ++k) EXPECT_LT(std::hypot(x[k].x - truth[k].x, x[k].y - truth[k].y), 0.5f) << k;
}

TEST(PoseGraph, ARobustEdgeLimitsAWrongLoopAndAPlainOneDoesNot) {
  const std::vector<Pose2> truth = rectangle(24);
  std::vector<PoseGraphEdge> edges;
  for (std::uint32_t k = 0; k + 1 < truth.size(); ++k) edges.push_back(edge(k, k + 1, truth, 0.01f, 0.002f));
  edges.push_back(edge(23, 0, truth, 0.01f, 0.002f));
  PoseGraphEdge wrong = edge(5, 17, truth, 0.05f, 0.01f);
  wrong.measurement.x += 2.0f;  // a false loop, 2 m off
  auto error_with = [&](bool robust) {
    std::vector<PoseGraphEdge> es = edges;
    wrong.robust = robust;
    es.push_back(wrong);
    std::vector<Pose2> x = truth;
    (void)optimize_pose_graph(x, es);
    float worst = 0.0f;
    for (std::size_t k = 0; k < truth.size(); ++k) worst = std::max(worst, std::hypot(x[k].x - truth[k].x, x[k].y - truth[k].y));
    return worst;
  };
  // Odometry good to 1 cm per edge: spreading 2 m over the loop costs more than the Huber loss
  // of leaving the false loop alone, but less than its square.
  const float plain = error_with(false), robust = error_with(true);
  std::printf("worst error: plain %.3f m, robust %.3f m\n", static_cast<double>(plain), static_cast<double>(robust));
  EXPECT_GT(plain, 0.15f);
  EXPECT_LT(robust, 0.5f * plain);
}

TEST(PoseGraph, AnotherFixedNodeStaysAndEmptyGraphsDoNothing) {
  const std::vector<Pose2> truth = rectangle(8);
  std::vector<PoseGraphEdge> edges;
  for (std::uint32_t k = 0; k + 1 < truth.size(); ++k) edges.push_back(edge(k, k + 1, truth));
  std::vector<Pose2> x(truth.size(), Pose2{1.0f, 2.0f, 0.3f});
  PoseGraphSettings s;
  s.fixed_node = 3;
  (void)optimize_pose_graph(x, edges, s);
  EXPECT_EQ(x[3].x, 1.0f);
  EXPECT_EQ(x[3].y, 2.0f);
  EXPECT_FLOAT_EQ(x[3].theta, 0.3f);
  // Relative poses are the measurements.
  for (const auto& e : edges) EXPECT_LT(pose_graph_edge_chi2(x, e), 1e-6);
  // No poses, one pose, no edges.
  std::vector<Pose2> none;
  EXPECT_EQ(optimize_pose_graph(none, {}).final_cost, 0.0);
  std::vector<Pose2> one{{1.0f, 1.0f, 1.0f}};
  (void)optimize_pose_graph(one, {});
  EXPECT_EQ(one[0].x, 1.0f);
  std::vector<Pose2> two{{0, 0, 0}, {1, 0, 0}};
  (void)optimize_pose_graph(two, {});
  EXPECT_EQ(two[1].x, 1.0f);
  // A node no edge reaches stays where it is.
  std::vector<Pose2> three{{0, 0, 0}, {1, 0, 0}, {5, 5, 1}};
  std::vector<PoseGraphEdge> e01{edge(0, 1, {{0, 0, 0}, {2, 0, 0}})};
  (void)optimize_pose_graph(three, e01);
  EXPECT_NEAR(three[1].x, 2.0f, 1e-4);
  EXPECT_EQ(three[2].x, 5.0f);
  EXPECT_EQ(three[2].theta, 1.0f);
}

TEST(PoseGraph, BadInputIsNamedAndLeavesThePoses) {
  std::vector<Pose2> x{{0, 0, 0}, {1, 0, 0}};
  const std::vector<Pose2> before = x;
  auto expect_error = [&](std::vector<PoseGraphEdge> es, const char* what, PoseGraphSettings s = {}) {
    try {
      (void)optimize_pose_graph(x, es, s);
      ADD_FAILURE() << "no error for " << what;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
    EXPECT_EQ(x[1].x, before[1].x);
  };
  PoseGraphEdge e;
  e.from = 0;
  e.to = 2;
  expect_error({e}, "names node 2");
  e.to = 0;
  expect_error({e}, "to itself");
  e.to = 1;
  e.measurement.x = std::nanf("");
  expect_error({e}, "non-finite measurement");
  e.measurement.x = 1.0f;
  e.sigma_xy_m = 0.0f;
  expect_error({e}, "sigmas");
  e.sigma_xy_m = 0.1f;
  PoseGraphSettings s;
  s.fixed_node = 5;
  expect_error({e}, "fixed_node", s);
  s = {};
  s.max_iterations = 0;
  expect_error({e}, "max_iterations", s);
  s = {};
  s.huber_delta = -1.0;
  expect_error({e}, "huber_delta", s);
  x[1].theta = std::numeric_limits<float>::infinity();
  expect_error({e}, "pose 1");
}

}  // namespace test_pose_graph
}  // namespace duet
