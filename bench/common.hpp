#pragma once
/// @file common.hpp
/// Shared inputs of duet_bench (DESIGN.md §8): every contender of a kernel reads the same
/// input, built once before any benchmark runs (never inside a timed loop).
///
/// Inputs (built by init_data() from ../shared/data, or a synthetic room when it is absent):
///  - dual : two real Kinect frames (slambook2_ch5 frames 1 and 3) back-projected as the two
///           sensors of the paper's robot, Eq. (6): sensor 1 at (-0.118, 0, 0.271) facing
///           forward, sensor 2 at (-0.118, 0, 0.481) yawed -90 deg (facing right); robot frame.
///  - accum: an accumulated world cloud: the 5 slambook2_ch5 frames with their poses plus two
///           3dmatch_seq01 frames (placed as a second room beside the first), each data set
///           levelled so that its floor is z = 0 (floor plane found by RANSAC).
#include <duet/kernels/back_projection.hpp>
#include <duet/kernels/grid.hpp>
#include <duet/kernels/segmentation.hpp>
#include <duet/kernels/types.hpp>

#include <benchmark/benchmark.h>

#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <tbb/task_arena.h>

namespace duet::bench {

/// One scan for the grid update: points [begin, end) of Input::cloud seen from sensor_xy.
struct Scan {
  std::size_t begin = 0, end = 0;
  Eigen::Vector2f sensor_xy = Eigen::Vector2f::Zero();
};

struct Input {
  std::string name;                      ///< "dual" or "accum"
  std::string frames_desc;               ///< which frames, for the benchmark context
  std::vector<SensorFrame> frames;       ///< views into Data::images_
  BackProjectionSettings bp_settings;    ///< depth range used for every contender
  PointCloud cloud;                      ///< back-projected cloud (points + colours)
  std::vector<std::size_t> offsets;      ///< frame i: [offsets[i], offsets[i+1])
  std::vector<Scan> scans;               ///< one per frame
  std::vector<PointLabel> labels;        ///< segmentation of `cloud` (for GridUpdate)
  PointCloud voxel;                      ///< `cloud` voxel-filtered at 0.05 m (duet kernel)
  OccupancyGrid grid_template{0.05f};    ///< all-unknown grid covering every scan
};

struct Data {
  bool real = false;        ///< false: synthetic scene (data folder absent)
  std::string source;       ///< short label shown in every benchmark
  Input dual, accum;
  std::vector<std::shared_ptr<void>> images;  ///< owns the image memory the frames view
};

/// Builds the inputs (prints a summary to stderr). Call once before running benchmarks.
void init_data();
[[nodiscard]] const Data& data();

/// The two arenas: threads = 2 ("duet") or 1 ("duet_1t"). Never created inside a timed loop.
[[nodiscard]] tbb::task_arena& arena(int threads);

/// Settings every contender of a kernel shares.
inline constexpr float kLeafSize = 0.05f;           ///< voxel edge [m] (paper §2.2)
inline constexpr int kNormalK = 10;                 ///< neighbours (paper §2.2)
inline constexpr float kClusterTolerance = 0.10f;   ///< [m]
inline constexpr unsigned kClusterMinSize = 20;     ///< [points]

/// A plain serial back-projection (the "naive" contender, also used to build inputs).
void naive_back_project(std::span<const SensorFrame> frames, const BackProjectionSettings& settings,
                        PointCloud& out);

/// Registration hooks, one per benchmark file (called from main after init_data()).
void register_back_projection();
void register_voxel_filter();
void register_normals();
void register_clustering();
void register_grid_update();
void register_memory();
// Exploration kernels (issue 3): one file each, bench_<area>.cpp.
void register_observation();
void register_partial_sim();
void register_frontier();
void register_path();
void register_dwa();
void register_render();  // issue 4: simulated RGB-D rendering (bench_render.cpp)
void register_scan_match();
void register_pose_graph();     // issue 4: loop closure's pose graph and grid rebuild (bench_pose_graph.cpp)
void register_decision_loop();  // issue 18: the decision as the runtime takes it, on states of real runs (bench_decision_loop.cpp)
void register_odometry();       // issue 21: visual odometry against OpenCV and Open3D on real frames (bench_odometry.cpp)

/// Runs `body` in the arena of `threads` threads and reports a duet::Error (or any
/// std::exception) as a skipped benchmark instead of aborting the whole run.
template <class F>
void run_guarded(benchmark::State& state, F&& body) {
  try {
    body();
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
  }
}

}  // namespace duet::bench
