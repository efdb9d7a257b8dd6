#pragma once
/// CSV outputs: tracks.csv and timing.csv of `ringtrack run`, objects.csv of a sequence folder.

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ringtrack/core/box3.hpp"
#include "ringtrack/io/output_file.hpp"

namespace ringtrack::io {

/// Header line of tracks.csv (docs/formats.md).
inline constexpr std::string_view kTracksCsvHeader =
    "scan,stamp,id,x,y,z,vx,vy,vz,min_x,min_y,min_z,max_x,max_y,max_z,dynamic,ever_dynamic,age,"
    "points,person";
/// Header line of objects.csv (docs/formats.md).
inline constexpr std::string_view kObjectsCsvHeader =
    "scan,stamp,id,class,points,x,y,z,min_x,min_y,min_z,max_x,max_y,max_z,true_x,true_y,true_z,"
    "moving";

/// One hypothesis in one scan, world frame (the poses', in double): a row of tracks.csv.
struct TrackRow {
  std::uint64_t scan{0};                              ///< scan index, from 0
  std::int64_t stamp_ns{0};                           ///< scan stamp
  std::uint64_t id{0};                                ///< hypothesis id, stable over time
  Eigen::Vector3d position{Eigen::Vector3d::Zero()};  ///< filter position, m
  Eigen::Vector3d velocity{Eigen::Vector3d::Zero()};  ///< filter velocity, m/s
  core::Box3d box;                                    ///< current box, m (empty: nan)
  bool dynamic{false};                                ///< dynamic in this scan
  bool ever_dynamic{false};                           ///< dynamic in this or any earlier scan
  std::uint32_t age{0};                               ///< scans since the hypothesis started
  std::uint32_t points{0};                            ///< points of its detection (0: none)
  bool person{false};  ///< person-shaped and confirmed, moving or not (tracking::Hypothesis)
};

/// Ground truth of one object in one scan, world frame: a row of objects.csv.
struct ObjectRow {
  std::uint64_t scan{0};                                 ///< scan index, from 0
  std::int64_t stamp_ns{0};                              ///< scan stamp
  std::uint32_t id{0};                                   ///< object id = its `label` in the scans
  std::string class_name{"person"};                      ///< person, robot, drone, ...
  std::uint32_t points{0};                               ///< hit points in this scan
  Eigen::Vector3d centroid{Eigen::Vector3d::Zero()};     ///< centroid of the hit points, m
  core::Box3d box;                                       ///< box of the hit points (empty: nan)
  Eigen::Vector3d true_center{Eigen::Vector3d::Zero()};  ///< true body centre, m
  bool moving{false};                                    ///< the object moves at this time
};

/// Time of one pipeline stage.
struct StageTime {
  std::string name;  ///< column name without the _ms suffix: [a-z0-9_]+
  double ms{0.0};
};

/// Stage times of one scan: a row of timing.csv.
struct TimingRow {
  std::uint64_t scan{0};          ///< scan index, from 0
  std::int64_t stamp_ns{0};       ///< scan stamp
  std::vector<StageTime> stages;  ///< same names in the same order on every row
  double total_ms{0.0};           ///< wall time of the whole scan (not necessarily the sum)
};

/// Formats a TrackRow as a CSV line (without the newline).
std::string format_track_row(const TrackRow& row);
/// Formats an ObjectRow as a CSV line (without the newline); throws core::Error when the class
/// name is empty or contains a comma, quote or line break.
std::string format_object_row(const ObjectRow& row);

/// Writes tracks.csv: the header on construction, then rows; failures throw core::Error.
class TracksCsvWriter {
 public:
  /// Creates the file and writes the header.
  explicit TracksCsvWriter(const std::filesystem::path& path);
  /// Appends one row.
  void write(const TrackRow& row);
  /// Appends rows.
  void write(std::span<const TrackRow> rows);
  /// Flushes and closes; the file is complete only when this returns without throwing.
  void close() { file_.close(); }
  /// Closes and deletes the file (a partial table must not look complete).
  void discard() noexcept { file_.discard(); }

 private:
  OutputFile file_;
};

/// Writes objects.csv: the header on construction, then rows; failures throw core::Error.
class ObjectsCsvWriter {
 public:
  /// Creates the file and writes the header.
  explicit ObjectsCsvWriter(const std::filesystem::path& path);
  /// Appends one row.
  void write(const ObjectRow& row);
  /// Appends rows.
  void write(std::span<const ObjectRow> rows);
  /// Flushes and closes; the file is complete only when this returns without throwing.
  void close() { file_.close(); }
  /// Closes and deletes the file (a partial table must not look complete).
  void discard() noexcept { file_.discard(); }

 private:
  OutputFile file_;
};

/// Writes timing.csv: "scan,stamp,<stage>_ms...,total_ms", the header from the first row's stage
/// names; a later row with other names throws core::Error. Failures throw core::Error.
class TimingCsvWriter {
 public:
  /// Creates the file; the header follows with the first row.
  explicit TimingCsvWriter(const std::filesystem::path& path);
  /// Appends one row (and the header before the first).
  void write(const TimingRow& row);
  /// Flushes and closes (writes "scan,stamp,total_ms" when no row came).
  void close();

 private:
  OutputFile file_;
  std::vector<std::string> stages_;
  bool header_written_{false};
};

}  // namespace ringtrack::io
