#pragma once
// Sub-commands of the `duet` program; each registers itself on the CLI11 app and runs from
// its callback, setting exit_code.
#include <CLI/CLI.hpp>

namespace duet::app {

void add_map_command(CLI::App& app, int& exit_code);
void add_profile_command(CLI::App& app, int& exit_code);
void add_explore_command(CLI::App& app, int& exit_code);
void add_compare_command(CLI::App& app, int& exit_code);

}  // namespace duet::app
