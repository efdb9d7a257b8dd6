#pragma once
/// Multi-object tracker (paper III.D): one constant-velocity Kalman filter and box per object,
/// Hungarian assignment on a gated cost, hypothesis lifecycle and static/dynamic classification.

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <vector>

#include "ringtrack/core/box3.hpp"
#include "ringtrack/core/config.hpp"
#include "ringtrack/core/detection.hpp"
#include "ringtrack/core/visibility.hpp"
#include "ringtrack/tracking/association_cost.hpp"
#include "ringtrack/tracking/kalman.hpp"

namespace ringtrack::tracking {

/// What a hypothesis keeps of the last detection assigned to it.
struct DetectionSummary {
  Eigen::Vector3f centroid{Eigen::Vector3f::Zero()};         ///< world frame
  Eigen::Vector3f object_centroid{Eigen::Vector3f::Zero()};  ///< with the completion (world)
  Eigen::Matrix3f covariance{Eigen::Matrix3f::Identity()};   ///< as the detector gave it
  core::Box3 box;                                            ///< world frame
  std::size_t points{0};                                     ///< number of grid cells
  bool relaxed{false};                                       ///< from the relaxed object model
  std::int64_t stamp_ns{0};                                  ///< scan it came from
};

/// One tracked object.
struct Hypothesis {
  std::uint64_t id{0};  ///< from 1, unique among the live hypotheses; a lost hypothesis' id
                        ///< continues in the one that took it over (tracking.relink_distance_m)
  std::int64_t created_ns{0};                               ///< stamp of its first detection
  Eigen::Vector3d first_position{Eigen::Vector3d::Zero()};  ///< its first detection's centroid
  ConstantVelocityKalman filter;  ///< world-frame position and velocity with covariance
  Eigen::Vector3d velocity_mps{Eigen::Vector3d::Zero()};  ///< reported: 0 up to min speed, capped
  core::Box3 box;          ///< current box: the assigned detection's, else the last one moved
                           ///< along the prediction
  core::Box3 initial_box;  ///< box of the detection that created the hypothesis
  core::Box3 anchor_box;   ///< box the static/dynamic test compares with (initial, or where a
                           ///< dynamic hypothesis came to rest)
  Eigen::Vector3d anchor_position{Eigen::Vector3d::Zero()};  ///< position when anchored
  bool dynamic{false};       ///< moving away from its anchor (see docs/tracking.md)
  bool ever_dynamic{false};  ///< has been dynamic at least once
  int age_scans{0};          ///< scans since creation, 1 in the creating scan
  int missed_scans{0};       ///< consecutive scans without an assigned detection
  int rest_scans{0};         ///< consecutive scans with reported speed zero
  int moved_scans{0};        ///< consecutive measured scans the dynamic test held in
  int hits{0};               ///< scans with an assigned detection, the creating one included
  int held_scans{0};         ///< consecutive measured scans held at the last full view
  bool fell_behind{false};   ///< last scan's detection lay outside the gate behind the
                             ///< prediction (paired by distance alone): it may be stopping
  bool confirmed{false};     ///< had confirm_hits detections: no longer a possible one-scan blip
  bool reported{false};      ///< confirmed and recently measured (or hidden): what outputs list
  int person_scans{0};       ///< scans with a strict (person-shaped, not relaxed) detection
  bool person{false};        ///< confirmed and person-shaped in person_min_scans scans; stays set
                             ///< (moving or not, see docs/tracking.md "Standing people")
  /// Measured centroid (world) in the first scan of the current moved_scans streak.
  Eigen::Vector3d streak_start{Eigen::Vector3d::Zero()};
  std::vector<Eigen::Vector3f> anchor_points;  ///< sample of the anchor detection's world points
  std::vector<Eigen::Vector3f> last_points;    ///< sample of the last detection's world points
  Eigen::Vector3d anchor_viewpoint{Eigen::Vector3d::Zero()};  ///< sensor position when anchored
  bool occluded{false};       ///< missed, and the scan saw something in front of its prediction
  int seen_through_scans{0};  ///< consecutive missed scans that saw through its predicted points
  bool unseen{false};         ///< missed, and no beam ended at its predicted points, none hid them
  std::size_t points{0};      ///< points of the assigned detection this scan, 0 when missed
  int detection{-1};          ///< index of the detection assigned this scan, -1 when none
  DetectionSummary last_detection;  ///< the most recent assigned detection

