/// @file world_geometry.cpp
/// Geometry queries on simulated worlds: collision, clearance, rasterised ground truth, reachable free space.
#include <duet/kernels/error.hpp>
#include <duet/sim/world.hpp>

#include "config/yaml_reader.hpp"
#include "world_detail.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <utility>
#include <vector>

namespace duet::sim {
namespace {

using detail::format_number;
using world_detail::bbox;
using world_detail::height_overlaps;
using world_detail::point_in_polygon;

float segment_distance_sq(const Eigen::Vector2f& a, const Eigen::Vector2f& b, const Eigen::Vector2f& p) {
  const Eigen::Vector2f ab = b - a;
  const float len2 = ab.squaredNorm();
  float t = len2 > 0.0f ? (p - a).dot(ab) / len2 : 0.0f;
  t = std::clamp(t, 0.0f, 1.0f);
  return (a + t * ab - p).squaredNorm();
}

/// Distance from p to the polygon (0 inside).
float polygon_distance(const std::vector<Eigen::Vector2f>& poly, const Eigen::Vector2f& p) {
  if (point_in_polygon(poly, p)) return 0.0f;
  float best = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0, n = poly.size(); i < n; ++i) best = std::min(best, segment_distance_sq(poly[i], poly[(i + 1) % n], p));
  return std::sqrt(best);
}

}  // namespace

void world_detail::bbox(const std::vector<Eigen::Vector2f>& poly, Eigen::Vector2f& lo, Eigen::Vector2f& hi) {
  lo = hi = poly.front();
  for (const auto& v : poly) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
}

bool world_detail::disc_overlaps(const Solid& s, const Eigen::Vector2f& lo, const Eigen::Vector2f& hi, const Eigen::Vector2f& c, float r,
                                 float r2) {
  if (c.x() + r < lo.x() || c.x() - r > hi.x() || c.y() + r < lo.y() || c.y() - r > hi.y()) return false;
  if (point_in_polygon(s.polygon, c)) return true;
  for (std::size_t i = 0, n = s.polygon.size(); i < n; ++i)
    if (segment_distance_sq(s.polygon[i], s.polygon[(i + 1) % n], c) < r2) return true;
  return false;
}

// ---------------------------------------------------------------------------------------------
// Geometry queries.

const Solid* overlapping_solid(const World& world, const Eigen::Vector2f& centre, float radius_m, float z_low_m, float z_high_m) {
  const float r2 = radius_m * radius_m;
  for (const Solid& s : world.solids) {
    if (!height_overlaps(s, z_low_m, z_high_m)) continue;
    Eigen::Vector2f lo, hi;
    bbox(s.polygon, lo, hi);
    if (world_detail::disc_overlaps(s, lo, hi, centre, radius_m, r2)) return &s;
  }
  return nullptr;
}

bool collides(const World& world, const Eigen::Vector2f& centre, float radius_m, float z_low_m, float z_high_m) {
  if (world_detail::leaves_floor(world.floor, centre, radius_m)) return true;
  return overlapping_solid(world, centre, radius_m, z_low_m, z_high_m) != nullptr;
}

float clearance(const World& world, const Eigen::Vector2f& p, float z_low_m, float z_high_m) {
  const Region& f = world.floor;
  if (!p.allFinite() || !f.contains(p)) return 0.0f;
  float best = std::min({p.x() - f.min.x(), p.y() - f.min.y(), f.max.x() - p.x(), f.max.y() - p.y()});
  for (const Solid& s : world.solids) {
    if (!height_overlaps(s, z_low_m, z_high_m)) continue;
    Eigen::Vector2f lo, hi;
    bbox(s.polygon, lo, hi);
    const float dx = std::max({lo.x() - p.x(), 0.0f, p.x() - hi.x()});
    const float dy = std::max({lo.y() - p.y(), 0.0f, p.y() - hi.y()});
    if (dx * dx + dy * dy >= best * best) continue;
    best = std::min(best, polygon_distance(s.polygon, p));
    if (best == 0.0f) return 0.0f;
  }
  return best;
}

