/// @file unexplored.cpp
/// find_unexplored() and describe() (see unexplored.hpp).
#include <duet/kernels/bottleneck.hpp>
#include <duet/runtime/navigation/unexplored.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>

namespace duet {

const char* to_string(LeftWhy w) {
  switch (w) {
    case LeftWhy::kReachable: return "reachable";
    case LeftWhy::kAbandoned: return "abandoned";
    case LeftWhy::kLookedAt: return "looked_at";
    case LeftWhy::kNarrowGap: return "narrow_gap";
    case LeftWhy::kNoKnownWay: return "no_known_way";
  }
  return "?";
}

std::vector<UnexploredRegion> find_unexplored(const InflatedGrid& g, const Eigen::Vector2f& robot_xy,
                                              std::span<const Eigen::Vector2f> frontier, std::span<const GoalFailures> failures,
                                              std::span<const Eigen::Vector2f> looked_at, const UnexploredSettings& s) {
  std::vector<UnexploredRegion> out;
  const std::size_t n = g.cell_count();
  if (frontier.empty() || n == 0) return out;
  std::vector<std::uint8_t> mark(n, 0);  // 1 frontier, 2 frontier already in a region
  for (const Eigen::Vector2f& p : frontier) {
    if (!p.allFinite()) continue;
    const Eigen::Vector2i c = g.cell_of(p);
    if (g.in_bounds(c.x(), c.y())) mark[g.index(c.x(), c.y())] = 1;
  }
  std::vector<float> passage;
  widest_passage(g, robot_xy, passage);
  // As the frontier search (frontier.hpp): a region is reached at one of its own cells, or - with
  // approach_radius_m > 0 - at a free cell within that distance of one, through free cells.
  const float approach2 = s.approach_radius_m * s.approach_radius_m;
  const float r2 = s.blacklist_radius_m * s.blacklist_radius_m;
  std::vector<std::uint8_t> seen(s.approach_radius_m > 0.0f ? n : 0, 0);
  std::vector<std::uint32_t> ring;
  std::vector<std::uint32_t> stack, cells;
  for (std::size_t seed = 0; seed < n; ++seed) {
    if (mark[seed] != 1) continue;
    cells.clear();
    stack.assign(1, static_cast<std::uint32_t>(seed));
    mark[seed] = 2;
    while (!stack.empty()) {
      const std::uint32_t c = stack.back();
      stack.pop_back();
      cells.push_back(c);
      const int x = static_cast<int>(c % static_cast<std::uint32_t>(g.width)), y = static_cast<int>(c / static_cast<std::uint32_t>(g.width));
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (!g.in_bounds(x + dx, y + dy)) continue;
          const std::size_t k = g.index(x + dx, y + dy);
          if (mark[k] == 1) {
            mark[k] = 2;
            stack.push_back(static_cast<std::uint32_t>(k));
          }
        }
    }
    if (static_cast<int>(cells.size()) < s.min_cells) continue;
    UnexploredRegion r;
    r.cells = static_cast<int>(cells.size());
    r.length_m = static_cast<float>(cells.size()) * g.resolution_m;
    r.needed_m = 2.0f * g.robot_radius_m;
    float best = 0.0f, nearest_d = std::numeric_limits<float>::infinity();
    Eigen::Vector2d sum(0.0, 0.0);
    std::vector<std::uint8_t> counted(failures.size(), 0);
    for (const std::uint32_t c : cells) {
      const Eigen::Vector2f p = g.cell_center(static_cast<std::size_t>(c));
      sum += p.cast<double>();
      const float d = (p - robot_xy).squaredNorm();
      if (d < nearest_d) {
        nearest_d = d;
        r.nearest = p;
      }
      for (std::size_t f = 0; f < failures.size(); ++f)
        if (!counted[f] && (failures[f].xy - p).squaredNorm() <= r2) {
          counted[f] = 1;
          r.failures += failures[f].count;
        }
      if (!r.looked_at)
        for (const Eigen::Vector2f& l : looked_at)
          if ((l - p).squaredNorm() <= r2) r.looked_at = true;
    }
    for (const std::uint32_t c : cells) best = std::max(best, passage[c]);
    if (!seen.empty()) {  // breadth-first from each cell through free cells, within the radius
      for (const std::uint32_t src : cells) {
        const Eigen::Vector2f o = g.cell_center(static_cast<std::size_t>(src));
        ring.assign(1, src);
        seen[src] = 1;
        for (std::size_t head = 0; head < ring.size(); ++head) {
          const std::uint32_t c = ring[head];
          best = std::max(best, passage[c]);
          const int x = static_cast<int>(c % static_cast<std::uint32_t>(g.width)), y = static_cast<int>(c / static_cast<std::uint32_t>(g.width));
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              if (!g.in_bounds(x + dx, y + dy)) continue;
              const std::size_t k = g.index(x + dx, y + dy);
              if (seen[k] || g.state[k] != CellState::kFree || (g.cell_center(k) - o).squaredNorm() > approach2) continue;
              seen[k] = 1;
              ring.push_back(static_cast<std::uint32_t>(k));
            }
        }
        for (const std::uint32_t c : ring) seen[c] = 0;
      }
    }
    r.centroid = (sum / static_cast<double>(cells.size())).cast<float>();
    // Clearance is measured centre to centre: a passage of k free cells has a middle cell (k+1)/2
    // cells from the walls, so its width is 2 * clearance - one cell (exact for odd k, one cell
    // short for even k).
    r.gap_m = !std::isfinite(best) ? std::numeric_limits<float>::infinity() : best > 0.0f ? 2.0f * best - g.resolution_m : 0.0f;
    if (best > g.robot_radius_m) r.why = r.looked_at ? LeftWhy::kLookedAt : r.failures > 0 ? LeftWhy::kAbandoned : LeftWhy::kReachable;
    else if (best > 0.0f) r.why = LeftWhy::kNarrowGap;
    else r.why = LeftWhy::kNoKnownWay;
    out.push_back(r);
  }
  std::stable_sort(out.begin(), out.end(), [](const UnexploredRegion& a, const UnexploredRegion& b) { return a.cells > b.cells; });
  return out;
}

