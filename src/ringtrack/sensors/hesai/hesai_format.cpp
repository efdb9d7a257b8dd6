#include "ringtrack/sensors/hesai/hesai_format.hpp"

#include <cctype>

namespace ringtrack::sensors::hesai {
namespace {

// One row per packet layout. Sources (user manuals, chapter "Data Structure", point cloud UDP
// data): Pandar40P (no header; 10 blocks of flag FF EE, azimuth and 40 x 3-byte records; 22-byte
// tail: reserved 5, shutdown flag, reserved 2, motor speed, timestamp, return mode, factory
// byte, UTC), Pandar64 (8-byte header EE FF, lasers, blocks, reserved, distance unit, returns,
// flags; 6 blocks of azimuth + 64 x 3 bytes; tail as the Pandar40P's), PandarXT16/XT32 (6-byte
// pre-header EE FF 06 01, 6-byte header; 8 blocks of azimuth + 4-byte records; 24-byte tail:
// reserved 9, shutdown flag, return mode, motor speed, date and time, timestamp, factory byte),
// PandarQT64 (pre-header EE FF 03 01, 4 blocks of 64 x 4-byte records; 24-byte tail: reserved
// 10, motor speed, timestamp, return mode, factory byte, date and time). Every layout may carry a
// 4-byte UDP sequence number after the tail. Columns per revolution at 10 Hz are the manuals'
// azimuth resolutions (0.2, 0.2, 0.6, 0.18, 0.18 deg), confirmed by the real captures' block
// azimuth steps.
constexpr HesaiFormat kFormats[] = {
    {"Pandar40P", 40, 10, 0, true, 3, 22, 14, 10, 8, 0, 0, 1800, 0.3, 200.0},
    {"Pandar64", 64, 6, 8, false, 3, 22, 14, 10, 8, 0, 0, 1800, 0.3, 200.0},
    {"PandarQT64", 64, 4, 12, false, 4, 24, 16, 12, 10, 3, 1, 600, 0.1, 60.0},
    {"PandarXT16", 16, 8, 12, false, 4, 24, 10, 19, 11, 6, 1, 2000, 0.05, 120.0},
    {"PandarXT32", 32, 8, 12, false, 4, 24, 10, 19, 11, 6, 1, 2000, 0.05, 120.0},
};

std::string normalized(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (std::isalnum(static_cast<unsigned char>(c))) {
      out.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
    }
  }
  if (out.rfind("hesai", 0) == 0) out.erase(0, 5);
  if (out.rfind("pandar", 0) == 0) out.erase(0, 6);
  return out;
}

bool size_fits(std::size_t size, const HesaiFormat& f) {
  return size == f.packet_bytes() || size == f.packet_bytes() + 4;
}

std::uint16_t le16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}

}  // namespace

std::span<const HesaiFormat> hesai_formats() {
  return kFormats;
}

const HesaiFormat* hesai_format_by_name(const std::string& name) {
  const std::string key = normalized(name);
  for (const auto& f : kFormats) {
    if (normalized(f.name) == key) return &f;
  }
  return nullptr;
}

std::string hesai_model_list() {
  std::string s;
  for (const auto& f : kFormats) s += (s.empty() ? "" : ", ") + std::string(f.name);
  return s;
}

const HesaiFormat* identify_hesai_packet(std::span<const std::uint8_t> payload) {
  const std::size_t n = payload.size();
  if (n < 12) return nullptr;
  const std::uint8_t* p = payload.data();
  for (const auto& f : kFormats) {
    if (!size_fits(n, f)) continue;
    if (f.block_flag) {
      if (p[0] == 0xFF && p[1] == 0xEE) return &f;
    } else if (p[0] == 0xEE && p[1] == 0xFF) {
      if (f.protocol_major == 0) {
        if (p[2] == f.channels && p[3] == f.blocks) return &f;
      } else if (p[2] == f.protocol_major && p[3] == f.protocol_minor && p[6] == f.channels &&
                 p[7] == f.blocks) {
        return &f;
      }
    }
  }
  return nullptr;
}