TruthGrid rasterize(const World& world, float resolution_m, float z_low_m, float z_high_m) {
  if (!(std::isfinite(resolution_m) && resolution_m > 0.0f))
    fail(ErrorCode::kInvalidArgument, "rasterize: resolution_m must be > 0, got " + format_number(resolution_m));
  TruthGrid g;
  g.resolution_m = resolution_m;
  g.origin = world.floor.min;
  const Eigen::Vector2f ext = world.floor.max - world.floor.min;
  const double cells = std::ceil(static_cast<double>(ext.x()) / resolution_m) * std::ceil(static_cast<double>(ext.y()) / resolution_m);
  if (!(cells <= static_cast<double>(1u << 28)))
    fail(ErrorCode::kOutOfRange, world.source + ": world '" + world.name + "': the floor (" + format_number(ext.x()) + " x " +
                                     format_number(ext.y()) + " m) is too large for " + format_number(resolution_m) +
                                     " m cells (at most 2^28 cells)");
  g.width = static_cast<int>(std::ceil(ext.x() / resolution_m - 1e-4f));
  g.height = static_cast<int>(std::ceil(ext.y() / resolution_m - 1e-4f));
  g.occupied.assign(static_cast<std::size_t>(g.width) * g.height, 0);
  for (const Solid& s : world.solids) {
    if (!height_overlaps(s, z_low_m, z_high_m)) continue;
    Eigen::Vector2f lo, hi;
    bbox(s.polygon, lo, hi);
    const int x0 = std::max(0, static_cast<int>(std::floor((lo.x() - g.origin.x()) / resolution_m)));
    const int y0 = std::max(0, static_cast<int>(std::floor((lo.y() - g.origin.y()) / resolution_m)));
    const int x1 = std::min(g.width - 1, static_cast<int>(std::floor((hi.x() - g.origin.x()) / resolution_m)));
    const int y1 = std::min(g.height - 1, static_cast<int>(std::floor((hi.y() - g.origin.y()) / resolution_m)));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        std::uint8_t& cell = g.occupied[static_cast<std::size_t>(y) * g.width + x];
        if (cell) continue;
        const Eigen::Vector2f c0 = g.origin + Eigen::Vector2f(static_cast<float>(x), static_cast<float>(y)) * resolution_m;
        const Eigen::Vector2f c1 = c0 + Eigen::Vector2f(resolution_m, resolution_m);
        // The open cell square overlaps the polygon: its centre is inside, or an edge of the
        // polygon crosses the square's interior (a polygon vertex inside the square is covered
        // by the edges), or the square is inside the polygon (centre test).
        bool hit = point_in_polygon(s.polygon, 0.5f * (c0 + c1));
        const float eps = 1e-5f * resolution_m;
        for (std::size_t i = 0, n = s.polygon.size(); !hit && i < n; ++i) {
          // Liang-Barsky clip of the edge against the square shrunk by eps (touching is not overlap).
          const Eigen::Vector2f a = s.polygon[i], b = s.polygon[(i + 1) % n];
          float t0 = 0.0f, t1 = 1.0f;
          const Eigen::Vector2f d = b - a;
          const float p[4] = {-d.x(), d.x(), -d.y(), d.y()};
          const float q[4] = {a.x() - (c0.x() + eps), (c1.x() - eps) - a.x(), a.y() - (c0.y() + eps), (c1.y() - eps) - a.y()};
          bool inside = true;
          for (int k = 0; k < 4 && inside; ++k) {
            if (p[k] == 0.0f) {
              if (q[k] < 0.0f) inside = false;
            } else {
              const float t = q[k] / p[k];
              if (p[k] < 0.0f) t0 = std::max(t0, t);
              else t1 = std::min(t1, t);
              if (t0 > t1) inside = false;
            }
          }
          hit = inside;
        }
        if (hit) cell = 1;
      }
  }
  return g;
}

