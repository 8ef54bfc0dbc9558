#pragma once
/// @file chassis.hpp
/// The simulated differential-drive chassis (issue 4, part 3): a Kobuki-like base driving in a
/// sim::World by the paper's motion model, Eq. (4), with velocity and acceleration limits,
/// wheel slip, wheel odometry at 50 Hz that drifts from the truth like a real robot's, and
/// collisions that are detected, counted and stop the robot.
///
/// Model, per physics step h (fixed grid: step k covers [k h, (k+1) h]):
///  1. target = the held command clamped to |v| <= max_linear_speed_mps,
///     |omega| <= max_angular_speed_radps (paper §4.1: 0.7 m/s, 180 deg/s);
///  2. the actual (body) twist moves toward it by at most max_linear_accel_mps2 * h and
///     max_angular_accel_radps2 * h (each axis separately, like the Kobuki driver's limiter);
///  3. the wheel controller turns the wheels at the nominal rim speeds
///     u_l,r = v -/+ omega * b / 2 (b = wheel_base_m); the encoders measure these (plus noise);
///  4. the ground moves each wheel by u (1 + s) with s the wheel's slip (a stationary
///     Gauss-Markov process, std wheel_slip_std, correlation time wheel_slip_correlation_s),
///     and the effective wheel base is b (1 + wheel_base_bias) (contact points are not where the
///     nominal geometry puts them): true twist v_t = (g_l + g_r) / 2,
///     omega_t = (g_r - g_l) / (b (1 + wheel_base_bias));
///  5. true pose <- motion_step(true pose, true twist, h)               (paper Eq. (4));
///     odometry pose <- motion_step(odometry pose, twist from the measured wheel speeds and the
///     NOMINAL b, h), so odometry drifts from the truth; with slip, bias and noise 0 both are
///     the same numbers; with gyro_heading the odometry's omega is the true omega plus the
///     gyro's constant bias (drawn once from its own generator, seeded from `seed`);
///  6. collision: if sim::collides(world, centre, radius, z_low, z_high) the step is undone
///     (true pose and odometry back to the last collision-free pose, i.e. the wheels did not
///     turn), the twist is set to zero and the robot stays stopped until the next command().
///     A contact counts once: a collision is counted at a contact onset, and the contact ends
///     when the robot is more than contact_release_m away from every obstacle.
/// Odometry is published every odometry period (an integer number of physics steps) as
/// OdometryMsg, stamped with the step's time; the first message is at t = 0. The odometry
/// frame is the world frame at the start (odometry starts at the start pose).
///
/// Frames and units: world frame (z up, SI, DESIGN.md §6); Pose2 theta counter-clockwise from +x.
/// Determinism: every random draw comes from a std::mt19937_64 owned by the chassis, seeded
/// with settings.seed, drawn in a fixed order per physics step (normals by Box-Muller written
/// here, not std::normal_distribution, so any standard library gives the same numbers). The
/// result depends only on the seed and on the sequence of command() calls and the times at
/// which they happen - not on how advance() splits the time.
/// Thread safety: not thread-safe; one thread drives it (the runtime loop). The const queries
/// may run concurrently with each other, not with command()/advance()/take_odometry().
#include <duet/kernels/motion_model.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/robot/robot_io.hpp>
#include <duet/sim/solid_index.hpp>
#include <duet/sim/world.hpp>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <random>
#include <vector>

