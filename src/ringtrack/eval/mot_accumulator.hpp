#pragma once
/// CLEAR MOT, MT/PT/ML and identity (IDF1) metrics from per-frame distance matrices.
/// Semantics follow py-motmetrics (see docs/evaluation.md for every rule and tie-break).

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <span>
#include <unordered_map>
#include <utility>
#include <vector>

namespace ringtrack::eval {

/// How a distance is compared with the threshold to decide whether a pair may match.
enum class ThresholdRule {
  kBelow,   ///< distance < threshold (CLEAR MOT with Euclidean distance, the paper's "below")
  kAtMost,  ///< distance <= threshold (1 - IoU <= 0.5, i.e. IoU >= 0.5, as MOTChallenge)
};

/// Options of a MotAccumulator.
struct MotOptions {
  /// Largest distance that may match; NaN and infinite distances never match.
  double threshold = std::numeric_limits<double>::infinity();
  /// Strict or inclusive comparison with threshold.
  ThresholdRule rule = ThresholdRule::kBelow;
  /// Keep a per-frame event log (events()); off by default to save memory on long sequences.
  bool record_events = false;
};

/// Kind of a per-frame event, as py-motmetrics' event types, plus kIgnored: a hypothesis matched
/// to a don't-care object (neither a true nor a false positive).
enum class MotEventType { kMatch, kSwitch, kMiss, kFalsePositive, kIgnored };

/// One event of the log: a match, switch or ignored pair has both ids, a miss only the object, an
/// FP only the hypothesis; absent ids are -1 and the distance of a miss or FP is NaN.
struct MotEvent {
  std::int64_t frame = 0;
  MotEventType type = MotEventType::kMatch;
  std::int64_t object_id = -1;
  std::int64_t hypothesis_id = -1;
  double distance = 0.0;
};

/// Summable counts of a sequence (or of several): ratios are computed from the sums, never
/// averaged.
struct MotSummary {
  std::int64_t frames = 0;        ///< frames given to update()
  std::int64_t gt_presences = 0;  ///< object presences summed over frames (MOTA denominator)
  std::int64_t hypothesis_presences = 0;  ///< hypothesis presences summed over frames
  std::int64_t matches = 0;   ///< correspondences that are not ID switches (py-motmetrics)
  std::int64_t switches = 0;  ///< correspondences to a different hypothesis than the last one
  std::int64_t false_positives = 0;  ///< unmatched hypothesis presences
  std::int64_t misses = 0;           ///< unmatched object presences (FN)
  std::int64_t fragmentations = 0;   ///< tracked -> missed transitions later tracked again
  double distance_sum = 0.0;         ///< sum of distances over matches and switches
  /// Correspondences whose offsets were added below (3-D protocol: all of them; boxes: none).
  std::int64_t offset_pairs = 0;
  double horizontal_distance_sum = 0.0;  ///< sum of x-y distances over those correspondences
  double vertical_error_sum = 0.0;       ///< sum of signed z errors (hypothesis - object)
  std::int64_t gt_objects = 0;           ///< distinct object ids
  std::int64_t hypotheses = 0;           ///< distinct hypothesis ids
  std::int64_t mostly_tracked = 0;       ///< objects tracked in >= 80 % of their frames
  std::int64_t partially_tracked = 0;    ///< objects tracked in >= 20 % and < 80 %
  std::int64_t mostly_lost = 0;          ///< objects tracked in < 20 % of their frames
  std::int64_t id_true_positives = 0;    ///< IDTP of the global id assignment
  std::int64_t id_false_positives = 0;   ///< IDFP
  std::int64_t id_false_negatives = 0;   ///< IDFN

  /// Matches plus switches: every frame-level correspondence (CLEAR MOT's c_t summed).
  [[nodiscard]] std::int64_t true_positives() const { return matches + switches; }
  /// 1 - (misses + FP + switches) / gt_presences; NaN without objects.
  [[nodiscard]] double mota() const;
  /// distance_sum / true_positives; NaN without correspondences.
  [[nodiscard]] double motp() const;
  /// horizontal_distance_sum / offset_pairs: MOTP in the x-y plane; NaN without offsets.
  [[nodiscard]] double horizontal_motp() const;
  /// vertical_error_sum / offset_pairs: mean signed height error; NaN without offsets.
  [[nodiscard]] double mean_vertical_error() const;
  /// true_positives / gt_presences; NaN without objects.
  [[nodiscard]] double recall() const;
  /// true_positives / hypothesis_presences; NaN without hypotheses.
  [[nodiscard]] double precision() const;
  /// mostly_tracked / gt_objects; NaN without objects.
  [[nodiscard]] double mostly_tracked_ratio() const;
  /// partially_tracked / gt_objects; NaN without objects.
  [[nodiscard]] double partially_tracked_ratio() const;
  /// mostly_lost / gt_objects; NaN without objects.
  [[nodiscard]] double mostly_lost_ratio() const;
  /// 2 IDTP / (2 IDTP + IDFP + IDFN); NaN when all three are zero.
  [[nodiscard]] double idf1() const;
  /// IDTP / (IDTP + IDFP); NaN when zero.
  [[nodiscard]] double idp() const;
  /// IDTP / (IDTP + IDFN); NaN when zero.
  [[nodiscard]] double idr() const;
  /// Adds another sequence's counts (objects of different sequences are different objects).
  MotSummary& operator+=(const MotSummary& other);
};

/// A correspondence of one frame: indices into that frame's object and hypothesis ids.
struct MotPair {
  Eigen::Index object = 0;
  Eigen::Index hypothesis = 0;
};

/// Accumulates CLEAR MOT events frame by frame from object ids, hypothesis ids and distances.
class MotAccumulator {
 public:
  /// Throws std::invalid_argument for a NaN or negative threshold.
  explicit MotAccumulator(MotOptions options = {});

