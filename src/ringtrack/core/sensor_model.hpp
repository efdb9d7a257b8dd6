#pragma once
/// Geometry and timing of a spinning multi-ring LiDAR.

#include <Eigen/Core>
#include <span>
#include <string>
#include <vector>

namespace ringtrack::core {

/// Ring elevations, offsets and firing timing of a spinning LiDAR. Rings are ordered bottom
/// (lowest elevation) to top; `laser_of_ring` maps back to the sensor's own laser numbering.
struct SensorModel {
  std::string name;                        ///< e.g. "VLP-16"
  std::vector<double> elevation_rad;       ///< per ring, ascending
  std::vector<double> vertical_offset_m;   ///< per ring, added to z (VLP-16 beam origins differ)
  std::vector<double> azimuth_offset_rad;  ///< per ring, added to the firing azimuth (VLP-32C)
  std::vector<int> laser_of_ring;          ///< per ring, the laser id in the sensor's data order
  std::vector<double> firing_offset_us;    ///< per ring, time of its firing within a sequence
  double firing_sequence_us{55.296};       ///< time of one firing sequence (one column)
  double scan_rate_hz{10.0};               ///< revolutions per second
  double min_range_m{0.3};                 ///< closer returns are invalid
  double max_range_m{100.0};               ///< farther returns are invalid

  /// Number of rings.
  [[nodiscard]] int rings() const { return static_cast<int>(elevation_rad.size()); }
  /// Azimuth advance between two columns (one firing sequence).
  [[nodiscard]] double azimuth_step_rad() const;
  /// Columns in one revolution: 2*pi / azimuth step, rounded.
  [[nodiscard]] int columns() const;
  /// Ring of a laser id (inverse of laser_of_ring).
  [[nodiscard]] int ring_of_laser(int laser) const;
  /// Sensor-frame point of a return: azimuth counter-clockwise from +x about +z.
  [[nodiscard]] Eigen::Vector3f point(int ring, double azimuth_rad, double range_m) const;
  /// Throws core::Error when the tables are inconsistent (sizes, order, ranges).
  void validate() const;

  /// Velodyne VLP-16 (Puck): 16 rings, -15..15 deg in 2 deg steps, 100 m.
  static SensorModel vlp16(double scan_rate_hz = 10.0);
  /// Velodyne VLP-32C (Ultra Puck): 32 rings, -25..15 deg, 200 m.
  static SensorModel vlp32c(double scan_rate_hz = 10.0);
  /// Velodyne HDL-32E: 32 rings, -30.67..10.67 deg, 100 m.
  static SensorModel hdl32e(double scan_rate_hz = 10.0);
  /// Velodyne HDL-64E S2 (KITTI's sensor), nominal: 32 upper rings +2..-8.33 deg in 1/3 deg
  /// steps, 32 lower rings -8.83..-24.33 deg in 1/2 deg steps, beam origins 0.20 / 0.11 m up,
  /// 120 m. For point clouds (no HDL-64E packet decoder); see docs/inputs.md for its error.
  static SensorModel hdl64e(double scan_rate_hz = 10.0);
  /// A generic sensor from a list of elevations (degrees, any order) and a column count.
  static SensorModel generic(const std::vector<double>& elevations_deg, int columns,
                             double scan_rate_hz = 10.0, double max_range_m = 100.0);
  /// A built-in model by name ("vlp16", "VLP-16", "vlp32c", "hdl32e", "hdl64e"; case and
  /// punctuation ignored). Throws core::Error listing the names for unknown ones, and saying
  /// what is needed for the known sensors without nominal geometry (Hesai, Ouster).
  static SensorModel by_name(const std::string& name, double scan_rate_hz = 10.0);
};

/// One row of the table of sensor names ringtrack knows (`--sensor`, sequence.yaml, Python).
struct BuiltInSensor {
  const char* name;     ///< the canonical spelling, e.g. "hdl64e", "PandarXT32"
  const char* family;   ///< "Velodyne", "Hesai", "Ouster"
  const char* aliases;  ///< other accepted spellings, normalized (lower case, no punctuation)
  /// The nominal geometry; nullptr when the library has none and the sensor's file is needed.
  SensorModel (*make)(double scan_rate_hz);
  const char* needs;  ///< without geometry: what provides it (for errors and `ringtrack sensors`)
};

/// The table, Velodyne first; the rows with geometry are what by_name builds.
std::span<const BuiltInSensor> built_in_sensors();
/// The names with geometry, e.g. "vlp16, vlp32c, hdl32e or hdl64e" (for messages).
std::string built_in_model_list();

}  // namespace ringtrack::core
