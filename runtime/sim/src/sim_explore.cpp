/// @file sim_explore.cpp
/// The simulated exploration run (see sim_explore.hpp).
#include <duet/kernels/error.hpp>
#include <duet/kernels/grid_view.hpp>
#include <duet/runtime/robot/resources.hpp>
#include <duet/sim/sim_explore.hpp>

#include <duet/runtime/config/seed_mix.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

namespace duet::sim {
namespace {

constexpr double kPaperAreaM2 = 31.0;  // paper §4.2, Fig. 10: dual sensors, 31.0 m^2 in 196 s

double sensor_rate(const ExploreSettings& s) { return s.sensor_rate_hz > 0.0 ? s.sensor_rate_hz : s.runtime.map_rate_hz; }

SimRobotSettings robot_settings(const ExploreSettings& s) {
  SimRobotSettings r;
  r.seed = s.seed;
  r.sensor_rate_hz = sensor_rate(s);
  r.render = s.render;
  r.chassis = s.chassis;
  return r;
}

/// The runtime's settings, with the sensors' rate the simulator renders at.
RuntimeSettings runtime_settings(const ExploreSettings& s) {
  RuntimeSettings r = s.runtime;
  r.sensor_rate_hz = sensor_rate(s);
  return r;
}

}  // namespace

const char* to_string(StopReason r) {
  switch (r) {
    case StopReason::kRunning: return "running";
    case StopReason::kExplorerDone: return "explorer_done";
    case StopReason::kTimeLimit: return "time_limit";
    case StopReason::kCoverageReached: return "coverage_reached";
    case StopReason::kInterrupted: return "interrupted";
  }
  return "unknown";
}

ExploreSettings explore_settings(const Profile& profile, std::uint64_t seed, double max_time_s, double sensor_rate_hz) {
  ExploreSettings es;
  es.runtime = profile.runtime;
  es.seed = seed;
  es.max_time_s = max_time_s;
  es.faults = profile.faults;
  if (sensor_rate_hz < 0.0) {
    double r = 0.0;
    for (const auto& sensor : profile.sensors) r = std::max(r, static_cast<double>(sensor.rate_hz));
    es.sensor_rate_hz = r;
  } else if (sensor_rate_hz == 0.0 && profile.runtime.visual_odometry.enabled) {
    es.sensor_rate_hz = profile.runtime.visual_odometry.rate_hz;  // the pipeline's rate: vision's
  } else {
    es.sensor_rate_hz = sensor_rate_hz;
  }
  return es;
}

void validate(const ExploreSettings& s) {
  auto bad = [](const std::string& what) { fail(ErrorCode::kInvalidArgument, "ExploreSettings::" + what); };
  if (!(std::isfinite(s.max_time_s) && s.max_time_s > 0.0 && s.max_time_s <= 1e6))
    bad("max_time_s must be in (0, 1e6] s, got " + std::to_string(s.max_time_s));
  if (!(std::isfinite(s.stop_at_coverage) && s.stop_at_coverage >= 0.0 && s.stop_at_coverage <= 1.0))
    bad("stop_at_coverage must be in [0, 1] (0 = never), got " + std::to_string(s.stop_at_coverage));
  if (!(std::isfinite(s.sensor_rate_hz) && s.sensor_rate_hz >= 0.0 && s.sensor_rate_hz <= 1000.0))
    bad("sensor_rate_hz must be in [0, 1000] Hz (0 = the map rate), got " + std::to_string(s.sensor_rate_hz));
  if (s.sensor_rate_hz > 0.0 && s.sensor_rate_hz < s.runtime.map_rate_hz)
    bad("sensor_rate_hz must be 0 or >= map_rate_hz, got " + std::to_string(s.sensor_rate_hz));
  if (!(std::isfinite(s.curve_period_s) && s.curve_period_s > 0.0 && s.curve_period_s <= 60.0))
    bad("curve_period_s must be in (0, 60] s, got " + std::to_string(s.curve_period_s));
  if (!(std::isfinite(s.coverage_resolution_m) && s.coverage_resolution_m > 0.0f && s.coverage_resolution_m <= 1.0f))
    bad("coverage_resolution_m must be in (0, 1] m, got " + std::to_string(s.coverage_resolution_m));
  if (!(std::isfinite(s.health_period_s) && s.health_period_s >= 0.0 && s.health_period_s <= 3600.0))
    bad("health_period_s must be in [0, 3600] s (0 = never), got " + std::to_string(s.health_period_s));
  validate(s.render);
  validate(runtime_settings(s));
}

SimExplore::SimExplore(World world, Profile profile, ExploreSettings settings)
    : world_([&] {
        validate(world, world.source.empty() ? "world" : world.source);
        return std::make_shared<const World>(std::move(world));
      }()),
      profile_(with_run_seed(std::move(profile), settings.seed)),
      settings_((validate(settings), settings)),
      robot_((validate(profile_, profile_.name), world_), profile_, robot_settings(settings_)) {
  if (!settings_.faults.empty()) {
    injector_ = std::make_unique<FaultInjector>(robot_, parse_faults(settings_.faults, profile_.sensors.size()), mix(settings_.seed ^ 0xFA017ull));
    fault_started_.assign(injector_->faults().size(), false);
  }
  if (!settings_.record_dir.empty()) {
    Profile recorded = profile_;
    recorded.runtime = runtime_settings(settings_);  // the settings the runtime runs with: a replay runs the same
    RecorderSettings rs;
    rs.block_when_full = true;  // a simulation waits for the disk: nothing may be lost
    recorder_ = std::make_unique<Recorder>(settings_.record_dir, recorded, rs);
    recording_ = std::make_unique<RecordingSource>(source(), *recorder_);
  }
  runtime_ = std::make_unique<ExplorationRuntime>(profile_, source().chassis(), source().sensors(), runtime_settings(settings_));
  dt_ = 1.0 / settings_.runtime.control_rate_hz;
  // Scored with every door open: what is behind a door counts as reachable (the run is judged
  // on finding it once it opens).
  truth_ = rasterize(with_doors_open(*world_), settings_.coverage_resolution_m, 0.0f, 0.6f);
  float range = 0.0f;
  for (const auto& s : profile_.sensors) range = std::max(range, s.max_depth_m);
  reachable_ = reachable_free_mask(truth_, world_->start, profile_.exploration.inflation.robot_radius_m, range);
  for (const auto m : reachable_) reachable_count_ += m;
  true_traj_.push_back({0.0, robot_.sim_chassis().true_pose()});
  est_traj_.push_back({0.0, world_->start});
}

SimExplore::~SimExplore() = default;

float occupied_clearance(const OccupancyGrid& g, const CellThresholds& cells, const Eigen::Vector2f& xy, float radius_m) {
  float best = std::numeric_limits<float>::infinity();
  if (!xy.allFinite() || !(radius_m > 0.0f) || g.width() <= 0 || g.height() <= 0) return best;
  // Farther than the radius from the grid's rectangle: no cell can count (and the cell index of
  // a far point may not fit an int).
  const Eigen::Vector2f lo = g.origin(), hi = lo + g.resolution() * Eigen::Vector2f(static_cast<float>(g.width()), static_cast<float>(g.height()));
  if (xy.x() < lo.x() - radius_m || xy.y() < lo.y() - radius_m || xy.x() > hi.x() + radius_m || xy.y() > hi.y() + radius_m) return best;
  const Eigen::Vector2i c = g.cell_of(xy);
  const int n = static_cast<int>(std::ceil(radius_m / g.resolution()));
  for (int y = c.y() - n; y <= c.y() + n; ++y)
    for (int x = c.x() - n; x <= c.x() + n; ++x) {
      if (!g.in_bounds(x, y) || classify(g.at(x, y), cells) != CellState::kOccupied) continue;
      const float d = (g.cell_center(x, y) - xy).norm();
      if (d <= radius_m) best = std::min(best, d);
    }
  return best;
}

CoverageMeasure measure_coverage(const OccupancyGrid& g, const CellThresholds& th, const TruthGrid& truth,
                                 std::span<const std::uint8_t> reachable) {
  CoverageMeasure m;
  std::size_t known = 0;
  for (const float l : g.logodds())
    if (classify(l, th) != CellState::kUnknown) ++known;
  m.area_m2 = static_cast<double>(known) * g.resolution() * g.resolution();
  std::size_t covered = 0, count = 0;
  for (int y = 0; y < truth.height; ++y)
    for (int x = 0; x < truth.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * truth.width + x;
      if (i >= reachable.size() || !reachable[i]) continue;
      ++count;
      const Eigen::Vector2f c = truth.origin + Eigen::Vector2f((x + 0.5f) * truth.resolution_m, (y + 0.5f) * truth.resolution_m);
      const Eigen::Vector2i cell = g.cell_of(c);
      if (g.in_bounds(cell.x(), cell.y()) && classify(g.at(cell.x(), cell.y()), th) != CellState::kUnknown) ++covered;
    }
  m.coverage = count ? static_cast<double>(covered) / static_cast<double>(count) : 0.0;
  return m;
}

CurvePoint SimExplore::measure() const {
  CurvePoint p;
  p.t_s = t_;
  const CoverageMeasure m = measure_coverage(runtime_->map_grid(), profile_.exploration.cells, truth_, reachable_);
  p.area_m2 = m.area_m2;
  p.coverage = m.coverage;
  return p;
}

double SimExplore::occupied_on_obstacles() const {
  // A grid cell is on an obstacle when the truth raster has an occupied cell within 0.1 m of its
  // centre (a wall's cells straddle its face; one cell of slack either way).
  const OccupancyGrid& g = runtime_->map_grid();
  const CellThresholds& th = profile_.exploration.cells;
  const int r = std::max(1, static_cast<int>(std::ceil(0.1f / truth_.resolution_m)));
  std::size_t occupied = 0, on = 0;
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < g.width(); ++x) {
      if (classify(g.at(x, y), th) != CellState::kOccupied) continue;
      ++occupied;
      const Eigen::Vector2f c = g.cell_center(x, y);
      const int tx = static_cast<int>(std::floor((c.x() - truth_.origin.x()) / truth_.resolution_m));
      const int ty = static_cast<int>(std::floor((c.y() - truth_.origin.y()) / truth_.resolution_m));
      bool hit = false;
      for (int dy = -r; dy <= r && !hit; ++dy)
        for (int dx = -r; dx <= r && !hit; ++dx) {
          const int qx = tx + dx, qy = ty + dy;
          // Outside the truth raster is outside the floor: solid.
          hit = qx < 0 || qy < 0 || qx >= truth_.width || qy >= truth_.height || truth_.at(qx, qy) != 0;
        }
      on += hit ? 1 : 0;
    }
  return occupied ? static_cast<double>(on) / static_cast<double>(occupied) : -1.0;
}