namespace duet::sim {

struct ChassisSimSettings {
  float max_linear_speed_mps = 0.7f;        ///< |v| limit [m/s], (0, 10]; paper §4.1 (Kobuki 70 cm/s)
  float max_angular_speed_radps = 3.14159265f;  ///< |omega| limit [rad/s], (0, 100]; paper §4.1 (180 deg/s)
  /// |dv/dt| [m/s^2], (0, 1e4]. 1.0: DESIGN.md / the profile's dynamic window assume 1.0 m/s^2,
  /// which the Kobuki's motors reach (its driver limits itself to 0.3 by default, a choice of
  /// smoothness, not a physical limit); the controller must not count on more.
  float max_linear_accel_mps2 = 1.0f;
  /// |domega/dt| [rad/s^2], (0, 1e4]. 3.5: the Kobuki driver's angular acceleration limit
  /// (kobuki_driver Parameters::angular_acceleration_limit = 3.5 rad/s^2); above the dynamic
  /// window's 3.0, so the controller's plans are feasible.
  float max_angular_accel_radps2 = 3.5f;
  /// Physics step h [s], [1e-5, 0.1]. 5 ms: at 0.7 m/s the robot moves 3.5 mm per step (the
  /// largest gap left to a wall after a collision), 4 steps per 50 Hz odometry period.
  double physics_step_s = 0.005;
  /// Wheel odometry rate [Hz], (0, 1000]; paper §4.1: up to 50 Hz. The period 1 / rate must be
  /// an integer multiple of physics_step_s (within 1e-6 relative).
  float odometry_rate_hz = 50.0f;
  float wheel_base_m = 0.230f;              ///< nominal distance between the wheels [m], (0, 5] (Kobuki)
  /// Per-wheel multiplicative speed error (slip) std [-], [0, 0.5]. 1 %: a hard floor.
  float wheel_slip_std = 0.01f;
  /// Correlation time of the slip [s], [0, 100] (0 = independent per physics step). 0.05 s: a
  /// wheel slips over floor irregularities for tens of ms; with 1 % slip it gives a heading
  /// random walk of about 2.5 deg (1 sigma) after 10 m straight at 0.5 m/s, and ~25 cm
  /// lateral error - the order of a Kobuki's wheel-only odometry.
  float wheel_slip_correlation_s = 0.05f;
  /// Relative error of the effective wheel base [-], [-0.2, 0.2]: the odometry over-estimates
  /// every rotation by this fraction (0.5 %: 1.8 deg per full turn, a typical calibration error).
  float wheel_base_bias = 0.005f;
  /// Encoder noise per wheel per odometry period [m], [0, 0.01]. 2.5e-5 m: the quantisation
  /// noise of a Kobuki encoder (pi * 0.070 m / 2578.33 ticks = 85 um per tick, / sqrt(12)).
  float encoder_noise_m = 2.5e-5f;
  /// A contact ends when the robot's clearance exceeds its radius by this much [m], [0, 1]
  /// (hysteresis: a robot pushing against a wall is one collision, not one per step).
  float contact_release_m = 0.01f;
  /// Heading of the odometry from a yaw gyro instead of the wheels (the Kobuki has a factory
  /// calibrated gyro and its driver uses it for the odometry's heading by default:
  /// kobuki_node use_imu_heading). Translation still comes from the wheels.
  bool gyro_heading = false;
  /// Std of the gyro's constant bias, drawn once per run from the seed [rad/s], [0, 0.1].
  /// 8.7e-5 rad/s = 0.005 deg/s = 0.3 deg/min: a MEMS yaw gyro calibrated at rest at start-up
  /// (consumer MEMS bias instability is 0.003-0.01 deg/s).
  float gyro_bias_std_radps = 8.7e-5f;
  /// The gyro's white rate noise, as a rate-noise density [rad/s/sqrt(Hz)], [0, 0.01]: each physics
  /// step adds a draw of std density / sqrt(h) to the measured omega, so the heading does an angle
  /// random walk of std density * sqrt(t). 0 = none (the default: the runs measured so far). A
  /// consumer MEMS yaw gyro is of the order of 0.01-0.03 deg/s/sqrt(Hz) = 1.7e-4 - 5.2e-4 (0.6-1.8
  /// deg after an hour). Drawn from the gyro's own generator: the wheels' noise stream and the
  /// true motion do not change with it.
  float gyro_noise_density = 0.0f;
  std::uint64_t seed = 1;                   ///< seeds the slip and encoder noise (and the gyro bias)

  /// The chassis profile's limits (max linear speed, 180 deg/s, wheel base, odometry rate), the
  /// defaults above for the rest; the physics step is the largest <= 5 ms that divides the
  /// odometry period.
  [[nodiscard]] static ChassisSimSettings from_profile(const ChassisProfile& profile);
};

/// Throws duet::Error(kInvalidArgument) naming the field and its allowed range.
void validate(const ChassisSimSettings& settings);

/// The robot's body for collision checks: a vertical cylinder.
struct ChassisBody {
  float radius_m = 0.177f;  ///< [m], (0, 5]; Kobuki body radius (the profile's chassis.radius_m)
  float z_low_m = 0.0f;     ///< bottom of the body [m], >= 0
  float z_high_m = 0.6f;    ///< top of the body with the sensor mast [m], > z_low_m, <= 10
  /// radius_m from the profile (the base touches walls; the planner inflates by more).
  [[nodiscard]] static ChassisBody from_profile(const ChassisProfile& profile);
};
void validate(const ChassisBody& body);

using OdometryMsg = duet::OdometryMsg;  // robot_io.hpp

class SimChassis final : public ChassisInterface {
 public:
  /// `world`: shared (kept alive by the chassis; the renderer shares it), validated by the
  /// caller (sim::validate). `start`: the true and odometry start pose; it must not collide.
  /// Throws duet::Error(kInvalidArgument) for a null world, invalid settings or body, a
  /// non-finite start pose or one that collides.
  SimChassis(std::shared_ptr<const World> world, const ChassisSimSettings& settings, const Pose2& start,
             const ChassisBody& body = {});

