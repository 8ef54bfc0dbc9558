/// @file navigator.cpp
/// Navigator: costmaps, goal life cycle, global path (see navigator.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/navigation/blocked_escape.hpp>
#include <duet/runtime/navigation/navigator.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>

namespace duet {

namespace {
/// The dynamic window's inflation: unknown cells are obstacles (an RGB-D sensor sees nothing
/// nearer than its minimum range: driving into unknown space near the robot is driving blind).
InflationSettings local_inflation(InflationSettings s) {
  s.unknown_is_obstacle = true;
  return s;
}

bool same_geometry(const GridView& a, const GridView& b) {
  return a.width == b.width && a.height == b.height && a.resolution_m == b.resolution_m &&
         a.origin.x() == b.origin.x() && a.origin.y() == b.origin.y();
}
}  // namespace

NavPlanView NavSnapshot::view() const {
  NavPlanView v;
  static_cast<NavPlanState&>(v) = *this;
  v.goal = goal ? &*goal : nullptr;
  v.path = path;
  v.local = &local;
  v.planning = &planning;
  return v;
}

Navigator::Navigator(const Profile& profile, const ExplorerSettings& settings)
    : Navigator(profile, settings, make_goal_strategies(profile, settings)) {}

Navigator::Navigator(const Profile& profile, const ExplorerSettings& settings, std::vector<std::unique_ptr<GoalStrategy>> strategies)
    : profile_(profile), settings_(settings), sectors_(observation_sectors(profile)), model_(profile.exploration.observation),
      planning_costmap_(profile.exploration.inflation, {}),
      local_costmap_(local_inflation(profile.exploration.inflation), {}),
      strategies_(std::move(strategies)) {
  const float occupied = std::max(profile_.exploration.cells.occupied_logodds, profile_.mapping.grid_update.max_logodds);
  const float free = std::min(profile_.exploration.cells.free_logodds, profile_.mapping.grid_update.min_logodds);
  auto contacts = std::make_unique<ContactLayer>(settings_.contact_radius_m, occupied);
  auto recent = std::make_unique<RecentObstacleLayer>(profile_.exploration.cells.occupied_logodds, occupied);
  auto trail = std::make_unique<TrailLayer>(profile_.chassis.radius_m,
                                            profile_.exploration.dwa.robot_radius_m + profile_.exploration.dwa.safety_margin_m, free);
  auto footprint = std::make_unique<FootprintLayer>(profile_.chassis.radius_m, profile_.exploration.cells.occupied_logodds, free);
  contacts_ = contacts.get();
  recent_ = recent.get();
  trail_ = trail.get();
  footprint_ = footprint.get();
  planning_costmap_.add(std::move(footprint));  // first: a contact the robot felt stays one
  planning_costmap_.add(std::move(contacts));
  local_costmap_.add(std::move(recent));
  local_costmap_.add(std::move(trail));
  if (strategies_.empty()) fail(ErrorCode::kInvalidArgument, "Navigator: no goal strategy");
  for (const auto& st : strategies_)
    if (!st) fail(ErrorCode::kInvalidArgument, "Navigator: a goal strategy is null");
  validate(settings_);
  validate(profile_.exploration.strategy);
  validate(profile_.exploration.dwa);
  validate(profile_.exploration.path);
  validate(profile_.exploration.inflation);
}

NavPlanState Navigator::plan_state() const {
  NavPlanState p;
  p.state = state_;
  p.have_map = have_map_;
  p.wait_for_map = wait_for_map_;
  p.blocked = blocked_since_s_ >= 0.0 && !goal_ && state_ == ExplorerState::kExploring;
  p.handoff_m = goal_ && handoff_ ? settings_.simulated_goal_handoff_m : 0.0f;
  p.goal_id = goal_id_;
  p.deadline_s = goal_deadline_s_;
  p.dwa = dwa_settings();
  return p;
}

NavPlanView Navigator::view() const {
  NavPlanView v;
  static_cast<NavPlanState&>(v) = plan_state();
  v.goal = goal_ ? &*goal_ : nullptr;
  v.path = path_;
  v.local = &local_grid();
  v.planning = &planning_grid();
  return v;
}

NavSnapshot Navigator::snapshot() const {
  NavSnapshot s;
  static_cast<NavPlanState&>(s) = plan_state();
  s.stop_status = stop_status_;
  s.stop_detail = stop_detail_;
  s.left = left_;
  s.goal = goal_;
  s.path = path_;
  s.local = local_grid();
  s.planning = planning_grid();
  return s;
}

void Navigator::add_trail(const Eigen::Vector2f& here) { trail_->add(here); }

void Navigator::add_layer(CostmapKind costmap, std::unique_ptr<CostmapLayer> layer) {
  (costmap == CostmapKind::kPlanning ? planning_costmap_ : local_costmap_).add(std::move(layer));
}

void Navigator::stall(const Eigen::Vector2f& contact, double now_s) {
  contacts_->add(contact);
  ++stats_.stalls;
  if (goal_) abandon_goal(stats_.goals_abandoned_stuck, now_s);
  wait_for_map_ = true;  // decide again once the grids hold the contact
}

void Navigator::goal_reached(std::uint64_t goal_id, double now_s) {
  if (!goal_ || goal_id != goal_id_) return;
  if (returning_) {
    drop_goal();
    state_ = ExplorerState::kDone;
    stop_detail_ += "; returned home";
    return;
  }
  if (state_ == ExplorerState::kPatrolling) {
    drop_goal();
    patrol_goal_ended(true);
    return;
  }
  ++stats_.goals_reached;
  if (GoalStrategy* by = active()) by->goal_ended(GoalEnd{true, now_s, goal_target_, decision_, blacklist_, stats_});
  drop_goal();
}

void Navigator::abandon(std::uint64_t goal_id, AbandonReason why, double now_s) {
  if (!goal_ || goal_id != goal_id_) return;
  abandon_goal(why == AbandonReason::kTimeout ? stats_.goals_abandoned_timeout : stats_.goals_abandoned_stuck, now_s);
}

void Navigator::set_recent_obstacles(std::span<const Eigen::Vector2f> points) { recent_->set(points); }

void Navigator::shift(const Pose2& D) {
  if (!(std::isfinite(D.x) && std::isfinite(D.y) && std::isfinite(D.theta)))
    fail(ErrorCode::kInvalidArgument, "Navigator::shift: the shift is not finite");
  auto move = [&](Eigen::Vector2f& p) { p = transform_point(D, p); };
  for (Eigen::Vector2f& p : path_) move(p);
  move(goal_target_);
  if (goal_frontier_) move(*goal_frontier_);
  planning_costmap_.shift(D);
  local_costmap_.shift(D);
  for (const auto& st : strategies_) st->shift(D);
  for (Eigen::Vector2f& p : patrol_) move(p);
  for (GoalFailures& f : failures_) move(f.xy);
  for (UnexploredRegion& r : left_) {
    move(r.centroid);
    move(r.nearest);
  }
  if (goal_) goal_ = compose(D, *goal_);
}


void Navigator::update_map(const OccupancyGrid& grid, const Pose2& robot, double now_s) {
  const GridView view(grid);
  if (model_geometry_valid_ && same_geometry(model_.grid(), view)) {
    (void)model_.update_grid(view);
  } else {
    model_.set_grid(view);
    model_geometry_valid_ = true;
  }
  // The robot stands where it is: map obstacles under its estimated body are not obstacles for
  // the planner and the dynamic window (the layer is active only when there are some).
  const Eigen::Vector2f here(robot.x, robot.y);
  footprint_->reset();
  if (settings_.clear_footprint && footprint_->occupied_under(grid, here) > 0) {
    footprint_->set(here);
    ++stats_.footprint_clearings;
  }
  // Planning and driving see the contact obstacles too (the observation model keeps the map).
  const OccupancyGrid& planning_map = planning_costmap_.update(grid);
  const GridView latest = latest_map();
  for (std::size_t i = 0; i < strategies_.size(); ++i) strategies_[i]->map_updated(latest, i == active_);
  // The recent obstacles block only the dynamic window: where the pose has moved since a place
  // was mapped, the map's copy of a wall and the recent one narrow a door between them, and
  // planning on both can close doors for good (every frontier unreachable; bench/RESULTS.md).
  (void)local_costmap_.update(planning_map);
  if (recent_->active()) stats_.recent_obstacle_cells += recent_->cells_marked();
  have_map_ = true;
  if (state_ == ExplorerState::kIdle) state_ = ExplorerState::kExploring;
  wait_for_map_ = false;  // a decision that found nothing may try again on the new map
  if (goal_ && goal_frontier_ && frontier_seen()) {
    // Its frontier was seen on the way: nothing new to see there; the next decision follows now.
    ++stats_.frontier_goals_seen;
    drop_goal();
  }
  if (goal_) {
    // The goal cell became an obstacle (or its inflation, or the margin of unknown cells) and no
    // cell near it will do: abandon; else re-plan on the new map.
    if (!recheck_goal()) {
      abandon_goal(stats_.goals_abandoned_blocked, now_s);
    } else if (plan(robot)) {
      ++stats_.replans;
    } else {
      abandon_goal(stats_.goals_abandoned_no_path, now_s);
    }
  }
}

GridView Navigator::latest_map() const {
  return planning_costmap_.layered() ? GridView(planning_costmap_.grid()) : model_.grid();
}

GoalStrategy* Navigator::active() const { return active_ < strategies_.size() ? strategies_[active_].get() : nullptr; }

const InflatedGrid& Navigator::planning_grid() const noexcept {
  const GoalStrategy* by = active();
  const InflatedGrid* own = by ? by->planning_grid() : nullptr;
  return own ? *own : inflated();
}

bool Navigator::plan(const Pose2& robot) {
  const PathResult r = plan_path(planning_grid(), Eigen::Vector2f(robot.x, robot.y), Eigen::Vector2f(goal_->x, goal_->y),
                                 profile_.exploration.path, path_ws_);
  if (r.status != PathStatus::kFound) return false;
  path_ = r.waypoints;
  if (path_.size() == 1) path_.push_back(path_.front());
  return true;
}

DwaSettings Navigator::dwa_settings() const {
  DwaSettings ds = profile_.exploration.dwa;
  if (const GoalStrategy* by = active())
    if (const std::optional<float> r = by->robot_radius_m()) ds.robot_radius_m = std::min(ds.robot_radius_m, *r);
  return ds;
}

float Navigator::dwa_clearance() const {
  const DwaSettings ds = dwa_settings();
  return ds.robot_radius_m + ds.safety_margin_m;
}


bool Navigator::can_stand_on(int x, int y) const {
  const InflatedGrid& g = planning_grid();
  if (!g.in_bounds(x, y) || !local_grid().in_bounds(x, y)) return false;
  const InflatedGrid& local = local_grid();
  return g.traversable[g.index(x, y)] != 0 && local.clearance_m[local.index(x, y)] > dwa_clearance();
}

std::optional<Eigen::Vector2f> Navigator::standoff(const Eigen::Vector2f& target) const {
  const Eigen::Vector2i c = inflated().cell_of(target);
  if (can_stand_on(c.x(), c.y())) return target;
  // The nearest fitting cell centre by distance to the target (ties: the lower row, then column,
  // so the result is deterministic).
  const float r = settings_.goal_standoff_search_m;
  const int rc = static_cast<int>(std::ceil(r / inflated().resolution_m));
  std::optional<Eigen::Vector2f> best;
  float best_d = std::numeric_limits<float>::infinity();
  for (int dy = -rc; dy <= rc; ++dy)
    for (int dx = -rc; dx <= rc; ++dx) {
      const int x = c.x() + dx, y = c.y() + dy;
      if (!can_stand_on(x, y)) continue;
      const Eigen::Vector2f p = inflated().cell_center(inflated().index(x, y));
      const float d = (p - target).norm();
      if (d <= r && d < best_d) {
        best_d = d;
        best = p;
      }
    }
  return best;
}

bool Navigator::recheck_goal() {
  const Eigen::Vector2i c = inflated().cell_of(Eigen::Vector2f(goal_->x, goal_->y));
  if (can_stand_on(c.x(), c.y())) return true;  // still fits
  const auto p = standoff(goal_target_);
  if (!p) return false;
  goal_->x = p->x();
  goal_->y = p->y();
  ++stats_.goals_moved;
  return true;
}

void Navigator::abandon_goal(int& counter, double now_s) {
  ++counter;
  if (returning_) {  // on the way home: tried again from where the robot is
    drop_goal();
    return;
  }
  if (state_ == ExplorerState::kPatrolling) {  // skipped for this lap
    drop_goal();
    patrol_goal_ended(false);
    return;
  }
  int failures = 0;
  if (goal_) {  // counted per place for the report of what was left (unexplored.hpp)
    const float r = profile_.exploration.strategy.frontier.blacklist_radius_m;
    auto same = std::find_if(failures_.begin(), failures_.end(),
                             [&](const GoalFailures& f) { return (f.xy - goal_target_).squaredNorm() <= r * r; });
    if (same == failures_.end()) same = failures_.insert(same, GoalFailures{goal_target_, 0});
    failures = ++same->count;
  }
  // The strategy it came from decides what is not tried again (for a while, or for good).
  if (GoalStrategy* by = goal_ ? active() : nullptr)
    by->goal_ended(GoalEnd{false, now_s, goal_target_, decision_, blacklist_, stats_, failures});
  drop_goal();
}

void Navigator::return_home(const Pose2& robot, double now_s) {
  if (state_ == ExplorerState::kDone || returning_) return;
  drop_goal();
  stop_detail_ = "the operator asked to return home";
  if (trail_->points().empty()) {
    state_ = ExplorerState::kDone;
    stop_detail_ += "; no trail yet: the robot is home";
    return;
  }
  returning_ = true;
  state_ = ExplorerState::kReturningHome;
  wait_for_map_ = false;
  home_attempts_ = 0;
  if (!plan_home(robot, now_s)) {
    state_ = ExplorerState::kDone;
    stop_detail_ += "; no path home";
  }
}

void Navigator::stop(const std::string& why) {
  drop_goal();
  state_ = ExplorerState::kDone;
  stop_detail_ = why;
}

bool Navigator::frontier_seen() const {
  return !any_frontier_cell_within(inflated(), *goal_frontier_, settings_.frontier_seen_radius_m);
}

void Navigator::drop_goal() {
  goal_frontier_.reset();
  goal_.reset();
  active_ = kNone;
  path_.clear();
}

void Navigator::decide(const Pose2& robot, double now_s) {
  if (goal_ || wait_for_map_ || !have_map_ || state_ == ExplorerState::kDone) return;
  if (returning_) {
    if (!plan_home(robot, now_s)) {
      state_ = ExplorerState::kDone;
      stop_detail_ += "; no path home";
    }
    return;
  }
  if (state_ == ExplorerState::kPatrolling) {
    next_patrol_goal(robot, now_s);
    return;
  }
  const auto start = std::chrono::steady_clock::now();
  struct Timer {  // records the whole decision's wall time on every return
    LatencyStats& out;
    std::chrono::steady_clock::time_point t0;
    ~Timer() { out.add(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()); }
  } timer{decide_latency_, start};
  blacklist_.expire(now_s);
  // Up to three attempts in one period: a goal without a path is blacklisted and the next one taken.
  for (int attempt = 0; attempt < 3 && !goal_; ++attempt) {
    active_ = kNone;
    GoalQuery q{robot, now_s, model_, latest_map(), inflated(), sectors_, blacklist_, decision_, log_, frontier_xy_, stats_,
                [this](int x, int y) { return can_stand_on(x, y); }};
    std::optional<GoalProposal> proposal;
    for (std::size_t i = 0; i < strategies_.size() && !proposal && !q.retry; ++i) {
      proposal = strategies_[i]->propose(q);
      if (proposal) active_ = i;
    }
    if (q.retry) continue;
    if (!proposal) {
      wait_for_map_ = true;
      path_.clear();
      if (decision_.status != ExplorationStatus::kRobotBlocked) {
        blocked_since_s_ = -1.0;
      } else if (settings_.blocked_recovery_s > 0.0f) {
        // Blocked: decide again at each map while the controller follows the way out to the
        // nearest traversable cell (plan_state().blocked; blocked_escape.hpp).
        if (blocked_since_s_ < 0.0) {
          blocked_since_s_ = now_s;
          ++stats_.blocked_recoveries;
        }
        if (now_s - blocked_since_s_ <= static_cast<double>(settings_.blocked_recovery_s)) {
          constexpr float kMaxWayOut = 2.0f;  // [m]
          path_ = path_out(inflated(), Eigen::Vector2f(robot.x, robot.y), profile_.chassis.radius_m, kMaxWayOut);
          return;
        }
      }
      if (!q.later && ++no_goal_decisions_ > settings_.final_retries) finish(robot, now_s);
      return;
    }
    blocked_since_s_ = -1.0;
    goal_ = proposal->goal;
    goal_target_ = Eigen::Vector2f(goal_->x, goal_->y);
    if (!recheck_goal()) {
      abandon_goal(stats_.goals_abandoned_no_path, now_s);
      continue;
    }
    log_.back().goal = *goal_;
    if (!plan(robot)) {
      abandon_goal(stats_.goals_abandoned_no_path, now_s);
      continue;
    }
    log_.back().planned = true;
    const bool frontier_goal = proposal->kind == GoalKind::kFrontier || proposal->kind == GoalKind::kRelaxedFrontier;
    if (frontier_goal && settings_.look_with_any_sensor && path_.size() >= 2) {
      // A frontier goal's heading is a direction to look in: point whichever sensor turns the
      // least from the heading the path arrives with. Procedure 1's X_g keeps its simulated
      // heading (its reward was computed for it), and so does a view goal: its line of sight
      // through a gap runs from the goal cell, and a side sensor sits 0.12 m off that line
      // (lab, seeds 1-5: view goals looked at with the side sensor made runs end 0-150 s later).
      const Eigen::Vector2f in = path_.back() - path_[path_.size() - 2];
      const float from = in.squaredNorm() > 0.0f ? std::atan2(in.y(), in.x()) : robot.theta;
      goal_->theta = heading_to_look(goal_->theta, from, sectors_);
      log_.back().goal = *goal_;
    }
    if (frontier_goal && settings_.frontier_seen_radius_m > 0.0f && decision_.frontier_searched &&
        decision_.frontier.status == FrontierStatus::kFound)
      goal_frontier_ = decision_.frontier.target_xy;
    simulated_goal_ = proposal->kind == GoalKind::kSimulated;
    // Handed off on the move only when the robot has a way to drive to it: an X_g the robot
    // already stands within handoff_m of is a turn to look (its heading is what it was chosen
    // for), and handing it off would end it at once without the look (lab seed 1: at 19 s such
    // a goal, 0.14 m away, ended unturned and the next decision left for a frontier 4.6 m back).
    handoff_ = simulated_goal_ && (Eigen::Vector2f(goal_->x, goal_->y) - Eigen::Vector2f(robot.x, robot.y)).norm() >
                                      settings_.simulated_goal_handoff_m;
    if (proposal->kind == GoalKind::kView) ++stats_.view_goals;
    else if (proposal->kind == GoalKind::kSimulated) ++stats_.simulated_goals;
    else ++stats_.frontier_goals;
    no_goal_decisions_ = 0;
    start_goal(now_s);
  }
}

void Navigator::finish(const Pose2& robot, double now_s) {
  stop_status_ = decision_.status;
  const std::size_t left = decision_.frontier_searched ? decision_.frontier.frontier_cells : 0;
  switch (stop_status_) {
    case ExplorationStatus::kNoFrontier: stop_detail_ = "explored: no frontier left"; break;
    case ExplorationStatus::kAllUnreachable:
      stop_detail_ = "explored: " + std::to_string(left) + " frontier cells left, all unreachable from the robot";
      break;
    case ExplorationStatus::kAllBlacklisted:
      stop_detail_ = "explored: " + std::to_string(left) +
                     " frontier cells left, all looked at and not observable from where the robot can stand";
      break;
    case ExplorationStatus::kRobotBlocked: stop_detail_ = "gave up: the robot is blocked (no traversable cell around it)"; break;
    default: stop_detail_ = std::string("stopped: ") + to_string(stop_status_); break;
  }
  // What is left, where and why; the frontier points are those of this decision's search.
  left_.clear();
  if (stop_status_ != ExplorationStatus::kNoFrontier && decision_.frontier_searched) {
    UnexploredSettings us;
    us.blacklist_radius_m = profile_.exploration.strategy.frontier.blacklist_radius_m;
    us.approach_radius_m = profile_.exploration.strategy.frontier.approach_radius_m;
    std::vector<Eigen::Vector2f> looked;  // stood at (blacklisted for good) or looked at from a view goal
    for (const GoalBlacklist::Entry& e : blacklist_.entries())
      if (std::isinf(e.expiry_s)) looked.push_back(e.xy);
    for (const auto& st : strategies_)
      for (const Eigen::Vector2f& p : st->looked_at()) looked.push_back(p);
    left_ = find_unexplored(inflated(), Eigen::Vector2f(robot.x, robot.y), frontier_xy_, failures_, looked, us);
    if (!left_.empty()) stop_detail_ += " - " + describe(left_);
  }
  for (const auto& st : strategies_)
    if (const std::string note = st->stop_note(); !note.empty()) stop_detail_ += "; " + note;
  if (settings_.on_done == OnDone::kPatrol && !trail_->points().empty()) {
    start_patrol(robot, now_s);
    return;
  }
  if (settings_.on_done != OnDone::kReturnHome || trail_->points().empty()) {
    state_ = ExplorerState::kDone;
    return;
  }
  returning_ = true;
  state_ = ExplorerState::kReturningHome;
  wait_for_map_ = false;
  if (!plan_home(robot, now_s)) {
    state_ = ExplorerState::kDone;
    stop_detail_ += "; no path home";
  }
}

bool Navigator::plan_home(const Pose2& robot, double now_s) {
  // A few tries (a goal abandoned on the way - time limit, stuck - is tried again from where
  // the robot is), each at a later map update.
  constexpr int kHomeAttempts = 3;
  if (++home_attempts_ > kHomeAttempts) return false;
  if (!set_goal_to(trail_->points().front(), robot, now_s)) {
    wait_for_map_ = true;  // try again on the next map
    return home_attempts_ < kHomeAttempts;
  }
  return true;
}

bool Navigator::set_goal_to(const Eigen::Vector2f& target, const Pose2& robot, double now_s) {
  goal_ = Pose2{target.x(), target.y(), robot.theta};
  goal_target_ = target;
  active_ = kNone;
  simulated_goal_ = false;
  handoff_ = false;
  if (!recheck_goal() || !plan(robot)) {
    drop_goal();
    return false;
  }
  start_goal(now_s);
  return true;
}

void Navigator::start_goal(double now_s) {
  float length = 0.0f;
  for (std::size_t i = 1; i < path_.size(); ++i) length += (path_[i] - path_[i - 1]).norm();
  goal_deadline_s_ = now_s + settings_.goal_timeout_s + length / settings_.nominal_speed_mps;
  ++goal_id_;  // the controller starts afresh on a new goal
}

void Navigator::start_patrol(const Pose2& robot, double now_s) {
  // Waypoints along the trail, in the order the robot first came by them, each at least
  // patrol_spacing_m from those kept before it.
  const float spacing = settings_.patrol_spacing_m;
  patrol_.clear();
  for (const Eigen::Vector2f& p : trail_->points()) {
    bool near = false;
    for (const Eigen::Vector2f& w : patrol_)
      if ((w - p).squaredNorm() < spacing * spacing) {
        near = true;
        break;
      }
    if (!near) patrol_.push_back(p);
  }
  // The round starts at the waypoint nearest the robot.
  patrol_next_ = 0;
  float best = std::numeric_limits<float>::infinity();
  for (std::size_t k = 0; k < patrol_.size(); ++k) {
    const float d = (patrol_[k] - Eigen::Vector2f(robot.x, robot.y)).squaredNorm();
    if (d < best) {
      best = d;
      patrol_next_ = k;
    }
  }
  patrol_misses_ = 0;
  stats_.patrol_waypoints = static_cast<int>(patrol_.size());
  stop_detail_ += "; patrolling " + std::to_string(patrol_.size()) + " waypoints";
  state_ = ExplorerState::kPatrolling;
  wait_for_map_ = false;
  next_patrol_goal(robot, now_s);
}

void Navigator::next_patrol_goal(const Pose2& robot, double now_s) {
  // At most a few paths per decision (a control period); the rest at later map updates.
  constexpr int kTriesPerDecision = 3;
  for (int k = 0; k < kTriesPerDecision && state_ == ExplorerState::kPatrolling; ++k) {
    if (set_goal_to(patrol_[patrol_next_], robot, now_s)) return;
    patrol_goal_ended(false);
  }
  if (state_ == ExplorerState::kPatrolling) wait_for_map_ = true;
}

void Navigator::patrol_goal_ended(bool reached) {
  if (reached) {
    ++stats_.patrol_reached;
    patrol_misses_ = 0;
  } else {
    ++stats_.patrol_skipped;
    ++patrol_misses_;
  }
  if (++patrol_next_ >= patrol_.size()) {
    patrol_next_ = 0;
    ++stats_.patrol_laps;
  }
  if (static_cast<std::size_t>(patrol_misses_) >= patrol_.size()) {
    state_ = ExplorerState::kDone;
    stop_detail_ += "; patrol ended: no waypoint reachable in a whole lap";
  }
}

}  // namespace duet
