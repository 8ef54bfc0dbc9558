// What a C user needs besides the kernels (issue 20, part 5): a profile's settings, map_server
// maps in and out of a grid, defaults from one place, no over-read when a size is forgotten.
#include "capi_helpers.hpp"

#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/io/grid_io.hpp>

#include <filesystem>
#include <fstream>

namespace {

using duet_capi_test::DeviceTest;
using CapiProfile = DeviceTest;

TEST_F(CapiProfile, SettingsOfAProfileAreWhatTheRuntimeRunsWith) {
  const char* sets[] = {"exploration.inflation.robot_radius_m=0.25", "mapping.voxel_filter.leaf_size_m=0.04"};
  duet_profile_settings s;
  duet_profile_settings_load(device_, DUET_PROFILE_NAME_OR_FILE, "single", sets, 2, &s);
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  duet::Profile p = duet::resolve_profile("single", std::vector<duet::ProfileOverlay>{duet::set_overlay(sets[0]), duet::set_overlay(sets[1])});
  EXPECT_EQ(s.inflation.robot_radius_m, 0.25f);
  EXPECT_EQ(s.voxel_filter.leaf_size_m, 0.04f);
  EXPECT_EQ(s.grid_resolution_m, p.mapping.grid_resolution_m);
  EXPECT_EQ(s.exploration.simulation.particles, p.exploration.strategy.simulation.particles);
  EXPECT_EQ(s.exploration.frontier.min_cluster_cells, p.exploration.strategy.frontier.min_cluster_cells);
  EXPECT_EQ(s.dwa.limits.max_v_mps, p.exploration.dwa.limits.max_v_mps);
  EXPECT_EQ(s.scan_match.linear_window_m, p.runtime.pose_correction.match.linear_window_m);
  ASSERT_EQ(s.sensor_count, 1u);
  const auto sectors = duet::observation_sectors(p);
  EXPECT_EQ(s.sensors[0].fov_rad, sectors[0].fov_rad);
  EXPECT_EQ(s.sensors[0].max_range_m, sectors[0].max_range_m);
  EXPECT_EQ(s.sensors[0].rays, sectors[0].rays);
  // The init functions give the built-in dual profile's values: the defaults the runtime uses
  // (they were the kernels' own, e.g. a robot radius of 0.20 m against the profile's 0.29 m).
  duet_profile_settings dual;
  duet_profile_settings_load(device_, DUET_PROFILE_NAME_OR_FILE, "dual", nullptr, 0, &dual);
  duet_inflation_settings is;
  duet_inflation_settings_init(&is);
  EXPECT_EQ(is.robot_radius_m, dual.inflation.robot_radius_m);
  EXPECT_EQ(is.robot_radius_m, 0.29f);
  duet_frontier_settings fs;
  duet_frontier_settings_init(&fs);
  EXPECT_EQ(fs.min_cluster_cells, dual.exploration.frontier.min_cluster_cells);
  EXPECT_EQ(fs.min_unknown_region_m2, dual.exploration.frontier.min_unknown_region_m2);
  duet_dwa_settings ds;
  duet_dwa_settings_init(&ds);
  EXPECT_EQ(ds.limits.min_v_mps, dual.dwa.limits.min_v_mps);
  EXPECT_EQ(ds.limits.min_v_mps, 0.0f);  // no reversing: both sensors look forward or right
  // Errors name the key; *out is unchanged.
  duet_profile_settings before = s;
  const char* bad[] = {"exploration.inflation.robot_radius_m=-1"};
  duet_profile_settings_load(device_, DUET_PROFILE_NAME_OR_FILE, "dual", bad, 1, &s);
  EXPECT_NE(take(), DUET_ERROR_NONE);
  EXPECT_NE(message().find("robot_radius_m"), std::string::npos) << message();
  EXPECT_EQ(std::memcmp(&before, &s, sizeof s), 0);
  duet_profile_settings_load(device_, DUET_PROFILE_YAML_TEXT, "name: [unclosed\n", nullptr, 0, &s);
  EXPECT_NE(take(), DUET_ERROR_NONE);
  duet_profile_settings_load(device_, DUET_PROFILE_NAME_OR_FILE, "dual", nullptr, 0, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
}

TEST_F(CapiProfile, MapServerMapsInAndOut) {
  const std::filesystem::path willow = std::filesystem::path(DUET_DATA_DIR) / "maps" / "willow-2010-02-18-0.10.yaml";
  if (!std::filesystem::exists(willow)) GTEST_SKIP() << "shared data not found: " << willow;
  duet_grid g = duet_grid_load_map_server(device_, willow.c_str());
  ASSERT_NE(g, nullptr) << message();
  const duet::OccupancyGrid ref = duet::read_map_server(willow);
  EXPECT_EQ(duet_grid_get_width(g), ref.width());
  EXPECT_EQ(duet_grid_get_height(g), ref.height());
  EXPECT_EQ(duet_grid_get_resolution(g), ref.resolution());
  EXPECT_EQ(duet_grid_get_known_cells(g), ref.known_cells());
  const auto dir = std::filesystem::temp_directory_path() / ("duet_capi_map_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  duet_grid_save_map_server(g, (dir / "copy.yaml").c_str());
  ASSERT_EQ(take(), DUET_ERROR_NONE) << message();
  EXPECT_TRUE(std::filesystem::is_regular_file(dir / "copy.pgm"));
  duet_grid again = duet_grid_load_map_server(device_, (dir / "copy.yaml").c_str());
  ASSERT_NE(again, nullptr) << message();
  EXPECT_EQ(duet_grid_get_known_cells(again), ref.known_cells());  // trinary in, trinary out
  std::vector<int8_t> a(ref.cell_count()), b(ref.cell_count());
  duet_grid_copy_ros(g, a.data(), a.size(), 0.65f, 0.45f);
  duet_grid_copy_ros(again, b.data(), b.size(), 0.65f, 0.45f);
  EXPECT_TRUE(a == b);
  duet_grid_release(again);
  // Errors name the file.
  EXPECT_EQ(duet_grid_load_map_server(device_, (dir / "missing.yaml").c_str()), nullptr);
  EXPECT_EQ(take(), DUET_ERROR_IO);
  EXPECT_NE(message().find("missing.yaml"), std::string::npos) << message();
  std::ofstream(dir / "bad.yaml") << "image: copy.pgm\nresolution: -1\norigin: [0, 0, 0]\n";
  EXPECT_EQ(duet_grid_load_map_server(device_, (dir / "bad.yaml").c_str()), nullptr);
  EXPECT_NE(take(), DUET_ERROR_NONE);
  EXPECT_NE(message().find("bad.yaml"), std::string::npos) << message();
  duet_grid_save_map_server(g, "/proc/no_such_dir/x.yaml");
  EXPECT_EQ(take(), DUET_ERROR_IO);
  duet_grid_save_map_server(g, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_grid empty = duet_grid_new(device_, 0.05f);
  duet_grid_save_map_server(empty, (dir / "empty.yaml").c_str());
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_grid_release(empty);
  EXPECT_EQ(duet_grid_load_map_server(device_, nullptr), nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  duet_grid_release(g);
  std::filesystem::remove_all(dir);
}

TEST_F(CapiProfile, AForgottenImageSizeIsAnErrorNotAnOverRead) {
  std::vector<uint16_t> small(8 * 6, 1000);  // 8x6: a 640x480 default would read 6400 times more
  duet_sensor_frame f;
  duet_sensor_frame_init(&f);
  f.depth = small.data();
  duet_cloud c = duet_cloud_new(device_);
  duet_back_project(c, &f, 1, nullptr, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(duet_cloud_get_size(c), 0u);
  f.width = 8;
  f.height = 6;
  duet_back_project(c, &f, 1, nullptr, nullptr);
  EXPECT_EQ(take(), DUET_ERROR_NONE) << message();
  EXPECT_GT(duet_cloud_get_size(c), 0u);
  duet_cloud_release(c);
}

}  // namespace