  /// Adds one frame. distances is objects x hypotheses (rows in object_ids order, columns in
  /// hypothesis_ids order); NaN/inf or beyond the threshold = not pairable. dont_care is empty
  /// or has one flag per object: a flagged object takes part in the matching like any other,
  /// but is not counted (no presence, miss or match) and the hypothesis matched to it is
  /// ignored (neither TP nor FP, no presence), as MOTChallenge's distractors. Returns the
  /// frame's counted correspondences (matches and switches). Throws core::InputError for
  /// duplicate ids, a shape mismatch or a negative distance.
  std::vector<MotPair> update(std::span<const std::int64_t> object_ids,
                              std::span<const std::int64_t> hypothesis_ids,
                              const Eigen::MatrixXd& distances,
                              std::span<const std::uint8_t> dont_care = {});

  /// True when the distance may form a match under the options' threshold rule.
  [[nodiscard]] bool pairable(double distance) const;
  /// The counts so far, with MT/PT/ML and the global id assignment computed now.
  [[nodiscard]] MotSummary summary() const;
  /// The event log (empty unless MotOptions::record_events).
  [[nodiscard]] const std::vector<MotEvent>& events() const { return events_; }

 private:
  struct ObjectState {
    std::optional<std::int64_t> last_hypothesis;  // hypothesis of the latest match, any frame
    std::int64_t last_match_frame = -1;
    std::int64_t frames_present = 0;  // counted frames only (not don't-care)
    std::int64_t frames_tracked = 0;
    bool tracked_before = false;      // matched at least once
    bool missed_since_match = false;  // a miss after the latest match (pending fragmentation)
  };
  struct PairHash {
    std::size_t operator()(const std::pair<std::int64_t, std::int64_t>& p) const {
      return std::hash<std::int64_t>{}(p.first) * 0x9E3779B97F4A7C15ULL ^
             std::hash<std::int64_t>{}(p.second);
    }
  };

  void record(MotEventType type, std::int64_t object_id, std::int64_t hypothesis_id,
              double distance);
  // For each hypothesis column, the object row that keeps it (the object was last matched to it
  // and the pair is still usable; several: the most recent match), or kUnassigned.
  [[nodiscard]] std::vector<Eigen::Index> keepers(std::span<const std::int64_t> hypothesis_ids,
                                                  const std::vector<ObjectState*>& state,
                                                  const Eigen::MatrixXd& usable) const;
  // Throws core::InputError for a frame whose sizes disagree, whose ids repeat or whose
  // distances are negative.
  void check_frame(std::span<const std::int64_t> object_ids,
                   std::span<const std::int64_t> hypothesis_ids, const Eigen::MatrixXd& distances,
                   std::span<const std::uint8_t> dont_care) const;
  // Misses, per-object tracking history, false positives and the id metrics' overlaps of the
  // frame being updated, after its matching (row_match: the column of each object's match;
  // col_taken / col_ignored: columns matched / matched to a don't-care object).
  void count_unmatched(std::span<const std::int64_t> object_ids,
                       std::span<const std::int64_t> hypothesis_ids, const Eigen::MatrixXd& usable,
                       std::span<const std::uint8_t> dont_care,
                       const std::vector<Eigen::Index>& row_match,
                       const std::vector<char>& col_taken, const std::vector<char>& col_ignored);

  MotOptions options_;
  MotSummary counts_;  // frame-level counts; per-object and id metrics are derived in summary()
  std::unordered_map<std::int64_t, ObjectState> objects_;
  std::unordered_map<std::int64_t, std::int64_t> hypothesis_frames_;
  // Frames in which (object, hypothesis) were both present and pairable, for IDF1.
  std::unordered_map<std::pair<std::int64_t, std::int64_t>, std::int64_t, PairHash> overlap_;
  std::vector<MotEvent> events_;
};

}  // namespace ringtrack::eval