  Eigen::Vector3d reported_position{
      Eigen::Vector3d::Zero()};  ///< what outputs list (world, m):
                                 ///< tracking.reported_position, set by every update

  /// Position estimate of the filter (world, m): association, prediction, deletion use it.
  [[nodiscard]] Eigen::Vector3d position() const { return filter.position(); }
  /// Covariance of the position estimate (m^2).
  [[nodiscard]] Eigen::Matrix3d position_covariance() const { return filter.position_covariance(); }
};

/// Counters of the last update, for logs and tests.
struct TrackerStats {
  int assigned{0};              ///< detections paired with hypotheses
  int created{0};               ///< new hypotheses
  int deleted_uncertain{0};     ///< deleted for a too large position covariance
  int deleted_merged{0};        ///< younger hypotheses deleted near older ones
  int deleted_seen_through{0};  ///< missed hypotheses whose predicted points the scan saw through
  int relaxed_unassigned{0};    ///< relaxed detections that paired with nothing (no new track)
  int relinked{0};              ///< confirmed hypotheses that took over a lost one's id
  int paired_at_rest{0};  ///< coasting hypotheses paired at rest where last measured (rest_pairing)
  int held_partly_hidden{0};  ///< hypotheses at rest held where their full view put them
                              ///< (hold_partly_hidden)
};

/// Tracks objects from the detections of successive scans.
class Tracker {
 public:
  /// Checks nothing: the config comes validated from core::validate_config.
  explicit Tracker(const core::TrackingConfig& config);

  /// Predicts every hypothesis to stamp_ns, assigns the detections (world frame), corrects,
  /// creates, deletes and classifies hypotheses. Stamps must not decrease (throws
  /// core::InputError); the first call or an equal stamp predicts nothing. Throws
  /// core::InputError for a detection with a non-finite centroid or covariance.
  /// `visibility` is the query of the scan the detections come from (their indices are its
  /// cells); with it the free-space rules apply (dynamic test, occluded coasting, deletion of
  /// hypotheses seen through), without it the box test decides and hypotheses coast blindly.
  const std::vector<Hypothesis>& update(const std::vector<core::Detection>& detections,
                                        std::int64_t stamp_ns,
                                        const core::VisibilityQuery* visibility = nullptr);

  /// Current hypotheses, oldest first; Hypothesis::detection indexes the last update's input.
  [[nodiscard]] const std::vector<Hypothesis>& hypotheses() const { return hypotheses_; }
  /// Positions of every hypothesis predicted to stamp_ns (world frame), e.g. for the
  /// detector's relaxed object model in the next scan.
  [[nodiscard]] std::vector<Eigen::Vector3f> predicted_positions(std::int64_t stamp_ns) const;
  /// Counters of the last update.
  [[nodiscard]] const TrackerStats& stats() const { return stats_; }
  /// Stamp of the last update (ns); meaningless before the first.
  [[nodiscard]] std::int64_t stamp_ns() const { return stamp_ns_; }
  /// Forgets every hypothesis and the time (ids keep counting).
  void reset();

  /// The cost of pairing a hypothesis with a detection under the configured cost, or +inf
  /// when a cheap lower bound already exceeds the gate.
  [[nodiscard]] double pair_cost(const Hypothesis& hypothesis,
                                 const core::Detection& detection) const;
  /// The gate of the configured cost.
  [[nodiscard]] double gate() const;
  /// Position uncertainty of a detection in the assignment cost (scaled covariance, symmetric,
  /// floored): the object's extent, so that a partial view of it still pairs.
  [[nodiscard]] Eigen::Matrix3d measurement_covariance(const core::Detection& detection) const;
  /// Measurement noise of the Kalman update with a detection: the standard error of its
  /// centroid plus centroid_noise_m per axis (the association covariance when that is 0).
  [[nodiscard]] Eigen::Matrix3d update_covariance(const core::Detection& detection) const;

