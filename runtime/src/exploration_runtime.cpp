/// @file exploration_runtime.cpp
/// The exploration loop on the robot interfaces (see exploration_runtime.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/exploration_runtime.hpp>

#include "cell_key.hpp"

#include <numbers>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

namespace duet {
namespace {

ApproximateTimeSettings sync_settings(const Profile& profile, const RuntimeSettings& s) {
  ApproximateTimeSettings a = s.sync;
  const double odom_rate = profile.chassis.odometry_rate_hz;
  // Odometry runs at 50 Hz against frames at sensor_rate_hz: hold at least two frame periods of
  // it so that overflow never takes the message a set needs.
  a.queue_size = std::max<std::size_t>(a.queue_size, static_cast<std::size_t>(std::ceil(2.0 * odom_rate / s.sensor_rate_hz)) + 2);
  // True lower bounds on the stamp intervals let sets be emitted at once.
  a.inter_message_lower_bounds_s.assign(profile.sensors.size(), 0.9 / s.sensor_rate_hz);
  a.inter_message_lower_bounds_s.push_back(0.9 / odom_rate);
  return a;
}

}  // namespace

void validate(const PoseCorrectionSettings& s) {
  validate(s.match);
  auto bad = [](const std::string& what) { fail(ErrorCode::kInvalidArgument, "PoseCorrectionSettings::" + what); };
  if (!(std::isfinite(s.min_height_m) && std::isfinite(s.max_height_m) && s.min_height_m < s.max_height_m))
    bad("min_height_m < max_height_m (finite) required, got " + std::to_string(s.min_height_m) + ", " + std::to_string(s.max_height_m));
  if (!(std::isfinite(s.reference_age_s) && s.reference_age_s >= 0.0 && s.reference_age_s <= 3600.0))
    bad("reference_age_s must be in [0, 3600] s, got " + std::to_string(s.reference_age_s));
  if (s.pixel_step < 1 || s.pixel_step > 64) bad("pixel_step must be in [1, 64], got " + std::to_string(s.pixel_step));
  if (s.max_points < 1) bad("max_points must be >= 1");
  if (!(std::isfinite(s.gain) && s.gain > 0.0f && s.gain <= 1.0f)) bad("gain must be in (0, 1], got " + std::to_string(s.gain));
  if (!(std::isfinite(s.rate_gain) && s.rate_gain >= 0.0f && s.rate_gain <= 1.0f))
    bad("rate_gain must be in [0, 1], got " + std::to_string(s.rate_gain));
  if (!(std::isfinite(s.rate_gain_initial) && s.rate_gain_initial >= s.rate_gain && s.rate_gain_initial <= 1.0f && s.rate_gain_initial > 0.0f))
    bad("rate_gain_initial must be in [rate_gain, 1] and > 0, got " + std::to_string(s.rate_gain_initial));
}

void validate(const RuntimeSettings& s) {
  auto bad = [](const std::string& what) { fail(ErrorCode::kInvalidArgument, "RuntimeSettings::" + what); };
  if (!(std::isfinite(s.control_rate_hz) && s.control_rate_hz > 0.0 && s.control_rate_hz <= 1000.0))
    bad("control_rate_hz must be in (0, 1000] Hz, got " + std::to_string(s.control_rate_hz));
  if (!(std::isfinite(s.map_rate_hz) && s.map_rate_hz > 0.0 && s.map_rate_hz <= s.control_rate_hz))
    bad("map_rate_hz must be in (0, control_rate_hz] Hz, got " + std::to_string(s.map_rate_hz));
  if (!(std::isfinite(s.sensor_rate_hz) && s.sensor_rate_hz > 0.0 && s.sensor_rate_hz <= 1000.0))
    bad("sensor_rate_hz must be in (0, 1000] Hz, got " + std::to_string(s.sensor_rate_hz));
  validate(s.explorer);
  validate(s.sync);
  validate(s.pose_correction);
  validate(s.loop_closure);
}

ExplorationRuntime::ExplorationRuntime(const Profile& profile, ChassisInterface& chassis,
                                       std::span<RgbdSensorInterface* const> sensors, const RuntimeSettings& settings)
    : profile_(profile),
      settings_((validate(settings), settings)),
      chassis_(chassis),
      sensors_(sensors.begin(), sensors.end()),
      mapper_(profile.mapping),
      explorer_(profile, settings.explorer),
      sync_(profile.sensors.size() + 1, sync_settings(profile, settings)) {
  if (sensors_.size() != profile_.sensors.size())
    fail(ErrorCode::kInvalidArgument, "ExplorationRuntime: " + std::to_string(sensors_.size()) + " sensors for a profile with " +
                                          std::to_string(profile_.sensors.size()));
  for (std::size_t i = 0; i < sensors_.size(); ++i)
    if (sensors_[i] == nullptr) fail(ErrorCode::kInvalidArgument, "ExplorationRuntime: sensor " + std::to_string(i) + " is null");
  if (settings_.loop_closure.enabled && settings_.pose_correction.enabled)
    loop_.emplace(settings_.loop_closure, profile_.exploration.cells, mapper_);
}

void ExplorationRuntime::integrate(const ApproximateTimeCore::Set& set, double now_s) {
  const std::size_t n = sensors_.size();
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
    // The mapper gets the pose at the frames' time: the odometry interpolated to the frames'
    // mean stamp (the synchronized message may be up to half an odometry period away: 0.6 deg
    // of heading at 1 rad/s), corrected by scan matching (or, for debugging, the overriding pose).
    double t_frames = 0.0;
    for (std::size_t i = 0; i < n; ++i) t_frames += set.stamps_s[i];
    t_frames /= static_cast<double>(n);
    const Pose2 odom_at = odometry_at(t_frames, odom);
    Pose2 at;
    if (pose_override_) {
      at = *pose_override_;
    } else {
      at = compose(correction_, odom_at);
      if (settings_.pose_correction.enabled) {
        at = correct(frames, odom_at, at, t_frames);
        pose_ = compose(correction_, odom_pose_);
      }
    }
    mapper_.integrate(frames, to_isometry(at));
    if (loop_ && !pose_override_) {
      if (const std::optional<Pose2> shift = loop_->update(mapper_, at, t_frames)) {
        // The map frame moved: so do the correction (map <- odometry), the pose, and what the
        // explorer keeps; the matcher's reference copy is of the old frame.
        correction_ = compose(*shift, correction_);
        pose_ = compose(correction_, odom_pose_);
        at = compose(*shift, at);
        explorer_.shift_frame(*shift);
        have_reference_ = false;
        pending_t_ = -1.0;
        ++stats_.loop_closures;
      }
    }
    if (settings_.explorer.recent_obstacles_s > 0.0f) remember_obstacles(at, odom_at, t_frames);
    explorer_.update_map(mapper_.grid(), pose_, now_s);
    ++stats_.sets_integrated;
    while (next_map_t_ <= stamp + 1e-9) next_map_t_ += 1.0 / settings_.map_rate_hz;
  } else {
    ++stats_.sets_not_integrated;
  }
  for (std::size_t i = 0; i < n; ++i) sensors_[i]->recycle(std::move(images[i]));
}

