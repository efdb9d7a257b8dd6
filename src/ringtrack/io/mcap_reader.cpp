#include "ringtrack/io/mcap_reader.hpp"

#include <fcntl.h>
#include <lz4frame.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <map>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/byte_buffer.hpp"
#include "ringtrack/io/mcap_format.hpp"

namespace ringtrack::io {
namespace {

using mcap::Op;

std::string hex32(std::uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%08x", v);
  return buf;
}

// Little-endian fields of one record's content; errors name the record, its offset and the
// field that did not fit.
class Fields {
 public:
  Fields(std::span<const std::uint8_t> content, std::string where)
      : content_(content), where_(std::move(where)) {}

  std::uint8_t u8(const char* field) { return get<std::uint8_t>(field); }
  std::uint16_t u16(const char* field) { return get<std::uint16_t>(field); }
  std::uint32_t u32(const char* field) { return get<std::uint32_t>(field); }
  std::uint64_t u64(const char* field) { return get<std::uint64_t>(field); }
  std::string string(const char* field) {
    const auto bytes = take(u32(field), field);
    return {reinterpret_cast<const char*>(bytes.data()), bytes.size()};
  }
  std::span<const std::uint8_t> take(std::uint64_t n, const char* field) {
    if (n > content_.size() - at_) {
      fail(std::string(field) + " of " + std::to_string(n) + " bytes runs past the record's end (" +
           std::to_string(content_.size() - at_) + " bytes left)");
    }
    const auto out = content_.subspan(at_, static_cast<std::size_t>(n));
    at_ += static_cast<std::size_t>(n);
    return out;
  }
  McapStringMap string_map(const char* field) {
    Fields inner(take(u32(field), field), where_ + ", " + field);
    McapStringMap out;
    while (inner.remaining() > 0) {
      std::string key = inner.string("key");
      out.emplace_back(std::move(key), inner.string("value"));
    }
    return out;
  }
  std::span<const std::uint8_t> rest() { return take(remaining(), "data"); }
  [[nodiscard]] std::size_t remaining() const { return content_.size() - at_; }
  [[noreturn]] void fail(const std::string& what) const {
    throw core::InputError(where_ + ": " + what);
  }

 private:
  template <typename T>
  T get(const char* field) {
    T v{};
    std::memcpy(&v, take(sizeof(T), field).data(), sizeof(T));
    return v;
  }

  std::span<const std::uint8_t> content_;
  std::string where_;
  std::size_t at_{0};
};

// Where the bytes come from: a file read with pread, or memory.
class Source {
 public:
  virtual ~Source() = default;
  [[nodiscard]] virtual std::uint64_t size() const = 0;
  // n bytes at offset (the caller checked they exist); valid until the next read into `buffer`.
  virtual std::span<const std::uint8_t> read(std::uint64_t offset, std::size_t n,
                                             ByteBuffer& buffer) = 0;
};

class FileSource final : public Source {
 public:
  FileSource(const std::filesystem::path& path, std::string name) : name_(std::move(name)) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) throw core::InputError(name_ + ": cannot open: " + std::strerror(errno));
    const off_t end = ::lseek(fd_, 0, SEEK_END);
    if (end < 0) {
      ::close(fd_);
      throw core::InputError(name_ + ": cannot seek: " + std::strerror(errno));
    }
    size_ = static_cast<std::uint64_t>(end);
  }
  ~FileSource() override { ::close(fd_); }
  FileSource(const FileSource&) = delete;
  FileSource& operator=(const FileSource&) = delete;
  [[nodiscard]] std::uint64_t size() const override { return size_; }
  std::span<const std::uint8_t> read(std::uint64_t offset, std::size_t n,
                                     ByteBuffer& buffer) override {
    buffer.clear();
    std::uint8_t* out = buffer.grow(n);
    std::size_t done = 0;
    while (done < n) {
      const ssize_t got = ::pread(fd_, out + done, n - done, static_cast<off_t>(offset + done));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) {
        throw core::InputError(name_ + ": read failed at offset " + std::to_string(offset + done) +
                               ": " + (got < 0 ? std::strerror(errno) : "unexpected end of file"));
      }
      done += static_cast<std::size_t>(got);
    }
    return {out, n};
  }

 private:
  std::string name_;
  int fd_{-1};
  std::uint64_t size_{0};
};

