// The `duet` command-line program: `duet explore`, `duet compare`, `duet run`, `duet map`, `duet profile`.
#include "commands.hpp"

#include <duet/kernels/error.hpp>
#include <duet/version.hpp>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <unistd.h>

#include <cstdio>
#include <iostream>

bool duet::app::stderr_is_tty() { return ::isatty(2) != 0; }

int main(int argc, char** argv) {
  CLI::App app{"duet: autonomous exploration and mapping with two RGB-D sensors (" DUET_VERSION_STRING ")"};
  app.require_subcommand(1);
  app.set_version_flag("--version", DUET_VERSION_STRING);
  int exit_code = 0;
  duet::app::add_map_command(app, exit_code);
  duet::app::add_profile_command(app, exit_code);
  duet::app::add_explore_command(app, exit_code);
  duet::app::add_compare_command(app, exit_code);
  duet::app::add_run_command(app, exit_code);
  duet::app::add_replay_command(app, exit_code);
  duet::app::add_eval_traj_command(app, exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const duet::Error& e) {
    std::fprintf(stderr, "duet: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "duet: error: %s\n", e.what());
    return 1;
  }
  return exit_code;
}
