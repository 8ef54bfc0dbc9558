// Profiles: the shipped YAML files carry the paper's values (§4.1, Eq. (6)), and every kind of
// bad input is an error naming the file and the key path.
#include <duet/kernels/error.hpp>
#include <duet/runtime/config/profile.hpp>

#include <gtest/gtest.h>

#include "runtime_test_util.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

const fs::path kProfiles = fs::path(DUET_SOURCE_DIR) / "profiles";

using duet_test::TempDir;

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The shipped dual profile with `from` replaced by `to` (exactly once).
std::string dual_with(const std::string& from, const std::string& to) {
  std::string text = read_text(kProfiles / "dual_kinect_kobuki.yaml");
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  EXPECT_EQ(text.find(from, pos + 1), std::string::npos) << "ambiguous: " << from;
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

// Loads `text` from a file and returns the error (fails the test if none).
duet::Error load_error(const TempDir& dir, const std::string& text, const std::string& file = "bad_profile.yaml") {
  const fs::path p = dir.write(file, text);
  try {
    (void)duet::load_profile(p);
  } catch (const duet::Error& e) {
    return e;
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return duet::Error(duet::ErrorCode::kInternal, "");
}

void expect_contains(const std::string& msg, const std::string& part) {
  EXPECT_NE(msg.find(part), std::string::npos) << "message: " << msg << "\nexpected to contain: " << part;
}

void expect_near(const Eigen::Vector3f& a, const Eigen::Vector3f& b, float tol = 1e-5f) {
  EXPECT_LT((a - b).norm(), tol) << "got " << a.transpose() << ", expected " << b.transpose();
}

}  // namespace

TEST(Profile, DualKinectKobukiCarriesThePapersValues) {
  const duet::Profile p = duet::load_profile(kProfiles / "dual_kinect_kobuki.yaml");
  EXPECT_EQ(p.name, "dual_kinect_kobuki");
  EXPECT_EQ(p.chassis.type, "differential");
  EXPECT_FLOAT_EQ(p.chassis.radius_m, 0.177f);
  EXPECT_FLOAT_EQ(p.chassis.footprint_diameter_m, 0.46f);
  EXPECT_FLOAT_EQ(p.chassis.max_linear_speed_mps, 0.7f);
  EXPECT_FLOAT_EQ(p.chassis.max_angular_speed_dps, 180.0f);
  EXPECT_NEAR(p.chassis.max_angular_speed_radps(), M_PI, 1e-6);
  EXPECT_FLOAT_EQ(p.chassis.odometry_rate_hz, 50.0f);

  ASSERT_EQ(p.sensors.size(), 2u);
  for (const auto& s : p.sensors) {
    EXPECT_EQ(s.intrinsics.width, 640);
    EXPECT_EQ(s.intrinsics.height, 480);
    EXPECT_FLOAT_EQ(s.fov_h_deg, 57.0f);
    EXPECT_FLOAT_EQ(s.fov_v_deg, 43.0f);
    // fx = (w/2) / tan(fov_h/2)
    EXPECT_NEAR(s.intrinsics.fx, 320.0 / std::tan(28.5 * M_PI / 180.0), 1e-3);
    EXPECT_NEAR(s.intrinsics.fy, 240.0 / std::tan(21.5 * M_PI / 180.0), 1e-3);
    EXPECT_FLOAT_EQ(s.intrinsics.cx, 319.5f);
    EXPECT_FLOAT_EQ(s.intrinsics.cy, 239.5f);
    EXPECT_FLOAT_EQ(s.rate_hz, 30.0f);
    EXPECT_FLOAT_EQ(s.min_depth_m, 0.5f);
    EXPECT_FLOAT_EQ(s.max_depth_m, 5.0f);
    EXPECT_FLOAT_EQ(s.depth_units_per_m, 1000.0f);
  }
  // Eq. (6).
  expect_near(p.sensors[0].extrinsics.xyz_m, {-0.118f, 0.0f, 0.271f});
  expect_near(p.sensors[0].extrinsics.zyx_euler_deg, {0.0f, 0.0f, 0.0f});
  expect_near(p.sensors[1].extrinsics.xyz_m, {-0.118f, 0.0f, 0.481f});
  expect_near(p.sensors[1].extrinsics.zyx_euler_deg, {-90.0f, 0.0f, 0.0f});

  EXPECT_FLOAT_EQ(p.mapping.voxel_filter.leaf_size_m, 0.05f);
  EXPECT_EQ(p.mapping.normals.k, 10);
  EXPECT_FLOAT_EQ(p.mapping.grid_resolution_m, 0.05f);
  EXPECT_EQ(p.mapping.segmentation.clustering.min_size, 20u);
  EXPECT_TRUE(p.mapping.grid_update.clear_along_rays);
}

TEST(Profile, ExtrinsicsTransformPointsAsEq6Says) {
  const duet::Profile p = duet::load_profile(kProfiles / "dual_kinect_kobuki.yaml");
  const Eigen::Vector3f ahead_optical(0.0f, 0.0f, 1.0f);  // 1 m along the optical axis
  // Sensor 1 looks forward: the point lies 1 m ahead of the sensor.
  expect_near(p.sensors[0].T_robot_optical() * ahead_optical, {0.882f, 0.0f, 0.271f});
  // Sensor 2 (theta = -90 deg) looks to the right (-y).
  expect_near(p.sensors[1].T_robot_optical() * ahead_optical, {-0.118f, -1.0f, 0.481f});
  // Optical x (image right) of the right-facing sensor points backward (-x), optical y (image
  // down) points down (-z).
  const Eigen::Matrix3f R = p.sensors[1].T_robot_optical().linear();
  expect_near(R.col(0), {-1.0f, 0.0f, 0.0f});
  expect_near(R.col(1), {0.0f, 0.0f, -1.0f});
  // Body frame: x forward of the sensor.
  expect_near(p.sensors[1].T_robot_body() * Eigen::Vector3f(1.0f, 0.0f, 0.0f), {-0.118f, -1.0f, 0.481f});
  // ZYX order: R = Rz(theta) Ry(phi) Rx(psi).
  const Eigen::Matrix3f R_zyx = duet::rotation_from_zyx_euler_deg({30.0f, 20.0f, 10.0f});
  const Eigen::Matrix3f expected = (Eigen::AngleAxisf(30.0f * float(M_PI) / 180.0f, Eigen::Vector3f::UnitZ()) *
                                    Eigen::AngleAxisf(20.0f * float(M_PI) / 180.0f, Eigen::Vector3f::UnitY()) *
                                    Eigen::AngleAxisf(10.0f * float(M_PI) / 180.0f, Eigen::Vector3f::UnitX()))
                                       .toRotationMatrix();
  EXPECT_LT((R_zyx - expected).norm(), 1e-6f);
}

TEST(Profile, SingleIsTheDualRobotWithSensorOneOnly) {
  const duet::Profile dual = duet::load_profile(kProfiles / "dual_kinect_kobuki.yaml");
  const duet::Profile single = duet::load_profile(kProfiles / "single_kinect_kobuki.yaml");
  EXPECT_EQ(single.name, "single_kinect_kobuki");
  ASSERT_EQ(single.sensors.size(), 1u);
  EXPECT_EQ(single.sensors[0].name, dual.sensors[0].name);
  EXPECT_TRUE(single.sensors[0].T_robot_optical().isApprox(dual.sensors[0].T_robot_optical()));
  EXPECT_FLOAT_EQ(single.chassis.max_linear_speed_mps, dual.chassis.max_linear_speed_mps);
  EXPECT_FLOAT_EQ(single.mapping.voxel_filter.leaf_size_m, dual.mapping.voxel_filter.leaf_size_m);
}

TEST(Profile, BuiltinProfilesMatchTheShippedFiles) {
  const auto names = duet::builtin_profile_names();
  EXPECT_NE(std::find(names.begin(), names.end(), "dual_kinect_kobuki"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "single_kinect_kobuki"), names.end());
  EXPECT_EQ(duet::builtin_profile_text("dual"), read_text(kProfiles / "dual_kinect_kobuki.yaml"));
  EXPECT_EQ(duet::builtin_profile_text("single_kinect_kobuki"), read_text(kProfiles / "single_kinect_kobuki.yaml"));
  EXPECT_EQ(duet::builtin_profile("dual").sensors.size(), 2u);
  EXPECT_EQ(duet::builtin_profile("single").sensors.size(), 1u);
  EXPECT_EQ(duet::resolve_profile("dual").name, "dual_kinect_kobuki");
  EXPECT_EQ(duet::resolve_profile((kProfiles / "single_kinect_kobuki.yaml").string()).name, "single_kinect_kobuki");
  try {
    (void)duet::builtin_profile("triple");
    FAIL() << "no error";
  } catch (const duet::Error& e) {
    EXPECT_EQ(e.code(), duet::ErrorCode::kInvalidArgument);
    expect_contains(e.what(), "'triple'");
    expect_contains(e.what(), "dual");
  }
}

TEST(Profile, CalibratedIntrinsicsAndOptionalDefaults) {
  TempDir dir;
  const std::string text = R"(name: tiny
chassis: {type: differential, radius_m: 0.2, max_linear_speed_mps: 0.5, max_angular_speed_dps: 90}
sensors:
  - name: cam
    intrinsics: {width: 640, height: 480, fx: 525, fy: 525, cx: 319.5, cy: 239.5}
    extrinsics: {xyz_m: [0.1, 0, 0.3], zyx_euler_deg: [0, 0, 0]}
)";
  const duet::Profile p = duet::load_profile(dir.write("tiny.yaml", text));
  EXPECT_FLOAT_EQ(p.sensors[0].intrinsics.fx, 525.0f);
  EXPECT_NEAR(p.sensors[0].fov_h_deg, 2.0 * std::atan(320.0 / 525.0) * 180.0 / M_PI, 1e-4);
  // Optional keys keep the in-class defaults.
  const duet::MappingSettings defaults;
  EXPECT_EQ(p.mapping.normals.k, defaults.normals.k);
  EXPECT_FLOAT_EQ(p.mapping.voxel_filter.leaf_size_m, defaults.voxel_filter.leaf_size_m);
  EXPECT_FLOAT_EQ(p.chassis.odometry_rate_hz, duet::ChassisProfile{}.odometry_rate_hz);
  EXPECT_FLOAT_EQ(p.sensors[0].rate_hz, 30.0f);
  EXPECT_NO_THROW(duet::validate(p));
}

