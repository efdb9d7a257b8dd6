#pragma once
// Runs a shell command for CLI tests and captures its exit code, stdout and stderr.

#include <sys/types.h>

#include <string>

namespace ringtrack::testing {

/// Result of a finished command.
struct CommandResult {
  int exit_code{-1};
  std::string out;
  std::string err;
};

/// Runs `command` through /bin/sh; stdout and stderr are captured separately.
CommandResult run_command(const std::string& command);

/// Waits up to 10 s for child pid to end, polling; a child still running then is killed
/// (SIGKILL) and reaped. Returns true when it ended by itself; status gets waitpid's status.
bool wait_or_kill(pid_t pid, int& status);

/// A fresh empty temporary directory (removed by the caller if it wishes).
std::string make_temp_dir(const std::string& prefix);

}  // namespace ringtrack::testing
