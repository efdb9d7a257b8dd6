#pragma once
/// UDP datagrams from .pcap / .pcapng capture files, through libpcap.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>

#include "ringtrack/core/error.hpp"

struct pcap;  // libpcap's handle (pcap_t), kept out of this header

namespace ringtrack::io {

/// One IPv4 UDP datagram of a capture.
struct UdpDatagram {
  std::span<const std::uint8_t> payload;  ///< valid until the next call to PcapReader::next
  std::int64_t stamp_ns{0};               ///< capture time, ns since the epoch
  std::uint32_t src_ip{0};                ///< host byte order
  std::uint32_t dst_ip{0};
  std::uint16_t src_port{0};
  std::uint16_t dst_port{0};
  std::uint64_t frame{0};  ///< 1-based frame number in the file
};

/// Counters of the frames a reader skipped, and how the file ended.
struct PcapStats {
  std::uint64_t frames{0};         ///< frames read
  std::uint64_t udp_datagrams{0};  ///< IPv4 UDP datagrams returned
  std::uint64_t non_ipv4{0};       ///< ARP, IPv6, other ether types or link families
  std::uint64_t non_udp{0};        ///< IPv4 but not UDP (TCP, ICMP, ...)
  std::uint64_t fragments{0};      ///< fragmented IPv4 datagrams (not reassembled)
  std::uint64_t short_frames{0};   ///< captured bytes shorter than the headers claim (snaplen)
  bool truncated{false};           ///< the file ended inside a record
  std::string truncation_message;  ///< libpcap's description of the truncation
};

/// Reads IPv4 UDP datagrams from a classic pcap or pcapng file (libpcap reads both) with
/// Ethernet (with VLAN tags), Linux cooked (SLL, SLL2), raw IP or BSD loopback link types.
/// Other traffic is skipped and counted.
class PcapReader {
 public:
  /// Opens the file; throws core::InputError naming it when it cannot be read as a capture or
  /// its link type is unsupported. With allow_truncated, a file that ends inside a record ends
  /// the stream (stats().truncated); otherwise that throws core::InputError.
  explicit PcapReader(const std::filesystem::path& path, bool allow_truncated = true);
  ~PcapReader();
  PcapReader(const PcapReader&) = delete;
  PcapReader& operator=(const PcapReader&) = delete;

  /// The next UDP datagram; false at the end of the file.
  bool next(UdpDatagram& out);
  /// libpcap's DLT link type of the file.
  [[nodiscard]] int link_type() const { return link_type_; }
  /// Counters.
  [[nodiscard]] const PcapStats& stats() const { return stats_; }
  /// The file's path as given.
  [[nodiscard]] const std::string& path() const { return path_; }

 private:
  struct Closer {
    void operator()(pcap* handle) const;
  };
  bool parse_frame(const std::uint8_t* data, std::size_t size, UdpDatagram& out);

  std::string path_;
  std::unique_ptr<pcap, Closer> handle_;
  int link_type_{0};
  bool allow_truncated_{true};
  bool done_{false};
  PcapStats stats_;
};

/// Feeds a datagram's payload to a sensor decoder (anything with add_packet(payload, stamp_ns));
/// a core::InputError it throws is thrown again with the capture's path and the frame in front.
template <class Decoder>
void add_packet_from(const PcapReader& reader, const UdpDatagram& datagram, Decoder& decoder) {
  try {
    decoder.add_packet(datagram.payload, datagram.stamp_ns);
  } catch (const core::InputError& e) {
    throw core::InputError(reader.path() + " (frame " + std::to_string(datagram.frame) +
                           "): " + e.what());
  }
}

/// Feeds the capture's first datagram to `port` to `probe` (a fresh decoder), so that a packet
/// of another model or one that does not fit the calibration is reported when a source opens
/// the file, before a front end creates any output, rather than at its first scan.
template <class Decoder>
void check_first_packet(const std::filesystem::path& path, std::uint16_t port, Decoder& probe) {
  PcapReader reader(path, true);
  UdpDatagram datagram;
  while (reader.next(datagram)) {
    if (datagram.dst_port != port) continue;
    add_packet_from(reader, datagram, probe);
    return;
  }
}

/// Parses one IPv4 packet (from its IP header) into a UDP datagram; false (with the reason in
/// `why`: "non-udp", "fragment", "short", "non-ipv4") when it is not a complete UDP datagram.
bool parse_ipv4_udp(const std::uint8_t* data, std::size_t size, UdpDatagram& out, const char*& why);

}  // namespace ringtrack::io