// ---- one test per kind of error ------------------------------------------------------------

TEST(ProfileErrors, UnknownKeyNamesFileKeyPathAndSuggestion) {
  TempDir dir;
  const duet::Error e = load_error(dir, dual_with("    leaf_size_m: 0.05", "    leaf_size: 0.05"));
  EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
  expect_contains(e.what(), "bad_profile.yaml:");
  expect_contains(e.what(), "mapping.voxel_filter.leaf_size: unknown key");
  expect_contains(e.what(), "did you mean 'leaf_size_m'?");
}

TEST(ProfileErrors, DuplicateKey) {
  TempDir dir;
  const duet::Error e = load_error(dir, dual_with("  radius_m: 0.177 ", "  radius_m: 0.177\n  radius_m: 0.2 "));
  EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
  expect_contains(e.what(), "bad_profile.yaml:");
  expect_contains(e.what(), "chassis.radius_m: duplicate key");
}

TEST(ProfileErrors, WrongTypeNamesFileAndKeyPath) {
  TempDir dir;
  {
    const duet::Error e = load_error(dir, dual_with("    k: 10 ", "    k: ten "));
    EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
    expect_contains(e.what(), "bad_profile.yaml:");
    expect_contains(e.what(), "mapping.normals.k: expected an integer, got 'ten'");
  }
  {  // a float where an integer is required
    const duet::Error e = load_error(dir, dual_with("    k: 10 ", "    k: 10.5 "));
    expect_contains(e.what(), "mapping.normals.k: expected an integer");
  }
  {  // a quoted number is a string
    const duet::Error e = load_error(dir, dual_with("    leaf_size_m: 0.05", "    leaf_size_m: \"0.05\""));
    expect_contains(e.what(), "mapping.voxel_filter.leaf_size_m: expected a number, got the quoted string '0.05'");
  }
  {  // a mapping where a sequence is required
    const duet::Error e = load_error(dir, dual_with("      xyz_m: [-0.118, 0.0, 0.481]", "      xyz_m: {x: 1}"));
    expect_contains(e.what(), "sensors[1].extrinsics.xyz_m: expected a sequence of 3 numbers");
  }
  {
    const duet::Error e = load_error(dir, dual_with("    clear_along_rays: true", "    clear_along_rays: maybe"));
    expect_contains(e.what(), "mapping.grid_update.clear_along_rays: expected true or false");
  }
}

