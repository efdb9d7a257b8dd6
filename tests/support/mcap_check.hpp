#pragma once
/// Test support: the independent MCAP checker (tests/mcap/*.cjs on node with the npm packages of
/// tools/mcap-check, which scripts/bootstrap installs). Tests skip when it is unavailable.

#include <filesystem>
#include <string>

namespace ringtrack::testing {

/// Why the node checker cannot run ("" when it can): node missing, or the npm packages not
/// installed (run scripts/bootstrap).
std::string mcap_check_unavailable();

/// The command prefix that runs a script of tests/mcap with node: `node <root>/tests/mcap/<name>`.
std::string mcap_script(const std::string& name);

}  // namespace ringtrack::testing
