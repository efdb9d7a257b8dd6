#pragma once
// Subcommands of the ringtrack tool; each lives in its own cmd_<name>.cpp and registers itself.

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "ringtrack/core/config.hpp"

namespace ringtrack::cli {

/// The --config/--set options shared by every command that runs the pipeline.
struct ConfigOptions {
  std::string file;
  std::vector<std::string> overrides;

  /// Adds --config and --set to a subcommand.
  void add_to(CLI::App& command);
  /// Defaults, then the file, then each --set in order; throws core::ConfigError.
  [[nodiscard]] core::Config load() const;
};

void register_dump_config(CLI::App& app);
void register_demo(CLI::App& app);
void register_run(CLI::App& app);
void register_eval(CLI::App& app);
void register_eval_trajectory(CLI::App& app);
void register_simulate(CLI::App& app);
void register_convert(CLI::App& app);
void register_benchmark(CLI::App& app);
void register_sensors(CLI::App& app);
void register_tune(CLI::App& app);

}  // namespace ringtrack::cli
