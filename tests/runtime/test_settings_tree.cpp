// The settings tree (config/profile.hpp): every settings struct is reachable from the profile
// YAML; to_yaml() writes the whole effective tree and it reads back to the same tree; every key
// can be set by --set (set_overlay) and --config (file_overlay) and a bad value names the key,
// the source and the allowed range.
#include <duet/kernels/error.hpp>
#include <duet/runtime/config/profile.hpp>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "runtime_test_util.hpp"

#include <cmath>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

namespace {

using duet_test::error_of;

/// Every leaf of a mapping tree (sequences are not walked: the sensors), as (dotted path, scalar).
void leaves(const YAML::Node& n, const std::string& path, std::vector<std::pair<std::string, std::string>>& out) {
  for (const auto& kv : n) {
    const std::string p = path.empty() ? kv.first.Scalar() : path + "." + kv.first.Scalar();
    if (kv.second.IsMap()) leaves(kv.second, p, out);
    else if (kv.second.IsScalar()) out.emplace_back(p, kv.second.Scalar());
  }
}

}  // namespace

TEST(SettingsTree, BuiltinProfilesRoundTripThroughToYaml) {
  for (const char* name : {"dual", "single"}) {
    const duet::Profile p = duet::builtin_profile(name);
    const std::string y = duet::to_yaml(p);
    const duet::Profile q = duet::parse_profile(y, "written.yaml");
    EXPECT_EQ(duet::to_yaml(q), y) << name;
    // What the text cannot show directly: derived and runtime fields came back.
    ASSERT_EQ(q.sensors.size(), p.sensors.size());
    for (std::size_t i = 0; i < p.sensors.size(); ++i) {
      EXPECT_EQ(q.sensors[i].fov_h_deg, p.sensors[i].fov_h_deg);
      EXPECT_EQ(q.sensors[i].intrinsics.fx, p.sensors[i].intrinsics.fx);
      EXPECT_TRUE(q.sensors[i].T_robot_optical().isApprox(p.sensors[i].T_robot_optical(), 0.0f));
    }
    EXPECT_EQ(q.exploration.dwa.robot_radius_m, p.exploration.dwa.robot_radius_m);
    EXPECT_EQ(q.runtime.explorer.view_range_m, p.runtime.explorer.view_range_m);
    EXPECT_EQ(q.runtime.loop_closure.match.linear_window_m, p.runtime.loop_closure.match.linear_window_m);
    // Every section of the tree is there.
    const YAML::Node root = YAML::Load(y);
    for (const char* section : {"chassis", "sensors", "mapping", "exploration", "control", "localization", "runtime"})
      EXPECT_TRUE(root[section]) << section;
  }
}

// A profile that leaves the mapping section out takes the kernels' defaults, one of which is
// +inf (grid_update.clear_max_height_m: every ray clears). Found by fuzz_profile: to_yaml
// wrote "inf", which the reader refused as not finite, so `duet profile` printed a profile
// duet could not read. It is written and read as ".inf" now; other keys stay finite.
TEST(SettingsTree, DefaultsWithAnInfiniteLimitRoundTrip) {
  const std::string text =
      "name: tiny\nchassis: {type: differential, radius_m: 0.2, wheel_base_m: 0.3, wheel_diameter_m: 0.07,"
      " max_linear_speed_mps: 0.5, max_angular_speed_dps: 90, odometry_rate_hz: 50}\n"
      "sensors:\n  - name: cam\n    intrinsics: {width: 64, height: 48, fov_h_deg: 57, fov_v_deg: 43}\n"
      "    extrinsics: {xyz_m: [0.0, 0.0, 0.3], zyx_euler_deg: [0.0, 0.0, 0.0]}\n";
  const duet::Profile p = duet::parse_profile(text, "tiny.yaml");
  EXPECT_TRUE(std::isinf(p.mapping.grid_update.clear_max_height_m));
  const std::string y = duet::to_yaml(p);
  EXPECT_NE(y.find("clear_max_height_m: .inf"), std::string::npos) << y;
  const duet::Profile q = duet::parse_profile(y, "written.yaml");
  EXPECT_TRUE(std::isinf(q.mapping.grid_update.clear_max_height_m));
  EXPECT_EQ(duet::to_yaml(q), y);
  const std::vector<duet::ProfileOverlay> finite{duet::set_overlay("mapping.grid_update.clear_max_height_m=0.6")};
  EXPECT_EQ(duet::parse_profile(y, "written.yaml", finite).mapping.grid_update.clear_max_height_m, 0.6f);
  // Only that limit may be infinite: another float key refuses .inf, naming the key.
  try {
    const std::vector<duet::ProfileOverlay> bad{duet::set_overlay("mapping.grid_update.max_ray_length_m=.inf")};
    (void)duet::parse_profile(y, "written.yaml", bad);
    ADD_FAILURE() << "max_ray_length_m = .inf was accepted";
  } catch (const duet::Error& e) {
    EXPECT_NE(std::string(e.what()).find("max_ray_length_m"), std::string::npos) << e.what();
  }
}

