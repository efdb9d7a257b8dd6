#pragma once
/// Live Velodyne packets from a UDP socket (the receiver of udp_packet_source.hpp with the
/// Velodyne decoder).

#include "ringtrack/io/udp_packet_source.hpp"
#include "ringtrack/io/velodyne_decoder.hpp"

namespace ringtrack::io {

/// Where to listen and how much to buffer (port 2368 by default).
using VelodyneUdpOptions = UdpOptions;
/// Socket counters.
using VelodyneUdpStats = UdpStats;

/// Receives Velodyne data packets on a UDP socket and decodes them on its own thread.
class VelodyneUdpSource final : public UdpPacketSource {
 public:
  /// Binds the socket and starts receiving; throws core::InputError when the address cannot be
  /// bound, core::ConfigError on bad options.
  explicit VelodyneUdpSource(VelodyneUdpOptions options,
                             VelodyneDecoderOptions decoder_options = {});
  /// Decoder counters (a snapshot).
  [[nodiscard]] VelodyneDecoderStats decoder_stats() const;
};

}  // namespace ringtrack::io
