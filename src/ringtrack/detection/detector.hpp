#pragma once
/// Detection (paper III.C, Alg. 1): region growing on the grid, the split of clusters that hold
/// several people side by side, and the object model.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "ringtrack/core/config.hpp"
#include "ringtrack/core/detection.hpp"
#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"
#include "ringtrack/core/scene_memory.hpp"

namespace ringtrack::detection {

/// The label value that marks a segment point (segmentation::kSegment); detection depends on
/// core only, so it names the value itself.
inline constexpr std::uint8_t kSegmentLabel = 1;

/// What happened to the clusters of the last detect() call, for diagnostics and tuning.
/// A rejected cluster counts under the first failed test of the strict model, in the order
/// too_high, too_tall, too_wide, too_short.
struct DetectorStats {
  std::size_t segment_points{0};  ///< valid cells labelled kSegmentLabel
  std::size_t clusters{0};        ///< clusters with at least min_cluster_points points, or
                                  ///< fewer but accepted as new to the scene (each part of a
                                  ///< split counts)
  std::size_t splits{0};          ///< cuts made by the split step (each adds one cluster)
  std::size_t too_small{0};       ///< clusters dropped for having fewer points (the scene
                                  ///< memory is not asked about one that fails the model)
  std::size_t too_high{0};        ///< lowest point more than max_altitude_m above the ground
  std::size_t too_tall{0};        ///< vertical extent above max_height_m
  std::size_t too_wide{0};        ///< horizontal diagonal above the model's maximum
  std::size_t too_short{0};       ///< vertical extent (plus ring-gap allowance) below min_height_m
  std::size_t relaxed{0};         ///< accepted by the relaxed model only (also clusters of
                                  ///< relaxed_min_cluster_points..min_cluster_points-1 points)
  std::size_t sparse{0};          ///< accepted as sparse (fewer than min_cluster_points, in
                                  ///< space earlier scans saw free, strict model)
  std::size_t detections{0};      ///< accepted clusters (strict, sparse and relaxed)
};

/// Most levels of the split step's recursion (at most 2^kMaxSplitDepth parts per cluster).
inline constexpr int kMaxSplitDepth = 4;
/// The split only examines clusters whose principal axis is at most 60 degrees from the
/// tangential direction (|cos| >= this): people side by side spread across the line of sight.
inline constexpr double kSplitMinAxisCos = 0.5;
/// Sub-bins per split_bin_m bin: the split's sliding window moves by a quarter bin.
inline constexpr std::size_t kSubBins = 4;

/// Clusters the segment points of a scan by region growing on the rings x columns grid and keeps
/// the clusters that fit the object model in the world frame.
///
/// Region growing: a segment point joins a neighbour within Manhattan distance neighbor_radius
/// on the grid (columns wrap across the 0/360 degree seam, rings do not) when their range
/// difference (or 3-D distance, per join_rule) is below join_distance_m. Because the columns
/// wrap, an object cut by the seam is one cluster without a separate fusion step.
///
/// Split: a cluster whose extent along its principal horizontal axis exceeds split_min_width_m
/// (axis within 60 degrees of the tangential direction) is cut at the deepest valley of its
/// coverage profile along that axis (each point spread over its column footprint, so a
/// uniformly sampled surface is flat), found with a split_bin_m window sliding by a quarter
/// bin, when the valley holds at most split_valley_ratio times the smaller of the highest
/// windows on either side and both parts have min_cluster_points (two people side by side,
/// whom the range-difference join merges); the parts are split again while still too wide, up
/// to kMaxSplitDepth levels.
///
/// Object model (world frame, each part of a split cluster on its own): vertical extent in
/// [min_height_m, max_height_m], horizontal box diagonal <= max_diagonal_m, lowest point <=
/// max_altitude_m above the ground (set_ground_z). The minimum-height test is skipped for clusters
/// with a point in the top or bottom ring and credits the extent with range *
/// tan(min_height_ring_gap_deg) (sparse rings under-sample height). A cluster that fails this
/// strict model but whose centroid lies within relaxed_radius_m (horizontally) of a predicted track
/// position is tested without the minimum height and with relaxed_max_diagonal_m; it is flagged
/// relaxed. Clusters with fewer than min_cluster_points but at least relaxed_min_cluster_points
/// points can be accepted this way.
///
/// Sparse detections: given a scene memory (core::SceneMemory; the pipeline passes the
/// background range model of a resting sensor), a cluster with fewer than
/// min_cluster_points but at least sparse_min_points points, every one of them at least
/// background_margin_m in front of what earlier scans saw through its space, is tested with the
/// strict model and flagged sparse (a far person hit by one or two beams where the scene was
/// seen free before). Unlike a relaxed detection it may start a track.
///
/// Cost: O(cells / 8) to find the segment points plus O(segment points * window cells); the
/// buffers live in the detector, so steady-state calls do not allocate.
class Detector {
 public:
  /// Throws core::ConfigError when a setting cannot work (negative radius, zero minimum size).
  explicit Detector(const core::DetectionConfig& config);

