// `duet profile [NAME|FILE]`: prints a built-in profile's YAML, or validates a profile file.
#include "commands.hpp"

#include <duet/runtime/config/profile.hpp>

#include <cstdio>
#include <filesystem>
#include <string>

namespace duet::app {

void add_profile_command(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand("profile", "Print a built-in profile, or check a profile file and print a summary");
  auto name = std::make_shared<std::string>("dual");
  cmd->add_option("profile", *name, "built-in name (dual, single) or a YAML file")->capture_default_str();
  cmd->callback([name, &exit_code] {
    const bool is_file = std::filesystem::exists(*name) || name->find('/') != std::string::npos ||
                         name->ends_with(".yaml") || name->ends_with(".yml");
    if (!is_file) {
      std::fputs(std::string(builtin_profile_text(*name)).c_str(), stdout);
      exit_code = 0;
      return;
    }
    const Profile p = resolve_profile(*name);
    std::printf("%s: OK - profile '%s', %zu sensor(s), voxel %.3f m, grid %.3f m\n", name->c_str(), p.name.c_str(),
                p.sensors.size(), static_cast<double>(p.mapping.voxel_filter.leaf_size_m),
                static_cast<double>(p.mapping.grid_resolution_m));
    for (const auto& s : p.sensors) {
      const auto t = s.extrinsics.xyz_m;
      const auto e = s.extrinsics.zyx_euler_deg;
      std::printf("  %-8s %dx%d fx %.1f fy %.1f, at (%.3f, %.3f, %.3f) m, zyx (%.1f, %.1f, %.1f) deg\n", s.name.c_str(),
                  s.intrinsics.width, s.intrinsics.height, static_cast<double>(s.intrinsics.fx),
                  static_cast<double>(s.intrinsics.fy), static_cast<double>(t.x()), static_cast<double>(t.y()),
                  static_cast<double>(t.z()), static_cast<double>(e.x()), static_cast<double>(e.y()),
                  static_cast<double>(e.z()));
    }
    exit_code = 0;
  });
}

}  // namespace duet::app
