/// @file pose_graph.cpp
/// Levenberg-Marquardt on the 2D pose graph (see pose_graph.hpp).
#include <duet/kernels/error.hpp>
#include <duet/kernels/pose_graph.hpp>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

namespace duet {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

struct P {
  double x, y, t;
};

double wrap(double a) { return std::remainder(a, kTwoPi); }

/// Error of edge (i, j) with measurement z, and optionally its Jacobians A = de/dx_i, B = de/dx_j.
Eigen::Vector3d edge_error(const P& xi, const P& xj, const P& z, Eigen::Matrix3d* A, Eigen::Matrix3d* B) {
  const double ci = std::cos(xi.t), si = std::sin(xi.t), cz = std::cos(z.t), sz = std::sin(z.t);
  const double dx = xj.x - xi.x, dy = xj.y - xi.y;
  // R_i^T d
  const double lx = ci * dx + si * dy, ly = -si * dx + ci * dy;
  // R_z^T (R_i^T d - t_z)
  const double ux = lx - z.x, uy = ly - z.y;
  Eigen::Vector3d e(cz * ux + sz * uy, -sz * ux + cz * uy, wrap(xj.t - xi.t - z.t));
  if (A != nullptr && B != nullptr) {
    Eigen::Matrix2d RzT;
    RzT << cz, sz, -sz, cz;
    Eigen::Matrix2d RiT;
    RiT << ci, si, -si, ci;
    Eigen::Matrix2d dRiT;  // d(R_i^T)/d theta_i
    dRiT << -si, ci, -ci, -si;
    const Eigen::Matrix2d M = RzT * RiT;
    A->setZero();
    B->setZero();
    A->topLeftCorner<2, 2>() = -M;
    A->block<2, 1>(0, 2) = RzT * (dRiT * Eigen::Vector2d(dx, dy));
    (*A)(2, 2) = -1.0;
    B->topLeftCorner<2, 2>() = M;
    (*B)(2, 2) = 1.0;
  }
  return e;
}

Eigen::Matrix3d information(const PoseGraphEdge& e) {
  const double ixy = 1.0 / (static_cast<double>(e.sigma_xy_m) * e.sigma_xy_m);
  const double it = 1.0 / (static_cast<double>(e.sigma_theta_rad) * e.sigma_theta_rad);
  return Eigen::Vector3d(ixy, ixy, it).asDiagonal();
}

P to_p(const Pose2& p) { return {p.x, p.y, p.theta}; }

/// rho(chi2) and the IRLS weight rho'(chi2).
std::pair<double, double> robust_loss(double chi2, bool robust, double delta) {
  if (!robust) return {chi2, 1.0};
  const double m = std::sqrt(chi2);
  if (m <= delta) return {chi2, 1.0};
  return {2.0 * delta * m - delta * delta, delta / m};
}

double total_cost(const std::vector<P>& x, std::span<const PoseGraphEdge> edges, double delta) {
  double c = 0.0;
  for (const auto& ed : edges) {
    const Eigen::Vector3d e = edge_error(x[ed.from], x[ed.to], to_p(ed.measurement), nullptr, nullptr);
    c += robust_loss(e.dot(information(ed) * e), ed.robust, delta).first;
  }
  return c;
}

}  // namespace

void validate(const PoseGraphSettings& s) {
  auto bad = [](const std::string& what) { fail(ErrorCode::kInvalidArgument, "PoseGraphSettings::" + what); };
  if (s.max_iterations < 1 || s.max_iterations > 1000) bad("max_iterations must be in [1, 1000], got " + std::to_string(s.max_iterations));
  if (!(std::isfinite(s.min_relative_decrease) && s.min_relative_decrease >= 0.0 && s.min_relative_decrease < 1.0))
    bad("min_relative_decrease must be in [0, 1), got " + std::to_string(s.min_relative_decrease));
  if (!(std::isfinite(s.huber_delta) && s.huber_delta > 0.0)) bad("huber_delta must be > 0, got " + std::to_string(s.huber_delta));
}

double pose_graph_edge_chi2(std::span<const Pose2> poses, const PoseGraphEdge& edge) {
  if (edge.from >= poses.size() || edge.to >= poses.size())
    fail(ErrorCode::kInvalidArgument, "pose_graph_edge_chi2: the edge names a node beyond the " + std::to_string(poses.size()) + " poses");
  const Eigen::Vector3d e = edge_error(to_p(poses[edge.from]), to_p(poses[edge.to]), to_p(edge.measurement), nullptr, nullptr);
  return e.dot(information(edge) * e);
}