  /// The latest velocity command, held until replaced (clamped to the limits in advance()).
  /// Any call - even with the same twist - releases a collision stop. A non-finite component
  /// is treated as a stop command (0, 0) and counted in invalid_commands().
  void command(const Twist& cmd) override;

  /// Moves time on by dt_s [s], finite, in [0, 3600]: runs every physics step that ends at or
  /// before the new time (now_s()), queueing the odometry messages that fall due.
  /// Throws duet::Error(kInvalidArgument) otherwise.
  void advance(double dt_s);

  /// The time advanced to [s] (0 at construction).
  [[nodiscard]] double now_s() const noexcept { return now_s_; }
  /// The true pose at now_s(): the last physics step's pose carried on with the current true
  /// twist over the part of a step since (less than one step; no collision check there).
  [[nodiscard]] Pose2 true_pose() const noexcept;
  /// The true pose at the last completed physics step (time physics_time_s()).
  [[nodiscard]] const Pose2& physics_pose() const noexcept { return true_pose_; }
  [[nodiscard]] double physics_time_s() const noexcept { return static_cast<double>(steps_) * h_; }
  /// The true twist (what the ground does, with slip) of the last physics step.
  [[nodiscard]] Twist true_twist() const noexcept { return true_twist_; }
  /// The odometry pose at the last physics step (not only at the messages).
  [[nodiscard]] const Pose2& odometry_pose() const noexcept { return odom_pose_; }
  /// This run's constant gyro bias [rad/s] (0 without gyro_heading): the truth an estimate of
  /// the odometry heading's drift is measured against.
  [[nodiscard]] float gyro_bias() const noexcept { return settings_.gyro_heading ? gyro_bias_ : 0.0f; }
  /// Collisions (contact onsets) so far.
  [[nodiscard]] std::size_t collisions() const noexcept { return collisions_; }
  /// True while the robot touches an obstacle (between a collision and the contact's end).
  [[nodiscard]] bool in_contact() const noexcept { return in_contact_; }
  /// True while stopped by a collision and waiting for a new command.
  [[nodiscard]] bool stopped_by_collision() const noexcept { return blocked_; }
  [[nodiscard]] std::size_t invalid_commands() const noexcept { return invalid_commands_; }
  /// FAULT INJECTION (kidnap): moves the robot by `d` [m] in the world without its wheels
  /// turning (the odometry does not see it). Refused (false, nothing moves) where the body would
  /// collide or leave the floor.
  bool displace(const Eigen::Vector2f& d);
  /// Odometry messages produced since the last call, in time order.
  [[nodiscard]] std::vector<OdometryMsg> take_odometry() override;

  [[nodiscard]] const ChassisSimSettings& settings() const noexcept { return settings_; }
  [[nodiscard]] const ChassisBody& body() const noexcept { return body_; }
  [[nodiscard]] const World& world() const noexcept { return *world_; }
  /// The world changed (a door opened): collisions are checked against `world` from now on.
  /// Throws duet::Error(kInvalidArgument) if it is null.
  void set_world(std::shared_ptr<const World> world);

 private:
  void step();
  double normal();
  [[nodiscard]] bool collides_at(const Pose2& p, float extra_radius) const;

  std::shared_ptr<const World> world_;
  SolidIndex solids_;           ///< world_'s solids by place, for collides_at()
  ChassisSimSettings settings_;
  ChassisBody body_;
  double h_;                    ///< physics step [s]
  std::uint64_t steps_per_odom_;
  std::uint64_t steps_ = 0;     ///< physics steps done
  double now_s_ = 0.0;          ///< time advanced to
  Twist command_;               ///< held command (unclamped)
  Twist actual_;                ///< body twist after the acceleration limits
  Twist true_twist_;            ///< ground twist (with slip) of the last step
  Pose2 true_pose_;
  Pose2 odom_pose_;
  double slip_l_ = 0.0, slip_r_ = 0.0;    ///< current slip of each wheel
  float gyro_bias_ = 0.0f;                ///< this run's gyro bias [rad/s]
  std::mt19937_64 gyro_rng_;              ///< the gyro's white noise (gyro_noise_density)
  float gyro_step_std_ = 0.0f;            ///< std of the gyro's rate noise per physics step [rad/s]
  double odom_dist_l_ = 0.0, odom_dist_r_ = 0.0;  ///< measured wheel travel this period [m]
  bool blocked_ = false;
  bool in_contact_ = false;
  std::size_t collisions_ = 0;
  std::size_t invalid_commands_ = 0;
  std::mt19937_64 rng_;
  std::vector<OdometryMsg> odometry_;
};

}  // namespace duet::sim
