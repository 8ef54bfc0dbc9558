/// @file view_goal.cpp
/// View goals (see view_goal.hpp).
#include <duet/runtime/navigation/view_goal.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace duet {

ViewGoal::ViewGoal(const Profile& profile, const ExplorerSettings& settings)
    : GoalStrategy(settings),
      frontier_(profile.exploration.strategy.frontier),
      settings_(settings),
      cells_(profile.exploration.cells),
      budget_(settings.view_min_gain_m2, settings.view_gain_window_s) {}

void ViewGoal::map_updated(const GridView& latest, bool) {
  if (dwell_max_s_ < 0.0) return;
  // Free cells within 2 m of what the robot looks at: more than at the last update = the view
  // is still changing (a door opened since the first look clears a few cells per update).
  constexpr float kRadius = 2.0f;
  const float res = latest.resolution_m;
  const int r = static_cast<int>(std::ceil(kRadius / res));
  const int cx = static_cast<int>(std::floor((target_.x() - latest.origin.x()) / res));
  const int cy = static_cast<int>(std::floor((target_.y() - latest.origin.y()) / res));
  std::size_t free = 0;
  for (int y = cy - r; y <= cy + r; ++y)
    for (int x = cx - r; x <= cx + r; ++x)
      if (latest.in_bounds(x, y) && (x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r &&
          classify(latest.logodds[latest.index(x, y)], cells_) == CellState::kFree)
        ++free;
  dwell_changed_ = free > dwell_free_;
  dwell_free_ = free;
}

const ViewGoal::Look* ViewGoal::look_near(const Eigen::Vector2f& p) const {
  const float r2 = frontier_.blacklist_radius_m * frontier_.blacklist_radius_m;
  for (const Look& l : looks_)
    if ((l.xy - p).squaredNorm() <= r2) return &l;
  return nullptr;
}

void ViewGoal::goal_ended(const GoalEnd& end) {
  // Reached (looked from) or not reachable: either way a look at that place.
  if (const Look* l = look_near(target_)) {
    Look& m = looks_[static_cast<std::size_t>(l - looks_.data())];
    ++m.count;
    m.last_s = end.now_s;
    if (end.reached && settings_.view_relook_dwell_s > 0.0f) {  // a look again: look on while the view changes
      dwell_max_s_ = end.now_s + settings_.view_relook_dwell_s;
      dwell_until_s_ = std::min(dwell_max_s_, end.now_s + 3.0);
      dwell_free_ = 0;
      dwell_changed_ = false;
    }
  } else {
    looks_.push_back(Look{target_, 1, end.now_s});
  }
  if (end.reached) ++end.stats.view_goals_reached;
}

void ViewGoal::shift(const Pose2& D) {
  target_ = transform_point(D, target_);
  for (Look& l : looks_) l.xy = transform_point(D, l.xy);  // what was looked at moves with the map frame
}

std::vector<Eigen::Vector2f> ViewGoal::looked_at() const {
  std::vector<Eigen::Vector2f> out;
  for (const Look& l : looks_) out.push_back(l.xy);
  return out;
}

namespace {
std::size_t known_cells(const GridView& g, const CellThresholds& t) {
  std::size_t n = 0;
  for (const float l : g.logodds) n += classify(l, t) != CellState::kUnknown ? 1 : 0;
  return n;
}
}  // namespace

std::optional<GoalProposal> ViewGoal::propose(GoalQuery& q) {
  const ExplorationDecision& d = q.decision;
  if (d.status != ExplorationStatus::kAllUnreachable && d.status != ExplorationStatus::kAllBlacklisted) {
    budget_.frontier_reachable();  // a reachable frontier (or none at all): the looking-only phase is over
    return std::nullopt;
  }
  if (!(settings_.view_range_m > 0.0f)) return std::nullopt;
  const double cell_m2 = static_cast<double>(q.latest.resolution_m) * static_cast<double>(q.latest.resolution_m);
  const std::size_t known = budget_.counts_at(q.now_s) ? known_cells(q.latest, cells_) : 0;
  if (!budget_.allows(q.now_s, known, cell_m2)) return std::nullopt;
  if (dwell_max_s_ >= 0.0) {  // looking on from where the robot looked again
    if (dwell_changed_) dwell_until_s_ = std::min(dwell_max_s_, q.now_s + 3.0);
    dwell_changed_ = false;
    if (q.now_s < dwell_until_s_) {
      q.later = true;
      return std::nullopt;
    }
    dwell_max_s_ = -1.0;
  }
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
  // Rank (first looks): path length to the view cell minus view_frontier_weight x the length of
  // the frontier the place belongs to (its cluster); looks again: path length alone.
  float best_score = std::numeric_limits<float>::infinity();
  std::size_t best_cell = 0, best_target = 0;
  const std::size_t n = g.cell_count();
  // Pass 0: places not looked at yet. Pass 1 (only if pass 0 found none): places looked at fewer
  // than view_looks times, the last at least view_relook_after_s ago.
  bool too_soon = false;
  for (int pass = 0; pass < 2 && !std::isfinite(best_score); ++pass)
  for (std::size_t i = 0; i < n && i < mask.size(); ++i) {
    if (mask[i] != 1) continue;  // frontier cells of kept clusters
    // A frontier cell the robot can reach is the frontier search's business (too near, or
    // blacklisted: it was stood at and looked at).
    if (std::isfinite(dist[i])) continue;
    const Eigen::Vector2f target = g.cell_center(i);
    if (q.blacklist.blocks(target, frontier_.blacklist_radius_m, q.now_s)) continue;
    if (const Look* l = look_near(target)) {
      if (pass == 0 || l->count >= settings_.view_looks) continue;
      if (q.now_s - l->last_s < settings_.view_relook_after_s) {
        too_soon = true;  // a look again later, unless a goal turns up now
        continue;
      }
    }
    const std::int32_t k = ws_.label[i];
    const float frontier_m = k >= 0 && static_cast<std::size_t>(k) < f.clusters.size()
                                 ? static_cast<float>(f.clusters[static_cast<std::size_t>(k)].cells) * g.resolution_m
                                 : g.resolution_m;
    // A look again (pass 1) is for what may have changed since (a door): the nearest first.
    const float bonus = pass == 0 ? settings_.view_frontier_weight * frontier_m : 0.0f;
    for (const Eigen::Vector2f& dir : dirs) {
      // Along the line of sight, through known-free cells only, the first cell the robot can
      // stand on beyond the minimum range.
      walk_cells(geometry, target, dir, 0.0f, rmax, [&](int ix, int iy, float t_enter, float) {
        if (!g.in_bounds(ix, iy)) return false;
        const std::size_t c = g.index(ix, iy);
        if (g.state[c] != CellState::kFree) return false;
        if (t_enter < rmin || !std::isfinite(dist[c]) || dist[c] - bonus >= best_score || !q.can_stand_on(ix, iy)) return true;
        best_score = dist[c] - bonus;
        best_cell = c;
        best_target = i;
        return false;
      });
    }
  }
  if (!std::isfinite(best_score)) {
    q.later = q.later || too_soon;
    return std::nullopt;
  }
  const Eigen::Vector2f at = g.cell_center(best_cell), target = g.cell_center(best_target);
  target_ = target;
  if (!q.log.empty()) {
    q.log.back().view = true;
    q.log.back().view_target = target;
  }
  return GoalProposal{Pose2{at.x(), at.y(), std::atan2(target.y() - at.y(), target.x() - at.x())}, GoalKind::kView, target};
}

}  // namespace duet
