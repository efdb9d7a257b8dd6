#pragma once
/// The whole per-scan pipeline: segmentation, detection, tracking, dynamic-object filter.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ringtrack/core/background_range.hpp"
#include "ringtrack/core/config.hpp"
#include "ringtrack/core/detection.hpp"
#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"
#include "ringtrack/core/recent_views.hpp"
#include "ringtrack/core/visibility.hpp"
#include "ringtrack/detection/completion.hpp"
#include "ringtrack/detection/detector.hpp"
#include "ringtrack/mapping/dynamic_object_filter.hpp"
#include "ringtrack/odometry/odometry.hpp"
#include "ringtrack/segmentation/segmenter.hpp"
#include "ringtrack/tracking/tracker.hpp"

namespace ringtrack::pipeline {

/// The local frame's origin is the first pose's position rounded to this grid (m): a whole number
/// that users can read off the outputs, near zero for worlds near their origin (those run exactly
/// as in the world frame), and a multiple of every usual voxel size (voxels stay world-aligned).
inline constexpr double kOriginGridM = 100.0;
/// Farthest a sensor may go from the local origin (m): float32 positions keep 4 mm there.
inline constexpr double kMaxLocalDistanceM = 50'000.0;

/// Wall time of each stage for one scan, in milliseconds.
struct StageTimes {
  double segmentation_ms{0};
  double detection_ms{0};
  double tracking_ms{0};
  double mapping_ms{0};
  double total_ms{0};     ///< every stage, odometry included
  double odometry_ms{0};  ///< pose estimation and motion compensation (0 when poses are given)
};

/// What one scan produced. The spans point into the pipeline's buffers and stay valid until the
/// next call to process() or finish(). Positions are in the pipeline's local frame: add origin
/// (in double) for the world frame of the poses (Pipeline::origin()).
struct FrameResult {
  std::int64_t stamp_ns{0};
  std::span<const std::uint8_t> segment_labels;      ///< per cell: 1 segment point, 0 not
  std::span<const core::Detection> detections;       ///< local frame
  std::span<const tracking::Hypothesis> hypotheses;  ///< after this scan's update, local frame
  std::span<const std::uint32_t> removed_cells;      ///< cells removed as dynamic from this scan
  std::size_t retroactive_points{0};                 ///< removed from earlier scans in the log
  StageTimes times;
  core::Pose pose;  ///< the sensor pose the scan was processed with (given or estimated), world
  Eigen::Vector3d origin{Eigen::Vector3d::Zero()};  ///< the local frame's origin in the world
  /// The scan was not processed (its stamp is not after the previous scan's: a host clock step,
  /// a corrupt stamp or a repeated scan); the spans are empty and skip_reason says why.
  bool skipped{false};
  std::string
      skip_reason;  ///< e.g. "stamp 1000 ns is 0.000000500 s older than the previous 1500 ns"
};

/// Runs the stages in order on each scan; one instance per sensor stream.
///
/// Frames (docs/inputs.md, "Frames"): poses come in the user's world frame, which may be
/// UTM-scale (GNSS, georeferenced maps) or far above sea level. The stages keep positions in
/// float, so the pipeline works in a local frame, the world shifted by origin(): the first pose's
/// position rounded to kOriginGridM, subtracted from every pose in double before anything
/// becomes float. Detections, hypotheses and the static map are in that frame; writers add the
/// origin back. Heights are relative: detection.max_altitude_m counts from the ground, taken as
/// detection.sensor_height_m below the first scan's sensor.
class Pipeline {
 public:
  /// The model is the sensor's that took the scans: the free-space tests follow its beams.
  Pipeline(const core::Config& config, core::SensorModel model);

