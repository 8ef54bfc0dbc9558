#include "random.hpp"

#include <duet/kernels/error.hpp>
#include <duet/kernels/visual_odometry.hpp>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

namespace duet {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

void bad(const std::string& where, const std::string& what) { fail(ErrorCode::kInvalidArgument, where + ": " + what); }

float depth_at(const DepthImageView& d, int x, int y) {
  const std::size_t elem = d.format == DepthFormat::kU16 ? 2 : 4;
  const std::size_t stride = d.row_stride_bytes == 0 ? static_cast<std::size_t>(d.width) * elem : d.row_stride_bytes;
  const auto* row = static_cast<const std::uint8_t*>(d.data) + static_cast<std::size_t>(y) * stride;
  if (d.format == DepthFormat::kU16) {
    std::uint16_t raw = 0;
    std::memcpy(&raw, row + static_cast<std::size_t>(x) * 2, 2);
    return raw == 0 ? kNaN : static_cast<float>(raw) / d.depth_units_per_m;
  }
  float m = 0.0f;
  std::memcpy(&m, row + static_cast<std::size_t>(x) * 4, 4);
  return m > 0.0f ? m : kNaN;
}

/// The depth at (x, y), or the median of its valid 3 x 3 neighbours when they agree (see header).
float depth_with_fill(const DepthImageView& d, int x, int y) {
  const float z = depth_at(d, x, y);
  if (std::isfinite(z)) return z;
  float v[8];
  int n = 0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const int xx = x + dx, yy = y + dy;
      if ((dx == 0 && dy == 0) || xx < 0 || yy < 0 || xx >= d.width || yy >= d.height) continue;
      const float w = depth_at(d, xx, yy);
      if (std::isfinite(w)) v[n++] = w;
    }
  if (n < 3) return kNaN;
  for (int i = 1; i < n; ++i)  // insertion sort of <= 8 values
    for (int j = i; j > 0 && v[j - 1] > v[j]; --j) std::swap(v[j - 1], v[j]);
  const float med = v[n / 2];
  return (v[n - 1] - v[0]) <= 0.03f * med ? med : kNaN;
}

void check_frame(const SensorFrame& f, std::size_t index) {
  const std::string where = "make_visual_frame: camera " + std::to_string(index);
  const auto& K = f.intrinsics;
  if (K.width <= 0 || K.height <= 0 || !(K.fx > 0.0f) || !(K.fy > 0.0f) || !std::isfinite(K.cx) || !std::isfinite(K.cy))
    bad(where, "intrinsics must have a positive size and focal lengths");
  if (f.depth.data == nullptr) bad(where, "has no depth image");
  if (f.depth.width != K.width || f.depth.height != K.height)
    bad(where, "depth image " + std::to_string(f.depth.width) + "x" + std::to_string(f.depth.height) +
                   " does not match the intrinsics' " + std::to_string(K.width) + "x" + std::to_string(K.height));
  const std::size_t elem = f.depth.format == DepthFormat::kU16 ? 2 : 4;
  if (f.depth.row_stride_bytes != 0 && f.depth.row_stride_bytes < static_cast<std::size_t>(K.width) * elem)
    bad(where, "depth row stride " + std::to_string(f.depth.row_stride_bytes) + " is below the row's bytes");
  if (f.depth.format == DepthFormat::kU16 && !(f.depth.depth_units_per_m > 0.0f))
    bad(where, "depth_units_per_m must be > 0");
  if (f.color.data != nullptr && (f.color.width != K.width || f.color.height != K.height))
    bad(where, "colour image " + std::to_string(f.color.width) + "x" + std::to_string(f.color.height) +
                   " does not match the depth image's " + std::to_string(K.width) + "x" + std::to_string(K.height));
}

/// One correspondence: previous 3D point (prev robot frame), current 3D point (curr robot
/// frame, NaN without depth), current pixel, camera, squared inlier threshold.
struct Corr {
  Eigen::Vector3d p;
  Eigen::Vector3d q;
  Eigen::Vector2d uv;
  std::uint32_t camera = 0;
  double thr2 = 0.0;
  bool has_q = false;
};

/// Projection of the current robot frame into camera c.
struct CamModel {
  Eigen::Matrix3d R_cr;
  Eigen::Vector3d t_cr;
  double fx, fy, cx, cy;
};

