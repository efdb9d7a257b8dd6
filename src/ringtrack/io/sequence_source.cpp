#include "ringtrack/io/sequence_source.hpp"

#include <utility>

#include "ringtrack/core/error.hpp"

namespace ringtrack::io {

SequenceSource::SequenceSource(const std::string& folder, SequenceReadOptions options)
    : reader_(folder, std::move(options)), folder_(folder) {
  // A sequence folder whose scans/ is empty: nothing to run on, said before any output.
  if (reader_.size() == 0) throw core::InputError(folder + ": no scans found");
}

std::optional<core::OrganizedScan> SequenceSource::next() {
  pose_.reset();
  if (taken_ >= reader_.size()) return std::nullopt;
  // Counted before reading: a file that fails is taken all the same, so ScanReader can skip it.
  ++taken_;
  SequenceScan item;
  if (!reader_.next(item)) return std::nullopt;
  if (reader_.has_poses()) pose_ = item.pose;
  return std::move(item.scan);
}

std::optional<core::Pose> SequenceSource::pose() const {
  return pose_;
}

std::string SequenceSource::description() const {
  return folder_ + (reader_.is_sequence() ? " (sequence folder)" : " (folder of scan files)");
}

std::string SequenceSource::summary() const {
  std::string line = std::to_string(reader_.size()) + " scan files";
  if (const auto organized = reader_.summary(); !organized.empty()) line += "; " + organized;
  return line;
}

}  // namespace ringtrack::io
