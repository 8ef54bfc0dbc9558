// duet_planner: the exploration and control kernels behind one handle (duet.h, "Exploration
// planner"). Every call takes the planner's mutex exclusively and runs the kernels inside the
// device's task arena.
#include "capi_internal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace duet::capi {
namespace {

/// Grids of this many cells or more are refused up front (the partial map simulation and the
/// Embree backend support < 2^30 cells), before anything is read or changed.
constexpr std::size_t kMaxCells = std::size_t{1} << 30;

/// Resolves the planner and runs `body(planner)` guarded, under the planner's mutex.
template <class F>
void with_planner(duet_planner handle, const char* fn, F&& body) noexcept {
  auto p = resolve<Planner>(handle, fn, "planner");
  if (!p) return;
  guarded(p->device.get(), fn, [&] {
    std::lock_guard lock(p->mutex);
    body(*p);
  });
}

/// Writes a result struct to the caller (all bytes, padding included).
template <class T>
void put(T* out, const T& value) {
  std::memcpy(out, &value, sizeof value);
}

void require_grid(const Planner& p) {
  if (!p.has_grid) {
    api_fail(DUET_ERROR_INVALID_OPERATION,
             "the planner has no grid yet (call duet_planner_set_grid or duet_planner_set_grid_from first)");
  }
}

void check_finite(float v, const char* name) {
  if (!std::isfinite(v)) invalid_argument(std::string(name) + " is not finite");
}

void check_finite(double v, const char* name) {
  if (!std::isfinite(v)) invalid_argument(std::string(name) + " is not finite");
}

Pose2 to_pose(const duet_pose2& p, const char* name) {
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.theta)) {
    invalid_argument(std::string(name) + " (" + std::to_string(p.x) + ", " + std::to_string(p.y) + ", " +
                     std::to_string(p.theta) + ") is not finite");
  }
  return Pose2{p.x, p.y, p.theta};
}

/// An output array with a capacity: NULL is allowed only with capacity 0.
void check_capacity(const void* ptr, std::size_t capacity, const char* name, const char* capacity_name) {
  if (ptr == nullptr && capacity > 0) {
    invalid_argument(std::string(name) + " is NULL but " + capacity_name + " is " + std::to_string(capacity));
  }
}

bool same_settings(const ObservationSettings& a, const ObservationSettings& b) {
  return a.backend == b.backend && a.tile_cells == b.tile_cells &&
         a.thresholds.occupied_logodds == b.thresholds.occupied_logodds &&
         a.thresholds.free_logodds == b.thresholds.free_logodds;
}

bool same_geometry(const GridView& a, const GridView& b) {
  return a.width == b.width && a.height == b.height && a.resolution_m == b.resolution_m &&
         a.origin.x() == b.origin.x() && a.origin.y() == b.origin.y();
}

/// Replaces the planner's grid by a copy of `view` (validated by the caller). Settings are
/// validated before anything changes; a failure inside the kernels leaves the planner without
/// a grid (the model and the inflated grid might disagree).
void set_grid_impl(Planner& p, const GridView& view, const ObservationSettings& os, const InflationSettings& is) {
  validate(view);
  if (view.cell_count() >= kMaxCells) {
    api_fail(DUET_ERROR_OUT_OF_RANGE, "grid of " + std::to_string(view.cell_count()) +
                                          " cells (at most 2^30 - 1 supported)");
  }
  const bool incremental = p.has_grid && same_settings(p.observation_settings, os) && same_geometry(p.model.grid(), view);
  p.has_grid = false;
  in_arena(*p.device, [&] {
    if (incremental) {
      (void)p.model.update_grid(view);
    } else {
      if (!same_settings(p.observation_settings, os)) {
        p.model = ObservationModel(os);  // a new Embree device/scene or none (DDA)
        p.observation_settings = os;
      }
      p.model.set_grid(view);
    }
    inflate(view, is, p.inflated);
  });
  p.inflation_settings = is;
  p.has_grid = true;
}

/// Copies min(capacity, points.size()) points to xy (x, y pairs).
void write_xy(std::span<const Eigen::Vector2f> points, float* xy, std::size_t capacity) {
  const std::size_t n = std::min(capacity, points.size());
  for (std::size_t i = 0; i < n; ++i) {
    xy[2 * i] = points[i].x();
    xy[2 * i + 1] = points[i].y();
  }
}

