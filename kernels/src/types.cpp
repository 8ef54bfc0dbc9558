#include <duet/kernels/error.hpp>
#include <duet/kernels/types.hpp>

#include <string>

namespace duet {

void PointCloud::check_consistent() const {
  const auto n = points.size();
  auto check = [n](std::size_t m, const char* what) {
    if (m != 0 && m != n)
      fail(ErrorCode::kInvalidArgument, std::string("PointCloud: ") + what + " has " + std::to_string(m) +
                                            " entries, points has " + std::to_string(n));
  };
  check(colors.size(), "colors");
  check(normals.size(), "normals");
  check(curvature.size(), "curvature");
}

void PointCloud::append(const PointCloud& other) {
  other.check_consistent();
  check_consistent();
  if (other.empty()) return;
  if (empty()) {
    const auto keep_cap = points.capacity();
    *this = other;
    if (keep_cap > points.capacity()) points.reserve(keep_cap);
    return;
  }
  auto need_same = [](bool a, bool b, const char* what) {
    if (a != b)
      fail(ErrorCode::kInvalidArgument, std::string("PointCloud::append: one cloud has ") + what + ", the other not");
  };
  need_same(has_colors(), other.has_colors(), "colors");
  need_same(has_normals(), other.has_normals(), "normals");
  need_same(!curvature.empty(), !other.curvature.empty(), "curvature");
  points.insert(points.end(), other.points.begin(), other.points.end());
  colors.insert(colors.end(), other.colors.begin(), other.colors.end());
  normals.insert(normals.end(), other.normals.begin(), other.normals.end());
  curvature.insert(curvature.end(), other.curvature.begin(), other.curvature.end());
}

void PointCloud::transform(const Eigen::Isometry3f& T) {
  const Eigen::Matrix3f R = T.linear();
  const Eigen::Vector3f t = T.translation();
  for (auto& p : points) p = R * p + t;
  for (auto& n : normals) n = R * n;
}

}  // namespace duet
