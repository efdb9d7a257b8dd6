#include "ringtrack/io/pcap_reader.hpp"

#include <pcap/pcap.h>

#include <cstring>

#include "ringtrack/core/error.hpp"

namespace ringtrack::io {
namespace {

// Link types by the DLT values libpcap reports for files (it maps LINKTYPE_RAW to DLT_RAW).
constexpr int kDltNull = DLT_NULL;  // BSD loopback: family in the writer's order
constexpr int kDltEthernet = DLT_EN10MB;
constexpr int kDltLoop = DLT_LOOP;             // OpenBSD loopback: family in network order
constexpr int kDltLinuxSll = DLT_LINUX_SLL;    // Linux cooked capture v1 (16-byte header)
constexpr int kDltLinuxSll2 = DLT_LINUX_SLL2;  // Linux cooked capture v2 (20-byte header)
constexpr std::uint32_t kAfInet = 2;
constexpr std::uint16_t kEtherIpv4 = 0x0800;

std::uint16_t be16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}

std::uint32_t be32(const std::uint8_t* p) {
  return (static_cast<std::uint32_t>(p[0]) << 24) | (static_cast<std::uint32_t>(p[1]) << 16) |
         (static_cast<std::uint32_t>(p[2]) << 8) | static_cast<std::uint32_t>(p[3]);
}

bool is_raw_ip(int dlt) {
  return dlt == DLT_RAW || dlt == DLT_IPV4;
}

bool supported(int dlt) {
  return dlt == kDltNull || dlt == kDltEthernet || dlt == kDltLoop || dlt == kDltLinuxSll ||
         dlt == kDltLinuxSll2 || is_raw_ip(dlt);
}

}  // namespace

bool parse_ipv4_udp(const std::uint8_t* data, std::size_t size, UdpDatagram& out,
                    const char*& why) {
  if (size < 20) {
    why = "short";
    return false;
  }
  if ((data[0] >> 4) != 4) {
    why = "non-ipv4";
    return false;
  }
  const std::size_t header = static_cast<std::size_t>(data[0] & 0x0F) * 4;
  const std::size_t total = be16(data + 2);
  if (header < 20 || total < header) {
    why = "non-ipv4";  // not a well-formed IPv4 header
    return false;
  }
  if (size < total) {
    why = "short";
    return false;
  }
  const std::uint16_t fragment = be16(data + 6);
  if ((fragment & 0x2000) != 0 || (fragment & 0x1FFF) != 0) {  // more fragments, or an offset
    why = "fragment";
    return false;
  }
  if (data[9] != 17) {
    why = "non-udp";
    return false;
  }
  const std::uint8_t* udp = data + header;
  const std::size_t available = total - header;
  if (available < 8) {
    why = "short";
    return false;
  }
  const std::size_t udp_length = be16(udp + 4);
  if (udp_length < 8 || udp_length > available) {
    why = "short";
    return false;
  }
  out.src_ip = be32(data + 12);
  out.dst_ip = be32(data + 16);
  out.src_port = be16(udp);
  out.dst_port = be16(udp + 2);
  out.payload = std::span<const std::uint8_t>(udp + 8, udp_length - 8);
  return true;
}

void PcapReader::Closer::operator()(pcap* handle) const {
  if (handle != nullptr) pcap_close(handle);
}

PcapReader::PcapReader(const std::filesystem::path& path, bool allow_truncated)
    : path_(path.string()), allow_truncated_(allow_truncated) {
  char error[PCAP_ERRBUF_SIZE] = {0};
  pcap* handle =
      pcap_open_offline_with_tstamp_precision(path_.c_str(), PCAP_TSTAMP_PRECISION_NANO, error);
  if (handle == nullptr) {
    throw core::InputError(path_ + ": cannot read as a pcap/pcapng capture: " + error);
  }
  handle_.reset(handle);
  link_type_ = pcap_datalink(handle);
  if (!supported(link_type_)) {
    const char* name = pcap_datalink_val_to_name(link_type_);
    throw core::InputError(path_ + ": link type " + std::to_string(link_type_) + " (" +
                           (name != nullptr ? name : "unknown") +
                           ") is not supported; expected Ethernet, Linux cooked (SLL, SLL2), raw "
                           "IP or BSD loopback");
  }
}