std::string describe(std::span<const UnexploredRegion> regions, std::size_t max_listed) {
  if (regions.empty()) return {};
  std::string s = std::to_string(regions.size()) + (regions.size() == 1 ? " region left: " : " regions left: ");
  char buf[256];
  for (std::size_t i = 0; i < regions.size() && i < max_listed; ++i) {
    const UnexploredRegion& r = regions[i];
    std::snprintf(buf, sizeof buf, "%s%d frontier cells (%.1f m) at (%.1f, %.1f) ", i ? "; " : "", r.cells, r.length_m, r.centroid.x(),
                  r.centroid.y());
    s += buf;
    switch (r.why) {
      case LeftWhy::kReachable: s += "still reachable"; break;
      case LeftWhy::kAbandoned:
        std::snprintf(buf, sizeof buf, "abandoned after %d failed goal%s", r.failures, r.failures == 1 ? "" : "s");
        s += buf;
        break;
      case LeftWhy::kLookedAt: s += "looked at, not observable from where the robot can stand"; break;
      case LeftWhy::kNarrowGap:
        std::snprintf(buf, sizeof buf, "unreachable through a gap of %.2f m (the robot needs %.2f m)", r.gap_m, r.needed_m);
        s += buf;
        break;
      case LeftWhy::kNoKnownWay: s += "unreachable: no known free way to it (seen across unknown space or over an obstacle)"; break;
    }
    if (r.looked_at && r.why != LeftWhy::kLookedAt) s += ", looked at from a view goal";
    if (r.why != LeftWhy::kAbandoned && r.failures > 0) {
      std::snprintf(buf, sizeof buf, ", %d failed goal%s there", r.failures, r.failures == 1 ? "" : "s");
      s += buf;
    }
  }
  if (regions.size() > max_listed) s += "; and " + std::to_string(regions.size() - max_listed) + " more";
  return s;
}

}  // namespace duet
