#pragma once
// Writes Ouster lidar packets from the software user manual's layouts (independently of the
// decoder), for round trips and hostile-input tests.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace ringtrack::test {

/// Pixel contents.
struct OusterEcho {
  std::uint32_t range_mm{0};  ///< as the profile can hold it (RNG15: a multiple of 8)
  std::uint32_t range2_mm{0};
  std::uint8_t reflectivity{0};
  std::uint8_t reflectivity2{7};  ///< the second return's (_DUAL)
};

/// Packet layout choices.
struct OusterEncoderOptions {
  std::string profile{"RNG19_RFL8_SIG16_NIR16"};  ///< or LEGACY, ..._DUAL, RNG15_RFL8_NIR8
  int pixels_per_column{16};
  int columns_per_packet{16};
  int frame_id{7};
};

/// Encodes one packet of columns first_m .. first_m + columns_per_packet - 1, every column valid.
std::vector<std::uint8_t> encode_ouster_packet(
    const OusterEncoderOptions& options, int first_m, std::int64_t first_stamp_ns,
    const std::function<OusterEcho(int m, int beam)>& echo);

/// A metadata JSON for the options: altitudes from +15 down in 2 deg steps, azimuths
/// alternating +-1.5 deg, shifts 0, 4, 8, 12 repeating, origin offset 15 mm, transform of an
/// OS sensor (rotation by 180 deg about z, 36.18 mm up), 1024 x 10.
std::string ouster_metadata_json(const OusterEncoderOptions& options);

}  // namespace ringtrack::test