  /// Detects objects in a scan. segment_labels holds one label per cell (kSegmentLabel marks a
  /// segment point; invalid cells are ignored whatever their label); sensor_pose maps the
  /// sensor frame to the world; predicted_positions_world are the tracker's predictions that
  /// enable the relaxed model; memory (optional) says where earlier scans saw free space, which
  /// enables sparse detections. Detections come in order of their smallest grid index, each
  /// with its grid indices ascending. The returned reference stays valid until the next call.
  /// Throws core::InputError when the labels do not match the scan's size.
  const std::vector<core::Detection>& detect(
      const core::OrganizedScan& scan, const std::vector<std::uint8_t>& segment_labels,
      const core::Pose& sensor_pose,
      const std::vector<Eigen::Vector3f>& predicted_positions_world = {},
      const core::SceneMemory* memory = nullptr);

  /// Sets the z (frame of the poses) of the ground max_altitude_m counts from; default 0. The
  /// pipeline places it sensor_height_m below its first pose, so the test follows the data
  /// rather than the world frame's datum.
  void set_ground_z(double z_m) { ground_z_m_ = z_m; }
  /// The detections of the last call.
  [[nodiscard]] const std::vector<core::Detection>& detections() const { return detections_; }
  /// Counters of the last call.
  [[nodiscard]] const DetectorStats& stats() const { return stats_; }
  /// The settings in use.
  [[nodiscard]] const core::DetectionConfig& config() const { return config_; }

 private:
  struct Offset {
    int d_ring;
    int d_column;
  };
  struct Frame;  // per-call constants (grid size, pose, predictions)

  void build_offsets(int columns);
  void collect_segment_points(const core::OrganizedScan& scan,
                              const std::vector<std::uint8_t>& labels);
  template <core::JoinRule kRule>
  void grow_clusters(const core::OrganizedScan& scan, const Frame& frame);
  void evaluate_cluster(const core::OrganizedScan& scan, const Frame& frame);
  [[nodiscard]] bool may_confirm(std::size_t n, const Frame& frame) const;
  [[nodiscard]] bool may_be_small(std::size_t n, const Frame& frame) const;
  [[nodiscard]] bool new_to_the_scene(const core::OrganizedScan& scan, const Frame& frame,
                                      std::size_t begin, std::size_t end) const;
  void split_cluster(const Frame& frame);
  bool find_split(const Frame& frame, std::size_t begin, std::size_t end, double& cut);
  // find_split's steps: the part's horizontal principal axis (fills projection_), its coverage
  // profile along that axis (coverage_), and the deepest valley window (window_.size() if none).
  struct SplitAxis {
    double mx{0.0}, my{0.0};        // centroid (world x, y)
    double ax{1.0}, ay{0.0};        // unit axis, pointing to +x
    double p_min{0.0}, p_max{0.0};  // extent of the projections
  };
  SplitAxis project_on_principal_axis(std::size_t begin, std::size_t end);
  void fill_coverage(const Frame& frame, const SplitAxis& axis, std::size_t begin, std::size_t m,
                     double sub, std::size_t sub_bins);
  std::size_t deepest_valley();
  struct PartShape;  // the object model's view of a part
  [[nodiscard]] PartShape measure_part(const core::OrganizedScan& scan, const Frame& frame,
                                       std::size_t begin, std::size_t end) const;
  [[nodiscard]] bool relaxable(const PartShape& shape, const Frame& frame) const;
  void count_rejected(const PartShape& shape);
  void evaluate_part(const core::OrganizedScan& scan, const Frame& frame, std::size_t begin,
                     std::size_t end);
  void add_detection(const PartShape& shape, std::size_t begin, std::size_t end, bool relaxed,
                     bool sparse, bool counted);
  core::Detection& next_detection();

  core::DetectionConfig config_;
  double ground_z_m_{0.0};              // max_altitude_m counts from here
  float join_threshold_{0};             // theta, squared for the Euclidean rule
  float min_height_gap_tan_{0};         // tan(min_height_ring_gap_deg)
  int offsets_columns_{-1};             // column count offsets_ was built for
  std::vector<Offset> offsets_;         // window cells (Manhattan radius), wrapped columns reduced
  std::vector<std::uint8_t> state_;     // per cell: 0 none, 1 unvisited segment point, 2 visited
  bool state_dirty_{false};             // set while state_ may hold marks (exception safety)
  std::vector<std::uint32_t> seeds_;    // segment cells in grid order
  std::vector<std::uint32_t> cluster_;  // cells of the cluster being grown, in visit order
  std::vector<Eigen::Vector3d> world_;  // world points of the cluster being evaluated
  struct Range {
    std::size_t begin, end;
    int depth;
  };
  std::vector<Range> split_stack_;  // parts of the cluster still to be examined
  std::vector<Range> parts_;        // final parts of the cluster (ranges of cluster_, world_)
  std::vector<double> projection_;  // per point of the part: position on its principal axis
  std::vector<double> coverage_;    // split: coverage profile along the axis, per sub-bin
  std::vector<double> window_;      // split: coverage per sliding window of one bin
  std::vector<double> left_max_;    // split: per window, the highest window entirely left of it
  std::vector<core::Detection> detections_;
  std::vector<core::Detection> spare_;  // detections from earlier calls, kept for their buffers
  DetectorStats stats_;
};

}  // namespace ringtrack::detection
