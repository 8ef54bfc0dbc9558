// Render/{duet,duet_1t,duet_robust,duet_1t_robust}/dual_640x480: one frame of each RGB-D sensor of the paper's robot
// (builtin_profile("dual_kinect_kobuki"): 640x480, 57 x 43 deg, Eq. (6) extrinsics) ray traced
// with Embree by sim::RgbdRenderer - depth with the default Kinect noise model plus textured,
// shaded colour - inside builtin_world("lab") (a small walled room built here if the lab is not
// available), from a fixed pose: the free point of the lab farthest from every solid (the middle
// of its largest open area), heading 30 deg. Issue 4 target: both frames in <= 15 ms on 2 cores.
// Items = pixels rendered per iteration (2 x 640 x 480); "out" = pixels with a depth return.
// The renderer (mesh + BVH) is built once outside the timed loop; frame seeds vary per iteration.
// The _robust variants: RenderSettings::robust_intersection (Embree's robust mode, no grown triangles).
#include "bench_util.hpp"

#include <duet/runtime/config/profile.hpp>
#include <duet/sim/renderer.hpp>
#include <duet/sim/world.hpp>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace duet::bench {
namespace {

sim::World fallback_world() {
  sim::World w;
  w.name = "bench room";
  w.source = "bench_render.cpp";
  w.floor.max = Eigen::Vector2f(8.0f, 6.0f);
  w.start = Pose2{4.0f, 3.0f, 0.0f};
  auto add = [&](std::vector<Eigen::Vector2f> poly, float h, sim::Texture t) {
    sim::Solid s;
    s.name = "solid " + std::to_string(w.solids.size());
    s.polygon = std::move(poly);
    s.z_max_m = h;
    s.surface.texture = t;
    w.solids.push_back(std::move(s));
  };
  add({{0, 0}, {8, 0}, {8, 0.1f}, {0, 0.1f}}, 2.5f, sim::Texture::kBricks);
  add({{0, 5.9f}, {8, 5.9f}, {8, 6}, {0, 6}}, 2.5f, sim::Texture::kNoise);
  add({{0, 0.1f}, {0.1f, 0.1f}, {0.1f, 5.9f}, {0, 5.9f}}, 2.5f, sim::Texture::kPosters);
  add({{7.9f, 0.1f}, {8, 0.1f}, {8, 5.9f}, {7.9f, 5.9f}}, 2.5f, sim::Texture::kNoise);
  add({{5.5f, 3.5f}, {6.5f, 3.5f}, {6.5f, 4.3f}, {5.5f, 4.3f}}, 0.8f, sim::Texture::kChecker);
  sim::validate(w, "bench room");
  return w;
}

struct RenderInput {
  sim::World world;
  Profile profile;
  Pose2 pose;
  std::unique_ptr<sim::RgbdRenderer> renderer;
  std::vector<Eigen::Isometry3f> T_world_optical;
  std::string label;
};

RenderInput make_render_input(bool robust) {
  RenderInput r;
  try {
    r.world = sim::builtin_world("lab");
    r.label = "builtin lab";
  } catch (const std::exception&) {
    r.world = fallback_world();
    r.label = "fallback room";
  }
  r.profile = builtin_profile("dual_kinect_kobuki");
  // The free point with the largest clearance (0.05 m search grid): the middle of a room.
  float best = -1.0f;
  const sim::Region& f = r.world.floor;
  for (float y = f.min.y() + 0.5f; y < f.max.y() - 0.5f; y += 0.05f)
    for (float x = f.min.x() + 0.5f; x < f.max.x() - 0.5f; x += 0.05f) {
      const float c = sim::clearance(r.world, Eigen::Vector2f(x, y));
      if (c > best) {
        best = c;
        r.pose = Pose2{x, y, 0.5235988f};
      }
    }
  Eigen::Isometry3f T_world_robot = Eigen::Isometry3f::Identity();
  T_world_robot.translate(Eigen::Vector3f(r.pose.x, r.pose.y, 0.0f));
  T_world_robot.rotate(Eigen::AngleAxisf(r.pose.theta, Eigen::Vector3f::UnitZ()));
  for (const SensorProfile& s : r.profile.sensors) r.T_world_optical.push_back(T_world_robot * s.T_robot_optical());
  sim::RenderSettings settings;
  settings.robust_intersection = robust;
  r.renderer = std::make_unique<sim::RgbdRenderer>(r.world, settings);
  r.label += " at (" + std::to_string(r.pose.x).substr(0, 4) + ", " + std::to_string(r.pose.y).substr(0, 4) + ")";
  if (robust) r.label += ", robust intersection";
  return r;
}

const RenderInput& render_input(bool robust) {
  if (robust) {
    static const RenderInput exact = make_render_input(true);
    return exact;
  }
  static const RenderInput fast = make_render_input(false);
  return fast;
}

}  // namespace

void register_render() {
  for (const bool robust : {false, true}) {
    for (const DuetImpl impl : kDuetImpls) {
      const std::string name = std::string(impl.name) + (robust ? "_robust" : "");
      benchmark::RegisterBenchmark(bench_name("Render", name.c_str(), "dual_640x480").c_str(), [impl, robust](benchmark::State& state) {
        run_guarded(state, [&] {
          const RenderInput& in = render_input(robust);
          const auto& sensors = in.profile.sensors;
          std::vector<sim::RgbdImage> images(sensors.size());
          std::size_t pixels = 0;
          for (const SensorProfile& s : sensors)
            pixels += static_cast<std::size_t>(s.intrinsics.width) * static_cast<std::size_t>(s.intrinsics.height);
          std::uint64_t frame = 0;
          for (auto _ : state) {
            arena(impl.threads).execute([&] {
              for (std::size_t i = 0; i < sensors.size(); ++i)
                in.renderer->render(sensors[i], in.T_world_optical[i], 2 * frame + i, images[i]);
            });
            ++frame;
            benchmark::DoNotOptimize(images.data());
            benchmark::ClobberMemory();
          }
          std::size_t returns = 0;
          for (const auto& img : images)
            for (const std::uint16_t d : img.depth) returns += d != 0 ? 1 : 0;
          report(state, pixels, static_cast<double>(returns));
          state.SetLabel(in.label);
        });
      })->Unit(benchmark::kMillisecond)->UseRealTime();  // wall time: the 2-thread variant's target is wall time
    }
  }
}

}  // namespace duet::bench
