#include <duet_ros/tf_mounts.hpp>

#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2/LinearMath/Transform.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace duet_ros {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// The optical axes in the body frame (columns): optical x = -body y, y = -body z, z = body x.
tf2::Matrix3x3 body_R_optical() { return tf2::Matrix3x3(0, 0, 1, -1, 0, 0, 0, -1, 0); }

std::string list3(double a, double b, double c) {
  std::ostringstream s;
  s.precision(9);
  s << "[" << a << ", " << b << ", " << c << "]";
  return s.str();
}

}  // namespace

std::vector<std::string> mount_overrides(std::size_t index, const std::string& sensor_name,
                                         const geometry_msgs::Transform& T_base_optical) {
  const auto& t = T_base_optical.translation;
  const auto& q = T_base_optical.rotation;
  const std::string who = "sensor " + std::to_string(index) + " (" + sensor_name + ")";
  for (double v : {t.x, t.y, t.z, q.x, q.y, q.z, q.w})
    if (!std::isfinite(v)) throw std::invalid_argument(who + ": its mount from tf is not finite");
  const double norm = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (std::abs(norm - 1.0) > 1e-3)
    throw std::invalid_argument(who + ": its mount's rotation from tf is not a unit quaternion (norm " + std::to_string(norm) + ")");
  // T_base_body = T_base_optical * T_optical_body: the rotation R_base_optical * R_body_optical^T.
  const tf2::Matrix3x3 base_R_optical(tf2::Quaternion(q.x / norm, q.y / norm, q.z / norm, q.w / norm));
  const tf2::Matrix3x3 base_R_body = base_R_optical * body_R_optical().transpose();
  double yaw = 0, pitch = 0, roll = 0;
  base_R_body.getEulerYPR(yaw, pitch, roll);  // R = Rz(yaw) Ry(pitch) Rx(roll): Eq. (6)'s [theta, phi, psi]
  const double deg = 180.0 / kPi;
  const std::string key = "sensors." + std::to_string(index) + ".extrinsics.";
  return {key + "xyz_m=" + list3(t.x, t.y, t.z), key + "zyx_euler_deg=" + list3(yaw * deg, pitch * deg, roll * deg)};
}

geometry_msgs::Transform optical_from_mount(const double xyz_m[3], const double zyx_euler_deg[3]) {
  const double rad = kPi / 180.0;
  tf2::Matrix3x3 base_R_body;
  base_R_body.setEulerYPR(zyx_euler_deg[0] * rad, zyx_euler_deg[1] * rad, zyx_euler_deg[2] * rad);
  tf2::Quaternion q;
  (base_R_body * body_R_optical()).getRotation(q);
  geometry_msgs::Transform T;
  T.translation.x = xyz_m[0];
  T.translation.y = xyz_m[1];
  T.translation.z = xyz_m[2];
  T.rotation.x = q.x();
  T.rotation.y = q.y();
  T.rotation.z = q.z();
  T.rotation.w = q.w();
  return T;
}

}  // namespace duet_ros
