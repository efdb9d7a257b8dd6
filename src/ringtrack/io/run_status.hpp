#pragma once
/// run.json: the completeness marker every command that writes a folder of outputs leaves in it
/// (docs/formats.md, "run.json"). Written as "running" when the outputs are opened and rewritten,
/// atomically, when the command ends, so a folder whose run.json does not say complete holds
/// outputs that must not be trusted.

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace ringtrack::io {

/// How a command that writes outputs ended (so far).
enum class RunState {
  kRunning,      ///< started; still running, or killed without a chance to say so
  kFinished,     ///< read its whole input; every output written and closed
  kInterrupted,  ///< stopped by a signal; every output written and closed up to the last scan
  kFailed,       ///< stopped by an error; the outputs are partial
};

/// The name of a state in run.json: running, finished, interrupted, failed.
const char* run_state_name(RunState state);

/// A scan that was read from the input but not processed, and why.
struct SkippedScan {
  std::uint64_t index{0};  ///< the scan's number in the input, from 0
  std::string reason;      ///< one line, e.g. the decoding error naming the file
};

/// Everything run.json records.
struct RunStatus {
  std::string command;                        ///< e.g. "run", "convert"
  std::vector<std::string> arguments;         ///< the command line, program name first
  std::string version;                        ///< of ringtrack
  std::string input;                          ///< what was read ("" when the command has no input)
  RunState state{RunState::kRunning};         ///< see RunState
  std::string signal;                         ///< kInterrupted: "SIGINT" or "SIGTERM"
  std::string error;                          ///< kFailed: the error message
  std::uint64_t scans_read{0};                ///< taken from the input, processed or not
  std::uint64_t scans_processed{0};           ///< that went into the outputs
  std::uint64_t scans_skipped_unreadable{0};  ///< that failed to decode (--on-bad-scan skip)
  std::uint64_t scans_skipped_stamp{0};  ///< whose stamp did not come after the previous scan's
  std::uint64_t scans_failed{0};         ///< the scan whose error stopped the command (0 or 1)
  std::vector<SkippedScan> skipped;      ///< the skipped scans (at most kMaxListedSkippedScans)
  /// The origin of the local frame the maps are written in (world = map point + origin, m);
  /// unset until the first scan is processed and for commands without maps.
  std::optional<std::array<double, 3>> origin_m;
  std::string started_utc;  ///< ISO 8601, set by RunStatusFile::start()
  std::string ended_utc;    ///< ISO 8601, set when the state leaves kRunning

  /// True when the outputs are whole: finished, or interrupted after closing them.
  [[nodiscard]] bool complete() const {
    return state == RunState::kFinished || state == RunState::kInterrupted;
  }
  /// Records a skipped scan (counted by the caller), keeping the list bounded.
  void add_skipped(std::uint64_t index, std::string reason);
};

/// The number of skipped scans listed in run.json by index and reason (all are counted).
inline constexpr std::size_t kMaxListedSkippedScans = 1000;

/// The JSON text of a status (one object, keys in a fixed order, ending in a newline).
std::string format_run_status(const RunStatus& status);

/// Writes `path` atomically: the text goes to a temporary file beside it, which then replaces
/// `path` by a rename, so a reader sees the old or the new file, never a part. Throws core::Error
/// naming the file.
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

/// The current UTC time as ISO 8601 ("2026-11-26T07:15:13Z").
std::string utc_now_iso8601();

/// The run.json of one output folder: the status and where it goes.
class RunStatusFile {
 public:
  /// Remembers the path (e.g. out / "run.json") and the status; writes nothing yet.
  RunStatusFile(std::filesystem::path path, RunStatus status);

  /// Writes the status as running (complete: false); throws core::Error when it cannot.
  void start();
  /// Marks the run finished (or interrupted by `signal` when it is not empty) and writes it.
  void finish(const std::string& signal = {});
  /// Marks the run failed with `error` and writes it; never throws (called while an error is
  /// already on its way), so a failure to write is lost.
  void fail(const std::string& error) noexcept;

  /// The status, for the command to update its counters.
  [[nodiscard]] RunStatus& status() { return status_; }
  /// The file's path.
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  RunStatus status_;
};

}  // namespace ringtrack::io
