#pragma once
/// Point clouds without rings (KITTI .bin, unorganized PCD, PointCloud2 without a ring field)
/// organized into the rings x columns grid of a sensor model, with the binning error stated;
/// docs/inputs.md ("Point clouds without rings").

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/sensor_model.hpp"

namespace ringtrack::core {

/// Points without ring or column, one entry per point, in the sensor frame.
struct UnorganizedCloud {
  std::vector<Eigen::Vector3f> xyz;   ///< NaN coordinates or the origin mean "no return"
  std::vector<float> intensity;       ///< empty, or one per point
  std::vector<std::int64_t> time_ns;  ///< empty, or each point's firing time (the poses' clock)
  std::int64_t stamp_ns{0};           ///< the cloud's stamp: column stamps without time_ns

  /// Number of points.
  [[nodiscard]] std::size_t size() const { return xyz.size(); }
};

/// Where the beams of a model with vertical beam offsets (VLP-16) start, for the points of a cloud.
enum class BeamOrigins : std::uint8_t {
  kAuto,          ///< per cloud, whichever fits its points better (drivers differ, see below)
  kModel,         ///< the model's offsets: points as ringtrack's decoder and simulator place them
  kSensorOrigin,  ///< all at the origin: drivers that ignore the offsets (e.g. tier4/nebula)
};

/// Column grid and ring window of CloudOrganizer.
struct CloudOrganizerOptions {
  /// Centre of column 0 (radians, counter-clockwise from +x). Columns are 2*pi / model.columns()
  /// wide: the grid closes on itself after one turn.
  double first_column_azimuth_rad{0.0};
  /// Columns advance clockwise seen from above, as Velodyne, Hesai and Ouster sensors turn;
  /// false: counter-clockwise, as OrganizedScan::set_uniform_columns and the simulator.
  bool clockwise{false};
  /// Undo the sensor's turn during each ring's firing delay (model.firing_offset_us) before
  /// binning by azimuth: right for clouds decoded from real packets, whose points carry it.
  bool undo_firing_rotation{false};
  /// A point goes to its nearest ring (elevation seen from that ring's beam origin) when it lies
  /// within this fraction of the gap to the neighbouring ring on its side; farther points are
  /// dropped and counted (between_rings). In (0, 0.5]; 0.5 assigns every point inside the fan.
  double ring_window{0.25};
  /// Beam origins of models with vertical offsets. kAuto compares the mean elevation residual of
  /// up to 4096 of the cloud's points under both hypotheses and takes the smaller.
  BeamOrigins beam_origins{BeamOrigins::kAuto};
};

/// What organizing one cloud did: where the points went and how well they fit the rings.
struct CloudOrganizeStats {
  std::uint64_t points{0};         ///< points in the cloud
  std::uint64_t organized{0};      ///< points that hold a cell of the scan
  std::uint64_t non_finite{0};     ///< NaN or infinite coordinates: skipped
  std::uint64_t at_origin{0};      ///< exactly (0, 0, 0), many drivers' "no return": skipped
  std::uint64_t between_rings{0};  ///< outside every ring's window: dropped
  std::uint64_t collided{0};       ///< lost their cell to a nearer point of the same cell
  std::uint64_t out_of_range{0};   ///< outside the model's [min_range_m, max_range_m]
  /// Absolute elevation residual (point's elevation from its ring's beam origin less the ring's
  /// elevation) over the points assigned to a ring: median, 95th percentile and maximum, degrees.
  double median_elevation_error_deg{0.0};
  double p95_elevation_error_deg{0.0};  ///< see median_elevation_error_deg
  double max_elevation_error_deg{0.0};  ///< see median_elevation_error_deg
  /// The model's beam offsets were applied (false: the model has none, or the cloud's points fit
  /// beams from the sensor origin better).
  bool beam_offsets{false};

