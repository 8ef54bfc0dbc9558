// `duet profile [NAME|FILE] [--set KEY=VALUE]... [--config FILE]...`: prints the whole effective
// settings tree as profile YAML (every key, loads back with `duet profile FILE`), or with
// --check one line per sensor after validating.
#include "commands.hpp"

#include <duet/runtime/config/profile.hpp>

#include <cstdio>
#include <string>
#include <vector>

namespace duet::app {

std::vector<ProfileOverlay> overlays(const std::vector<std::string>& configs, const std::vector<std::string>& sets) {
  std::vector<ProfileOverlay> out;
  for (const std::string& c : configs) out.push_back(file_overlay(c));
  for (const std::string& s : sets) out.push_back(set_overlay(s));
  return out;
}

void add_overlay_options(CLI::App* cmd, std::vector<std::string>& configs, std::vector<std::string>& sets) {
  cmd->add_option("--config", configs,
                  "a YAML file of profile keys laid over the profile (repeatable; before the --set values)");
  cmd->add_option("--set", sets,
                  "KEY=VALUE: one profile key by its dotted path, e.g. exploration.view_range_m=3 or "
                  "runtime.execution=background (repeatable; `duet profile` lists every key)");
}

void add_profile_command(CLI::App& app, int& exit_code) {
  struct Options {
    std::string name = "dual";
    std::vector<std::string> configs, sets;
    bool check = false;
  };
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("profile", "Print the whole effective settings tree of a profile as YAML (or --check it)");
  cmd->add_option("profile", o->name, "built-in name (dual, single) or a YAML file")->capture_default_str();
  add_overlay_options(cmd, o->configs, o->sets);
  cmd->add_flag("--check", o->check, "validate and print a summary instead of the tree");
  cmd->callback([o, &exit_code] {
    const Profile p = resolve_profile(o->name, overlays(o->configs, o->sets));
    if (!o->check) {
      std::fputs(to_yaml(p).c_str(), stdout);
      exit_code = 0;
      return;
    }
    std::printf("%s: OK - profile '%s', %zu sensor(s), voxel %.3f m, grid %.3f m, execution %s\n", o->name.c_str(), p.name.c_str(),
                p.sensors.size(), static_cast<double>(p.mapping.voxel_filter.leaf_size_m),
                static_cast<double>(p.mapping.grid_resolution_m), to_string(p.runtime.execution));
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