std::string to_string(HesaiPacketStatus status) {
  switch (status) {
    case HesaiPacketStatus::kOk:
      return "ok";
    case HesaiPacketStatus::kWrongSize:
      return "wrong payload size";
    case HesaiPacketStatus::kBadHeader:
      return "bad header";
    case HesaiPacketStatus::kBadAzimuth:
      return "azimuth out of range";
    case HesaiPacketStatus::kUnknownReturnMode:
      return "unknown return mode";
    case HesaiPacketStatus::kBadDistanceUnit:
      return "zero distance unit";
  }
  return "unknown status";
}

bool hesai_dual_return_mode(std::uint8_t mode) {
  return mode == 0x39 || mode == 0x3B || mode == 0x3C;
}

HesaiPacketStatus parse_hesai_packet(std::span<const std::uint8_t> payload,
                                     const HesaiFormat& format, HesaiParsedPacket& out) {
  if (!size_fits(payload.size(), format)) return HesaiPacketStatus::kWrongSize;
  const std::uint8_t* p = payload.data();
  out.format = &format;
  out.distance_unit_m = 0.004;  // Pandar40P: fixed 4 mm (manual); the others say it in the header
  if (!format.block_flag) {
    if (p[0] != 0xEE || p[1] != 0xFF) return HesaiPacketStatus::kBadHeader;
    const std::size_t h = format.protocol_major == 0 ? 2 : 6;  // laser count's offset
    if (format.protocol_major != 0 &&
        (p[2] != format.protocol_major || p[3] != format.protocol_minor)) {
      return HesaiPacketStatus::kBadHeader;
    }
    if (p[h] != format.channels || p[h + 1] != format.blocks) return HesaiPacketStatus::kBadHeader;
    const std::uint8_t unit_mm = p[h + 3];
    if (unit_mm == 0) return HesaiPacketStatus::kBadDistanceUnit;
    out.distance_unit_m = unit_mm * 1e-3;
  }
  const std::size_t tail = format.header_bytes + format.blocks * format.block_bytes();
  out.return_mode = p[tail + format.tail_return_mode];
  switch (out.return_mode) {
    case 0x33:  // first
    case 0x37:  // strongest
    case 0x38:  // last
      out.dual = false;
      break;
    case 0x39:  // last + strongest
    case 0x3B:  // last + first
    case 0x3C:  // first + strongest
      out.dual = true;
      break;
    default:
      return HesaiPacketStatus::kUnknownReturnMode;
  }
  const std::uint8_t* ts = p + tail + format.tail_timestamp;
  out.timestamp_us = static_cast<std::uint32_t>(ts[0]) | (static_cast<std::uint32_t>(ts[1]) << 8) |
                     (static_cast<std::uint32_t>(ts[2]) << 16) |
                     (static_cast<std::uint32_t>(ts[3]) << 24);
  out.motor_rpm = le16(p + tail + format.tail_motor_speed);
  out.blocks = format.blocks;
  for (int b = 0; b < format.blocks; ++b) {
    const std::uint8_t* block = p + format.header_bytes + b * format.block_bytes();
    if (format.block_flag) {
      if (block[0] != 0xFF || block[1] != 0xEE) return HesaiPacketStatus::kBadHeader;
      block += 2;
    }
    const std::uint16_t az = le16(block);
    if (az >= 36000) return HesaiPacketStatus::kBadAzimuth;
    out.azimuth[static_cast<std::size_t>(b)] = az;
    out.records[static_cast<std::size_t>(b)] = block + 2;
  }
  if (out.dual) {
    for (int b = 0; b + 1 < format.blocks; b += 2) {
      const auto first = static_cast<std::size_t>(b);
      if (out.azimuth[first] != out.azimuth[first + 1]) {
        return HesaiPacketStatus::kBadAzimuth;
      }
    }
  }
  return HesaiPacketStatus::kOk;
}

}  // namespace ringtrack::sensors::hesai
