/// @file world_from_map.cpp
/// world_from_map: a map_server map (occupancy image + YAML) as a simulated World.
#include <duet/kernels/error.hpp>
#include <duet/runtime/io/grid_io.hpp>
#include <duet/sim/world.hpp>

#include "config/yaml_reader.hpp"

#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace duet::sim {
namespace {

using detail::format_number;

}  // namespace

World world_from_map(const std::filesystem::path& map_yaml, const MapWorldOptions& options) {
  const std::string src = map_yaml.string();
  if (!(std::isfinite(options.wall_height_m) && options.wall_height_m > 0.0f))
    fail(ErrorCode::kInvalidArgument, src + ": wall_height_m must be > 0, got " + format_number(options.wall_height_m));
  if (!(std::isfinite(options.start_clearance_m) && options.start_clearance_m >= 0.0f))
    fail(ErrorCode::kInvalidArgument, src + ": start_clearance_m must be >= 0");
  const OccupancyGrid grid = read_map_server(map_yaml);
  const int w = grid.width(), h = grid.height();
  const float res = grid.resolution();
  // Solid = occupied or unknown (the outside of a map is solid). Only solid cells next to a
  // free cell (8-neighbourhood, dilated by one more cell for a 2-cell-thick skin) matter for
  // rendering and collision; the rest of the solid mass is never seen.
  std::vector<std::uint8_t> free(static_cast<std::size_t>(w) * h, 0);
  std::size_t free_count = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float l = grid.at(x, y);
      if (std::isfinite(l) && l < 0.0f) {
        free[grid.index(x, y)] = 1;
        ++free_count;
      }
    }
  if (free_count == 0) fail(ErrorCode::kInvalidArgument, src + ": the map has no free cell to put a robot on");
  auto dilate = [&](const std::vector<std::uint8_t>& in) {
    std::vector<std::uint8_t> out(in.size(), 0);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        if (!in[grid.index(x, y)]) continue;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx >= 0 && yy >= 0 && xx < w && yy < h) out[grid.index(xx, yy)] = 1;
          }
      }
    return out;
  };
  const std::vector<std::uint8_t> near_free = dilate(dilate(free));
  std::vector<std::uint8_t> skin(free.size(), 0);
  for (std::size_t i = 0; i < free.size(); ++i) skin[i] = (!free[i] && near_free[i]) ? 1 : 0;

  World world;
  world.name = map_yaml.stem().string();
  world.source = src;
  world.floor.min = grid.origin();
  world.floor.max = grid.origin() + Eigen::Vector2f(static_cast<float>(w), static_cast<float>(h)) * res;
  // Greedy rectangles: runs along x, extended along y while the run below is identical.
  std::vector<std::uint8_t> used(skin.size(), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w;) {
      const std::size_t i = grid.index(x, y);
      if (!skin[i] || used[i]) {
        ++x;
        continue;
      }
      int x1 = x;
      while (x1 + 1 < w && skin[grid.index(x1 + 1, y)] && !used[grid.index(x1 + 1, y)]) ++x1;
      int y1 = y;
      auto row_full = [&](int yy) {
        for (int xx = x; xx <= x1; ++xx)
          if (!skin[grid.index(xx, yy)] || used[grid.index(xx, yy)]) return false;
        return true;
      };
      while (y1 + 1 < h && row_full(y1 + 1)) ++y1;
      for (int yy = y; yy <= y1; ++yy)
        for (int xx = x; xx <= x1; ++xx) used[grid.index(xx, yy)] = 1;
      Solid s;
      s.name = "cells (" + std::to_string(x) + ".." + std::to_string(x1) + ", " + std::to_string(y) + ".." +
               std::to_string(y1) + ")";
      const Eigen::Vector2f lo = grid.origin() + Eigen::Vector2f(static_cast<float>(x), static_cast<float>(y)) * res;
      const Eigen::Vector2f hi =
          grid.origin() + Eigen::Vector2f(static_cast<float>(x1 + 1), static_cast<float>(y1 + 1)) * res;
      s.polygon = {lo, {hi.x(), lo.y()}, hi, {lo.x(), hi.y()}};
      s.z_min_m = 0.0f;
      s.z_max_m = options.wall_height_m;
      s.surface = options.wall_surface;
      world.solids.push_back(std::move(s));
      x = x1 + 1;
    }

  std::filesystem::path start_file = map_yaml;
  start_file.replace_extension(".start");
  if (options.start) {
    world.start = *options.start;
  } else if (options.start_file && std::filesystem::exists(start_file)) {
    set_start(world, read_start_file(start_file), 0.0f, start_file.string());  // on the floor, not inside a wall
  } else {
    // The largest 4-connected component of cells with room for the robot; start at its cell
    // nearest the component's centroid.
    const int r_cells = static_cast<int>(std::ceil(options.start_clearance_m / res));
    std::vector<std::uint8_t> roomy(free.size(), 0);
    {
      // Cells whose every cell within r_cells (square, conservative) is free.
      std::vector<int> integral(static_cast<std::size_t>(w + 1) * (h + 1), 0);
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
          integral[static_cast<std::size_t>(y + 1) * (w + 1) + x + 1] =
              (free[grid.index(x, y)] ? 0 : 1) + integral[static_cast<std::size_t>(y) * (w + 1) + x + 1] +
              integral[static_cast<std::size_t>(y + 1) * (w + 1) + x] - integral[static_cast<std::size_t>(y) * (w + 1) + x];
      for (int y = r_cells; y < h - r_cells; ++y)
        for (int x = r_cells; x < w - r_cells; ++x) {
          const int x0 = x - r_cells, x1 = x + r_cells + 1, y0 = y - r_cells, y1 = y + r_cells + 1;
          const int blocked = integral[static_cast<std::size_t>(y1) * (w + 1) + x1] -
                              integral[static_cast<std::size_t>(y0) * (w + 1) + x1] -
                              integral[static_cast<std::size_t>(y1) * (w + 1) + x0] +
                              integral[static_cast<std::size_t>(y0) * (w + 1) + x0];
          roomy[grid.index(x, y)] = blocked == 0 ? 1 : 0;
        }
    }
    std::vector<int> comp(free.size(), -1);
    int best = -1;
    std::size_t best_size = 0;
    std::vector<std::size_t> best_cells, cells;
    std::deque<std::size_t> q;
    int next = 0;
    for (std::size_t s0 = 0; s0 < free.size(); ++s0) {
      if (!roomy[s0] || comp[s0] >= 0) continue;
      cells.clear();
      comp[s0] = next;
      q.push_back(s0);
      while (!q.empty()) {
        const std::size_t c = q.front();
        q.pop_front();
        cells.push_back(c);
        const int cx = static_cast<int>(c % static_cast<std::size_t>(w)), cy = static_cast<int>(c / static_cast<std::size_t>(w));
        const int nb[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
        for (const auto& d : nb) {
          const int nx = cx + d[0], ny = cy + d[1];
          if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
          const std::size_t ni = grid.index(nx, ny);
          if (roomy[ni] && comp[ni] < 0) {
            comp[ni] = next;
            q.push_back(ni);
          }
        }
      }
      if (cells.size() > best_size) {
        best_size = cells.size();
        best = next;
        best_cells = cells;
      }
      ++next;
    }
    if (best < 0)
      fail(ErrorCode::kInvalidArgument, src + ": no free area has room for a robot of radius " +
                                            format_number(options.start_clearance_m) + " m");
    Eigen::Vector2d mean(0.0, 0.0);
    for (const std::size_t c : best_cells)
      mean += Eigen::Vector2d(static_cast<double>(c % static_cast<std::size_t>(w)), static_cast<double>(c / static_cast<std::size_t>(w)));
    mean /= static_cast<double>(best_cells.size());
    std::size_t pick = best_cells.front();
    double pick_d = std::numeric_limits<double>::infinity();
    for (const std::size_t c : best_cells) {
      const double dx = static_cast<double>(c % static_cast<std::size_t>(w)) - mean.x();
      const double dy = static_cast<double>(c / static_cast<std::size_t>(w)) - mean.y();
      const double d = dx * dx + dy * dy;
      if (d < pick_d) {
        pick_d = d;
        pick = c;
      }
    }
    const Eigen::Vector2f p = grid.cell_center(static_cast<int>(pick % static_cast<std::size_t>(w)),
                                               static_cast<int>(pick / static_cast<std::size_t>(w)));
    world.start = Pose2{p.x(), p.y(), 0.0f};
  }
  validate(world, src);
  return world;
}

}  // namespace duet::sim
