#pragma once
/// @file faults.hpp
/// Faults injected into a running robot (issue 19, part 3), to test that the runtime survives
/// what real drivers, clocks and wheels do. A fault is written
///
///     KIND[:SENSOR]@START[+DURATION][=AMOUNT]          e.g. camera_stop:1@60+10
///
/// SENSOR numbers the profile's sensors from 1 (the paper's "sensor 1", "sensor 2"); 0 is the
/// wheel odometry for the stamp faults. START and DURATION are seconds on the runtime's clock
/// (DURATION omitted: one instant for the step faults, to the end of the run for the others).
///
///   kind              stream     what happens                                   AMOUNT (default)
///   camera_stop       sensor     no frames                                      -
///   depth_zero        sensor     every depth pixel 0 (no return)                -
///   depth_noise       sensor     every depth pixel random (a garbled frame)     -
///   color_black       sensor     every colour pixel 0                           -
///   extrinsics        sensor     the sensor's true mount yawed by AMOUNT        deg (2)
///   wheel_slip        odometry   the wheels report AMOUNT x the distance        factor (1.5)
///                                (the heading is the gyro's)
///   odom_jump         odometry   the odometry pose jumps AMOUNT m forward       m (0.5)
///   stamp_disorder    either     each message swapped with the next one         -
///   stamp_duplicate   either     each message delivered twice                   -
///   stamp_late        either     messages delivered AMOUNT s after their stamp  s (0.5)
///   clock_back        all        every stamp from START on AMOUNT s earlier     s (1.0)
///   kidnap            robot      the robot pushed AMOUNT m sideways             m (0.5)
///
/// FaultInjector applies the stream faults to any RobotSource; extrinsics and kidnap change the
/// world itself, so only the simulator applies them (sim::SimExplore). Each fault counts what it
/// did (frames dropped or changed, messages changed); the runtime's own counters (RuntimeStats)
/// say what it did about it.
#include <duet/runtime/robot/robot_io.hpp>
#include <duet/runtime/robot/robot_source.hpp>

#include <cstdint>
#include <deque>
#include <limits>
#include <memory>
#include <random>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace duet {

enum class FaultKind {
  kCameraStop,
  kDepthZero,
  kDepthNoise,
  kColorBlack,
  kExtrinsics,
  kWheelSlip,
  kOdomJump,
  kStampDisorder,
  kStampDuplicate,
  kStampLate,
  kClockBack,
  kKidnap,
};
[[nodiscard]] const char* to_string(FaultKind k);

struct Fault {
  FaultKind kind = FaultKind::kCameraStop;
  int sensor = 0;            ///< 1-based sensor; 0 = the odometry (stamp faults) or none
  double start_s = 0.0;      ///< [s] on the runtime clock
  double duration_s = std::numeric_limits<double>::infinity();  ///< [s]; +inf = to the end
  double amount = 0.0;       ///< the kind's amount (its default when not written)
  std::string spec;          ///< as written
  /// True at time t for a fault with a duration; a step fault (odom_jump, clock_back, kidnap)
  /// is active from start_s on.
  [[nodiscard]] bool active(double t) const noexcept { return t >= start_s && t < start_s + duration_s; }
};

/// Parses one fault. Throws duet::Error(kInvalidArgument) naming the spec and what is wrong
/// (unknown kind - the message lists them -, a sensor beyond `sensor_count`, a sensor where the
/// kind has none or none where it needs one, a negative or non-finite time, an amount out of
/// its range: extrinsics |deg| <= 45, wheel_slip factor in [0, 10], odom_jump and kidnap
/// |m| <= 10, stamp_late and clock_back in (0, 3600] s).
[[nodiscard]] Fault parse_fault(std::string_view spec, std::size_t sensor_count);
[[nodiscard]] std::vector<Fault> parse_faults(std::span<const std::string> specs, std::size_t sensor_count);

/// What one fault did.
struct FaultCount {
  Fault fault;
  std::uint64_t injected = 0;  ///< messages changed, dropped, delayed or duplicated; 1 for a step
};

/// A RobotSource that passes another one's data through the stream faults. The wrapped source
/// must outlive it. Deterministic for a seed (depth noise).
class FaultInjector final : public RobotSource {
 public:
  FaultInjector(RobotSource& inner, std::vector<Fault> faults, std::uint64_t seed = 1);
  ~FaultInjector() override;
  FaultInjector(const FaultInjector&) = delete;
  FaultInjector& operator=(const FaultInjector&) = delete;

  [[nodiscard]] ChassisInterface& chassis() override;
  [[nodiscard]] std::span<RgbdSensorInterface* const> sensors() override;
  void advance(double now_s) override;

  [[nodiscard]] std::vector<FaultCount> counts() const;
  /// Counts a fault applied outside the injector (the simulator's extrinsics and kidnap).
  void count(std::size_t fault_index, std::uint64_t n = 1);
  [[nodiscard]] const std::vector<Fault>& faults() const noexcept { return faults_; }

 private:
  class Chassis;
  class Sensor;
  RobotSource& inner_;
  std::vector<Fault> faults_;
  std::vector<std::uint64_t> injected_;
  double now_s_ = 0.0;
  std::unique_ptr<Chassis> chassis_;
  std::vector<std::unique_ptr<Sensor>> sensors_;
  std::vector<RgbdSensorInterface*> ifaces_;
};

}  // namespace duet