TEST(ProfileErrors, OutOfRangeNamesFileKeyPathAndRange) {
  TempDir dir;
  {
    const duet::Error e = load_error(dir, dual_with("    leaf_size_m: 0.05", "    leaf_size_m: -1"));
    EXPECT_EQ(e.code(), duet::ErrorCode::kInvalidArgument);
    expect_contains(e.what(), "bad_profile.yaml:");
    expect_contains(e.what(), "mapping.voxel_filter.leaf_size_m: must be finite and > 0 m, got -1");
  }
  {
    const duet::Error e = load_error(dir, dual_with("      zyx_euler_deg: [-90.0, 0.0, 0.0]", "      zyx_euler_deg: [-900.0, 0.0, 0.0]"));
    EXPECT_EQ(e.code(), duet::ErrorCode::kInvalidArgument);
    expect_contains(e.what(), "sensors[1].extrinsics.zyx_euler_deg[0]: must be in [-360, 360] deg, got -900");
  }
  {  // an integer's type range checked before narrowing
    const duet::Error e = load_error(dir, dual_with("    k: 10 ", "    k: 99999999999 "));
    expect_contains(e.what(), "mapping.normals.k: must be in [-2147483648, 2147483647], got 99999999999");
  }
  {  // the kernel's range (NormalSettings' validate(), the one place it is written)
    const duet::Error e = load_error(dir, dual_with("    k: 10 ", "    k: 300 "));
    expect_contains(e.what(), "bad_profile.yaml:");
    expect_contains(e.what(), "mapping.normals.k: must be in [3, 256], got 300");
  }
  {  // inconsistent pair
    const duet::Error e = load_error(dir, dual_with("    max_height_m: 1.20", "    max_height_m: -0.5"));
    expect_contains(e.what(), "mapping.segmentation.max_height_m: must be finite and greater than min_height_m");
  }
  {
    const duet::Error e = load_error(dir, dual_with("      fov_h_deg: 57.0\n      fov_v_deg: 43.0\n    rate_hz: 30.0\n    min_depth_m: 0.5\n    max_depth_m: 5.0\n    depth_units_per_m: 1000.0\n    extrinsics:                 # Eq. (6), sensor 2",
                                                    "      fov_h_deg: 190.0\n      fov_v_deg: 43.0\n    rate_hz: 30.0\n    min_depth_m: 0.5\n    max_depth_m: 5.0\n    depth_units_per_m: 1000.0\n    extrinsics:                 # Eq. (6), sensor 2"));
    expect_contains(e.what(), "sensors[1].intrinsics.fov_h_deg: must be in (0, 180) deg, got 190");
  }
  {
    const duet::Error e = load_error(dir, dual_with("  type: differential ", "  type: omni "));
    expect_contains(e.what(), "chassis.type: must be one of: differential; got 'omni'");
  }
  {
    const duet::Error e = load_error(dir, dual_with("  - name: kinect_right", "  - name: kinect_front"));
    expect_contains(e.what(), "sensors[1].name: 'kinect_front' is already the name of another sensor");
  }
}