/// Squared reprojection error of correspondence k under X = T_curr_prev; +inf behind the camera.
double error2(const Corr& c, const CamModel& m, const Eigen::Isometry3d& X) {
  const Eigen::Vector3d r = m.R_cr * (X * c.p) + m.t_cr;
  if (r.z() < 0.05) return std::numeric_limits<double>::infinity();
  const double u = m.fx * r.x() / r.z() + m.cx, v = m.fy * r.y() / r.z() + m.cy;
  return (u - c.uv.x()) * (u - c.uv.x()) + (v - c.uv.y()) * (v - c.uv.y());
}

struct Score {
  double cost = std::numeric_limits<double>::infinity();
  std::size_t inliers = 0;
};

Score score(std::span<const Corr> corr, std::span<const CamModel> cams, const Eigen::Isometry3d& X) {
  Score s{0.0, 0};
  for (const Corr& c : corr) {
    const double e2 = error2(c, cams[c.camera], X) / c.thr2;
    if (e2 < 1.0) {
      s.cost += e2;
      ++s.inliers;
    } else {
      s.cost += 1.0;
    }
  }
  return s;
}

/// The rigid X with q ~ X p from three correspondences; false for a degenerate sample.
bool rigid_from_three(const Corr& a, const Corr& b, const Corr& c, Eigen::Isometry3d& X) {
  const Eigen::Vector3d pab = b.p - a.p, pac = c.p - a.p, qab = b.q - a.q, qac = c.q - a.q;
  if (pab.cross(pac).norm() < 1e-4) return false;  // collinear (area < 0.5e-4 m^2)
  // A rigid motion keeps distances: a sample whose distances disagree by > 10 % is not one.
  auto agree = [](double dp, double dq) { return std::abs(dp - dq) <= 0.1 * std::max(dp, dq) + 0.02; };
  if (!agree(pab.norm(), qab.norm()) || !agree(pac.norm(), qac.norm()) || !agree((c.p - b.p).norm(), (c.q - b.q).norm()))
    return false;
  Eigen::Matrix3d P, Q;
  P << a.p, b.p, c.p;
  Q << a.q, b.q, c.q;
  const Eigen::Matrix4d T = Eigen::umeyama(P, Q, false);
  if (!T.allFinite()) return false;
  X.matrix() = T;
  return true;
}

/// Gauss-Newton on the reprojection error of `inl` (PnP refinement), in place. Returns J^T J of
/// the last linearisation and the sum of squared errors at the end.
void refine(std::span<const Corr> corr, std::span<const std::uint32_t> inl, std::span<const CamModel> cams, int iterations,
            Eigen::Isometry3d& X, Eigen::Matrix<double, 6, 6>& H_out, double& sse_out) {
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  auto linearise = [&](const Eigen::Isometry3d& T, Mat6& H, Vec6& g) {
    H.setZero();
    g.setZero();
    double sse = 0.0;
    for (const std::uint32_t k : inl) {
      const Corr& c = corr[k];
      const CamModel& m = cams[c.camera];
      const Eigen::Vector3d q = T * c.p;
      const Eigen::Vector3d r = m.R_cr * q + m.t_cr;
      if (r.z() < 0.05) continue;
      const double iz = 1.0 / r.z();
      const Eigen::Vector2d res(m.fx * r.x() * iz + m.cx - c.uv.x(), m.fy * r.y() * iz + m.cy - c.uv.y());
      Eigen::Matrix<double, 2, 3> dpi;
      dpi << m.fx * iz, 0.0, -m.fx * r.x() * iz * iz, 0.0, m.fy * iz, -m.fy * r.y() * iz * iz;
      Eigen::Matrix<double, 3, 6> dq;  // d(q) / d(omega, v) for exp(delta) * T
      dq.leftCols<3>() << 0.0, q.z(), -q.y(), -q.z(), 0.0, q.x(), q.y(), -q.x(), 0.0;
      dq.rightCols<3>().setIdentity();
      const Eigen::Matrix<double, 2, 6> J = dpi * m.R_cr * dq;
      H.noalias() += J.transpose() * J;
      g.noalias() += J.transpose() * res;
      sse += res.squaredNorm();
    }
    return sse;
  };
  Mat6 H;
  Vec6 g;
  double sse = linearise(X, H, g);
  for (int it = 0; it < iterations; ++it) {
    const Eigen::LDLT<Mat6> ldlt(H);
    if (ldlt.info() != Eigen::Success) break;
    const Vec6 delta = -ldlt.solve(g);
    if (!delta.allFinite()) break;
    Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
    const double angle = delta.head<3>().norm();
    if (angle > 1e-12) step.linear() = Eigen::AngleAxisd(angle, delta.head<3>() / angle).toRotationMatrix();
    step.translation() = delta.tail<3>();
    const Eigen::Isometry3d candidate = step * X;
    Mat6 Hc;
    Vec6 gc;
    const double sse_c = linearise(candidate, Hc, gc);
    if (!(sse_c <= sse)) break;  // no improvement: keep X (also stops on NaN)
    X = candidate;
    H = Hc;
    g = gc;
    const bool converged = sse - sse_c < 1e-9 * std::max(1.0, sse);
    sse = sse_c;
    if (converged) break;
  }
  H_out = H;
  sse_out = sse;
}

