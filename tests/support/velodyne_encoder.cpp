#include "support/velodyne_encoder.hpp"

#include <cmath>
#include <fstream>
#include <stdexcept>

namespace ringtrack::test {
namespace {

constexpr int kBlocks = 12;
constexpr std::size_t kBlockBytes = 100;
constexpr std::size_t kPacketBytes = 1206;

void put_le16(std::vector<std::uint8_t>& b, std::size_t at, std::uint32_t v) {
  b[at] = static_cast<std::uint8_t>(v & 0xFF);
  b[at + 1] = static_cast<std::uint8_t>((v >> 8) & 0xFF);
}

void push_le16(std::vector<std::uint8_t>& b, std::uint32_t v) {
  b.push_back(static_cast<std::uint8_t>(v & 0xFF));
  b.push_back(static_cast<std::uint8_t>((v >> 8) & 0xFF));
}

void push_le32(std::vector<std::uint8_t>& b, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b.push_back(static_cast<std::uint8_t>((v >> (8 * i)) & 0xFF));
}

void push_be16(std::vector<std::uint8_t>& b, std::uint32_t v) {
  b.push_back(static_cast<std::uint8_t>((v >> 8) & 0xFF));
  b.push_back(static_cast<std::uint8_t>(v & 0xFF));
}

void push_bytes(std::vector<std::uint8_t>& b, std::initializer_list<int> bytes) {
  for (int v : bytes) b.push_back(static_cast<std::uint8_t>(v));
}

std::vector<std::uint8_t> ipv4_packet(std::uint8_t protocol, const std::vector<std::uint8_t>& l4) {
  std::vector<std::uint8_t> ip;
  push_bytes(ip, {0x45, 0x00});
  push_be16(ip, static_cast<std::uint32_t>(20 + l4.size()));
  push_bytes(ip, {0x00, 0x00, 0x40, 0x00, 64, protocol, 0x00, 0x00});
  push_bytes(ip, {192, 168, 1, 201, 255, 255, 255, 255});
  std::uint32_t sum = 0;
  for (std::size_t i = 0; i < 20; i += 2)
    sum += static_cast<std::uint32_t>((ip[i] << 8) | ip[i + 1]);
  while (sum > 0xFFFF) sum = (sum & 0xFFFF) + (sum >> 16);
  const std::uint32_t checksum = ~sum & 0xFFFF;
  ip[10] = static_cast<std::uint8_t>(checksum >> 8);
  ip[11] = static_cast<std::uint8_t>(checksum & 0xFF);
  ip.insert(ip.end(), l4.begin(), l4.end());
  return ip;
}

std::vector<std::uint8_t> link_header(PcapLink link, std::uint16_t ether_type) {
  std::vector<std::uint8_t> h;
  switch (link) {
    case PcapLink::kEthernet:
      push_bytes(h, {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x60, 0x76, 0x88, 0x00, 0x00, 0x08});
      push_be16(h, ether_type);
      break;
    case PcapLink::kLinuxSll:
      push_bytes(h, {0x00, 0x01, 0x00, 0x01, 0x00, 0x06, 0x60, 0x76, 0x88, 0x00, 0x00, 0x08, 0, 0});
      push_be16(h, ether_type);
      break;
    case PcapLink::kLinuxSll2:
      push_be16(h, ether_type);
      push_bytes(h, {0, 0, 0, 0, 0, 2, 0x00, 0x01, 0x01, 0x06});
      push_bytes(h, {0x60, 0x76, 0x88, 0x00, 0x00, 0x08, 0, 0});
      break;
    case PcapLink::kRawIp:
      break;
    case PcapLink::kNull:
      push_le32(h, 2);
      break;  // AF_INET in the writer's (little) order
  }
  return h;
}

}  // namespace

VelodyneEncoder::VelodyneEncoder(VelodyneEncoderOptions options) : options_(options) {
  switch (options_.product) {
    case 0x28:
      lasers_ = 32;
      sequence_us_ = 55.296;
      break;  // VLP-32C: 16 firings of 2 lasers
    case 0x21:
      lasers_ = 32;
      sequence_us_ = 46.08;
      break;  // HDL-32E: 32 firings of 1.152 us
    default:
      lasers_ = 16;
      sequence_us_ = 55.296;
      break;  // VLP-16 layout
  }
}

int VelodyneEncoder::sequences_per_packet() const {
  const int firing_blocks = options_.return_mode == 0x39 ? kBlocks / 2 : kBlocks;
  return firing_blocks * sequences_per_block();
}

double VelodyneEncoder::advance_deg() const {
  return 360.0 * options_.rpm / 60.0 * sequence_us_ * 1e-6;
}

double VelodyneEncoder::sequence_azimuth_deg(long long sequence) const {
  double a =
      std::fmod(options_.start_azimuth_deg + static_cast<double>(sequence) * advance_deg(), 360.0);
  if (a < 0) a += 360.0;
  return a;
}

double VelodyneEncoder::sequence_time_us(long long sequence) const {
  return options_.start_time_us + static_cast<double>(sequence) * sequence_us_;
}

std::vector<EncodedVelodynePacket> VelodyneEncoder::encode(long long first_packet,
                                                           long long packets,
                                                           const VelodyneEchoFn& echoes) const {
  const bool dual = options_.return_mode == 0x39;
  const int per_block = sequences_per_block();
  const int per_packet = sequences_per_packet();
  std::vector<EncodedVelodynePacket> out;
  for (long long p = first_packet; p < first_packet + packets; ++p) {
    EncodedVelodynePacket packet;
    packet.first_sequence = p * per_packet;
    packet.payload.assign(kPacketBytes, 0);
    auto& b = packet.payload;
    for (int block = 0; block < kBlocks; ++block) {
      const int firing_block = dual ? block / 2 : block;
      const bool second = dual && (block % 2 == 1);
      const long long seq0 =
          packet.first_sequence + static_cast<long long>(firing_block) * per_block;
      const std::size_t at = static_cast<std::size_t>(block) * kBlockBytes;
      b[at] = 0xFF;
      b[at + 1] = 0xEE;
      const auto azimuth =
          static_cast<std::uint32_t>(std::llround(sequence_azimuth_deg(seq0) * 100.0) % 36000);
      put_le16(b, at + 2, azimuth);
      for (int s = 0; s < per_block; ++s) {
        for (int laser = 0; laser < lasers_; ++laser) {
          const VelodyneEchoPair pair = echoes(seq0 + s, laser);
          const VelodyneEcho& e = second ? pair.second : pair.first;
          const std::size_t rec = at + 4 + static_cast<std::size_t>(s * lasers_ + laser) * 3;
          put_le16(b, rec, e.distance_raw);
          b[rec + 2] = e.reflectivity;
        }
      }
    }
    const long long stamp = std::llround(sequence_time_us(packet.first_sequence));
    const auto wrapped =
        static_cast<std::uint32_t>(((stamp % 3'600'000'000LL) + 3'600'000'000LL) % 3'600'000'000LL);
    for (int i = 0; i < 4; ++i)
      b[1200 + static_cast<std::size_t>(i)] =
          static_cast<std::uint8_t>((wrapped >> (8 * i)) & 0xFF);
    b[1204] = options_.return_mode;
    b[1205] = options_.product;
    packet.host_stamp_ns = options_.host_epoch_ns +
                           std::llround(sequence_time_us(packet.first_sequence + per_packet) * 1e3);
    out.push_back(std::move(packet));
  }
  return out;
}

std::uint32_t pcap_linktype(PcapLink link) {
  switch (link) {
    case PcapLink::kEthernet:
      return 1;
    case PcapLink::kLinuxSll:
      return 113;
    case PcapLink::kLinuxSll2:
      return 276;
    case PcapLink::kRawIp:
      return 101;
    case PcapLink::kNull:
      return 0;
  }
  return 1;
}

PcapFrame udp_frame(PcapLink link, const std::vector<std::uint8_t>& payload, std::uint16_t dst_port,
                    std::int64_t stamp_ns, std::uint16_t src_port) {
  std::vector<std::uint8_t> udp;
  push_be16(udp, src_port);
  push_be16(udp, dst_port);
  push_be16(udp, static_cast<std::uint32_t>(8 + payload.size()));
  push_be16(udp, 0);
  udp.insert(udp.end(), payload.begin(), payload.end());
  PcapFrame frame{link_header(link, 0x0800), stamp_ns};
  const auto ip = ipv4_packet(17, udp);
  frame.bytes.insert(frame.bytes.end(), ip.begin(), ip.end());
  return frame;
}

PcapFrame tcp_frame(PcapLink link, std::int64_t stamp_ns) {
  std::vector<std::uint8_t> tcp(20 + 16, 0);
  tcp[0] = 0x00;
  tcp[1] = 80;
  tcp[2] = 0x09;
  tcp[3] = 0x40;   // destination port 2368: a TCP segment to the data port is still not UDP
  tcp[12] = 0x50;  // data offset 5 words
  PcapFrame frame{link_header(link, 0x0800), stamp_ns};
  const auto ip = ipv4_packet(6, tcp);
  frame.bytes.insert(frame.bytes.end(), ip.begin(), ip.end());
  return frame;
}

PcapFrame arp_frame(std::int64_t stamp_ns) {
  PcapFrame frame{link_header(PcapLink::kEthernet, 0x0806), stamp_ns};
  push_bytes(frame.bytes, {0,   1,   8, 0,   6, 4, 0, 1, 0x60, 0x76, 0x88, 0,   0, 8,
                           192, 168, 1, 201, 0, 0, 0, 0, 0,    0,    192,  168, 1, 77});
  return frame;
}

PcapFrame ipv6_udp_frame(const std::vector<std::uint8_t>& payload, std::uint16_t dst_port,
                         std::int64_t stamp_ns) {
  PcapFrame frame{link_header(PcapLink::kEthernet, 0x86DD), stamp_ns};
  auto& b = frame.bytes;
  push_bytes(b, {0x60, 0, 0, 0});
  push_be16(b, static_cast<std::uint32_t>(8 + payload.size()));
  push_bytes(b, {17, 64});
  for (int i = 0; i < 32; ++i) b.push_back(static_cast<std::uint8_t>(i == 15 || i == 31 ? 1 : 0));
  push_be16(b, 2368);
  push_be16(b, dst_port);
  push_be16(b, static_cast<std::uint32_t>(8 + payload.size()));
  push_be16(b, 0);
  b.insert(b.end(), payload.begin(), payload.end());
  return frame;
}

void write_pcap(const std::filesystem::path& path, PcapLink link,
                const std::vector<PcapFrame>& frames, bool nanoseconds) {
  std::vector<std::uint8_t> out;
  push_le32(out, nanoseconds ? 0xA1B23C4D : 0xA1B2C3D4);
  push_le16(out, 2);
  push_le16(out, 4);
  push_le32(out, 0);
  push_le32(out, 0);
  push_le32(out, 65535);
  push_le32(out, pcap_linktype(link));
  for (const auto& f : frames) {
    const std::int64_t sec = f.stamp_ns / 1'000'000'000;
    const std::int64_t frac = f.stamp_ns % 1'000'000'000;
    push_le32(out, static_cast<std::uint32_t>(sec));
    push_le32(out, static_cast<std::uint32_t>(nanoseconds ? frac : frac / 1000));
    push_le32(out, static_cast<std::uint32_t>(f.bytes.size()));
    push_le32(out, static_cast<std::uint32_t>(f.bytes.size()));
    out.insert(out.end(), f.bytes.begin(), f.bytes.end());
  }
  std::ofstream file(path, std::ios::binary);
  file.write(reinterpret_cast<const char*>(out.data()), static_cast<std::streamsize>(out.size()));
  if (!file) throw std::runtime_error("cannot write " + path.string());
}

void write_pcapng(const std::filesystem::path& path, PcapLink link,
                  const std::vector<PcapFrame>& frames) {
  std::vector<std::uint8_t> out;
  // Section header block.
  push_le32(out, 0x0A0D0D0A);
  push_le32(out, 28);
  push_le32(out, 0x1A2B3C4D);
  push_le16(out, 1);
  push_le16(out, 0);
  push_le32(out, 0xFFFFFFFF);
  push_le32(out, 0xFFFFFFFF);
  push_le32(out, 28);
  // Interface description block (default time resolution: microseconds).
  push_le32(out, 1);
  push_le32(out, 20);
  push_le16(out, pcap_linktype(link));
  push_le16(out, 0);
  push_le32(out, 65535);
  push_le32(out, 20);
  for (const auto& f : frames) {
    const std::size_t padded = (f.bytes.size() + 3) / 4 * 4;
    const auto total = static_cast<std::uint32_t>(32 + padded);
    const auto us = static_cast<std::uint64_t>(f.stamp_ns / 1000);
    push_le32(out, 6);
    push_le32(out, total);
    push_le32(out, 0);
    push_le32(out, static_cast<std::uint32_t>(us >> 32));
    push_le32(out, static_cast<std::uint32_t>(us & 0xFFFFFFFF));
    push_le32(out, static_cast<std::uint32_t>(f.bytes.size()));
    push_le32(out, static_cast<std::uint32_t>(f.bytes.size()));
    out.insert(out.end(), f.bytes.begin(), f.bytes.end());
    out.resize(out.size() + (padded - f.bytes.size()), 0);
    push_le32(out, total);
  }
  std::ofstream file(path, std::ios::binary);
  file.write(reinterpret_cast<const char*>(out.data()), static_cast<std::streamsize>(out.size()));
  if (!file) throw std::runtime_error("cannot write " + path.string());
}

std::vector<PcapFrame> frame_packets(PcapLink link,
                                     const std::vector<EncodedVelodynePacket>& packets,
                                     std::uint16_t port) {
  std::vector<PcapFrame> frames;
  frames.reserve(packets.size());
  for (const auto& p : packets) frames.push_back(udp_frame(link, p.payload, port, p.host_stamp_ns));
  return frames;
}

}  // namespace ringtrack::test
