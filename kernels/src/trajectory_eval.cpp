#include <duet/kernels/error.hpp>
#include <duet/kernels/trajectory_eval.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <tuple>

namespace duet {
namespace {

bool finite_pose(const Eigen::Isometry3d& T) { return T.matrix().allFinite(); }

double rotation_deg(const Eigen::Matrix3d& R) {
  // angle = acos((trace - 1) / 2), clamped against rounding.
  const double c = std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c) * 180.0 / 3.14159265358979323846;
}

}  // namespace

std::vector<std::pair<std::size_t, std::size_t>> associate(std::span<const StampedPose> est, std::span<const StampedPose> gt,
                                                           const AssociationSettings& s) {
  if (!(s.max_dt_s > 0.0) || !std::isfinite(s.max_dt_s))
    fail(ErrorCode::kInvalidArgument, "associate: max_dt_s must be > 0, got " + std::to_string(s.max_dt_s));
  if (!std::isfinite(s.offset_s)) fail(ErrorCode::kInvalidArgument, "associate: offset_s must be finite");
  std::vector<std::size_t> g;
  for (std::size_t j = 0; j < gt.size(); ++j)
    if (std::isfinite(gt[j].stamp_s)) g.push_back(j);
  std::sort(g.begin(), g.end(), [&](std::size_t a, std::size_t b) { return gt[a].stamp_s < gt[b].stamp_s; });
  // Candidates (|dt|, est stamp, gt stamp, i, j) within the window, by binary search.
  std::vector<std::tuple<double, double, double, std::size_t, std::size_t>> cand;
  for (std::size_t i = 0; i < est.size(); ++i) {
    const double t = est[i].stamp_s + s.offset_s;
    if (!std::isfinite(t)) continue;
    auto it = std::lower_bound(g.begin(), g.end(), t - s.max_dt_s, [&](std::size_t j, double v) { return gt[j].stamp_s < v; });
    for (; it != g.end() && gt[*it].stamp_s <= t + s.max_dt_s; ++it) {
      const double d = std::abs(t - gt[*it].stamp_s);
      if (d < s.max_dt_s) cand.emplace_back(d, est[i].stamp_s, gt[*it].stamp_s, i, *it);
    }
  }
  std::sort(cand.begin(), cand.end());
  std::vector<char> used_e(est.size(), 0), used_g(gt.size(), 0);
  std::vector<std::pair<std::size_t, std::size_t>> out;
  for (const auto& [d, te, tg, i, j] : cand) {
    if (used_e[i] || used_g[j]) continue;
    used_e[i] = used_g[j] = 1;
    out.emplace_back(i, j);
  }
  std::sort(out.begin(), out.end(), [&](const auto& a, const auto& b) {
    return est[a.first].stamp_s != est[b.first].stamp_s ? est[a.first].stamp_s < est[b.first].stamp_s : a.first < b.first;
  });
  return out;
}

ErrorStats error_stats(std::span<const double> e) {
  ErrorStats s;
  s.count = e.size();
  if (e.empty()) return s;
  std::vector<double> v(e.begin(), e.end());
  std::sort(v.begin(), v.end());
  double sum = 0.0, sq = 0.0;
  for (double x : v) {
    sum += x;
    sq += x * x;
  }
  const double n = static_cast<double>(v.size());
  s.mean = sum / n;
  s.rmse = std::sqrt(sq / n);
  s.std = std::sqrt(std::max(0.0, sq / n - s.mean * s.mean));  // population std (numpy's, as the TUM tools)
  s.min = v.front();
  s.max = v.back();
  s.median = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  return s;
}

