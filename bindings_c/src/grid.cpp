// duet_grid: creation, reference counting, update and copies (duet.h, "Occupancy grid").
#include "capi_internal.hpp"

#include <duet/runtime/io/grid_io.hpp>

#include <cmath>
#include <span>
#include <string>
#include <vector>

namespace duet::capi {
namespace {

template <class F>
void with_grid(duet_grid handle, const char* fn, F&& body) noexcept {
  auto g = resolve<Grid>(handle, fn, "grid");
  if (!g) return;
  guarded(g->device.get(), fn, [&] { body(*g); });
}

/// Validates a caller output buffer for the whole grid (`count` must be width * height).
void check_grid_out(const Grid& g, const void* out, std::size_t count, std::size_t elem) {
  check_buffer(out, 0, count, elem, elem, "out");
  check_count(g.grid.cell_count(), count, "out (width * height cells)");
}

}  // namespace
}  // namespace duet::capi

using namespace duet::capi;

extern "C" {

DUET_API duet_grid duet_grid_new(duet_device device, float resolution_m) {
  static constexpr const char* fn = "duet_grid_new";
  auto d = resolve<Device>(device, fn, "device");
  if (!d) return nullptr;
  duet_grid result = nullptr;
  guarded(d.get(), fn, [&] {
    if (!std::isfinite(resolution_m) || !(resolution_m > 0.0f)) {
      invalid_argument("resolution_m is " + std::to_string(resolution_m) + " (must be finite and > 0)");
    }
    auto g = std::make_shared<Grid>(d, resolution_m);
    g->parent = d->key;
    result = to_handle<duet_grid>(register_object(std::move(g)));
  });
  return result;
}

DUET_API duet_grid duet_grid_load_map_server(duet_device device, const char* yaml_path) {
  static constexpr const char* fn = "duet_grid_load_map_server";
  auto d = resolve<Device>(device, fn, "device");
  if (!d) return nullptr;
  duet_grid result = nullptr;
  guarded(d.get(), fn, [&] {
    check_not_null(yaml_path, "yaml_path");
    duet::OccupancyGrid loaded = duet::read_map_server(yaml_path);
    auto g = std::make_shared<Grid>(d, loaded.resolution());
    g->grid = std::move(loaded);
    g->parent = d->key;
    result = to_handle<duet_grid>(register_object(std::move(g)));
  });
  return result;
}

DUET_API void duet_grid_save_map_server(duet_grid grid, const char* yaml_path) {
  with_grid(grid, "duet_grid_save_map_server", [&](Grid& g) {
    check_not_null(yaml_path, "yaml_path");
    std::shared_lock lock(g.mutex);
    if (g.grid.width() == 0 || g.grid.height() == 0) invalid_argument("the grid is empty (0 x 0 cells): nothing to save");
    duet::write_map_server(g.grid, yaml_path);
  });
}

DUET_API void duet_grid_retain(duet_grid grid) {
  retain_handle(grid, Kind::kGrid, "duet_grid_retain");
}

DUET_API void duet_grid_release(duet_grid grid) {
  release_handle(grid, Kind::kGrid, "duet_grid_release");
}

DUET_API void duet_grid_update(duet_grid grid, float sensor_x, float sensor_y, const float* xyz,
                               size_t xyz_stride, const uint8_t* labels, size_t labels_stride,
                               size_t count, const duet_grid_update_settings* settings) {
  with_grid(grid, "duet_grid_update", [&](Grid& g) {
    if (!std::isfinite(sensor_x) || !std::isfinite(sensor_y)) {
      invalid_argument("sensor position is not finite");
    }
    const std::size_t xs = check_buffer(xyz, xyz_stride, count, 3 * sizeof(float), 4, "xyz");
    const std::size_t ls = check_buffer(labels, labels_stride, count, 1, 1, "labels");
    const auto s = to_cpp(settings);
    // Labels are validated (an out-of-enum value would be undefined behaviour in the kernel);
    // read in place when packed, else one gathered copy.
    std::vector<duet::PointLabel> gathered;
    if (ls != 1 && count > 0) gathered.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
      const std::uint8_t v = labels[i * ls];
      if (v > DUET_LABEL_IGNORED) {
        invalid_argument("labels[" + std::to_string(i) + "] is " + std::to_string(v) +
                         " (allowed: DUET_LABEL_FLOOR, DUET_LABEL_OBSTACLE, DUET_LABEL_IGNORED)");
      }
      if (ls != 1) gathered[i] = static_cast<duet::PointLabel>(v);
    }
    std::span<const duet::PointLabel> lab;
    if (count > 0) {
      lab = ls == 1 ? std::span<const duet::PointLabel>(
                          reinterpret_cast<const duet::PointLabel*>(labels), count)
                    : std::span<const duet::PointLabel>(gathered);
    }
    const duet::PointsView points = count == 0 ? duet::PointsView() : duet::PointsView(xyz, count, xs);
    std::unique_lock lock(g.mutex);
    in_arena(*g.device, [&] {
      duet::update_grid(g.grid, Eigen::Vector2f(sensor_x, sensor_y), points, lab, s, g.workspace);
    });
  });
}