void ExplorationRuntime::remember_obstacles(const Pose2& at, const Pose2& odom, double t) {
  const ExplorerSettings& es = settings_.explorer;
  const float res = mapper_.grid().resolution();
  const float r2 = es.recent_obstacle_range_m * es.recent_obstacle_range_m;
  const Eigen::Vector2f robot(at.x, at.y);
  // One point per grid cell of this scan (the voxel filter leaves a column of points per cell).
  recent_keys_.clear();
  for (const Eigen::Vector2f& p : mapper_.last_obstacles()) {
    if (!p.allFinite() || (p - robot).squaredNorm() > r2) continue;
    recent_keys_.push_back(cell_key(p.x(), p.y(), res));
  }
  std::sort(recent_keys_.begin(), recent_keys_.end());
  recent_keys_.erase(std::unique(recent_keys_.begin(), recent_keys_.end()), recent_keys_.end());
  // Map -> odometry at the frames' time: the odometry is exact relative to the robot over the
  // window (its drift is the pose error's source only over minutes).
  const Pose2 odom_from_map = compose(odom, inverse(at));
  RecentScan scan{t, {}};
  scan.points.reserve(recent_keys_.size());
  for (const std::uint64_t k : recent_keys_) {
    const Eigen::Vector2f c = key_center(k, res);
    const Pose2 q = compose(odom_from_map, Pose2{c.x(), c.y(), 0.0f});
    scan.points.emplace_back(q.x, q.y);
  }
  recent_.push_back(std::move(scan));
  while (!recent_.empty() && recent_.front().t < t - static_cast<double>(es.recent_obstacles_s)) recent_.pop_front();
  // Back to the map frame with the correction the frames were integrated with (= the one the
  // control loop uses until the next update); a cell counts when at least min_scans scans of the
  // window put a point in it (a single noisy return does not).
  const Pose2 map_from_odom = compose(at, inverse(odom));
  recent_count_.clear();
  for (std::size_t k = 0; k < recent_.size(); ++k)
    for (const Eigen::Vector2f& p : recent_[k].points) {
      const Pose2 q = compose(map_from_odom, Pose2{p.x(), p.y(), 0.0f});
      recent_count_.emplace_back(cell_key(q.x, q.y, res), static_cast<std::uint32_t>(k));
    }
  std::sort(recent_count_.begin(), recent_count_.end());
  recent_count_.erase(std::unique(recent_count_.begin(), recent_count_.end()), recent_count_.end());
  recent_map_.clear();
  const auto need = static_cast<std::size_t>(es.recent_obstacle_min_scans);
  for (std::size_t b = 0; b < recent_count_.size();) {
    std::size_t e = b + 1;
    while (e < recent_count_.size() && recent_count_[e].first == recent_count_[b].first) ++e;
    if (e - b >= need) recent_map_.push_back(key_center(recent_count_[b].first, res));
    b = e;
  }
  explorer_.set_recent_obstacles(recent_map_);
}

