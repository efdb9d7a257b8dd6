#pragma once
// Writes Hesai point-cloud packets from the user manuals' layouts, independently of the decoder's
// format table, for round-trip and hostile-input tests.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace ringtrack::test {

/// One channel record.
struct HesaiEcho {
  std::uint16_t distance_raw{0};  ///< 4 mm units, 0 = no return
  std::uint8_t reflectivity{0};
};

/// Encoder settings.
struct HesaiEncoderOptions {
  std::string model{"PandarXT32"};  ///< Pandar40P, Pandar64, PandarQT64, PandarXT16, PandarXT32
  std::uint8_t return_mode{0x37};   ///< 0x37 strongest, 0x38 last, 0x39 dual (last, strongest)
  bool udp_sequence{true};          ///< append the 4-byte sequence number
  double start_azimuth_deg{0.0};    ///< azimuth of the first firing
  double scan_rate_hz{10.0};
};

/// Packet writer. Echo callbacks get (firing index from the start, channel) and return the
/// first block's and (dual) second block's record.
class HesaiEncoder {
 public:
  explicit HesaiEncoder(HesaiEncoderOptions options);
  /// Channels of the model.
  [[nodiscard]] int channels() const { return channels_; }
  /// Firings (columns) per packet.
  [[nodiscard]] int firings_per_packet() const;
  /// Firings per revolution.
  [[nodiscard]] int firings_per_revolution() const;
  /// Azimuth (0.01 deg units) written for a firing.
  [[nodiscard]] std::uint16_t azimuth_of(long long firing) const;
  /// Encodes `count` packets starting with packet `first`.
  std::vector<std::vector<std::uint8_t>> encode(
      long long first, int count,
      const std::function<std::pair<HesaiEcho, HesaiEcho>(long long, int)>& echo) const;

 private:
  HesaiEncoderOptions o_;
  int channels_{32};
  int blocks_{8};
  int columns_10hz_{2000};
};

/// A calibration CSV for `channels` channels: elevations from +15 down in 1 deg steps (the
/// first channel is the top one, as in Hesai's files) and alternating azimuth offsets.
std::string hesai_calibration_csv(int channels);

}  // namespace ringtrack::test