bool SimExplore::step() {
  if (reason_ != StopReason::kRunning) return false;
  const double step_w0 = wall_.now_s();
  // 1-2. The chassis moves one control period (physics inside; odometry at 50 Hz); the sensors
  // render when due, from the true pose of that instant (SimRobot::advance).
  const double t_end = t_ + dt_;
  const SimChassis& chassis = robot_.sim_chassis();
  const std::size_t collisions_before = chassis.collisions();
  if (injector_) apply_sim_faults();
  source().advance(t_end);
  t_ = t_end;
  if (chassis.collisions() > collisions_before) {
    const Pose2 est = runtime_->pose();
    collision_log_.push_back({t_, chassis.true_pose(), runtime_->last_command(), est,
                              occupied_clearance(runtime_->map_grid(), profile_.exploration.cells, Eigen::Vector2f(est.x, est.y), 1.0f)});
  }
  // Paced by the wall clock, the robot's tick comes at its time: the world of the period (its
  // motion, the frames stamped in it) was computed ahead, as sensors deliver frames on their
  // own, so the control period is the runtime's and not the renderer's.
  if (settings_.realtime) wall_.sleep_until(t_);
  // 3. The robot's runtime: synchronizer -> mapper -> explorer -> command.
  runtime_->override_pose(settings_.use_true_pose ? std::optional<Pose2>(chassis.true_pose()) : std::nullopt);
  const double tick_w0 = wall_.now_s();
  runtime_->tick(t_);
  const double tick_s = wall_.now_s() - tick_w0;

  // 4. Scoring.
  const Pose2 truth = chassis.true_pose();
  const Pose2 last = true_traj_.back().pose;
  path_length_ += std::hypot(truth.x - last.x, truth.y - last.y);
  true_traj_.push_back({t_, truth});
  est_traj_.push_back({t_, runtime_->pose()});
  pose_error_max_ = std::max(pose_error_max_, static_cast<double>(std::hypot(runtime_->pose().x - truth.x, runtime_->pose().y - truth.y)));
  if (target_entered_ < 0.0 && world_->target_region && world_->target_region->contains({truth.x, truth.y}))
    target_entered_ = t_;
  bool coverage_reached = false;
  if (t_ + 1e-9 >= next_curve_t_) {
    const CurvePoint p = measure();
    curve_.push_back(p);
    if (t90_ < 0.0 && p.coverage >= 0.9) t90_ = t_;
    if (t_paper_ < 0.0 && p.area_m2 >= kPaperAreaM2) t_paper_ = t_;
    coverage_reached = settings_.stop_at_coverage > 0.0 && p.coverage >= settings_.stop_at_coverage;
    next_curve_t_ += settings_.curve_period_s;
  }
  if (runtime_->state() == ExplorerState::kDone) reason_ = StopReason::kExplorerDone;
  else if (coverage_reached) reason_ = StopReason::kCoverageReached;
  else if (t_ + 1e-9 >= settings_.max_time_s) reason_ = StopReason::kTimeLimit;
  if (reason_ != StopReason::kRunning) finish();
  wall_elapsed_ = wall_.now_s();
  sample_health(tick_s, wall_elapsed_ - step_w0);
  return reason_ == StopReason::kRunning;
}

