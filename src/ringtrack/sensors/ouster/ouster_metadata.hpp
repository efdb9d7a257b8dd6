#pragma once
/// The metadata JSON of an Ouster sensor (what the sensor reports and ouster-sdk saves beside a
/// recording): beam angles, beam origin offset (beam_to_lidar_transform or
/// lidar_origin_to_beam_origin_mm), lidar-to-sensor transform and the packet data format. See
/// docs/ouster.md.

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "ringtrack/core/sensor_model.hpp"

namespace ringtrack::sensors::ouster {

/// Lidar packet profiles (udp_profile_lidar).
enum class OusterProfile : std::uint8_t {
  kLegacy,                   ///< firmware < 2.2 default: per-column headers and status words
  kRng19Rfl8Sig16Nir16,      ///< single return, 12-byte pixels
  kRng19Rfl8Sig16Nir16Dual,  ///< two returns, 16-byte pixels
  kRng15Rfl8Nir8,            ///< low data rate, 4-byte pixels, range in 8 mm units
};

/// Name of a profile as the metadata spells it.
std::string to_string(OusterProfile profile);

/// What ringtrack needs of the metadata.
struct OusterMetadata {
  std::string source;                     ///< file name (for messages)
  std::string product;                    ///< e.g. "OS-1-128" (prod_line), if present
  std::vector<double> beam_altitude_deg;  ///< per beam (row), as sent
  std::vector<double> beam_azimuth_deg;   ///< per beam, offset from the encoder angle
  /// Distance from the lidar origin to the beam origin, subtracted from ranges:
  /// lidar_origin_to_beam_origin_mm, or the length of beam_to_lidar_transform's translation.
  double origin_to_beam_mm{0};
  /// The beam origin's offset along the encoder direction and its height (mm): the translation
  /// of beam_to_lidar_transform when the metadata has one (newer firmware), else
  /// (lidar_origin_to_beam_origin_mm, 0).
  double beam_x_mm{0};
  double beam_z_mm{0};
  std::array<double, 16> lidar_to_sensor{};  ///< row-major 4x4, translation in mm
  int columns_per_frame{1024};
  int columns_per_packet{16};
  int pixels_per_column{0};
  std::vector<int> pixel_shift_by_row;        ///< destaggering shift per beam
  std::array<int, 2> column_window{0, 1023};  ///< first and last measurement id sent
  OusterProfile profile{OusterProfile::kLegacy};
  double scan_rate_hz{10.0};  ///< from lidar_mode "WxR"

  /// Bytes of a lidar packet of this format.
  [[nodiscard]] std::size_t packet_bytes() const;
  /// Bytes of one pixel.
  [[nodiscard]] std::size_t pixel_bytes() const;
  /// True when measurement id m is inside the column window (which may wrap).
  [[nodiscard]] bool in_window(int m) const;
};

/// Parses metadata text; throws core::InputError naming `source` and the missing or malformed
/// key (e.g. "os.json: metadata has no 'beam_altitude_angles'").
OusterMetadata parse_ouster_metadata(const std::string& text, const std::string& source);
/// Reads and parses a metadata file; throws core::InputError.
OusterMetadata read_ouster_metadata(const std::filesystem::path& path);

/// The sensor model: rings = beams sorted bottom to top, azimuth offsets in ringtrack's
/// counter-clockwise convention, columns per frame, the frame rate. Its point() ignores the beam
/// origin offset and the lidar-to-sensor transform; the decoder applies both.
core::SensorModel ouster_sensor_model(const OusterMetadata& metadata);

}  // namespace ringtrack::sensors::ouster