TEST(ProfileErrors, MissingRequiredKey) {
  TempDir dir;
  const duet::Error e = load_error(dir, dual_with("  max_linear_speed_mps: 0.7     # paper §4.1: 70 cm/s\n", ""));
  EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
  expect_contains(e.what(), "bad_profile.yaml:");
  expect_contains(e.what(), "chassis.max_linear_speed_mps: required key is missing");
}

TEST(ProfileErrors, MissingFile) {
  TempDir dir;
  const fs::path p = dir.path() / "no_such_profile.yaml";
  try {
    (void)duet::load_profile(p);
    FAIL() << "no error";
  } catch (const duet::Error& e) {
    EXPECT_EQ(e.code(), duet::ErrorCode::kIo);
    expect_contains(e.what(), p.string());
    expect_contains(e.what(), "not found");
  }
  // resolve_profile treats anything with a '/' or a .yaml suffix as a path.
  EXPECT_THROW((void)duet::resolve_profile("no_such_profile.yaml"), duet::Error);
}

TEST(ProfileErrors, MalformedYaml) {
  TempDir dir;
  {
    const duet::Error e = load_error(dir, "name: x\nchassis: [1, 2\nsensors: []\n");
    EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
    expect_contains(e.what(), "bad_profile.yaml:");
    expect_contains(e.what(), "malformed YAML");
  }
  {
    const duet::Error e = load_error(dir, "");
    EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
    expect_contains(e.what(), "bad_profile.yaml: the document is empty");
  }
  {
    const duet::Error e = load_error(dir, "- just\n- a list\n");
    expect_contains(e.what(), "top level: expected a mapping");
  }
}