Pose2 ExplorationRuntime::odometry_at(double t, const OdometryMsg& fallback) const {
  // The two messages around t in the recent history (stamps increasing); else the fallback.
  for (std::size_t k = 1; k < odom_history_.size(); ++k) {
    const OdometryMsg& a = odom_history_[k - 1];
    const OdometryMsg& b = odom_history_[k];
    if (!(a.stamp_s <= t && t <= b.stamp_s)) continue;
    const double span = b.stamp_s - a.stamp_s;
    const float u = span > 0.0 ? static_cast<float>((t - a.stamp_s) / span) : 0.0f;
    const float dth = std::remainder(b.pose.theta - a.pose.theta, 2.0f * std::numbers::pi_v<float>);
    return {a.pose.x + u * (b.pose.x - a.pose.x), a.pose.y + u * (b.pose.y - a.pose.y),
            std::remainder(a.pose.theta + u * dth, 2.0f * std::numbers::pi_v<float>)};
  }
  return fallback.pose;
}

Pose2 ExplorationRuntime::correct(std::span<const SensorFrame> frames, const Pose2& odom, Pose2 prior, double t) {
  const auto t0 = std::chrono::steady_clock::now();
  const PoseCorrectionSettings& pc = settings_.pose_correction;
  constexpr float kTwoPi = 2.0f * std::numbers::pi_v<float>;
  // Predict: the heading drifts at the estimated rate since the last update.
  const double dt = last_match_t_ >= 0.0 ? std::max(0.0, t - last_match_t_) : 0.0;
  last_match_t_ = t;
  prior.theta = std::remainder(prior.theta + heading_rate_ * static_cast<float>(dt), kTwoPi);
  const OccupancyGrid& grid = mapper_.grid();
  // Obstacle points of the frames in the robot frame, one per grid cell (the first in pixel
  // order), heights relative to the floor of the map frame.
  BackProjectionSettings bp = profile_.mapping.back_projection;
  bp.pixel_step = pc.pixel_step;
  back_project(frames, bp, scan_cloud_);
  const float floor_z = profile_.mapping.segmentation.floor_z_m;
  const float res = grid.resolution();
  scan_keys_.clear();
  for (std::size_t i = 0; i < scan_cloud_.size(); ++i) {
    const Eigen::Vector3f& p = scan_cloud_.points[i];
    const float h = p.z() - floor_z;
    if (!(h >= pc.min_height_m && h <= pc.max_height_m)) continue;
    scan_keys_.emplace_back(cell_key(p.x(), p.y(), res), static_cast<std::uint32_t>(i));
  }
  std::sort(scan_keys_.begin(), scan_keys_.end());
  scan_keys_.erase(std::unique(scan_keys_.begin(), scan_keys_.end(), [](const auto& a, const auto& b) { return a.first == b.first; }),
                   scan_keys_.end());
  const std::size_t stride = (scan_keys_.size() + pc.max_points - 1) / pc.max_points;
  scan_points_.clear();
  for (std::size_t k = 0; k < scan_keys_.size(); k += std::max<std::size_t>(stride, 1)) {
    const Eigen::Vector3f& p = scan_cloud_.points[scan_keys_[k].second];
    scan_points_.emplace_back(p.x(), p.y());
  }
  Pose2 at = prior;  // not accepted: the predicted drift still applies
  bool accepted = false;
  // The reference map (PoseCorrectionSettings::reference_age_s): the copy before the latest.
  if (pc.reference_age_s <= 0.0) {
    if (grid.width() > 0 && grid.height() > 0) {
      occupied_distance(GridView(grid), profile_.exploration.cells, distance_);
      have_reference_ = true;
    }
  } else if (pending_t_ < 0.0 || t - pending_t_ >= pc.reference_age_s) {
    if (pending_t_ >= 0.0 && pending_grid_.width() > 0 && pending_grid_.height() > 0) {
      occupied_distance(GridView(pending_grid_), profile_.exploration.cells, distance_);
      have_reference_ = true;
    }
    pending_grid_ = grid;
    pending_t_ = t;
  }
  if (have_reference_ && scan_points_.size() >= pc.match.min_points) {
    const ScanMatchResult r = scan_match(distance_.clearance(), scan_points_, prior, pc.match);
    if (r.status == ScanMatchStatus::kMatched) {
      const float g = pc.gain;
      const float e_theta = std::remainder(r.pose.theta - prior.theta, kTwoPi);
      at = Pose2{prior.x + g * (r.pose.x - prior.x), prior.y + g * (r.pose.y - prior.y), std::remainder(prior.theta + g * e_theta, kTwoPi)};
      if (dt > 0.0 && pc.rate_gain > 0.0f) {
        const float k = std::max(pc.rate_gain, 1.0f / (1.0f / pc.rate_gain_initial + static_cast<float>(rate_updates_++)));
        heading_rate_ += k * e_theta / static_cast<float>(dt);
      }
      accepted = true;
    }
  }
  correction_ = compose(at, inverse(odom));
  ++(accepted ? stats_.scan_matches : stats_.scan_match_rejected);
  stats_.scan_match_time_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return at;
}