class MemorySource final : public Source {
 public:
  explicit MemorySource(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  [[nodiscard]] std::uint64_t size() const override { return bytes_.size(); }
  std::span<const std::uint8_t> read(std::uint64_t offset, std::size_t n, ByteBuffer&) override {
    return bytes_.subspan(static_cast<std::size_t>(offset), n);
  }

 private:
  std::span<const std::uint8_t> bytes_;
};

}  // namespace

struct McapReader::Impl {
  std::string name;
  McapReaderOptions options;
  std::unique_ptr<Source> source;
  std::string profile;
  std::map<std::uint16_t, McapSchema> schemas;
  std::vector<McapChannel> channels;
  std::map<std::uint16_t, std::uint64_t> counts;
  bool used_summary{false};
  std::vector<McapChunkIndex> chunk_indexes;
  bool complete{false};  // the file ends with a footer and the magic: no cut-off tolerated
  std::string warning;

  // Linear reading state.
  std::uint64_t pos{0};
  std::uint32_t data_crc{0};
  bool done{false};
  ByteBuffer record;  // content of the record just read (file sources)
  ByteBuffer chunk;   // decompressed records of the current chunk
  std::span<const std::uint8_t> chunk_records;
  std::size_t chunk_at{0};
  std::uint64_t chunk_offset{0};
  bool in_chunk{false};
  ZSTD_DCtx* zstd{nullptr};
  LZ4F_dctx* lz4{nullptr};

  ~Impl() {
    if (zstd != nullptr) ZSTD_freeDCtx(zstd);
    if (lz4 != nullptr) LZ4F_freeDecompressionContext(lz4);
  }

  std::string at(const char* what, std::uint64_t offset) const {
    return name + ": " + what + " record at offset " + std::to_string(offset);
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw core::InputError(name + ": " + what);
  }

  void open() {
    ByteBuffer buf;
    const std::uint64_t size = source->size();
    const auto head =
        source->read(0, static_cast<std::size_t>(std::min<std::uint64_t>(size, 8)), buf);
    if (size < 8 || !std::equal(mcap::kMagic.begin(), mcap::kMagic.end(), head.begin())) {
      fail("not an MCAP file (expected the magic 89 4D 43 41 50 30 0D 0A at offset 0)");
    }
    complete = size >= 8 + mcap::kRecordPrefixBytes + mcap::kFooterContentBytes + 8 + 8 &&
               trailing_magic();
    if (!(complete && options.use_summary && read_summary())) scan_for_channels();
    rewind();
  }

  bool trailing_magic() {
    ByteBuffer buf;
    const auto tail = source->read(source->size() - 8, 8, buf);
    return std::equal(mcap::kMagic.begin(), mcap::kMagic.end(), tail.begin());
  }

