#pragma once
/// The Velodyne packet inputs (pcap/pcapng files, live UDP) as ScanSources, and the options
/// packet inputs share. Front ends (`ringtrack run`, `ringtrack convert`) open every input
/// through io::open_source (scan_source.hpp), which calls these for Velodyne packets.

#include <atomic>
#include <cstddef>
#include <memory>
#include <string>

#include "ringtrack/io/source.hpp"
#include "ringtrack/io/velodyne_decoder.hpp"
#include "ringtrack/io/velodyne_pcap_source.hpp"
#include "ringtrack/io/velodyne_udp_source.hpp"

namespace ringtrack::io {

/// Everything a packet input needs: decoding, pcap ports, the UDP queue and the interrupt flag.
struct VelodyneSourceOptions {
  VelodyneDecoderOptions decoder;
  VelodynePcapOptions pcap;
  std::size_t udp_max_queued_scans{2};
  /// Live input: when set and true, next() stops the source and returns the remaining scans
  /// (set it from a SIGINT handler).
  const std::atomic<bool>* interrupt{nullptr};
};

/// A pcap/pcapng capture of Velodyne packets; throws core::InputError / core::ConfigError.
std::unique_ptr<ScanSource> open_velodyne_pcap_source(const std::string& path,
                                                      const VelodyneSourceOptions& options);
/// Live Velodyne packets from udp://HOST:PORT; throws core::InputError / core::ConfigError.
std::unique_ptr<ScanSource> open_velodyne_udp_source(const std::string& url,
                                                     const VelodyneSourceOptions& options);

}  // namespace ringtrack::io