 private:
  void predict_all(double dt_s);
  void assign(const std::vector<core::Detection>& detections);
  void add_rest_alternatives(const std::vector<core::Detection>& detections);
  [[nodiscard]] bool may_have_stopped(const Hypothesis& h) const;
  void reassociate(const std::vector<core::Detection>& detections);
  // The filter update at `at` and the bookkeeping of a measured scan, shared by correct() and
  // hold_at_full_view().
  void measure(Hypothesis& h, const Eigen::Vector3d& at, const core::Detection& d, int index);
  void correct(Hypothesis& h, const core::Detection& d, int index);
  [[nodiscard]] bool shows_part_at_rest(const Hypothesis& h, const core::Detection& d) const;
  void hold_at_full_view(Hypothesis& h, const core::Detection& d, int index);
  void coast(Hypothesis& h);
  void create(const core::Detection& d, int index);
  void delete_uncertain();
  void delete_merged();
  void classify(Hypothesis& h) const;
  void classify_by_box(Hypothesis& h) const;
  void classify_by_free_space(Hypothesis& h) const;
  /// Counts a measured scan in which the dynamic test held (sets streak_start on the first),
  /// or breaks the streak.
  static void extend_streak(Hypothesis& h, bool held);
  void remember_points(Hypothesis& h, const core::Detection& d) const;
  void look_for_missed(Hypothesis& h) const;
  void report_velocity(Hypothesis& h) const;
  void decide_report(Hypothesis& h) const;
  void set_reported_position(Hypothesis& h) const;
  void update_person_flag(Hypothesis& h) const;
  /// relink(): the lost hypothesis a newly confirmed one takes over, by index into
  /// hypotheses_ (live) or lost_ (deleted); both -1 when none is near enough.
  struct RelinkCandidate {
    double distance{std::numeric_limits<double>::infinity()};
    int live{-1};
    int lost{-1};
  };
  void relink(const std::vector<std::size_t>& newly_confirmed);
  [[nodiscard]] RelinkCandidate nearest_lost(const Hypothesis& young,
                                             const std::vector<char>& taken) const;
  [[nodiscard]] double relink_distance(const Hypothesis& lost, const Hypothesis& young) const;
  void take_over(Hypothesis& young, const Hypothesis& old);
  void forget_lost();

  core::TrackingConfig config_;
  double min_speed_mps_;
  double max_speed_mps_;
  std::vector<Hypothesis> hypotheses_;
  std::vector<Hypothesis> lost_;  // deleted lately, confirmed and had moved: ids may continue
  std::vector<std::size_t> newly_confirmed_;    // update(): hypotheses confirmed in this scan
  std::vector<Eigen::Matrix3d> measurement_r_;  // association noise per detection of the update
  std::vector<Eigen::Matrix3d> update_r_;       // Kalman update noise per detection
  std::vector<GaussianTerm> h_terms_, d_terms_;
  std::vector<int> col_of_row_;
  std::vector<char> rest_cheaper_;    // hypotheses x detections: pairing at rest cost less; empty
                                      // when no hypothesis may have stopped
  std::vector<char> paired_at_rest_;  // per hypothesis: paired at rest where last measured
  std::vector<char> detection_used_;  // per detection: paired with a hypothesis this update
  struct LeftoverPair {               // reassociate(): a candidate pair and its distance
    double distance;
    std::size_t row, col;
  };
  std::vector<LeftoverPair> leftover_pairs_;
  Eigen::MatrixXd cost_;
  std::uint64_t next_id_{1};
  std::int64_t stamp_ns_{0};
  bool started_{false};
  const core::VisibilityQuery* visibility_{nullptr};  // of the scan being updated, may be null
  TrackerStats stats_;
};

/// Scans a hypothesis created from one detection with covariance r_create survives without
/// further detections at scan period dt_s when it had `updates` more detections one period
/// apart, each with update noise r_update, by running the filter alone: the number of
/// predictions after the last update until the largest position-covariance eigenvalue exceeds
/// delete_eigenvalue_m2 (the deletion scan counts).
int missed_scans_until_deletion(const core::TrackingConfig& config, const Eigen::Matrix3d& r_create,
                                const Eigen::Matrix3d& r_update, double dt_s, int updates);

}  // namespace ringtrack::tracking
