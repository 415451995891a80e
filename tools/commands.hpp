// Subcommands of the `pseudohaptic` tool. Each registers its options on the app and returns the function
// that runs it once CLI11 has parsed the command line.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace ph::tools {

using Run = std::function<int()>;

Run add_targets_command(CLI::App& app);
Run add_surfaces_command(CLI::App& app);
Run add_inspect_command(CLI::App& app);
Run add_trace_command(CLI::App& app);
Run add_demo_command(CLI::App& app);
Run add_replay_command(CLI::App& app);
Run add_check_config_command(CLI::App& app);
Run add_accuracy_command(CLI::App& app);
Run add_study_command(CLI::App& app);
Run add_stability_command(CLI::App& app);
Run add_status_command(CLI::App& app);
Run add_cursor_command(CLI::App& app);
Run add_passthrough_command(CLI::App& app);

}  // namespace ph::tools
