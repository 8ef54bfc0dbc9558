// 2D scan-to-map matching (see scan_match.hpp for the semantics).
//
// The likelihood field exp(-d^2 / (2 sigma^2)) is evaluated once per call at the cell centres
// of the window the candidates can reach (with a ring of zeros around it and outside the grid)
// and interpolated bilinearly, so a candidate costs one rotation per angle (shared by all
// translations) and four lookups per point.
#include <duet/kernels/error.hpp>
#include <duet/kernels/grid.hpp>
#include <duet/kernels/scan_match.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace duet {
namespace {

constexpr float kDegToRad = std::numbers::pi_v<float> / 180.0f;

/// The likelihood field on a window of cells [x0, x0 + w) x [y0, y0 + h) of the grid (cells off
/// the grid are 0), sampled bilinearly between cell centres.
struct Field {
  std::vector<float> s;
  int x0 = 0, y0 = 0, w = 0, h = 0;
  float inv_res = 20.0f;
  Eigen::Vector2f origin{0.0f, 0.0f};

  /// Bilinear sample at a map point; 0 off the window.
  [[nodiscard]] float at(float x, float y) const noexcept {
    const float fx = (x - origin.x()) * inv_res - 0.5f - static_cast<float>(x0);
    const float fy = (y - origin.y()) * inv_res - 0.5f - static_cast<float>(y0);
    if (!(fx >= 0.0f) || !(fy >= 0.0f) || !(fx < static_cast<float>(w - 1)) || !(fy < static_cast<float>(h - 1))) return 0.0f;
    const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
    const float ax = fx - static_cast<float>(ix), ay = fy - static_cast<float>(iy);
    const float* r0 = s.data() + static_cast<std::size_t>(iy) * static_cast<std::size_t>(w) + static_cast<std::size_t>(ix);
    const float* r1 = r0 + w;
    const float top = r0[0] + ax * (r0[1] - r0[0]);
    const float bottom = r1[0] + ax * (r1[1] - r1[0]);
    return top + ay * (bottom - top);
  }
};

Field make_field(const ClearanceView& d, const Eigen::Vector2f& centre, float radius, const ScanMatchSettings& s) {
  Field f;
  const float res = d.resolution_m;
  f.inv_res = 1.0f / res;
  f.origin = d.origin;
  // Cells whose centres may be needed (+1 each side for the bilinear stencil), clipped to the
  // grid with one ring of zero cells outside it.
  // In double and clamped to the grid before the cast: a window far off the grid (or wider than
  // an int counts cells) must not overflow the cast (found by fuzz_capi with huge points).
  const auto cell = [&](double v, int min, int max) {
    return static_cast<int>(std::clamp(std::floor(v), static_cast<double>(min), static_cast<double>(max)));
  };
  const double rad = radius;
  const int x0 = cell((centre.x() - rad - d.origin.x()) / res - 1.0, -1, d.width + 1);
  const int x1 = cell((centre.x() + rad - d.origin.x()) / res + 2.0, -1, d.width + 1);
  const int y0 = cell((centre.y() - rad - d.origin.y()) / res - 1.0, -1, d.height + 1);
  const int y1 = cell((centre.y() + rad - d.origin.y()) / res + 2.0, -1, d.height + 1);
  if (x1 <= x0 + 1 || y1 <= y0 + 1) return f;  // the window misses the grid: w, h stay 0 (every sample 0)
  f.x0 = x0;
  f.y0 = y0;
  f.w = x1 - x0;
  f.h = y1 - y0;
  f.s.assign(static_cast<std::size_t>(f.w) * static_cast<std::size_t>(f.h), 0.0f);
  const float k = -0.5f / (s.sigma_m * s.sigma_m);
  tbb::parallel_for(tbb::blocked_range<int>(0, f.h, 16), [&](const tbb::blocked_range<int>& r) {
    for (int j = r.begin(); j != r.end(); ++j) {
      const int gy = y0 + j;
      if (gy < 0 || gy >= d.height) continue;
      for (int i = 0; i < f.w; ++i) {
        const int gx = x0 + i;
        if (gx < 0 || gx >= d.width) continue;
        const float c = d.clearance_m[static_cast<std::size_t>(gy) * static_cast<std::size_t>(d.width) + static_cast<std::size_t>(gx)];
        const float dist = std::isnan(c) ? s.max_distance_m : std::min(c, s.max_distance_m);
        f.s[static_cast<std::size_t>(j) * static_cast<std::size_t>(f.w) + static_cast<std::size_t>(i)] = std::exp(k * dist * dist);
      }
    }
  });
  return f;
}

struct Candidate {
  float weighted = -1.0f;  ///< W (score x prior)
  float score = 0.0f;      ///< S
  Pose2 pose;
};

/// Scores the lattice centre + (i dl, j dl, k da) for |i|, |j| <= nl, |k| <= na; the best by W
/// (ties: lowest (k, j, i) in that order of loops).
/// With `all`, every candidate's S is stored there at index (k + na) (2 nl + 1)^2 + (j + nl) (2 nl + 1) + (i + nl).
Candidate search(const Field& f, std::span<const Eigen::Vector2f> pts, std::size_t n_total, const Pose2& prior, const Pose2& centre,
                 int nl, float dl, int na, float da, const ScanMatchSettings& s, std::size_t& scored,
                 std::vector<float>* all = nullptr) {
  const int n_angles = 2 * na + 1;
  const std::size_t side = static_cast<std::size_t>(2 * nl + 1);
  if (all != nullptr) all->assign(static_cast<std::size_t>(n_angles) * side * side, 0.0f);
  std::vector<Candidate> per_angle(static_cast<std::size_t>(n_angles));
  const float inv_n = 1.0f / static_cast<float>(n_total);
  const float kt = -0.5f / (s.prior_sigma_m * s.prior_sigma_m);
  const float sa = s.prior_sigma_deg * kDegToRad;
  const float ka = -0.5f / (sa * sa);
  tbb::parallel_for(tbb::blocked_range<int>(0, n_angles, 1), [&](const tbb::blocked_range<int>& r) {
    std::vector<Eigen::Vector2f> rotated(pts.size());
    for (int ai = r.begin(); ai != r.end(); ++ai) {
      const float theta = centre.theta + static_cast<float>(ai - na) * da;
      const float c = std::cos(theta), sn = std::sin(theta);
      for (std::size_t p = 0; p < pts.size(); ++p)
        rotated[p] = Eigen::Vector2f(c * pts[p].x() - sn * pts[p].y(), sn * pts[p].x() + c * pts[p].y());
      const float dtheta = std::remainder(theta - prior.theta, 2.0f * std::numbers::pi_v<float>);
      const float angle_weight = std::exp(ka * dtheta * dtheta);
      Candidate best;
      for (int j = -nl; j <= nl; ++j)
        for (int i = -nl; i <= nl; ++i) {
          const float x = centre.x + static_cast<float>(i) * dl, y = centre.y + static_cast<float>(j) * dl;
          float sum = 0.0f;
          for (const Eigen::Vector2f& q : rotated) sum += f.at(q.x() + x, q.y() + y);
          const float score = sum * inv_n;
          if (all != nullptr)
            (*all)[static_cast<std::size_t>(ai) * side * side + static_cast<std::size_t>(j + nl) * side + static_cast<std::size_t>(i + nl)] = score;
          const float dx = x - prior.x, dy = y - prior.y;
          const float w = score * angle_weight * std::exp(kt * (dx * dx + dy * dy));
          if (w > best.weighted) best = Candidate{w, score, Pose2{x, y, theta}};
        }
      per_angle[static_cast<std::size_t>(ai)] = best;
    }
  });
  scored += static_cast<std::size_t>(n_angles) * static_cast<std::size_t>(2 * nl + 1) * static_cast<std::size_t>(2 * nl + 1);
  Candidate best;
  for (const Candidate& c : per_angle)
    if (c.weighted > best.weighted) best = c;
  return best;
}

void check_view(const ClearanceView& d, const char* who) {
  if (d.width < 0 || d.height < 0 || d.clearance_m.size() != static_cast<std::size_t>(d.width) * static_cast<std::size_t>(d.height))
    fail(ErrorCode::kInvalidArgument, std::string(who) + ": the distance view's span (" + std::to_string(d.clearance_m.size()) +
                                          ") does not match its size " + std::to_string(d.width) + " x " + std::to_string(d.height));
  if (!(std::isfinite(d.resolution_m) && d.resolution_m > 0.0f) || !d.origin.allFinite())
    fail(ErrorCode::kInvalidArgument, std::string(who) + ": the distance view needs a positive resolution and a finite origin");
}

}  // namespace

