#pragma once
/// A run's input: scans from any source (io::open_source) with the pose to process each one
/// at, motion-compensated (pipeline::deskew_scan) whenever the sensor's motion is known: from a
/// folder's own poses (or a poses file given in their place), or from a TUM trajectory matched to
/// a recording's stamps (docs/inputs.md, "Sensor poses and motion compensation"). `ringtrack run`
/// reads its input through it; the pipeline, the outputs and the odometry stay with the caller.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/io/bad_scans.hpp"
#include "ringtrack/io/poses.hpp"
#include "ringtrack/io/scan_source.hpp"

namespace ringtrack::runner {

/// Where a run's poses come from and whether its scans are compensated.
struct RunInputOptions {
  io::ScanSourceOptions source;  ///< how to open the input (format, sensor, interrupt, ...)
  /// A poses file (`--poses`): for a folder it replaces its poses.txt; for a recording it must
  /// be TUM (stamps), matched to each scan's stamp. Empty: the folder's own, or none.
  std::string poses;
  std::string poses_format{"tum"};  ///< tum | kitti (folders only)
  bool no_deskew{false};            ///< never compensate the motion (`--no-deskew`)
  io::BadScanPolicy on_bad_scan{io::BadScanPolicy::kSkip};  ///< unreadable scans
};

/// Earliest and latest column stamps of a scan (its first and last column in firing order); equal
/// when it has no per-column times (all columns share one stamp, or none are set): then there is
/// no motion within the scan to compensate.
std::pair<std::int64_t, std::int64_t> column_time_span(const core::OrganizedScan& scan);

/// Scans with their poses from one input.
class RunInput {
 public:
  /// Called for each scan that could not be read and was skipped: its number and the error.
  using SkipHandler = io::ScanReader::SkipHandler;

  /// Opens `input`; throws core::InputError / core::ConfigError naming the input, the poses file
  /// or the option and what was expected.
  RunInput(const std::string& input, const RunInputOptions& options, SkipHandler on_skip = {});

  /// The input as given (for messages).
  [[nodiscard]] const std::string& name() const { return name_; }
  /// True for a folder of scan files (a recording is anything else).
  [[nodiscard]] bool folder() const { return sequence_ != nullptr; }
  /// The odometry estimates the poses and compensates the motion with its own velocity (when
  /// `odometry_deskew`): next() then gives the scans as read.
  void use_odometry(bool odometry_deskew);

  /// The next scan (motion-compensated when the sensor's motion is known) and the pose to process
  /// it with; false at the end. Throws core::InputError for a scan that cannot be read (under
  /// kStop) or whose stamp the poses do not cover.
  bool next(std::size_t& index, core::OrganizedScan& scan, core::Pose& pose);

  /// Scans taken from the input so far, skipped ones included.
  [[nodiscard]] std::uint64_t read() const { return reader_.read(); }
  /// Scans skipped so far because they could not be read (kSkip).
  [[nodiscard]] std::uint64_t unreadable() const { return reader_.skipped(); }
  /// The sensor's height above the ground that a sequence folder states (simulated ones do).
  [[nodiscard]] std::optional<double> stated_sensor_height() const;
  /// The sensor that took the scans (for recordings known once the first scan was read).
  [[nodiscard]] const core::SensorModel& sensor_model() const { return source_->model(); }
  /// Number of scans when known in advance (0 for recordings and streams).
  [[nodiscard]] std::size_t size() const { return source_->size(); }
  /// What the source survived (e.g. a bag cut off), "" when nothing.
  [[nodiscard]] std::string warning() const { return source_->warning(); }
  /// What the source counted (packets, drops, ...); for folders only what organizing clouds
  /// did (the number of scans is said elsewhere).
  [[nodiscard]] std::string summary() const;
  /// Where the poses came from, for the summary; `odometry_mode` is the run's --odometry.
  [[nodiscard]] std::string pose_summary(const std::string& odometry_mode) const;
  /// Whether and how the scans were motion-compensated, for the summary.
  [[nodiscard]] std::string deskew_summary() const;
  /// The source.
  [[nodiscard]] const io::ScanSource& source() const { return *source_; }

 private:
  void plan_sequence_deskew(const RunInputOptions& options);
  void plan_recording_deskew(const RunInputOptions& options);
  void deskew_sequence_scan(std::size_t index, core::OrganizedScan& scan, core::Pose& pose);
  core::Pose recording_pose(std::size_t index, core::OrganizedScan& scan);
  [[nodiscard]] std::optional<std::size_t> deskew_pair(std::size_t i) const;

  std::string name_;
  std::unique_ptr<io::ScanSource> source_;
  io::ScanReader reader_;
  const io::SequenceReader* sequence_{nullptr};  // the folder behind source_, if it is one
  std::string poses_;                            // the poses file given, if any
  bool odometry_{false};                         // poses come from the odometry, not the input
  io::Trajectory trajectory_;                    // the poses file of a recording
  bool deskew_{false};                           // compensate scans that have per-column times
  std::string deskew_method_;                    // where the motion comes from (deskew_)
  std::string deskew_off_;                       // why not (!deskew_)
  std::size_t scans_{0}, deskewed_{0};
  std::size_t no_motion_{0};  // sequence scans without a forward-moving pose pair
};

}  // namespace ringtrack::runner
