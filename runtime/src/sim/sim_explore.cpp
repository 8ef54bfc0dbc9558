/// @file sim_explore.cpp
/// The simulated exploration run (see sim_explore.hpp).
#include <duet/kernels/error.hpp>
#include <duet/kernels/grid_view.hpp>
#include <duet/runtime/sim/sim_explore.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace duet::sim {
namespace {

constexpr double kPaperAreaM2 = 31.0;  // paper §4.2, Fig. 10: dual sensors, 31.0 m^2 in 196 s

double wall_now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

Eigen::Isometry3f to_iso(const Pose2& p) {
  Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
  T.linear() = Eigen::AngleAxisf(p.theta, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3f(p.x, p.y, 0.0f);
  return T;
}

std::uint64_t mix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

ChassisSimSettings chassis_settings(const Profile& profile, const ExploreSettings& s) {
  ChassisSimSettings c = s.chassis ? *s.chassis : ChassisSimSettings::from_profile(profile.chassis);
  // The Kobuki's odometry takes its heading from the gyro (kobuki_node's default).
  if (!s.chassis) c.gyro_heading = true;
  c.seed = mix(s.seed ^ 0xC4A551ull);
  return c;
}

Profile seeded(Profile p, std::uint64_t seed) {
  p.exploration.strategy.simulation.seed = mix(seed ^ 0x5EED5EEDull);
  return p;
}

double sensor_rate(const ExploreSettings& s) { return s.sensor_rate_hz > 0.0 ? s.sensor_rate_hz : s.map_rate_hz; }

ApproximateTimeSettings sync_settings(const Profile& profile, const ExploreSettings& s) {
  ApproximateTimeSettings a = s.sync;
  const double odom_rate = profile.chassis.odometry_rate_hz;
  const double rate = sensor_rate(s);
  // The odometry stream runs at 50 Hz against sensors at `rate`: hold at least two sensor
  // periods of it so that overflow never takes the message a set needs.
  a.queue_size = std::max<std::size_t>(a.queue_size, static_cast<std::size_t>(std::ceil(2.0 * odom_rate / rate)) + 2);
  // True lower bounds on the stamp intervals let sets be emitted at once (no waiting for the
  // next frame to prove optimality).
  a.inter_message_lower_bounds_s.assign(profile.sensors.size(), 0.9 / rate);
  a.inter_message_lower_bounds_s.push_back(0.9 / odom_rate);
  return a;
}

}  // namespace

const char* to_string(StopReason r) {
  switch (r) {
    case StopReason::kRunning: return "running";
    case StopReason::kExplorerDone: return "explorer_done";
    case StopReason::kTimeLimit: return "time_limit";
  }
  return "unknown";
}

void validate(const ExploreSettings& s) {
  auto bad = [](const std::string& what) { fail(ErrorCode::kInvalidArgument, "ExploreSettings::" + what); };
  if (!(std::isfinite(s.max_time_s) && s.max_time_s > 0.0 && s.max_time_s <= 1e6))
    bad("max_time_s must be in (0, 1e6] s, got " + std::to_string(s.max_time_s));
  if (!(std::isfinite(s.control_rate_hz) && s.control_rate_hz > 0.0 && s.control_rate_hz <= 1000.0))
    bad("control_rate_hz must be in (0, 1000] Hz, got " + std::to_string(s.control_rate_hz));
  if (!(std::isfinite(s.map_rate_hz) && s.map_rate_hz > 0.0 && s.map_rate_hz <= s.control_rate_hz))
    bad("map_rate_hz must be in (0, control_rate_hz] Hz, got " + std::to_string(s.map_rate_hz));
  if (!(std::isfinite(s.sensor_rate_hz) && s.sensor_rate_hz >= 0.0 && s.sensor_rate_hz <= 1000.0))
    bad("sensor_rate_hz must be in [0, 1000] Hz (0 = the map rate), got " + std::to_string(s.sensor_rate_hz));
  if (s.sensor_rate_hz > 0.0 && s.sensor_rate_hz < s.map_rate_hz)
    bad("sensor_rate_hz must be 0 or >= map_rate_hz, got " + std::to_string(s.sensor_rate_hz));
  if (!(std::isfinite(s.curve_period_s) && s.curve_period_s > 0.0 && s.curve_period_s <= 60.0))
    bad("curve_period_s must be in (0, 60] s, got " + std::to_string(s.curve_period_s));
  if (!(std::isfinite(s.coverage_resolution_m) && s.coverage_resolution_m > 0.0f && s.coverage_resolution_m <= 1.0f))
    bad("coverage_resolution_m must be in (0, 1] m, got " + std::to_string(s.coverage_resolution_m));
  validate(s.explorer);
  validate(s.render);
  validate(s.sync);
}

SimExplore::SimExplore(World world, Profile profile, ExploreSettings settings)
    : world_([&] {
        validate(world, world.source.empty() ? "world" : world.source);
        return std::make_shared<const World>(std::move(world));
      }()),
      profile_(seeded(std::move(profile), settings.seed)),
      settings_((validate(settings), settings)),
      renderer_(*world_, settings_.render),
      chassis_(world_, chassis_settings(profile_, settings_), world_->start, ChassisBody::from_profile(profile_.chassis)),
      mapper_(profile_.mapping),
      explorer_(profile_, settings_.explorer),
      sync_(profile_.sensors.size() + 1, sync_settings(profile_, settings_)) {
  validate(profile_, profile_.name);
  dt_ = 1.0 / settings_.control_rate_hz;
  pose_ = world_->start;
  truth_ = rasterize(*world_, settings_.coverage_resolution_m, 0.0f, 0.6f);
  float range = 0.0f;
  for (const auto& s : profile_.sensors) range = std::max(range, s.max_depth_m);
  reachable_ = reachable_free_mask(truth_, world_->start, profile_.exploration.inflation.robot_radius_m, range);
  for (const auto m : reachable_) reachable_count_ += m;
  if (settings_.realtime) wall_clock_ = std::make_unique<SteadyClock>(1.0);
  wall_start_ = wall_now();
  true_traj_.push_back({0.0, chassis_.true_pose()});
  est_traj_.push_back({0.0, pose_});
}

SimExplore::~SimExplore() = default;

void SimExplore::render_sensors() {
  const Eigen::Isometry3f T_world_robot = to_iso(chassis_.true_pose());
  for (std::size_t i = 0; i < profile_.sensors.size(); ++i) {
    const SensorProfile& sp = profile_.sensors[i];
    RgbdImage img;
    if (!spare_images_.empty()) {
      img = std::move(spare_images_.back());
      spare_images_.pop_back();
    }
    const std::uint64_t seed = mix(settings_.seed * 0x100000001B3ull + frame_counter_ * 64 + i);
    renderer_.render(sp, T_world_robot * sp.T_robot_optical(), seed, img);
    ++frames_rendered_;
    const std::uint64_t id = next_id_++;
    frames_.emplace(id, std::move(img));
    sync_.add(i, t_, id);
  }
  ++frame_counter_;
}

void SimExplore::integrate(const ApproximateTimeCore::Set& set) {
  const std::size_t n = profile_.sensors.size();
  std::vector<RgbdImage> images(n);
  for (std::size_t i = 0; i < n; ++i) {
    auto it = frames_.find(set.ids[i]);
    if (it == frames_.end()) fail(ErrorCode::kInternal, "synchronizer returned an unknown frame id");
    images[i] = std::move(it->second);
    frames_.erase(it);
  }
  auto ot = odometry_.find(set.ids[n]);
  if (ot == odometry_.end()) fail(ErrorCode::kInternal, "synchronizer returned an unknown odometry id");
  const OdometryMsg odom = ot->second;
  odometry_.erase(ot);
  const double stamp = set.stamps_s[n];
  if (stamp + 1e-9 >= next_map_t_) {
    std::vector<SensorFrame> frames;
    frames.reserve(n);
    for (std::size_t i = 0; i < n; ++i)
      frames.push_back(frame_view(images[i], profile_.sensors[i], profile_.sensors[i].T_robot_optical()));
    // The frames were rendered at the true pose; the mapper gets the runtime's estimate at the
    // frames' time: the synchronized odometry (or, for debugging, the truth).
    const Pose2 at = settings_.use_true_pose ? chassis_.true_pose() : odom.pose;
    mapper_.integrate(frames, to_iso(at));
    explorer_.update_map(mapper_.grid(), pose_, t_);
    map_ready_ = true;
    ++sets_integrated_;
    while (next_map_t_ <= stamp + 1e-9) next_map_t_ += 1.0 / settings_.map_rate_hz;
  } else {
    ++sets_not_integrated_;
  }
  for (auto& img : images) spare_images_.push_back(std::move(img));
}

void SimExplore::drain_sync() {
  for (const auto& set : sync_.take_sets()) integrate(set);
  const std::size_t n = profile_.sensors.size();
  for (const auto& d : sync_.take_drops()) {
    if (d.stream < n) {
      ++frame_drops_;
      auto it = frames_.find(d.id);
      if (it != frames_.end()) {
        spare_images_.push_back(std::move(it->second));
        frames_.erase(it);
      }
    } else {
      ++odometry_unmatched_;
      odometry_.erase(d.id);
    }
  }
}

CurvePoint SimExplore::measure() const {
  CurvePoint p;
  p.t_s = t_;
  const OccupancyGrid& g = mapper_.grid();
  const CellThresholds& th = profile_.exploration.cells;
  std::size_t known = 0;
  for (const float l : g.logodds())
    if (classify(l, th) != CellState::kUnknown) ++known;
  p.area_m2 = static_cast<double>(known) * g.resolution() * g.resolution();
  std::size_t covered = 0;
  for (int y = 0; y < truth_.height; ++y)
    for (int x = 0; x < truth_.width; ++x) {
      if (!reachable_[static_cast<std::size_t>(y) * truth_.width + x]) continue;
      const Eigen::Vector2f c = truth_.origin + Eigen::Vector2f((x + 0.5f) * truth_.resolution_m, (y + 0.5f) * truth_.resolution_m);
      const Eigen::Vector2i cell = g.cell_of(c);
      if (g.in_bounds(cell.x(), cell.y()) && classify(g.at(cell.x(), cell.y()), th) != CellState::kUnknown) ++covered;
    }
  p.coverage = reachable_count_ ? static_cast<double>(covered) / static_cast<double>(reachable_count_) : 0.0;
  return p;
}

bool SimExplore::step() {
  if (reason_ != StopReason::kRunning) return false;
  // 1. The chassis moves one control period (physics inside); odometry at 50 Hz.
  const double t_next = t_ + dt_;
  const std::size_t collisions_before = chassis_.collisions();
  chassis_.advance(dt_);
  if (chassis_.collisions() > collisions_before) collision_log_.push_back({t_next, chassis_.true_pose(), last_cmd_});
  t_ = t_next;
  const std::size_t n = profile_.sensors.size();
  for (OdometryMsg& m : chassis_.take_odometry()) {
    pose_ = m.pose;
    odom_twist_ = m.twist;
    const std::uint64_t id = next_id_++;
    const double stamp = m.stamp_s;
    odometry_.emplace(id, m);
    sync_.add(n, stamp, id);
  }
  if (settings_.use_true_pose) pose_ = chassis_.true_pose();
  // 2. Sensors, when due (stamped with this period's end, where the true pose is).
  if (t_ + 1e-9 >= next_sensor_t_) {
    render_sensors();
    const double period = 1.0 / sensor_rate(settings_);
    while (next_sensor_t_ <= t_ + 1e-9) next_sensor_t_ += period;
  }
  // 3. Synchronized sets -> mapper (1 Hz) -> explorer's map.
  drain_sync();
  // 4-5. Control at 20 Hz on the pose estimate.
  const Twist cmd = explorer_.control(pose_, odom_twist_, t_);
  chassis_.command(cmd);
  last_cmd_ = cmd;

  const Pose2 truth = chassis_.true_pose();
  const Pose2 last = true_traj_.back().pose;
  path_length_ += std::hypot(truth.x - last.x, truth.y - last.y);
  true_traj_.push_back({t_, truth});
  est_traj_.push_back({t_, pose_});
  if (target_entered_ < 0.0 && world_->target_region && world_->target_region->contains({truth.x, truth.y}))
    target_entered_ = t_;
  if (t_ + 1e-9 >= next_curve_t_) {
    const CurvePoint p = measure();
    curve_.push_back(p);
    if (t90_ < 0.0 && p.coverage >= 0.9) t90_ = t_;
    if (t_paper_ < 0.0 && p.area_m2 >= kPaperAreaM2) t_paper_ = t_;
    next_curve_t_ += settings_.curve_period_s;
  }
  if (explorer_.state() == ExplorerState::kDone) reason_ = StopReason::kExplorerDone;
  else if (t_ + 1e-9 >= settings_.max_time_s) reason_ = StopReason::kTimeLimit;
  if (reason_ != StopReason::kRunning) {
    const CurvePoint p = measure();
    if (curve_.empty() || curve_.back().t_s < t_) curve_.push_back(p);
  }
  if (wall_clock_) wall_clock_->sleep_until(t_);
  wall_elapsed_ = wall_now() - wall_start_;
  return reason_ == StopReason::kRunning;
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
  s.profile = profile_.name;
  s.seed = settings_.seed;
  s.stop_reason = reason_;
  if (explorer_.state() == ExplorerState::kDone) s.explorer_status = duet::to_string(explorer_.stop_status());
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
  s.collisions = chassis_.collisions();
  s.explorer = explorer_.stats();
  s.frames_rendered = frames_rendered_;
  s.sets_integrated = sets_integrated_;
  s.sets_not_integrated = sets_not_integrated_;
  s.frame_drops = frame_drops_;
  s.odometry_unmatched = odometry_unmatched_;
  const Pose2 tp = chassis_.true_pose();
  s.odometry_error_m = std::hypot(chassis_.odometry_pose().x - tp.x, chassis_.odometry_pose().y - tp.y);
  return s;
}

}  // namespace duet::sim