TEST(ProfileErrors, WrongSequenceLength) {
  TempDir dir;
  {
    const duet::Error e = load_error(dir, dual_with("      zyx_euler_deg: [-90.0, 0.0, 0.0]", "      zyx_euler_deg: [-90.0, 0.0]"));
    EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
    expect_contains(e.what(), "bad_profile.yaml:");
    expect_contains(e.what(), "sensors[1].extrinsics.zyx_euler_deg: expected a sequence of 3 numbers");
    expect_contains(e.what(), "got 2 elements");
  }
  {
    std::string text = read_text(kProfiles / "dual_kinect_kobuki.yaml");
    const auto a = text.find("sensors:\n");
    const auto b = text.find("\nmapping:");
    text.replace(a, b - a, "sensors: []\n");
    const duet::Error e = load_error(dir, text);
    expect_contains(e.what(), "sensors: expected a sequence of 1 to 16 sensors, got 0 elements");
  }
}

TEST(ProfileErrors, IntrinsicsNeedOneForm) {
  TempDir dir;
  const std::string head = R"(name: tiny
chassis: {type: differential, radius_m: 0.2, max_linear_speed_mps: 0.5, max_angular_speed_dps: 90}
sensors:
  - name: cam
    extrinsics: {xyz_m: [0, 0, 0], zyx_euler_deg: [0, 0, 0]}
)";
  {
    const duet::Error e = load_error(dir, head + "    intrinsics: {width: 640, height: 480, fov_h_deg: 57, fov_v_deg: 43, fx: 500}\n");
    EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
    expect_contains(e.what(), "bad_profile.yaml:");
    expect_contains(e.what(), "sensors[0].intrinsics: give either fx, fy, cx, cy");
  }
  {
    const duet::Error e = load_error(dir, head + "    intrinsics: {width: 640, height: 480}\n");
    expect_contains(e.what(), "sensors[0].intrinsics: no focal length");
  }
  {
    const duet::Error e = load_error(dir, head + "    intrinsics: {width: 640, height: 480, fx: 500, fy: 500, cx: 320}\n");
    expect_contains(e.what(), "sensors[0].intrinsics.cy: required key is missing");
  }
  {
    const duet::Error e = load_error(dir, head + "    intrinsics: {width: 640, height: 480, fx: -500, fy: 500, cx: 320, cy: 240}\n");
    EXPECT_EQ(e.code(), duet::ErrorCode::kInvalidArgument);
    expect_contains(e.what(), "sensors[0].intrinsics.fx: must be in (0, 1000000] px, got -500");
  }
}

TEST(ProfileErrors, ValidateProfileBuiltInCode) {
  duet::Profile p = duet::builtin_profile("dual");
  p.mapping.grid_resolution_m = 0.0f;
  try {
    duet::validate(p, "my_robot");
    FAIL() << "no error";
  } catch (const duet::Error& e) {
    EXPECT_EQ(e.code(), duet::ErrorCode::kInvalidArgument);
    expect_contains(e.what(), "my_robot: mapping.grid_resolution_m: must be in [0.001, 10] m, got 0");
  }
}

