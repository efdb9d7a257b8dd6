#pragma once
/// Scenario files (YAML, docs/formats.md) and scripted-trajectory CSV files (t, id, class, x, y
/// and optional z, height_m, width_m, reflectivity). The only file access of the sim module:
/// reading these two kinds of file.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "ringtrack/sim/scenario.hpp"

namespace ringtrack::sim {

/// Parses scenario YAML text strictly: unknown keys, wrong types and bad values throw
/// core::ConfigError naming source, the line and the entry. A `trajectories` file is not read
/// here (see load_scenario_file); Scenario::trajectories_file keeps its name.
Scenario parse_scenario_yaml(const std::string& text, const std::string& source);
/// Reads and parses a scenario file, then its trajectories CSV (relative to the file), and
/// validates.
Scenario load_scenario_file(const std::filesystem::path& path);
/// The YAML text of a scenario (parse_scenario_yaml reads it back to the same scenario).
std::string format_scenario_yaml(const Scenario& s);
/// Parses trajectory CSV rows `t, id, class, x, y[, z[, height_m[, width_m[, reflectivity]]]]`
/// (# comments; an optional header naming the columns in any order, also after comments),
/// grouped by id and sorted by time; throws core::InputError naming source, line and column.
std::vector<ScriptedActor> parse_trajectories_csv(std::string_view text, const std::string& source);
/// The trajectory CSV text of scripted actors (header with every column, body values on each
/// actor's first row); parse_trajectories_csv reads it back to the same actors.
std::string format_trajectories_csv(const std::vector<ScriptedActor>& actors);
/// A built-in scenario (number or name, optionally "-moving") or, when the argument names an
/// existing file or ends in .yaml/.yml, that file.
Scenario resolve_scenario(const std::string& number_name_or_file);

}  // namespace ringtrack::sim
