/// @file loop_closure.cpp
/// Submaps, loop search against the old map, pose-graph optimisation (see loop_closure.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/localization/loop_closure.hpp>

#include "mapping/cell_key.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

namespace duet {
namespace {

constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;

}  // namespace

void validate(const LoopClosureSettings& s) {
  auto bad = [](const std::string& what) { fail(ErrorCode::kInvalidArgument, "LoopClosureSettings::" + what); };
  auto pos = [&](double v, const char* name) {
    if (!(std::isfinite(v) && v > 0.0)) bad(std::string(name) + " must be > 0, got " + std::to_string(v));
  };
  auto nonneg = [&](double v, const char* name) {
    if (!(std::isfinite(v) && v >= 0.0)) bad(std::string(name) + " must be >= 0, got " + std::to_string(v));
  };
  if (!(std::isfinite(s.submap_duration_s) && s.submap_duration_s > 0.0 && s.submap_duration_s <= 3600.0))
    bad("submap_duration_s must be in (0, 3600] s, got " + std::to_string(s.submap_duration_s));
  pos(s.submap_travel_m, "submap_travel_m");
  pos(s.check_period_s, "check_period_s");
  pos(s.query_window_s, "query_window_s");
  nonneg(s.min_age_s, "min_age_s");
  pos(s.search_radius_m, "search_radius_m");
  if (s.max_query_points < 1) bad("max_query_points must be >= 1");
  validate(s.match);
  nonneg(s.confirm_m, "confirm_m");
  nonneg(s.confirm_deg, "confirm_deg");
  nonneg(s.min_correction_m, "min_correction_m");
  nonneg(s.min_correction_deg, "min_correction_deg");
  pos(s.odom_sigma_xy_m, "odom_sigma_xy_m");
  nonneg(s.odom_sigma_xy_per_m, "odom_sigma_xy_per_m");
  pos(s.odom_sigma_theta_deg, "odom_sigma_theta_deg");
  nonneg(s.odom_sigma_theta_per_m, "odom_sigma_theta_per_m");
  pos(s.loop_sigma_xy_m, "loop_sigma_xy_m");
  pos(s.loop_sigma_theta_deg, "loop_sigma_theta_deg");
  pos(s.max_loop_chi2, "max_loop_chi2");
  nonneg(s.verify_hit_m, "verify_hit_m");
  if (!(std::isfinite(s.verify_free_m) && s.verify_free_m >= s.verify_hit_m))
    bad("verify_free_m must be >= verify_hit_m, got " + std::to_string(s.verify_free_m));
  if (!(std::isfinite(s.min_prediction_conflict) && s.min_prediction_conflict >= 0.0f && s.min_prediction_conflict <= 1.0f))
    bad("min_prediction_conflict must be in [0, 1], got " + std::to_string(s.min_prediction_conflict));
  if (!(std::isfinite(s.prediction_check_min_shift_m) && s.prediction_check_min_shift_m >= 0.0f))
    bad("prediction_check_min_shift_m must be >= 0, got " + std::to_string(s.prediction_check_min_shift_m));
  if (!(std::isfinite(s.max_conflict_ratio) && s.max_conflict_ratio >= 0.0f))
    bad("max_conflict_ratio must be >= 0, got " + std::to_string(s.max_conflict_ratio));
  validate(s.graph);
}

LoopCloser::LoopCloser(const LoopClosureSettings& settings, const CellThresholds& cells, Mapper& mapper)
    : settings_((validate(settings), settings)), cells_((validate(cells), cells)) {
  mapper.keep_submaps();
}

std::optional<Pose2> LoopCloser::update(Mapper& mapper, const Pose2& at, double t) {
  if (!(std::isfinite(at.x) && std::isfinite(at.y) && std::isfinite(at.theta) && std::isfinite(t)))
    fail(ErrorCode::kInvalidArgument, "LoopCloser::update: the pose or the time is not finite");
  if (!mapper.keeps_submaps() || mapper.submaps().size() < nodes_.size())
    fail(ErrorCode::kInvalidArgument, "LoopCloser::update: not the mapper this loop closer was made with");
  const auto t0 = std::chrono::steady_clock::now();
  // 1. The open submap's node (at its first frames), joined to the previous node by the front end.
  if (last_at_) travel_m_ += std::hypot(at.x - last_at_->x, at.y - last_at_->y);
  last_at_ = at;
  if (nodes_.size() < mapper.submaps().size()) {
    if (!nodes_.empty()) {
      const float d = travel_m_;
      PoseGraphEdge e;
      e.from = static_cast<std::uint32_t>(nodes_.size() - 1);
      e.to = static_cast<std::uint32_t>(nodes_.size());
      e.measurement = compose(inverse(nodes_.back()), at);
      e.sigma_xy_m = settings_.odom_sigma_xy_m + settings_.odom_sigma_xy_per_m * d;
      e.sigma_theta_rad = (settings_.odom_sigma_theta_deg + settings_.odom_sigma_theta_per_m * d) * kDeg;
      edges_.push_back(e);
      closed_t_.back() = t;
    }
    nodes_.push_back(at);
    anchors_.push_back(at);
    closed_t_.push_back(std::numeric_limits<double>::infinity());
    opened_t_ = t;
    travel_m_ = 0.0f;
  }
  // 2. The query window: this update's obstacle points, one per cell (the first in order).
  if (!frozen_) {
    const float res = mapper.grid().resolution();
    cells_scratch_.clear();
    for (const Eigen::Vector2f& p : mapper.last_obstacles())
      if (p.allFinite()) cells_scratch_.emplace_back(cell_key(p.x(), p.y(), res), p);
    std::stable_sort(cells_scratch_.begin(), cells_scratch_.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    QueryScan scan{t, {}};
    for (std::size_t i = 0; i < cells_scratch_.size(); ++i)
      if (i == 0 || cells_scratch_[i].first != cells_scratch_[i - 1].first) scan.points.push_back(cells_scratch_[i].second);
    ring_.push_back(std::move(scan));
    while (!ring_.empty() && ring_.front().t < t - settings_.query_window_s) ring_.pop_front();
  }
  // 3. Loop search (none once the map is finished).
  std::optional<Pose2> shift;
  if (!frozen_ && t - last_check_t_ >= settings_.check_period_s) {
    last_check_t_ = t;
    Pose2 match;
    std::size_t old_node = 0;
    if (check(mapper, at, t, match, old_node)) {
      const Pose2 offset = compose(match, inverse(at));
      const bool agrees = pending_ && pending_->node == old_node &&
                          std::hypot(offset.x - pending_->offset.x, offset.y - pending_->offset.y) <= settings_.confirm_m &&
                          std::fabs(std::remainder(offset.theta - pending_->offset.theta, 2.0f * std::numbers::pi_v<float>)) <=
                              settings_.confirm_deg * kDeg;
      if (agrees) {
        ++stats_.confirmed;
        pending_.reset();
        shift = close(mapper, at, t, match, old_node);
      } else {
        pending_ = Pending{offset, old_node};
      }
    } else {
      pending_.reset();
    }
  }
  // 4. A new submap after its time or travel (or after a closure, which closes the open one).
  if (!frozen_ && !shift && (t - opened_t_ >= settings_.submap_duration_s || travel_m_ >= settings_.submap_travel_m))
    (void)mapper.open_submap();
  stats_.time_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return shift;
}

void LoopCloser::freeze(double t) {
  if (frozen_) return;
  frozen_ = true;
  stats_.frozen_at_s = t;
  pending_.reset();
  ring_.clear();
}

bool LoopCloser::beyond_min_correction(const Pose2& at, const Pose2& match) const {
  return std::hypot(match.x - at.x, match.y - at.y) > settings_.min_correction_m ||
         std::fabs(std::remainder(match.theta - at.theta, 2.0f * std::numbers::pi_v<float>)) > settings_.min_correction_deg * kDeg;
}

bool LoopCloser::check(Mapper& mapper, const Pose2& at, double t, Pose2& match, std::size_t& old_node) {
  const auto& submaps = mapper.submaps();
  // The old map around the robot.
  const auto tb = std::chrono::steady_clock::now();
  const float r = settings_.search_radius_m;
  reference_ = OccupancyGrid(mapper.grid().resolution());
  std::vector<std::size_t> used;
  for (std::size_t k = 0; k + 1 < nodes_.size() && k < submaps.size(); ++k) {
    if (!(closed_t_[k] <= t - settings_.min_age_s)) continue;
    // A closed submap's extent does not change: computed once.
    while (extents_.size() <= k) {
      Extent e;
      e.observed = observed_extent(submaps[extents_.size()].grid, e.lo, e.hi);
      extents_.push_back(e);
    }
    if (!extents_[k].observed) continue;
    const Eigen::Vector2f lo = extents_[k].lo, hi = extents_[k].hi;
    // The extent's placed bounding circle against the robot.
    const Eigen::Vector2f c = transform_point(submaps[k].placement, 0.5f * (lo + hi));
    const float rad = 0.5f * (hi - lo).norm();
    if ((c - Eigen::Vector2f(at.x, at.y)).norm() > r + rad) continue;
    accumulate_grid(reference_, submaps[k].grid, submaps[k].placement, mapper.settings().grid_update.min_logodds,
                    mapper.settings().grid_update.max_logodds);
    used.push_back(k);
  }
  if (used.empty()) return false;
  ++stats_.checks;
  // The query: the window's points in the robot frame, one per cell, thinned evenly.
  const Pose2 robot_from_map = inverse(at);
  const float res = mapper.grid().resolution();
  std::vector<std::pair<std::uint64_t, Eigen::Vector2f>>& cells = cells_scratch_;
  cells.clear();
  for (const QueryScan& s : ring_)
    for (const Eigen::Vector2f& p : s.points) cells.emplace_back(cell_key(p.x(), p.y(), res), p);
  std::stable_sort(cells.begin(), cells.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  cells.erase(std::unique(cells.begin(), cells.end(), [](const auto& a, const auto& b) { return a.first == b.first; }), cells.end());
  const std::size_t stride = (cells.size() + settings_.max_query_points - 1) / settings_.max_query_points;
  query_.clear();
  for (std::size_t k = 0; k < cells.size(); k += std::max<std::size_t>(stride, 1)) query_.push_back(transform_point(robot_from_map, cells[k].second));
  if (query_.size() < settings_.match.min_points) return false;
  const auto tc = std::chrono::steady_clock::now();
  occupied_distance(GridView(reference_), cells_, distance_);
  const auto td = std::chrono::steady_clock::now();
  const ScanMatchResult res_match = scan_match(distance_.clearance(), query_, at, settings_.match);
  stats_.compose_time_s += std::chrono::duration<double>(tc - tb).count();
  stats_.distance_time_s += std::chrono::duration<double>(td - tc).count();
  stats_.match_time_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - td).count();
  if (res_match.status != ScanMatchStatus::kMatched) return false;
  // A best candidate on the window's edge wants to go further: not a peak.
  const Pose2 off = compose(inverse(at), res_match.pose);
  const ScanMatchSettings& ms = settings_.match;
  if (std::fabs(off.x) >= ms.linear_window_m - 0.5f * ms.linear_step_m || std::fabs(off.y) >= ms.linear_window_m - 0.5f * ms.linear_step_m ||
      std::fabs(off.theta) >= (ms.angular_window_deg - 0.5f * ms.angular_step_deg) * kDeg) {
    ++stats_.rejected_edge;
    return false;
  }
  // Free-space check: the likelihood field only rewards points near walls; a wrong alignment that
  // lays a new wall on an old one can score high while other points fall in the old map's open
  // floor. Points near an old wall count for the match, points on known free floor against it.
  std::size_t hits = 0, conflicts = 0;
  for (const Eigen::Vector2f& q : query_) {
    const Eigen::Vector2f p = transform_point(res_match.pose, q);
    Eigen::Vector2i cell;
    if (!distance_.cell_of(p, cell)) continue;
    const std::size_t i = distance_.index(cell.x(), cell.y());
    if (distance_.clearance_m[i] <= settings_.verify_hit_m)
      ++hits;
    else if (distance_.state[i] == CellState::kFree && distance_.clearance_m[i] > settings_.verify_free_m)
      ++conflicts;
  }
  if (hits < settings_.min_hits || static_cast<float>(conflicts) > settings_.max_conflict_ratio * static_cast<float>(hits)) {
    ++stats_.rejected_free_space;
    return false;
  }
  // The prediction must be contradicted by the old map for a correction to be believed: query
  // points that, at the predicted pose, lie on old free floor farther from any old wall than
  // half the correction (a drift of d puts a wall's points about d off it). A prediction whose
  // points fall on old walls or on cells the old map never saw is not wrong; a lattice pose
  // that lays the new walls on old ones elsewhere then is an alias (a shelf's or a door's
  // repeat), not a loop.
  // The correction's mean shift of the query's points (a turn moves far points more).
  float shift = 0.0f;
  for (const Eigen::Vector2f& q : query_) shift += (transform_point(off, q) - q).norm();
  shift = query_.empty() ? 0.0f : shift / static_cast<float>(query_.size());
  {
    const float d = std::hypot(off.x, off.y);
    const float near_m = std::max(settings_.verify_hit_m, 0.5f * d);
    std::size_t contradicted = 0;
    for (const Eigen::Vector2f& q : query_) {
      const Eigen::Vector2f p = transform_point(at, q);
      Eigen::Vector2i cell;
      if (!distance_.cell_of(p, cell)) continue;
      const std::size_t i = distance_.index(cell.x(), cell.y());
      if (distance_.state[i] == CellState::kFree && distance_.clearance_m[i] > near_m) ++contradicted;
    }
    last_prior_conflict_ = query_.empty() ? 0.0f : static_cast<float>(contradicted) / static_cast<float>(query_.size());
  }
  const bool moves_map = beyond_min_correction(at, res_match.pose);
  const bool unexplained = moves_map && shift >= settings_.prediction_check_min_shift_m && settings_.min_prediction_conflict > 0.0f &&
                           last_prior_conflict_ < settings_.min_prediction_conflict;
  matches_.push_back({t, off, res_match.score, res_match.prior_score, last_prior_conflict_, shift, moves_map, !unexplained});
  if (unexplained) {
    ++stats_.rejected_unexplained;
    return false;
  }
  ++stats_.matches;
  match = res_match.pose;
  last_score_ = res_match.score;
  last_prior_score_ = res_match.prior_score;
  // The old submap holding most matched points (occupied there, at its placement).
  std::size_t best = used.front(), best_count = 0;
  for (const std::size_t k : used) {
    const Submap& sm = submaps[k];
    const Pose2 to_sub = inverse(sm.placement);
    std::size_t count = 0;
    for (const Eigen::Vector2f& q : query_) {
      const Eigen::Vector2f p = transform_point(to_sub, transform_point(match, q));
      const Eigen::Vector2i c = sm.grid.cell_of(p);
      if (sm.grid.in_bounds(c.x(), c.y()) && classify(sm.grid.at(c.x(), c.y()), cells_) == CellState::kOccupied) ++count;
    }
    if (count > best_count) {
      best_count = count;
      best = k;
    }
  }
  if (best_count == 0) return false;
  old_node = best;
  return true;
}

std::optional<Pose2> LoopCloser::close(Mapper& mapper, const Pose2& at, double t, const Pose2& match, std::size_t old_node) {
  const std::size_t c = nodes_.size() - 1;  // the open submap's node; its content is in the current frame
  const Submap& old = mapper.submaps()[old_node];
  // The robot in the old submap's integration frame, relative to its node; and relative to the open node.
  const Pose2 q = compose(inverse(old.placement), match);
  const Pose2 rel_old = compose(inverse(anchors_[old_node]), q);
  const Pose2 rel_open = compose(inverse(nodes_[c]), at);
  PoseGraphEdge e;
  e.from = static_cast<std::uint32_t>(old_node);
  e.to = static_cast<std::uint32_t>(c);
  e.measurement = compose(rel_old, inverse(rel_open));
  e.sigma_xy_m = settings_.loop_sigma_xy_m;
  e.sigma_theta_rad = settings_.loop_sigma_theta_deg * kDeg;
  e.robust = true;
  edges_.push_back(e);
  const bool big = beyond_min_correction(at, match);
  if (!big) return std::nullopt;
  std::vector<Pose2> x = nodes_;
  PoseGraphSettings gs = settings_.graph;
  gs.fixed_node = 0;
  (void)optimize_pose_graph(x, edges_, gs);
  if (pose_graph_edge_chi2(x, e) > settings_.max_loop_chi2) {
    edges_.pop_back();
    ++stats_.rejected_inconsistent;
    return std::nullopt;
  }
  nodes_ = x;
  std::vector<Pose2> placements(mapper.submaps().size());
  for (std::size_t k = 0; k < placements.size(); ++k)
    placements[k] = k < nodes_.size() ? compose(nodes_[k], inverse(anchors_[k])) : mapper.submaps()[k].placement;
  mapper.place_submaps(placements);
  const Pose2 shift = placements[c];  // the open submap's content (the current frame) moves by this
  for (QueryScan& s : ring_)
    for (Eigen::Vector2f& p : s.points) p = transform_point(shift, p);
  last_at_ = compose(shift, at);
  (void)mapper.open_submap();
  ++stats_.closures;
  const float moved = std::hypot(last_at_->x - at.x, last_at_->y - at.y);
  stats_.max_shift_m = std::max(stats_.max_shift_m, moved);
  events_.push_back({t, old_node, c, shift, moved, last_score_, last_prior_score_});
  return shift;
}

}  // namespace duet
