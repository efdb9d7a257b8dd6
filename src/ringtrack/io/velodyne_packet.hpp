#pragma once
/// The Velodyne data packet (VLP-16, VLP-32C, HDL-32E): layout, parsing into firing sequences and
/// decoding into points. Facts from the sensors' user manuals; see docs/vlp16.md.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "ringtrack/core/sensor_model.hpp"

namespace ringtrack::io {

/// Bytes of a data packet's UDP payload: 12 blocks of 100 bytes, a time stamp and two factory
/// bytes.
inline constexpr std::size_t kVelodyneDataPacketBytes = 1206;
/// Bytes of a position (GPS/NMEA) packet's UDP payload.
inline constexpr std::size_t kVelodynePositionPacketBytes = 512;
/// Data blocks per packet.
inline constexpr int kVelodyneBlocks = 12;
/// Bytes per data block: flag (2), azimuth (2), 32 x (distance 2, reflectivity 1).
inline constexpr std::size_t kVelodyneBlockBytes = 100;
/// Channel records per data block.
inline constexpr int kVelodyneChannelsPerBlock = 32;
/// The block flag 0xFFEE as it appears on the wire (bytes FF EE, read little-endian).
inline constexpr std::uint16_t kVelodyneBlockFlag = 0xEEFF;
/// Distance unit of the VLP-16 and HDL-32E (2 mm); a raw distance of 0 means no return.
inline constexpr double kVelodyneDistanceUnitM = 0.002;
/// Distance unit of the VLP-32C (4 mm: VLP-32C User Manual, "Data Packet Format").
inline constexpr double kVlp32cDistanceUnitM = 0.004;
/// Firing sequences in one packet at most (VLP-16 single return: 12 blocks x 2).
inline constexpr int kVelodyneMaxSequences = 24;

/// The product byte (last byte of a data packet).
enum class VelodyneProduct : std::uint8_t {
  kUnknown = 0x00,  ///< old firmware leaves the factory bytes zero
  kHdl32e = 0x21,
  kVlp16 = 0x22,
  kVlp32c = 0x28,
};

/// The return-mode byte (second-to-last byte of a data packet).
enum class VelodyneReturnMode : std::uint8_t {
  kUnspecified = 0x00,  ///< old firmware: single return, taken as strongest
  kStrongest = 0x37,
  kLast = 0x38,
  kDual = 0x39,  ///< blocks come in pairs: (last, strongest or second strongest)
};

/// Why a data packet was accepted or skipped.
enum class VelodynePacketStatus : std::uint8_t {
  kOk = 0,
  kWrongSize,          ///< payload is not 1206 bytes
  kBadBlockFlag,       ///< a block does not start with 0xFFEE
  kBadAzimuth,         ///< a block azimuth is >= 36000 (0.01 deg units)
  kDualPairMismatch,   ///< dual mode, but a block pair's azimuths differ
  kUnknownReturnMode,  ///< return-mode byte is not 0x00, 0x37, 0x38 or 0x39
  kProductChanged,     ///< product or return-mode byte differs from the stream's first packet
  kOutOfOrder,         ///< the packet lies before the previous one (dropped)
};

/// Human-readable name of a status ("wrong payload size", ...).
std::string to_string(VelodynePacketStatus status);
/// Name of a product byte ("VLP-16", ..., "unknown product 0x24").
std::string velodyne_product_name(std::uint8_t product_byte);
/// The built-in sensor model of a product byte; throws core::InputError for unsupported products.
core::SensorModel velodyne_model_for_product(std::uint8_t product_byte, double scan_rate_hz);
/// The product byte a model stands for (by its name), or kUnknown for non-Velodyne models.
VelodyneProduct velodyne_product_of_model(const core::SensorModel& model);

/// Converts a Velodyne azimuth (degrees clockwise seen from above, the
/// packet's convention) to ringtrack's (radians counter-clockwise from +x, in [0, 2 pi)).
double velodyne_to_ringtrack_azimuth_rad(double velodyne_azimuth_deg);

/// Packet layout of one laser arrangement, derived from a sensor model.
struct VelodyneLayout {
  int lasers{16};              ///< lasers per firing sequence (16 or 32)
  int sequences_per_block{2};  ///< VLP-16 blocks hold two sequences, 32-laser blocks one
  double sequence_us{55.296};  ///< duration of one firing sequence
  double distance_unit_m{kVelodyneDistanceUnitM};  ///< metres per raw distance count
  /// Layout of a built-in Velodyne model (16 rings: VLP-16 layout, 32: one sequence per block).
  static VelodyneLayout of(const core::SensorModel& model);
};

/// One firing sequence of a packet: all lasers fired once, one column of a scan.
struct VelodyneSequence {
  double azimuth_deg{0};     ///< Velodyne azimuth of its first firing, [0, 360)
  double advance_deg{0};     ///< azimuth advance over one sequence period (for interpolation)
  double time_offset_us{0};  ///< first firing relative to the packet time stamp
  /// 3-byte channel records (distance LE16, reflectivity) of laser 0: [0] the block's own
  /// returns (single mode, or the last return in dual mode), [1] the pair's second block in dual
  /// mode (strongest, or second strongest when the strongest is the last), else nullptr.
  std::array<const std::uint8_t*, 2> records{nullptr, nullptr};
  int block{0};              ///< block index of records[0]
  int sequence_in_block{0};  ///< 0 or 1 (VLP-16)
};

/// A packet split into its firing sequences (pointers into the payload, which must outlive it).
struct VelodyneParsedPacket {
  std::uint32_t timestamp_us{0};  ///< microseconds past the hour of the first firing
  std::uint8_t return_mode{0};    ///< raw return-mode byte
  std::uint8_t product{0};        ///< raw product byte
  bool dual{false};               ///< dual-return packet
  int count{0};                   ///< firing sequences in `sequences`
  double packet_us{0};            ///< time covered by the packet's sequences
  std::array<VelodyneSequence, kVelodyneMaxSequences> sequences{};
};

/// Splits a data packet into firing sequences with interpolated azimuths. Never throws: a
/// malformed payload returns its status and leaves `out` unspecified. The azimuth advance of a
/// block is the difference to the next distinct block (the previous one for the packet's last);
/// advances outside [0.25, 4] x nominal_advance_deg fall back to the nominal value.
VelodynePacketStatus parse_velodyne_packet(std::span<const std::uint8_t> payload,
                                           const VelodyneLayout& layout, double nominal_advance_deg,
                                           VelodyneParsedPacket& out);

/// Reads the product byte of a data packet (0 when the payload is too short).
std::uint8_t velodyne_product_byte(std::span<const std::uint8_t> payload);

/// One decoded return in data order, for flat point lists and validation.
struct VelodynePoint {
  int ring{0};            ///< ring (bottom = 0) of the sensor model
  int laser{0};           ///< laser id in the packet's data order
  double azimuth_deg{0};  ///< Velodyne azimuth of this firing (interpolated, no laser offset)
  double distance_m{0};   ///< measured distance
  std::uint8_t reflectivity{0};  ///< calibrated reflectivity byte
  std::uint8_t block{0};         ///< block the return was read from
  std::uint8_t sequence_in_block{0};
  bool second_of_pair{false};  ///< dual mode: read from the pair's second (strongest) block
  double time_offset_us{0};    ///< firing time relative to the packet time stamp
};

/// Appends every return of a parsed packet in data order (block, sequence, laser). Zero
/// distances are skipped; in dual mode a second-block return whose distance equals the first
/// block's is the same echo reported twice (the sensor saw one echo) and is skipped.
void append_velodyne_points(const VelodyneParsedPacket& packet, const core::SensorModel& model,
                            std::vector<VelodynePoint>& out);

}  // namespace ringtrack::io