void SimExplore::sample_health(double tick_s, double step_s) {
  if (settings_.health_period_s <= 0.0) return;
  tick_sum_s_ += tick_s;
  tick_max_s_ = std::max(tick_max_s_, tick_s);
  step_sum_s_ += step_s;
  ++health_periods_;
  if (next_health_t_ <= 0.0) next_health_t_ = settings_.health_period_s;
  if (t_ + 1e-9 < next_health_t_ && reason_ == StopReason::kRunning) return;
  HealthSample h;
  h.t_s = t_;
  const std::int64_t rss = resident_memory_bytes();
  h.rss_mb = rss < 0 ? -1.0 : static_cast<double>(rss) / (1024.0 * 1024.0);
  const double n = static_cast<double>(health_periods_);
  h.tick_mean_ms = 1e3 * tick_sum_s_ / n;
  h.tick_max_ms = 1e3 * tick_max_s_;
  h.step_mean_ms = 1e3 * step_sum_s_ / n;
  const OccupancyGrid& g = runtime_->map_grid();
  h.grid_cells = static_cast<std::size_t>(g.width()) * static_cast<std::size_t>(g.height());
  if (settings_.runtime.execution == Execution::kLockstep || reason_ != StopReason::kRunning)
    h.submaps = static_cast<long>(runtime_->mapper().submaps().size());
  h.explorer_state = duet::to_string(runtime_->state());
  h.heading_rate_radps = runtime_->heading_rate();
  health_.push_back(std::move(h));
  tick_sum_s_ = tick_max_s_ = step_sum_s_ = 0.0;
  health_periods_ = 0;
  while (next_health_t_ <= t_ + 1e-9) next_health_t_ += settings_.health_period_s;
}