VisualOdometryResult estimate_motion_once(const VisualFrame& prev, const VisualFrame& curr, const Eigen::Isometry3d& guess,
                                          const VisualOdometrySettings& s);

}  // namespace

const char* to_string(VisualOdometryStatus s) noexcept {
  switch (s) {
    case VisualOdometryStatus::kOk: return "ok";
    case VisualOdometryStatus::kTooFewFeatures: return "too_few_features";
    case VisualOdometryStatus::kTooFewMatches: return "too_few_matches";
    case VisualOdometryStatus::kTooFewInliers: return "too_few_inliers";
  }
  return "unknown";
}

std::size_t VisualFrame::features() const noexcept {
  std::size_t n = 0;
  for (const auto& c : cameras) n += c.features.size();
  return n;
}

std::size_t VisualFrame::features_with_depth() const noexcept {
  std::size_t n = 0;
  for (const auto& c : cameras)
    for (const auto& d : c.depths_m) n += std::isfinite(d) ? 1 : 0;
  return n;
}

void validate(const VisualFrameSettings& s) {
  validate(s.orb);
  const std::string w = "visual frame settings";
  if (!(s.max_depth_m > s.min_depth_m && s.max_depth_m <= 100.0f)) bad(w, "max_depth_m must be in (min_depth_m, 100], got " + std::to_string(s.max_depth_m));
  if (!(s.min_depth_m >= 0.0f)) bad(w, "min_depth_m must be >= 0, got " + std::to_string(s.min_depth_m));
}

void validate(const VisualOdometrySettings& s) {
  validate(s.match);
  const std::string w = "visual odometry settings";
  if (!(s.guided_radius_px >= 0.0f && s.guided_radius_px <= 1000.0f)) bad(w, "guided_radius_px must be in [0, 1000], got " + std::to_string(s.guided_radius_px));
  if (!(s.rematch_radius_px >= 0.0f && s.rematch_radius_px <= 1000.0f)) bad(w, "rematch_radius_px must be in [0, 1000], got " + std::to_string(s.rematch_radius_px));
  if (!(s.fundamental_threshold_px > 0.0f && s.fundamental_threshold_px <= 50.0f)) bad(w, "fundamental_threshold_px must be in (0, 50], got " + std::to_string(s.fundamental_threshold_px));
  if (s.min_fundamental_matches < 8 || s.min_fundamental_matches > 10000) bad(w, "min_fundamental_matches must be in [8, 10000], got " + std::to_string(s.min_fundamental_matches));
  if (!(s.inlier_threshold_px > 0.0f && s.inlier_threshold_px <= 50.0f)) bad(w, "inlier_threshold_px must be in (0, 50], got " + std::to_string(s.inlier_threshold_px));
  if (s.max_hypotheses < 1 || s.max_hypotheses > 100000) bad(w, "max_hypotheses must be in [1, 100000], got " + std::to_string(s.max_hypotheses));
  if (!(s.confidence > 0.0f && s.confidence < 1.0f)) bad(w, "confidence must be in (0, 1), got " + std::to_string(s.confidence));
  if (s.refine_iterations < 0 || s.refine_iterations > 100) bad(w, "refine_iterations must be in [0, 100], got " + std::to_string(s.refine_iterations));
  if (s.min_inliers < 4 || s.min_inliers > 100000) bad(w, "min_inliers must be in [4, 100000], got " + std::to_string(s.min_inliers));
}

