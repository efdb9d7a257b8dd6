#pragma once
/// Dynamic-object filter (paper III.E): removes the points of dynamic objects from every scan,
/// retroactively from a log of recent scans, and feeds the delayed, filtered scans into a
/// voxel map of the static world.

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <unordered_map>
#include <vector>

#include "ringtrack/core/box3.hpp"
#include "ringtrack/core/config.hpp"
#include "ringtrack/core/detection.hpp"
#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"
#include "ringtrack/core/visibility.hpp"
#include "ringtrack/mapping/static_map.hpp"
#include "ringtrack/mapping/transient_grid.hpp"
#include "ringtrack/tracking/tracker.hpp"

namespace ringtrack::mapping {

/// One filtered scan: its valid points in the world frame and which of them were removed.
struct LoggedScan {
  std::uint64_t sequence{0};  ///< 0 for the first scan processed, then +1 per scan
  std::int64_t stamp_ns{0};
  core::Pose pose;  ///< sensor in world for this scan
  int rings{0};     ///< grid size of the source scan
  int columns{0};
  std::vector<std::uint32_t> cells;     ///< grid cell (ring * columns + column) of each point
  std::vector<Eigen::Vector3f> points;  ///< world frame
  std::vector<float> intensities;
  std::vector<std::uint8_t> removed;  ///< 1 = removed as part of a dynamic object
  std::size_t removed_count{0};
  /// Points the free-space line tests against later scans (segmented or near a hypothesis).
  std::vector<std::uint32_t> candidates;
  std::vector<float> candidate_ranges;  ///< each candidate's measured range (m)
  /// Points the transient line judges when the scan leaves the log (segmented, above the ground).
  std::vector<std::uint32_t> transient_candidates;
  std::vector<std::uint64_t> transient_keys;  ///< their TransientGrid cells
  /// Bounds of the finite points [kBlockPoints * b, kBlockPoints * (b + 1)): consecutive points
  /// lie along a ring, so a box meets few blocks (empty when not computed).
  std::vector<core::Box3> block_bounds;
  std::size_t bounded_points{0};  ///< points.size() when block_bounds was computed

  /// Points per entry of block_bounds.
  static constexpr std::size_t kBlockPoints = 64;
  /// Recomputes block_bounds from points (call it after changing points).
  void update_bounds();
  /// Marks the points inside box removed; returns how many were newly removed, and appends
  /// their cells to removed_cells when given. Skips blocks whose bounds miss the box when the
  /// bounds were computed for as many points as there are now, else tests every point.
  /// `keep`, when given, spares the points it returns true for.
  std::size_t remove_inside(const core::Box3& box,
                            std::vector<std::uint32_t>* removed_cells = nullptr,
                            const std::function<bool(const Eigen::Vector3f&)>& keep = {});
  /// Lowest height of the points inside box; +infinity when none is. Skips blocks as
  /// remove_inside does.
  [[nodiscard]] float lowest_in(const core::Box3& box) const;
  /// Whether block_bounds were computed for the points there are now.
  [[nodiscard]] bool bounds_current() const;
};

/// What the filter did in one call.
struct FilterResult {
  std::uint64_t sequence{0};                 ///< of the scan just processed
  std::vector<std::uint32_t> removed_cells;  ///< its cells removed (dynamic objects)
  std::size_t retroactive_points{0};         ///< points removed from earlier scans still in the log
  /// Points of this scan removed for lying in a dynamic object's grown box, not in its cells.
  std::size_t object_box_points{0};
  std::size_t map_voxels_removed{
      0};                       ///< voxels removed from the map (decisions too late for the log)
  std::size_t scans_to_map{0};  ///< scans that left the log into the map
  /// Points of logged scans removed because this scan saw through them (free-space line).
  std::size_t free_space_points{0};
  /// Points this scan saw through that stayed: their voxel is structure seen many times.
  std::size_t free_space_protected{0};
  /// Points of the scan that left the log removed as transient (transient line).
  std::size_t transient_points{0};
  /// Voxels that left the map for lying beyond mapping.map_radius_m of the sensor (evicted()).
  std::size_t map_voxels_evicted{0};
};

/// What the scan itself says, for the free-space line: both may be absent (then only the
/// tracks remove points).
struct ScanEvidence {
  const core::VisibilityQuery* visibility{nullptr};    ///< the scan seen from its pose
  const std::vector<std::uint8_t>* segments{nullptr};  ///< per cell, non-zero = segmented
};

/// Keeps the log and the map; call process() once per scan after Tracker::update().
class DynamicObjectFilter {
 public:
  /// Checks nothing: the config comes validated from core::validate_config.
  explicit DynamicObjectFilter(const core::MappingConfig& config);

