#pragma once
/// Live Ouster lidar packets (udp://HOST:7502) with the sensor's metadata JSON: the UDP receiver
/// of udp_packet_source.hpp with the Ouster decoder. See docs/ouster.md.

#include <memory>
#include <string>

#include "ringtrack/io/source.hpp"
#include "ringtrack/io/udp_packet_source.hpp"
#include "ringtrack/io/velodyne_source.hpp"
#include "ringtrack/sensors/ouster/ouster_decoder.hpp"

namespace ringtrack::io {

/// Ouster's lidar data port (IMU packets go to 7503, which is not bound).
inline constexpr std::uint16_t kOusterLidarPort = 7502;

/// Receives Ouster lidar packets on a UDP socket and decodes them on its own thread.
class OusterUdpSource final : public UdpPacketSource {
 public:
  /// Binds the socket and starts receiving; throws core::InputError (address in use, metadata
  /// that cannot give the selected return), core::ConfigError on bad options.
  OusterUdpSource(const UdpOptions& options, sensors::ouster::OusterMetadata metadata,
                  sensors::ouster::OusterDecoderOptions decoder_options = {});
  /// Decoder counters (a snapshot).
  [[nodiscard]] sensors::ouster::OusterDecoderStats decoder_stats() const;
};

/// Live Ouster packets from udp://HOST:PORT (PORT defaults to 7502) as a ScanSource, with the
/// queue length and interrupt flag of `live`; throws core::InputError / core::ConfigError.
std::unique_ptr<ScanSource> open_ouster_udp_source(const std::string& url,
                                                   sensors::ouster::OusterMetadata metadata,
                                                   sensors::ouster::OusterDecoderOptions decoder,
                                                   const VelodyneSourceOptions& live);

}  // namespace ringtrack::io