// Procedure 1's cell budget is checked with the profile's sensors and grid (issue 19), naming
// the key, so that a profile that loads does not fail at its first decision.
TEST(SettingsTree, TheDecisionsCellBudgetIsCheckedAtLoad) {
  const std::string y = duet::to_yaml(duet::builtin_profile("dual"));
  const std::vector<duet::ProfileOverlay> heavy{duet::set_overlay("exploration.simulation.particles=5000")};
  try {
    (void)duet::parse_profile(y, "dual.yaml", heavy);
    ADD_FAILURE() << "5000 particles (4.8e9 cell visits per decision) accepted";
  } catch (const duet::Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("exploration.simulation.particles"), std::string::npos) << m;
    EXPECT_NE(m.find("cell visits per decision"), std::string::npos) << m;
  }
  const std::vector<duet::ProfileOverlay> ok{duet::set_overlay("exploration.simulation.particles=1000")};
  EXPECT_NO_THROW((void)duet::parse_profile(y, "dual.yaml", ok));
}

// Each key of the written tree, set to its own value by --set, reads back to the same tree (the
// readers accept every key the writer writes); set to a value out of every range, it is either
// accepted or rejected with a message naming that key.
TEST(SettingsTree, EveryKeyCanBeSetAndABadValueIsNamed) {
  const duet::Profile p = duet::builtin_profile("dual");
  const std::string y = duet::to_yaml(p);
  std::vector<std::pair<std::string, std::string>> keys;
  leaves(YAML::Load(y), "", keys);
  ASSERT_GT(keys.size(), 150u);
  std::size_t rejected = 0;
  for (const auto& entry : keys) {
    const std::string& key = entry.first;  // named, not a structured binding: a lambda below captures it (clang 14)
    const std::string& value = entry.second;
    if (key == "name" || key == "description") continue;
    const std::vector<duet::ProfileOverlay> same = {duet::set_overlay(key + "=" + value)};
    duet::Profile q;
    ASSERT_NO_THROW(q = duet::resolve_profile("dual", same)) << key;
    EXPECT_EQ(duet::to_yaml(q), y) << key;
    for (const char* bad : {"-1e30", "nonsense"}) {
      const std::string e = error_of([&] { (void)duet::resolve_profile("dual", std::vector{duet::set_overlay(key + "=" + bad)}); });
      if (e.empty()) continue;
      ++rejected;
      EXPECT_NE(e.find("--set " + key + "=" + bad), std::string::npos) << e;  // the source
      const std::string leaf = key.substr(key.rfind('.') + 1);
      EXPECT_NE(e.find(leaf), std::string::npos) << e;  // the key
    }
  }
  EXPECT_GT(rejected, keys.size());  // "nonsense" is no number, no name and (nearly) no string
}