PcapReader::~PcapReader() = default;

bool PcapReader::parse_frame(const std::uint8_t* data, std::size_t size, UdpDatagram& out) {
  std::size_t offset = 0;
  bool ipv4 = false;
  if (link_type_ == kDltEthernet) {
    if (size < 14) {
      ++stats_.short_frames;
      return false;
    }
    std::uint16_t type = be16(data + 12);
    offset = 14;
    // 802.1Q / 802.1ad VLAN tags (up to two).
    for (int tags = 0; tags < 2 && (type == 0x8100 || type == 0x88A8 || type == 0x9100); ++tags) {
      if (size < offset + 4) {
        ++stats_.short_frames;
        return false;
      }
      type = be16(data + offset + 2);
      offset += 4;
    }
    ipv4 = type == kEtherIpv4;
  } else if (link_type_ == kDltLinuxSll) {
    if (size < 16) {
      ++stats_.short_frames;
      return false;
    }
    ipv4 = be16(data + 14) == kEtherIpv4;
    offset = 16;
  } else if (link_type_ == kDltLinuxSll2) {
    if (size < 20) {
      ++stats_.short_frames;
      return false;
    }
    ipv4 = be16(data) == kEtherIpv4;
    offset = 20;
  } else if (link_type_ == kDltNull || link_type_ == kDltLoop) {
    if (size < 4) {
      ++stats_.short_frames;
      return false;
    }
    const std::uint32_t big = be32(data);
    const std::uint32_t little =
        (big >> 24) | ((big >> 8) & 0xFF00) | ((big << 8) & 0xFF0000) | (big << 24);
    ipv4 = big == kAfInet || (link_type_ == kDltNull && little == kAfInet);
    offset = 4;
  } else {  // raw IP
    ipv4 = size > 0 && (data[0] >> 4) == 4;
  }
  if (!ipv4) {
    ++stats_.non_ipv4;
    return false;
  }
  const char* why = "";
  if (!parse_ipv4_udp(data + offset, size - offset, out, why)) {
    if (std::strcmp(why, "non-udp") == 0) {
      ++stats_.non_udp;
    } else if (std::strcmp(why, "fragment") == 0) {
      ++stats_.fragments;
    } else if (std::strcmp(why, "short") == 0) {
      ++stats_.short_frames;
    } else {
      ++stats_.non_ipv4;
    }
    return false;
  }
  return true;
}

bool PcapReader::next(UdpDatagram& out) {
  while (!done_) {
    pcap_pkthdr* header = nullptr;
    const u_char* data = nullptr;
    const int rc = pcap_next_ex(handle_.get(), &header, &data);
    if (rc == PCAP_ERROR_BREAK) {  // end of file
      done_ = true;
      break;
    }
    if (rc != 1) {
      const std::string message = pcap_geterr(handle_.get());
      done_ = true;
      if (!allow_truncated_) {
        throw core::InputError(path_ + ": after frame " + std::to_string(stats_.frames) + ": " +
                               message);
      }
      stats_.truncated = true;
      stats_.truncation_message = message;
      break;
    }
    ++stats_.frames;
    if (!parse_frame(data, header->caplen, out)) continue;
    // With nanosecond precision requested, tv_usec holds nanoseconds.
    out.stamp_ns = static_cast<std::int64_t>(header->ts.tv_sec) * 1'000'000'000 +
                   static_cast<std::int64_t>(header->ts.tv_usec);
    out.frame = stats_.frames;
    ++stats_.udp_datagrams;
    return true;
  }
  return false;
}

}  // namespace ringtrack::io
