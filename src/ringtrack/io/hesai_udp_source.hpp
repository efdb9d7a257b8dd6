#pragma once
/// Live Hesai point-cloud packets (udp://HOST:2368) with the sensor's angle-correction file: the
/// UDP receiver of udp_packet_source.hpp with the Hesai decoder. See docs/hesai.md.

#include <memory>
#include <string>

#include "ringtrack/io/source.hpp"
#include "ringtrack/io/udp_packet_source.hpp"
#include "ringtrack/io/velodyne_source.hpp"
#include "ringtrack/sensors/hesai/hesai_decoder.hpp"

namespace ringtrack::io {

/// Receives Hesai point-cloud packets on a UDP socket and decodes them on its own thread.
class HesaiUdpSource final : public UdpPacketSource {
 public:
  /// Binds the socket and starts receiving; throws core::InputError (address in use),
  /// core::ConfigError on bad options (unknown model, empty calibration).
  HesaiUdpSource(const UdpOptions& options, sensors::hesai::HesaiDecoderOptions decoder_options);
  /// Decoder counters (a snapshot).
  [[nodiscard]] sensors::hesai::HesaiDecoderStats decoder_stats() const;
};

/// Live Hesai packets from udp://HOST:PORT (PORT defaults to 2368, the sensors' factory setting)
/// as a ScanSource, with the queue length and interrupt flag of `live`; throws
/// core::InputError / core::ConfigError.
std::unique_ptr<ScanSource> open_hesai_udp_source(const std::string& url,
                                                  sensors::hesai::HesaiDecoderOptions decoder,
                                                  const VelodyneSourceOptions& live);

}  // namespace ringtrack::io
