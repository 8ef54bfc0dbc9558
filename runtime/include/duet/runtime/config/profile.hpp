#pragma once
/// @file profile.hpp
/// Robot profiles: the chassis, the RGB-D sensors with their intrinsics and their pose on the
/// robot (paper Eq. (6)), and the mapping settings, read from YAML (profiles/*.yaml, DESIGN.md §5).
///
/// YAML is read only here, at the edge, into the kernels' settings structs. Every problem is
/// a duet::Error whose message names the file (with line:column where known), the key path
/// (e.g. `sensors[1].extrinsics.zyx_euler_deg`) and what was expected, with the allowed range:
///   - the file cannot be read                                   -> ErrorCode::kIo
///   - malformed YAML, an unknown key (with a "did you mean"), a
///     duplicate key, a missing required key, a wrong type, a
///     sequence of the wrong length                              -> ErrorCode::kParse
///   - a value out of its range or inconsistent with another     -> ErrorCode::kInvalidArgument
/// Optional keys take the in-class defaults of the structs below. The schema is written in
/// the header comment of profiles/dual_kinect_kobuki.yaml and in the field comments here.
///
/// Frames (DESIGN.md §6, REP 103/105): robot base x forward, y left, z up; a sensor's body
/// frame x forward, y left, z up; its optical frame z forward, x right, y down.
///
/// Thread safety: all functions are reentrant (no global mutable state); Profile is a value type.
#include <duet/runtime/robot/runtime_settings.hpp>
#include <duet/kernels/back_projection.hpp>
#include <duet/kernels/dwa.hpp>
#include <duet/kernels/exploration.hpp>
#include <duet/kernels/grid.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/kernels/observation.hpp>
#include <duet/kernels/path.hpp>
#include <duet/kernels/normals.hpp>
#include <duet/kernels/segmentation.hpp>
#include <duet/kernels/voxel_filter.hpp>

#include <Eigen/Geometry>

#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace duet {

/// The mobile base. YAML key `chassis`.
struct ChassisProfile {
  std::string type = "differential";   ///< drive type; only "differential" is supported (required)
  float radius_m = 0.177f;             ///< body radius of the base [m], (0, 5] (required)
  /// Paper §4.1 says the Kobuki is "driven by the two wheels, with a diameter of 0.46 m"; a
  /// Kobuki wheel is 0.070 m, so duet reads it as the footprint diameter of the robot with the
  /// sensor mast and both Kinects mounted [m], (0, 10] (optional).
  float footprint_diameter_m = 0.46f;
  float wheel_base_m = 0.230f;         ///< distance between the drive wheels [m], (0, 5] (optional)
  float wheel_diameter_m = 0.070f;     ///< drive wheel diameter [m], (0, 2] (optional)
  float max_linear_speed_mps = 0.7f;   ///< [m/s], (0, 10] (required)
  float max_angular_speed_dps = 180.0f;///< [deg/s], (0, 3600] (required)
  float odometry_rate_hz = 50.0f;      ///< wheel odometry rate [Hz], (0, 1000] (optional)

  /// max_angular_speed_dps in [rad/s] (derived, so the two can never disagree).
  [[nodiscard]] float max_angular_speed_radps() const noexcept {
    return max_angular_speed_dps * 0.017453292519943295f;
  }
};

/// The pose of a sensor's body frame (x forward, y left, z up) relative to the robot base,
/// as in the paper's Eq. (6). YAML key `sensors[i].extrinsics` (both keys required).
struct SensorExtrinsics {
  Eigen::Vector3f xyz_m = Eigen::Vector3f::Zero();  ///< [x, y, z] of the body origin [m], each in [-10, 10]
  /// ZYX Euler angles [theta, phi, psi] [deg], each in [-360, 360]: R = Rz(theta) Ry(phi) Rx(psi)
  /// (theta = yaw about z, phi = pitch about y, psi = roll about x).
  Eigen::Vector3f zyx_euler_deg = Eigen::Vector3f::Zero();
};

