// duet_bench: one Google Benchmark binary for every kernel and its peers (DESIGN.md §8).
// Names: Kernel/impl/size. impl: duet = a tbb::task_arena of 2 threads, duet_1t = an arena of
// 1 thread, pcl = the PCL peer, naive = a plain serial baseline. Inputs are built once, before
// any benchmark runs (bench/data.cpp), and every contender reads the same ones.
#include "common.hpp"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  try {
    duet::bench::init_data();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "duet_bench: cannot build the inputs: %s\n", e.what());
    return 1;
  }
  duet::bench::register_memory();
  duet::bench::register_back_projection();
  duet::bench::register_voxel_filter();
  duet::bench::register_normals();
  duet::bench::register_clustering();
  duet::bench::register_grid_update();
  duet::bench::register_observation();
  duet::bench::register_partial_sim();
  duet::bench::register_frontier();
  duet::bench::register_path();
  duet::bench::register_dwa();
  duet::bench::register_render();
  duet::bench::register_scan_match();
  duet::bench::register_pose_graph();
  duet::bench::register_decision_loop();
  duet::bench::register_odometry();
#ifdef DUET_HAVE_PCL
  benchmark::AddCustomContext("duet_pcl", "PCL peers enabled");
#else
  benchmark::AddCustomContext("duet_pcl", "PCL not found at build time: no pcl contenders");
#endif
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
