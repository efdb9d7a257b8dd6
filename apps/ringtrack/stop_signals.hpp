#pragma once
// Ctrl-C (SIGINT) and SIGTERM (kill, docker stop, systemd) ask a long command to stop after the
// scan at hand and close its outputs properly; one helper for every command (issues 16, 17).

#include <atomic>
#include <string>

namespace ringtrack::cli {

/// While alive, SIGINT and SIGTERM set stop_flag() instead of ending the process; a second
/// signal ends it the default way (for a command that does not get to its next check). The
/// previous handlers come back on destruction.
class StopSignals {
 public:
  /// Installs the handlers and clears the flag.
  StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;
  /// Restores the handlers in place before.
  ~StopSignals();

  /// The flag the handlers set (for io::VelodyneSourceOptions::interrupt).
  [[nodiscard]] static const std::atomic<bool>& stop_flag();
  /// True once a signal asked to stop.
  [[nodiscard]] static bool requested() { return stop_flag().load(); }
  /// "SIGINT" or "SIGTERM" once a signal asked to stop, else "".
  [[nodiscard]] static std::string signal_name();
};

}  // namespace ringtrack::cli