duet_path_status to_c(PathStatus s) {
  switch (s) {
    case PathStatus::kFound: return DUET_PATH_FOUND;
    case PathStatus::kStartBlocked: return DUET_PATH_START_BLOCKED;
    case PathStatus::kGoalBlocked: return DUET_PATH_GOAL_BLOCKED;
    case PathStatus::kNoPath: return DUET_PATH_NO_PATH;
    case PathStatus::kOutsideGrid: return DUET_PATH_OUTSIDE_GRID;
  }
  api_fail(DUET_ERROR_UNKNOWN, "unknown PathStatus (internal error)");
}

duet_exploration_status to_c(ExplorationStatus s) {
  switch (s) {
    case ExplorationStatus::kSimulatedGoal: return DUET_EXPLORATION_SIMULATED_GOAL;
    case ExplorationStatus::kFrontierGoal: return DUET_EXPLORATION_FRONTIER_GOAL;
    case ExplorationStatus::kNoFrontier: return DUET_EXPLORATION_NO_FRONTIER;
    case ExplorationStatus::kAllUnreachable: return DUET_EXPLORATION_ALL_UNREACHABLE;
    case ExplorationStatus::kAllBlacklisted: return DUET_EXPLORATION_ALL_BLACKLISTED;
    case ExplorationStatus::kRobotBlocked: return DUET_EXPLORATION_ROBOT_BLOCKED;
  }
  api_fail(DUET_ERROR_UNKNOWN, "unknown ExplorationStatus (internal error)");
}

duet_dwa_status to_c(DwaStatus s) {
  switch (s) {
    case DwaStatus::kOk: return DUET_DWA_OK;
    case DwaStatus::kGoalReached: return DUET_DWA_GOAL_REACHED;
    case DwaStatus::kRotateInPlace: return DUET_DWA_ROTATE_IN_PLACE;
    case DwaStatus::kBackOff: return DUET_DWA_BACK_OFF;
    case DwaStatus::kNoValidTrajectory: return DUET_DWA_NO_VALID_TRAJECTORY;
    case DwaStatus::kNoPath: return DUET_DWA_NO_PATH;
  }
  api_fail(DUET_ERROR_UNKNOWN, "unknown DwaStatus (internal error)");
}

}  // namespace
}  // namespace duet::capi

using namespace duet::capi;

