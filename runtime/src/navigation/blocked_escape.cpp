/// @file blocked_escape.cpp
/// The way out for a blocked robot (see blocked_escape.hpp).
#include <duet/runtime/navigation/blocked_escape.hpp>
#include <duet/runtime/navigation/escape.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numbers>
#include <queue>
#include <utility>

namespace duet {

namespace {

float clearance_at(const InflatedGrid& g, const Eigen::Vector2f& xy) {
  Eigen::Vector2i c;
  return g.cell_of(xy, c) ? g.clearance_m[g.index(c.x(), c.y())] : 0.0f;
}

}  // namespace

std::vector<Eigen::Vector2f> path_out(const InflatedGrid& g, const Eigen::Vector2f& robot, float body_radius_m, float max_length_m) {
  Eigen::Vector2i rc;
  if (!g.cell_of(robot, rc)) return {};
  const std::size_t start = g.index(rc.x(), rc.y());
  if (g.traversable[start]) return {};
  const float need = std::min(body_radius_m, g.clearance_m[start]);
  const float res = g.resolution_m;
  // Dijkstra over the cells the body fits in, bounded by max_length_m; the first traversable
  // cell popped is the nearest by path.
  std::vector<float> dist(g.cell_count(), std::numeric_limits<float>::infinity());
  std::vector<std::int64_t> from(g.cell_count(), -1);
  using Item = std::pair<float, std::size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  dist[start] = 0.0f;
  open.emplace(0.0f, start);
  std::int64_t found = -1;
  while (!open.empty()) {
    const auto [d, i] = open.top();
    open.pop();
    if (d > dist[i]) continue;
    if (g.traversable[i]) {
      found = static_cast<std::int64_t>(i);
      break;
    }
    const int x = static_cast<int>(i % static_cast<std::size_t>(g.width)), y = static_cast<int>(i / static_cast<std::size_t>(g.width));
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if ((dx == 0 && dy == 0) || !g.in_bounds(x + dx, y + dy)) continue;
        const std::size_t j = g.index(x + dx, y + dy);
        if (!(g.clearance_m[j] >= need) && !g.traversable[j]) continue;
        const float nd = d + res * (dx != 0 && dy != 0 ? std::numbers::sqrt2_v<float> : 1.0f);
        if (nd > max_length_m || !(nd < dist[j])) continue;
        dist[j] = nd;
        from[j] = static_cast<std::int64_t>(i);
        open.emplace(nd, j);
      }
  }
  std::vector<Eigen::Vector2f> path;
  for (std::int64_t i = found; i >= 0; i = from[static_cast<std::size_t>(i)]) path.push_back(g.cell_center(static_cast<std::size_t>(i)));
  std::reverse(path.begin(), path.end());
  return path;
}

std::optional<Twist> creep_along(const Pose2& robot, const Twist& current, std::span<const Eigen::Vector2f> path, const InflatedGrid& g,
                                 float body_radius_m, const DwaSettings& ds) {
  if (path.empty()) return std::nullopt;
  const Eigen::Vector2f here(robot.x, robot.y);
  if ((path.back() - here).norm() <= g.resolution_m) return std::nullopt;
  // The path point nearest the robot, then the first one at least 0.15 m beyond it (or the end).
  std::size_t k = 0;
  float best = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i < path.size(); ++i)
    if (const float d = (path[i] - here).squaredNorm(); d < best) {
      best = d;
      k = i;
    }
  constexpr float kLookahead = 0.15f, kSpeed = 0.1f;
  std::size_t a = k;
  while (a + 1 < path.size() && (path[a] - here).norm() < kLookahead) ++a;
  const Eigen::Vector2f to = path[a] - here;
  if (to.squaredNorm() == 0.0f) return std::nullopt;
  const float err = wrap_angle(std::atan2(to.y(), to.x()) - robot.theta);
  if (std::fabs(err) > 0.3f) return turn_in_place(err, current, ds);
  // Creep, steering towards the lookahead point (turn_in_place()'s rate, with the speed).
  const float v = std::min(kSpeed, std::max(0.0f, current.v) + ds.limits.max_accel_mps2 * ds.control_period_s);
  const float omega = turn_in_place(err, current, ds).omega;
  // Stop short of a cell the body does not fit in (never tighter than here): turn on the spot
  // towards the lookahead point instead.
  const float need = std::min(body_radius_m, clearance_at(g, here));
  const Eigen::Vector2f next = here + (v * ds.control_period_s + 0.5f * g.resolution_m) * Eigen::Vector2f(std::cos(robot.theta), std::sin(robot.theta));
  if (!(clearance_at(g, next) >= need)) {
    if (std::fabs(err) > 0.02f) return turn_in_place(err, current, ds);
    return std::nullopt;
  }
  return Twist{v, omega};
}

}  // namespace duet
