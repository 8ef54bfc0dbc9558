// BackProjection/{duet,duet_1t,naive}/{dual,accum}: depth (+ colour) images -> coloured cloud.
// Items = pixels read.
// TransformPoints/{duet,duet_1t,eigen}/{dual,accum}: the frames' camera points (back_project_camera)
// moved by a pose, as the mapper moves them into the map each cycle. Items = points.
#include "bench_util.hpp"

namespace duet::bench {

void register_back_projection() {
  for (const Input* in : {&data().dual, &data().accum}) {
    std::size_t pixels = 0;
    for (const auto& f : in->frames) pixels += std::size_t(f.depth.width) * std::size_t(f.depth.height);
    for (const DuetImpl impl : kDuetImpls) {
      benchmark::RegisterBenchmark(bench_name("BackProjection", impl.name, in->name).c_str(),
                                   [in, impl, pixels](benchmark::State& state) {
                                     PointCloud out;
                                     std::vector<std::size_t> offsets;
                                     run_guarded(state, [&] {
                                       for (auto _ : state) {
                                         arena(impl.threads).execute(
                                             [&] { back_project(in->frames, in->bp_settings, out, &offsets); });
                                         benchmark::DoNotOptimize(out.points.data());
                                         benchmark::ClobberMemory();
                                       }
                                     });
                                     report(state, pixels, double(out.size()));
                                   });
    }
    auto cam = std::make_shared<CameraPoints>();
    back_project_camera(in->frames, in->bp_settings, *cam);
    const Eigen::Isometry3f T = in->frames.front().T_robot_camera;
    for (const DuetImpl impl : kDuetImpls) {
      benchmark::RegisterBenchmark(bench_name("TransformPoints", impl.name, in->name).c_str(), [cam, impl, T](benchmark::State& state) {
        std::vector<Eigen::Vector3f> out(cam->cloud.size());
        for (auto _ : state) {
          arena(impl.threads).execute([&] { transform_points(cam->cloud.points.data(), cam->cloud.size(), T, out.data()); });
          benchmark::DoNotOptimize(out.data());
          benchmark::ClobberMemory();
        }
        report(state, cam->cloud.size(), double(out.size()));
      });
    }
    // The plain Eigen expression, one thread: the reference.
    benchmark::RegisterBenchmark(bench_name("TransformPoints", "eigen", in->name).c_str(), [cam, T](benchmark::State& state) {
      std::vector<Eigen::Vector3f> out(cam->cloud.size());
      for (auto _ : state) {
        for (std::size_t i = 0; i < out.size(); ++i) out[i] = T * cam->cloud.points[i];
        benchmark::DoNotOptimize(out.data());
        benchmark::ClobberMemory();
      }
      report(state, cam->cloud.size(), double(out.size()));
    });
    benchmark::RegisterBenchmark(bench_name("BackProjection", "naive", in->name).c_str(),
                                 [in, pixels](benchmark::State& state) {
                                   PointCloud out;
                                   for (auto _ : state) {
                                     naive_back_project(in->frames, in->bp_settings, out);
                                     benchmark::DoNotOptimize(out.points.data());
                                     benchmark::ClobberMemory();
                                   }
                                   report(state, pixels, double(out.size()));
                                 });
  }
}

}  // namespace duet::bench