void ExplorationRuntime::tick(double now_s) {
  const std::size_t n = sensors_.size();
  // 1. Odometry (pose at up to the odometry rate) and frames into the synchronizer.
  for (OdometryMsg& m : chassis_.take_odometry()) {
    ++stats_.odometry_received;
    odom_pose_ = m.pose;
    pose_ = compose(correction_, m.pose);
    if (odom_history_.empty() || m.stamp_s > odom_history_.back().stamp_s) odom_history_.push_back(m);
    while (odom_history_.size() > kOdomHistory) odom_history_.pop_front();
    odom_twist_ = m.twist;
    const std::uint64_t id = next_id_++;
    const double stamp = m.stamp_s;
    odometry_.emplace(id, m);
    (void)sync_.add(n, stamp, id);  // a refused message comes back in take_drops()
  }
  if (pose_override_) pose_ = *pose_override_;
  for (std::size_t i = 0; i < n; ++i)
    for (StampedRgbd& f : sensors_[i]->take_frames()) {
      ++stats_.frames_received;
      const std::uint64_t id = next_id_++;
      frames_.emplace(id, std::move(f.image));
      (void)sync_.add(i, f.stamp_s, id);  // a refused message comes back in take_drops()
    }
  // 2. Synchronized sets -> mapper (map rate) -> explorer's map; drops release their payloads.
  for (const auto& set : sync_.take_sets()) integrate(set, now_s);
  for (const auto& d : sync_.take_drops()) {
    if (d.stream < n) {
      ++stats_.frame_drops;
      auto it = frames_.find(d.id);
      if (it != frames_.end()) {
        sensors_[d.stream]->recycle(std::move(it->second));
        frames_.erase(it);
      }
    } else {
      ++stats_.odometry_unmatched;
      odometry_.erase(d.id);
    }
  }
  // 3-4. Control on the pose estimate.
  last_cmd_ = explorer_.control(pose_, odom_twist_, now_s);
  chassis_.command(last_cmd_);
}

}  // namespace duet
