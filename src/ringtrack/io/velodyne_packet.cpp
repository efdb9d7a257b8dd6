#include "ringtrack/io/velodyne_packet.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>

#include "ringtrack/core/error.hpp"

namespace ringtrack::io {
namespace {

constexpr std::size_t kTimestampOffset = 1200;
constexpr std::size_t kReturnModeOffset = 1204;
constexpr std::size_t kProductOffset = 1205;

std::uint16_t read_u16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}

std::uint32_t read_u32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}

std::string hex_byte(std::uint8_t b) {
  char text[8];
  std::snprintf(text, sizeof text, "0x%02X", static_cast<unsigned>(b));
  return text;
}

}  // namespace

std::string to_string(VelodynePacketStatus status) {
  switch (status) {
    case VelodynePacketStatus::kOk:
      return "ok";
    case VelodynePacketStatus::kWrongSize:
      return "wrong payload size";
    case VelodynePacketStatus::kBadBlockFlag:
      return "bad block flag";
    case VelodynePacketStatus::kBadAzimuth:
      return "azimuth out of range";
    case VelodynePacketStatus::kDualPairMismatch:
      return "dual block pair with different azimuths";
    case VelodynePacketStatus::kUnknownReturnMode:
      return "unknown return mode";
    case VelodynePacketStatus::kProductChanged:
      return "product or return mode changed";
    case VelodynePacketStatus::kOutOfOrder:
      return "out of order";
  }
  return "unknown status";
}

std::string velodyne_product_name(std::uint8_t product_byte) {
  switch (static_cast<VelodyneProduct>(product_byte)) {
    case VelodyneProduct::kHdl32e:
      return "HDL-32E";
    case VelodyneProduct::kVlp16:
      return "VLP-16";
    case VelodyneProduct::kVlp32c:
      return "VLP-32C";
    case VelodyneProduct::kUnknown:
      break;
  }
  return "unknown product " + hex_byte(product_byte);
}

core::SensorModel velodyne_model_for_product(std::uint8_t product_byte, double scan_rate_hz) {
  switch (static_cast<VelodyneProduct>(product_byte)) {
    case VelodyneProduct::kHdl32e:
      return core::SensorModel::hdl32e(scan_rate_hz);
    case VelodyneProduct::kVlp16:
      return core::SensorModel::vlp16(scan_rate_hz);
    case VelodyneProduct::kVlp32c:
      return core::SensorModel::vlp32c(scan_rate_hz);
    case VelodyneProduct::kUnknown:
      break;
  }
  throw core::InputError("velodyne: unsupported product byte " + hex_byte(product_byte) +
                         " (supported: 0x22 VLP-16, 0x28 VLP-32C, 0x21 HDL-32E); name the model "
                         "to decode packets without a product byte");
}

VelodyneProduct velodyne_product_of_model(const core::SensorModel& model) {
  if (model.name == "VLP-16") return VelodyneProduct::kVlp16;
  if (model.name == "VLP-32C") return VelodyneProduct::kVlp32c;
  if (model.name == "HDL-32E") return VelodyneProduct::kHdl32e;
  return VelodyneProduct::kUnknown;
}

double velodyne_to_ringtrack_azimuth_rad(double velodyne_azimuth_deg) {
  // Velodyne turns clockwise seen from above; ringtrack (like REP 103 and velodyne_pointcloud)
  // puts +x at Velodyne azimuth 0 and counts counter-clockwise.
  double a = -velodyne_azimuth_deg * (std::numbers::pi / 180.0);
  a = std::fmod(a, 2.0 * std::numbers::pi);
  if (a < 0) a += 2.0 * std::numbers::pi;
  if (a >= 2.0 * std::numbers::pi) a = 0.0;
  return a;
}

VelodyneLayout VelodyneLayout::of(const core::SensorModel& model) {
  VelodyneLayout layout;
  layout.lasers = model.rings();
  layout.sequences_per_block = model.rings() == 16 ? 2 : 1;
  layout.sequence_us = model.firing_sequence_us;
  // The VLP-32C reports distances in 4 mm units, the VLP-16 and HDL-32E in 2 mm units.
  layout.distance_unit_m = model.name == "VLP-32C" ? kVlp32cDistanceUnitM : kVelodyneDistanceUnitM;
  if (model.rings() != 16 && model.rings() != 32) {
    throw core::InputError("velodyne: model " + model.name + " has " +
                           std::to_string(model.rings()) +
                           " rings; packets are decoded for 16 and 32 rings only (vlp16, vlp32c, "
                           "hdl32e; the HDL-64E's point clouds are organized, not its packets)");
  }
  return layout;
}

std::uint8_t velodyne_product_byte(std::span<const std::uint8_t> payload) {
  return payload.size() > kProductOffset ? payload[kProductOffset] : 0;
}

