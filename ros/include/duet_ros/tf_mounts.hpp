#pragma once
/// @file tf_mounts.hpp
/// The sensors' mounts from tf instead of the profile (the node's ~mounts_from_tf): the pose of a
/// camera's optical frame in the robot's base frame, as the profile keys `sensors.I.extrinsics.*`
/// (Eq. (6): the sensor body's position and ZYX Euler angles in the base frame; the body frame is
/// x forward, y left, z up, the optical frame z forward, x right, y down - REP 103).
#include <geometry_msgs/Transform.h>

#include <cstddef>
#include <string>
#include <vector>

namespace duet_ros {

/// `--set` overrides that give sensor `index` the mount `T_base_optical` (the camera's optical
/// frame -> the base frame, as tf's lookupTransform(base, optical) returns it). Throws
/// std::invalid_argument for a transform that is not finite or whose rotation is not a unit
/// quaternion (within 1e-3), naming the sensor.
[[nodiscard]] std::vector<std::string> mount_overrides(std::size_t index, const std::string& sensor_name,
                                                       const geometry_msgs::Transform& T_base_optical);

/// The inverse, for tests and logs: the optical frame's pose for a profile mount (xyz [m], ZYX
/// Euler angles [deg]).
[[nodiscard]] geometry_msgs::Transform optical_from_mount(const double xyz_m[3], const double zyx_euler_deg[3]);

}  // namespace duet_ros
