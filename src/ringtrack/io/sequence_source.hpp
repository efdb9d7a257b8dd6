#pragma once
/// A folder of scan files (a sequence folder, a folder of PCD files or of KITTI-style .bin
/// files; sequence.hpp) as a ScanSource: scans in order with their poses when the folder has
/// some (its poses.txt, or a poses file given in their place).

#include <cstdint>
#include <optional>
#include <string>

#include "ringtrack/io/sequence.hpp"
#include "ringtrack/io/source.hpp"

namespace ringtrack::io {

/// Reads a folder through SequenceReader.
class SequenceSource final : public ScanSource {
 public:
  /// Opens the folder; throws core::InputError naming the file and what was expected, or when
  /// the folder holds no scan.
  SequenceSource(const std::string& folder, SequenceReadOptions options);

  /// The next scan, its pose in pose(); throws core::InputError for a malformed file (which
  /// is taken: the next call reads the file after it).
  std::optional<core::OrganizedScan> next() override;
  /// The last scan's pose when the folder has poses.
  [[nodiscard]] std::optional<core::Pose> pose() const override;
  /// The folder's sensor.
  [[nodiscard]] const core::SensorModel& model() const override { return reader_.sensor(); }
  /// The folder's name and kind.
  [[nodiscard]] std::string description() const override;
  /// The number of scan files and what organizing clouds without rings did.
  [[nodiscard]] std::string summary() const override;
  /// Files taken so far, the one that failed included.
  [[nodiscard]] std::optional<std::uint64_t> items_taken() const override { return taken_; }
  /// Number of scan files.
  [[nodiscard]] std::size_t size() const override { return reader_.size(); }
  /// The reader (every scan's pose, the folder's metadata).
  [[nodiscard]] const SequenceReader* sequence() const override { return &reader_; }

 private:
  SequenceReader reader_;
  std::string folder_;
  std::uint64_t taken_{0};
  std::optional<core::Pose> pose_;  // the last scan's, when the folder has poses
};

}  // namespace ringtrack::io
