/// @file exploration_runtime.cpp
/// The exploration loop on the robot interfaces (see exploration_runtime.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/exploration_runtime.hpp>

#include <algorithm>
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
    // The mapper gets the pose at the frames' time: the synchronized odometry (or, for
    // debugging, the overriding pose).
    const Pose2 at = pose_override_ ? *pose_override_ : odom.pose;
    mapper_.integrate(frames, to_isometry(at));
    explorer_.update_map(mapper_.grid(), pose_, now_s);
    ++stats_.sets_integrated;
    while (next_map_t_ <= stamp + 1e-9) next_map_t_ += 1.0 / settings_.map_rate_hz;
  } else {
    ++stats_.sets_not_integrated;
  }
  for (std::size_t i = 0; i < n; ++i) sensors_[i]->recycle(std::move(images[i]));
}

void ExplorationRuntime::tick(double now_s) {
  const std::size_t n = sensors_.size();
  // 1. Odometry (pose at up to the odometry rate) and frames into the synchronizer.
  for (OdometryMsg& m : chassis_.take_odometry()) {
    ++stats_.odometry_received;
    pose_ = m.pose;
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
