#pragma once
/// @file input_guard.hpp
/// What the runtime does about inputs a misbehaving driver, clock or wheel delivers (issue 19,
/// part 3): every odometry message and frame passes here before the synchronizer.
///
///  - A non-finite stamp, pose or twist, or a frame of the wrong size: dropped and counted.
///  - Odometry stamps that step back and stay behind (clock_step_messages messages in a row, in
///    order among themselves: a clock reset or an NTP step): kRestart - the runtime restarts its
///    synchronizer and odometry history on the new time base. A message behind on its own (out
///    of order, duplicated) and frames behind their sensor's last: dropped and counted.
///  - An odometry step no chassis makes (farther than jump_speed_factor x the chassis' top
///    speeds allow in the time between the messages, plus a margin): the odometry frame is
///    moved so that the message continues the previous one (the pose estimate does not jump;
///    scan matching corrects what the robot did move), counted.
///  - A frame with no depth return at all: counted (mapped: it adds nothing). A frame whose
///    depth is noise (most neighbouring pixels differ by more than garbled_step_m - a real
///    scene is piecewise smooth): counted and replaced by a missing frame.
///  - A sensor silent for sensor_timeout_periods frame periods while another delivers: counted
///    once per silence; the runtime maps with the others (silent_sensors() names the sensors to
///    add a missing frame for, so that sets still form) until it speaks again.
///
/// Each event is logged (events(), capped) with its time. Not thread-safe: the control thread.
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/robot/input_guard_settings.hpp>
#include <duet/runtime/robot/robot_io.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace duet {

struct InputStats {
  std::uint64_t odometry_invalid = 0;       ///< non-finite stamp, pose or twist: dropped
  std::uint64_t odometry_out_of_order = 0;  ///< stamp not after the previous one: dropped
  std::uint64_t odometry_jumps = 0;         ///< steps no chassis makes: absorbed into the odometry frame
  std::uint64_t frames_invalid = 0;         ///< non-finite stamp or wrong size: dropped
  std::uint64_t frames_out_of_order = 0;    ///< stamp not after the sensor's previous frame: dropped
  std::uint64_t frames_empty = 0;           ///< no depth return at all (mapped: they add nothing)
  std::uint64_t frames_garbled = 0;         ///< depth that is noise: mapped as missing
  std::uint64_t clock_restarts = 0;         ///< stamps stepped back beyond clock_step_back_s
  std::uint64_t sensor_silences = 0;        ///< a sensor went silent while another delivered
  std::uint64_t missing_frames = 0;         ///< missing frames added for silent sensors
};

struct RuntimeEvent {
  double t_s = 0.0;  ///< runtime clock [s]
  std::string what;
};

class InputGuard {
 public:
  enum class Verdict { kAccept, kDrop, kRestart };

  InputGuard(const Profile& profile, double sensor_rate_hz, const InputGuardSettings& settings = {});

  /// Checks one odometry message (may rewrite its pose: a jump absorbed). kRestart: the caller
  /// restarts its time base (restart()), then passes the message again.
  Verdict odometry(OdometryMsg& m, double now_s);
  /// Checks one frame of sensor i. On kAccept, `missing` says the frame's depth was noise: map
  /// it as a missing frame.
  Verdict frame(std::size_t i, const StampedRgbd& f, double now_s, bool& missing);
  /// The sensors now considered silent for which a missing frame should be added beside a frame
  /// stamped `stamp` of another sensor (their last stamps are advanced to it). Call after every
  /// frame of the period has passed frame(), so a sensor that delivered is not silent.
  std::vector<std::size_t> silent_sensors(std::size_t from_sensor, double stamp, double now_s);
  /// Forgets the last stamps (after a restart of the time base).
  void restart(double now_s, const std::string& why);

  /// Logs an event of the runtime's own (e.g. holding still while blind).
  void note(double t, std::string what) { log(t, std::move(what)); }
  [[nodiscard]] const InputStats& stats() const noexcept { return stats_; }
  [[nodiscard]] const std::vector<RuntimeEvent>& events() const noexcept { return events_; }
  [[nodiscard]] std::uint64_t events_dropped() const noexcept { return events_dropped_; }

 private:
  void log(double t, std::string what);
  [[nodiscard]] bool garbled(const RgbdImage& image, float units_per_m, bool& empty) const;

  InputGuardSettings settings_;
  std::vector<SensorProfile> sensors_;
  double max_v_ = 0.7, max_w_ = 3.14;  // chassis top speeds [m/s, rad/s]
  double sensor_period_s_ = 1.0;
  bool have_odom_ = false;
  double last_odom_t_ = 0.0;
  int behind_ = 0;             ///< odometry messages in a row behind last_odom_t_
  double last_behind_t_ = 0.0;
  Pose2 odom_fix_;   ///< odometry frame correction for absorbed jumps
  Pose2 last_odom_;  ///< last accepted (fixed) odometry pose
  std::vector<bool> have_frame_, silent_;
  std::vector<double> last_frame_t_;
  bool have_any_frame_ = false;
  double first_frame_t_ = 0.0;  ///< the first frame's stamp (since the start or a restart)
  InputStats stats_;
  std::vector<RuntimeEvent> events_;
  std::uint64_t events_dropped_ = 0;
};

}  // namespace duet
