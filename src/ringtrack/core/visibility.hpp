#pragma once
/// Visibility queries: what one organized scan says about a world point or a world box (seen
/// free, occupied, occluded, no return, unknown). See docs/visibility.md.

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "ringtrack/core/box3.hpp"
#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"
#include "ringtrack/core/sensor_model.hpp"

namespace ringtrack::core {

/// What a scan says about a point (or about the part of a beam inside a box).
enum class Visibility : std::uint8_t {
  kUnknown = 0,   ///< outside the field of view, between columns of a gap, or a too-close return
  kFree = 1,      ///< the beam ends beyond it by more than the margin
  kOccupied = 2,  ///< the beam ends at it (within the margin)
  kOccluded = 3,  ///< the beam ends before it by more than the margin
  kNoReturn = 4,  ///< the beam returned nothing (kNoReturn or kTooFar): sky, or absorbing surface
};

/// Short lower-case name ("free", "occupied", ...).
[[nodiscard]] const char* to_string(Visibility v);

/// Number of beams of each kind.
struct VisibilityCounts {
  int free = 0;       ///< beams ending beyond the box
  int occupied = 0;   ///< beams ending inside the box
  int occluded = 0;   ///< beams ending before the box
  int no_return = 0;  ///< beams through the box without a return
  int unknown = 0;    ///< beams through the box with a too-close return
  /// Sum of all kinds.
  [[nodiscard]] int total() const { return free + occupied + occluded + no_return + unknown; }
  /// Adds one beam of kind v.
  void add(Visibility v);
  /// Field-wise equality.
  friend bool operator==(const VisibilityCounts&, const VisibilityCounts&) = default;
};

/// A cell's beam in the world frame: origin (the ring's beam origin) and unit direction.
struct BeamRay {
  Eigen::Vector3d origin;     ///< world position of the beam origin
  Eigen::Vector3d direction;  ///< unit direction in the world
};

/// One beam through a box: its cell, its verdict and where it enters and leaves the box.
struct BoxBeam {
  std::size_t cell{0};                          ///< scan index ring * columns + column
  Visibility visibility{Visibility::kUnknown};  ///< verdict of the beam about the box
  double entry_m{0.0};                          ///< distance from the beam origin to the box entry
  double exit_m{0.0};                           ///< distance from the beam origin to the box exit
};

/// A point's verdict with how far the deciding beam passes from the point.
struct PointProbe {
  Visibility visibility{Visibility::kUnknown};  ///< as VisibilityQuery::at
  double lateral_m{0.0};  ///< distance from the point to the deciding beam (0 when unknown)
  /// Height of the beam above the point where it passes closest (world z; negative: below).
  double beam_above_m{0.0};
  /// World z of the beam's unit direction (negative: descending); 0 when unknown.
  double beam_direction_z{0.0};
  /// How far beyond the point the beam's return lies (negative: before it); 0 without a return.
  double beyond_m{0.0};
};

/// The part of a VisibilityQuery that depends only on the sensor model and the scan's column
/// azimuths, not on the scan's ranges or pose: per-ring beam geometry and the column lookup.
/// A sensor's column azimuths usually repeat from revolution to revolution (always in
/// simulation, often in captures), so the pipeline builds this once and shares it between the
/// queries of the scans it fits(), which saves the trigonometry and the sort of every column
/// per scan.
struct BeamGeometry {
  /// Validates the model and the scan's column azimuths and precomputes. Throws InputError when
  /// the scan does not match the model (rings, column azimuths).
  BeamGeometry(const OrganizedScan& scan, const SensorModel& model);
  /// True when a scan (of the same sensor model) has exactly these rings and column azimuths.
  [[nodiscard]] bool fits(const OrganizedScan& scan) const;

  int rings;
  int columns;
  std::vector<double> column_azimuth_rad;  // as the scan gave them (fits() compares them)
  // Per ring.
  std::vector<double> elevation_rad, cos_el, sin_el, offset_m, az_offset_rad, cos_az_off,
      sin_az_off, accept_below_rad, accept_above_rad;
  double max_abs_elevation_rad{0.0};
  double offset_min_m{0.0};
  double offset_max_m{0.0};
  // Per column: cos/sin of its azimuth.
  std::vector<double> cos_az, sin_az;
  // Column azimuths wrapped to [0, 2 pi), ascending, with their columns; a bucket table into it.
  std::vector<double> sorted_az;
  std::vector<int> sorted_column;
  std::vector<int> bucket;
  double nominal_step_rad{0.0};

