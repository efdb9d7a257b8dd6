#pragma once
/// Readers for the evaluation tables: objects.csv and tracks.csv (docs/formats.md; the rows are the
/// writers' ObjectRow and TrackRow) and MOTChallenge gt.txt / result files. Errors name the file,
/// the line and what was expected.

#include <cstdint>
#include <filesystem>
#include <istream>
#include <string>
#include <vector>

#include "ringtrack/io/csv_writers.hpp"

namespace ringtrack::io {

/// One row of a MOTChallenge file: frame, id, left, top, width, height, conf, ...
struct MotChallengeRow {
  std::int64_t frame{0};
  std::int64_t id{0};
  double left{0.0};        ///< x of the top-left corner, pixels
  double top{0.0};         ///< y of the top-left corner, pixels
  double width{0.0};       ///< pixels, >= 0
  double height{0.0};      ///< pixels, >= 0
  double confidence{1.0};  ///< 7th column (ground truth: the "consider" flag); 1 when absent
};

/// Reads objects.csv; columns are found by header name (any order, extra columns ignored).
/// Throws core::InputError for a missing file or column, a malformed value, a centroid that is
/// not finite although the object has points, or a duplicate (scan, id).
[[nodiscard]] std::vector<ObjectRow> read_objects_csv(const std::filesystem::path& path);
/// Same from a stream; name is used in error messages.
[[nodiscard]] std::vector<ObjectRow> read_objects_csv(std::istream& in, const std::string& name);

/// Optional columns of tracks.csv: files written before they existed lack them.
struct TracksCsvColumns {
  bool person{false};  ///< the person flag (added in issue 10; absent: every row reads 0)
};

/// Reads tracks.csv; same rules as read_objects_csv (the position must be finite). The person
/// column is optional (older files): without it every row has person = false, and `present`
/// (when given) tells which optional columns the file has.
[[nodiscard]] std::vector<TrackRow> read_tracks_csv(const std::filesystem::path& path,
                                                    TracksCsvColumns* present = nullptr);
/// Same from a stream; name is used in error messages.
[[nodiscard]] std::vector<TrackRow> read_tracks_csv(std::istream& in, const std::string& name,
                                                    TracksCsvColumns* present = nullptr);

/// Reads a MOTChallenge file (no header; comma- or whitespace-separated; >= 6 columns). With
/// ground_truth, rows whose 7th column (the "consider" flag) is 0 are dropped, as MOTChallenge
/// does. Throws core::InputError for malformed rows or a duplicate (frame, id).
[[nodiscard]] std::vector<MotChallengeRow> read_motchallenge(const std::filesystem::path& path,
                                                             bool ground_truth);
/// Same from a stream; name is used in error messages.
[[nodiscard]] std::vector<MotChallengeRow> read_motchallenge(std::istream& in,
                                                             const std::string& name,
                                                             bool ground_truth);

/// Checks that two tables index the same scans: within each, one stamp per scan and stamps
/// non-decreasing with the scan index; across them, the same stamp for every scan both contain.
/// Throws core::InputError naming the files, the scan and both stamps.
void check_scan_stamps(const std::vector<ObjectRow>& objects, const std::string& objects_name,
                       const std::vector<TrackRow>& tracks, const std::string& tracks_name);

}  // namespace ringtrack::io
