#pragma once
/// @file robot_io.hpp
/// What the runtime needs from a robot (issue 4, DESIGN.md §3): a chassis that takes velocity
/// commands and publishes wheel odometry, and RGB-D sensors that publish stamped frames. The
/// simulator (sim/sim_explore.hpp) is the first implementation; recorded-data replay, the C API
/// and real drivers implement the same two interfaces.
///
/// Time: every stamp is in seconds on the runtime's clock (clock.hpp).
/// Thread safety: the runtime calls an interface from one thread; implementations that are fed
/// by driver threads must synchronise internally.
#include <duet/kernels/back_projection.hpp>
#include <duet/kernels/motion_model.hpp>
#include <duet/runtime/config/profile.hpp>

#include <Eigen/Geometry>

#include <cstdint>
#include <optional>
#include <vector>

namespace duet {

/// One RGB-D frame: 16-bit depth in the sensor's depth units (0 = no return) and 8-bit RGB
/// registered to it. Buffers are reused across frames where the producer can.
struct RgbdImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint16_t> depth;  ///< width * height raw depth units, row-major; 0 = no return
  std::vector<std::uint8_t> rgb;     ///< width * height * 3, R G B; empty = no colour
  /// This frame's own pinhole intrinsics (a camera that reports them per frame; the size must be
  /// the sensor's); nullopt: the sensor's from the profile. Used to back-project this frame; the
  /// planner's sensor fans stay the profile's.
  std::optional<PinholeIntrinsics> intrinsics;
};

/// The views of `image` the mapper takes (DepthImageView kU16 in sensor.depth_units_per_m,
/// ColorImageView RGB - null data when the image has no colour - the sensor's intrinsics and
/// T_robot_camera = T_robot_optical). The views point into `image`: keep it alive and
/// unchanged while they are used. Throws duet::Error(kInvalidArgument) when the image's size
/// does not match the sensor's intrinsics or its buffers.
[[nodiscard]] SensorFrame frame_view(const RgbdImage& image, const SensorProfile& sensor,
                                     const Eigen::Isometry3f& T_robot_optical);

/// The planar pose as a 3D transform (rotation about z by theta, z = 0): T_world_robot of a
/// robot on the floor, as the mapper takes it.
[[nodiscard]] Eigen::Isometry3f to_isometry(const Pose2& pose);

/// A stamped frame of one sensor.
struct StampedRgbd {
  double stamp_s = 0.0;
  RgbdImage image;
};

/// One wheel odometry message.
struct OdometryMsg {
  double stamp_s = 0.0;  ///< [s] on the runtime clock
  Pose2 pose;            ///< odometry pose (odometry frame) [m, rad]
  Twist twist;           ///< mean measured twist over the last odometry period [m/s, rad/s]
};

/// A differential-drive chassis as the runtime sees it.
class ChassisInterface {
 public:
  virtual ~ChassisInterface() = default;
  /// The latest velocity command [m/s, rad/s], held until replaced.
  virtual void command(const Twist& cmd) = 0;
  /// Odometry messages produced since the last call, in time order.
  [[nodiscard]] virtual std::vector<OdometryMsg> take_odometry() = 0;
};

/// An RGB-D sensor as the runtime sees it (its geometry and intrinsics are in the profile).
class RgbdSensorInterface {
 public:
  virtual ~RgbdSensorInterface() = default;
  /// Frames captured since the last call, oldest first.
  [[nodiscard]] virtual std::vector<StampedRgbd> take_frames() = 0;
  /// Gives a consumed frame's buffers back for reuse (optional).
  virtual void recycle(RgbdImage&& image) { (void)image; }
};

}  // namespace duet