  /// Filters one scan. detections and hypotheses are the tracker's input and output for this
  /// scan (world frame; Hypothesis::detection indexes detections). With evidence (the scan's
  /// visibility query and segment labels) the free-space line runs too (mapping.free_space).
  /// Throws core::InputError when a hypothesis names a detection that does not exist or the
  /// segment labels do not match the scan.
  const FilterResult& process(const core::OrganizedScan& scan, const core::Pose& pose,
                              const std::vector<core::Detection>& detections,
                              const std::vector<tracking::Hypothesis>& hypotheses,
                              const ScanEvidence& evidence = {});
  /// The ground's height in the world frame, which the transient line needs (until it is set
  /// the line is off): points less than mapping.transient_min_height_m above it are never
  /// transient.
  void set_ground_z(double z_m) { ground_z_m_ = z_m; }
  /// Moves every logged scan into the map (end of a run).
  const FilterResult& flush();

  /// The static map.
  [[nodiscard]] const StaticMap& map() const { return map_; }
  /// Scans still waiting, oldest first (at most log_delay_scans).
  [[nodiscard]] const std::deque<LoggedScan>& log() const { return log_; }
  /// Scans that left the log in the last process() or flush() call, e.g. to write them out.
  [[nodiscard]] const std::vector<LoggedScan>& released() const { return released_; }
  /// With mapping.map_radius_m, a sweep checks every map voxel in at most this many scans, so
  /// each voxel is checked at least once in any 2 x kSweepScans consecutive scans.
  static constexpr std::size_t kSweepScans = 10;
  /// ... and each scan checks at least this many (a small map is swept in one scan).
  static constexpr std::size_t kMinSweepVisits = 4096;
  /// The transient line remembers where points were segmented for at least this many scans
  /// (a minute at 10 Hz): what stood there that long ago still confirms a point.
  static constexpr std::uint64_t kTransientMemoryScans = 600;

  /// Map voxels that left memory in the last process() call for lying farther than
  /// mapping.map_radius_m from the sensor, e.g. to write them out; final (no later removal
  /// reaches them). Whoever does not take them before the next call drops them.
  [[nodiscard]] const std::vector<MapPoint>& evicted() const { return evicted_; }
  /// Hypotheses the filter currently keeps history for.
  [[nodiscard]] std::size_t tracked_objects() const { return objects_.size(); }

 private:
  struct BoxAt {
    std::uint64_t sequence;
    core::Box3 box;
  };
  // History of one hypothesis, bounded by the log window (older static boxes are folded into
  // one union) and by the tracker's coasting limit (gap boxes).
  struct ObjectHistory {
    bool removing{false};            // turned removable (mapping.remove): its points leave
    std::deque<BoxAt> static_boxes;  // boxes while static, for scans still in the log
    core::Box3 expired_static;       // union of static boxes whose scans are in the map
    std::vector<BoxAt> gap;          // predicted boxes while a dynamic hypothesis is missed
    bool seen{false};                // last_seen is valid
    BoxAt last_seen{0, {}};          // last box with an assigned detection
    std::uint64_t touched{0};        // sequence of the last scan it appeared in
  };