  // Footer and summary: schemas, channels and Statistics. False when the file has no summary
  // or no per-channel counts (then a linear pass finds them). A corrupt summary is an error.
  bool read_summary() {
    const std::uint64_t size = source->size();
    const std::uint64_t footer_at = size - 8 - mcap::kRecordPrefixBytes - mcap::kFooterContentBytes;
    ByteBuffer buf;
    const auto footer =
        source->read(footer_at, mcap::kRecordPrefixBytes + mcap::kFooterContentBytes, buf);
    Fields f(footer, at("Footer", footer_at));
    if (f.u8("opcode") != static_cast<std::uint8_t>(Op::kFooter)) {
      f.fail("expected a Footer record before the trailing magic");
    }
    if (f.u64("length") != mcap::kFooterContentBytes) f.fail("length is not 20 bytes");
    const std::uint64_t summary_start = f.u64("summary_start");
    f.u64("summary_offset_start");
    const std::uint32_t summary_crc = f.u32("summary_crc");
    if (summary_start == 0) return false;
    if (summary_start < 8 || summary_start > footer_at) {
      f.fail("summary_start " + std::to_string(summary_start) + " lies outside the file's records");
    }
    ByteBuffer summary_buf;
    const auto summary =
        source->read(summary_start,
                     static_cast<std::size_t>(footer_at - summary_start + 1 + 8 + 16), summary_buf);
    if (summary_crc != 0) {
      const std::uint32_t crc = mcap::crc32(summary);
      if (crc != summary_crc) {
        fail("summary at offset " + std::to_string(summary_start) + ": CRC " + hex32(crc) +
             " but the footer says " + hex32(summary_crc) + " (corrupt file)");
      }
    }
    const auto records = summary.first(static_cast<std::size_t>(footer_at - summary_start));
    bool statistics = false;
    std::size_t i = 0;
    while (i < records.size()) {
      const std::uint64_t offset = summary_start + i;
      Fields prefix(records.subspan(i), at("summary", offset));
      const std::uint8_t op = prefix.u8("opcode");
      const std::uint64_t length = prefix.u64("length");
      Fields content(prefix.take(length, "content"), at(mcap::op_name(op), offset));
      i += mcap::kRecordPrefixBytes + static_cast<std::size_t>(length);
      switch (static_cast<Op>(op)) {
        case Op::kSchema:
          add_schema(content);
          break;
        case Op::kChannel:
          add_channel(content);
          break;
        case Op::kChunkIndex:
          chunk_indexes.push_back(chunk_index(content));
          break;
        case Op::kStatistics: {
          content.u64("message_count");
          content.u16("schema_count");
          content.u32("channel_count");
          content.u32("attachment_count");
          content.u32("metadata_count");
          content.u32("chunk_count");
          content.u64("message_start_time");
          content.u64("message_end_time");
          Fields map(content.take(content.u32("channel_message_counts"), "channel_message_counts"),
                     at("Statistics", offset));
          while (map.remaining() > 0) {
            const std::uint16_t id = map.u16("channel id");
            counts[id] = map.u64("count");
          }
          statistics = !counts.empty() || channels.empty();
          break;
        }
        default:
          break;
      }
    }
    used_summary = statistics;
    if (!statistics) chunk_indexes.clear();
    return statistics;
  }

  static McapChunkIndex chunk_index(Fields& f) {
    McapChunkIndex c;
    c.message_start_time_ns = f.u64("message_start_time");
    c.message_end_time_ns = f.u64("message_end_time");
    c.chunk_offset = f.u64("chunk_start_offset");
    c.chunk_length = f.u64("chunk_length");
    const std::uint32_t map_bytes = f.u32("message_index_offsets");
    if (map_bytes % 10 != 0) {
      f.fail("message_index_offsets of " + std::to_string(map_bytes) +
             " bytes is not a whole number of (uint16, uint64) entries");
    }
    for (std::uint32_t k = 0; k < map_bytes / 10; ++k) {
      const std::uint16_t channel = f.u16("channel id");
      c.message_index_offsets.emplace_back(channel, f.u64("offset"));
    }
    c.message_index_length = f.u64("message_index_length");
    c.compression = f.string("compression");
    c.compressed_size = f.u64("compressed_size");
    c.uncompressed_size = f.u64("uncompressed_size");
    return c;
  }

  // The Message Index records of one chunk, read where its Chunk Index says they are.
  std::vector<std::pair<std::uint16_t, std::vector<McapIndexEntry>>> message_indexes(
      const McapChunkIndex& index) {
    std::vector<std::pair<std::uint16_t, std::vector<McapIndexEntry>>> out;
    ByteBuffer buf;
    for (const auto& [channel, offset] : index.message_index_offsets) {
      const std::string where = at("Message Index", offset);
      const std::uint64_t size = source->size();
      if (offset > size || size - offset < mcap::kRecordPrefixBytes) {
        fail("Chunk Index of the chunk at offset " + std::to_string(index.chunk_offset) +
             ": Message Index offset " + std::to_string(offset) +
             " lies past the end of the file (" + std::to_string(size) + " bytes)");
      }
      Fields prefix(source->read(offset, mcap::kRecordPrefixBytes, buf), where);
      const std::uint8_t op = prefix.u8("opcode");
      const std::uint64_t length = prefix.u64("length");
      if (op != static_cast<std::uint8_t>(Op::kMessageIndex)) {
        prefix.fail(std::string("expected a Message Index record, found opcode ") +
                    std::to_string(op) + " (" + mcap::op_name(op) + ")");
      }
      if (length > size - offset - mcap::kRecordPrefixBytes) {
        prefix.fail("length " + std::to_string(length) + " runs past the end of the file");
      }
      Fields f(
          source->read(offset + mcap::kRecordPrefixBytes, static_cast<std::size_t>(length), buf),
          where);
      const std::uint16_t id = f.u16("channel_id");
      if (id != channel) {
        f.fail("channel " + std::to_string(id) + ", the Chunk Index says " +
               std::to_string(channel));
      }
      Fields records(f.take(f.u32("records"), "records"), where + ", records");
      std::vector<McapIndexEntry> entries;
      while (records.remaining() > 0) {
        McapIndexEntry e;
        e.log_time_ns = records.u64("log_time");
        e.offset = records.u64("offset");
        entries.push_back(e);
      }
      out.emplace_back(channel, std::move(entries));
    }
    return out;
  }

