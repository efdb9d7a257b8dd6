#pragma once
/// Sequence folders (docs/formats.md): sequence.yaml, scans/NNNNNN.pcd, stamps.txt, poses.txt,
/// objects.csv. Written by the simulator, read by `ringtrack run`; plain PCD folders read too.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ringtrack/core/cloud_organizer.hpp"
#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/io/csv_writers.hpp"
#include "ringtrack/io/output_file.hpp"
#include "ringtrack/io/pcd.hpp"
#include "ringtrack/io/poses.hpp"

namespace ringtrack::io {

/// Version of the sequence folder format this code reads and writes.
inline constexpr int kSequenceFormatVersion = 1;

/// Contents of sequence.yaml.
struct SequenceMeta {
  int format_version{kSequenceFormatVersion};  ///< always kSequenceFormatVersion
  std::string sensor{"vlp16"};                 ///< vlp16 | vlp32c | hdl32e | generic
  std::vector<double> elevations_deg;          ///< generic only: ring elevations, degrees
  double max_range_m{100.0};                   ///< generic only: maximum range
  double scan_rate_hz{10.0};                   ///< revolutions per second
  int columns{0};                      ///< WIDTH of every scan (0 in a writer: the first scan's)
  std::optional<std::uint64_t> scans;  ///< number of scans (the writer's finish() sets it)
  std::string name;                    ///< optional free text
  std::string scenario;                ///< optional: the simulator scenario (number or name)
  std::optional<std::uint64_t> seed;   ///< optional: the simulator seed
  /// optional: the sensor's height above the ground at the first scan (m), as the simulator
  /// knows it; `run` takes it for detection.sensor_height_m unless the configuration sets that.
  std::optional<double> sensor_height_m;

  /// The sensor model: a built-in by name, or generic from elevations_deg; throws core::Error
  /// when the description is inconsistent.
  [[nodiscard]] core::SensorModel sensor_model() const;
  /// A description of `model` (a built-in name when it is one, else generic with its elevations).
  static SequenceMeta for_sensor(const core::SensorModel& model, int columns);
};

/// Reads sequence.yaml strictly (unknown keys, wrong types, unsupported versions and
/// out-of-range values throw core::InputError naming the file, line and key).
SequenceMeta read_sequence_yaml(const std::filesystem::path& path);
/// The YAML text of a SequenceMeta, as the writer stores it.
std::string format_sequence_yaml(const SequenceMeta& meta);

/// Options of SequenceWriter.
struct SequenceWriteOptions {
  PcdEncoding encoding{PcdEncoding::kBinaryCompressed};  ///< of scans/NNNNNN.pcd
  bool ground_truth{true};  ///< write objects.csv (header even when no object is ever added)
  bool overwrite{false};    ///< replace an existing sequence in the folder
};

/// Writes a sequence folder scan by scan. sequence.yaml is written last, by finish(), so a folder
/// whose writing failed or was interrupted lacks it and is rejected by SequenceReader as
/// incomplete. Every I/O failure throws core::Error naming the file.
class SequenceWriter {
 public:
  /// Creates the folder (and scans/); refuses a folder holding a sequence unless overwrite.
  SequenceWriter(const std::filesystem::path& folder, SequenceMeta meta,
                 SequenceWriteOptions options = {});
  SequenceWriter(const SequenceWriter&) = delete;
  SequenceWriter& operator=(const SequenceWriter&) = delete;
  ~SequenceWriter();

  /// Writes scans/NNNNNN.pcd (labels: empty or one per cell), the scan's stamp (scan.stamp_ns,
  /// strictly increasing) to stamps.txt, the pose (if any) to poses.txt and the ground-truth rows
  /// to objects.csv (their scan and stamp_ns are set to this scan's). Throws core::Error on a
  /// scan whose size differs from the sequence's.
  void add_scan(const core::OrganizedScan& scan, std::span<const std::uint32_t> labels,
                const std::optional<core::Pose>& pose = std::nullopt,
                std::span<const ObjectRow> objects = {});
  /// Adds a pose sample between scans (a trajectory sampled faster than the scans); stamps of
  /// all poses must strictly increase.
  void add_pose(const core::Pose& pose);
  /// Scans written so far.
  [[nodiscard]] std::size_t size() const { return scans_; }
  /// The folder being written.
  [[nodiscard]] const std::filesystem::path& folder() const { return folder_; }
  /// Closes every file and writes sequence.yaml; the sequence is complete only after this.
  void finish();