void make_visual_frame(std::span<const SensorFrame> frames, const VisualFrameSettings& settings, VisualFrame& out) {
  validate(settings);
  for (std::size_t i = 0; i < frames.size(); ++i) check_frame(frames[i], i);
  out.cameras.resize(frames.size());
  tbb::parallel_for(std::size_t{0}, frames.size(), [&](std::size_t i) {
    const SensorFrame& f = frames[i];
    VisualCamera& cam = out.cameras[i];
    cam.intrinsics = f.intrinsics;
    cam.T_robot_camera = f.T_robot_camera;
    cam.scale_factor = settings.orb.scale_factor;
    extract_orb(f.color, settings.orb, cam.features);
    const std::size_t n = cam.features.size();
    cam.points_robot.resize(n);
    cam.depths_m.resize(n);
    const auto& K = f.intrinsics;
    for (std::size_t k = 0; k < n; ++k) {
      const Eigen::Vector2f uv = cam.features.pixels[k];
      const int x = std::clamp(static_cast<int>(std::lround(uv.x())), 0, K.width - 1);
      const int y = std::clamp(static_cast<int>(std::lround(uv.y())), 0, K.height - 1);
      const float z = depth_with_fill(f.depth, x, y);
      if (!(z >= settings.min_depth_m && z <= settings.max_depth_m)) {
        cam.depths_m[k] = kNaN;
        cam.points_robot[k] = Eigen::Vector3f::Constant(kNaN);
        continue;
      }
      cam.depths_m[k] = z;
      const Eigen::Vector3f pc((uv.x() - K.cx) * z / K.fx, (uv.y() - K.cy) * z / K.fy, z);
      cam.points_robot[k] = f.T_robot_camera * pc;
    }
  });
}

VisualOdometryResult estimate_motion(const VisualFrame& prev, const VisualFrame& curr, const Eigen::Isometry3d& guess,
                                     const VisualOdometrySettings& s) {
  validate(s);
  VisualOdometryResult r = estimate_motion_once(prev, curr, guess, s);
  if (r.status == VisualOdometryStatus::kOk || !(s.guided_radius_px > 0.0f) || r.status == VisualOdometryStatus::kTooFewFeatures)
    return r;
  // The guess was too far off for its window (or the window too small): brute force.
  VisualOdometrySettings brute = s;
  brute.guided_radius_px = 0.0f;
  VisualOdometryResult b = estimate_motion_once(prev, curr, guess, brute);
  b.matches += r.matches;
  return b;
}

