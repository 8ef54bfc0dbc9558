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

/// Reads the `mapping` section through its field list (absent keys keep the defaults).
[[nodiscard]] MappingSettings read_mapping(Reader& r, const YAML::Node& node);

/// Reads the kernels' keys of the `exploration` section into `ex` (absent keys keep its values);
/// the caller checks the section's keys (the goal life cycle's keys share it).
void read_exploration_kernels(Reader& r, const YAML::Node& node, ExplorationProfile& ex);

/// Every struct's validate() and the constraints between sections; errors name the key with
/// the file:line:column `loc` recorded for it (profile_validate.cpp).
void validate_profile(const Profile& p, const Locator& loc);

/// Merges an overlay document into `base` (mappings key by key, anything else replaced);
/// the overlay's nodes are located in `source`. Throws kParse if the overlay is not a mapping.
void merge_overlay(YAML::Node base, const YAML::Node& overlay, Locator& loc, const std::string& source);

}  // namespace duet::detail
