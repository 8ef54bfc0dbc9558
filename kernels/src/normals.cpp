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
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i = 0; i < count; ++i) mean += get(i).template cast<double>();
  mean /= count;
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d d = get(i).template cast<double>() - mean;
    C.noalias() += d * d.transpose();
  }
  C /= count;
  const double trace = C.trace();
  if (!(trace > 0.0) || !std::isfinite(trace)) {
    normal.setConstant(kNaN);
    curvature = kNaN;
    return false;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.computeDirect(C);
  const Eigen::Vector3d ev = es.eigenvalues();  // ascending
  // Collinear points: no plane, no normal (as PCL). computeDirect is accurate to ~sqrt(eps) of
  // the trace for a double eigenvalue, so "zero" means below 1e-7 of the trace.
  if (ev[1] <= 1e-7 * trace) {
    normal.setConstant(kNaN);
    curvature = kNaN;
    return false;
  }
  normal = es.eigenvectors().col(0).cast<float>().normalized();
  curvature = static_cast<float>(std::max(0.0, ev[0]) / (std::max(0.0, ev[0]) + ev[1] + ev[2]));
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
  // Queries in tree order: consecutive queries touch the same leaves (cache friendly); every
  // result is written to its own input index, so the output is independent of the thread count.
  detail::for_blocks(tp.size(), 1024, [&](std::size_t, std::size_t begin, std::size_t end) {
    std::uint32_t pos[256];
    float d2[256];
    int prev = 0;  // neighbours of the previous query (tree positions in pos)
    for (std::size_t j = begin; j < end; ++j) {
      const Eigen::Vector3f& q = tp[j];
      // The previous query's k neighbours are k points: the farthest of them from q bounds q's
      // k-th distance, so the bounded search returns exactly the unbounded result. The margin
      // covers a different rounding of the same distance in the search (e.g. FMA contraction).
      float bound = std::numeric_limits<float>::infinity();
      if (prev == k) {
        float far = 0.0f;
        for (int i = 0; i < k; ++i) far = std::max(far, (tp[pos[i]] - q).squaredNorm());
        bound = far * 1.0001f + std::numeric_limits<float>::min();
      }
      const int c = tree.knn_tree_near(q, k, bound, static_cast<std::uint32_t>(j), pos, d2);
      prev = c;
      Eigen::Vector3f nrm;
      float curv;
      if (normal_of(c, [&](int i) -> const Eigen::Vector3f& { return tp[pos[i]]; }, nrm, curv)) {
        if ((vp - q).dot(nrm) < 0.0f) nrm = -nrm;  // face the viewpoint (as PCL)
      }
      const std::uint32_t i = ids[j];
      normals[i] = nrm;
      if (!curvature.empty()) curvature[i] = curv;
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
