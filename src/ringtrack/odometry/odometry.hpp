#pragma once
/// LiDAR odometry: the sensor's pose per scan from the scans alone (docs/odometry.md).

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "ringtrack/core/box3.hpp"
#include "ringtrack/core/config.hpp"
#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"
#include "ringtrack/odometry/voxel_map.hpp"

namespace ringtrack::odometry {

/// What the odometry made of one scan.
struct OdometryResult {
  core::Pose pose;         ///< world_T_sensor at scan.stamp_ns (world: see Odometry's start)
  bool first{false};       ///< the first scan: it defines the world frame and starts the map
  bool registered{false};  ///< ICP ran on enough correspondences (else pose = prediction)
  bool degenerate{false};  ///< unreliable: too little geometry, or not registered
  bool weak{false};  ///< not degenerate, but weakest_share < odometry.weak_share_threshold: the
                     ///< pose may slide along the weakest direction (docs/odometry.md)
  double weakest_share{0.0};  ///< odometry.degeneracy_threshold compares with this
  int iterations{0};
  std::size_t source_points{0};    ///< scan points registered (after downsampling)
  std::size_t correspondences{0};  ///< pairs in the last ICP iteration
  std::size_t excluded_points{0};  ///< points inside tracked objects' boxes, left out
  double threshold_m{0.0};         ///< correspondence distance used
};

/// Moves every valid point of a scan into the sensor frame at scan.stamp_ns, for a sensor that
/// moves uniformly by `motion` (the frame at the end of the interval in the frame at its start)
/// every `motion_duration_s` seconds: a column at time t is moved by that motion scaled to
/// t - stamp (linear translation, scaled rotation angle). Scans without per-column times and
/// non-positive durations are left as they are.
void deskew_constant_velocity(core::OrganizedScan& scan, const Eigen::Isometry3d& motion,
                              double motion_duration_s);

/// The motion scaled by s: rotation angle and translation times s.
[[nodiscard]] Eigen::Isometry3d scale_motion(const Eigen::Isometry3d& motion, double s);

/// deskew_constant_velocity applied twice to a scan, in two steps that write the scan once: the
/// first compensation goes to own arrays (the odometry selects its points and normals from
/// them), the second is applied on top when the scan is written. The written scan is bit for bit
/// what two deskew_constant_velocity calls leave, with one setter call per cell instead of two
/// (docs/odometry.md, "Speed").
class ScanCompensation {
 public:
  /// Compensates the scan's points as deskew_constant_velocity(scan, motion, motion_duration_s)
  /// would, into own arrays (the scan is not changed). A non-positive duration copies them.
  void compensate(const core::OrganizedScan& scan, const Eigen::Isometry3d& motion,
                  double motion_duration_s);
  /// Cell i holds a valid return with finite compensated coordinates.
  [[nodiscard]] bool usable(std::size_t i) const { return usable_[i] != 0; }
  /// Compensated point of cell i.
  [[nodiscard]] Eigen::Vector3f point(std::size_t i) const { return {x_[i], y_[i], z_[i]}; }
  /// Writes the compensated points into the scan (the one compensate() read), compensated once
  /// more with `motion` over `motion_duration_s` (a non-positive duration: as they are).
  void write(core::OrganizedScan& scan, const Eigen::Isometry3d& motion,
             double motion_duration_s) const;

 private:
  std::vector<float> x_, y_, z_;
  std::vector<std::uint8_t> usable_;
  std::vector<std::uint8_t> moved_;  // per column: the first compensation moved it
};

/// Scan-to-map odometry with constant-velocity prediction and deskew, adaptive correspondence
/// threshold, robust point-to-point ICP and a voxel local map cropped around the sensor.
class Odometry {
 public:
  /// start: the world pose of the first scan (default: the world is the first scan's frame).
  /// Throws core::ConfigError when the settings are inconsistent.
  explicit Odometry(const core::OdometryConfig& config,
                    const Eigen::Isometry3d& start = Eigen::Isometry3d::Identity());

  /// Estimates the pose of the scan, motion-compensating it in place (config.deskew) into the
  /// sensor frame at scan.stamp_ns, and adds its points to the local map. Points inside the
  /// world-frame boxes `excluded` (tracked objects predicted to this scan) are left out of both.
  /// Invalid cells and non-finite coordinates are ignored; a scan with no usable point keeps
  /// the predicted pose and is flagged degenerate. Throws core::InputError when the stamp is not
  /// later than the previous scan's.
  OdometryResult process(core::OrganizedScan& scan, std::span<const core::Box3> excluded = {});

  /// The local map (world frame).
  [[nodiscard]] const VoxelMap& local_map() const { return map_; }
  /// Scans processed so far.
  [[nodiscard]] std::size_t scans() const { return scans_; }