void validate(const ScanMatchSettings& s) {
  auto bad = [](const char* field, double v, const char* range) {
    fail(ErrorCode::kInvalidArgument, std::string("ScanMatchSettings::") + field + " must be in " + range + ", got " + std::to_string(v));
  };
  auto in = [](float v, float lo, float hi) { return std::isfinite(v) && v >= lo && v <= hi; };
  if (!in(s.linear_window_m, 0.0f, 5.0f)) bad("linear_window_m", s.linear_window_m, "[0, 5] m");
  if (!in(s.angular_window_deg, 0.0f, 45.0f)) bad("angular_window_deg", s.angular_window_deg, "[0, 45] deg");
  if (!(in(s.linear_step_m, 0.0f, 1.0f) && s.linear_step_m > 0.0f)) bad("linear_step_m", s.linear_step_m, "(0, 1] m");
  if (!(in(s.angular_step_deg, 0.0f, 10.0f) && s.angular_step_deg > 0.0f)) bad("angular_step_deg", s.angular_step_deg, "(0, 10] deg");
  if (!(in(s.sigma_m, 0.0f, 1.0f) && s.sigma_m > 0.0f)) bad("sigma_m", s.sigma_m, "(0, 1] m");
  if (!(in(s.max_distance_m, 0.0f, 10.0f) && s.max_distance_m > 0.0f)) bad("max_distance_m", s.max_distance_m, "(0, 10] m");
  if (!(std::isfinite(s.prior_sigma_m) && s.prior_sigma_m > 0.0f)) bad("prior_sigma_m", s.prior_sigma_m, "(0, inf) m");
  if (!(std::isfinite(s.prior_sigma_deg) && s.prior_sigma_deg > 0.0f)) bad("prior_sigma_deg", s.prior_sigma_deg, "(0, inf) deg");
  if (s.min_points < 1) bad("min_points", static_cast<double>(s.min_points), "[1, inf)");
  if (!in(s.min_score, 0.0f, 1.0f)) bad("min_score", s.min_score, "[0, 1]");
  if (!in(s.runner_up_distance_m, 0.0f, 5.0f)) bad("runner_up_distance_m", s.runner_up_distance_m, "[0, 5] m");
  // The lattice must stay a sane size: at most 401 steps per axis.
  if (s.linear_window_m / s.linear_step_m > 200.0f) bad("linear_window_m / linear_step_m", s.linear_window_m / s.linear_step_m, "[0, 200]");
  if (s.angular_window_deg / s.angular_step_deg > 200.0f)
    bad("angular_window_deg / angular_step_deg", s.angular_window_deg / s.angular_step_deg, "[0, 200]");
  // Work budget: the lattice's poses (each scores every point).
  const double nl = std::floor(s.linear_window_m / s.linear_step_m + 1e-4), na = std::floor(s.angular_window_deg / s.angular_step_deg + 1e-4);
  const double poses = (2.0 * nl + 1.0) * (2.0 * nl + 1.0) * (2.0 * na + 1.0);
  if (!(poses <= kMaxScanMatchPoses))
    fail(ErrorCode::kInvalidArgument, "ScanMatchSettings: the windows and steps make " + std::to_string(static_cast<long long>(poses)) +
                                          " lattice poses, more than the budget of " + std::to_string(static_cast<long long>(kMaxScanMatchPoses)) +
                                          " (narrow linear_window_m / angular_window_deg or raise linear_step_m / angular_step_deg)");
}

