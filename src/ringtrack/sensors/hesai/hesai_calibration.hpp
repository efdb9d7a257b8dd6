#pragma once
/// The angle-correction file of a Hesai sensor: per channel an elevation and an azimuth offset
/// in degrees (CSV with a header line, then "channel,elevation,azimuth" rows, channels 1..N).

#include <filesystem>
#include <string>
#include <vector>

#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/sensors/hesai/hesai_format.hpp"

namespace ringtrack::sensors::hesai {

/// Per-channel angles, index = channel - 1 (the packet's record order).
struct HesaiCalibration {
  std::string source;                 ///< file name (for messages)
  std::vector<double> elevation_deg;  ///< per channel
  std::vector<double> azimuth_deg;    ///< per channel, added to the block azimuth (clockwise)

  /// Number of channels.
  [[nodiscard]] int channels() const { return static_cast<int>(elevation_deg.size()); }
  /// Throws core::InputError naming the file when it does not hold exactly the format's channels.
  void check(const HesaiFormat& format) const;
};

/// Parses an angle-correction CSV; throws core::InputError naming `source`, the line and what
/// was expected (non-numeric values, repeated or missing channels, angles out of range).
HesaiCalibration parse_hesai_calibration(const std::string& text, const std::string& source);
/// Reads and parses a file; throws core::InputError.
HesaiCalibration read_hesai_calibration(const std::filesystem::path& path);

/// The sensor model of a format and calibration: rings sorted bottom to top, per-ring azimuth
/// offsets in ringtrack's counter-clockwise convention, columns from the scan rate.
core::SensorModel hesai_sensor_model(const HesaiFormat& format, const HesaiCalibration& calibration,
                                     double scan_rate_hz);

}  // namespace ringtrack::sensors::hesai
