#include <duet/kernels/voxel_filter.hpp>
#include <duet/version.hpp>

#include <cstdio>

int main() {
  std::vector<Eigen::Vector3f> pts{{0.01f, 0.01f, 0.01f}, {0.02f, 0.02f, 0.02f}, {1.0f, 1.0f, 1.0f}};
  duet::PointCloud out;
  duet::voxel_filter(pts, {}, {}, out);
  std::printf("duet %s: %zu voxels\n", DUET_VERSION_STRING, out.size());
  return out.size() == 2 ? 0 : 1;
}
