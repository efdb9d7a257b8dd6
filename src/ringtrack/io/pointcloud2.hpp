#pragma once
/// sensor_msgs/PointCloud2 messages (ROS 1 or CDR serialized) and their conversion into
/// organized scans: clouds with a ring field, or organized clouds (one row per ring).

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ringtrack/core/cloud_organizer.hpp"
#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/io/rosbag_reader.hpp"

namespace ringtrack::io {

/// sensor_msgs/PointField datatypes.
enum class PointFieldType : std::uint8_t {
  kInt8 = 1,
  kUint8 = 2,
  kInt16 = 3,
  kUint16 = 4,
  kInt32 = 5,
  kUint32 = 6,
  kFloat32 = 7,
  kFloat64 = 8,
};

/// Bytes of one element of a datatype (0 for unknown types).
std::size_t point_field_type_bytes(std::uint8_t datatype);

/// One field of a point record.
struct PointField {
  std::string name;
  std::uint32_t offset{0};   ///< byte offset in the point record
  std::uint8_t datatype{0};  ///< a PointFieldType
  std::uint32_t count{1};    ///< elements
};

/// A parsed sensor_msgs/PointCloud2; `data` points into the serialized message.
struct PointCloud2 {
  std::int64_t stamp_ns{0};  ///< header stamp
  std::string frame_id;
  std::uint32_t height{1};  ///< rows (1: unorganized)
  std::uint32_t width{0};   ///< points per row
  std::vector<PointField> fields;
  bool is_bigendian{false};
  std::uint32_t point_step{0};  ///< bytes per point
  std::uint32_t row_step{0};    ///< bytes per row
  std::span<const std::uint8_t> data;
  bool is_dense{false};

  /// The field with this name, or nullptr.
  [[nodiscard]] const PointField* find(const std::string& name) const;
  /// Reads element 0 of `field` of point (row, column) as a double.
  [[nodiscard]] double value(const PointField& field, std::uint32_t row,
                             std::uint32_t column) const;
};

/// Parses a serialized sensor_msgs/PointCloud2 and checks its layout (fields inside the point
/// record, known datatypes, data large enough, little endian); throws core::InputError naming
/// `where` and what was expected.
PointCloud2 parse_pointcloud2(std::span<const std::uint8_t> message, RosSerialization serialization,
                              const std::string& where);

/// How clouds become organized scans.
struct PointCloud2Options {
  /// vlp16 | vlp32c | hdl32e; "" = vlp16 when the cloud has at most 16 rings, else an error
  /// asking for the model.
  std::string model;
  double scan_rate_hz{10.0};       ///< revolutions per second; sets the scan's columns
  double cut_azimuth_deg{0.0};     ///< column 0 starts here (Velodyne azimuth: clockwise, 0 = +x)
  std::string ring_field{"ring"};  ///< ring index (0 = bottom), as velodyne_pointcloud writes it
};

/// Counters of PointCloud2Organizer.
struct PointCloud2Stats {
  std::uint64_t clouds{0};           ///< clouds organized
  std::uint64_t points{0};           ///< points read
  std::uint64_t empty_points{0};     ///< NaN / zero points (no return), skipped
  std::uint64_t dropped_points{0};   ///< points that lost their cell to a nearer point
  std::uint64_t bad_ring_points{0};  ///< ring values outside the model's rings, skipped
  /// Unorganized clouds without a ring field: what core::CloudOrganizer did (also counted above:
  /// clouds, points, empty points and points that lost their cell).
  core::CloudOrganizeTotals ringless;
};

/// Points that already carry their ring, as many drivers and datasets hold them (sensor frame).
struct RingedPoints {
  std::span<const Eigen::Vector3f> xyz;   ///< metres
  std::span<const std::uint16_t> ring;    ///< per point, 0 = bottom ring of the model
  std::span<const float> intensity;       ///< per point, or empty (0)
  std::span<const std::int64_t> time_ns;  ///< per point, absolute, or empty (nominal column times)
  std::int64_t stamp_ns{0};               ///< the cloud's stamp (the first column's without times)
};

/// Organizes points with rings into the model's rings x columns exactly as PointCloud2Organizer
/// does for a cloud with a ring field (column by firing azimuth clockwise from
/// options.cut_azimuth_deg, range from the ring's beam origin, the nearer point kept per cell),
/// for users who already have points in memory. options.model and ring_field are not used.
/// Throws core::InputError when the spans' sizes differ. Counts into stats when given.
core::OrganizedScan organize_points(const RingedPoints& points, const core::SensorModel& model,
                                    const PointCloud2Options& options = {},
                                    PointCloud2Stats* stats = nullptr);

/// Turns point clouds into OrganizedScans of the sensor model's rings x columns. A point's
/// ring is its ring field, or, without one, its row of an organized cloud (rows ordered bottom
/// to top by their points' elevations). Its column is its firing azimuth (the point's azimuth
/// less the laser's azimuth offset and firing delay) counted clockwise from the cut azimuth in
/// steps of the model's azimuth step, like the packet decoder's columns. Its range is the
/// `distance` field, else the distance from the ring's beam origin (the model's vertical offset).
/// Points keep their coordinates; a cell hit twice keeps the nearer point (the other is counted).
/// Unorganized clouds without a ring field go through core::CloudOrganizer instead: ring by
/// elevation, column by firing azimuth on the same clockwise grid from the cut azimuth; their
/// model is the named one, else measured on the first cloud (core::measure_cloud_sensor).
class PointCloud2Organizer {
 public:
  /// Throws core::ConfigError on bad options.
  explicit PointCloud2Organizer(PointCloud2Options options = {});
  /// The organized scan of one cloud; throws core::InputError naming `where` when the cloud has
  /// no x/y/z fields, neither a ring field nor an organized layout, or contradicts the model.
  core::OrganizedScan organize(const PointCloud2& cloud, const std::string& where);
  /// True once the model is known (named, or chosen at the first cloud).
  [[nodiscard]] bool has_model() const { return model_.has_value(); }
  /// The sensor model; throws core::Error before has_model().
  [[nodiscard]] const core::SensorModel& model() const;
  /// Counters.
  [[nodiscard]] const PointCloud2Stats& stats() const { return stats_; }

 private:
  core::OrganizedScan organize_ringless(const PointCloud2& cloud, const std::string& where);

  PointCloud2Options options_;
  std::optional<core::SensorModel> model_;
  std::optional<core::CloudOrganizer> ringless_;
  PointCloud2Stats stats_;
};

}  // namespace ringtrack::io
