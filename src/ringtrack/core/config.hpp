#pragma once
/// The one configuration aggregate: a struct per module with documented defaults.

#include <string>
#include <vector>

namespace ringtrack::core {

/// Width-range segmentation (paper III.B). Widths define the objects to find: the noise median
/// removes groups narrower than min_width_m, the background median removes groups narrower than
/// max_width_m, and points where the two differ by delta (certainty >= threshold) are segments.
struct SegmentationConfig {
  double min_width_m{0.1};          // narrower groups (thin poles, spikes) are noise
  double max_width_m{1.2};          // wider groups (walls, cars) are background
  int max_kernel_radius{450};       // cap on a median window's half width, in columns
  double invalid_range_m{250.0};    // range given to invalid returns; must exceed the sensor's max
  double delta_min_m{0.1};          // certainty 0 below this background-minus-noise difference
  double delta_low_m{0.3};          // certainty rises linearly to 1 here
  double delta_high_m{300.0};       // certainty 1 up to here (objects against the sky included)
  double delta_max_m{400.0};        // certainty falls linearly to 0 here
  double certainty_threshold{0.5};  // a point is a segment point when certainty >= this
};

/// How region growing decides that two neighbouring segment points belong together.
enum class JoinRule {
  kEuclidean,        ///< 3-D distance below theta (the paper's rule)
  kRangeDifference,  ///< range difference below theta (the authors' code)
};

/// Region growing and the object model (paper III.C).
struct DetectionConfig {
  int neighbor_radius{3};  // Manhattan radius of the grid neighbourhood, in cells
  JoinRule join_rule{JoinRule::kRangeDifference};
  double join_distance_m{0.5};        // theta: the largest distance (or range difference) joined
  int min_cluster_points{3};          // smaller clusters are dropped ...
  int relaxed_min_cluster_points{2};  // ... unless this big and near a prediction (relaxed):
                                      // far people are hit by one or two beams
  int sparse_min_points{1};           // ... or this big with every point in front of the
                                      // learned background (sparse: may start a track)
  double background_margin_m{0.5};    // in front of the background: nearer by at least this
  double min_height_m{0.8};           // object model: vertical extent range
  double max_height_m{2.3};
  double min_height_ring_gap_deg{2.0};  // min-height test credits range*tan(this): sparse rings
                                        // under-sample height (VLP-16 ring spacing; 0 = off)
  double max_diagonal_m{1.3};           // largest horizontal box diagonal
  double max_altitude_m{3.0};           // largest height of the cluster's lowest point above
                                        // the ground (sensor_height_m below the first pose)
  double sensor_height_m{2.5};          // sensor above the ground at the first scan
  double relaxed_max_diagonal_m{1.8};   // relaxed model near predicted tracks (no minimum height)
  double relaxed_radius_m{0.8};  // a cluster this close to a prediction uses the relaxed model
  double min_position_stddev_m{0.03};  // floor on each axis of a detection's covariance
  double split_min_width_m{0.9};       // clusters wider than this (along their principal horizontal
                                       // axis) are split at a density valley; 0 = no splitting
  double split_bin_m{0.1};             // width of the split's sliding window along the axis
  double split_valley_ratio{0.5};      // a valley splits at coverage <= this * the smaller peak
  double complete_range_m{0.3};   // completion: ring neighbours within this range join (0 = off)
  double complete_margin_m{0.2};  // ... inside the box grown by this (horizontally and on top)
};

/// Cost of pairing a detection with a hypothesis in the assignment (paper III.D).
enum class AssociationCost {
  kBhattacharyya,  ///< between the predicted position and the detection distributions (the paper)
  kMahalanobis,    ///< of the centroid under the innovation covariance (predicted + detection)
  kEuclidean,      ///< 3-D distance between the predicted position and the centroid
};

/// What turns a static hypothesis dynamic (docs/tracking.md, "Static and dynamic").
enum class DynamicTest {
  kFreeSpace,  ///< the scan sees through space the object occupied where it was anchored
  kBox,        ///< its footprint leaves the anchor footprint (the paper's box test, refined)
};

/// How a hypothesis' height evolves.
enum class VerticalMotion {
  kConstantPosition,  ///< vertical velocity held at zero: walkers and ground robots
  kConstantVelocity,  ///< like the horizontal axes: flying objects
};

/// What position outputs list for a hypothesis measured in the scan (docs/tracking.md,
/// "Reported position").
enum class ReportedPosition {
  kMeasured,  ///< the centroid of its detection in this scan (the filter's when missed)
  kFiltered,  ///< the Kalman filter's estimate in every scan
};

/// Multi-object tracking (paper III.D): constant-velocity Kalman filters in the world frame,
/// Hungarian assignment with a gate, hypothesis lifecycle and static/dynamic classification.
struct TrackingConfig {
  AssociationCost cost{AssociationCost::kBhattacharyya};
  double gate_bhattacharyya{4.0};  // pairs above this Bhattacharyya distance are forbidden
  double gate_mahalanobis{4.0};    // ... above this Mahalanobis distance (sigmas)
  double gate_euclidean_m{1.0};    // ... above this distance (m)
  double process_noise{0.2};       // white-acceleration spectral density q (m^2/s^3)
  VerticalMotion vertical_motion{
      VerticalMotion::kConstantPosition};    // a z velocity fitted to
                                             // ring jumps drifts coasting tracks up or into the
                                             // ground
  double vertical_position_noise{0.5};       // constant_position: z random-walk density (m^2/s)
  double initial_velocity_stddev_mps{1.5};   // velocity prior of a new hypothesis
  double measurement_covariance_scale{0.5};  // detection covariance times this: association R
  double centroid_noise_m{0.05};  // filter update noise: centroid standard error (+) this per axis
  ReportedPosition reported_position{ReportedPosition::kMeasured};  // what outputs list
  double few_point_stddev_m{0.2};      // association: horizontal std floor of 1-2-point detections
  double reassociate_distance_m{0.5};  // second pass: leftovers this close (horizontally) pair
  double delete_eigenvalue_m2{1.0};    // delete when a position-covariance eigenvalue exceeds this
  double merge_distance_m{0.3};        // younger hypotheses this close to older ones are deleted
  double few_point_merge_distance_m{0.6};  // ... this close when both were last measured by <= 2
                                           // points (far people)
  double min_speed_kmh{1.0};               // reported speeds up to this are reported as zero
  double max_speed_kmh{15.0};              // speeds are capped here (state and report)
  double dynamic_min_distance_m{1.5};  // besides disjoint footprints, the centre must move this far
  int dynamic_confirm_scans{5};        // ... in this many consecutive strict detections
  double dynamic_streak_min_m{0.5};    // ... while the centre covers this much (m)
  int rest_scans_to_static{30};  // dynamic hypotheses at rest this long turn static (0 = never)
  DynamicTest dynamic_test{DynamicTest::kFreeSpace};  // free_space needs the scan (Pipeline)
  double free_space_margin_m{0.3};        // a beam ending this far beyond a point sees it free
  double free_space_lateral_m{0.15};      // ... if it passes this close to the point
  double free_space_min_share{0.6};       // share of the remembered points seen free (of decided)
  int free_space_confirm_scans{2};        // consecutive scans the free-space evidence must hold
  double free_space_min_distance_m{0.5};  // and the measured centre moved this far (m)
  double free_space_max_viewpoint_shift_m{0.1};  // farther from the anchor's viewpoint: box test
  int occluded_coast_scans{30};  // a hypothesis whose predicted points are occluded coasts this
                                 // many missed scans before the covariance test may delete it
  int confirm_hits{2};           // detections before a hypothesis is reported (M of M)
  int report_missed_scans{5};    // a hypothesis missed longer is not reported (hidden or not)
  int person_min_scans{10};      // strict detections before a confirmed hypothesis is a person
  int free_delete_scans{2};  // missed in this many consecutive scans seeing through its predicted
                             // points: deleted
  double relink_distance_m{1.0};  // a newly confirmed hypothesis takes the id of one lost this
                                  // close to its birth (extrapolated; 0 = off)
  double relink_max_gap_s{2.0};   // ... when it was last measured at most this long before
  bool rest_pairing{true};  // a coasting hypothesis that has moved may also pair at rest where it
                            // was last measured (a walker who stopped while unmeasured)
  bool hold_partly_hidden{true};  // a hypothesis at rest whose detection shows only part of it,
                                  // the rest hidden behind something nearer, stays where it was
};

/// Dynamic-object filter and static map (paper III.E).
/// Which tracked objects the dynamic-object filter removes from the scans and the map.
enum class RemovedObjects {
  kDynamic,    ///< those that moved (the paper's rule: people who stand all along stay)
  kPerson,     ///< those, and every hypothesis flagged person (standing people too)
  kConfirmed,  ///< every confirmed hypothesis, moving or not (posts and bushes tracked too)
};

struct MappingConfig {
  int log_delay_scans{50};      // filtered scans wait this many scans in the log before the map
  double voxel_size_m{0.1};     // static-map voxel edge (one point per voxel)
  double box_margin_m{0.1};     // boxes grow by this before points inside them are removed
  double object_margin_m{0.2};  // a measured dynamic box grows by this sideways and up, and every
                                // point inside leaves its scan (0: only its detection's cells)
  double object_ground_clearance_m{0.1};  // ... and down to this height above the ground around
                                          // it (its lowest point within 1 m; 0: not down)
  double object_min_height_m{2.0};  // ... and up to at least this height above that ground (0: no)
  double object_outer_margin_m{0.3};  // ... and sideways to this, but for points of map voxels seen
                                      // free_space_protect_count times (<= object_margin_m: no)
  RemovedObjects remove{RemovedObjects::kDynamic};  // which tracked objects leave the map
  // Free-space line (docs/tracking.md): a logged candidate point (segmented, or near a
  // hypothesis) that a later scan sees through leaves the scan before it reaches the map.
  bool free_space{true};
  double free_space_margin_m{0.3};     // the beam must end this far beyond the point
  double free_space_lateral_m{0.05};   // ... and pass this close to it
  bool free_space_moving{false};       // also test scans from other viewpoints (inexact)
  double free_space_clearance_m{0.1};  // moving sensor: no beam may end this near the point
  int free_space_lag_scans{5};         // first test this many scans later; again at release
  double free_space_reach_m{0.8};      // points this near a hypothesis' box are candidates
  int free_space_protect_count{10};    // a map voxel of this many points protects its points
  // Transient line (docs/tracking.md): a segmented point this far above the ground that no scan
  // transient_scans or more before or after its own segmented again near it leaves its scan.
  int transient_scans{20};              // 0 = off
  double transient_cell_m{0.15};        // "near": the point's x-y cell of this edge or the 8 around
  double transient_min_height_m{0.15};  // lower points (the ground) never count as transient
  double map_radius_m{0.0};  // voxels farther from the sensor (x-y) leave memory (0 = keep all)
};

/// Background range model of a static sensor (core::BackgroundRangeModel, docs/visibility.md):
/// per cell, the range of the static background learned over scans.
struct BackgroundRangeConfig {
  /// Two ranges are one surface when within tolerance_m + relative_tolerance * (nearer range).
  double tolerance_m{0.15};
  /// Range-proportional part of the tolerance (far returns and grazing surfaces are noisier).
  double relative_tolerance{0.01};
  /// Consecutive scans a range nearer than the background (or the first range) must hold to
  /// become background: a person passing stays foreground, a parked car is learned.
  int scans_to_learn{20};
  /// Consecutive scans a range behind the background must hold to replace it; seeing through the
  /// old background proves it gone, so this may be shorter.
  int scans_to_learn_behind{5};
  /// Weight of a return matching the background in its running average (0 freezes it).
  double smoothing{0.05};
  /// Whether a cell without returns (sky, kTooFar) for scans_to_learn scans learns an open
  /// (infinite) background, in front of which any return counts.
  bool learn_no_return{true};
  /// The pipeline learns the model while the sensor stays within this distance (m) ...
  double static_shift_m{0.02};
  /// ... and this rotation (degrees) of the pose where it came to rest; beyond, it forgets it.
  double static_turn_deg{0.1};
  /// A moving sensor's memory instead (core::RecentViews): whether earlier scans saw through
  /// the points of a small cluster, from their own viewpoints.
  bool moving_memory{true};
  /// The scans this many scans back, twice and four times as far back are asked.
  int moving_lag_scans{5};
  /// An earlier scan's beam decides about a point passing this close to it (m) ...
  double moving_lateral_m{0.1};
  /// ... and none of its beams through the cube of this half side around the point may end
  /// inside or before the cube (m).
  double moving_clearance_m{0.1};
  /// Column test (0 = off): an earlier scan also saw through a point when its beams through the
  /// vertical column of this half width (m) under the point, from moving_column_ground_m above
  /// the ground up to moving_clearance_m below the point, pass it free, at least one of them and
  /// none ending inside or before it: a standing body fills the column under its hits, so where
  /// a far person is hit by one ring and an earlier scan's rings passed a metre higher or lower,
  /// the ones below still tell (docs/detection.md).
  double moving_column_m{0.1};
  /// ... the column stops this far above the ground (m): ground hits inside it would say
  /// "occupied" everywhere.
  double moving_column_ground_m{0.2};
};

/// What ICP minimises per correspondence (docs/odometry.md, "Residual").
enum class OdometryResidual {
  kPointToPoint,  ///< distance to the nearest map point (KISS-ICP's choice)
  kPointToPlane,  ///< ... along the scan point's surface normal from the grid (the default)
};

/// LiDAR odometry (docs/odometry.md): the sensor's pose per scan from the scans alone when no
/// pose source is given. Scan-to-local-map point-to-point ICP with a robust kernel, constant-
/// velocity prediction and per-column motion compensation.
struct OdometryConfig {
  double voxel_size_m{1.0};      // local-map voxel edge; the nearest-neighbour search spans
                                 // one voxel, so this bounds the correspondence distance
  int max_points_per_voxel{20};  // points kept per map voxel (bounded memory and search)
  double map_spacing_m{0.5};     // scan points enter the map at most one per cube this size
  double source_voxel_m{2.0};    // registration uses at most one scan point per cube this size
  int min_source_points{200};    // fewer in the source grid: its edge halves, down to map_spacing_m
  double map_radius_m{100.0};    // map voxels farther than this from the sensor are dropped
  double min_range_m{1.0};       // nearer returns (the platform, the operator) are not used
  double max_range_m{100.0};     // farther returns are not used
  double initial_threshold_m{2.0};  // correspondence distance before motion statistics exist
  double min_motion_m{0.1};         // prediction errors below this do not enter the statistics
  double min_threshold_m{0.3};      // floor of the adaptive correspondence distance
  int max_iterations{30};           // ICP iterations per scan at most
  double convergence_m{1e-3};       // ICP stops when a step moves less than this (m and rad)
  OdometryResidual residual{OdometryResidual::kPointToPlane};  // point_to_plane: a sparse scan's
                                                               // ground rings do not pull the
                                                               // estimate back to the last pose
  bool deskew{true};                  // motion-compensate each scan with the estimated velocity
  double deskew_acceleration{0.3};    // share of the last change of the motion extrapolated over
                                      // a scan's own revolution (0: constant velocity)
  bool exclude_tracks{true};          // points of tracked objects stay out of ICP and the map
  double exclude_margin_m{0.3};       // ... inside their predicted boxes grown by this
  double weak_share_threshold{0.05};  // registered scans below it are flagged weak (may slide)
  double degeneracy_threshold{0.01};  // a scan whose weakest translation direction gets less than
                                      // this share of the surface normals is flagged unreliable
};

/// Every setting of the pipeline.
struct Config {
  SegmentationConfig segmentation;
  DetectionConfig detection;
  TrackingConfig tracking;
  MappingConfig mapping;
  BackgroundRangeConfig background;
  OdometryConfig odometry;
};

/// Documentation of one key, as dump-config prints it.
struct ConfigKeyInfo {
  std::string key;          ///< "section.name"
  std::string value;        ///< current value as YAML text
  std::string description;  ///< meaning and allowed range
};

/// Lists every key with its value and meaning.
std::vector<ConfigKeyInfo> describe_config(const Config& config);
/// Applies the overrides in a YAML file; unknown keys and out-of-range values throw ConfigError
/// naming the file and the key.
void apply_config_file(Config& config, const std::string& path);
/// Applies overrides from YAML text (source names it in errors).
void apply_config_yaml(Config& config, const std::string& yaml_text, const std::string& source);
/// Applies one "section.key=value" override.
void apply_config_override(Config& config, const std::string& assignment);
/// Checks relations between keys (e.g. min_width < max_width); throws ConfigError.
void validate_config(const Config& config);
/// The configuration as commented YAML that apply_config_yaml reads back unchanged.
std::string dump_config(const Config& config);

}  // namespace ringtrack::core
