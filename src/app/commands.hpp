#pragma once
// The CLI is thin: each subcommand lives in its own src/app/cmd_*.cpp, parses its options with
// CLI11 and calls the library. An add_*_command registers the subcommand and sets `action` (run
// by main after parsing) when it is selected. Exit codes: 0 success, 2 bad input or usage,
// 3 run ended early for a numerical reason. Messages on stderr, results on stdout or files.
#include <CLI/CLI.hpp>
#include <functional>

namespace rubdyn::app {

using Action = std::function<int()>;

void add_check_command(CLI::App& app, Action& action);
void add_campbell_command(CLI::App& app, Action& action);
void add_run_command(CLI::App& app, Action& action);
void add_compare_command(CLI::App& app, Action& action);
void add_analyze_command(CLI::App& app, Action& action);
void add_sweep_commands(CLI::App& app, Action& action);
void add_orbit_command(CLI::App& app, Action& action);
void add_branch_command(CLI::App& app, Action& action);

}  // namespace rubdyn::app
