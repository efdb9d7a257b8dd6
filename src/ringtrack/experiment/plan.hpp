#pragma once
/// Which scenario runs a benchmark or a tuning study is made of: built-in scenarios and scenario
/// files, each with a static sensor and with a moving one.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "ringtrack/sim/scenario.hpp"

namespace ringtrack::experiment {

/// One run: a scenario with its sensor motion.
struct PlannedRun {
  sim::Scenario scenario;
  bool validation{false};  ///< from a scenario file (the validation set), reported apart
  /// Whether the sensor moves.
  [[nodiscard]] bool moving() const;
  /// Short unique name: "3-static", "6-moving", "V-<name>-static".
  [[nodiscard]] std::string stem() const;
};

/// What to plan.
struct PlanOptions {
  std::vector<int> builtins{1, 2, 3, 4, 5, 6, 7};  ///< built-in scenario numbers
  /// Built-ins run by default, and beside scenario files only when named explicitly.
  bool builtins_given{false};
  std::vector<std::string> scenario_files;  ///< validation scenarios (YAML)
  std::optional<double> duration_s;         ///< replaces every scenario's duration
  bool with_static{true};
  bool with_moving{true};
};

/// The runs in order (built-ins, then files; static before moving), each validated before any
/// runs: a moving variant may cross a solid. The moving variant of a scenario is the figure 8
/// about its position; a file's scripted sensor path is kept as its moving run. Throws
/// core::InputError / core::ConfigError naming the scenario.
std::vector<PlannedRun> plan_runs(const PlanOptions& options);

/// The scenario files (*.yaml) of a folder, sorted; throws core::InputError when there is none.
std::vector<std::string> scenario_files_in(const std::filesystem::path& dir);

}  // namespace ringtrack::experiment