  void add_schema(Fields& f) {
    McapSchema s;
    s.id = f.u16("id");
    s.name = f.string("name");
    s.encoding = f.string("encoding");
    const auto data = f.take(f.u32("data"), "data");
    s.data.assign(data.begin(), data.end());
    if (s.id != 0) schemas.try_emplace(s.id, std::move(s));
  }

  void add_channel(Fields& f) {
    McapChannel c;
    c.id = f.u16("id");
    c.schema_id = f.u16("schema_id");
    c.topic = f.string("topic");
    c.message_encoding = f.string("message_encoding");
    c.metadata = f.string_map("metadata");
    const auto it =
        std::lower_bound(channels.begin(), channels.end(), c.id,
                         [](const McapChannel& a, std::uint16_t id) { return a.id < id; });
    if (it == channels.end() || it->id != c.id) channels.insert(it, std::move(c));
  }

  // One linear pass: every channel and the messages of each (for files without a summary).
  void scan_for_channels() {
    counts.clear();
    rewind();
    McapMessage m;
    while (next(m)) ++counts[m.channel_id];
  }

  void rewind() {
    pos = 8;
    data_crc = mcap::crc32(mcap::kMagic);
    done = false;
    in_chunk = false;
    warning.clear();
  }

  // Stops at a record cut off by the end of the file: fine for a file without footer (an
  // interrupted recording), an error for a file that claims to be complete.
  bool cut_off(std::uint64_t offset, const std::string& what) {
    if (complete) {
      fail("record at offset " + std::to_string(offset) + ": " + what +
           " runs past the end of the file (" + std::to_string(source->size()) + " bytes)");
    }
    warning = name + ": file cut off at offset " + std::to_string(offset) + " (" + what +
              " runs past the end of the file at " + std::to_string(source->size()) +
              " bytes; the messages before it were read)";
    done = true;
    return false;
  }

  void decompress(const std::string& compression, std::span<const std::uint8_t> in,
                  std::uint64_t size, const std::string& where) {
    if (size > options.max_chunk_bytes) {
      fail(where.substr(name.size() + 2) + ": uncompressed size " + std::to_string(size) +
           " above the limit of " + std::to_string(options.max_chunk_bytes) + " bytes");
    }
    const auto n = static_cast<std::size_t>(size);
    if (compression.empty()) {
      if (in.size() != n) {
        throw core::InputError(where + ": uncompressed_size " + std::to_string(size) +
                               " but the records hold " + std::to_string(in.size()) + " bytes");
      }
      chunk_records = in;
      return;
    }
    chunk.clear();
    std::uint8_t* out = chunk.grow(n);
    if (compression == "zstd") {
      if (zstd == nullptr) zstd = ZSTD_createDCtx();
      const std::size_t got = ZSTD_decompressDCtx(zstd, out, n, in.data(), in.size());
      if (ZSTD_isError(got) != 0U) {
        throw core::InputError(where + ": zstd data corrupt (" + ZSTD_getErrorName(got) + ")");
      }
      if (got != n) {
        throw core::InputError(where + ": zstd data decompress to " + std::to_string(got) +
                               " bytes, expected uncompressed_size " + std::to_string(n));
      }
    } else if (compression == "lz4") {
      if (lz4 == nullptr) LZ4F_createDecompressionContext(&lz4, LZ4F_VERSION);
      LZ4F_resetDecompressionContext(lz4);
      std::size_t out_done = 0;
      std::size_t in_done = 0;
      for (;;) {
        std::size_t out_size = n - out_done;
        std::size_t in_size = in.size() - in_done;
        const std::size_t hint =
            LZ4F_decompress(lz4, out + out_done, &out_size, in.data() + in_done, &in_size, nullptr);
        if (LZ4F_isError(hint) != 0U) {
          throw core::InputError(where + ": lz4 data corrupt (" + LZ4F_getErrorName(hint) + ")");
        }
        out_done += out_size;
        in_done += in_size;
        if (hint == 0) break;  // frame complete
        if ((in_size == 0 && out_size == 0) || in_done == in.size()) {
          throw core::InputError(where + ": lz4 data end before the frame does (" +
                                 std::to_string(out_done) + " of " + std::to_string(n) +
                                 " bytes decompressed)");
        }
      }
      if (out_done != n) {
        throw core::InputError(where + ": lz4 data decompress to " + std::to_string(out_done) +
                               " bytes, expected uncompressed_size " + std::to_string(n));
      }
    } else {
      throw core::InputError(where + ": compression '" + compression +
                             "' is not supported (expected none, lz4 or zstd)");
    }
    chunk_records = chunk.span();
  }