DUET_API int duet_grid_get_width(duet_grid grid) {
  int r = 0;
  with_grid(grid, "duet_grid_get_width", [&](Grid& g) {
    std::shared_lock lock(g.mutex);
    r = g.grid.width();
  });
  return r;
}

DUET_API int duet_grid_get_height(duet_grid grid) {
  int r = 0;
  with_grid(grid, "duet_grid_get_height", [&](Grid& g) {
    std::shared_lock lock(g.mutex);
    r = g.grid.height();
  });
  return r;
}

DUET_API float duet_grid_get_resolution(duet_grid grid) {
  float r = 0.0f;
  with_grid(grid, "duet_grid_get_resolution", [&](Grid& g) {
    std::shared_lock lock(g.mutex);
    r = g.grid.resolution();
  });
  return r;
}

DUET_API void duet_grid_get_origin(duet_grid grid, float* origin_x, float* origin_y) {
  with_grid(grid, "duet_grid_get_origin", [&](Grid& g) {
    check_not_null(origin_x, "origin_x");
    check_not_null(origin_y, "origin_y");
    std::shared_lock lock(g.mutex);
    *origin_x = g.grid.origin().x();
    *origin_y = g.grid.origin().y();
  });
}

DUET_API size_t duet_grid_get_known_cells(duet_grid grid) {
  std::size_t r = 0;
  with_grid(grid, "duet_grid_get_known_cells", [&](Grid& g) {
    std::shared_lock lock(g.mutex);
    r = g.grid.known_cells();
  });
  return r;
}

DUET_API void duet_grid_scan_match(duet_grid grid, const float* xy, size_t xy_stride, size_t count,
                                   duet_pose2 prior, const duet_scan_match_settings* settings,
                                   duet_scan_match_result* out) {
  with_grid(grid, "duet_grid_scan_match", [&](Grid& g) {
    if (out == nullptr) invalid_argument("out is NULL");
    const std::size_t st = check_buffer(xy, xy_stride, count, 2 * sizeof(float), 4, "xy");
    if (!std::isfinite(prior.x) || !std::isfinite(prior.y) || !std::isfinite(prior.theta)) invalid_argument("prior is not finite");
    const duet::ScanMatchSettings s = to_cpp(settings);
    std::vector<Eigen::Vector2f> pts(count);
    for (std::size_t i = 0; i < count; ++i) {
      const auto* p = reinterpret_cast<const float*>(reinterpret_cast<const unsigned char*>(xy) + i * st);
      pts[i] = Eigen::Vector2f(p[0], p[1]);
    }
    duet::InflatedGrid field;
    duet::ScanMatchResult r;
    {
      std::shared_lock lock(g.mutex);
      in_arena(*g.device, [&] {
        duet::occupied_distance(duet::GridView(g.grid), duet::CellThresholds{}, field);
        r = duet::scan_match(field.clearance(), pts, duet::Pose2{prior.x, prior.y, prior.theta}, s);
      });
    }
    out->status = static_cast<int>(r.status);
    out->pose = duet_pose2{r.pose.x, r.pose.y, r.pose.theta};
    out->score = r.score;
    out->prior_score = r.prior_score;
    out->candidates = r.candidates;
  });
}

DUET_API void duet_grid_copy_logodds(duet_grid grid, float* out, size_t count) {
  with_grid(grid, "duet_grid_copy_logodds", [&](Grid& g) {
    std::shared_lock lock(g.mutex);
    check_grid_out(g, out, count, sizeof(float));
    const auto l = g.grid.logodds();
    if (count > 0) std::memcpy(out, l.data(), count * sizeof(float));
  });
}

DUET_API void duet_grid_copy_probabilities(duet_grid grid, float* out, size_t count) {
  with_grid(grid, "duet_grid_copy_probabilities", [&](Grid& g) {
    std::shared_lock lock(g.mutex);
    check_grid_out(g, out, count, sizeof(float));
    if (count == 0) return;
    in_arena(*g.device, [&] { g.grid.to_probabilities(std::span<float>(out, count)); });
  });
}

DUET_API void duet_grid_copy_ros(duet_grid grid, int8_t* out, size_t count,
                                 float occupied_threshold, float free_threshold) {
  with_grid(grid, "duet_grid_copy_ros", [&](Grid& g) {
    if (!(occupied_threshold >= 0.0f && occupied_threshold <= 1.0f) ||
        !(free_threshold >= 0.0f && free_threshold <= 1.0f) || free_threshold > occupied_threshold) {
      invalid_argument("thresholds occupied " + std::to_string(occupied_threshold) + ", free " +
                       std::to_string(free_threshold) +
                       " (allowed: 0 <= free <= occupied <= 1)");
    }
    std::shared_lock lock(g.mutex);
    check_grid_out(g, out, count, sizeof(std::int8_t));
    if (count == 0) return;
    in_arena(*g.device, [&] {
      g.grid.to_ros_trinary(std::span<std::int8_t>(out, count), occupied_threshold, free_threshold);
    });
  });
}

}  // extern "C"