AteResult absolute_trajectory_error(std::span<const StampedPose> est, std::span<const StampedPose> gt, const AteSettings& s) {
  AteResult r;
  r.pairs = associate(est, gt, s.association);
  const std::size_t need = s.align ? 3 : 1;
  if (r.pairs.size() < need)
    fail(ErrorCode::kInvalidArgument, "ATE: " + std::to_string(r.pairs.size()) + " associated poses (max_dt " +
                                          std::to_string(s.association.max_dt_s) + " s), need at least " + std::to_string(need));
  Eigen::Matrix3Xd P(3, static_cast<Eigen::Index>(r.pairs.size())), G(3, static_cast<Eigen::Index>(r.pairs.size()));
  for (std::size_t k = 0; k < r.pairs.size(); ++k) {
    const auto& [i, j] = r.pairs[k];
    if (!finite_pose(est[i].pose) || !finite_pose(gt[j].pose))
      fail(ErrorCode::kInvalidArgument, "ATE: a non-finite pose at stamp " + std::to_string(est[i].stamp_s));
    P.col(static_cast<Eigen::Index>(k)) = est[i].pose.translation();
    G.col(static_cast<Eigen::Index>(k)) = gt[j].pose.translation();
  }
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  if (s.align) T = Eigen::umeyama(P, G, s.with_scale);
  // umeyama returns [s R | t]: scale = cube root of det(sR).
  r.scale = s.with_scale ? std::cbrt(T.topLeftCorner<3, 3>().determinant()) : 1.0;
  r.alignment.linear() = T.topLeftCorner<3, 3>() / r.scale;
  r.alignment.translation() = T.topRightCorner<3, 1>();
  r.errors.resize(r.pairs.size());
  for (Eigen::Index k = 0; k < P.cols(); ++k) {
    const Eigen::Vector3d a = T.topLeftCorner<3, 3>() * P.col(k) + T.topRightCorner<3, 1>();
    r.errors[static_cast<std::size_t>(k)] = (a - G.col(k)).norm();
  }
  r.translation = error_stats(r.errors);
  return r;
}

RpeResult relative_pose_error(std::span<const StampedPose> est, std::span<const StampedPose> gt, const RpeSettings& s) {
  if (!(s.delta > 0.0) || !std::isfinite(s.delta))
    fail(ErrorCode::kInvalidArgument, "RPE: delta must be > 0, got " + std::to_string(s.delta));
  if (s.unit == RpeUnit::kFrames && s.delta != std::floor(s.delta))
    fail(ErrorCode::kInvalidArgument, "RPE: a delta in frames must be a whole number, got " + std::to_string(s.delta));
  const auto pairs = associate(est, gt, s.association);
  const std::size_t n = pairs.size();
  for (const auto& [i, j] : pairs)
    if (!finite_pose(est[i].pose) || !finite_pose(gt[j].pose))
      fail(ErrorCode::kInvalidArgument, "RPE: a non-finite pose at stamp " + std::to_string(est[i].stamp_s));
  // The index of each associated pose along the unit.
  std::vector<double> index(n, 0.0);
  for (std::size_t k = 0; k < n; ++k) {
    switch (s.unit) {
      case RpeUnit::kFrames: index[k] = static_cast<double>(k); break;
      case RpeUnit::kSeconds: index[k] = est[pairs[k].first].stamp_s; break;
      case RpeUnit::kMetres:
        index[k] = k == 0 ? 0.0
                          : index[k - 1] + (gt[pairs[k].second].pose.translation() - gt[pairs[k - 1].second].pose.translation()).norm();
        break;
    }
  }
  std::vector<double> te, re;
  for (std::size_t a = 0; a < n; ++a) {
    // The first b with index[b] >= index[a] + delta (a small tolerance for float frames / stamps).
    const double target = index[a] + s.delta - 1e-9;
    const auto it = std::lower_bound(index.begin() + static_cast<std::ptrdiff_t>(a) + 1, index.end(), target);
    if (it == index.end()) break;
    const std::size_t b = static_cast<std::size_t>(it - index.begin());
    const Eigen::Isometry3d& P0 = est[pairs[a].first].pose;
    const Eigen::Isometry3d& P1 = est[pairs[b].first].pose;
    const Eigen::Isometry3d& G0 = gt[pairs[a].second].pose;
    const Eigen::Isometry3d& G1 = gt[pairs[b].second].pose;
    const Eigen::Isometry3d E = (G0.inverse() * G1).inverse() * (P0.inverse() * P1);
    te.push_back(E.translation().norm());
    re.push_back(rotation_deg(E.linear()));
  }
  if (te.empty())
    fail(ErrorCode::kInvalidArgument, "RPE: no pose pair is " + std::to_string(s.delta) +
                                          (s.unit == RpeUnit::kFrames ? " frames" : s.unit == RpeUnit::kSeconds ? " s" : " m") +
                                          " apart among " + std::to_string(n) + " associated poses");
  RpeResult r;
  r.translation = error_stats(te);
  r.rotation = error_stats(re);
  r.pairs = te.size();
  return r;
}

}  // namespace duet
