#pragma once
/// Hesai point-cloud packet formats (Pandar40P, Pandar64, PandarQT64, PandarXT16, PandarXT32) as
/// one table, and the parse of a UDP payload into blocks. Facts from each sensor's user manual,
/// "Data Structure" chapter (point cloud data packet); see docs/hesai.md.

#include <array>
#include <cstdint>
#include <span>
#include <string>

namespace ringtrack::sensors::hesai {

/// Most blocks in any supported packet (Pandar40P: 10).
inline constexpr int kMaxBlocks = 10;

/// One packet layout of the table. Offsets are bytes; tail offsets count from the tail's start.
struct HesaiFormat {
  const char* name;              ///< model name, e.g. "PandarXT32"
  int channels;                  ///< lasers (channels) per block
  int blocks;                    ///< blocks per packet
  std::size_t header_bytes;      ///< bytes before the first block (pre-header + header)
  bool block_flag;               ///< each block starts with bytes FF EE (Pandar40P)
  std::size_t unit_bytes;        ///< bytes per channel record: distance u16, reflectivity u8 (+1)
  std::size_t tail_bytes;        ///< bytes after the body, without the UDP sequence number
  std::size_t tail_return_mode;  ///< return-mode byte within the tail
  std::size_t tail_timestamp;    ///< uint32 microseconds within the tail
  std::size_t tail_motor_speed;  ///< uint16 rpm within the tail
  std::uint8_t protocol_major;   ///< pre-header version (0: the layout has no pre-header)
  std::uint8_t protocol_minor;   ///< pre-header minor version
  int columns_at_10hz;           ///< blocks (firings) per revolution at 600 rpm
  double default_min_range_m;    ///< range limits of the reference decodes / specification
  double default_max_range_m;

  /// Bytes of one block: optional flag, azimuth (u16, 0.01 deg), channel records.
  [[nodiscard]] std::size_t block_bytes() const {
    return (block_flag ? 2u : 0u) + 2u + static_cast<std::size_t>(channels) * unit_bytes;
  }
  /// Payload bytes without the optional 4-byte UDP sequence number.
  [[nodiscard]] std::size_t packet_bytes() const {
    return header_bytes + static_cast<std::size_t>(blocks) * block_bytes() + tail_bytes;
  }
};

/// The table of supported formats.
std::span<const HesaiFormat> hesai_formats();
/// The format of a model name (case and punctuation ignored: "xt32", "PandarXT-32", "pandar40p");
/// nullptr when unknown.
const HesaiFormat* hesai_format_by_name(const std::string& name);
/// Recognizes a payload's format from its size and header bytes; nullptr when it is none of the
/// table's (e.g. a Velodyne packet).
const HesaiFormat* identify_hesai_packet(std::span<const std::uint8_t> payload);
/// Names of the supported models, comma-separated.
std::string hesai_model_list();

/// Why a packet was decoded or skipped.
enum class HesaiPacketStatus : std::uint8_t {
  kOk = 0,
  kWrongSize,          ///< the payload size is not the format's (with or without sequence)
  kBadHeader,          ///< start-of-block / pre-header bytes or laser/block counts differ
  kBadAzimuth,         ///< a block azimuth >= 36000 or a dual pair with different azimuths
  kUnknownReturnMode,  ///< the tail's return-mode byte is none of the documented ones
  kBadDistanceUnit,    ///< the header's distance unit is zero
};

/// Human-readable status ("wrong payload size", ...).
std::string to_string(HesaiPacketStatus status);

/// A parsed packet (pointers into the payload, which must outlive it).
struct HesaiParsedPacket {
  const HesaiFormat* format{nullptr};
  std::uint8_t return_mode{0};    ///< raw return-mode byte
  bool dual{false};               ///< blocks come in pairs of equal azimuth
  std::uint32_t timestamp_us{0};  ///< microseconds within the second (sensor clock)
  std::uint16_t motor_rpm{0};
  double distance_unit_m{0.004};
  int blocks{0};
  std::array<std::uint16_t, kMaxBlocks> azimuth{};        ///< 0.01 deg, clockwise (Hesai's)
  std::array<const std::uint8_t*, kMaxBlocks> records{};  ///< first channel record of a block
};

/// Parses a payload of the given format. Never throws.
HesaiPacketStatus parse_hesai_packet(std::span<const std::uint8_t> payload,
                                     const HesaiFormat& format, HesaiParsedPacket& out);

/// True for a dual-return mode byte (0x39 last+strongest, 0x3B last+first, 0x3C first+strongest).
bool hesai_dual_return_mode(std::uint8_t mode);

}  // namespace ringtrack::sensors::hesai