extern "C" {

DUET_API duet_planner duet_planner_new(duet_device device) {
  static constexpr const char* fn = "duet_planner_new";
  auto d = resolve<Device>(device, fn, "device");
  if (!d) return nullptr;
  duet_planner result = nullptr;
  guarded(d.get(), fn, [&] {
    auto p = std::make_shared<Planner>(d);
    p->parent = d->key;
    result = to_handle<duet_planner>(register_object(std::move(p)));
  });
  return result;
}

DUET_API void duet_planner_retain(duet_planner planner) {
  retain_handle(planner, Kind::kPlanner, "duet_planner_retain");
}

DUET_API void duet_planner_release(duet_planner planner) {
  release_handle(planner, Kind::kPlanner, "duet_planner_release");
}

DUET_API void duet_planner_set_sensors(duet_planner planner, const duet_sensor_sector* sensors,
                                       size_t count) {
  with_planner(planner, "duet_planner_set_sensors", [&](Planner& p) {
    check_not_null(sensors, "sensors");
    if (count == 0) invalid_argument("count is 0 (at least one sensor is required)");
    if (count > 1000) invalid_argument("count is " + std::to_string(count) + " (at most 1000 sensors)");
    std::vector<duet::SensorSector> s(count);
    std::size_t total = 0;
    for (std::size_t i = 0; i < count; ++i) {
      s[i] = to_cpp(sensors[i]);
      try {
        duet::validate(s[i]);
      } catch (const duet::Error& e) {
        invalid_argument("sensors[" + std::to_string(i) + "]: " + e.what());
      }
      total += static_cast<std::size_t>(s[i].rays);
    }
    if (total > 1000000) {
      invalid_argument("the sensors have " + std::to_string(total) + " rays in total (at most 1000000)");
    }
    p.sensors = std::move(s);
  });
}

DUET_API size_t duet_planner_get_sensors(duet_planner planner, duet_sensor_sector* out,
                                         size_t capacity) {
  std::size_t r = 0;
  with_planner(planner, "duet_planner_get_sensors", [&](Planner& p) {
    check_capacity(out, capacity, "out", "capacity");
    const std::size_t n = std::min(capacity, p.sensors.size());
    for (std::size_t i = 0; i < n; ++i) out[i] = to_c(p.sensors[i]);
    r = p.sensors.size();
  });
  return r;
}

DUET_API size_t duet_planner_get_ray_count(duet_planner planner) {
  std::size_t r = 0;
  with_planner(planner, "duet_planner_get_ray_count", [&](Planner& p) {
    for (const auto& s : p.sensors) r += static_cast<std::size_t>(s.rays);
  });
  return r;
}

DUET_API void duet_planner_set_grid(duet_planner planner, const float* logodds,
                                    size_t row_stride_bytes, int width, int height,
                                    float resolution_m, float origin_x, float origin_y,
                                    const duet_observation_settings* observation_settings,
                                    const duet_inflation_settings* inflation_settings) {
  with_planner(planner, "duet_planner_set_grid", [&](Planner& p) {
    if (width <= 0 || height <= 0) {
      invalid_argument("width x height is " + std::to_string(width) + " x " + std::to_string(height) +
                       " (both must be > 0)");
    }
    const std::size_t w = static_cast<std::size_t>(width), h = static_cast<std::size_t>(height);
    if (w * h >= kMaxCells) {
      api_fail(DUET_ERROR_OUT_OF_RANGE, "width x height = " + std::to_string(w * h) +
                                            " cells (at most 2^30 - 1 supported)");
    }
    if (!(resolution_m >= duet::kMinGridResolutionM && resolution_m <= duet::kMaxGridResolutionM)) {
      invalid_argument("resolution_m is " + std::to_string(resolution_m) + " (must be in [0.001, 100] m)");
    }
    check_finite(origin_x, "origin_x");
    check_finite(origin_y, "origin_y");
    if (std::fabs(origin_x) > 2.0f * duet::kMaxCoordinateM || std::fabs(origin_y) > 2.0f * duet::kMaxCoordinateM) {
      api_fail(DUET_ERROR_OUT_OF_RANGE, "origin (" + std::to_string(origin_x) + ", " + std::to_string(origin_y) +
                                            ") is beyond the map frame's +-20 km");
    }
    // One row is one "element" of width * 4 bytes; rows at row_stride_bytes.
    const std::size_t stride = check_buffer(logodds, row_stride_bytes, h, w * sizeof(float), 4, "logodds");
    const auto os = to_cpp(observation_settings, "observation_settings");
    const auto is = to_cpp(inflation_settings, "inflation_settings");
    std::span<const float> cells;
    if (stride == w * sizeof(float)) {
      cells = std::span<const float>(logodds, w * h);  // packed: the model copies it
    } else {
      p.staging.resize(w * h);
      const auto* src = reinterpret_cast<const std::byte*>(logodds);
      for (std::size_t y = 0; y < h; ++y) {
        std::memcpy(p.staging.data() + y * w, src + y * stride, w * sizeof(float));
      }
      cells = p.staging;
    }
    const duet::GridView view(cells, width, height, resolution_m, Eigen::Vector2f(origin_x, origin_y));
    set_grid_impl(p, view, os, is);
  });
}

DUET_API void duet_planner_set_grid_from(duet_planner planner, duet_grid grid,
                                         const duet_observation_settings* observation_settings,
                                         const duet_inflation_settings* inflation_settings) {
  static constexpr const char* fn = "duet_planner_set_grid_from";
  auto p = resolve<Planner>(planner, fn, "planner");
  if (!p) return;
  auto g = resolve<Grid>(grid, fn, "grid");
  if (!g) return;
  guarded(p->device.get(), fn, [&] {
    if (g->device.get() != p->device.get()) {
      api_fail(DUET_ERROR_INVALID_OPERATION, "grid was created by another device than the planner");
    }
    const auto os = to_cpp(observation_settings, "observation_settings");
    const auto is = to_cpp(inflation_settings, "inflation_settings");
    std::lock_guard lock(p->mutex);
    std::shared_lock grid_lock(g->mutex);
    if (g->grid.width() <= 0 || g->grid.height() <= 0) {
      invalid_argument("grid is empty (0 x 0 cells): update it first");
    }
    set_grid_impl(*p, duet::GridView(g->grid), os, is);
  });
}

DUET_API void duet_planner_get_grid_size(duet_planner planner, int* width, int* height) {
  if (width != nullptr) *width = 0;
  if (height != nullptr) *height = 0;
  with_planner(planner, "duet_planner_get_grid_size", [&](Planner& p) {
    if (!p.has_grid) return;
    if (width != nullptr) *width = p.inflated.width;
    if (height != nullptr) *height = p.inflated.height;
  });
}

DUET_API void duet_planner_copy_clearance(duet_planner planner, float* out, size_t count) {
  with_planner(planner, "duet_planner_copy_clearance", [&](Planner& p) {
    require_grid(p);
    check_buffer(out, 0, count, sizeof(float), alignof(float), "out");
    check_count(p.inflated.cell_count(), count, "out (width * height cells)");
    std::memcpy(out, p.inflated.clearance_m.data(), count * sizeof(float));
  });
}

DUET_API void duet_planner_copy_traversable(duet_planner planner, uint8_t* out, size_t count) {
  with_planner(planner, "duet_planner_copy_traversable", [&](Planner& p) {
    require_grid(p);
    check_buffer(out, 0, count, 1, 1, "out");
    check_count(p.inflated.cell_count(), count, "out (width * height cells)");
    std::memcpy(out, p.inflated.traversable.data(), count);
  });
}

DUET_API void duet_planner_copy_frontier_mask(duet_planner planner, uint8_t* out, size_t count) {
  with_planner(planner, "duet_planner_copy_frontier_mask", [&](Planner& p) {
    require_grid(p);
    check_buffer(out, 0, count, 1, 1, "out");
    check_count(p.inflated.cell_count(), count, "out (width * height cells)");
    in_arena(*p.device, [&] {
      (void)duet::frontier_mask(p.inflated.state, p.inflated.width, p.inflated.height,
                                std::span<std::uint8_t>(out, count));
    });
  });
}

DUET_API void duet_planner_observe(duet_planner planner, const duet_pose2* poses, size_t count,
                                   duet_ray_observation* out, size_t out_count) {
  with_planner(planner, "duet_planner_observe", [&](Planner& p) {
    require_grid(p);
    check_buffer(poses, 0, count, sizeof(duet_pose2), alignof(float), "poses");
    check_buffer(out, 0, out_count, sizeof(duet_ray_observation), alignof(std::int32_t), "out");
    std::size_t rays = 0;
    for (const auto& s : p.sensors) rays += static_cast<std::size_t>(s.rays);
    if (count > 0 && rays > std::numeric_limits<std::size_t>::max() / count) {
      invalid_argument("count * rays overflows");
    }
    check_count(count * rays, out_count, "out (count * total rays)");
    // Reused planner buffers: no allocation once warmed up with the same sizes.
    std::vector<duet::Pose2>& ps = p.poses_in;
    std::vector<duet::RayObservation>& obs = p.rays_out;
    ps.resize(count);
    obs.resize(out_count);
    for (std::size_t i = 0; i < count; ++i) {
      const duet_pose2& q = poses[i];
      if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.theta)) {
        (void)to_pose(q, ("poses[" + std::to_string(i) + "]").c_str());  // throws naming it
      }
      ps[i] = duet::Pose2{q.x, q.y, q.theta};
    }
    in_arena(*p.device, [&] { p.model.observe(ps, p.sensors, obs); });
    for (std::size_t i = 0; i < out_count; ++i) {
      out[i] = blank<duet_ray_observation>();
      out[i].entropy_bits = obs[i].entropy_bits;
      out[i].range_m = obs[i].range_m;
      out[i].hit = obs[i].hit ? 1 : 0;
      out[i].cells = obs[i].cells;
    }
  });
}

