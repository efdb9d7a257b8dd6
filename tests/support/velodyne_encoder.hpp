#pragma once
/// Test support: a Velodyne data-packet encoder (the decoder's oracle) and pcap/pcapng writers.
/// Written from the user manuals' packet description, independently of src/ringtrack/io.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace ringtrack::test {

/// What the encoded sensor is and how it turns.
struct VelodyneEncoderOptions {
  std::uint8_t product{0x22};      ///< 0x22 VLP-16, 0x28 VLP-32C, 0x21 HDL-32E
  std::uint8_t return_mode{0x37};  ///< 0x37 strongest, 0x38 last, 0x39 dual
  double rpm{600.0};
  double start_azimuth_deg{0.0};  ///< azimuth of sequence 0's first firing
  double start_time_us{0.0};      ///< sensor time (us past the hour) of sequence 0
  std::int64_t host_epoch_ns{1'700'000'000'000'000'000};  ///< host time at sensor time 0
};

/// One echo as the packet stores it.
struct VelodyneEcho {
  std::uint16_t distance_raw{0};  ///< 2 mm units (VLP-32C: 4 mm), 0 = no return
  std::uint8_t reflectivity{0};
};

/// The echoes of one laser in one firing sequence: `first` is the single return (or, in dual
/// mode, the last return); `second` is the dual pair's second block (ignored in single mode).
struct VelodyneEchoPair {
  VelodyneEcho first;
  VelodyneEcho second;
};

/// Echoes of laser `laser` (data order) in firing sequence `sequence` (counted from 0).
using VelodyneEchoFn = std::function<VelodyneEchoPair(long long sequence, int laser)>;

/// One encoded data packet.
struct EncodedVelodynePacket {
  std::vector<std::uint8_t> payload;  ///< 1206 bytes
  std::int64_t host_stamp_ns{0};      ///< receive time: the end of its last firing sequence
  long long first_sequence{0};        ///< firing sequence of its first block
};

/// Encodes firing sequences into data packets: block azimuths are the exact azimuths rounded to
/// 0.01 deg, time stamps the exact sensor times rounded to 1 us.
class VelodyneEncoder {
 public:
  explicit VelodyneEncoder(VelodyneEncoderOptions options);
  /// Lasers per firing sequence (16 or 32).
  [[nodiscard]] int lasers() const { return lasers_; }
  /// Firing sequences per block (2 for the VLP-16, else 1).
  [[nodiscard]] int sequences_per_block() const { return lasers_ == 16 ? 2 : 1; }
  /// Firing sequences per packet (halved in dual mode).
  [[nodiscard]] int sequences_per_packet() const;
  /// Duration of one firing sequence, us.
  [[nodiscard]] double sequence_us() const { return sequence_us_; }
  /// Exact azimuth (deg, [0, 360)) of a sequence's first firing.
  [[nodiscard]] double sequence_azimuth_deg(long long sequence) const;
  /// Azimuth advance per firing sequence, deg.
  [[nodiscard]] double advance_deg() const;
  /// Sensor time (us past the hour, not wrapped) of a sequence's first firing.
  [[nodiscard]] double sequence_time_us(long long sequence) const;
  /// Encodes packets number first_packet .. first_packet + packets - 1.
  [[nodiscard]] std::vector<EncodedVelodynePacket> encode(long long first_packet, long long packets,
                                                          const VelodyneEchoFn& echoes) const;
  /// Options.
  [[nodiscard]] const VelodyneEncoderOptions& options() const { return options_; }

 private:
  VelodyneEncoderOptions options_;
  int lasers_{16};
  double sequence_us_{55.296};
};

/// Link layers the pcap writers can frame datagrams in.
enum class PcapLink { kEthernet, kLinuxSll, kLinuxSll2, kRawIp, kNull };

/// One captured frame (link header included).
struct PcapFrame {
  std::vector<std::uint8_t> bytes;
  std::int64_t stamp_ns{0};
};

/// An IPv4 UDP datagram framed for `link` (sender 192.168.1.201, the sensor's default address).
PcapFrame udp_frame(PcapLink link, const std::vector<std::uint8_t>& payload, std::uint16_t dst_port,
                    std::int64_t stamp_ns, std::uint16_t src_port = 2368);
/// A non-UDP IPv4 frame (TCP header and some bytes) for `link`.
PcapFrame tcp_frame(PcapLink link, std::int64_t stamp_ns);
/// An Ethernet ARP request (Ethernet only).
PcapFrame arp_frame(std::int64_t stamp_ns);
/// An IPv6 UDP datagram to `dst_port` (Ethernet only).
PcapFrame ipv6_udp_frame(const std::vector<std::uint8_t>& payload, std::uint16_t dst_port,
                         std::int64_t stamp_ns);
/// The link-type number a pcap file header stores for `link`.
std::uint32_t pcap_linktype(PcapLink link);
/// Writes a classic pcap file (microsecond or nanosecond time stamps).
void write_pcap(const std::filesystem::path& path, PcapLink link,
                const std::vector<PcapFrame>& frames, bool nanoseconds = false);
/// Writes a pcapng file: section header, one interface, enhanced packet blocks (us stamps).
void write_pcapng(const std::filesystem::path& path, PcapLink link,
                  const std::vector<PcapFrame>& frames);
/// Frames every encoded packet as UDP to `port` on `link`.
std::vector<PcapFrame> frame_packets(PcapLink link,
                                     const std::vector<EncodedVelodynePacket>& packets,
                                     std::uint16_t port = 2368);

}  // namespace ringtrack::test
