#pragma once
/// @file settings_yaml.hpp
/// The settings tree's YAML (private to config/): the runtime's sections read through the
/// field lists of settings_fields.hpp, the whole tree written, overlays merged.
#include <duet/runtime/config/profile.hpp>

#include "config/yaml_reader.hpp"

#include <yaml-cpp/yaml.h>

#include <string>
#include <string_view>
#include <vector>

namespace duet::detail {

/// The keys the goal life cycle adds to the `exploration` section.
[[nodiscard]] std::vector<std::string_view> exploration_goal_keys();

/// Reads the runtime's sections of a profile document (`exploration`'s goal keys, `control`,
/// `localization`, `runtime`; absent keys keep `base`'s values) and validates each part,
/// naming the key (file:line:col) a struct's validate() rejects.
[[nodiscard]] RuntimeSettings read_runtime_settings(Reader& r, const YAML::Node& root, RuntimeSettings base);

/// Merges an overlay document into `base` (mappings key by key, anything else replaced);
/// the overlay's nodes are located in `source`. Throws kParse if the overlay is not a mapping.
void merge_overlay(YAML::Node base, const YAML::Node& overlay, Locator& loc, const std::string& source);

}  // namespace duet::detail