std::vector<std::uint8_t> reachable_free_mask(const TruthGrid& truth, const Pose2& start, float robot_radius_m,
                                              float sensor_range_m) {
  if (!(std::isfinite(robot_radius_m) && robot_radius_m >= 0.0f))
    fail(ErrorCode::kInvalidArgument, "reachable_free_mask: robot_radius_m must be >= 0");
  if (!(std::isfinite(sensor_range_m) && sensor_range_m >= 0.0f))
    fail(ErrorCode::kInvalidArgument, "reachable_free_mask: sensor_range_m must be >= 0");
  const int w = truth.width, h = truth.height;
  const std::size_t n = static_cast<std::size_t>(w) * h;
  std::vector<std::uint8_t> mask(n, 0);
  if (n == 0) return mask;
  const float res = truth.resolution_m;
  // Cells the robot's centre may occupy: centre at least robot_radius_m from every occupied
  // cell's square (distance from the centre point to the square).
  std::vector<std::uint8_t> blocked(n, 0);
  const int rc = static_cast<int>(std::ceil(robot_radius_m / res)) + 1;
  std::vector<Eigen::Vector2i> disc;
  for (int dy = -rc; dy <= rc; ++dy)
    for (int dx = -rc; dx <= rc; ++dx) {
      // Distance from a cell centre to the square of the cell at offset (dx, dy).
      const float ex = std::max(0.0f, (std::abs(dx) - 0.5f) * res), ey = std::max(0.0f, (std::abs(dy) - 0.5f) * res);
      if (ex * ex + ey * ey < robot_radius_m * robot_radius_m) disc.emplace_back(dx, dy);
    }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (!truth.at(x, y)) continue;
      for (const auto& d : disc) {
        const int xx = x + d.x(), yy = y + d.y();
        if (xx >= 0 && yy >= 0 && xx < w && yy < h) blocked[static_cast<std::size_t>(yy) * w + xx] = 1;
      }
    }
  // The floor's edge blocks too.
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float cx = (static_cast<float>(x) + 0.5f) * res, cy = (static_cast<float>(y) + 0.5f) * res;
      if (cx < robot_radius_m || cy < robot_radius_m || static_cast<float>(w) * res - cx < robot_radius_m ||
          static_cast<float>(h) * res - cy < robot_radius_m)
        blocked[static_cast<std::size_t>(y) * w + x] = 1;
    }
  const int sx = static_cast<int>(std::floor((start.x - truth.origin.x()) / res));
  const int sy = static_cast<int>(std::floor((start.y - truth.origin.y()) / res));
  if (sx < 0 || sy < 0 || sx >= w || sy >= h) return mask;
  std::vector<std::uint8_t> reach(n, 0);
  std::deque<std::size_t> q;
  const std::size_t s0 = static_cast<std::size_t>(sy) * w + sx;
  if (blocked[s0]) {
    // A start pose hugging a wall: seed from the nearest unblocked free cell within 2 radii.
    float best = std::numeric_limits<float>::infinity();
    std::size_t pick = n;
    const int rr = 2 * rc;
    for (int dy = -rr; dy <= rr; ++dy)
      for (int dx = -rr; dx <= rr; ++dx) {
        const int xx = sx + dx, yy = sy + dy;
        if (xx < 0 || yy < 0 || xx >= w || yy >= h) continue;
        const std::size_t i = static_cast<std::size_t>(yy) * w + xx;
        const float d = static_cast<float>(dx * dx + dy * dy);
        if (!blocked[i] && d < best) {
          best = d;
          pick = i;
        }
      }
    if (pick == n) return mask;
    reach[pick] = 1;
    q.push_back(pick);
  } else {
    reach[s0] = 1;
    q.push_back(s0);
  }
  const int nb[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  while (!q.empty()) {
    const std::size_t c = q.front();
    q.pop_front();
    const int cx = static_cast<int>(c % static_cast<std::size_t>(w)), cy = static_cast<int>(c / static_cast<std::size_t>(w));
    for (const auto& d : nb) {
      const int nx = cx + d[0], ny = cy + d[1];
      if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
      const std::size_t ni = static_cast<std::size_t>(ny) * w + nx;
      if (!blocked[ni] && !reach[ni]) {
        reach[ni] = 1;
        q.push_back(ni);
      }
    }
  }
  // Free cells within sensor_range_m of a reachable cell, measured through free cells
  // (8-connected BFS distance in cells, diagonal steps sqrt(2)): what a sensor on the robot can
  // plausibly see. Line of sight is approximated by geodesic distance through free space.
  std::vector<float> dist(n, std::numeric_limits<float>::infinity());
  // Dial-like: a simple Dijkstra with a binary heap (the grids are small).
  using Item = std::pair<float, std::size_t>;
  std::vector<Item> heap;
  for (std::size_t i = 0; i < n; ++i)
    if (reach[i]) {
      dist[i] = 0.0f;
      heap.emplace_back(0.0f, i);
    }
  auto cmp = [](const Item& a, const Item& b) { return a.first > b.first; };
  std::make_heap(heap.begin(), heap.end(), cmp);
  const float limit = sensor_range_m / res;
  const int nb8[8][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {1, -1}, {-1, 1}, {-1, -1}};
  while (!heap.empty()) {
    std::pop_heap(heap.begin(), heap.end(), cmp);
    const auto [d, c] = heap.back();
    heap.pop_back();
    if (d > dist[c]) continue;
    const int cx = static_cast<int>(c % static_cast<std::size_t>(w)), cy = static_cast<int>(c / static_cast<std::size_t>(w));
    for (int k = 0; k < 8; ++k) {
      const int nx = cx + nb8[k][0], ny = cy + nb8[k][1];
      if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
      const std::size_t ni = static_cast<std::size_t>(ny) * w + nx;
      if (truth.occupied[ni]) continue;
      const float nd = d + (k < 4 ? 1.0f : 1.41421356f);
      if (nd <= limit && nd < dist[ni]) {
        dist[ni] = nd;
        heap.emplace_back(nd, ni);
        std::push_heap(heap.begin(), heap.end(), cmp);
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) mask[i] = (!truth.occupied[i] && std::isfinite(dist[i])) ? 1 : 0;
  return mask;
}

}  // namespace duet::sim
