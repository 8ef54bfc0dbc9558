// scan_match(): recovery of a known offset in a room (both axes and heading constrained), a
// corridor (the prior kept along it), the score against a plain per-point reference, the search
// against an exhaustive reference over the same lattice, thread counts, empty / NaN / off-grid
// points, an empty map, and invalid settings, views and priors.
#include "kernel_test_util.hpp"

#include <duet/kernels/error.hpp>
#include <duet/kernels/scan_match.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

namespace duet {
namespace test_scan_match {

constexpr float kRes = 0.05f;
constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;

struct Map {
  std::vector<float> l;
  int w = 0, h = 0;
  InflatedGrid field;
  /// Distance to the nearest occupied cell (unknown and uncertain cells not blocking).
  void build() { occupied_distance(GridView(l, w, h, kRes, Eigen::Vector2f::Zero()), CellThresholds{}, field); }
  void occupy(float x, float y) {
    const int ix = static_cast<int>(std::floor(x / kRes)), iy = static_cast<int>(std::floor(y / kRes));
    if (ix >= 0 && iy >= 0 && ix < w && iy < h) l[static_cast<std::size_t>(iy) * w + ix] = 3.0f;
  }
};

/// Walls of a 6 x 4 m room with an inner box, sampled every 2 cm (map frame). Their lines run
/// through cell centres (x.x25 m): the field's minima are the occupied cells' centres, so a wall
/// on a cell edge would put the match half a cell (the grid's own quantisation) off.
std::vector<Eigen::Vector2f> room_walls() {
  std::vector<Eigen::Vector2f> w;
  constexpr float c = 0.025f;
  for (float t = 0.0f; t <= 6.0f; t += 0.02f) {
    w.emplace_back(1.0f + c + t, 1.0f + c);
    w.emplace_back(1.0f + c + t, 5.0f + c);
  }
  for (float t = 0.0f; t <= 4.0f; t += 0.02f) {
    w.emplace_back(1.0f + c, 1.0f + c + t);
    w.emplace_back(7.0f + c, 1.0f + c + t);
  }
  for (float t = 0.0f; t <= 0.8f; t += 0.02f) {  // a 0.8 m box at (4.5, 3.2)
    w.emplace_back(4.5f + c + t, 3.2f + c);
    w.emplace_back(4.5f + c, 3.2f + c + t);
  }
  return w;
}

/// Two parallel walls 2 m apart along x (y = 2.025 and 4.025 m, 7.8 m long), every 2 cm.
std::vector<Eigen::Vector2f> corridor_walls() {
  std::vector<Eigen::Vector2f> w;
  for (float t = 0.0f; t <= 7.8f; t += 0.02f) {
    w.emplace_back(t, 2.025f);
    w.emplace_back(t, 4.025f);
  }
  return w;
}

Map map_of(const std::vector<Eigen::Vector2f>& walls, int w = 160, int h = 120) {
  Map m;
  m.w = w;
  m.h = h;
  m.l.assign(static_cast<std::size_t>(w) * h, -2.0f);  // known free
  for (const auto& p : walls) m.occupy(p.x(), p.y());
  m.build();
  return m;
}

/// The wall points within `range` of `truth`, in the robot frame, with Gaussian noise.
std::vector<Eigen::Vector2f> scan_from(const std::vector<Eigen::Vector2f>& walls, const Pose2& truth, float range, float noise,
                                       std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> n(0.0f, noise);
  const float c = std::cos(truth.theta), s = std::sin(truth.theta);
  std::vector<Eigen::Vector2f> out;
  for (const auto& p : walls) {
    const Eigen::Vector2f d = p - Eigen::Vector2f(truth.x, truth.y);
    if (d.norm() > range) continue;
    out.emplace_back(c * d.x() + s * d.y() + n(rng), -s * d.x() + c * d.y() + n(rng));
  }
  return out;
}

float weight(const Pose2& p, const Pose2& prior, float score, const ScanMatchSettings& s) {
  const float dx = p.x - prior.x, dy = p.y - prior.y;
  const float dt = std::remainder(p.theta - prior.theta, 2.0f * std::numbers::pi_v<float>);
  const float sa = s.prior_sigma_deg * kDeg;
  return score * std::exp(-(dx * dx + dy * dy) / (2 * s.prior_sigma_m * s.prior_sigma_m) - dt * dt / (2 * sa * sa));
}

TEST(ScanMatch, RecoversAnOffsetInARoom) {
  const auto walls = room_walls();
  const Map m = map_of(walls);
  const Pose2 truth{3.0f, 2.6f, 0.4f};
  const auto pts = scan_from(walls, truth, 5.0f, 0.01f, 7);
  ASSERT_GT(pts.size(), 200u);
  for (const Pose2 off : {Pose2{0.1f, -0.06f, 1.2f * kDeg}, Pose2{-0.12f, 0.1f, -1.4f * kDeg}, Pose2{0.0f, 0.0f, 0.0f}}) {
    const Pose2 prior{truth.x + off.x, truth.y + off.y, truth.theta + off.theta};
    // With the default prior (and window) the match moves towards the truth: the translation
    // (here well constrained) most of the way; the heading at least not away (the 2 deg prior
    // holds a 1.4 deg offset; the runtime's corrections per update are far smaller).
    const ScanMatchResult d = scan_match(m.field.clearance(), pts, prior);
    EXPECT_EQ(d.status, ScanMatchStatus::kMatched);
    EXPECT_LE(std::hypot(d.pose.x - truth.x, d.pose.y - truth.y), 0.5f * std::hypot(off.x, off.y) + 0.02f);
    EXPECT_LE(std::fabs(d.pose.theta - truth.theta), std::fabs(off.theta) + 0.3f * kDeg);
    EXPECT_GE(d.score, d.prior_score);
    // With a flat prior it finds the truth.
    ScanMatchSettings flat;
    flat.prior_sigma_m = 100.0f;
    flat.prior_sigma_deg = 100.0f;
    const ScanMatchResult r = scan_match(m.field.clearance(), pts, prior, flat);
    EXPECT_EQ(r.status, ScanMatchStatus::kMatched);
    EXPECT_NEAR(r.pose.x, truth.x, 0.02f) << off.x;
    EXPECT_NEAR(r.pose.y, truth.y, 0.02f) << off.y;
    EXPECT_NEAR(r.pose.theta, truth.theta, 0.3f * kDeg) << off.theta;
    EXPECT_GE(r.score, r.prior_score);
    EXPECT_GT(r.score, 0.8f);
  }
}

// Two parallel walls 2 m apart along x: the offset across the corridor and the heading are
// corrected, the one along it is not (the scan does not constrain it): the prior is kept.
TEST(ScanMatch, KeepsThePriorAlongACorridor) {
  const std::vector<Eigen::Vector2f> walls = corridor_walls();
  const Map m = map_of(walls);
  const Pose2 truth{4.0f, 3.1f, 0.1f};
  const auto pts = scan_from(walls, truth, 3.0f, 0.005f, 3);
  const Pose2 prior{truth.x + 0.1f, truth.y - 0.1f, truth.theta + 1.5f * kDeg};
  ScanMatchSettings weak;  // a weak prior: enough to keep the unconstrained coordinate
  weak.prior_sigma_m = 1.0f;
  weak.prior_sigma_deg = 10.0f;
  weak.linear_window_m = 0.25f;
  weak.angular_window_deg = 3.0f;
  const ScanMatchResult r = scan_match(m.field.clearance(), pts, prior, weak);
  ASSERT_EQ(r.status, ScanMatchStatus::kMatched);
  EXPECT_NEAR(r.pose.y, truth.y, 0.02f);
  EXPECT_NEAR(r.pose.theta, truth.theta, 0.3f * kDeg);
  EXPECT_NEAR(r.pose.x, prior.x, 0.02f);  // along the corridor: the prior's x
}

// The field interpolation inside the search gives scan_match_score()'s value (the reference:
// bilinear over cell-centre likelihoods, one point at a time, in double).
TEST(ScanMatch, ScoreMatchesTheReferenceAndTheSearchIsExhaustive) {
  const auto walls = room_walls();
  const Map m = map_of(walls);
  const Pose2 truth{5.5f, 2.2f, -2.0f};
  const auto pts = scan_from(walls, truth, 4.0f, 0.02f, 11);
  ScanMatchSettings s;
  s.linear_window_m = 0.1f;
  s.angular_window_deg = 1.0f;
  const Pose2 prior{truth.x + 0.07f, truth.y + 0.03f, truth.theta - 0.7f * kDeg};
  const ScanMatchResult r = scan_match(m.field.clearance(), pts, prior, s);
  ASSERT_EQ(r.status, ScanMatchStatus::kMatched);
  EXPECT_NEAR(r.score, scan_match_score(m.field.clearance(), pts, r.pose, s), 1e-4f);
  EXPECT_NEAR(r.prior_score, scan_match_score(m.field.clearance(), pts, prior, s), 1e-4f);
  // Coarse lattice: 5 x 5 x 5 (+-2 steps of 0.05 m, 0.5 deg); refined: 7 x 7 x 7; plus the prior,
  // the 26 neighbours of the refined best (the quadratic fit) and the fitted peak.
  EXPECT_EQ(r.candidates, 1u + 125u + 343u + 26u + 1u);
  // No coarse candidate weighs more than the result (the refinement can only add).
  const float w_best = weight(r.pose, prior, r.score, s);
  for (int k = -2; k <= 2; ++k)
    for (int j = -2; j <= 2; ++j)
      for (int i = -2; i <= 2; ++i) {
        const Pose2 c{prior.x + i * s.linear_step_m, prior.y + j * s.linear_step_m, prior.theta + k * s.angular_step_deg * kDeg};
        EXPECT_LE(weight(c, prior, scan_match_score(m.field.clearance(), pts, c, s), s), w_best + 1e-4f) << i << " " << j << " " << k;
      }
}

TEST(ScanMatch, InterpolatesBelowTheLattice) {
  // The lattice is centred on the prior, so without interpolation the result moves with the
  // prior in quarter steps (0.125 deg, 0.0125 m). With a flat prior the peak is the scan's:
  // priors a fraction of a step apart give nearly the same pose, and not a lattice point.
  const auto walls = room_walls();
  const Map m = map_of(walls);
  ScanMatchSettings s;
  s.prior_sigma_m = 10.0f;
  s.prior_sigma_deg = 100.0f;
  for (int seed = 1; seed <= 4; ++seed) {
    const Pose2 truth{3.0f + 0.1f * seed, 2.5f, 0.3f * seed};
    const auto pts = scan_from(walls, truth, 5.0f, 0.0f, seed);
    float lo = 1e9f, hi = -1e9f, xlo = 1e9f, xhi = -1e9f;
    bool off_lattice = false;
    for (int k = 0; k < 4; ++k) {
      const Pose2 prior{truth.x + 0.003f * k, truth.y - 0.004f, truth.theta + (0.03f * k - 0.04f) * kDeg};
      const ScanMatchResult r = scan_match(m.field.clearance(), pts, prior, s);
      ASSERT_EQ(r.status, ScanMatchStatus::kMatched);
      const float dth = std::remainder(r.pose.theta - truth.theta, 2.0f * std::numbers::pi_v<float>) / kDeg;
      lo = std::min(lo, dth);
      hi = std::max(hi, dth);
      xlo = std::min(xlo, r.pose.x - truth.x);
      xhi = std::max(xhi, r.pose.x - truth.x);
      const float steps = std::remainder(r.pose.theta - prior.theta, 2.0f * std::numbers::pi_v<float>) / (0.125f * kDeg);
      off_lattice = off_lattice || std::abs(steps - std::round(steps)) > 0.05f;
      EXPECT_LT(std::abs(dth), 0.15f) << "seed " << seed << " prior " << k;
      EXPECT_LT(std::abs(r.pose.y - truth.y), 0.006f) << "seed " << seed << " prior " << k;
    }
    EXPECT_LT(hi - lo, 0.07f) << "seed " << seed;      // the lattice alone: 0.095 deg here
    EXPECT_LT(xhi - xlo, 0.004f) << "seed " << seed;   // ... and 0.0095 m
    EXPECT_TRUE(off_lattice) << "seed " << seed;
  }
}

TEST(ScanMatch, SameResultOnOneAndTwoThreads) {
  const auto walls = room_walls();
  const Map m = map_of(walls);
  const Pose2 truth{2.4f, 3.7f, 1.2f};
  const auto pts = scan_from(walls, truth, 5.0f, 0.02f, 5);
  const Pose2 prior{truth.x - 0.1f, truth.y + 0.1f, truth.theta + 1.0f * kDeg};
  const auto r1 = test::in_arena(1, [&] { return scan_match(m.field.clearance(), pts, prior); });
  const auto r2 = test::in_arena(2, [&] { return scan_match(m.field.clearance(), pts, prior); });
  EXPECT_EQ(r1.status, r2.status);
  EXPECT_EQ(r1.pose.x, r2.pose.x);
  EXPECT_EQ(r1.pose.y, r2.pose.y);
  EXPECT_EQ(r1.pose.theta, r2.pose.theta);
  EXPECT_EQ(r1.score, r2.score);
}

TEST(ScanMatch, EmptyTinyNanAndOffGridInputKeepThePrior) {
  const auto walls = room_walls();
  const Map m = map_of(walls);
  const Pose2 prior{3.0f, 2.0f, 0.3f};
  const ScanMatchResult none = scan_match(m.field.clearance(), {}, prior);
  EXPECT_EQ(none.status, ScanMatchStatus::kTooFewPoints);
  EXPECT_EQ(none.pose.x, prior.x);
  EXPECT_EQ(none.pose.theta, prior.theta);
  EXPECT_EQ(scan_match_score(m.field.clearance(), {}, prior, {}), 0.0f);
  // NaN points are skipped, and do not count towards min_points.
  std::vector<Eigen::Vector2f> nan_pts(100, Eigen::Vector2f(std::nanf(""), 1.0f));
  nan_pts.resize(120, Eigen::Vector2f(1.0f, 0.0f));
  EXPECT_EQ(scan_match(m.field.clearance(), nan_pts, prior).status, ScanMatchStatus::kTooFewPoints);
  // All points far off the grid: nothing to match, the prior stays.
  std::vector<Eigen::Vector2f> far(200, Eigen::Vector2f(500.0f, 500.0f));
  const ScanMatchResult off = scan_match(m.field.clearance(), far, prior);
  EXPECT_EQ(off.status, ScanMatchStatus::kNotConfident);
  EXPECT_EQ(off.score, 0.0f);
  EXPECT_EQ(off.pose.x, prior.x);
  // A map with no occupied cell (clearance +inf everywhere): nothing to match either.
  Map empty;
  empty.w = 40;
  empty.h = 40;
  empty.l.assign(1600, -2.0f);
  empty.build();
  const auto pts = scan_from(walls, Pose2{1.0f, 1.0f, 0.0f}, 5.0f, 0.0f, 1);
  const ScanMatchResult e = scan_match(empty.field.clearance(), pts, Pose2{1.0f, 1.0f, 0.0f});
  EXPECT_EQ(e.status, ScanMatchStatus::kNotConfident);
  EXPECT_EQ(e.pose.x, 1.0f);
  // A 0 x 0 view: every sample is off the grid.
  const ScanMatchResult z = scan_match(ClearanceView{}, pts, prior);
  EXPECT_EQ(z.status, ScanMatchStatus::kNotConfident);
}

// Huge finite points or a far prior (found by fuzz_capi: a point at 3e38 m made the field's
// window -inf cells wide, cast to int - undefined behaviour): such points are skipped, a prior
// beyond the map frame's limit is an error, a view far from the prior is just missed.
TEST(ScanMatch, HugePointsAndFarPriorsAreSafe) {
  const auto walls = room_walls();
  const Map m = map_of(walls);
  const Pose2 prior{3.0f, 2.0f, 0.3f};
  auto pts = scan_from(walls, prior, 5.0f, 0.0f, 1);
  const ScanMatchResult clean = scan_match(m.field.clearance(), pts, prior);
  for (const float big : {3e38f, -3e38f, 1e5f}) pts.emplace_back(big, 1.0f);
  const ScanMatchResult with_huge = scan_match(m.field.clearance(), pts, prior);
  EXPECT_EQ(with_huge.status, clean.status);
  EXPECT_EQ(with_huge.pose.x, clean.pose.x);
  EXPECT_EQ(with_huge.pose.theta, clean.pose.theta);
  std::vector<Eigen::Vector2f> only_huge(200, Eigen::Vector2f(3e38f, -3e38f));
  EXPECT_EQ(scan_match(m.field.clearance(), only_huge, prior).status, ScanMatchStatus::kTooFewPoints);
  try {
    (void)scan_match(m.field.clearance(), pts, Pose2{2e4f, 0.0f, 0.0f});
    ADD_FAILURE() << "a prior 20 km away was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kOutOfRange);
  }
  // A prior near the limit with the grid far away: nothing to match, no overflow.
  const ScanMatchResult far = scan_match(m.field.clearance(), scan_from(walls, prior, 5.0f, 0.0f, 1), Pose2{9999.0f, -9999.0f, 0.0f});
  EXPECT_EQ(far.status, ScanMatchStatus::kNotConfident);
  EXPECT_EQ(far.pose.x, 9999.0f);
}

// The runner-up (ScanMatchSettings::runner_up_distance_m): in a room the scan fits one place, so
// the best other fit scores far below the match; along a corridor it fits everywhere, so the
// runner-up scores as the match does. Against a reference: every coarse candidate scored by
// scan_match_score(), the coarse best by the weight, the best score farther than the distance.
// Asking for it does not change the match.
TEST(ScanMatch, RunnerUpIsTheBestFitElsewhere) {
  ScanMatchSettings wide;
  wide.linear_window_m = 1.0f;
  wide.linear_step_m = 0.1f;
  wide.angular_window_deg = 3.0f;
  wide.angular_step_deg = 1.0f;
  wide.prior_sigma_m = 100.0f;
  wide.prior_sigma_deg = 100.0f;
  ScanMatchSettings with = wide;
  with.runner_up_distance_m = 0.3f;
  auto reference = [&](const Map& m, const std::vector<Eigen::Vector2f>& pts, const Pose2& prior) {
    const int nl = 10, na = 3;
    Pose2 best;
    float best_w = -1.0f;
    std::vector<std::pair<Pose2, float>> all;
    for (int k = -na; k <= na; ++k)
      for (int j = -nl; j <= nl; ++j)
        for (int i = -nl; i <= nl; ++i) {
          const Pose2 c{prior.x + static_cast<float>(i) * 0.1f, prior.y + static_cast<float>(j) * 0.1f,
                        prior.theta + static_cast<float>(k) * kDeg};
          const float sc = scan_match_score(m.field.clearance(), pts, c, wide);
          all.emplace_back(c, sc);
          const float w = weight(c, prior, sc, wide);
          if (w > best_w + 1e-6f) {
            best_w = w;
            best = c;
          }
        }
    float runner_up = 0.0f;
    for (const auto& [c, sc] : all)
      if (std::hypot(c.x - best.x, c.y - best.y) > 0.3f) runner_up = std::max(runner_up, sc);
    return runner_up;
  };
  {  // the room: one fit
    const auto walls = room_walls();
    const Map m = map_of(walls);
    const Pose2 truth{3.0f, 2.6f, 0.4f};
    const auto pts = scan_from(walls, truth, 5.0f, 0.01f, 7);
    const Pose2 prior{truth.x + 0.42f, truth.y - 0.31f, truth.theta + 1.0f * kDeg};
    const ScanMatchResult plain = scan_match(m.field.clearance(), pts, prior, wide);
    const ScanMatchResult r = scan_match(m.field.clearance(), pts, prior, with);
    ASSERT_EQ(r.status, ScanMatchStatus::kMatched);
    EXPECT_EQ(plain.runner_up_score, 0.0f);  // not asked for
    EXPECT_EQ(r.pose.x, plain.pose.x);
    EXPECT_EQ(r.pose.y, plain.pose.y);
    EXPECT_EQ(r.pose.theta, plain.pose.theta);
    EXPECT_EQ(r.score, plain.score);
    EXPECT_NEAR(r.pose.x, truth.x, 0.02f);
    EXPECT_NEAR(r.pose.y, truth.y, 0.02f);
    EXPECT_NEAR(r.runner_up_score, reference(m, pts, prior), 1e-4f);
    EXPECT_GT(r.runner_up_score, 0.0f);
    EXPECT_LT(r.runner_up_score, r.score - 0.3f) << r.runner_up_score << " vs " << r.score;
  }
  {  // a corridor along x: the scan fits anywhere along it
    const std::vector<Eigen::Vector2f> walls = corridor_walls();
    const Map m = map_of(walls);
    const Pose2 truth{4.0f, 3.1f, 0.1f};
    const auto pts = scan_from(walls, truth, 2.5f, 0.005f, 3);
    const Pose2 prior{truth.x + 0.3f, truth.y - 0.3f, truth.theta};
    const ScanMatchResult r = scan_match(m.field.clearance(), pts, prior, with);
    ASSERT_EQ(r.status, ScanMatchStatus::kMatched);
    EXPECT_NEAR(r.pose.y, truth.y, 0.02f);
    EXPECT_NEAR(r.runner_up_score, reference(m, pts, prior), 1e-4f);
    EXPECT_GT(r.runner_up_score, r.score - 0.05f) << r.runner_up_score << " vs " << r.score;
  }
  {  // too few points: nothing scored, no runner-up
    const Map m = map_of(room_walls());
    const std::vector<Eigen::Vector2f> few(3, Eigen::Vector2f(1.0f, 0.0f));
    const ScanMatchResult r = scan_match(m.field.clearance(), few, Pose2{3.0f, 3.0f, 0.0f}, with);
    EXPECT_EQ(r.status, ScanMatchStatus::kTooFewPoints);
    EXPECT_EQ(r.runner_up_score, 0.0f);
  }
}

TEST(ScanMatch, InvalidInputThrows) {
  const auto walls = room_walls();
  const Map m = map_of(walls);
  const auto pts = scan_from(walls, Pose2{3.0f, 3.0f, 0.0f}, 5.0f, 0.0f, 1);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW((void)scan_match(m.field.clearance(), pts, Pose2{nan, 0.0f, 0.0f}), Error);
  EXPECT_THROW((void)scan_match(m.field.clearance(), pts, Pose2{0.0f, 0.0f, std::numeric_limits<float>::infinity()}), Error);
  ClearanceView bad = m.field.clearance();
  bad.width += 1;  // span no longer matches
  EXPECT_THROW((void)scan_match(bad, pts, Pose2{3.0f, 3.0f, 0.0f}), Error);
  ClearanceView bad_res = m.field.clearance();
  bad_res.resolution_m = 0.0f;
  EXPECT_THROW((void)scan_match(bad_res, pts, Pose2{3.0f, 3.0f, 0.0f}), Error);
  {  // within the per-axis limits (200 steps each way) but 401^3 = 6.4e7 lattice poses: refused
    ScanMatchSettings s;
    s.linear_window_m = 2.0f;
    s.linear_step_m = 0.01f;
    s.angular_window_deg = 20.0f;
    s.angular_step_deg = 0.1f;
    try {
      (void)scan_match(m.field.clearance(), pts, Pose2{3.0f, 3.0f, 0.0f}, s);
      ADD_FAILURE() << "6.4e7 lattice poses accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("lattice poses, more than the budget"), std::string::npos) << e.what();
    }
  }
  auto expect_bad = [&](auto mutate, const char* field) {
    ScanMatchSettings s;
    mutate(s);
    try {
      (void)scan_match(m.field.clearance(), pts, Pose2{3.0f, 3.0f, 0.0f}, s);
      ADD_FAILURE() << field << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  expect_bad([](ScanMatchSettings& s) { s.linear_window_m = -0.1f; }, "linear_window_m");
  expect_bad([](ScanMatchSettings& s) { s.angular_window_deg = 90.0f; }, "angular_window_deg");
  expect_bad([](ScanMatchSettings& s) { s.linear_step_m = 0.0f; }, "linear_step_m");
  expect_bad([](ScanMatchSettings& s) { s.angular_step_deg = std::nanf(""); }, "angular_step_deg");
  expect_bad([](ScanMatchSettings& s) { s.sigma_m = 0.0f; }, "sigma_m");
  expect_bad([](ScanMatchSettings& s) { s.max_distance_m = -1.0f; }, "max_distance_m");
  expect_bad([](ScanMatchSettings& s) { s.prior_sigma_m = 0.0f; }, "prior_sigma_m");
  expect_bad([](ScanMatchSettings& s) { s.prior_sigma_deg = std::numeric_limits<float>::infinity(); }, "prior_sigma_deg");
  expect_bad([](ScanMatchSettings& s) { s.min_points = 0; }, "min_points");
  expect_bad([](ScanMatchSettings& s) { s.min_score = 1.5f; }, "min_score");
  expect_bad([](ScanMatchSettings& s) { s.runner_up_distance_m = -0.1f; }, "runner_up_distance_m");
  expect_bad([](ScanMatchSettings& s) { s.runner_up_distance_m = std::nanf(""); }, "runner_up_distance_m");
  expect_bad([](ScanMatchSettings& s) { s.linear_window_m = 5.0f; s.linear_step_m = 0.001f; }, "linear_window_m / linear_step_m");
}

}  // namespace test_scan_match
}  // namespace duet