 private:
  std::filesystem::path folder_;
  SequenceMeta meta_;
  SequenceWriteOptions options_;
  int rings_{0};
  std::size_t scans_{0};
  std::optional<std::int64_t> last_stamp_ns_;
  std::optional<std::int64_t> last_pose_ns_;
  std::unique_ptr<OutputFile> stamps_;
  std::unique_ptr<OutputFile> poses_;
  std::unique_ptr<ObjectsCsvWriter> objects_;
  bool finished_{false};
};

/// Format of a poses file.
enum class PoseFileFormat {
  kTum,    ///< t x y z qx qy qz qw (any stamps; interpolated to the scan stamps)
  kKitti,  ///< 12 numbers per line, one line per scan in scan order (stamps = scan stamps)
};

/// Options of SequenceReader.
struct SequenceReadOptions {
  std::filesystem::path poses;  ///< poses file replacing the folder's poses.txt (empty: none)
  PoseFileFormat poses_format{PoseFileFormat::kTum};  ///< format of `poses` / poses.txt
  std::filesystem::path stamps;  ///< stamps file replacing the folder's stamps.txt (empty: none)
  /// Plain folders: the sensor (default: a generic one with the first scan's ring elevations,
  /// measured by core::measure_cloud_sensor for clouds without rings).
  std::optional<core::SensorModel> sensor;
  /// Clouds without rings (.bin files, PCD of HEIGHT 1 without a ring field): the column grid.
  /// Clockwise from +x, as real sensors turn, with the firing delays of a named model undone, as
  /// a driver's points carry them (a measured sensor has none).
  core::CloudOrganizerOptions organizer{
      .first_column_azimuth_rad = 0.0, .clockwise = true, .undo_firing_rotation = true};
  /// Plain PCD folders without a stamps file: stamp of scan i = i / scan_rate_hz.
  double scan_rate_hz{10.0};
  PcdReadOptions pcd;  ///< how the PCD files are read (row order, organizing unorganized clouds)
};

/// One scan of a sequence with its stamp, pose and labels.
struct SequenceScan {
  std::size_t index{0};               ///< position in the sequence, from 0
  std::filesystem::path path;         ///< its PCD file
  core::OrganizedScan scan;           ///< stamp_ns and column stamps set
  std::vector<std::uint32_t> labels;  ///< per cell, empty without a label field
  core::Pose pose;                    ///< sensor in world at scan.stamp_ns
};

/// Reads a sequence folder, or a plain folder of PCD files or of KITTI-style .bin files sorted by
/// name (digit runs compared as numbers). Clouds without rings (.bin, PCD of HEIGHT 1 without a
/// ring field) are organized by core::CloudOrganizer into the sensor's grid. Stamps, poses and the
/// scan list are checked on construction, so errors (missing files, stamps outside the poses)
/// surface before the first scan is processed.
class SequenceReader {
 public:
  /// Opens the folder; throws core::InputError naming the file and what was expected.
  explicit SequenceReader(const std::filesystem::path& folder, SequenceReadOptions options = {});

  /// True for a sequence folder (sequence.yaml), false for a plain PCD folder.
  [[nodiscard]] bool is_sequence() const { return is_sequence_; }
  /// sequence.yaml, or for a plain folder the values used (sensor "generic" when inferred).
  [[nodiscard]] const SequenceMeta& meta() const { return meta_; }
  /// The sensor model the scans are checked against.
  [[nodiscard]] const core::SensorModel& sensor() const { return sensor_; }
  /// Number of scans.
  [[nodiscard]] std::size_t size() const { return paths_.size(); }
  /// PCD or .bin file of scan i.
  [[nodiscard]] const std::filesystem::path& scan_path(std::size_t i) const { return paths_.at(i); }
  /// Stamp of scan i (time of its first column).
  [[nodiscard]] std::int64_t stamp_ns(std::size_t i) const { return stamps_.at(i); }
  /// Pose of the sensor in the world at scan i's stamp (identity without a poses file).
  [[nodiscard]] const core::Pose& pose(std::size_t i) const { return poses_.at(i); }
  /// True when poses came from a file.
  [[nodiscard]] bool has_poses() const { return has_poses_; }
  /// objects.csv of a sequence folder, when present.
  [[nodiscard]] std::optional<std::filesystem::path> objects_csv() const { return objects_csv_; }
  /// Reads scan i; throws core::InputError when its file is malformed or its rings or columns
  /// differ from the sequence's.
  [[nodiscard]] SequenceScan read(std::size_t i) const;
  /// Reads the next scan (from 0); false after the last.
  bool next(SequenceScan& out);
  /// What organizing the clouds without rings read so far did (clouds 0 when none was read).
  [[nodiscard]] const core::CloudOrganizeTotals& organize_totals() const {
    return organize_totals_;
  }
  /// organize_totals() as one line (after the measured sensor's rings and columns when it was
  /// measured), "" when no cloud without rings was read.
  [[nodiscard]] std::string summary() const;

 private:
  // A scan file's contents: an organized scan, or a cloud without rings.
  struct ScanFile {
    std::optional<PcdScan> pcd;
    std::optional<core::UnorganizedCloud> cloud;
  };
  [[nodiscard]] ScanFile read_scan_file(const std::filesystem::path& path) const;
  void open_sequence(const std::filesystem::path& folder);
  void open_plain(const std::filesystem::path& folder);
  void load_stamps_and_poses(const std::filesystem::path& folder);

  SequenceReadOptions options_;
  bool is_sequence_{false};
  SequenceMeta meta_;
  core::SensorModel sensor_;
  std::vector<std::filesystem::path> paths_;
  std::vector<std::int64_t> stamps_;
  std::vector<core::Pose> poses_;
  bool has_poses_{false};
  std::optional<std::filesystem::path> objects_csv_;
  std::size_t next_{0};
  mutable std::optional<core::CloudOrganizer> organizer_;  // built at the first cloud
  mutable core::CloudOrganizeTotals organize_totals_;
  std::string measured_sensor_;  // how the sensor was measured on the first cloud, or ""
};

/// Per-ring elevations measured on an organized scan (core/cloud_organizer.hpp).
using core::measure_elevations_deg;

/// Name of scan i inside scans/: six or more digits and ".pcd" ("000042.pcd").
std::string scan_file_name(std::size_t index);

}  // namespace ringtrack::io
