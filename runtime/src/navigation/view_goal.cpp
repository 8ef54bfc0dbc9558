/// @file view_goal.cpp
/// View goals (see view_goal.hpp).
#include <duet/runtime/navigation/view_goal.hpp>

#include <cmath>
#include <limits>
#include <numbers>

namespace duet {

ViewGoal::ViewGoal(const Profile& profile, const ExplorerSettings& settings)
    : GoalStrategy(settings.blacklist_ttl_s), frontier_(profile.exploration.strategy.frontier), settings_(settings) {}

void ViewGoal::goal_ended(const GoalEnd& end) {
  // Reached (looked from) or not reachable: either way the frontier cell is not looked for again.
  viewed_.add(target_, end.now_s, std::numeric_limits<double>::infinity());
  if (end.reached) ++end.stats.view_goals_reached;
}

void ViewGoal::shift(const Pose2& D) { target_ = transform_point(D, target_); }

std::optional<GoalProposal> ViewGoal::propose(GoalQuery& q) {
  const ExplorationDecision& d = q.decision;
  if (!(settings_.view_range_m > 0.0f) ||
      (d.status != ExplorationStatus::kAllUnreachable && d.status != ExplorationStatus::kAllBlacklisted))
    return std::nullopt;
  // A fresh search on the planning grid: a relaxed one (if it ran) searched another grid.
  const InflatedGrid& g = q.planning;
  const FrontierResult f = find_frontier(g, Eigen::Vector2f(q.robot.x, q.robot.y), q.blacklist, q.now_s, frontier_, ws_);
  if (f.status != FrontierStatus::kAllUnreachable && f.status != FrontierStatus::kAllBlacklisted &&
      f.status != FrontierStatus::kFound)
    return std::nullopt;  // no frontier, or the robot blocked: the search's distances were not computed
  const GridView geometry = q.model.grid();  // the latest map: the geometry of the planning grid
  const std::vector<std::uint8_t>& mask = ws_.mask;
  const std::vector<float>& dist = ws_.dist;
  const float rmin = settings_.view_min_range_m, rmax = settings_.view_range_m;
  std::vector<Eigen::Vector2f> dirs(static_cast<std::size_t>(settings_.view_rays));
  for (std::size_t r = 0; r < dirs.size(); ++r) {
    const float a = 2.0f * std::numbers::pi_v<float> * static_cast<float>(r) / static_cast<float>(dirs.size());
    dirs[r] = Eigen::Vector2f(std::cos(a), std::sin(a));
  }
  float best_len = std::numeric_limits<float>::infinity();
  std::size_t best_cell = 0, best_target = 0;
  const std::size_t n = g.cell_count();
  for (std::size_t i = 0; i < n && i < mask.size(); ++i) {
    if (mask[i] != 1) continue;  // frontier cells of kept clusters
    // A frontier cell the robot can reach is the frontier search's business (too near, or
    // blacklisted: it was stood at and looked at).
    if (std::isfinite(dist[i])) continue;
    const Eigen::Vector2f target = g.cell_center(i);
    if (q.blacklist.blocks(target, frontier_.blacklist_radius_m, q.now_s) || viewed_.blocks(target, frontier_.blacklist_radius_m, q.now_s))
      continue;
    for (const Eigen::Vector2f& dir : dirs) {
      // Along the line of sight, through known-free cells only, the first cell the robot can
      // stand on beyond the minimum range.
      walk_cells(geometry, target, dir, 0.0f, rmax, [&](int ix, int iy, float t_enter, float) {
        if (!g.in_bounds(ix, iy)) return false;
        const std::size_t c = g.index(ix, iy);
        if (g.state[c] != CellState::kFree) return false;
        if (t_enter < rmin || !std::isfinite(dist[c]) || dist[c] >= best_len || !q.can_stand_on(ix, iy)) return true;
        best_len = dist[c];
        best_cell = c;
        best_target = i;
        return false;
      });
    }
  }
  if (!std::isfinite(best_len)) return std::nullopt;
  const Eigen::Vector2f at = g.cell_center(best_cell), target = g.cell_center(best_target);
  target_ = target;
  if (!q.log.empty()) {
    q.log.back().view = true;
    q.log.back().view_target = target;
  }
  return GoalProposal{Pose2{at.x(), at.y(), std::atan2(target.y() - at.y(), target.x() - at.x())}, GoalKind::kView, target};
}

}  // namespace duet