 private:
  /// Downsamples the usable points of the scan into frame_ (map spacing) and source_ (registration
  /// spacing), leaving out points in the excluded boxes seen from the predicted pose.
  void select_points(const core::OrganizedScan& scan, const Eigen::Isometry3d& predicted,
                     std::span<const core::Box3> excluded, OdometryResult& result);
  /// Samples the source points from the frame points, one per cube of edge voxel_m.
  void sample_source(double voxel_m);
  /// Pose predicted for a scan dt_s after the last one (constant velocity).
  [[nodiscard]] Eigen::Isometry3d predict(double dt_s) const;
  /// Correspondence distance from the statistics of past prediction errors.
  [[nodiscard]] double correspondence_threshold() const;
  /// Adds the prediction error of this scan to the statistics.
  void update_threshold(const Eigen::Isometry3d& predicted, const Eigen::Isometry3d& estimated);
  /// Surface normals of the source points from the grid (zero where there is none).
  void compute_normals(const core::OrganizedScan& scan);
  /// Runs ICP from the prediction; sets estimate when it registered; true when it converged.
  bool register_scan(const Eigen::Isometry3d& predicted, int max_iterations, OdometryResult& result,
                     Eigen::Isometry3d& estimate);
  /// How far (m, at 20 m range) compensating with the estimate's motion (scan interval dt_s)
  /// instead of the one applied moves points over a revolution.
  [[nodiscard]] double deskew_correction_m(const Eigen::Isometry3d& estimate, double dt_s) const;
  /// The motion over this scan's own revolution (after its stamp): the motion since the last
  /// scan (implied, over dt_s), extrapolated with config.deskew_acceleration times the change
  /// from the interval before.
  [[nodiscard]] Eigen::Isometry3d forward_motion(const Eigen::Isometry3d& implied,
                                                 double dt_s) const;
  /// Compensates and registers again while the compensation changes noticeably.
  void refine_passes(core::OrganizedScan& scan, double dt_s, bool converged, OdometryResult& result,
                     Eigen::Isometry3d& estimate);
  /// Compensates the selected points again with the motion the estimate implies (applied_).
  void refine_deskew(const Eigen::Isometry3d& estimate, double dt_s);
  /// Rebuilds the map from the first scan compensated with the first motion (second scan).
  void restart_map(const Eigen::Isometry3d& first_motion, double dt_s);
  /// Moves the pose history on, puts the previous scan into the map and holds this one back
  /// (its frame compensated with applied_ over dt_s).
  void commit(const Eigen::Isometry3d& pose, std::int64_t stamp_ns, double dt_s);
  /// Corrects the held-back scan's compensation with its true motion and adds it to the map.
  void insert_pending(const Eigen::Isometry3d& actual, double actual_dt_s);

  core::OdometryConfig config_;
  Eigen::Isometry3d start_;
  VoxelMap map_;
  ScanCompensation compensation_;     // this scan's points, compensated with the prediction
  std::vector<float> column_time_s_;  // per column: its time after the scan stamp
  VoxelKeySet frame_keys_, source_keys_;
  std::vector<Eigen::Vector3f> frame_, source_;
  std::vector<float> frame_time_s_;  // per frame point: its column's time after the scan stamp
  std::vector<std::uint32_t> frame_cells_;  // per frame point: its scan cell
  std::vector<float> source_time_s_;        // the same per source point
  // The last scan's points (sensor frame), held back until the next pose is known.
  std::vector<Eigen::Vector3f> pending_;
  std::vector<float> pending_time_s_;
  std::vector<Eigen::Vector3f> first_frame_;  // the first scan's points, until the second scan
  std::vector<float> first_time_s_;
  Eigen::Isometry3d pending_pose_{Eigen::Isometry3d::Identity()};
  Eigen::Isometry3d pending_used_{Eigen::Isometry3d::Identity()};  // compensated with this ...
  double pending_used_dt_s_{0.0};                                  // ... motion over this time
  std::vector<std::uint32_t> source_cells_;
  // Neighbours of the source points, shared by one scan's passes (the map does not change
  // between them, the points move by millimetres); reset (memory kept) for every scan and when
  // the map changes.
  NeighbourCache neighbours_{map_, 0.0, 0};
  bool neighbours_ready_{false};
  std::vector<Eigen::Vector3f> source_normals_, valid_normals_;
  Eigen::Isometry3d last_pose_{Eigen::Isometry3d::Identity()};
  Eigen::Isometry3d motion_{Eigen::Isometry3d::Identity()};  // last scan-to-scan motion
  double motion_dt_s_{0.0};                                  // ... and its duration
  Eigen::Isometry3d change_{Eigen::Isometry3d::Identity()};  // motion_ after the one before
  bool change_known_{false};                                 // ... measured (two intervals)
  bool velocity_reset_{false};  // motion_ is the stop assumed after a degenerate scan
  Eigen::Isometry3d applied_{Eigen::Isometry3d::Identity()};  // this scan compensated with this
  std::int64_t last_stamp_ns_{0};
  double error_sse_{0.0};
  std::size_t error_samples_{0};
  std::size_t scans_{0};
  Eigen::Vector3f last_crop_{Eigen::Vector3f::Zero()};
};

}  // namespace ringtrack::odometry