VelodynePacketStatus parse_velodyne_packet(std::span<const std::uint8_t> payload,
                                           const VelodyneLayout& layout, double nominal_advance_deg,
                                           VelodyneParsedPacket& out) {
  if (payload.size() != kVelodyneDataPacketBytes) return VelodynePacketStatus::kWrongSize;
  const std::uint8_t* data = payload.data();
  out.timestamp_us = read_u32(data + kTimestampOffset);
  out.return_mode = data[kReturnModeOffset];
  out.product = data[kProductOffset];
  switch (static_cast<VelodyneReturnMode>(out.return_mode)) {
    case VelodyneReturnMode::kUnspecified:
    case VelodyneReturnMode::kStrongest:
    case VelodyneReturnMode::kLast:
      out.dual = false;
      break;
    case VelodyneReturnMode::kDual:
      out.dual = true;
      break;
    default:
      return VelodynePacketStatus::kUnknownReturnMode;
  }

  std::array<int, kVelodyneBlocks> azimuth{};
  for (int b = 0; b < kVelodyneBlocks; ++b) {
    const std::uint8_t* block = data + static_cast<std::size_t>(b) * kVelodyneBlockBytes;
    if (read_u16(block) != kVelodyneBlockFlag) return VelodynePacketStatus::kBadBlockFlag;
    azimuth[static_cast<std::size_t>(b)] = read_u16(block + 2);
    if (azimuth[static_cast<std::size_t>(b)] >= 36000) return VelodynePacketStatus::kBadAzimuth;
  }
  const int stride = out.dual ? 2 : 1;  // distinct firing blocks
  if (out.dual) {
    for (int b = 0; b < kVelodyneBlocks; b += 2) {
      if (azimuth[static_cast<std::size_t>(b)] != azimuth[static_cast<std::size_t>(b) + 1]) {
        return VelodynePacketStatus::kDualPairMismatch;
      }
    }
  }

  const int per_block = layout.sequences_per_block;
  const double block_us = layout.sequence_us * per_block;
  const double nominal_block_deg = nominal_advance_deg * per_block;
  double last_advance = nominal_block_deg;
  out.count = 0;
  for (int b = 0; b < kVelodyneBlocks; b += stride) {
    // Advance to the next distinct block; the packet's last block reuses the previous advance
    // (the next packet is not known yet).
    double advance = last_advance;
    if (b + stride < kVelodyneBlocks) {
      const auto at = static_cast<std::size_t>(b);
      const int diff =
          (azimuth[at + static_cast<std::size_t>(stride)] - azimuth[at] + 36000) % 36000;
      advance = diff * 0.01;
      if (!(advance >= 0.25 * nominal_block_deg && advance <= 4.0 * nominal_block_deg)) {
        advance = nominal_block_deg;
      }
      last_advance = advance;
    }
    const double base_deg = azimuth[static_cast<std::size_t>(b)] * 0.01;
    const int firing_block = b / stride;  // index of the firing in time
    for (int s = 0; s < per_block; ++s) {
      VelodyneSequence& seq = out.sequences[static_cast<std::size_t>(out.count++)];
      double az = base_deg + advance * s / per_block;
      if (az >= 360.0) az -= 360.0;
      seq.azimuth_deg = az;
      seq.advance_deg = advance / per_block;
      seq.time_offset_us = firing_block * block_us + s * layout.sequence_us;
      const std::size_t record0 = static_cast<std::size_t>(b) * kVelodyneBlockBytes + 4 +
                                  static_cast<std::size_t>(s * layout.lasers) * 3;
      seq.records[0] = data + record0;
      seq.records[1] = out.dual ? data + record0 + kVelodyneBlockBytes : nullptr;
      seq.block = b;
      seq.sequence_in_block = s;
    }
  }
  const int firings = kVelodyneBlocks / stride;  // exact: 12 blocks, one or two per firing
  out.packet_us = firings * block_us;
  return VelodynePacketStatus::kOk;
}

void append_velodyne_points(const VelodyneParsedPacket& packet, const core::SensorModel& model,
                            std::vector<VelodynePoint>& out) {
  const int lasers = model.rings();
  const double unit_m = VelodyneLayout::of(model).distance_unit_m;
  std::vector<int> ring_of_laser(static_cast<std::size_t>(lasers));
  for (int r = 0; r < lasers; ++r) {
    ring_of_laser[static_cast<std::size_t>(model.laser_of_ring[static_cast<std::size_t>(r)])] = r;
  }
  const int kinds = packet.dual ? 2 : 1;
  // Data order: the pair's first block (all its sequences), then the second block.
  for (int i = 0; i < packet.count;) {
    const int block = packet.sequences[static_cast<std::size_t>(i)].block;
    int end = i;
    while (end < packet.count && packet.sequences[static_cast<std::size_t>(end)].block == block) {
      ++end;
    }
    for (int kind = 0; kind < kinds; ++kind) {
      for (int k = i; k < end; ++k) {
        const VelodyneSequence& seq = packet.sequences[static_cast<std::size_t>(k)];
        for (int laser = 0; laser < lasers; ++laser) {
          const std::size_t at = 3 * static_cast<std::size_t>(laser);  // 3-byte records
          const std::uint8_t* rec = seq.records[static_cast<std::size_t>(kind)] + at;
          const int raw = read_u16(rec);
          if (raw == 0) continue;
          if (kind == 1 && read_u16(seq.records[0] + at) == raw) continue;
          const int ring = ring_of_laser[static_cast<std::size_t>(laser)];
          const double firing_us = model.firing_offset_us[static_cast<std::size_t>(ring)];
          VelodynePoint p;
          p.ring = ring;
          p.laser = laser;
          p.azimuth_deg = seq.azimuth_deg + seq.advance_deg * firing_us / model.firing_sequence_us;
          if (p.azimuth_deg >= 360.0) p.azimuth_deg -= 360.0;
          p.distance_m = raw * unit_m;
          p.reflectivity = rec[2];
          p.block = static_cast<std::uint8_t>(seq.block + kind);
          p.sequence_in_block = static_cast<std::uint8_t>(seq.sequence_in_block);
          p.second_of_pair = kind == 1;
          p.time_offset_us = seq.time_offset_us + firing_us;
          out.push_back(p);
        }
      }
    }
    i = end;
  }
}

}  // namespace ringtrack::io