PoseGraphResult optimize_pose_graph(std::span<Pose2> poses, std::span<const PoseGraphEdge> edges, const PoseGraphSettings& settings) {
  validate(settings);
  const std::size_t n = poses.size();
  for (std::size_t k = 0; k < n; ++k)
    if (!(std::isfinite(poses[k].x) && std::isfinite(poses[k].y) && std::isfinite(poses[k].theta)))
      fail(ErrorCode::kInvalidArgument, "optimize_pose_graph: pose " + std::to_string(k) + " is not finite");
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const PoseGraphEdge& e = edges[k];
    const std::string where = "optimize_pose_graph: edge " + std::to_string(k) + " ";
    if (e.from >= n || e.to >= n)
      fail(ErrorCode::kInvalidArgument, where + "names node " + std::to_string(std::max(e.from, e.to)) + " of " + std::to_string(n));
    if (e.from == e.to) fail(ErrorCode::kInvalidArgument, where + "joins node " + std::to_string(e.from) + " to itself");
    if (!(std::isfinite(e.measurement.x) && std::isfinite(e.measurement.y) && std::isfinite(e.measurement.theta)))
      fail(ErrorCode::kInvalidArgument, where + "has a non-finite measurement");
    if (!(std::isfinite(e.sigma_xy_m) && e.sigma_xy_m > 0.0f && std::isfinite(e.sigma_theta_rad) && e.sigma_theta_rad > 0.0f))
      fail(ErrorCode::kInvalidArgument, where + "needs finite sigmas > 0");
  }
  PoseGraphResult result;
  if (n > 0 && settings.fixed_node >= n)
    fail(ErrorCode::kInvalidArgument, "PoseGraphSettings::fixed_node " + std::to_string(settings.fixed_node) + " is not one of the " +
                                          std::to_string(n) + " nodes");
  std::vector<P> x(n);
  for (std::size_t k = 0; k < n; ++k) x[k] = to_p(poses[k]);
  const double delta = settings.huber_delta;
  result.initial_cost = result.final_cost = total_cost(x, edges, delta);
  if (n < 2 || edges.empty()) return result;

  // Variable blocks: every node but the fixed one.
  std::vector<int> var(n, -1);
  int nv = 0;
  for (std::size_t k = 0; k < n; ++k)
    if (k != settings.fixed_node) var[k] = nv++;
  const int dim = 3 * nv;
  double cost = result.initial_cost;
  double lambda = 1e-4;
  std::vector<Eigen::Triplet<double>> trip;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
  bool pattern_ready = false;
  for (int it = 0; it < settings.max_iterations; ++it) {
    ++result.iterations;
    trip.clear();
    Eigen::VectorXd b = Eigen::VectorXd::Zero(dim);
    Eigen::VectorXd diag = Eigen::VectorXd::Zero(dim);
    for (const auto& ed : edges) {
      Eigen::Matrix3d A, B;
      const Eigen::Vector3d e = edge_error(x[ed.from], x[ed.to], to_p(ed.measurement), &A, &B);
      const Eigen::Matrix3d Om = information(ed);
      const double w = robust_loss(e.dot(Om * e), ed.robust, delta).second;
      const Eigen::Matrix3d W = w * Om;
      const int vi = var[ed.from], vj = var[ed.to];
      const Eigen::Matrix3d* J[2] = {&A, &B};
      const int v[2] = {vi, vj};
      for (int a = 0; a < 2; ++a) {
        if (v[a] < 0) continue;
        b.segment<3>(3 * v[a]) += J[a]->transpose() * W * e;
        for (int c = 0; c < 2; ++c) {
          if (v[c] < 0) continue;
          const Eigen::Matrix3d H = J[a]->transpose() * W * (*J[c]);
          for (int r = 0; r < 3; ++r)
            for (int q = 0; q < 3; ++q) trip.emplace_back(3 * v[a] + r, 3 * v[c] + q, H(r, q));
          if (a == c) diag.segment<3>(3 * v[a]) += H.diagonal();
        }
      }
    }
    // A node no edge reaches has a zero block: keep it where it is.
    for (int k = 0; k < dim; ++k) trip.emplace_back(k, k, lambda * std::max(diag[k], 1e-6) + (diag[k] == 0.0 ? 1.0 : 0.0));
    Eigen::SparseMatrix<double> H(dim, dim);
    H.setFromTriplets(trip.begin(), trip.end());
    if (!pattern_ready) {
      solver.analyzePattern(H);
      pattern_ready = true;
    }
    solver.factorize(H);
    if (solver.info() != Eigen::Success) {
      lambda *= 10.0;
      continue;
    }
    const Eigen::VectorXd dx = solver.solve(-b);
    std::vector<P> trial = x;
    for (std::size_t k = 0; k < n; ++k) {
      if (var[k] < 0) continue;
      const auto d = dx.segment<3>(3 * var[k]);
      trial[k] = {x[k].x + d[0], x[k].y + d[1], wrap(x[k].t + d[2])};
    }
    const double trial_cost = total_cost(trial, edges, delta);
    if (std::isfinite(trial_cost) && trial_cost < cost) {
      const double decrease = (cost - trial_cost) / std::max(cost, 1e-300);
      x = std::move(trial);
      cost = trial_cost;
      lambda = std::max(lambda / 10.0, 1e-9);
      if (decrease < settings.min_relative_decrease) break;
    } else {
      lambda *= 10.0;
      if (lambda > 1e12) break;
    }
  }
  for (std::size_t k = 0; k < n; ++k)
    poses[k] = Pose2{static_cast<float>(x[k].x), static_cast<float>(x[k].y), static_cast<float>(wrap(x[k].t))};
  result.final_cost = total_cost(x, edges, delta);
  return result;
}

}  // namespace duet