// The exploration section (issue 3): the shipped values, the sensor fans, and errors that name
// the key path.
TEST(Profile, ExplorationSectionCarriesTheDefaultsAndTheSensorFans) {
  const duet::Profile p = duet::load_profile(kProfiles / "dual_kinect_kobuki.yaml");
  const duet::ExplorationProfile& ex = p.exploration;
  EXPECT_EQ(ex.strategy.simulation.iterations, 5);
  EXPECT_EQ(ex.strategy.simulation.particles, 100);
  EXPECT_EQ(ex.strategy.simulation.stages, 4);
  EXPECT_EQ(ex.observation.backend, duet::ObservationBackend::kDda);
  EXPECT_FLOAT_EQ(ex.inflation.robot_radius_m, 0.29f);  // paper §4.1: 0.46 m footprint + 0.06 m
  EXPECT_FLOAT_EQ(ex.dwa.robot_radius_m, ex.inflation.robot_radius_m);  // one source
  EXPECT_FALSE(ex.inflation.unknown_is_obstacle);  // frontiers stay reachable
  EXPECT_TRUE(ex.inflation.uncertain_is_obstacle);  // faces seen at grazing angles block
  EXPECT_FLOAT_EQ(ex.strategy.frontier.approach_radius_m, 0.0f);     // measured worse on Willow
  EXPECT_FLOAT_EQ(ex.strategy.frontier.min_unknown_region_m2, 0.5f);  // enclosed pockets are no frontiers
  EXPECT_FLOAT_EQ(ex.observation.thresholds.occupied_logodds, ex.cells.occupied_logodds);
  EXPECT_FLOAT_EQ(ex.dwa.limits.max_v_mps, 0.5f);
  EXPECT_TRUE(ex.strategy.use_simulation);
  // The profile's sensors give the paper's two fans (Eq. 6).
  const auto fans = duet::observation_sectors(p);
  const auto paper = duet::paper_dual_sensors(30);
  ASSERT_EQ(fans.size(), paper.size());
  for (std::size_t i = 0; i < fans.size(); ++i) {
    EXPECT_NEAR(fans[i].x_m, paper[i].x_m, 1e-6f);
    EXPECT_NEAR(fans[i].y_m, paper[i].y_m, 1e-6f);
    EXPECT_NEAR(fans[i].yaw_rad, paper[i].yaw_rad, 1e-6f);
    EXPECT_NEAR(fans[i].fov_rad, paper[i].fov_rad, 1e-6f);
    EXPECT_EQ(fans[i].rays, 30);
    EXPECT_FLOAT_EQ(fans[i].min_range_m, 0.5f);
    EXPECT_FLOAT_EQ(fans[i].max_range_m, 5.0f);
  }
  EXPECT_EQ(duet::observation_sectors(duet::load_profile(kProfiles / "single_kinect_kobuki.yaml")).size(), 1u);
  // Without the section: the C++ defaults, with speeds clamped to the chassis.
  duet::Profile code = p;
  code.exploration = duet::ExplorationProfile{};
  EXPECT_NO_THROW(duet::validate(code));
}

TEST(ProfileErrors, ExplorationKeysAreCheckedLikeTheRest) {
  TempDir dir;
  {
    const duet::Error e = load_error(dir, dual_with("    particles: 100 ", "    particle: 100 "));
    EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
    expect_contains(e.what(), "exploration.simulation.particle: unknown key (did you mean 'particles'?)");
  }
  {
    const duet::Error e = load_error(dir, dual_with("    iterations: 5 ", "    iterations: 0 "));
    EXPECT_EQ(e.code(), duet::ErrorCode::kInvalidArgument);
    expect_contains(e.what(), "exploration.simulation");
    expect_contains(e.what(), "iterations");
  }
  {
    const duet::Error e = load_error(dir, dual_with("    backend: dda ", "    backend: optix "));
    expect_contains(e.what(), "exploration.observation.backend: must be one of: dda, embree; got 'optix'");
  }
  {
    const duet::Error e = load_error(dir, dual_with("    max_v_mps: 0.5 ", "    max_v_mps: 0.9 "));
    expect_contains(e.what(), "exploration.dwa.max_v_mps: must not exceed chassis.max_linear_speed_mps");
  }
  {
    const duet::Error e = load_error(dir, dual_with("    robot_radius_m: 0.29 ", "    robot_radius_m: 0.10 "));
    expect_contains(e.what(), "exploration.inflation.robot_radius_m: must be at least chassis.radius_m");
  }
  {
    const duet::Error e = load_error(dir, dual_with("    uncertain_is_obstacle: true ", "    uncertain_is_obstacle: maybe "));
    EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
    expect_contains(e.what(), "exploration.inflation.uncertain_is_obstacle");
  }
  {
    const duet::Error e = load_error(dir, dual_with("    approach_radius_m: 0.0 ", "    approach_radius_m: -1.0 "));
    expect_contains(e.what(), "approach_radius_m");
  }
  {
    const duet::Error e = load_error(dir, dual_with("    gamma: 0.9 ", "    gamma: fast "));
    EXPECT_EQ(e.code(), duet::ErrorCode::kParse);
    expect_contains(e.what(), "exploration.simulation.gamma");
  }
  {
    const duet::Error e = load_error(dir, dual_with("  eps_r_bits: 12.0\n", "  eps_r_bits: -1.0\n"));
    expect_contains(e.what(), "eps_r_bits");
  }
}
