// VoxelFilter/{duet,duet_1t,pcl}/{dual,accum}: 0.05 m voxel grid, centroid + mean colour per
// voxel (pcl::VoxelGrid<PointXYZRGB> semantics). Items = input points.
#include "bench_util.hpp"
#include "pcl_util.hpp"

#include <duet/kernels/voxel_filter.hpp>

#ifdef DUET_HAVE_PCL
#include <pcl/filters/voxel_grid.h>
#endif

namespace duet::bench {

void register_voxel_filter() {
  for (const Input* in : {&data().dual, &data().accum}) {
    for (const DuetImpl impl : kDuetImpls) {
      benchmark::RegisterBenchmark(bench_name("VoxelFilter", impl.name, in->name).c_str(),
                                   [in, impl](benchmark::State& state) {
                                     VoxelFilterSettings s;
                                     s.leaf_size_m = kLeafSize;
                                     VoxelFilterWorkspace ws;
                                     PointCloud out;
                                     run_guarded(state, [&] {
                                       for (auto _ : state) {
                                         arena(impl.threads).execute([&] {
                                           voxel_filter(in->cloud.points_view(), in->cloud.colors_view(), s, ws, out);
                                         });
                                         benchmark::DoNotOptimize(out.points.data());
                                         benchmark::ClobberMemory();
                                       }
                                     });
                                     report(state, in->cloud.size(), double(out.size()));
                                   });
    }
#ifdef DUET_HAVE_PCL
    benchmark::RegisterBenchmark(bench_name("VoxelFilter", "pcl", in->name).c_str(), [in](benchmark::State& state) {
      const auto cloud = to_pcl_xyzrgb(in->cloud);
      pcl::VoxelGrid<pcl::PointXYZRGB> vg;
      vg.setInputCloud(cloud);
      vg.setLeafSize(kLeafSize, kLeafSize, kLeafSize);
      pcl::PointCloud<pcl::PointXYZRGB> out;
      for (auto _ : state) {
        vg.filter(out);
        benchmark::DoNotOptimize(out.data());
        benchmark::ClobberMemory();
      }
      report(state, cloud->size(), double(out.size()));
    });
#endif
  }
}

}  // namespace duet::bench
