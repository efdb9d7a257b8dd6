#pragma once
/// Where the CLI finds the files it runs or reads besides its own code: the plot scripts, the
/// shipped configuration and the Python package. An installed binary finds them relative to
/// itself (<prefix>/bin/ringtrack -> <prefix>/share/ringtrack), the build tree's binary in the
/// source and build trees (docs/cpp.md, "Installing").

#include <filesystem>

namespace ringtrack::cli {

/// The plot scripts (scripts/ of the source tree, <prefix>/share/ringtrack/scripts installed).
std::filesystem::path scripts_dir();
/// The shipped configuration (config/ of the source tree, <prefix>/share/ringtrack/config).
std::filesystem::path config_dir();
/// The folder holding the ringtrack Python package, for PYTHONPATH (build/python, or the
/// installed package's folder, RINGTRACK_PYTHON_INSTALL_DIR under the prefix).
std::filesystem::path python_dir();

}  // namespace ringtrack::cli