DUET_API float duet_planner_information(duet_planner planner, duet_pose2 pose) {
  float r = 0.0f;
  with_planner(planner, "duet_planner_information", [&](Planner& p) {
    require_grid(p);
    const duet::Pose2 x = to_pose(pose, "pose");
    in_arena(*p.device, [&] { r = p.model.information_bits(x, p.sensors); });
  });
  return r;
}

DUET_API void duet_planner_simulate(duet_planner planner, duet_pose2 robot,
                                    const duet_partial_sim_settings* settings,
                                    duet_partial_sim_result* out, duet_pose2* trajectory,
                                    size_t trajectory_capacity) {
  with_planner(planner, "duet_planner_simulate", [&](Planner& p) {
    require_grid(p);
    check_not_null(out, "out");
    check_capacity(trajectory, trajectory_capacity, "trajectory", "trajectory_capacity");
    const duet::Pose2 x = to_pose(robot, "robot");
    const auto s = to_cpp(settings);
    duet::PartialSimResult r;
    in_arena(*p.device, [&] {
      r = duet::partial_map_simulation(p.model, p.inflated, x, p.sensors, s, p.exploration_ws.simulation);
    });
    const std::size_t n = std::min(trajectory_capacity, r.best_trajectory.size());
    for (std::size_t i = 0; i < n; ++i) trajectory[i] = to_c(r.best_trajectory[i]);
    put(out, to_c(r));
  });
}

