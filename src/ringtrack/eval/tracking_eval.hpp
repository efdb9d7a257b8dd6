#pragma once
/// Sequence-level drivers: 3-D ground-truth objects vs tracks (the paper's protocol) and
/// MOTChallenge-style 2-D boxes (IoU), both feeding a MotAccumulator frame by frame.

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "ringtrack/eval/mot_accumulator.hpp"

namespace ringtrack::eval {

/// One ground-truth object in one scan (a row of objects.csv).
struct GroundTruthObject {
  std::int64_t scan = 0;
  std::int64_t id = 0;
  std::string class_name;
  std::int64_t points = 0;       ///< LiDAR returns that hit the object in this scan
  Eigen::Vector3d centroid_m{};  ///< centroid of those hit points, world frame
  /// True centre of the object's body when known (NaN: unknown, the centroid stands in); only
  /// used to decide whether the object moves (moving_objects()).
  Eigen::Vector3d true_center_m{
      Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN())};
};

/// One hypothesis in one scan (a row of tracks.csv).
struct TrackObservation {
  std::int64_t scan = 0;
  std::int64_t id = 0;
  Eigen::Vector3d position_m{};  ///< world frame
  bool dynamic = false;          ///< classified dynamic in this scan
  bool ever_dynamic = false;     ///< classified dynamic in this or an earlier scan
  bool person = false;           ///< flagged person (person-shaped, confirmed) in this scan
};

/// Which hypotheses the 3-D evaluation scores; a selected track id counts in all its scans.
enum class HypothesisSelection {
  kEverDynamic,  ///< paper mode: ids flagged dynamic or ever_dynamic in at least one scan
  kPerson,       ///< ids flagged person in at least one scan, whether they moved or not
  kAll,          ///< every id
};

/// Options of the 3-D evaluation.
struct TrackingEvalOptions {
  /// A pair matches when its Euclidean distance is strictly below this (paper: 0.5 m).
  double threshold_m = 0.5;
  /// Only ground-truth objects of this class are evaluated (exact, case-sensitive).
  std::string target_class = "person";
  /// Only ground-truth objects with at least this many hit points in a scan count in that scan.
  std::int64_t min_points = 1;
  /// Which hypotheses are evaluated (default: the paper's mode).
  HypothesisSelection hypotheses = HypothesisSelection::kEverDynamic;
  /// For the "moving objects only" figures: an object moves when its horizontal position leaves
  /// the disc of this radius around its first position (metres, >= 0).
  double moving_radius_m = 1.0;
};

/// Metrics of one sequence plus what the filters left out.
struct TrackingEvalResult {
  MotSummary summary;
  /// The same tracks against ground truth restricted to objects that move: objects that never
  /// move are don't-care (not counted; a hypothesis matched to one is neither TP nor FP).
  MotSummary moving_only;
  std::int64_t moving_objects = 0;    ///< evaluated object ids that move (counted in moving_only)
  std::int64_t still_objects = 0;     ///< evaluated object ids that never move (don't-care there)
  std::int64_t gt_rows_used = 0;      ///< ground-truth rows that passed class and min_points
  std::int64_t gt_rows_skipped = 0;   ///< rows of another class or with too few points
  std::int64_t hypotheses_total = 0;  ///< distinct track ids in the input
  std::int64_t hypotheses_evaluated = 0;  ///< distinct track ids kept by the selection
};

/// The option's name: "dynamic", "person" or "all".
[[nodiscard]] const char* selection_name(HypothesisSelection selection);
/// Parses "dynamic", "person" or "all"; throws core::InputError naming the value otherwise.
[[nodiscard]] HypothesisSelection parse_selection(const std::string& name);

/// Ids (ascending) of the objects whose horizontal (x-y) position is ever farther than radius_m
/// from their first position. The position of a row is its true centre when finite, else its
/// centroid when it has hit points, else the row is skipped; "first" = the lowest scan with a
/// position. Rows of every class and any number of points count. Throws core::InputError for a
/// negative or non-finite radius.
[[nodiscard]] std::vector<std::int64_t> moving_objects(
    std::span<const GroundTruthObject> ground_truth, double radius_m);

/// Evaluates tracks against ground truth scan by scan (scans in increasing order, ids in
/// increasing order within a scan). Throws core::InputError for duplicate (scan, id) pairs,
/// non-finite positions, min_points < 1 or a bad moving radius. Fills the full figures
/// (summary) and the moving-objects-only figures (moving_only); offsets (horizontal MOTP,
/// vertical error) are hypothesis minus object position.
[[nodiscard]] TrackingEvalResult evaluate_tracks(std::span<const GroundTruthObject> ground_truth,
                                                 std::span<const TrackObservation> tracks,
                                                 const TrackingEvalOptions& options = {});

/// An axis-aligned image box in one frame (a row of a MOTChallenge file).
struct BoxObservation {
  std::int64_t frame = 0;
  std::int64_t id = 0;
  double left = 0.0;  ///< x of the top-left corner, pixels
  double top = 0.0;   ///< y of the top-left corner, pixels
  double width = 0.0;
  double height = 0.0;
};

/// Intersection over union of two boxes on continuous coordinates; 0 when the union is empty.
[[nodiscard]] double box_iou(const BoxObservation& a, const BoxObservation& b);

/// MOTChallenge-style evaluation: distance 1 - IoU, a pair matches when IoU >= min_iou.
/// Throws core::InputError for duplicate (frame, id) pairs or negative/non-finite boxes.
[[nodiscard]] MotSummary evaluate_boxes(std::span<const BoxObservation> ground_truth,
                                        std::span<const BoxObservation> hypotheses,
                                        double min_iou = 0.5);

}  // namespace ringtrack::eval
