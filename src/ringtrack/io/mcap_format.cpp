#include "ringtrack/io/mcap_format.hpp"

namespace ringtrack::io::mcap {
namespace {

// Slicing-by-8 tables of the reflected IEEE polynomial: eight bytes per step instead of one
// keeps the CRC of a scan's point cloud (several hundred kB) well below the write budget.
struct CrcTables {
  std::array<std::array<std::uint32_t, 256>, 8> t{};
  CrcTables() {
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1U) != 0 ? 0xEDB88320U ^ (c >> 1) : c >> 1;
      t[0][i] = c;
    }
    for (std::uint32_t i = 0; i < 256; ++i) {
      for (std::size_t s = 1; s < 8; ++s) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xFF];
    }
  }
};

const CrcTables& crc_tables() {
  static const CrcTables tables;
  return tables;
}

}  // namespace

const char* op_name(std::uint8_t op) {
  switch (static_cast<Op>(op)) {
    case Op::kHeader:
      return "Header";
    case Op::kFooter:
      return "Footer";
    case Op::kSchema:
      return "Schema";
    case Op::kChannel:
      return "Channel";
    case Op::kMessage:
      return "Message";
    case Op::kChunk:
      return "Chunk";
    case Op::kMessageIndex:
      return "Message Index";
    case Op::kChunkIndex:
      return "Chunk Index";
    case Op::kAttachment:
      return "Attachment";
    case Op::kAttachmentIndex:
      return "Attachment Index";
    case Op::kStatistics:
      return "Statistics";
    case Op::kMetadata:
      return "Metadata";
    case Op::kMetadataIndex:
      return "Metadata Index";
    case Op::kSummaryOffset:
      return "Summary Offset";
    case Op::kDataEnd:
      return "Data End";
  }
  return "unknown";
}

std::uint32_t crc32(std::span<const std::uint8_t> data, std::uint32_t crc) {
  const auto& t = crc_tables().t;
  std::uint32_t c = ~crc;
  const std::uint8_t* p = data.data();
  std::size_t n = data.size();
  while (n >= 8) {
    std::uint32_t lo = 0;
    std::uint32_t hi = 0;
    std::memcpy(&lo, p, 4);
    std::memcpy(&hi, p + 4, 4);
    lo ^= c;
    c = t[7][lo & 0xFF] ^ t[6][(lo >> 8) & 0xFF] ^ t[5][(lo >> 16) & 0xFF] ^ t[4][lo >> 24] ^
        t[3][hi & 0xFF] ^ t[2][(hi >> 8) & 0xFF] ^ t[1][(hi >> 16) & 0xFF] ^ t[0][hi >> 24];
    p += 8;
    n -= 8;
  }
  while (n-- > 0) c = t[0][(c ^ *p++) & 0xFF] ^ (c >> 8);
  return ~c;
}

void Buffer::string(std::string_view s) {
  u32(static_cast<std::uint32_t>(s.size()));
  bytes_.append(s.data(), s.size());
}

std::size_t Buffer::begin_record(Op op) {
  const std::size_t start = bytes_.size();
  u8(static_cast<std::uint8_t>(op));
  u64(0);
  return start;
}

void Buffer::end_record(std::size_t start) {
  const std::uint64_t length = bytes_.size() - start - kRecordPrefixBytes;
  std::memcpy(bytes_.data() + start + 1, &length, sizeof length);
}

std::size_t Buffer::begin_group() {
  const std::size_t start = bytes_.size();
  u32(0);
  return start;
}

void Buffer::end_group(std::size_t start) {
  const auto length = static_cast<std::uint32_t>(bytes_.size() - start - 4);
  std::memcpy(bytes_.data() + start, &length, sizeof length);
}

}  // namespace ringtrack::io::mcap