DUET_API void duet_planner_find_frontier(duet_planner planner, float x, float y, double now_s,
                                         const duet_frontier_settings* settings,
                                         duet_frontier_result* out, float* path_xy,
                                         size_t path_capacity, duet_frontier_cluster* clusters,
                                         size_t cluster_capacity) {
  with_planner(planner, "duet_planner_find_frontier", [&](Planner& p) {
    require_grid(p);
    check_not_null(out, "out");
    check_capacity(path_xy, path_capacity, "path_xy", "path_capacity");
    check_capacity(clusters, cluster_capacity, "clusters", "cluster_capacity");
    check_finite(x, "x");
    check_finite(y, "y");
    check_finite(now_s, "now_s");
    const auto s = to_cpp(settings);
    duet::FrontierResult r;
    in_arena(*p.device, [&] {
      r = duet::find_frontier(p.inflated, Eigen::Vector2f(x, y), p.blacklist, now_s, s, p.exploration_ws.frontier);
    });
    const duet_frontier_result c = to_c(r);
    write_xy(r.path, path_xy, path_capacity);
    const std::size_t n = std::min(cluster_capacity, r.clusters.size());
    for (std::size_t i = 0; i < n; ++i) {
      const duet::FrontierCluster& k = r.clusters[i];
      clusters[i] = blank<duet_frontier_cluster>();
      clusters[i].cells = k.cells;
      clusters[i].centroid_x = k.centroid.x();
      clusters[i].centroid_y = k.centroid.y();
      clusters[i].nearest_x = k.nearest_xy.x();
      clusters[i].nearest_y = k.nearest_xy.y();
      clusters[i].path_length_m = k.path_length_m;
      clusters[i].reachable = k.reachable ? 1 : 0;
      clusters[i].blacklisted = k.blacklisted ? 1 : 0;
    }
    put(out, c);
  });
}

DUET_API void duet_planner_blacklist_add(duet_planner planner, float x, float y, double now_s,
                                         double ttl_s) {
  with_planner(planner, "duet_planner_blacklist_add", [&](Planner& p) {
    check_finite(x, "x");
    check_finite(y, "y");
    check_finite(now_s, "now_s");
    if (!(ttl_s > 0.0)) {
      invalid_argument("ttl_s is " + std::to_string(ttl_s) + " (must be > 0 [s]; +inf = forever)");
    }
    p.blacklist.add(Eigen::Vector2f(x, y), now_s, ttl_s);
  });
}

DUET_API void duet_planner_blacklist_expire(duet_planner planner, double now_s) {
  with_planner(planner, "duet_planner_blacklist_expire", [&](Planner& p) {
    check_finite(now_s, "now_s");
    p.blacklist.expire(now_s);
  });
}

DUET_API void duet_planner_blacklist_clear(duet_planner planner) {
  with_planner(planner, "duet_planner_blacklist_clear", [&](Planner& p) { p.blacklist.clear(); });
}

DUET_API size_t duet_planner_blacklist_get_size(duet_planner planner) {
  std::size_t r = 0;
  with_planner(planner, "duet_planner_blacklist_get_size", [&](Planner& p) { r = p.blacklist.size(); });
  return r;
}

