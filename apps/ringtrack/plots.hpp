#pragma once
/// Pictures drawn by the Python scripts in scripts/ (Debian's python3-matplotlib).

#include <filesystem>
#include <string>
#include <vector>

namespace ringtrack::cli {

/// Runs the plot script (scripts/<script>, installed in share/ringtrack/scripts/) with
/// /usr/bin/python3 and the given arguments; false, with a one-line warning on stderr saying why,
/// when Python, matplotlib or the script is missing or it fails.
bool run_plot_script(const std::string& script, const std::vector<std::filesystem::path>& args);

}  // namespace ringtrack::cli