void SimExplore::apply_sim_faults() {
  const auto& faults = injector_->faults();
  for (std::size_t i = 0; i < faults.size(); ++i) {
    const Fault& f = faults[i];
    if (f.kind == FaultKind::kExtrinsics) {
      const bool on = f.active(t_);
      robot_.sim_sensor(static_cast<std::size_t>(f.sensor - 1))
          .set_mount_error(on ? static_cast<float>(f.amount * std::numbers::pi / 180.0) : 0.0f);
      if (on && !fault_started_[i]) injector_->count(i);
      fault_started_[i] = on;
    } else if (f.kind == FaultKind::kKidnap && !fault_started_[i] && t_ >= f.start_s) {
      // Pushed sideways (left, else right; else as far as there is room).
      const Pose2 p = robot_.sim_chassis().true_pose();
      const Eigen::Vector2f left(-std::sin(p.theta), std::cos(p.theta));
      const float a = static_cast<float>(f.amount);
      for (const float k : {1.0f, -1.0f, 0.5f, -0.5f, 0.25f, -0.25f})
        if (robot_.sim_chassis().displace(left * (a * k))) {
          injector_->count(i);
          break;
        }
      fault_started_[i] = true;
    }
  }
}

void SimExplore::finish() {
  runtime_->drain();  // background tasks done: the mapper and the explorer are the caller's to read
  const CurvePoint p = measure();
  if (curve_.empty() || curve_.back().t_s < t_) curve_.push_back(p);
  if (recorder_) recorder_->close();  // everything written (throws the first write error)
}

void SimExplore::interrupt(const std::string& why) {
  if (reason_ != StopReason::kRunning) return;
  reason_ = StopReason::kInterrupted;
  interrupt_detail_ = why;
  finish();
  wall_elapsed_ = wall_.now_s();
}

void SimExplore::run(const std::function<void(const SimExplore&)>& progress) {
  double next_report = 0.0;
  while (step()) {
    if (progress && t_ + 1e-9 >= next_report) {
      progress(*this);
      next_report += 1.0;
    }
  }
  if (progress) progress(*this);
}