 private:
  void set_rings(const SensorModel& model);  // the per-ring tables and bounds
  void set_columns(const OrganizedScan& scan, const SensorModel& model);  // per-column tables
};

/// Keeps the BeamGeometry of the last scan and builds a new one only for a scan it does not fit.
class BeamGeometryCache {
 public:
  /// The geometry of this scan of `model` (the same model at every call); throws InputError as
  /// BeamGeometry's constructor.
  const std::shared_ptr<const BeamGeometry>& get(const OrganizedScan& scan,
                                                 const SensorModel& model) {
    if (geometry_ == nullptr || !geometry_->fits(scan)) {
      geometry_ = std::make_shared<const BeamGeometry>(scan, model);
    }
    return geometry_;
  }

 private:
  std::shared_ptr<const BeamGeometry> geometry_;
};

/// Answers visibility questions about world points and boxes from one organized scan taken at a
/// pose (sensor in world). Holds a reference to the scan, which must outlive the query.
/// Construction is O(columns log columns), O(1) over a shared BeamGeometry; queries do not allocate
/// (except cells_in_box's output).
///
/// A moving sensor measures each column from where it was at that column's time. Given the
/// sensor's motion (and the scan's column_stamp_ns), every beam starts from the sensor's pose at
/// its column's stamp, `pose` being the pose at scan.stamp_ns: at 5 m/s and 1.25 rad/s one
/// revolution moves the beams by 0.5 m and 7 degrees, far more than the margins the tests use.
/// The scan's points are then taken as motion-compensated to `pose` (pipeline::deskew_scan,
/// which keeps the ranges as measured): world_point() uses `pose`, the range comparisons the
/// column's own pose.
class VisibilityQuery {
 public:
  /// Precomputes world->sensor, per-ring beam geometry and the column lookup. Throws InputError
  /// when the scan does not match the model (rings, column azimuths) or the pose is not finite.
  /// A motion that is still, not finite, or a scan without one stamp per column: every column
  /// at `pose`.
  VisibilityQuery(const OrganizedScan& scan, const SensorModel& model, const Pose& pose,
                  const Motion& motion = {});
  /// The same with a geometry built for this scan's model and column azimuths (or for an earlier
  /// scan it fits(); not compared here beyond the ring and column counts, which throw
  /// InputError). Only the pose and the motion are checked and precomputed: O(1).
  VisibilityQuery(const OrganizedScan& scan, std::shared_ptr<const BeamGeometry> geometry,
                  const Pose& pose, const Motion& motion = {});

  /// Verdict of the scan about one world point; margin_m >= 0 is the range tolerance in metres.
  [[nodiscard]] Visibility at(const Eigen::Vector3d& world_point, double margin_m) const;
  /// Like at(), with the distance between the point and the beam that decided: a beam that
  /// passes a metre beside a point says little about it (a moving sensor's rings fall between
  /// the heights an earlier scan saw).
  [[nodiscard]] PointProbe probe(const Eigen::Vector3d& world_point, double margin_m) const;
  /// A valid cell's point in the world frame.
  [[nodiscard]] Eigen::Vector3d world_point(std::size_t cell) const {
    return world_R_sensor_ * scan_->point(cell).cast<double>() + world_t_sensor_;
  }
  /// The cell whose beam passes closest to the point (nearest ring elevation, nearest column
  /// azimuth), or nothing when the point lies outside the field of view.
  [[nodiscard]] std::optional<std::size_t> cell_of(const Eigen::Vector3d& world_point) const;
  /// Distance from the point to the beam origin of the ring of cell_of (nothing outside the FOV).
  [[nodiscard]] std::optional<double> beam_distance(const Eigen::Vector3d& world_point) const;
  /// True when this scan saw through a point from its viewpoint: the point's nearest beam passes
  /// within lateral_m of it and ends more than margin_m beyond it (a descending beam that passes
  /// over a point on the ground must also end beyond where it meets the ground there), and no
  /// beam through the cube of half side clearance_m around the point ends inside or before it
  /// (from another viewpoint the nearest beam may pass just beside a thin pole and see past it).
  [[nodiscard]] bool sees_through(const Eigen::Vector3d& point, double margin_m, double lateral_m,
                                  double clearance_m) const;
  /// The same with the point's probe(point, margin_m) already made.
  [[nodiscard]] bool sees_through(const Eigen::Vector3d& point, const PointProbe& probe,
                                  double margin_m, double lateral_m, double clearance_m) const;
  /// Verdicts of every beam that passes through the box (rays are half-lines from their origin).
  [[nodiscard]] VisibilityCounts in_box(const Box3& world_box, double margin_m) const;
  /// in_box's free > 0 && occupied == 0 && occluded == 0, stopping at the first beam that ends
  /// inside or before the box (the common answer for clutter, at a fraction of the cost).
  [[nodiscard]] bool seen_through_box(const Box3& world_box, double margin_m) const;
  /// Like in_box, listing each beam; out is cleared first. Order: by ring, then by azimuth.
  void cells_in_box(const Box3& world_box, double margin_m, std::vector<BoxBeam>& out) const;