  /// Points that were returns (neither non-finite nor at the origin) but hold no cell.
  [[nodiscard]] std::uint64_t dropped() const { return between_rings + collided + out_of_range; }
};

/// Counts summed over many clouds (a sequence): errors as the largest per-cloud figures.
struct CloudOrganizeTotals {
  std::uint64_t clouds{0};  ///< clouds organized
  CloudOrganizeStats sum;   ///< counts summed; the error fields are the per-cloud maxima
  /// Adds one cloud's stats.
  void add(const CloudOrganizeStats& stats);
  /// One line: counts, shares and elevation errors, e.g. for a run's summary.
  [[nodiscard]] std::string summary() const;
};

/// An organized scan and how it was made.
struct OrganizedCloud {
  OrganizedScan scan;        ///< rings x columns of the model; empty cells kNoReturn
  CloudOrganizeStats stats;  ///< counts and binning error
};

/// Bins unorganized points into a sensor model's rings x columns. A point's ring is the ring
/// whose elevation, seen from that ring's beam origin (model.vertical_offset_m), is nearest to
/// the point's; its column is its firing azimuth (less the ring's azimuth offset, and its firing
/// delay's turn when asked) on the options' grid. When two points fall into one cell the nearer
/// return (smaller range) is kept, as the decoders keep the strongest/first of a dual return
/// pair never two; the other is counted as collided. Points keep their coordinates; ranges are
/// measured from the ring's beam origin; cells where nothing fell stay kNoReturn.
class CloudOrganizer {
 public:
  /// Throws core::ConfigError on an invalid model or options.
  explicit CloudOrganizer(SensorModel model, CloudOrganizerOptions options = {});
  /// Organizes one cloud (intensity and time_ns must be empty or one per point, else
  /// core::InputError).
  [[nodiscard]] OrganizedCloud organize(const UnorganizedCloud& cloud) const;
  /// The model the clouds are organized into.
  [[nodiscard]] const SensorModel& model() const { return model_; }
  /// The options.
  [[nodiscard]] const CloudOrganizerOptions& options() const { return options_; }

 private:
  SensorModel model_;
  CloudOrganizerOptions options_;
  int columns_{0};
  double step_rad_{0.0};
  bool has_offsets_{false};
  std::vector<double> below_rad_;         // per ring: allowed residual below it
  std::vector<double> above_rad_;         // per ring: allowed residual above it
  std::vector<double> column_shift_rad_;  // per ring: added to the point azimuth before binning

  // Whether the cloud's points fit the model's beam offsets better than beams from the origin.
  [[nodiscard]] bool offsets_fit_better(const UnorganizedCloud& cloud) const;
  // Column azimuths on the grid; stamps as stamp_columns gives them at the nominal column
  // period.
  void set_columns(OrganizedScan& scan, const std::vector<std::int64_t>& first_ns,
                   std::int64_t stamp_ns) const;
};

/// Marks a column without a point time in stamp_columns' first_ns.
inline constexpr std::int64_t kNoColumnTime = std::numeric_limits<std::int64_t>::max();

/// Column stamps of a scan organized from points: a column's earliest point time where it has
/// one (first_ns[c], kNoColumnTime for none; first_ns empty when the points carry no times),
/// else continued at period_ns from the nearest timed column before it (after it, for the
/// columns before the first timed one), else stamp_ns + c * period_ns. Shared by
/// CloudOrganizer and io::PointCloud2Organizer.
void stamp_columns(OrganizedScan& scan, const std::vector<std::int64_t>& first_ns,
                   std::int64_t stamp_ns, double period_ns);

/// The valid cells of an organized scan as an unorganized cloud, ring by ring (each point's time
/// its column's stamp): what drivers without a ring field publish.
UnorganizedCloud flatten_scan(const OrganizedScan& scan);

/// Per-ring elevation (degrees, bottom ring first) of an organized scan: the mean over each
/// ring's valid points, rings without points interpolated; throws core::InputError naming `name`
/// when fewer than two rings have points or the rings are not ordered by elevation.
std::vector<double> measure_elevations_deg(const OrganizedScan& scan, const std::string& name);

/// A generic sensor measured on an unorganized cloud: ring elevations from the peaks of its
/// elevation histogram, refined by measure_elevations_deg over the cloud organized with them;
/// columns from the median azimuth spacing of neighbouring points within a ring, unless
/// `columns` > 0. Throws core::InputError naming `name` when fewer than two rings stand out.
SensorModel measure_cloud_sensor(const UnorganizedCloud& cloud, const std::string& name,
                                 double scan_rate_hz = 10.0, int columns = 0);

}  // namespace ringtrack::core