namespace {

VisualOdometryResult estimate_motion_once(const VisualFrame& prev, const VisualFrame& curr, const Eigen::Isometry3d& guess,
                                          const VisualOdometrySettings& s) {
  if (prev.cameras.size() != curr.cameras.size())
    fail(ErrorCode::kInvalidArgument, "estimate_motion: the previous frame has " + std::to_string(prev.cameras.size()) +
                                          " cameras, the current one " + std::to_string(curr.cameras.size()));
  VisualOdometryResult res;
  res.motion = guess;
  res.camera_inliers.assign(curr.cameras.size(), 0);
  const auto min_n = static_cast<std::size_t>(s.min_inliers);
  if (prev.features_with_depth() < min_n || curr.features() < min_n) return res;

  const Eigen::Isometry3d X_guess = guess.inverse();  // T_curr_prev
  std::vector<CamModel> cams(curr.cameras.size());
  for (std::size_t c = 0; c < curr.cameras.size(); ++c) {
    const VisualCamera& cc = curr.cameras[c];
    const Eigen::Isometry3d T_cr = cc.T_robot_camera.cast<double>().inverse();
    cams[c] = {T_cr.linear(), T_cr.translation(), cc.intrinsics.fx, cc.intrinsics.fy, cc.intrinsics.cx, cc.intrinsics.cy};
  }
  // Correspondences of every camera: brute force, or guided by `X_pred` within `radius`;
  // with the fundamental-matrix filter when `f_filter`. Counts matches into *matched.
  auto build = [&](const Eigen::Isometry3d* X_pred, float radius, bool f_filter, std::size_t* matched) {
    std::vector<Corr> corr;
    std::vector<DescriptorMatch> matches;
    for (std::size_t c = 0; c < curr.cameras.size(); ++c) {
      const VisualCamera& pc = prev.cameras[c];
      const VisualCamera& cc = curr.cameras[c];
      // Queries: the previous features with a 3D point.
      std::vector<std::uint32_t> qidx;
      std::vector<Descriptor256> qdesc;
      for (std::size_t k = 0; k < pc.features.size(); ++k)
        if (std::isfinite(pc.depths_m[k])) {
          qidx.push_back(static_cast<std::uint32_t>(k));
          qdesc.push_back(pc.features.descriptors[k]);
        }
      if (qidx.empty() || cc.features.empty()) continue;
      if (X_pred != nullptr) {
        std::vector<Eigen::Vector2f> predicted(qidx.size());
        for (std::size_t i = 0; i < qidx.size(); ++i) {
          const Eigen::Vector3d r = cams[c].R_cr * (*X_pred * pc.points_robot[qidx[i]].cast<double>()) + cams[c].t_cr;
          predicted[i] = r.z() > 0.05 ? Eigen::Vector2f(static_cast<float>(cams[c].fx * r.x() / r.z() + cams[c].cx),
                                                        static_cast<float>(cams[c].fy * r.y() / r.z() + cams[c].cy))
                                      : Eigen::Vector2f::Constant(kNaN);
        }
        match_descriptors_guided(qdesc, predicted, cc.features.descriptors, cc.features.pixels, radius, s.match, matches);
      } else {
        match_descriptors(qdesc, cc.features.descriptors, s.match, matches);
      }
      if (matched != nullptr) *matched += matches.size();
      std::vector<char> keep(matches.size(), 1);
      if (f_filter && matches.size() >= static_cast<std::size_t>(s.min_fundamental_matches)) {
        std::vector<cv::Point2f> a, b;
        a.reserve(matches.size());
        b.reserve(matches.size());
        for (const auto& m : matches) {
          const Eigen::Vector2f pa = pc.features.pixels[qidx[m.query]], pb = cc.features.pixels[m.train];
          a.emplace_back(pa.x(), pa.y());
          b.emplace_back(pb.x(), pb.y());
        }
        std::vector<unsigned char> mask;
        const cv::Mat F = cv::findFundamentalMat(a, b, cv::FM_RANSAC, s.fundamental_threshold_px, 0.99, mask);
        // No F (degenerate), or one that explains under half of the matches: keep them all (header, step b).
        if (!F.empty() && mask.size() == matches.size()) {
          const auto kept = static_cast<std::size_t>(std::count(mask.begin(), mask.end(), static_cast<unsigned char>(1)));
          if (2 * kept >= matches.size())
            for (std::size_t i = 0; i < matches.size(); ++i) keep[i] = mask[i] != 0;
        }
      }
      for (std::size_t i = 0; i < matches.size(); ++i) {
        if (!keep[i]) continue;
        const auto& m = matches[i];
        Corr k;
        k.p = pc.points_robot[qidx[m.query]].cast<double>();
        k.q = cc.points_robot[m.train].cast<double>();
        k.has_q = k.q.allFinite();
        k.uv = cc.features.pixels[m.train].cast<double>();
        k.camera = static_cast<std::uint32_t>(c);
        const double thr = s.inlier_threshold_px * std::pow(static_cast<double>(cc.scale_factor), cc.features.octaves[m.train]);
        k.thr2 = thr * thr;
        corr.push_back(k);
      }
    }
    return corr;
  };
  std::vector<Corr> corr = s.guided_radius_px > 0.0f ? build(&X_guess, s.guided_radius_px, s.fundamental_filter, &res.matches)
                                                     : build(nullptr, 0.0f, s.fundamental_filter, &res.matches);
  res.fundamental_inliers = corr.size();
  if (corr.size() < min_n) {
    res.status = VisualOdometryStatus::kTooFewMatches;
    return res;
  }

  // RANSAC (MSAC) in blocks of 32 hypotheses; hypothesis 0 is the guess.
  std::vector<std::uint32_t> sampleable;
  for (std::size_t k = 0; k < corr.size(); ++k)
    if (corr[k].has_q) sampleable.push_back(static_cast<std::uint32_t>(k));
  constexpr int kBlock = 32;
  Eigen::Isometry3d best_X = X_guess;
  Score best = score(corr, cams, X_guess);
  int done = 1;
  const double log_fail = std::log(1.0 - static_cast<double>(s.confidence));
  while (sampleable.size() >= 3 && done < s.max_hypotheses) {
    const int n = std::min(kBlock, s.max_hypotheses - done);
    std::vector<Score> scores(static_cast<std::size_t>(n));
    std::vector<Eigen::Isometry3d> hyps(static_cast<std::size_t>(n), Eigen::Isometry3d::Identity());
    tbb::parallel_for(0, n, [&](int i) {
      const auto h = static_cast<std::uint64_t>(done + i);
      detail::Rng rng(detail::stream_seed(s.seed, h));
      const auto m = static_cast<std::uint64_t>(sampleable.size());
      const std::uint32_t a = sampleable[rng.next() % m];
      std::uint32_t b = sampleable[rng.next() % m], c = sampleable[rng.next() % m];
      if (a == b || a == c || b == c) return;
      if (!rigid_from_three(corr[a], corr[b], corr[c], hyps[static_cast<std::size_t>(i)])) return;
      scores[static_cast<std::size_t>(i)] = score(corr, cams, hyps[static_cast<std::size_t>(i)]);
    });
    for (int i = 0; i < n; ++i)
      if (scores[static_cast<std::size_t>(i)].cost < best.cost) {
        best = scores[static_cast<std::size_t>(i)];
        best_X = hyps[static_cast<std::size_t>(i)];
      }
    done += n;
    const double w = static_cast<double>(best.inliers) / static_cast<double>(sampleable.size());
    const double w3 = std::min(w * w * w, 1.0 - 1e-12);
    if (w3 > 0.0 && static_cast<double>(done) >= log_fail / std::log(1.0 - w3)) break;
  }
  res.hypotheses = static_cast<std::size_t>(done);

  // Refine on the inliers, re-choose them, refine again.
  Eigen::Isometry3d X = best_X;
  std::vector<std::uint32_t> inl;
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  double sse = 0.0;
  auto refine_rounds = [&] {  // inliers of X, refine; twice
    for (int round = 0; round < 2; ++round) {
      inl.clear();
      for (std::size_t k = 0; k < corr.size(); ++k)
        if (error2(corr[k], cams[corr[k].camera], X) < corr[k].thr2) inl.push_back(static_cast<std::uint32_t>(k));
      if (inl.size() < min_n) break;
      refine(corr, inl, cams, s.refine_iterations, X, H, sse);
    }
  };
  refine_rounds();
  // d': search by projection with the refined motion, then refine on the new matches.
  if (s.rematch_radius_px > 0.0f && inl.size() >= min_n) {
    std::vector<Corr> again = build(&X, s.rematch_radius_px, false, nullptr);
    if (again.size() >= inl.size()) {
      corr = std::move(again);
      refine_rounds();
    }
  }
  inl.clear();
  sse = 0.0;
  for (std::size_t k = 0; k < corr.size(); ++k) {
    const double e2 = error2(corr[k], cams[corr[k].camera], X);
    if (e2 < corr[k].thr2) {
      inl.push_back(static_cast<std::uint32_t>(k));
      sse += e2;
      ++res.camera_inliers[corr[k].camera];
    }
  }
  res.inliers = inl.size();
  if (inl.size() < min_n) {
    res.status = VisualOdometryStatus::kTooFewInliers;
    std::fill(res.camera_inliers.begin(), res.camera_inliers.end(), 0);
    res.inliers = 0;
    return res;
  }
  // Covariance from the final inliers' linearisation.
  Eigen::Isometry3d Xc = X;
  refine(corr, inl, cams, 0, Xc, H, sse);
  const double dof = std::max(1.0, 2.0 * static_cast<double>(inl.size()) - 6.0);
  const double sigma2 = sse / dof;
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(H);
  if (ldlt.info() == Eigen::Success) res.covariance = sigma2 * ldlt.solve(Eigen::Matrix<double, 6, 6>::Identity());
  res.rms_px = std::sqrt(sse / static_cast<double>(inl.size()));
  res.motion = X.inverse();
  res.status = VisualOdometryStatus::kOk;
  return res;
}

}  // namespace

Eigen::Matrix3d planar_covariance(const Eigen::Isometry3d& motion, const Eigen::Matrix<double, 6, 6>& covariance) {
  // motion * exp(xi): translation += R v, rotation vector (previous frame) += R omega.
  const Eigen::Matrix3d R = motion.linear();
  Eigen::Matrix<double, 3, 6> J = Eigen::Matrix<double, 3, 6>::Zero();
  J.block<2, 3>(0, 3) = R.topRows<2>();
  J.block<1, 3>(2, 0) = R.row(2);
  return J * covariance * J.transpose();
}

}  // namespace duet
