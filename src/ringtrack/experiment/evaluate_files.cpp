#include "ringtrack/experiment/evaluate_files.hpp"

#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/mot_tables.hpp"

namespace ringtrack::experiment {

eval::TrackingEvalResult evaluate_track_files(const std::filesystem::path& objects_csv,
                                              const std::filesystem::path& tracks_csv,
                                              const FileEvalOptions& options) {
  const std::vector<io::ObjectRow> objects = io::read_objects_csv(objects_csv);
  io::TracksCsvColumns columns;
  const std::vector<io::TrackRow> tracks = io::read_tracks_csv(tracks_csv, &columns);
  if (options.evaluation.hypotheses == eval::HypothesisSelection::kPerson && !columns.person) {
    throw core::InputError(tracks_csv.string() +
                           ": no 'person' column (written by an older ringtrack); "
                           "--hypotheses person needs it: run the sequence again");
  }
  if (!options.ignore_stamps) {
    io::check_scan_stamps(objects, objects_csv.string(), tracks, tracks_csv.string());
  }
  std::vector<eval::GroundTruthObject> gt;
  gt.reserve(objects.size());
  for (const io::ObjectRow& r : objects) {
    gt.push_back({static_cast<std::int64_t>(r.scan), static_cast<std::int64_t>(r.id), r.class_name,
                  static_cast<std::int64_t>(r.points), r.centroid, r.true_center});
  }
  std::vector<eval::TrackObservation> hyps;
  hyps.reserve(tracks.size());
  for (const io::TrackRow& r : tracks) {
    hyps.push_back({static_cast<std::int64_t>(r.scan), static_cast<std::int64_t>(r.id), r.position,
                    r.dynamic, r.ever_dynamic, r.person});
  }
  return eval::evaluate_tracks(gt, hyps, options.evaluation);
}

}  // namespace ringtrack::experiment
