#include "ringtrack/io/bad_scans.hpp"

#include <utility>

#include "ringtrack/core/error.hpp"

namespace ringtrack::io {

BadScanPolicy parse_bad_scan_policy(const std::string& name) {
  if (name == "skip") return BadScanPolicy::kSkip;
  if (name == "stop") return BadScanPolicy::kStop;
  throw core::ConfigError("--on-bad-scan '" + name + "': expected skip or stop");
}

ScanReader::ScanReader(ScanSource& source, BadScanPolicy policy, SkipHandler on_skip)
    : source_(source), policy_(policy), on_skip_(std::move(on_skip)) {}

std::optional<core::OrganizedScan> ScanReader::next(std::uint64_t& index) {
  for (;;) {
    const auto before = source_.items_taken();
    try {
      auto scan = source_.next();
      if (scan) index = next_index_++;
      return scan;
    } catch (const core::InputError& e) {
      // Skippable only when the failing message or file was taken (bag sources count a message
      // before decoding it, folder sources a file before reading it), so the next call starts
      // at the one after it.
      const auto after = source_.items_taken();
      if (policy_ == BadScanPolicy::kStop || !before || !after || *after <= *before) {
        ++next_index_;  // the scan that stops the reading was taken too
        throw;
      }
      ++skipped_;
      const std::uint64_t bad = next_index_++;
      if (on_skip_) on_skip_(bad, e.what());
    }
  }
}

}  // namespace ringtrack::io