  /// Processes one scan taken at `world_pose` (sensor in world). A scan whose stamp is not after
  /// the previous processed one's is skipped, not processed (the tracker's filters cannot run
  /// backwards, and a repeated scan would count as a second observation): the result says so
  /// and why, and skipped_scans() counts it; later scans continue the tracks. Throws
  /// core::InputError for a pose with a non-finite position or farther than the local frame
  /// allows from origin() (kMaxLocalDistanceM, less for voxels under 5 cm).
  const FrameResult& process(const core::OrganizedScan& scan, const core::Pose& world_pose);
  /// Processes a scan of a sensor without a pose source: the odometry (config.odometry) estimates
  /// its pose and motion-compensates the scan in place, leaving out the points of the objects
  /// tracked so far (predicted to this scan), and the scan is then processed with that pose.
  /// odometry_result() tells how reliable the pose is. Do not mix with process() on one pipeline.
  const FrameResult& process_with_odometry(core::OrganizedScan& scan);
  /// Where the odometry's world frame is: the pose of the first scan given to
  /// process_with_odometry() (default: identity, the world is that scan's frame). Call first.
  void set_odometry_start(const core::Pose& first_scan_pose) { odometry_start_ = first_scan_pose; }
  /// The odometry's account of the last scan given to process_with_odometry().
  [[nodiscard]] const odometry::OdometryResult& odometry_result() const { return odometry_result_; }
  /// The odometry (nullptr before the first process_with_odometry()).
  [[nodiscard]] const odometry::Odometry* odometry() const { return odometry_.get(); }
  /// Where the local frame's origin lies in the world frame (zero before the first scan): world =
  /// local + origin. Everything the pipeline keeps (hypotheses, map, filter log) is local.
  [[nodiscard]] const Eigen::Vector3d& origin() const { return origin_; }
  /// Local z of the ground max_altitude_m counts from (first sensor z - sensor_height_m).
  [[nodiscard]] double ground_z() const { return ground_z_; }
  /// The detector's counters of the last processed scan (e.g. clusters above max_altitude_m).
  [[nodiscard]] const detection::DetectorStats& detector_stats() const { return detector_.stats(); }
  /// Scans skipped so far because their stamp was not after the previous scan's.
  [[nodiscard]] std::uint64_t skipped_scans() const { return skipped_scans_; }
  /// The result of the last process() / process_with_odometry() call (what it returned), for
  /// sinks that come after the call (the Python package's MCAP writer).
  [[nodiscard]] const FrameResult& last_result() const { return result_; }
  /// Moves the scans still held back by the dynamic-object filter into the static map.
  void finish();

  /// The static map built so far (complete after finish()).
  [[nodiscard]] const mapping::StaticMap& static_map() const { return filter_.map(); }
  /// The dynamic-object filter (its log and the scans it released in the last call).
  [[nodiscard]] const mapping::DynamicObjectFilter& dynamic_filter() const { return filter_; }
  [[nodiscard]] const core::Config& config() const { return config_; }
  [[nodiscard]] const tracking::Tracker& tracker() const { return tracker_; }
  [[nodiscard]] const core::SensorModel& sensor_model() const { return model_; }
  /// The background range model learned while the sensor rests (empty while it moves).
  [[nodiscard]] const core::BackgroundRangeModel& background() const { return background_; }

 private:
  /// Counts a skipped scan and makes the result say why.
  const FrameResult& skip(const core::OrganizedScan& scan, std::string reason);
  /// Fixes the local frame at the first pose (origin, ground height); the pose in it afterwards.
  /// Throws core::InputError for a pose too far from the origin for float positions.
  core::Pose to_local(const core::Pose& world);
  /// Forgets the background when the sensor left its resting pose; true while it rests there.
  bool track_rest(const core::Pose& pose);
  /// World boxes of the reported tracks predicted to stamp_ns and grown by the exclusion margin.
  void predicted_track_boxes(std::int64_t stamp_ns);

  core::Config config_;
  core::SensorModel model_;
  segmentation::Segmenter segmenter_;
  detection::Detector detector_;
  detection::DetectionCompleter completer_;
  tracking::Tracker tracker_;
  mapping::DynamicObjectFilter filter_;
  core::BackgroundRangeModel background_;
  core::RecentViews recent_views_;  // a moving sensor's memory (background.moving_memory)
  /// The scene memory for this scan's sparse detections (nothing when there is none yet), and
  /// learns this scan into it afterwards (remember()).
  [[nodiscard]] const core::SceneMemory* scene_memory(bool resting) const;
  void remember(const core::OrganizedScan& scan, const core::Pose& pose, const core::Motion& motion,
                bool resting, const std::shared_ptr<const core::BeamGeometry>& geometry);
  // The beam geometry of the visibility queries, rebuilt only when the column azimuths change.
  core::BeamGeometryCache beam_geometry_;
  /// The sensor's motion during this scan, taken as the motion from the previous scan's pose.
  [[nodiscard]] core::Motion sweep_motion(const core::OrganizedScan& scan,
                                          const core::Pose& pose) const;
  std::optional<core::Pose> previous_pose_;  // of the last processed scan
  std::optional<core::Pose> rest_pose_;      // where the sensor came to rest (background's pose)
  std::vector<std::uint8_t> labels_;
  FrameResult result_;
  std::uint64_t skipped_scans_{0};
  std::unique_ptr<odometry::Odometry> odometry_;
  odometry::OdometryResult odometry_result_;
  core::Pose odometry_start_;
  std::vector<core::Box3> excluded_boxes_;
  bool framed_{false};  // origin_ and ground_z_ are fixed (at the first scan)
  Eigen::Vector3d origin_{Eigen::Vector3d::Zero()};
  double ground_z_{0.0};
};

}  // namespace ringtrack::pipeline