  /// The beam of a cell in the world frame (the geometry SensorModel::point uses).
  [[nodiscard]] BeamRay cell_ray(int ring, int column) const;
  /// Column of a firing azimuth (radians, any turn): nearest column azimuth, or nothing inside
  /// a gap wider than two nominal column steps beyond half a step from its ends.
  [[nodiscard]] std::optional<int> column_of_azimuth(double azimuth_rad) const;
  /// Ring of a sensor-frame point: nearest ring elevation seen from each ring's beam origin,
  /// within half the gap to the neighbouring ring (half a nominal gap at the ends).
  [[nodiscard]] std::optional<int> ring_of_sensor_point(const Eigen::Vector3d& sensor_point) const;
  /// Median spacing of the column azimuths (radians), the nominal column step.
  [[nodiscard]] double nominal_column_step_rad() const { return geo_->nominal_step_rad; }

  /// The sensor's position in the world (the pose's translation).
  [[nodiscard]] const Eigen::Vector3d& sensor_position() const { return world_t_sensor_; }
  /// True when the beams start from per-column poses (a moving sensor, see the class comment).
  [[nodiscard]] bool per_column_poses() const { return moving_; }
  /// The scan this query answers from.
  [[nodiscard]] const OrganizedScan& scan() const { return *scan_; }

 private:
  struct Located {
    int ring;
    int column;
    double distance_m;
  };
  // The sensor in the world when it fired one column.
  struct Frame {
    Eigen::Matrix3d world_R_sensor;
    Eigen::Vector3d world_t_sensor;
  };
  void set_motion(const Motion& motion);
  [[nodiscard]] Frame column_frame(int column) const;
  // Ring, column and beam distance of a point given in the frame of the sensor that fired.
  [[nodiscard]] std::optional<Located> locate_sensor_point(const Eigen::Vector3d& p) const;
  [[nodiscard]] std::optional<Located> locate(const Eigen::Vector3d& world_point) const;
  // The beams that can reach a box: its azimuth band (start and span, before each ring's azimuth
  // offset; every azimuth when the sensor's z axis meets the box) and elevation band, widened
  // for a moving sensor by its travel and turn during the sweep.
  struct BeamBand {
    bool all_azimuths{true};
    double az_start{0.0};
    double az_span{0.0};
    double el_min{0.0};
    double el_max{0.0};
  };
  [[nodiscard]] BeamBand beam_band(const Box3& world_box) const;
  // Calls visit(cell, verdict, entry, exit) for every beam through the box until it returns false.
  template <typename Visit>
  void visit_box(const Box3& world_box, double margin_m, Visit&& visit) const;

  const OrganizedScan* scan_;
  int rings_;
  int columns_;
  Eigen::Matrix3d world_R_sensor_;
  Eigen::Vector3d world_t_sensor_;
  Eigen::Matrix3d sensor_R_world_;
  Eigen::Vector3d sensor_t_world_;
  std::shared_ptr<const BeamGeometry> geo_;
  // Motion during the sweep (moving_ only): the column's rotation is world_R_sensor_ +
  // sin(a) spin_a_ + (1 - cos(a)) spin_b_ for the angle a = spin_rate_ * dt (Rodrigues, the
  // axis' cross-product matrix K folded in: spin_a_ = K R, spin_b_ = K^2 R).
  bool moving_{false};
  Eigen::Vector3d velocity_{Eigen::Vector3d::Zero()};
  Eigen::Matrix3d spin_a_{Eigen::Matrix3d::Zero()};
  Eigen::Matrix3d spin_b_{Eigen::Matrix3d::Zero()};
  double spin_rate_{0.0};
  double sweep_s_{0.0};  // largest |column stamp - scan stamp|
};

}  // namespace ringtrack::core
