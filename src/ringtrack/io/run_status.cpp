#include "ringtrack/io/run_status.hpp"

#include <chrono>
#include <ctime>
#include <nlohmann/json.hpp>
#include <system_error>
#include <utility>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/output_file.hpp"

namespace ringtrack::io {

const char* run_state_name(RunState state) {
  switch (state) {
    case RunState::kRunning:
      return "running";
    case RunState::kFinished:
      return "finished";
    case RunState::kInterrupted:
      return "interrupted";
    case RunState::kFailed:
      return "failed";
  }
  return "running";
}

void RunStatus::add_skipped(std::uint64_t index, std::string reason) {
  if (skipped.size() < kMaxListedSkippedScans) skipped.push_back({index, std::move(reason)});
}

std::string format_run_status(const RunStatus& s) {
  nlohmann::ordered_json j;
  j["complete"] = s.complete();
  j["state"] = run_state_name(s.state);
  j["interrupted"] = s.signal.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(s.signal);
  j["error"] = s.error.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(s.error);
  j["command"] = s.command;
  j["arguments"] = s.arguments;
  j["version"] = s.version;
  j["input"] = s.input;
  j["scans"] = {{"read", s.scans_read},
                {"processed", s.scans_processed},
                {"skipped", s.scans_skipped_unreadable + s.scans_skipped_stamp},
                {"skipped_unreadable", s.scans_skipped_unreadable},
                {"skipped_stamp", s.scans_skipped_stamp},
                {"failed", s.scans_failed}};
  auto skipped = nlohmann::ordered_json::array();
  for (const auto& k : s.skipped) skipped.push_back({{"scan", k.index}, {"reason", k.reason}});
  j["skipped_scans"] = std::move(skipped);
  if (s.origin_m) j["origin_m"] = *s.origin_m;
  j["started_utc"] = s.started_utc;
  j["ended_utc"] =
      s.ended_utc.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(s.ended_utc);
  // Invalid UTF-8 (e.g. from a file name in an error) is replaced rather than thrown on.
  return j.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
}

void write_file_atomically(const std::filesystem::path& path, std::string_view bytes) {
  std::filesystem::path temporary = path;
  temporary += ".tmp";
  write_file(temporary, bytes);
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) {
    std::filesystem::remove(temporary, ec);
    throw core::Error(path.string() + ": cannot replace it with " + temporary.string() + ": " +
                      ec.message());
  }
}

std::string utc_now_iso8601() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

RunStatusFile::RunStatusFile(std::filesystem::path path, RunStatus status)
    : path_(std::move(path)), status_(std::move(status)) {}

void RunStatusFile::start() {
  status_.state = RunState::kRunning;
  status_.started_utc = utc_now_iso8601();
  write_file_atomically(path_, format_run_status(status_));
}

void RunStatusFile::finish(const std::string& signal) {
  status_.state = signal.empty() ? RunState::kFinished : RunState::kInterrupted;
  status_.signal = signal;
  status_.ended_utc = utc_now_iso8601();
  write_file_atomically(path_, format_run_status(status_));
}

void RunStatusFile::fail(const std::string& error) noexcept {
  try {
    status_.state = RunState::kFailed;
    status_.error = error;
    status_.ended_utc = utc_now_iso8601();
    write_file_atomically(path_, format_run_status(status_));
  } catch (...) {  // NOLINT(bugprone-empty-catch): the error being reported matters more
  }
}

}  // namespace ringtrack::io
