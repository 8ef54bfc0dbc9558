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
/// Thread safety: push_*(), latest_command(), stats() and spare_image() from any thread; the
/// interfaces' take_*(), command() and recycle() from the runtime's control thread.
#include <duet/runtime/robot/robot_io.hpp>
#include <duet/runtime/robot/robot_source.hpp>

#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

namespace duet {

struct PushRobotSettings {
  std::size_t frame_queue = 8;       ///< frames kept per sensor until the runtime takes them, [1, 1024]
  std::size_t odometry_queue = 1024; ///< odometry messages kept until the runtime takes them, [1, 1e6]
};
void validate(const PushRobotSettings& s);

/// What the queues saw (all counters since construction).
struct PushStats {
  std::uint64_t frames_pushed = 0;
  std::uint64_t frames_overflowed = 0;    ///< oldest frames dropped because the runtime did not take them in time
  std::uint64_t odometry_pushed = 0;
  std::uint64_t odometry_overflowed = 0;  ///< oldest odometry dropped likewise
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

  mutable std::mutex mutex_;  ///< guards everything below
  std::vector<std::deque<StampedRgbd>> frames_;
  std::deque<OdometryMsg> odometry_;
  std::vector<RgbdImage> spare_;
  Twist command_;
  PushStats stats_;
};

}  // namespace duet
