// Normals/{duet,duet_1t,pcl}/{dual,accum}: k = 10 nearest-neighbour normals + curvature on the
// raw (not voxel-filtered) clouds. The kd-tree build is inside the timed loop on both sides:
// duet builds duet::KdTree; PCL rebuilds its search::KdTree via setInputCloud (NormalEstimation
// would otherwise reuse the tree built in the first iteration). PCL runs NormalEstimationOMP
// with 2 OpenMP threads. Items = input points.
#include "bench_util.hpp"
#include "pcl_util.hpp"

#include <duet/kernels/kdtree.hpp>
#include <duet/kernels/normals.hpp>

#include <cmath>

#ifdef DUET_HAVE_PCL
#include <pcl/features/normal_3d_omp.h>
#include <pcl/search/kdtree.h>
#endif

namespace duet::bench {

void register_normals() {
  for (const Input* in : {&data().dual, &data().accum}) {
    for (const DuetImpl impl : kDuetImpls) {
      benchmark::RegisterBenchmark(bench_name("Normals", impl.name, in->name).c_str(), [in, impl](benchmark::State& state) {
        NormalSettings s;
        s.k = kNormalK;
        KdTree tree;
        std::vector<Eigen::Vector3f> normals(in->cloud.size());
        std::vector<float> curvature(in->cloud.size());
        const PointsView pts = in->cloud.points_view();
        run_guarded(state, [&] {
          for (auto _ : state) {
            arena(impl.threads).execute([&] {
              tree.build(pts);
              estimate_normals(pts, tree, s, normals, curvature);
            });
            benchmark::DoNotOptimize(normals.data());
            benchmark::ClobberMemory();
          }
        });
        std::size_t finite = 0;
        for (const auto& n : normals) finite += std::isfinite(n.x()) ? 1u : 0u;
        report(state, in->cloud.size(), double(finite));
      });
    }
#ifdef DUET_HAVE_PCL
    benchmark::RegisterBenchmark(bench_name("Normals", "pcl", in->name).c_str(), [in](benchmark::State& state) {
      const auto cloud = to_pcl_xyz(in->cloud);
      pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
      pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> ne(2);
      ne.setInputCloud(cloud);
      ne.setSearchMethod(tree);
      ne.setKSearch(kNormalK);
      pcl::PointCloud<pcl::Normal> out;
      for (auto _ : state) {
        tree->setInputCloud(cloud);  // rebuild the kd-tree every iteration, as duet does
        ne.compute(out);
        benchmark::DoNotOptimize(out.data());
        benchmark::ClobberMemory();
      }
      std::size_t finite = 0;
      for (const auto& n : out) finite += std::isfinite(n.normal_x) ? 1u : 0u;
      report(state, cloud->size(), double(finite));
    });
#endif
  }
}

}  // namespace duet::bench
