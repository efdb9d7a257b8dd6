#pragma once
/// The MCAP container format (mcap.dev/spec, major version 0): record opcodes, the magic, CRC-32
/// and the little-endian serialization both our writer and reader use. Own code: Debian ships no
/// C++ MCAP library (docs/formats.md, "MCAP").

#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ringtrack/io/byte_buffer.hpp"

namespace ringtrack::io::mcap {

/// The 8 bytes that start and end every MCAP file.
inline constexpr std::array<std::uint8_t, 8> kMagic = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
/// Bytes of a record's opcode and length prefix.
inline constexpr std::size_t kRecordPrefixBytes = 9;
/// Content bytes of a Footer record (summary_start, summary_offset_start, summary_crc).
inline constexpr std::size_t kFooterContentBytes = 20;

/// Record opcodes of the specification.
enum class Op : std::uint8_t {
  kHeader = 0x01,           ///< profile, library
  kFooter = 0x02,           ///< summary offsets and CRC; last record
  kSchema = 0x03,           ///< id, name, encoding, data
  kChannel = 0x04,          ///< id, schema id, topic, message encoding, metadata
  kMessage = 0x05,          ///< channel id, sequence, log and publish time, data
  kChunk = 0x06,            ///< compressed batch of schema, channel and message records
  kMessageIndex = 0x07,     ///< per channel: (log time, offset in the chunk) after a chunk
  kChunkIndex = 0x08,       ///< where a chunk and its message indexes are
  kAttachment = 0x09,       ///< an attached file
  kAttachmentIndex = 0x0A,  ///< where an attachment is
  kStatistics = 0x0B,       ///< counts and time range of the file
  kMetadata = 0x0C,         ///< name and string map
  kMetadataIndex = 0x0D,    ///< where a metadata record is
  kSummaryOffset = 0x0E,    ///< where a group of summary records is
  kDataEnd = 0x0F,          ///< end of the data section and its CRC
};

/// The specification's name of an opcode ("Chunk", "Message Index", ...), "unknown" otherwise.
const char* op_name(std::uint8_t op);

/// CRC-32 (IEEE 802.3, as zlib's crc32) of `data` continuing from `crc` (0 to start).
std::uint32_t crc32(std::span<const std::uint8_t> data, std::uint32_t crc = 0);

/// Appends little-endian fields to a byte vector, the MCAP serialization of each type.
class Buffer {
 public:
  /// The bytes so far.
  [[nodiscard]] std::span<const std::uint8_t> bytes() const { return bytes_.span(); }
  /// Number of bytes so far.
  [[nodiscard]] std::size_t size() const { return bytes_.size(); }
  /// Empties the buffer, keeping its capacity.
  void clear() { bytes_.clear(); }
  /// uint8.
  void u8(std::uint8_t v) { bytes_.push_back(v); }
  /// uint16, little endian.
  void u16(std::uint16_t v) { put(v); }
  /// uint32, little endian.
  void u32(std::uint32_t v) { put(v); }
  /// uint64, little endian.
  void u64(std::uint64_t v) { put(v); }
  /// Raw bytes without a prefix.
  void raw(std::span<const std::uint8_t> data) { bytes_.append(data.data(), data.size()); }
  /// String: uint32 byte length, then the bytes.
  void string(std::string_view s);
  /// Starts a record: opcode and a placeholder length; returns the position for end_record().
  std::size_t begin_record(Op op);
  /// Sets the length of the record begun at `start` to the bytes appended since.
  void end_record(std::size_t start);
  /// Starts a uint32 length-prefixed group (Map or Array); returns the position for end_group().
  std::size_t begin_group();
  /// Sets the byte length of the group begun at `start`.
  void end_group(std::size_t start);

 private:
  template <typename T>
  void put(T v) {
    static_assert(std::endian::native == std::endian::little, "MCAP is little endian");
    std::memcpy(bytes_.grow(sizeof(T)), &v, sizeof(T));
  }

  ByteBuffer bytes_;
};

}  // namespace ringtrack::io::mcap
