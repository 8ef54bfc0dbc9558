/// Fuzz target: the C API driven by random call sequences. The input is a program: each step
/// picks a function and draws its arguments - handles (live ones, NULL, or one released
/// earlier but still referenced elsewhere), sizes, strides (valid or not), counts, settings
/// and values (NaN, inf, huge, denormal, raw bits). Buffers are always as large as the
/// arguments say (the C contract: duet cannot check the length of caller memory); everything
/// else is fair game. After each call the device's error is read and must be a known code
/// with a message. A hang shows as a libFuzzer timeout; the work-heavy counts (particles,
/// iterations, rays, image sizes) are drawn small so one input stays far below it - their
/// budgets are unit-tested at the limits.
#include "fuzz_util.hpp"

#include <duet.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <vector>

namespace {

using duet::fuzz::Bytes;

struct State {
  std::vector<duet_device> devices;
  std::vector<duet_cloud> clouds;
  std::vector<duet_grid> grids;
  std::vector<duet_planner> planners;
  std::vector<duet_runtime> runtimes;
  std::vector<duet_sim> sims;
  int spins = 0;  ///< control periods run (each may map and decide: a few per input)
};

/// A robot profile with one 8x6 camera (frames small enough to fuzz; the runtime and the
/// simulator take its sizes).
constexpr const char* kTinyProfile =
    "name: tiny\nchassis: {type: differential, radius_m: 0.2, wheel_base_m: 0.3, wheel_diameter_m: 0.07,"
    " max_linear_speed_mps: 0.5, max_angular_speed_dps: 90, odometry_rate_hz: 50}\n"
    "sensors:\n  - name: cam\n    intrinsics: {width: 8, height: 6, fov_h_deg: 57, fov_v_deg: 43}\n"
    "    extrinsics: {xyz_m: [0.0, 0.0, 0.3], zyx_euler_deg: [0.0, 0.0, 0.0]}\n";

template <class H>
H pick(Bytes& in, const std::vector<H>& pool) {
  const std::size_t i = static_cast<std::size_t>(in.range(0, static_cast<std::int64_t>(pool.size())));
  return i < pool.size() ? pool[i] : nullptr;  // one slot past the pool = NULL
}

void check_error(duet_device d) {
  const duet_error e = duet_device_get_error(d);
  if (static_cast<int>(e) < 0 || static_cast<int>(e) > DUET_ERROR_UNKNOWN) std::abort();
  const char* msg = duet_device_get_error_message(d);
  if (!msg) std::abort();
  if (e != DUET_ERROR_NONE && msg[0] == '\0') std::abort();  // every error says what was wrong
  (void)duet_error_string(e);
}

std::vector<float> floats(Bytes& in, std::size_t n, float scale) {
  std::vector<float> v(n);
  for (auto& x : v) x = in.value(scale);
  return v;
}

// A stride for elements of `elem` bytes: packed, 0, a bad one, or padded.
std::size_t stride(Bytes& in, std::size_t elem) {
  switch (in.get<std::uint8_t>() % 5) {
    case 0: return 0;
    case 1: return elem - 1;  // too small: must be refused
    case 2: return elem + 4;
    default: return elem;
  }
}
std::size_t stored(std::size_t s, std::size_t elem) { return s < elem ? elem : s; }  // bytes per element actually provided

// Points: count elements of 3 floats at a drawn stride, in a buffer as large as that says.
struct Points {
  std::size_t count, stride;
  std::vector<float> buf;
};
Points points(Bytes& in, float scale) {
  Points p;
  p.count = static_cast<std::size_t>(in.range(0, 48));
  p.stride = stride(in, 12);
  const std::size_t per = stored(p.stride, 12) / 4;
  p.buf = floats(in, p.count * per + 3, scale);
  return p;
}

void random_settings_bytes(Bytes& in, void* s, std::size_t n) {  // perturb a few fields' bytes
  auto* b = static_cast<std::uint8_t*>(s);
  const int edits = static_cast<int>(in.range(0, 3));
  for (int i = 0; i < edits; ++i) {
    const std::size_t at = static_cast<std::size_t>(in.range(0, static_cast<std::int64_t>(n / 4) - 1)) * 4;
    const float v = in.value(10.0f);
    if (in.get<std::uint8_t>() & 1) {
      std::memcpy(b + at, &v, 4);
    } else {
      const std::int32_t iv = static_cast<std::int32_t>(in.range(-5, 200));
      std::memcpy(b + at, &iv, 4);
    }
  }
}

duet_pose2 pose(Bytes& in, float scale) { return {in.value(scale), in.value(scale), in.value(4.0f)}; }

void step(State& st, Bytes& in) {
  duet_device dev = pick(in, st.devices);
  switch (in.get<std::uint8_t>() % 32) {
    case 0: {
      static constexpr std::array<const char*, 8> kConfigs = {
          nullptr, "", "threads=1", "threads=0", "threads=-3", "bogus=1", "threads=1,threads=2", "threads=1, verbose=0"};
      if (st.devices.size() < 3) {
        duet_device d = duet_device_new(kConfigs[static_cast<std::size_t>(in.range(0, 7))]);
        check_error(nullptr);
        if (d) st.devices.push_back(d);
      }
      return;
    }
    case 1:
      if (!st.devices.empty() && in.get<std::uint8_t>() % 4 == 0) {  // release; clouds etc. keep it alive
        duet_device_release(st.devices.back());
        st.devices.pop_back();
      }
      return;
    case 2:
      if (st.clouds.size() < 4) {
        duet_cloud c = duet_cloud_new(dev);
        check_error(dev);
        if (c) st.clouds.push_back(c);
      }
      return;
    case 3: {
      duet_cloud c = pick(in, st.clouds);
      Points p = points(in, 5.0f);
      const bool rgb = in.get<std::uint8_t>() & 1;
      std::vector<std::uint8_t> colours(p.count * 4 + 1, 7);
      duet_cloud_set_points(c, p.count ? p.buf.data() : nullptr, p.stride, rgb ? colours.data() : nullptr, rgb ? 4 : 0, p.count);
      break;
    }
    case 4: {
      duet_cloud c = pick(in, st.clouds);
      const std::size_t n = duet_cloud_get_size(c);
      const std::size_t count = in.get<std::uint8_t>() & 1 ? n : static_cast<std::size_t>(in.range(0, 50));
      std::vector<float> out(count * 4 + 4);
      std::vector<std::uint8_t> rgb(count * 4 + 4);
      duet_cloud_copy_points(c, out.data(), 16, count);
      duet_cloud_copy_colors(c, rgb.data(), 4, count);
      duet_cloud_copy_normals(c, out.data(), 16, count);
      duet_cloud_copy_curvature(c, out.data(), 4, count);
      const float* ptr = nullptr;
      std::size_t s = 0;
      duet_cloud_get_points(c, &ptr, &s);
      if (ptr && n > 0 && !(s >= 12)) std::abort();
      (void)duet_cloud_has_colors(c);
      (void)duet_cloud_has_normals(c);
      break;
    }
    case 5: {
      duet_cloud c = pick(in, st.clouds);
      duet_normal_settings ns;
      duet_normal_settings_init(&ns);
      random_settings_bytes(in, &ns, sizeof ns);
      duet_cloud_estimate_normals(c, in.get<std::uint8_t>() & 1 ? &ns : nullptr);
      break;
    }
    case 6: {
      duet_cloud c = pick(in, st.clouds);
      const int frames = static_cast<int>(in.range(0, 2));
      std::vector<duet_sensor_frame> f(static_cast<std::size_t>(frames));
      std::vector<std::vector<std::uint8_t>> depth(f.size()), colour(f.size());
      for (std::size_t i = 0; i < f.size(); ++i) {
        duet_sensor_frame_init(&f[i]);
        f[i].width = static_cast<int>(in.range(-1, 12));
        f[i].height = static_cast<int>(in.range(-1, 10));
        f[i].depth_format = in.get<std::uint8_t>() & 1 ? DUET_DEPTH_F32 : DUET_DEPTH_U16;
        const std::size_t px = f[i].depth_format == DUET_DEPTH_F32 ? 4 : 2;
        const std::size_t w = static_cast<std::size_t>(std::max(f[i].width, 0)), h = static_cast<std::size_t>(std::max(f[i].height, 0));
        switch (in.get<std::uint8_t>() % 4) {  // packed, padded, too small (refused), exact
          case 0: f[i].depth_row_stride = 0; break;
          case 1: f[i].depth_row_stride = w * px + 6; break;
          case 2: f[i].depth_row_stride = w * px > 1 ? w * px - 1 : 1; break;
          default: f[i].depth_row_stride = w * px;
        }
        const std::size_t row = std::max(f[i].depth_row_stride, w * px);
        depth[i].resize(row * h + 8);
        for (std::size_t b = 0; b < depth[i].size(); ++b) depth[i][b] = in.get<std::uint8_t>();
        f[i].depth = depth[i].data();
        if (in.get<std::uint8_t>() & 1) {
          f[i].color_channels = static_cast<int>(in.range(2, 5));
          colour[i].assign(w * h * 5 + 8, 100);
          f[i].color = colour[i].data();
        }
        f[i].fx = in.value(600.0f);
        f[i].fy = in.value(600.0f);
        f[i].cx = in.value(10.0f);
        f[i].cy = in.value(10.0f);
        f[i].depth_units_per_m = in.value(1000.0f);
        duet_camera_mount_matrix(in.value(), in.value(), in.value(), in.value(3.0f), in.value(3.0f), in.value(3.0f), f[i].T_robot_camera);
        if (in.get<std::uint8_t>() % 4 == 0) f[i].T_robot_camera[in.range(0, 15)] = in.value(2.0f);
      }
      duet_back_projection_settings bs;
      duet_back_projection_settings_init(&bs);
      random_settings_bytes(in, &bs, sizeof bs);
      std::vector<std::size_t> offsets(f.size() + 1);
      duet_back_project(c, f.empty() && (in.get<std::uint8_t>() & 1) ? nullptr : f.data(), f.size(), &bs, offsets.data());
      break;
    }
    case 7: {
      duet_cloud c = pick(in, st.clouds);
      Points p = points(in, 3.0f);
      duet_voxel_filter_settings vs;
      duet_voxel_filter_settings_init(&vs);
      random_settings_bytes(in, &vs, sizeof vs);
      duet_voxel_filter(c, p.buf.data(), p.stride, nullptr, 0, p.count, &vs);
      break;
    }
    case 8: {
      Points p = points(in, 3.0f);
      duet_normal_settings ns;
      duet_normal_settings_init(&ns);
      random_settings_bytes(in, &ns, sizeof ns);
      std::vector<float> nrm(p.count * 3 + 3), curv(p.count + 1);
      duet_estimate_normals(dev, p.buf.data(), p.stride, p.count, &ns, nrm.data(), 12, curv.data(), 4);
      break;
    }
    case 9: {
      Points p = points(in, 3.0f);
      duet_clustering_settings cs;
      duet_clustering_settings_init(&cs);
      random_settings_bytes(in, &cs, sizeof cs);
      std::vector<std::uint32_t> labels(p.count + 1);
      std::size_t clusters = 0;
      duet_euclidean_clusters(dev, p.buf.data(), p.stride, p.count, &cs, labels.data(), 4, &clusters);
      if (clusters > p.count) std::abort();
      break;
    }
    case 10: {
      Points p = points(in, 3.0f);
      std::vector<float> nrm = floats(in, p.count * 3 + 3, 1.0f);
      duet_segmentation_settings ss;
      duet_segmentation_settings_init(&ss);
      random_settings_bytes(in, &ss, sizeof ss);
      std::vector<std::uint8_t> labels(p.count + 1);
      duet_segment(dev, p.buf.data(), p.stride, nrm.data(), 12, p.count, &ss, labels.data(), 1);
      break;
    }
    case 11:
      if (st.grids.size() < 3) {
        duet_grid g = duet_grid_new(dev, in.get<std::uint8_t>() & 1 ? 0.05f * static_cast<float>(in.range(1, 20)) : in.value(1.0f));
        check_error(dev);
        if (g) st.grids.push_back(g);
      }
      return;
    case 12: {
      duet_grid g = pick(in, st.grids);
      Points p = points(in, 4.0f);
      std::vector<std::uint8_t> labels(p.count + 1);
      for (auto& l : labels) l = static_cast<std::uint8_t>(in.range(0, 3));
      duet_grid_update_settings us;
      duet_grid_update_settings_init(&us);
      random_settings_bytes(in, &us, sizeof us);
      duet_grid_update(g, in.value(4.0f), in.value(4.0f), p.buf.data(), p.stride, labels.data(), 1, p.count, &us);
      break;
    }
    case 13: {
      duet_grid g = pick(in, st.grids);
      const std::size_t n = static_cast<std::size_t>(duet_grid_get_width(g)) * static_cast<std::size_t>(duet_grid_get_height(g));
      const std::size_t count = in.get<std::uint8_t>() & 1 ? n : static_cast<std::size_t>(in.range(0, 64));
      std::vector<float> out(count + 1);
      std::vector<std::int8_t> ros(count + 1);
      duet_grid_copy_logodds(g, out.data(), count);
      duet_grid_copy_probabilities(g, out.data(), count);
      duet_grid_copy_ros(g, ros.data(), count, in.value(), in.value());
      float ox = 0, oy = 0;
      duet_grid_get_origin(g, &ox, &oy);
      (void)duet_grid_get_resolution(g);
      (void)duet_grid_get_known_cells(g);
      break;
    }
    case 14: {
      duet_grid g = pick(in, st.grids);
      const std::size_t count = static_cast<std::size_t>(in.range(0, 80));
      const std::size_t s = stride(in, 8);
      std::vector<float> xy = floats(in, count * (stored(s, 8) / 4) + 2, 3.0f);
      duet_scan_match_settings ms;
      duet_scan_match_settings_init(&ms);
      random_settings_bytes(in, &ms, sizeof ms);
      ms.linear_window_m = std::min(ms.linear_window_m, 0.5f);  // keep the lattice small (budget is validated)
      duet_scan_match_result r{};
      duet_grid_scan_match(g, xy.data(), s, count, pose(in, 3.0f), &ms, &r);
      break;
    }
    case 15:
      if (st.planners.size() < 2) {
        duet_planner p = duet_planner_new(dev);
        check_error(dev);
        if (p) st.planners.push_back(p);
      }
      return;
    case 16: {
      duet_planner p = pick(in, st.planners);
      std::vector<duet_sensor_sector> s(static_cast<std::size_t>(in.range(0, 3)));
      for (auto& x : s) {
        duet_sensor_sector_init(&x);
        x.rays = static_cast<int>(in.range(-1, 40));
        x.fov_rad = in.value(7.0f);
        x.max_range_m = in.get<std::uint8_t>() & 1 ? in.value(8.0f) : 4.0f;
        x.min_range_m = in.value(1.0f);
        x.yaw_rad = in.value(4.0f);
      }
      duet_planner_set_sensors(p, s.empty() && (in.get<std::uint8_t>() & 1) ? nullptr : s.data(), s.size());
      std::array<duet_sensor_sector, 4> back{};
      (void)duet_planner_get_sensors(p, back.data(), back.size());
      break;
    }
    case 17: {
      duet_planner p = pick(in, st.planners);
      const int w = static_cast<int>(in.range(-1, 48)), h = static_cast<int>(in.range(-1, 48));
      const std::size_t cells = static_cast<std::size_t>(std::max(w, 0)) * static_cast<std::size_t>(std::max(h, 0));
      std::vector<float> l(cells + 1);
      const int fill = static_cast<int>(in.range(0, 2));
      for (auto& x : l) x = fill == 0 ? in.value(4.0f) : (in.get<std::uint8_t>() % 5 == 0 ? 3.5f : (fill == 1 ? -2.0f : std::numeric_limits<float>::quiet_NaN()));
      duet_observation_settings os;
      duet_observation_settings_init(&os);
      os.backend = in.get<std::uint8_t>() & 1 ? DUET_OBSERVATION_EMBREE : DUET_OBSERVATION_DDA;
      duet_inflation_settings is;
      duet_inflation_settings_init(&is);
      random_settings_bytes(in, &is, sizeof is);
      const float res = in.get<std::uint8_t>() & 1 ? 0.1f : in.value(1.0f);
      duet_planner_set_grid(p, l.data(), 0, w, h, res, in.value(5.0f), in.value(5.0f), &os, &is);
      break;
    }
    case 18: {
      duet_planner p = pick(in, st.planners);
      duet_planner_set_grid_from(p, pick(in, st.grids), nullptr, nullptr);
      break;
    }
    case 19: {
      duet_planner p = pick(in, st.planners);
      const std::size_t poses = static_cast<std::size_t>(in.range(0, 3));
      std::vector<duet_pose2> ps(poses + 1);
      for (auto& x : ps) x = pose(in, 3.0f);
      const std::size_t rays = duet_planner_get_ray_count(p);
      const std::size_t count = in.get<std::uint8_t>() & 1 ? poses * rays : static_cast<std::size_t>(in.range(0, 20));
      std::vector<duet_ray_observation> out(count + 1);
      duet_planner_observe(p, ps.data(), poses, out.data(), count);
      (void)duet_planner_information(p, pose(in, 3.0f));
      break;
    }
    case 20: {
      duet_planner p = pick(in, st.planners);
      duet_partial_sim_settings s;
      duet_partial_sim_settings_init(&s);
      random_settings_bytes(in, &s, sizeof s);
      s.particles = std::min(s.particles, 40);
      s.iterations = std::min(s.iterations, 3);
      s.stages = std::min(s.stages, 4);
      duet_partial_sim_result r{};
      std::array<duet_pose2, 8> traj{};
      duet_planner_simulate(p, pose(in, 3.0f), &s, &r, traj.data(), in.range(0, 8));
      break;
    }
    case 21: {
      duet_planner p = pick(in, st.planners);
      duet_frontier_settings fs;
      duet_frontier_settings_init(&fs);
      random_settings_bytes(in, &fs, sizeof fs);
      duet_frontier_result r{};
      std::array<float, 64> path{};
      std::array<duet_frontier_cluster, 4> cl{};
      duet_planner_find_frontier(p, in.value(3.0f), in.value(3.0f), static_cast<double>(in.value(100.0f)), &fs, &r, path.data(),
                                 static_cast<std::size_t>(in.range(0, 32)), cl.data(), static_cast<std::size_t>(in.range(0, 4)));
      break;
    }
    case 22: {
      duet_planner p = pick(in, st.planners);
      const double now = static_cast<double>(in.value(100.0f));
      switch (in.get<std::uint8_t>() % 4) {
        case 0: duet_planner_blacklist_add(p, in.value(3.0f), in.value(3.0f), now, static_cast<double>(in.value(50.0f))); break;
        case 1: duet_planner_blacklist_expire(p, now); break;
        case 2: duet_planner_blacklist_clear(p); break;
        default: (void)duet_planner_blacklist_get_size(p);
      }
      break;
    }
    case 23: {
      duet_planner p = pick(in, st.planners);
      duet_exploration_settings es;
      duet_exploration_settings_init(&es);
      random_settings_bytes(in, &es, sizeof es);
      es.simulation.particles = std::min(es.simulation.particles, 40);
      es.simulation.iterations = std::min(es.simulation.iterations, 3);
      es.simulation.stages = std::min(es.simulation.stages, 4);
      duet_decision d{};
      duet_planner_decide(p, pose(in, 3.0f), static_cast<double>(in.value(100.0f)), &es, &d);
      break;
    }
    case 24: {
      duet_planner p = pick(in, st.planners);
      duet_path_settings ps;
      duet_path_settings_init(&ps);
      random_settings_bytes(in, &ps, sizeof ps);
      duet_path_result r{};
      std::array<float, 64> xy{};
      duet_planner_plan_path(p, in.value(3.0f), in.value(3.0f), in.value(3.0f), in.value(3.0f), &ps, &r, xy.data(),
                             static_cast<std::size_t>(in.range(0, 32)));
      break;
    }
    case 25: {
      duet_planner p = pick(in, st.planners);
      const std::size_t n = static_cast<std::size_t>(in.range(0, 6));
      const std::size_t s = stride(in, 8);
      std::vector<float> path = floats(in, n * (stored(s, 8) / 4) + 2, 3.0f);
      duet_dwa_settings ds;
      duet_dwa_settings_init(&ds);
      random_settings_bytes(in, &ds, sizeof ds);
      ds.v_samples = std::min(ds.v_samples, 20);
      ds.omega_samples = std::min(ds.omega_samples, 20);
      ds.steps = std::min(ds.steps, 30);
      duet_dwa_result r{};
      r.status = DUET_DWA_NO_PATH;  // stays so if the call refuses its arguments
      duet_planner_dwa_step(p, pose(in, 3.0f), {in.value(1.0f), in.value(1.0f)}, path.data(), s, n, &ds, &r);
      if (r.status == DUET_DWA_OK && ds.limits.max_v_mps > 0.0f &&
          (r.cmd.v > ds.limits.max_v_mps * 1.0001f || r.cmd.v < ds.limits.min_v_mps * 1.0001f))
        std::abort();  // never beyond the chassis limits (issue 19)
      if (in.get<std::uint8_t>() % 8 == 0) duet_planner_dwa_reset(p);
      break;
    }
    case 26: {  // retain + release pairs and releases of anything
      switch (in.get<std::uint8_t>() % 4) {
        case 0:
          if (!st.clouds.empty()) {
            duet_cloud_release(st.clouds.back());
            st.clouds.pop_back();
          }
          break;
        case 1:
          if (!st.grids.empty()) {
            duet_grid_release(st.grids.back());
            st.grids.pop_back();
          }
          break;
        case 2:
          if (!st.planners.empty()) {
            duet_planner_release(st.planners.back());
            st.planners.pop_back();
          }
          break;
        default: {
          duet_cloud c = pick(in, st.clouds);
          duet_cloud_retain(c);
          duet_cloud_release(c);
        }
      }
      return;
    }
    case 27: {
      (void)duet_path_status_string(static_cast<duet_path_status>(in.range(-2, 8)));
      (void)duet_frontier_status_string(static_cast<duet_frontier_status>(in.range(-2, 8)));
      (void)duet_exploration_status_string(static_cast<duet_exploration_status>(in.range(-2, 8)));
      (void)duet_dwa_status_string(static_cast<duet_dwa_status>(in.range(-2, 8)));
      (void)duet_error_string(static_cast<duet_error>(in.range(-2, 12)));
      return;
    }
    case 28: {
      duet_planner p = pick(in, st.planners);
      int w = -1, h = -1;
      duet_planner_get_grid_size(p, &w, &h);
      const std::size_t n = static_cast<std::size_t>(std::max(w, 0)) * static_cast<std::size_t>(std::max(h, 0));
      const std::size_t count = in.get<std::uint8_t>() & 1 ? n : static_cast<std::size_t>(in.range(0, 30));
      std::vector<float> c(count + 1);
      std::vector<std::uint8_t> m(count + 1);
      duet_planner_copy_clearance(p, c.data(), count);
      duet_planner_copy_traversable(p, m.data(), count);
      duet_planner_copy_frontier_mask(p, m.data(), count);
      break;
    }
    case 29: {  // an error callback that calls back into duet
      static const duet_error_callback cb = [](void*, duet_error code, const char* message) {
        if (!message || static_cast<int>(code) <= 0) std::abort();
        (void)duet_device_get_thread_count(nullptr);
      };
      duet_device_set_error_callback(dev, in.get<std::uint8_t>() & 1 ? cb : nullptr, nullptr);
      break;
    }
    case 30: {  // runtimes and simulators: made, released
      const char* sets[] = {"runtime.sensor_rate_hz=1", "bogus.key=1", "runtime.control_rate_hz=nan"};
      const std::size_t nsets = static_cast<std::size_t>(in.range(0, 3));
      switch (in.get<std::uint8_t>() % 8) {
        case 5: {  // a profile's settings
          duet_profile_settings ps;
          duet_profile_settings_load(dev, static_cast<duet_profile_kind>(in.range(-1, 2)), in.get<std::uint8_t>() & 1 ? kTinyProfile : "dual",
                                     nsets ? sets : nullptr, nsets, in.get<std::uint8_t>() % 8 ? &ps : nullptr);
          break;
        }
        case 6: {  // a grid saved as a map_server map and loaded again
          duet_grid g = pick(in, st.grids);
          const std::string path = (duet::fuzz::scratch() / "capi_map.yaml").string();
          duet_grid_save_map_server(g, in.get<std::uint8_t>() % 8 ? path.c_str() : nullptr);
          check_error(dev);
          duet_grid loaded = duet_grid_load_map_server(dev, in.get<std::uint8_t>() % 8 ? path.c_str() : "/nonexistent.yaml");
          check_error(dev);
          if (loaded && st.grids.size() < 4) st.grids.push_back(loaded);
          else if (loaded) duet_grid_release(loaded);
          break;
        }
        case 7: {  // a forgotten frame size
          duet_sensor_frame f;
          duet_sensor_frame_init(&f);
          std::uint16_t d[4] = {1000, 1000, 1000, 1000};
          f.depth = d;
          duet_back_project(pick(in, st.clouds), &f, 1, nullptr, nullptr);
          break;
        }
        case 0:
        case 1:
          if (st.runtimes.size() < 2) {
            const bool text = in.get<std::uint8_t>() % 4 != 0;
            duet_runtime r = duet_runtime_new(dev, text ? DUET_PROFILE_YAML_TEXT : static_cast<duet_profile_kind>(in.range(-1, 2)),
                                              text ? kTinyProfile : "tiny_no_such_profile", nsets ? sets : nullptr, nsets, in.get<std::uint8_t>());
            check_error(dev);
            if (r) {
              if (in.get<std::uint8_t>() & 1) duet_runtime_set_time_origin(r, in.value(100.0f));
              st.runtimes.push_back(r);
            }
          }
          break;
        case 2:
          if (st.sims.empty()) {
            duet_sim s = duet_sim_new(dev, in.get<std::uint8_t>() & 1 ? "lab" : "no_such_world", DUET_PROFILE_YAML_TEXT, kTinyProfile,
                                      sets, nsets, in.get<std::uint8_t>());
            check_error(dev);
            if (s) st.sims.push_back(s);
          }
          break;
        case 3:
          if (!st.runtimes.empty()) {
            duet_runtime_release(st.runtimes.back());
            st.runtimes.pop_back();
          }
          break;
        default:
          if (!st.sims.empty()) {
            duet_sim_release(st.sims.back());
            st.sims.pop_back();
          }
      }
      return;
    }
    case 31: {  // a runtime or a simulator used, with valid or broken arguments
      duet_runtime r = pick(in, st.runtimes);
      duet_sim sim = pick(in, st.sims);
      switch (in.get<std::uint8_t>() % 12) {
        case 0:
        case 1: {
          duet_rgbd_image im;
          duet_rgbd_image_init(&im);
          im.stamp_s = in.value(100.0f);
          im.width = in.get<std::uint8_t>() % 4 ? 8 : static_cast<int>(in.range(-2, 12));
          im.height = in.get<std::uint8_t>() % 4 ? 6 : static_cast<int>(in.range(-2, 12));
          const int fmt = static_cast<int>(in.range(0, 2));  // 2: not a format (never loaded as the enum here)
          std::memcpy(&im.depth_format, &fmt, sizeof fmt);
          im.depth_units_per_m = in.get<std::uint8_t>() % 3 ? 1000.0f : in.value(5000.0f);
          const std::size_t px = fmt == DUET_DEPTH_U16 ? 2 : 4;
          im.depth_row_stride = stride(in, px * 8);
          const std::size_t rows = 12, row_bytes = std::max<std::size_t>(stored(im.depth_row_stride, px * 8), px * 12);
          std::vector<float> depth((rows * row_bytes) / 4 + 4);
          for (auto& d : depth) d = in.get<std::uint8_t>() % 8 ? 1.5f : in.value(10.0f);
          im.depth = in.get<std::uint8_t>() % 8 ? depth.data() : nullptr;
          std::vector<std::uint8_t> colour(12 * 12 * 4 + 64, 100);
          if (in.get<std::uint8_t>() & 1) {
            im.color = colour.data();
            im.color_channels = static_cast<int>(in.range(2, 5));
            im.color_bgr = in.get<std::uint8_t>() & 1;
            im.color_row_stride = in.get<std::uint8_t>() % 3 ? 0 : static_cast<std::size_t>(in.range(0, 48));
          }
          const float k[4] = {in.value(10.0f), in.value(10.0f), in.value(8.0f), in.value(6.0f)};
          if (in.get<std::uint8_t>() % 4 == 0) im.intrinsics = k;
          duet_runtime_push_rgbd(r, static_cast<std::size_t>(in.range(0, 2)), in.get<std::uint8_t>() % 16 ? &im : nullptr);
          break;
        }
        case 2:
          if (in.get<std::uint8_t>() & 1) duet_runtime_push_gyro(r, in.value(100.0f), in.value(2.0f));
          duet_runtime_push_odometry(r, in.value(100.0f), pose(in, 5.0f), duet_twist{in.value(2.0f), in.value(2.0f)});
          break;
        case 3:
          if (st.spins < 4) {
            ++st.spins;
            duet_runtime_spin_once(r, in.value(100.0f));
          }
          break;
        case 4: {
          duet_runtime_status s;
          duet_runtime_get_status(r, in.get<std::uint8_t>() % 8 ? &s : nullptr);
          duet_runtime_stats t;
          duet_runtime_get_stats(r, &t);
          (void)duet_runtime_get_command(r);
          char buf[16];
          const std::size_t cap = static_cast<std::size_t>(in.range(0, 16));
          (void)duet_runtime_get_stop_detail(r, cap ? buf : nullptr, cap);
          const std::size_t n = static_cast<std::size_t>(in.range(0, 8));
          const std::size_t ps = stride(in, 8);
          std::vector<float> xy((stored(ps, 8) * n) / 4 + 2);
          (void)duet_runtime_get_path(r, n ? xy.data() : nullptr, ps, n);
          (void)duet_explorer_state_string(static_cast<duet_explorer_state>(in.range(-1, 6)));
          (void)duet_pose_health_string(static_cast<duet_pose_health>(in.range(-1, 4)));
          break;
        }
        case 5: {
          duet_grid g = duet_runtime_get_grid(r);
          if (g) duet_grid_release(g);
          break;
        }
        case 6:
          switch (in.get<std::uint8_t>() % 4) {
            case 0: duet_runtime_pause(r); break;
            case 1: duet_runtime_resume(r); break;
            case 2: duet_runtime_stop(r); break;
            default: duet_runtime_return_home(r);
          }
          break;
        case 7: {
          duet_runtime_sensor_info info;
          duet_runtime_get_sensor_info(r, static_cast<std::size_t>(in.range(0, 2)), in.get<std::uint8_t>() % 8 ? &info : nullptr);
          (void)duet_runtime_get_sensor_count(r);
          (void)duet_runtime_get_control_period(r);
          break;
        }
        case 8:
          if (st.spins < 4) {
            ++st.spins;
            duet_sim_step(sim, duet_twist{in.value(1.0f), in.value(2.0f)}, in.get<std::uint8_t>() % 4 ? 0.05 : in.value(20.0f));
          }
          break;
        case 9: {
          double stamp = 0.0;
          const int w = in.get<std::uint8_t>() % 4 ? 8 : static_cast<int>(in.range(-1, 12));
          const int h = in.get<std::uint8_t>() % 4 ? 6 : static_cast<int>(in.range(-1, 12));
          const std::size_t ds = stride(in, 16), cs = stride(in, 24);
          std::vector<std::uint16_t> depth(12 * std::max<std::size_t>(stored(ds, 16), 24) / 2 + 8);
          std::vector<std::uint8_t> rgb(12 * std::max<std::size_t>(stored(cs, 24), 36) + 8);
          (void)duet_sim_take_frame(sim, static_cast<std::size_t>(in.range(0, 2)), &stamp, depth.data(), ds,
                                    in.get<std::uint8_t>() & 1 ? rgb.data() : nullptr, cs, w, h);
          double t[4];
          duet_pose2 p[4];
          duet_twist tw[4];
          (void)duet_sim_take_odometry(sim, t, in.get<std::uint8_t>() & 1 ? p : nullptr, tw, static_cast<std::size_t>(in.range(0, 4)));
          break;
        }
        case 10: {
          duet_grid g = pick(in, st.grids);
          double c = 0.0, a = 0.0;
          duet_sim_score(sim, g, &c, &a);
          (void)duet_sim_get_true_pose(sim);
          (void)duet_sim_get_collisions(sim);
          (void)duet_sim_get_time(sim);
          (void)duet_sim_get_frames_waiting(sim, static_cast<std::size_t>(in.range(0, 2)));
          break;
        }
        default: {
          duet_cloud c = duet_runtime_get_cloud(r);
          if (c) duet_cloud_release(c);
        }
      }
      break;
    }
    default:
      (void)duet_device_get_thread_count(dev);
      break;
  }
  check_error(dev);
  check_error(nullptr);
  for (duet_device d : st.devices) check_error(d);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Bytes in(data, size);
  State st;
  for (int steps = 0; steps < 48 && !in.empty(); ++steps) step(st, in);
  for (auto r : st.runtimes) duet_runtime_release(r);
  for (auto s : st.sims) duet_sim_release(s);
  for (auto p : st.planners) duet_planner_release(p);
  for (auto g : st.grids) duet_grid_release(g);
  for (auto c : st.clouds) duet_cloud_release(c);
  for (auto d : st.devices) duet_device_release(d);
  duet_device_set_error_callback(nullptr, nullptr, nullptr);
  return 0;
}