void occupied_distance(const GridView& grid, const CellThresholds& thresholds, InflatedGrid& out) {
  InflationSettings s;
  s.thresholds = thresholds;
  s.robot_radius_m = 0.0f;
  s.unknown_is_obstacle = false;
  s.uncertain_is_obstacle = false;
  inflate(grid, s, out);
}

float scan_match_score(ClearanceView distance, std::span<const Eigen::Vector2f> points_robot, const Pose2& pose,
                       const ScanMatchSettings& settings) {
  validate(settings);
  check_view(distance, "scan_match_score");
  if (points_robot.empty()) return 0.0f;
  const float c = std::cos(pose.theta), sn = std::sin(pose.theta);
  const float k = -0.5f / (settings.sigma_m * settings.sigma_m);
  const float res = distance.resolution_m;
  auto dist_at = [&](int gx, int gy) {
    if (gx < 0 || gy < 0 || gx >= distance.width || gy >= distance.height) return -1.0f;  // off the grid
    const float v = distance.clearance_m[static_cast<std::size_t>(gy) * static_cast<std::size_t>(distance.width) + static_cast<std::size_t>(gx)];
    return std::isnan(v) ? settings.max_distance_m : std::min(v, settings.max_distance_m);
  };
  auto lik = [&](int gx, int gy) {
    const float d = dist_at(gx, gy);
    return d < 0.0f ? 0.0f : std::exp(k * d * d);
  };
  double sum = 0.0;
  for (const Eigen::Vector2f& p : points_robot) {
    if (!p.allFinite()) continue;
    const float x = c * p.x() - sn * p.y() + pose.x, y = sn * p.x() + c * p.y() + pose.y;
    const float fx = (x - distance.origin.x()) / res - 0.5f, fy = (y - distance.origin.y()) / res - 0.5f;
    // One ring of zero cells around the grid; farther out the sample is 0.
    if (!(fx >= -1.0f) || !(fy >= -1.0f) || !(fx < static_cast<float>(distance.width)) || !(fy < static_cast<float>(distance.height)))
      continue;
    const int ix = static_cast<int>(std::floor(fx)), iy = static_cast<int>(std::floor(fy));
    const float ax = fx - static_cast<float>(ix), ay = fy - static_cast<float>(iy);
    const float top = lik(ix, iy) + ax * (lik(ix + 1, iy) - lik(ix, iy));
    const float bottom = lik(ix, iy + 1) + ax * (lik(ix + 1, iy + 1) - lik(ix, iy + 1));
    sum += top + ay * (bottom - top);
  }
  return static_cast<float>(sum / static_cast<double>(points_robot.size()));
}