/// One RGB-D sensor. YAML: an element of `sensors`.
struct SensorProfile {
  std::string name;              ///< unique among the profile's sensors, non-empty (required)
  /// Intrinsics (required, YAML `intrinsics`): `width`, `height` [px] in [1, 16384], then either
  /// `fx`, `fy`, `cx`, `cy` [px] (calibrated; fx, fy in (0, 1e6], cx in [0, width],
  /// cy in [0, height]) or `fov_h_deg`, `fov_v_deg` in (0, 180) with optional `cx`, `cy`
  /// (default: image centre (w-1)/2, (h-1)/2), giving fx = (w/2) / tan(fov_h/2),
  /// fy = (h/2) / tan(fov_v/2).
  PinholeIntrinsics intrinsics;
  float fov_h_deg = 57.0f;       ///< horizontal field of view [deg] (given, or derived from fx)
  float fov_v_deg = 43.0f;       ///< vertical field of view [deg] (given, or derived from fy)
  float rate_hz = 30.0f;         ///< frame rate [Hz], (0, 1000] (optional)
  float min_depth_m = 0.5f;      ///< nearest valid depth [m], [0, 100) (optional)
  float max_depth_m = 5.0f;      ///< farthest valid depth [m], (min_depth_m, 100] (optional)
  float depth_units_per_m = 1000.0f;  ///< raw 16-bit depth units per metre, (0, 1e6] (optional)
  SensorExtrinsics extrinsics;   ///< Eq. (6) (required)

  /// Body frame -> robot base: [R | xyz] with R = Rz(theta) Ry(phi) Rx(psi) (Eq. (6)).
  [[nodiscard]] Eigen::Isometry3f T_robot_body() const;
  /// Optical frame -> robot base: T_robot_body() * T_body_optical(), the transform the
  /// back-projection kernel takes as SensorFrame::T_robot_camera.
  [[nodiscard]] Eigen::Isometry3f T_robot_optical() const;
};

/// Optical frame (z forward, x right, y down) -> body frame (x forward, y left, z up):
/// optical z = body x, optical x = -body y, optical y = -body z.
[[nodiscard]] Eigen::Isometry3f T_body_optical();

/// R = Rz(theta) Ry(phi) Rx(psi) for ZYX Euler angles [theta, phi, psi] in degrees (Eq. (6)).
[[nodiscard]] Eigen::Matrix3f rotation_from_zyx_euler_deg(const Eigen::Vector3f& zyx_euler_deg);

/// Settings of the mapping pipeline (paper §2.2, Fig. 4). YAML key `mapping` (optional, as are
/// all its keys). The sub-keys have the names of the structs' fields:
///   back_projection: {min_depth_m, max_depth_m, pixel_step}
///   voxel_filter:    {leaf_size_m, min_points_per_voxel}
///   normals:         {k, viewpoint_m: [x, y, z]}
///   segmentation:    {floor_z_m, max_floor_tilt_deg, floor_height_threshold_m, min_height_m,
///                     max_height_m, clustering: {tolerance_m, min_size, max_size}}
///   grid_update:     {hit_logodds, miss_logodds, min_logodds, max_logodds, clear_along_rays,
///                     clear_max_height_m, keep_occupied_within_m, keep_occupied_logodds,
///                     max_ray_length_m, grow_margin_cells}
///   grid_resolution_m
struct MappingSettings {
  BackProjectionSettings back_projection;
  VoxelFilterSettings voxel_filter;    ///< leaf 0.05 m (paper)
  NormalSettings normals;              ///< k = 10 (paper)
  SegmentationSettings segmentation;
  GridUpdateSettings grid_update;
  float grid_resolution_m = 0.05f;     ///< occupancy grid cell edge [m], (0, 10]
};

/// Settings of exploration and motion control (paper §3, Procedure 1, Fig. 6; DESIGN.md §1).
/// YAML key `exploration` (optional, as are all its keys); sub-keys have the structs' field names:
///   rays_per_sensor                  (the observation model's rays per sensor fan, [1, 10000])
///   cells:       {occupied_logodds, free_logodds}   (shared by observation and inflation)
///   observation: {backend: dda | embree, tile_cells}
///   inflation:   {robot_radius_m, unknown_is_obstacle, uncertain_is_obstacle}   (also the dynamic window's radius;
///                 must be >= chassis.radius_m)
///   path:        {allow_diagonal, clearance_weight, clearance_decay_m, goal_tolerance_m}
///   frontier:    {min_cluster_cells, min_goal_distance_m, blacklist_radius_m}
///   simulation:  PartialSimSettings' fields (iterations, particles, phi_a, phi_b, stages, ...)
///   eps_r_bits, eps_r_unknown_only, use_simulation
///   dwa:         DwaSettings' fields except robot_radius_m, plus the ChassisLimits fields
///                {max_v_mps, min_v_mps, max_omega_rps, max_accel_mps2, max_alpha_rps2}
///                (max_v_mps and max_omega_rps must not exceed the chassis' maxima)
/// The sensors' fans come from `sensors` (observation_sectors()).
struct ExplorationProfile {
  int rays_per_sensor = 30;      ///< rays per sensor fan (the issue's benchmark case: 30)
  CellThresholds cells;          ///< free / unknown / occupied classification of the grid
  ObservationSettings observation;
  InflationSettings inflation;
  PathSettings path;
  ExplorationSettings strategy;  ///< simulation + frontier + eps_r_bits + use_simulation
  DwaSettings dwa;
};

