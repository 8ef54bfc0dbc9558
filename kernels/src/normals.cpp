#include <duet/kernels/error.hpp>
#include <duet/kernels/normals.hpp>

#include "parallel.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace duet {

void validate(const NormalSettings& s) {
  if (s.k < 3 || s.k > 256)
    fail(ErrorCode::kInvalidArgument, "NormalSettings.k must be in [3, 256], got " + std::to_string(s.k));
  if (!s.viewpoint.allFinite()) fail(ErrorCode::kInvalidArgument, "NormalSettings.viewpoint must be finite");
}

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Smallest eigenvalue l0 (and l1 <= l2) and a unit eigenvector v of l0 for a symmetric positive
// semi-definite 3x3 matrix C, without trigonometry: l0 is the smallest root of the
// characteristic polynomial p(l) = l^3 - c2 l^2 + c1 l - c0, found by Newton's method from 0
// (p is increasing and concave on [0, l0], as l0 <= trace/3 = the inflection point: the
// iterates rise monotonically to l0); l1, l2 from the remaining quadratic; v = the largest
// cross product of two rows of C - l0 I (its null space). Returns false when l0 is not well
// separated from l1 (gap < 1e-3 of the trace), where v is ill-conditioned: the caller then uses
// Eigen's closed-form solver. No atan2 / sincos: the eigen-solve's share of the normals time went
// from ~14 % to ~7-10 % in perf.
bool smallest_eigenpair(const Eigen::Matrix3d& C, double trace, double& l0, double& l1, double& l2,
                        Eigen::Vector3d& v) {
  const double a = C(0, 0), b = C(1, 1), c = C(2, 2), d = C(0, 1), e = C(1, 2), f = C(0, 2);
  const double c2 = trace;
  const double c1 = a * b + a * c + b * c - d * d - e * e - f * f;
  const double c0 = a * (b * c - e * e) - d * (d * c - e * f) + f * (d * e - b * f);
  double l = 0.0;
  if (c0 > 0.0) {
    for (int it = 0; it < 64; ++it) {
      const double pv = ((l - c2) * l + c1) * l - c0;
      const double dp = (3.0 * l - 2.0 * c2) * l + c1;
      if (!(pv < 0.0) || !(dp > 0.0)) break;
      const double step = -pv / dp;
      l += step;
      if (step <= 1e-9 * l) break;  // quadratic convergence: the remaining error is ~(1e-9)^2 of l
    }
  }
  const double s = c2 - l, prod = c1 - l * s;
  const double root = std::sqrt(std::max(0.0, s * s - 4.0 * prod));
  l0 = l;
  l1 = 0.5 * (s - root);
  l2 = s - l1;
  if (!(l1 - l0 >= 1e-3 * trace)) return false;
  const Eigen::Vector3d r0(a - l, d, f), r1(d, b - l, e), r2(f, e, c - l);
  const Eigen::Vector3d x01 = r0.cross(r1), x02 = r0.cross(r2), x12 = r1.cross(r2);
  const double n01 = x01.squaredNorm(), n02 = x02.squaredNorm(), n12 = x12.squaredNorm();
  const Eigen::Vector3d& best = n01 >= n02 ? (n01 >= n12 ? x01 : x12) : (n02 >= n12 ? x02 : x12);
  const double nb = std::max({n01, n02, n12});
  if (!(nb > 0.0) || !std::isfinite(nb)) return false;
  v = best / std::sqrt(nb);
  return true;
}

// Eq. (2): covariance of the neighbourhood, normal = eigenvector of the smallest eigenvalue.
// get(i) returns the i-th neighbour. Double precision: the neighbourhoods are small (cm) and
// their coordinates large (m), so float sums lose digits.
template <class Get>
bool normal_of(int count, Get&& get, Eigen::Vector3f& normal, float& curvature) {
  if (count < 3) {
    normal.setConstant(kNaN);
    curvature = kNaN;
    return false;
  }
  // One pass over the points shifted by the first one (neighbourhoods are small, coordinates
  // large: the shifted values are small and exact to float rounding), sums in double:
  // C = sum(d d^T)/n - mean mean^T with d = p - p0.
  const Eigen::Vector3f p0 = get(0);
  double sx = 0, sy = 0, sz = 0, sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3f& p = get(i);
    const double x = static_cast<double>(p.x() - p0.x()), y = static_cast<double>(p.y() - p0.y()),
                 z = static_cast<double>(p.z() - p0.z());
    sx += x;
    sy += y;
    sz += z;
    sxx += x * x;
    sxy += x * y;
    sxz += x * z;
    syy += y * y;
    syz += y * z;
    szz += z * z;
  }
  const double inv_n = 1.0 / count;
  const double mx = sx * inv_n, my = sy * inv_n, mz = sz * inv_n;
  Eigen::Matrix3d C;
  C(0, 0) = sxx * inv_n - mx * mx;
  C(1, 1) = syy * inv_n - my * my;
  C(2, 2) = szz * inv_n - mz * mz;
  C(0, 1) = C(1, 0) = sxy * inv_n - mx * my;
  C(0, 2) = C(2, 0) = sxz * inv_n - mx * mz;
  C(1, 2) = C(2, 1) = syz * inv_n - my * mz;
  const double trace = C.trace();
  if (!(trace > 0.0) || !std::isfinite(trace)) {
    normal.setConstant(kNaN);
    curvature = kNaN;
    return false;
  }
  double l0, l1, l2;
  Eigen::Vector3d v;
  if (!smallest_eigenpair(C, trace, l0, l1, l2, v)) {  // (nearly) repeated smallest eigenvalue
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
    es.computeDirect(C);
    const Eigen::Vector3d ev = es.eigenvalues();  // ascending
    l0 = ev[0], l1 = ev[1], l2 = ev[2];
    v = es.eigenvectors().col(0);
  }
  // Collinear points: no plane, no normal (as PCL). computeDirect is accurate to ~sqrt(eps) of
  // the trace for a double eigenvalue, so "zero" means below 1e-7 of the trace.
  if (l1 <= 1e-7 * trace) {
    normal.setConstant(kNaN);
    curvature = kNaN;
    return false;
  }
  normal = v.cast<float>().normalized();
  curvature = static_cast<float>(std::max(0.0, l0) / (std::max(0.0, l0) + l1 + l2));
  return true;
}

}  // namespace

