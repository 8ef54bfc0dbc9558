#pragma once
/// @file push_robot.hpp
/// A robot whose data is pushed in from outside - driver callbacks, the C API (duet_runtime.h),
/// a replay - as a RobotSource (robot_source.hpp): frames and odometry are pushed from any
/// thread into bounded queues, and the runtime's control thread takes them at its next tick.
/// The latest velocity command the runtime gave is read back from any thread.
///
/// Time: pushed stamps are on the caller's clock. The runtime works on a time line near 0, so
/// the queues hand out stamp - origin (set_time_origin(); 0 until set). A stamp that is not
/// finite passes through unchanged: the runtime's input guard drops and counts it, as it does
/// for out-of-order and duplicate stamps.
///
/// Bounded: a sensor's queue keeps at most PushRobotSettings::frame_queue frames and the
/// odometry queue odometry_queue messages; when a push finds the queue full, the oldest entry is
/// dropped and counted (PushStats) - a runtime that does not tick cannot grow the memory.
///
/// Gyro: when yaw-rate samples are pushed (push_gyro), the odometry the runtime takes gets its
/// heading from the gyro and its distance from the wheels - what a Kobuki's firmware does, and
/// what keeps the heading when the wheels slip. Each wheel message's heading change is the gyro's
/// integral over the time since the previous message (each sample holds its rate back to the
/// sample before); a step the gyro does not cover keeps the wheels' heading change (counted).
///
/// Thread safety: push_*(), latest_command(), stats() and spare_image() from any thread; the
/// interfaces' take_*(), command() and recycle() from the runtime's control thread.
#include <duet/runtime/robot/robot_io.hpp>
#include <duet/runtime/robot/robot_source.hpp>

#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <utility>
#include <span>
#include <vector>

namespace duet {

struct PushRobotSettings {
  std::size_t frame_queue = 8;       ///< frames kept per sensor until the runtime takes them, [1, 1024]
  std::size_t odometry_queue = 1024; ///< odometry messages kept until the runtime takes them, [1, 1e6]
  std::size_t gyro_queue = 4096;     ///< gyro samples kept until the runtime takes them, [1, 1e6]
};
void validate(const PushRobotSettings& s);

/// What the queues saw (all counters since construction).
struct PushStats {
  std::uint64_t frames_pushed = 0;
  std::uint64_t frames_overflowed = 0;    ///< oldest frames dropped because the runtime did not take them in time
  std::uint64_t odometry_pushed = 0;
  std::uint64_t odometry_overflowed = 0;  ///< oldest odometry dropped likewise
  std::uint64_t gyro_pushed = 0;
  std::uint64_t gyro_overflowed = 0;      ///< oldest gyro samples dropped likewise
  std::uint64_t gyro_invalid = 0;         ///< non-finite stamp or rate, or a stamp not after the previous: dropped
  std::uint64_t gyro_gaps = 0;            ///< odometry steps the gyro did not cover: the wheels' heading kept
};

class PushRobot;

/// The chassis side: odometry in, the runtime's command out.
class PushChassis final : public ChassisInterface {
 public:
  void command(const Twist& cmd) override;
  [[nodiscard]] std::vector<OdometryMsg> take_odometry() override;

 private:
  friend class PushRobot;
  explicit PushChassis(PushRobot& robot) : robot_(robot) {}
  PushRobot& robot_;
};

/// One sensor's side: frames in.
class PushSensor final : public RgbdSensorInterface {
 public:
  [[nodiscard]] std::vector<StampedRgbd> take_frames() override;
  void recycle(RgbdImage&& image) override;

 private:
  friend class PushRobot;
  PushSensor(PushRobot& robot, std::size_t index) : robot_(robot), index_(index) {}
  PushRobot& robot_;
  std::size_t index_;
};

class PushRobot final : public RobotSource {
 public:
  /// `sensors`: the number of RGB-D sensors (the profile's), [1, 16]. Throws
  /// duet::Error(kInvalidArgument) for a bad count or settings.
  explicit PushRobot(std::size_t sensors, const PushRobotSettings& settings = {});
  PushRobot(const PushRobot&) = delete;
  PushRobot& operator=(const PushRobot&) = delete;

  /// Queues a frame of sensor i (stamp on the caller's clock). Any thread. Throws
  /// duet::Error(kInvalidArgument) for a sensor index out of range.
  void push_frame(std::size_t sensor, double stamp_s, RgbdImage&& image);
  /// Queues an odometry message (stamp on the caller's clock). Any thread.
  void push_odometry(const OdometryMsg& msg);
  /// Queues a gyro sample: the yaw rate [rad/s, counter-clockwise] measured up to stamp_s (the
  /// caller's clock). From the first sample on, the odometry's heading comes from the gyro. Any thread.
  void push_gyro(double stamp_s, float yaw_rate_rps);
  /// A buffer a consumed frame left behind, for the next push to fill (empty if none). Any thread.
  [[nodiscard]] RgbdImage spare_image();
  /// The latest command the runtime gave (zero before the first). Any thread.
  [[nodiscard]] Twist latest_command() const;
  [[nodiscard]] PushStats stats() const;
  /// The caller's clock time that is 0 on the runtime's time line. Any thread; takes effect for
  /// what is taken from then on.
  void set_time_origin(double origin_s) noexcept { origin_.store(origin_s, std::memory_order_relaxed); }
  [[nodiscard]] double time_origin() const noexcept { return origin_.load(std::memory_order_relaxed); }

  [[nodiscard]] ChassisInterface& chassis() override { return chassis_; }
  [[nodiscard]] std::span<RgbdSensorInterface* const> sensors() override { return ifaces_; }
  /// Nothing to move on: the pushers deliver on their own.
  void advance(double now_s) override { (void)now_s; }

 private:
  friend class PushChassis;
  friend class PushSensor;

  PushRobotSettings settings_;
  PushChassis chassis_;
  std::vector<std::unique_ptr<PushSensor>> sensor_objs_;
  std::vector<RgbdSensorInterface*> ifaces_;
  std::atomic<double> origin_{0.0};

  // The control thread's gyro fusion (take_odometry).
  void fuse(std::vector<OdometryMsg>& msgs, std::deque<std::pair<double, float>>&& gyro);
  bool gyro_on_ = false;                              ///< a gyro sample was seen
  std::deque<std::pair<double, float>> gyro_hist_;    ///< samples (runtime time, rate), oldest first
  std::optional<OdometryMsg> last_wheel_;             ///< the previous wheel message (raw)
  Pose2 fused_;                                       ///< the fused pose of that message
  double last_gyro_t_ = -1e300;

  mutable std::mutex mutex_;  ///< guards everything below
  std::vector<std::deque<StampedRgbd>> frames_;
  std::deque<OdometryMsg> odometry_;
  std::deque<std::pair<double, float>> gyro_;  ///< (stamp, rate) pushed, not yet taken
  std::vector<RgbdImage> spare_;
  Twist command_;
  PushStats stats_;
};

}  // namespace duet