ExploreSummary SimExplore::summary() const {
  ExploreSummary s;
  s.world = world_->name;
  s.start = world_->start;
  s.profile = profile_.name;
  s.seed = settings_.seed;
  s.stop_reason = reason_;
  if (runtime_->state() == ExplorerState::kDone) s.explorer_status = duet::to_string(runtime_->stop_status());
  if (reason_ == StopReason::kInterrupted) {
    s.stop_detail = interrupt_detail_;
  } else if (reason_ == StopReason::kCoverageReached) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "coverage %.1f %% reached the run's stop at %.1f %%", 100.0 * curve_.back().coverage,
                  100.0 * settings_.stop_at_coverage);
    s.stop_detail = buf;
  } else {
    s.stop_detail = runtime_->stop_detail();
  }
  s.explorer_state = duet::to_string(runtime_->state());
  s.left = runtime_->left_unexplored();
  s.sim_time_s = t_;
  s.wall_time_s = wall_elapsed_;
  const CurvePoint p = measure();
  s.explored_area_m2 = p.area_m2;
  s.coverage = p.coverage;
  s.reachable_free_area_m2 = static_cast<double>(reachable_count_) * truth_.resolution_m * truth_.resolution_m;
  s.t90_s = t90_;
  s.t_paper_area_s = t_paper_;
  s.target_entered_s = target_entered_;
  s.path_length_m = path_length_;
  s.collisions = robot_.sim_chassis().collisions();
  s.explorer = runtime_->explorer_stats();
  s.frames_rendered = robot_.frames_rendered();
  const RuntimeStats& rs = runtime_->stats();
  s.sets_integrated = rs.sets_integrated;
  s.sets_not_integrated = rs.sets_not_integrated;
  s.frame_drops = rs.frame_drops;
  s.odometry_unmatched = rs.odometry_unmatched;
  const Pose2 tp = robot_.sim_chassis().true_pose();
  s.odometry_error_m = std::hypot(robot_.sim_chassis().odometry_pose().x - tp.x, robot_.sim_chassis().odometry_pose().y - tp.y);
  const Pose2 est = runtime_->pose();
  s.pose_error_m = std::hypot(est.x - tp.x, est.y - tp.y);
  s.pose_error_max_m = pose_error_max_;
  s.heading_error_deg = std::fabs(std::remainder(est.theta - tp.theta, 2.0 * std::numbers::pi)) * 180.0 / std::numbers::pi;
  s.heading_rate_radps = runtime_->heading_rate();
  s.gyro_bias_radps = robot_.sim_chassis().gyro_bias();
  s.scan_matches = rs.scan_matches;
  s.scan_match_rejected = rs.scan_match_rejected;
  s.scan_match_time_s = rs.scan_match_time_s;
  s.visual_odometry = settings_.runtime.visual_odometry.enabled;
  s.visual = rs.visual;
  s.visual_sets_incomplete = rs.visual_sets_incomplete;
  s.visual_sets_busy = rs.visual_sets_busy;
  if (const auto h = runtime_->localization_health()) s.localization_health = to_string(*h);
  s.execution = settings_.runtime.execution;
  s.realtime = settings_.realtime;
  s.timing = runtime_->timing();
  s.map_sets_skipped = rs.map_sets_skipped;
  // In the background mode the loop closer belongs to the background task while the run goes on.
  const bool pipeline_readable = settings_.runtime.execution == Execution::kLockstep || reason_ != StopReason::kRunning;
  if (const LoopCloser* lc = runtime_->loop_closer(); lc && pipeline_readable) {
    s.loop_closure = true;
    s.loops = lc->stats();
  }
  if (injector_) s.faults = injector_->counts();
  s.input = rs.input;
  s.sets_with_missing = rs.sets_with_missing;
  s.blind_holds = rs.blind_holds;
  s.relocalizations = rs.relocalizations;
  s.relocalizations_held = rs.relocalizations_held;
  s.relocalizations_new_space = rs.relocalizations_new_space;
  s.relocalizations_ambiguous = rs.relocalizations_ambiguous;
  s.relocalizations_in_obstacle = rs.relocalizations_in_obstacle;
  s.relocalizations_at_edge = rs.relocalizations_at_edge;
  s.relocalizations_asked = rs.relocalizations_asked;
  s.occupied_on_obstacles = occupied_on_obstacles();
  return s;
}

}  // namespace duet::sim
