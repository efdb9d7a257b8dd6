#pragma once
// Subcommands of the ringtrack tool; each lives in its own cmd_<name>.cpp and registers itself.

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "ringtrack/core/config.hpp"
#include "ringtrack/io/run_status.hpp"
#include "ringtrack/io/scan_source.hpp"

namespace ringtrack::cli {

/// The --config/--set options shared by every command that runs the pipeline.
struct ConfigOptions {
  std::string file;
  std::vector<std::string> overrides;

  /// Adds --config and --set to a subcommand.
  void add_to(CLI::App& command);
  /// Defaults, then the file, then each --set in order; throws core::ConfigError.
  [[nodiscard]] core::Config load() const;
  /// True when the file or a --set gives `key` (section.name) a value.
  [[nodiscard]] bool sets(const std::string& key) const;
};

/// The input and decoder options `run` and `convert` share (docs/inputs.md): one definition, so
/// whatever converts also runs.
struct InputOptions {
  std::string format{"auto"};
  std::string topic;
  std::string model;
  std::string calibration;
  std::string metadata;
  std::string return_selection{"auto"};
  std::string time_source{"host"};
  std::string ring_field{"ring"};
  double cut_azimuth_deg{0.0};
  double scan_rate_hz{10.0};
  int port{2368};
  bool keep_partial{false};

  /// Adds --format, --topic, --model/--sensor, --calibration, --metadata, --return,
  /// --cut-azimuth, --scan-rate, --time-source, --port, --ring-field and --keep-partial.
  void add_to(CLI::App& command);
  /// The source options they describe; throws core::ConfigError naming a bad value.
  [[nodiscard]] io::ScanSourceOptions source_options() const;
};

/// Keeps the command line (program name first) for run.json; called once by main().
void set_command_line(int argc, char** argv);
/// A run.json status for `command` reading `input`: its command line and ringtrack's version.
io::RunStatus new_run_status(const std::string& command, const std::string& input);
/// Flushes standard output and throws core::Error when anything written to it was lost (a full
/// disk, /dev/full, a closed pipe): such a command must not exit 0.
void check_stdout();

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
