#include "support/mcap_check.hpp"

#include <cstdlib>

#include "support/run_command.hpp"

namespace ringtrack::testing {
namespace {

std::string source_dir() {
  const char* env = std::getenv("RINGTRACK_SOURCE_DIR");
  return env != nullptr ? env : RINGTRACK_SOURCE_DIR;
}

}  // namespace

std::string mcap_check_unavailable() {
  if (run_command("node --version").exit_code != 0) {
    return "node is not installed (the MCAP checks run the reference library @mcap/core on node)";
  }
  const std::filesystem::path modules =
      std::filesystem::path(source_dir()) / "tools/mcap-check/node_modules/@mcap/core";
  if (!std::filesystem::exists(modules)) {
    return "the npm packages of tools/mcap-check are not installed (run scripts/bootstrap)";
  }
  return "";
}

std::string mcap_script(const std::string& name) {
  return "node " + source_dir() + "/tests/mcap/" + name;
}

}  // namespace ringtrack::testing
