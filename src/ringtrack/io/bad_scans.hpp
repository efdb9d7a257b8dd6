#pragma once
/// What a front end does with a scan that fails to read or decode (a truncated PCD in a
/// sequence folder, a corrupt bag message): skip it and go on, or stop (docs/inputs.md,
/// "Bad scans").

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/io/source.hpp"

namespace ringtrack::io {

/// The --on-bad-scan policy.
enum class BadScanPolicy {
  kSkip,  ///< count and report the scan, read on (when the input can)
  kStop,  ///< the error ends the command
};

/// Parses "skip" or "stop"; throws core::ConfigError otherwise.
BadScanPolicy parse_bad_scan_policy(const std::string& name);

/// Reads a ScanSource scan by scan, numbering the scans from 0; under kSkip a scan whose
/// message fails to decode is passed over (it keeps its number) and reported to `on_skip`.
/// Only errors inside one message are skipped: an error in the container itself (a corrupt
/// chunk, an unreadable file) cannot be read past and is rethrown, as under kStop.
class ScanReader {
 public:
  /// Called with the number and the error of each skipped scan.
  using SkipHandler = std::function<void(std::uint64_t index, const std::string& error)>;

  /// Reads from `source` (which must outlive the reader).
  ScanReader(ScanSource& source, BadScanPolicy policy, SkipHandler on_skip = {});

  /// The next readable scan and its number, or nullopt at the end; rethrows what it cannot skip.
  std::optional<core::OrganizedScan> next(std::uint64_t& index);
  /// Scans skipped so far.
  [[nodiscard]] std::uint64_t skipped() const { return skipped_; }
  /// Scans taken from the source so far, skipped ones and one that failed included.
  [[nodiscard]] std::uint64_t read() const { return next_index_; }

 private:
  ScanSource& source_;
  BadScanPolicy policy_;
  SkipHandler on_skip_;
  std::uint64_t next_index_{0};
  std::uint64_t skipped_{0};
};

}  // namespace ringtrack::io