struct Profile {
  std::string name;                    ///< non-empty (required)
  std::string description;             ///< free text (optional)
  ChassisProfile chassis;              ///< (required)
  std::vector<SensorProfile> sensors;  ///< 1 to 16 sensors (required)
  MappingSettings mapping;             ///< (optional)
  ExplorationProfile exploration;      ///< (optional)
  /// The runtime's settings (optional): YAML sections `runtime` (rates, execution,
  /// synchronizer), `localization` (pose_correction, loop_closure), the goal life cycle's keys
  /// in `exploration` and the controller's behaviours in `control` (see to_yaml() for the tree).
  RuntimeSettings runtime;
  /// Faults to inject when the profile runs in the simulator (optional; YAML `faults`: a list of
  /// specs "KIND[:SENSOR]@START[+DURATION][=AMOUNT]", runtime/robot/faults.hpp), e.g. to test a
  /// robot's launch setup against a camera that stops. A real robot ignores them.
  std::vector<std::string> faults;
};

/// The observation model's fan of each sensor (paper §3.1): origin (x, y) and yaw from the
/// extrinsics (Eq. (6)), the horizontal field of view, the depth range, rays_per_sensor rays.
[[nodiscard]] std::vector<SensorSector> observation_sectors(const Profile& profile);

/// A partial profile document laid over a profile before it is read: mappings merge key by key,
/// any other value replaces the profile's. `source` names it in messages (a file, or
/// "--set KEY=VALUE").
struct ProfileOverlay {
  std::string source;
  std::string yaml;
};
/// The overlay of one `--set` assignment: a dotted key path and a YAML value
/// ("exploration.view_range_m=3", "runtime.execution=background"). Throws kInvalidArgument for
/// a malformed assignment.
[[nodiscard]] ProfileOverlay set_overlay(std::string_view assignment);
/// The overlay of a YAML file (`--config`). Throws kIo if it cannot be read.
[[nodiscard]] ProfileOverlay file_overlay(const std::filesystem::path& path);

/// Reads and validates a profile file, with overlays applied in order.
[[nodiscard]] Profile load_profile(const std::filesystem::path& path, std::span<const ProfileOverlay> overlays = {});

/// Parses and validates profile YAML text; `source_name` stands for the file in messages.
[[nodiscard]] Profile parse_profile(std::string_view yaml_text, std::string_view source_name,
                                    std::span<const ProfileOverlay> overlays = {});

/// The whole effective settings tree as profile YAML, every key written (numbers in their
/// shortest form that reads back exactly): parse_profile(to_yaml(p)) gives p again.
[[nodiscard]] std::string to_yaml(const Profile& profile);

/// A profile shipped with duet, compiled into the library (works without the source tree):
/// "dual" / "dual_kinect_kobuki" or "single" / "single_kinect_kobuki".
/// Throws duet::Error(kInvalidArgument) listing the known names for any other name.
[[nodiscard]] Profile builtin_profile(std::string_view name);

/// Names of the built-in profiles (file stems, e.g. "dual_kinect_kobuki").
[[nodiscard]] std::vector<std::string> builtin_profile_names();

/// The YAML text of a built-in profile (as shipped in profiles/), for `duet` to print or copy.
[[nodiscard]] std::string_view builtin_profile_text(std::string_view name);

/// A path (contains a '/', ends in .yaml / .yml, or names an existing file) is loaded with
/// load_profile(); anything else is a built-in profile name.
[[nodiscard]] Profile resolve_profile(std::string_view name_or_path, std::span<const ProfileOverlay> overlays = {});

/// The profile with Procedure 1's random simulation seeded from a run's seed, as `duet explore
/// --seed` does (exploration.strategy.simulation.seed = mix(run_seed ^ 0x5EED5EED)): the same
/// run seed gives the same decisions in the simulator, the C API and `duet run`.
[[nodiscard]] Profile with_run_seed(Profile profile, std::uint64_t run_seed);

/// Range checks of the profile's structs (the kernels' settings have their own validate()):
/// each throws duet::Error(kInvalidArgument) "Struct.field must be in RANGE, got V".
void validate(const ChassisProfile& chassis);
void validate(const SensorProfile& sensor);
void validate(const MappingSettings& mapping);  ///< the five kernels' validate() and grid_resolution_m

/// Checks the ranges and consistency of a profile built in code (load_profile does this);
/// `source_name` prefixes the messages. Throws duet::Error(kInvalidArgument).
void validate(const Profile& profile, std::string_view source_name = "profile");

}  // namespace duet