  void remove_box(std::uint64_t sequence, const core::Box3& box);
  // Appends the scan's valid points (world frame) to the log as scan `sequence`, reusing the
  // buffers of a released scan; fills point_of_cell_.
  LoggedScan& log_scan(const core::OrganizedScan& scan, const core::Pose& pose,
                       std::uint64_t sequence);
  // One hypothesis of the scan just logged: remembers a static one's box; removes a removable
  // one's points (its cells, its grown box, its static era, the gaps it coasted through).
  void update_object(const tracking::Hypothesis& h, const std::vector<core::Detection>& detections,
                     LoggedScan& current, std::uint64_t sequence);
  // A recovered object's points in the scans it was missed in: the predicted boxes, and the
  // straight way from where it was last seen to box.
  void remove_gap(ObjectHistory& object, const core::Box3& box, std::uint64_t sequence);
  // Whether the hypothesis' points leave the scans (mapping.remove).
  [[nodiscard]] bool removable(const tracking::Hypothesis& h) const;
  // Removes the points inside a measured dynamic box grown by object_margin_m sideways and up,
  // and by reach_ground down to the ground and up to a body's height.
  void remove_object_box(LoggedScan& scan, const core::Box3& box);
  // Removes the points between grown and grown widened to object_outer_margin_m whose map
  // voxels are not established structure (free_space_protect_count).
  void remove_outer_ring(LoggedScan& scan, const core::Box3& grown);
  // Grows a box down to object_ground_clearance_m above the ground around it and up to
  // object_min_height_m above that ground (both optional: 0 = unchanged; unchanged too when no
  // point is lower). Measured boxes and, in scans still in the log, static-era and gap boxes.
  void reach_ground(const LoggedScan& scan, core::Box3& grown) const;
  [[nodiscard]] core::Box3 inflate(const core::Box3& box) const;
  void release_front();
  // Moves map voxels farther than mapping.map_radius_m from the sensor at pose to evicted_, a
  // slice of the map per scan (kSweepScans).
  void bound_map(const core::Pose& pose);
  // The candidates of the scan just logged: segmented points and points near a hypothesis.
  void mark_candidates(LoggedScan& logged, const core::OrganizedScan& scan,
                       const std::vector<std::uint8_t>* segments,
                       const std::vector<tracking::Hypothesis>& hypotheses);
  // Notes the segmented points of the scan just logged that stand above the ground in the
  // transient grid and keeps them as the scan's transient candidates.
  void note_transient_candidates(LoggedScan& logged, const std::vector<std::uint8_t>& segments);
  // Removes the transient candidates of a scan about to leave the log that no scan
  // transient_scans or more away from it saw again (transient line).
  void remove_transient(LoggedScan& scan);
  // Removes the candidates of a logged scan that the newest scan (seen through the visibility
  // query, taken at pose) sees through; from another viewpoint only when moved_too.
  void clear_seen_through(LoggedScan& logged, const core::VisibilityQuery& visibility,
                          const core::Pose& pose, bool moved_too);

  core::MappingConfig config_;
  StaticMap map_;
  SettledCells settled_;
  std::deque<LoggedScan> log_;
  std::vector<LoggedScan> released_;
  std::vector<MapPoint> evicted_;
  std::size_t sweep_cursor_{0};  // bound_map's sweep: voxels below this are still to check
  std::vector<std::int32_t> point_of_cell_;
  std::vector<core::Box3> near_boxes_;         // free-space candidates: around these boxes
  std::vector<const core::Box3*> near_block_;  // ... those that meet the block at hand
  std::unordered_map<std::uint64_t, ObjectHistory> objects_;
  TransientGrid transient_grid_;
  std::vector<std::uint32_t> transient_out_;  // remove_transient's unconfirmed candidates
  std::optional<double> ground_z_m_;          // the transient line's ground (set_ground_z)
  std::uint64_t next_sequence_{0};
  FilterResult result_;
};

}  // namespace ringtrack::mapping
