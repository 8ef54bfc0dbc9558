#pragma once
/// @file pose_ekf.hpp
/// Extended Kalman filter of the robot's planar pose, fusing the wheels, a gyro and visual
/// odometry (paper §2.1: "the RGB-D localization and wheel odometry can be fused by means of an
/// extended Kalman filter in order to achieve robust localization").
///
/// State: x = [px, py, theta, k, b | kx, ky, ktheta] - the pose in the odom frame [m, rad], the
/// wheels' errors - a speed scale k (the true speed is k times the wheels') and a yaw-rate bias
/// b (the wheels report omega + b), random walks - and a clone of the pose at the last location
/// point (stochastic cloning, Roumeliotis & Burdick 2002): a visual increment measures the
/// motion from the location point to now, so it measures the current pose relative to the
/// clone, with their correlation kept.
///  - predict(dt, v, omega, gyro): the wheels' speeds (or the gyro's yaw rate) drive the motion:
///    v' = k v, omega' = omega - b (a gyro's rate is taken as is), px += v' cos(theta) dt,
///    py += v' sin(theta) dt, theta += omega' dt. The speed noise (wheel_speed_sigma, or
///    gyro_sigma for the rate) enters per step; k and b walk.
///  - update_visual(d, R): h(x) = [R(ktheta)^T (p - k_xy); theta - ktheta]. The innovation's
///    squared Mahalanobis distance must stay below gate_chi2 (chi-square, 3 dof): a sudden visual
///    jump (a wrong match set) is rejected and counted, so it cannot move the pose control follows.
///    With learn_wheels = false the update is a Schmidt ("consider") update: k and b keep their
///    values (their rows of the gain are zero) while their uncertainty still enters the pose's -
///    a weakly constrained increment (few features) corrects the pose but does not recalibrate the
///    wheels, which would otherwise absorb its error and carry it on after vision is gone. The
///    Joseph form keeps the covariance right for that gain.
///  - clone(): the location point moved to now; k's correlation with the pose is dropped there,
///    so an increment teaches k from the motion since the location point and does not move
///    the whole path driven before it (see clone()).
/// The velocity is the wheels' (corrected), not a state: wheel odometry at 50 Hz is not 50
/// independent measurements of the speed - its error is systematic (tyre radius, slip on one
/// floor). A filter that takes each message as one becomes sure of a wrong speed and averages
/// vision away; here the wheels are the motion model, vision is the measurement, and k and b
/// are learnt while vision sees - where it stops seeing, the wheels carry on calibrated, and
/// without vision k and b stay where they were (they are unobservable from the wheels alone).
/// Updates use the Joseph form. Angles are wrapped to (-pi, pi].
/// Thread safety: one thread at a time.
#include <duet/kernels/motion_model.hpp>

#include <Eigen/Core>

#include <cstddef>

namespace duet {

struct PoseEkfSettings {
  float wheel_speed_sigma = 0.02f;     ///< the wheels' speed noise per message [m/s], (0, 10]
  float wheel_yaw_rate_sigma = 0.05f;  ///< their yaw-rate noise per message [rad/s], (0, 10]
  float gyro_sigma = 0.002f;           ///< a gyro's yaw-rate noise per message [rad/s], (0, 10] (at 50 Hz: 2.8e-4 rad/s/sqrt(Hz), a consumer MEMS gyro)
  float wheel_scale_sigma = 0.05f;     ///< prior std of the speed scale k (about 1), (0, 1]
  float wheel_bias_sigma = 0.05f;      ///< prior std of the yaw-rate bias b [rad/s], (0, 1]
  float wheel_scale_walk = 0.02f;      ///< k's random walk [1/sqrt(s)], [0, 1] (slip on a new floor changes it within seconds)
  float wheel_bias_walk = 0.001f;      ///< b's random walk [rad/s/sqrt(s)], [0, 1]
  float visual_min_sigma_m = 0.005f;   ///< floor of a visual increment's position std [m], [0, 1]
  float visual_min_sigma_deg = 0.2f;   ///< floor of its heading std [deg], [0, 10]
  float gate_chi2 = 16.27f;            ///< visual gate (chi-square 3 dof, 99.9 %), (0, 1000]
};
/// Throws duet::Error(kInvalidArgument) naming the bad field.
void validate(const PoseEkfSettings& s);

class PoseEkf {
 public:
  static constexpr int kN = 8;  ///< state size
  using State = Eigen::Matrix<double, kN, 1>;
  using Covariance = Eigen::Matrix<double, kN, kN>;

  explicit PoseEkf(const PoseEkfSettings& settings = {}, const Pose2& start = {});

  /// Starts over at `pose` (k = 1, b = 0 with their prior spread, the clone at the pose).
  void reset(const Pose2& pose);
  /// Moves the state dt [s] on the wheels' speed v [m/s] and yaw rate omega [rad/s] - or, with
  /// gyro = true, on a gyro's rate (no bias applied). dt <= 0 or a non-finite input: nothing.
  void predict(double dt, double v, double omega, bool gyro = false);
  /// A visual increment d = (dx, dy, dtheta) from the clone to now (clone's robot frame) with its
  /// 3 x 3 covariance (floored at the settings' sigmas). Returns false when gated out (the
  /// state is unchanged) or when the innovation covariance is not positive definite.
  /// learn_wheels = false: k and b are not updated (a consider update, see above).
  bool update_visual(const Eigen::Vector3d& d, const Eigen::Matrix3d& covariance, bool learn_wheels = true);
  /// The clone becomes the current pose (a new location point).
  void clone();

  [[nodiscard]] Pose2 pose() const noexcept;
  /// The corrected speed and yaw rate of the last prediction.
  [[nodiscard]] Twist twist() const noexcept { return twist_; }
  [[nodiscard]] Pose2 clone_pose() const noexcept;
  /// The wheels' estimated speed scale (true speed = scale x theirs) and yaw-rate bias [rad/s].
  [[nodiscard]] double wheel_scale() const noexcept { return x_(3); }
  [[nodiscard]] double wheel_bias() const noexcept { return x_(4); }
  [[nodiscard]] const State& state() const noexcept { return x_; }
  [[nodiscard]] const Covariance& covariance() const noexcept { return P_; }
  /// The last visual update's squared Mahalanobis distance (accepted or not).
  [[nodiscard]] double last_visual_chi2() const noexcept { return last_chi2_; }
  [[nodiscard]] std::size_t visual_accepted() const noexcept { return accepted_; }
  [[nodiscard]] std::size_t visual_rejected() const noexcept { return rejected_; }

 private:
  PoseEkfSettings settings_;
  State x_ = State::Zero();
  Covariance P_ = Covariance::Zero();
  Twist twist_;
  double last_chi2_ = 0.0;
  std::size_t accepted_ = 0, rejected_ = 0;
};

}  // namespace duet