  void open_chunk(Fields& f, std::uint64_t offset) {
    const std::string where = at("Chunk", offset);
    f.u64("message_start_time");
    f.u64("message_end_time");
    const std::uint64_t size = f.u64("uncompressed_size");
    const std::uint32_t crc = f.u32("uncompressed_crc");
    const std::string compression = f.string("compression");
    const auto records = f.take(f.u64("records"), "records");
    decompress(compression, records, size, where);
    if (crc != 0) {
      const std::uint32_t actual = mcap::crc32(chunk_records);
      if (actual != crc) {
        throw core::InputError(where + ": CRC of the uncompressed records is " + hex32(actual) +
                               ", the chunk says " + hex32(crc) + " (corrupt file)");
      }
    }
    chunk_at = 0;
    chunk_offset = offset;
    in_chunk = !chunk_records.empty();  // a chunk may hold no records
  }

  bool message(Fields& f, std::uint64_t offset, McapMessage& out) {
    out.channel_id = f.u16("channel_id");
    out.sequence = f.u32("sequence");
    out.log_time_ns = f.u64("log_time");
    out.publish_time_ns = f.u64("publish_time");
    out.data = f.rest();
    out.offset = offset;
    if (!std::binary_search(channels.begin(), channels.end(), out.channel_id,
                            [](const auto& a, const auto& b) { return id_of(a) < id_of(b); })) {
      f.fail("message on channel " + std::to_string(out.channel_id) +
             ", which no earlier Channel record declares");
    }
    return true;
  }
  static std::uint16_t id_of(const McapChannel& c) { return c.id; }
  static std::uint16_t id_of(std::uint16_t id) { return id; }

  // The next record inside the current chunk; true when it was a message.
  bool next_in_chunk(McapMessage& out) {
    const std::size_t begin = chunk_at;
    const std::string where =
        at("Chunk", chunk_offset) + ", byte " + std::to_string(begin) + " of its records";
    Fields prefix(chunk_records.subspan(begin), where);
    const std::uint8_t op = prefix.u8("opcode");
    const std::uint64_t length = prefix.u64("length");
    Fields content(prefix.take(length, "record content"), where + " (" + mcap::op_name(op) + ")");
    chunk_at = begin + mcap::kRecordPrefixBytes + static_cast<std::size_t>(length);
    if (chunk_at >= chunk_records.size()) in_chunk = false;
    switch (static_cast<Op>(op)) {
      case Op::kSchema:
        add_schema(content);
        return false;
      case Op::kChannel:
        add_channel(content);
        return false;
      case Op::kMessage:
        out.in_chunk = true;
        out.offset_in_chunk = begin;
        return message(content, chunk_offset, out);
      default:
        return false;  // other records do not belong in chunks: ignored
    }
  }