DUET_API void duet_planner_decide(duet_planner planner, duet_pose2 robot, double now_s,
                                  const duet_exploration_settings* settings, duet_decision* out) {
  with_planner(planner, "duet_planner_decide", [&](Planner& p) {
    require_grid(p);
    check_not_null(out, "out");
    const duet::Pose2 x = to_pose(robot, "robot");
    check_finite(now_s, "now_s");
    const auto s = to_cpp(settings);
    duet::ExplorationDecision d;
    in_arena(*p.device, [&] {
      d = duet::decide_goal(p.model, p.inflated, x, p.sensors, p.blacklist, now_s, s, p.exploration_ws);
    });
    auto c = blank<duet_decision>();
    c.status = to_c(d.status);
    c.goal = to_c(d.goal);
    c.reward_bits = d.reward_bits;
    c.simulated_goal_blacklisted = d.simulated_goal_blacklisted ? 1 : 0;
    c.simulation_ran = s.use_simulation ? 1 : 0;
    c.frontier_ran = d.status != duet::ExplorationStatus::kSimulatedGoal ? 1 : 0;
    c.simulation = to_c(d.simulation);
    c.frontier = to_c(d.frontier);
    put(out, c);
  });
}

DUET_API void duet_planner_plan_path(duet_planner planner, float start_x, float start_y,
                                     float goal_x, float goal_y,
                                     const duet_path_settings* settings, duet_path_result* out,
                                     float* xy, size_t capacity) {
  with_planner(planner, "duet_planner_plan_path", [&](Planner& p) {
    require_grid(p);
    check_not_null(out, "out");
    check_capacity(xy, capacity, "xy", "capacity");
    check_finite(start_x, "start_x");
    check_finite(start_y, "start_y");
    check_finite(goal_x, "goal_x");
    check_finite(goal_y, "goal_y");
    const auto s = to_cpp(settings);
    duet::PathResult r;
    in_arena(*p.device, [&] {  // serial kernel; in the arena like every other
      r = duet::plan_path(p.inflated, Eigen::Vector2f(start_x, start_y), Eigen::Vector2f(goal_x, goal_y), s,
                          p.path_ws);
    });
    auto c = blank<duet_path_result>();
    c.status = to_c(r.status);
    c.waypoint_count = r.waypoints.size();
    c.length_m = r.length_m;
    c.cost = r.cost;
    c.start_moved = r.start_moved ? 1 : 0;
    c.expanded = r.expanded;
    write_xy(r.waypoints, xy, capacity);
    put(out, c);
  });
}

DUET_API void duet_planner_dwa_step(duet_planner planner, duet_pose2 pose, duet_twist current,
                                    const float* path_xy, size_t path_stride, size_t path_count,
                                    const duet_dwa_settings* settings, duet_dwa_result* out) {
  with_planner(planner, "duet_planner_dwa_step", [&](Planner& p) {
    require_grid(p);
    check_not_null(out, "out");
    const std::size_t stride = check_buffer(path_xy, path_stride, path_count, 2 * sizeof(float), 4, "path_xy");
    const duet::Pose2 x = to_pose(pose, "pose");
    if (!std::isfinite(current.v) || !std::isfinite(current.omega)) invalid_argument("current is not finite");
    const auto s = to_cpp(settings);
    p.path_in.resize(path_count);
    const auto* src = reinterpret_cast<const std::byte*>(path_xy);
    for (std::size_t i = 0; i < path_count; ++i) {
      float v[2];
      std::memcpy(v, src + i * stride, sizeof v);
      if (!std::isfinite(v[0]) || !std::isfinite(v[1])) {
        invalid_argument("path_xy[" + std::to_string(i) + "] is not finite");
      }
      p.path_in[i] = Eigen::Vector2f(v[0], v[1]);
    }
    // The state is updated only if the step succeeds.
    duet::DwaState state = p.dwa_state;
    duet::DwaResult r;
    in_arena(*p.device, [&] {
      r = duet::dwa_step(p.inflated.clearance(), x, duet::Twist{current.v, current.omega}, p.path_in, s, state,
                         p.dwa_ws);
    });
    auto c = blank<duet_dwa_result>();
    c.status = to_c(r.status);
    c.cmd.v = r.cmd.v;
    c.cmd.omega = r.cmd.omega;
    c.score = r.score;
    c.valid_trajectories = r.valid_trajectories;
    c.evaluated_trajectories = r.evaluated_trajectories;
    c.oscillation = r.oscillation ? 1 : 0;
    c.lookahead_x = r.lookahead.x();
    c.lookahead_y = r.lookahead.y();
    p.dwa_state = state;
    put(out, c);
  });
}

DUET_API void duet_planner_dwa_reset(duet_planner planner) {
  with_planner(planner, "duet_planner_dwa_reset", [&](Planner& p) { p.dwa_state.reset(); });
}

}  // extern "C"
