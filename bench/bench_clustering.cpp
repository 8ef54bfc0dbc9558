// Clustering/{duet,duet_1t,pcl}/{dual_voxel,accum_voxel,dual}: Euclidean clusters, tolerance
// 0.1 m, min 20 points, no max. On the 0.05 m voxel-filtered dual frame and accumulated cloud
// (what the mapper clusters) and on the raw dual frame (a dense worst case; PCL runs it only 3
// times, see below). PCL builds its
// search::KdTree inside the timed loop; duet builds its hashed grid inside the kernel.
// Items = input points; "out" = number of clusters.
#include "bench_util.hpp"
#include "pcl_util.hpp"

#include <duet/kernels/clustering.hpp>

#include <limits>

#ifdef DUET_HAVE_PCL
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
#endif

namespace duet::bench {

void register_clustering() {
  struct Case {
    const PointCloud* cloud;
    std::string size;
  };
  const std::vector<Case> cases{{&data().dual.voxel, "dual_voxel"},
                                {&data().accum.voxel, "accum_voxel"},
                                {&data().dual.cloud, "dual"}};
  for (const Case& c : cases) {
    const PointCloud* cloud = c.cloud;
    for (const DuetImpl impl : kDuetImpls) {
      benchmark::RegisterBenchmark(bench_name("Clustering", impl.name, c.size).c_str(), [cloud, impl](benchmark::State& state) {
        ClusteringSettings s;
        s.tolerance_m = kClusterTolerance;
        s.min_size = kClusterMinSize;
        s.max_size = std::numeric_limits<std::uint32_t>::max();
        ClusteringWorkspace ws;
        std::vector<std::vector<std::uint32_t>> clusters;
        run_guarded(state, [&] {
          for (auto _ : state) {
            arena(impl.threads).execute([&] { clusters = euclidean_clusters(cloud->points_view(), {}, s, ws); });
            benchmark::DoNotOptimize(clusters.data());
            benchmark::ClobberMemory();
          }
        });
        report(state, cloud->size(), double(clusters.size()));
      });
    }
#ifdef DUET_HAVE_PCL
    auto* pcl_bench = benchmark::RegisterBenchmark(bench_name("Clustering", "pcl", c.size).c_str(), [cloud](benchmark::State& state) {
      const auto pc = to_pcl_xyz(*cloud);
      pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
      pcl::EuclideanClusterExtraction<pcl::PointXYZ> ec;
      ec.setClusterTolerance(kClusterTolerance);
      ec.setMinClusterSize(kClusterMinSize);
      ec.setMaxClusterSize(std::numeric_limits<pcl::uindex_t>::max());
      ec.setSearchMethod(tree);
      ec.setInputCloud(pc);
      std::vector<pcl::PointIndices> clusters;
      for (auto _ : state) {
        tree->setInputCloud(pc);  // kd-tree built inside the timed loop
        clusters.clear();
        ec.extract(clusters);
        benchmark::DoNotOptimize(clusters.data());
        benchmark::ClobberMemory();
      }
      report(state, pc->size(), double(clusters.size()));
    });
    // PCL on the raw dual frame takes ~20 s per call (every point has thousands of neighbours
    // within 0.1 m): 3 repetitions, whatever --benchmark_repetitions says, keep the run short.
    if (c.size == "dual") pcl_bench->Repetitions(3);
#endif
  }
}

}  // namespace duet::bench