TEST(SettingsTree, OverlaysSetRuntimeSettingsAndNameTheirSource) {
  duet_test::TempDir dir;
  const auto over = dir.path() / "over.yaml";
  std::ofstream(over) << "runtime:\n  execution: background\n  control_rate_hz: 25\nexploration:\n  on_done: return_home\n"
                         "localization:\n  loop_closure:\n    enabled: false\n";
  const duet::Profile p = duet::resolve_profile("dual", std::vector{duet::file_overlay(over), duet::set_overlay("control.stall_timeout_s=2")});
  EXPECT_EQ(p.runtime.execution, duet::Execution::kBackground);
  EXPECT_EQ(p.runtime.control_rate_hz, 25.0);
  EXPECT_EQ(p.runtime.explorer.on_done, duet::OnDone::kReturnHome);
  EXPECT_FALSE(p.runtime.loop_closure.enabled);
  EXPECT_EQ(p.runtime.explorer.stall_timeout_s, 2.0f);
  EXPECT_EQ(p.mapping.voxel_filter.leaf_size_m, 0.05f);  // untouched keys keep the profile's values
  // Patrol and its spacing, by name and range.
  const duet::Profile q = duet::resolve_profile(
      "dual", std::vector{duet::set_overlay("exploration.on_done=patrol"), duet::set_overlay("exploration.patrol_spacing_m=2.5")});
  EXPECT_EQ(q.runtime.explorer.on_done, duet::OnDone::kPatrol);
  EXPECT_EQ(q.runtime.explorer.patrol_spacing_m, 2.5f);
  const std::string spacing = error_of([&] { (void)duet::resolve_profile("dual", std::vector{duet::set_overlay("exploration.patrol_spacing_m=0.1")}); });
  EXPECT_NE(spacing.find("patrol_spacing_m"), std::string::npos) << spacing;
  EXPECT_NE(spacing.find("[0.5, 100]"), std::string::npos) << spacing;
  // A later overlay wins.
  EXPECT_EQ(duet::resolve_profile("dual", std::vector{duet::file_overlay(over), duet::set_overlay("runtime.execution=lockstep")})
                .runtime.execution,
            duet::Execution::kLockstep);
  // A bad value in the file: the file, its line and column, the key, the range.
  std::ofstream(over) << "control:\n  slow_clearance_m: 20\n";
  std::string e = error_of([&] { (void)duet::resolve_profile("dual", std::vector{duet::file_overlay(over)}); });
  EXPECT_NE(e.find("over.yaml:2:21: control.slow_clearance_m"), std::string::npos) << e;
  EXPECT_NE(e.find("[0, 10]"), std::string::npos) << e;
  // An unknown key: named, with a suggestion.
  std::ofstream(over) << "runtime:\n  control_rate: 25\n";
  e = error_of([&] { (void)duet::resolve_profile("dual", std::vector{duet::file_overlay(over)}); });
  EXPECT_NE(e.find("runtime.control_rate"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'control_rate_hz'"), std::string::npos) << e;
  // A cross-field constraint: map rate above the control rate.
  e = error_of([&] { (void)duet::resolve_profile("dual", std::vector{duet::set_overlay("runtime.map_rate_hz=50")}); });
  EXPECT_NE(e.find("runtime.map_rate_hz"), std::string::npos) << e;
  // Not an overlay, a missing file, malformed assignments.
  std::ofstream(over) << "- 1\n- 2\n";
  EXPECT_NE(error_of([&] { (void)duet::resolve_profile("dual", std::vector{duet::file_overlay(over)}); }).find("must be a mapping"),
            std::string::npos);
  EXPECT_THROW((void)duet::file_overlay(dir.path() / "none.yaml"), duet::Error);
  for (const char* bad : {"noequals", "=3", "a..b=1"}) EXPECT_THROW((void)duet::set_overlay(bad), duet::Error) << bad;
}

// The profile written by to_yaml() of a profile with changed runtime settings keeps them.
TEST(SettingsTree, ChangedSettingsSurviveTheRoundTrip) {
  const duet::Profile p = duet::resolve_profile(
      "single", std::vector{duet::set_overlay("exploration.frontier.selection=explore_lite"), duet::set_overlay("runtime.background_threads=1"),
                            duet::set_overlay("localization.pose_correction.match.sigma_m=0.07")});
  const duet::Profile q = duet::parse_profile(duet::to_yaml(p), "written.yaml");
  EXPECT_EQ(q.exploration.strategy.frontier.selection, duet::FrontierSelection::kExploreLite);
  EXPECT_EQ(q.runtime.background_threads, 1);
  EXPECT_EQ(q.runtime.pose_correction.match.sigma_m, 0.07f);
}

// Range checks live in one place, each struct's validate(): for the mapping kernels' keys the
// profile reports exactly what the kernel's validate() says (at the key, with the overlay named),
// and accepts what the kernel accepts.
TEST(SettingsTree, MappingRangesAreTheKernelsValidate) {
  struct Case {
    const char* key;
    const char* value;
    std::function<void(duet::MappingSettings&)> set;
  };
  const std::vector<Case> bad = {
      {"mapping.voxel_filter.leaf_size_m", "-0.5", [](auto& m) { m.voxel_filter.leaf_size_m = -0.5f; }},
      {"mapping.normals.k", "257", [](auto& m) { m.normals.k = 257; }},
      {"mapping.normals.k", "2", [](auto& m) { m.normals.k = 2; }},
      {"mapping.back_projection.pixel_step", "65", [](auto& m) { m.back_projection.pixel_step = 65; }},
      {"mapping.segmentation.max_floor_tilt_deg", "91", [](auto& m) { m.segmentation.max_floor_tilt_deg = 91.0f; }},
      {"mapping.segmentation.clustering.tolerance_m", "0", [](auto& m) { m.segmentation.clustering.tolerance_m = 0.0f; }},
      {"mapping.grid_update.hit_logodds", "-1", [](auto& m) { m.grid_update.hit_logodds = -1.0f; }},
      {"mapping.grid_update.grow_margin_cells", "100001", [](auto& m) { m.grid_update.grow_margin_cells = 100001; }},
      {"mapping.grid_resolution_m", "0", [](auto& m) { m.grid_resolution_m = 0.0f; }},
  };
  const duet::Profile dual = duet::builtin_profile("dual");
  for (const Case& c : bad) {
    SCOPED_TRACE(c.key);
    duet::MappingSettings m = dual.mapping;
    c.set(m);
    const std::string kernel = error_of([&] { duet::validate(m); });
    ASSERT_FALSE(kernel.empty()) << "the struct's validate() accepts the bad value";
    const std::string assignment = std::string(c.key) + "=" + c.value;
    const std::vector<duet::ProfileOverlay> overlays = {duet::set_overlay(assignment)};
    const std::string msg = error_of([&] { (void)duet::resolve_profile("dual", overlays); });
    ASSERT_FALSE(msg.empty()) << "the profile accepts what the kernel rejects";
    EXPECT_NE(msg.find("--set " + assignment), std::string::npos) << msg;
    EXPECT_NE(msg.find(std::string(c.key) + ": "), std::string::npos) << msg;
    // The kernel's words after "Struct.field " are the profile's words after the key.
    const std::string words = kernel.substr(kernel.find(' ') + 1);
    EXPECT_NE(msg.find(std::string(c.key) + ": " + words), std::string::npos) << msg << "\nkernel: " << kernel;
  }
  // The kernels' bounds, not a second table: the edges they accept load.
  for (const char* ok : {"mapping.normals.k=256", "mapping.back_projection.pixel_step=64", "mapping.voxel_filter.leaf_size_m=20"}) {
    const std::vector<duet::ProfileOverlay> overlays = {duet::set_overlay(ok)};
    EXPECT_EQ(error_of([&] { (void)duet::resolve_profile("dual", overlays); }), "") << ok;
  }
}

// A list's element is set by its 0-based index (the ROS node sets each sensor's mount from tf
// this way); an index the list does not have is named, and the other elements are untouched.
TEST(SettingsTree, AListElementIsSetByItsIndex) {
  const std::string y = duet::to_yaml(duet::builtin_profile("dual"));
  const duet::Profile base = duet::parse_profile(y, "dual.yaml");
  const std::vector<duet::ProfileOverlay> mount{duet::set_overlay("sensors.1.extrinsics.xyz_m=[0.1, -0.2, 0.5]"),
                                                duet::set_overlay("sensors.1.extrinsics.zyx_euler_deg=[-80, 5, 1]")};
  const duet::Profile p = duet::parse_profile(y, "dual.yaml", mount);
  ASSERT_EQ(p.sensors.size(), 2u);
  EXPECT_EQ(p.sensors[1].extrinsics.xyz_m, Eigen::Vector3f(0.1f, -0.2f, 0.5f));
  EXPECT_EQ(p.sensors[1].extrinsics.zyx_euler_deg, Eigen::Vector3f(-80.0f, 5.0f, 1.0f));
  EXPECT_EQ(p.sensors[1].name, base.sensors[1].name);  // the element is overlaid, not replaced
  EXPECT_EQ(p.sensors[1].intrinsics.width, base.sensors[1].intrinsics.width);
  EXPECT_EQ(p.sensors[0].extrinsics.xyz_m, base.sensors[0].extrinsics.xyz_m);
  for (const char* bad : {"sensors.2.rate_hz=15", "sensors.x.rate_hz=15", "sensors.-1.rate_hz=15"}) {
    try {
      const std::vector<duet::ProfileOverlay> o{duet::set_overlay(bad)};
      (void)duet::parse_profile(y, "dual.yaml", o);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const duet::Error& e) {
      EXPECT_NE(std::string(e.what()).find("list of 2 elements"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
  // A value out of range inside an element is still named by the profile's checks.
  try {
    const std::vector<duet::ProfileOverlay> o{duet::set_overlay("sensors.0.extrinsics.xyz_m=[0, 0, 500]")};
    (void)duet::parse_profile(y, "dual.yaml", o);
    ADD_FAILURE() << "a mount 500 m up was accepted";
  } catch (const duet::Error& e) {
    EXPECT_NE(std::string(e.what()).find("xyz_m"), std::string::npos) << e.what();
  }
}
