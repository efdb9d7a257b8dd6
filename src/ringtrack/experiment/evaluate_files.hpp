#pragma once
/// Evaluation of a run from its files: objects.csv (ground truth) against tracks.csv, as
/// `ringtrack eval` and the Python package do it.

#include <filesystem>

#include "ringtrack/eval/tracking_eval.hpp"

namespace ringtrack::experiment {

/// How the files are compared.
struct FileEvalOptions {
  eval::TrackingEvalOptions evaluation;  ///< threshold, class, min points, selection, radius
  bool ignore_stamps{false};             ///< skip the check that both files' scans share stamps
};

/// Reads both tables and evaluates (docs/evaluation.md). Throws core::InputError naming the file
/// and row for malformed tables, mismatched stamps, or person mode on a table without the
/// person column.
eval::TrackingEvalResult evaluate_track_files(const std::filesystem::path& objects_csv,
                                              const std::filesystem::path& tracks_csv,
                                              const FileEvalOptions& options = {});

}  // namespace ringtrack::experiment