ScanMatchResult scan_match(ClearanceView distance, std::span<const Eigen::Vector2f> points_robot, const Pose2& prior,
                           const ScanMatchSettings& settings) {
  validate(settings);
  check_view(distance, "scan_match");
  if (!(std::isfinite(prior.x) && std::isfinite(prior.y) && std::isfinite(prior.theta)))
    fail(ErrorCode::kInvalidArgument, "scan_match: the prior pose is not finite");
  if (!within_map_limits({prior.x, prior.y}))
    fail(ErrorCode::kOutOfRange, "scan_match: the prior pose is beyond the map frame's +-" + std::to_string(kMaxCoordinateM) + " m");
  ScanMatchResult out;
  out.pose = prior;
  std::vector<Eigen::Vector2f> pts;
  pts.reserve(points_robot.size());
  float radius = 0.0f;
  for (const Eigen::Vector2f& p : points_robot)
    if (within_map_limits(p)) {  // finite and within the map frame's reach: a farther point is no scan
      pts.push_back(p);
      radius = std::max(radius, p.norm());
    }
  if (pts.size() < settings.min_points || points_robot.empty()) {
    out.status = ScanMatchStatus::kTooFewPoints;
    return out;
  }
  const float dl = settings.linear_step_m, da = settings.angular_step_deg * kDegToRad;
  const int nl = static_cast<int>(std::floor(settings.linear_window_m / dl + 1e-4f));
  const int na = static_cast<int>(std::floor(settings.angular_window_deg / settings.angular_step_deg + 1e-4f));
  // Every candidate (coarse and refined) keeps its points within this radius of the prior.
  const float reach = radius + 1.5f * std::sqrt(2.0f) * (static_cast<float>(nl) + 1.0f) * dl;
  const Field f = make_field(distance, Eigen::Vector2f(prior.x, prior.y), reach, settings);
  const std::size_t n = points_robot.size();
  std::size_t scored = 0;
  Candidate prior_c = search(f, pts, n, prior, prior, 0, dl, 0, da, settings, scored);
  std::vector<float> coarse;
  const bool runner_up = settings.runner_up_distance_m > 0.0f;
  Candidate best = search(f, pts, n, prior, prior, nl, dl, na, da, settings, scored, runner_up ? &coarse : nullptr);
  if (runner_up) {
    // The best S of a coarse candidate farther than runner_up_distance_m from the coarse best.
    const float r2 = settings.runner_up_distance_m * settings.runner_up_distance_m;
    const std::size_t side = static_cast<std::size_t>(2 * nl + 1);
    for (std::size_t k = 0; k < coarse.size(); ++k) {
      const int i = static_cast<int>(k % side) - nl, j = static_cast<int>((k / side) % side) - nl;
      const float dx = prior.x + static_cast<float>(i) * dl - best.pose.x, dy = prior.y + static_cast<float>(j) * dl - best.pose.y;
      if (dx * dx + dy * dy > r2) out.runner_up_score = std::max(out.runner_up_score, coarse[k]);
    }
  }
  // Refine: a quarter of the steps, +-3/4 of a coarse step around the best.
  best = search(f, pts, n, prior, best.pose, 3, dl / 4.0f, 3, da / 4.0f, settings, scored);
  // Below the lattice: a quadratic in (x, y, theta) fitted by least squares to W on the 3 x 3 x 3
  // quarter-step neighbourhood of the best; its peak (if the fit is concave, at most one quarter
  // step from the best per axis) replaces the best only if its W is at least as high. Without it
  // every match is a multiple of the quarter step (0.125 deg, 0.0125 m) from the prior, and those
  // quantised offsets, fed to the runtime's heading-rate estimate, make it wander.
  {
    const float steps[3] = {dl / 4.0f, dl / 4.0f, da / 4.0f};
    Eigen::Matrix<double, 27, 10> A;
    Eigen::Matrix<double, 27, 1> b;
    int row = 0;
    for (int k = -1; k <= 1; ++k)
      for (int j = -1; j <= 1; ++j)
        for (int i = -1; i <= 1; ++i, ++row) {
          const double u[3] = {static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)};
          if (i == 0 && j == 0 && k == 0) {
            b(row) = best.weighted;
          } else {
            const Pose2 q{best.pose.x + i * steps[0], best.pose.y + j * steps[1], best.pose.theta + k * steps[2]};
            b(row) = search(f, pts, n, prior, q, 0, dl, 0, da, settings, scored).weighted;
          }
          // W ~ c + g.u + 1/2 u' H u, H symmetric: 1 + 3 + 6 coefficients.
          A.row(row) << 1.0, u[0], u[1], u[2], 0.5 * u[0] * u[0], 0.5 * u[1] * u[1], 0.5 * u[2] * u[2], u[0] * u[1], u[0] * u[2], u[1] * u[2];
        }
    const Eigen::Matrix<double, 10, 1> c = (A.transpose() * A).ldlt().solve(A.transpose() * b);
    Eigen::Matrix3d H;
    H << c(4), c(7), c(8), c(7), c(5), c(9), c(8), c(9), c(6);
    const Eigen::Vector3d g(c(1), c(2), c(3));
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(H);
    if (es.info() == Eigen::Success && es.eigenvalues().maxCoeff() < 0.0) {
      const Eigen::Vector3d u = (-H.inverse() * g).cwiseMax(-1.0).cwiseMin(1.0);
      const Pose2 q{best.pose.x + static_cast<float>(u(0)) * steps[0], best.pose.y + static_cast<float>(u(1)) * steps[1],
                    best.pose.theta + static_cast<float>(u(2)) * steps[2]};
      const Candidate cq = search(f, pts, n, prior, q, 0, dl, 0, da, settings, scored);
      if (cq.weighted >= best.weighted) best = cq;
    }
  }
  out.candidates = scored;
  out.prior_score = prior_c.score;
  out.score = best.score;
  if (!(best.score >= settings.min_score)) {
    out.status = ScanMatchStatus::kNotConfident;
    return out;
  }
  out.status = ScanMatchStatus::kMatched;
  out.pose = best.pose;
  out.pose.theta = std::remainder(out.pose.theta, 2.0f * std::numbers::pi_v<float>);
  return out;
}

}  // namespace duet