  bool next(McapMessage& out) {
    for (;;) {
      if (in_chunk) {
        if (next_in_chunk(out)) return true;
        continue;
      }
      if (done) return false;
      const std::uint64_t size = source->size();
      const std::uint64_t offset = pos;
      if (size - offset < mcap::kRecordPrefixBytes) {
        return cut_off(offset, "a record's opcode and length");
      }
      ByteBuffer prefix_buf;
      const auto prefix = source->read(offset, mcap::kRecordPrefixBytes, prefix_buf);
      const std::uint8_t op = prefix[0];
      std::uint64_t length = 0;
      std::memcpy(&length, prefix.data() + 1, sizeof length);
      if (op == 0) fail("record at offset " + std::to_string(offset) + ": opcode 0 is invalid");
      if (length > size - offset - mcap::kRecordPrefixBytes) {
        return cut_off(offset, std::string("a ") + mcap::op_name(op) + " record of " +
                                   std::to_string(length) + " bytes");
      }
      const auto content =
          source->read(offset + mcap::kRecordPrefixBytes, static_cast<std::size_t>(length), record);
      pos = offset + mcap::kRecordPrefixBytes + length;
      Fields f(content, at(mcap::op_name(op), offset));
      if (static_cast<Op>(op) == Op::kDataEnd) {
        const std::uint32_t expected = f.u32("data_section_crc");
        if (expected != 0 && expected != data_crc) {
          f.fail("data section CRC is " + hex32(data_crc) + ", the record says " + hex32(expected) +
                 " (corrupt file)");
        }
        done = true;  // the summary follows: nothing more to read in order
        return false;
      }
      if (offset == 8 && static_cast<Op>(op) != Op::kHeader) {
        f.fail("expected a Header record after the magic");
      }
      data_crc = mcap::crc32(prefix, data_crc);
      data_crc = mcap::crc32(content, data_crc);
      switch (static_cast<Op>(op)) {
        case Op::kHeader:
          if (offset == 8) {
            profile = f.string("profile");
          } else {
            f.fail("a second Header record");
          }
          break;
        case Op::kFooter:
          done = true;
          return false;
        case Op::kSchema:
          add_schema(f);
          break;
        case Op::kChannel:
          add_channel(f);
          break;
        case Op::kMessage:
          out.in_chunk = false;
          out.offset_in_chunk = 0;
          return message(f, offset, out);
        case Op::kChunk:
          open_chunk(f, offset);
          break;
        default:
          break;  // indexes, attachments, metadata: not needed to read messages
      }
    }
  }
};

McapReader::McapReader(const std::filesystem::path& path, McapReaderOptions options)
    : McapReader(path, path.string(), options) {}

McapReader::McapReader(const std::filesystem::path& path, std::string name,
                       McapReaderOptions options)
    : impl_(std::make_unique<Impl>()) {
  impl_->name = std::move(name);
  impl_->options = options;
  impl_->source = std::make_unique<FileSource>(path, impl_->name);
  impl_->open();
}

McapReader::McapReader(std::span<const std::uint8_t> bytes, std::string name,
                       McapReaderOptions options)
    : impl_(std::make_unique<Impl>()) {
  impl_->name = std::move(name);
  impl_->options = options;
  impl_->source = std::make_unique<MemorySource>(bytes);
  impl_->open();
}

McapReader::~McapReader() = default;

const std::string& McapReader::profile() const {
  return impl_->profile;
}

const std::vector<McapChannel>& McapReader::channels() const {
  return impl_->channels;
}

const McapSchema* McapReader::schema(std::uint16_t id) const {
  const auto it = impl_->schemas.find(id);
  return it == impl_->schemas.end() ? nullptr : &it->second;
}

std::uint64_t McapReader::message_count(std::uint16_t channel_id) const {
  const auto it = impl_->counts.find(channel_id);
  return it == impl_->counts.end() ? 0 : it->second;
}

bool McapReader::used_summary() const {
  return impl_->used_summary;
}

const std::vector<McapChunkIndex>& McapReader::chunk_indexes() const {
  return impl_->chunk_indexes;
}

std::vector<std::pair<std::uint16_t, std::vector<McapIndexEntry>>> McapReader::message_indexes(
    const McapChunkIndex& chunk) {
  return impl_->message_indexes(chunk);
}

bool McapReader::next(McapMessage& out) {
  return impl_->next(out);
}

void McapReader::rewind() {
  impl_->rewind();
}

const std::string& McapReader::warning() const {
  return impl_->warning;
}

const std::string& McapReader::name() const {
  return impl_->name;
}

bool is_mcap_file(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  std::ifstream in(path, std::ios::binary);
  char magic[8] = {};
  in.read(magic, sizeof magic);
  return in.gcount() == sizeof magic && std::equal(mcap::kMagic.begin(), mcap::kMagic.end(),
                                                   reinterpret_cast<const std::uint8_t*>(magic));
}

}  // namespace ringtrack::io