bool normal_from_neighbours(std::span<const Eigen::Vector3f> nbrs, Eigen::Vector3f& normal, float& curvature) {
  return normal_of(static_cast<int>(nbrs.size()), [&](int i) -> const Eigen::Vector3f& { return nbrs[static_cast<std::size_t>(i)]; },
                   normal, curvature);
}

void estimate_normals(PointsView points, const KdTree& tree, const NormalSettings& settings,
                      std::span<Eigen::Vector3f> normals, std::span<float> curvature) {
  validate(settings);
  const std::size_t n = points.size();
  if (tree.size() != n)
    fail(ErrorCode::kInvalidArgument, "estimate_normals: the tree indexes " + std::to_string(tree.size()) +
                                          " points, the cloud has " + std::to_string(n));
  if (normals.size() != n)
    fail(ErrorCode::kInvalidArgument, "estimate_normals: normals has " + std::to_string(normals.size()) +
                                          " entries, expected " + std::to_string(n));
  if (!curvature.empty() && curvature.size() != n)
    fail(ErrorCode::kInvalidArgument, "estimate_normals: curvature has " + std::to_string(curvature.size()) +
                                          " entries, expected " + std::to_string(n) + " (or 0)");
  const auto tp = tree.tree_points();
  const auto ids = tree.order();
  if (tp.size() < n) {  // non-finite inputs are not in the tree: they get NaN
    detail::for_each_index(n, 4096, [&](std::size_t i) {
      if (!is_finite(points[i])) {
        normals[i].setConstant(kNaN);
        if (!curvature.empty()) curvature[i] = kNaN;
      }
    });
  }
  const int k = settings.k;
  const Eigen::Vector3f vp = settings.viewpoint;
  // Queries leaf by leaf, in tree order (KdTree::knn_leaf: one batch per leaf bucket, the
  // neighbours of all its points at once); every result is exact and written to its own input
  // index, so the output is independent of the thread count and of the blocking.
  const std::size_t leaves = tree.leaf_count();
  detail::for_blocks(leaves, 32, [&](std::size_t, std::size_t lbegin, std::size_t lend) {
    KdTree::LeafKnn ws;
    for (std::size_t l = lbegin; l < lend; ++l) {
      const std::uint32_t m = tree.knn_leaf(l, k, ws, /*sorted=*/false);  // Eq. (2) is a sum: any order
      const std::uint32_t first = tree.leaf_begin(l);
      for (std::uint32_t i = 0; i < m; ++i) {
        const std::uint32_t j = first + i;
        const Eigen::Vector3f& q = tp[j];
        const std::uint32_t* pos = ws.pos.data() + static_cast<std::size_t>(i) * static_cast<std::size_t>(k);
        Eigen::Vector3f nrm;
        float curv;
        if (normal_of(ws.count[i], [&](int r) -> const Eigen::Vector3f& { return tp[pos[r]]; }, nrm, curv)) {
          if ((vp - q).dot(nrm) < 0.0f) nrm = -nrm;  // face the viewpoint (as PCL)
        }
        const std::uint32_t id = ids[j];
        normals[id] = nrm;
        if (!curvature.empty()) curvature[id] = curv;
      }
    }
  });
}

void estimate_normals(PointCloud& cloud, const NormalSettings& settings) {
  validate(settings);
  KdTree tree(cloud.points_view());
  cloud.normals.resize(cloud.size());
  cloud.curvature.resize(cloud.size());
  estimate_normals(cloud.points_view(), tree, settings, cloud.normals, cloud.curvature);
}

}  // namespace duet
