#include "ringtrack/io/rosbag1_reader.hpp"

#include <bzlib.h>
#include <lz4frame.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ringtrack/core/error.hpp"

namespace ringtrack::io {
namespace {

namespace fs = std::filesystem;

constexpr std::string_view kMagic = "#ROSBAG V2.0\n";
// Chunks far beyond rosbag's 768 KiB default mean a corrupt size field; refuse to allocate.
constexpr std::uint64_t kMaxChunkBytes = 512ull << 20;
// Connection headers and record headers are small; a larger length is corruption.
constexpr std::uint32_t kMaxHeaderBytes = 16u << 20;

// Grows the output of a decompressor that filled it: doubling from 64 KiB up to the declared
// size plus one byte (room to notice a stream longer than declared). False when it is that big.
// Growing with what the stream really produces, instead of sizing the buffer from the chunk's
// declared size up front, keeps a corrupt or hostile size field from costing its full claim.
bool grow_output(std::vector<std::uint8_t>& out, std::uint32_t declared) {
  const std::size_t limit = static_cast<std::size_t>(declared) + 1;
  if (out.size() >= limit) return false;
  out.resize(std::min(limit, std::max<std::size_t>(2 * out.size(), 64u << 10)));
  return true;
}

// Decompresses a bz2 stream into `out` (resized to what it produced); returns "" or the error.
std::string decompress_bz2(std::span<const std::uint8_t> in, std::uint32_t declared,
                           std::vector<std::uint8_t>& out) {
  bz_stream s{};
  if (BZ2_bzDecompressInit(&s, 0, 0) != BZ_OK) return "cannot start the bzip2 decoder";
  s.next_in = const_cast<char*>(reinterpret_cast<const char*>(in.data()));
  s.avail_in = static_cast<unsigned int>(in.size());
  out.clear();
  std::size_t out_at = 0;
  std::string error;
  while (true) {
    if (out_at == out.size() && !grow_output(out, declared)) {
      error = "more data than declared";
      break;
    }
    s.next_out = reinterpret_cast<char*>(out.data() + out_at);
    s.avail_out = static_cast<unsigned int>(out.size() - out_at);
    const unsigned int avail_in = s.avail_in;
    const int rc = BZ2_bzDecompress(&s);
    const std::size_t produced = out.size() - s.avail_out - out_at;
    out_at += produced;
    if (rc == BZ_STREAM_END) break;
    if (rc != BZ_OK) {
      error = "bzip2 error " + std::to_string(rc);
      break;
    }
    // Room left for output but nothing more came: the input ran out (or the decoder is stuck).
    if (s.avail_out != 0 && (s.avail_in == 0 || (s.avail_in == avail_in && produced == 0))) {
      error = "the stream is cut off";
      break;
    }
  }
  BZ2_bzDecompressEnd(&s);
  out.resize(out_at);
  return error;
}

// Decompresses an LZ4 frame (what roslz4 writes) into `out`; returns "" or the error.
std::string decompress_lz4(std::span<const std::uint8_t> in, std::uint32_t declared,
                           std::vector<std::uint8_t>& out) {
  LZ4F_dctx* ctx = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION))) {
    return "cannot create an LZ4 decompression context";
  }
  out.clear();
  std::size_t in_at = 0;
  std::size_t out_at = 0;
  std::size_t rc = 1;
  std::string error;
  while (rc != 0) {
    if (out_at == out.size() && !grow_output(out, declared)) {
      error = "more data than declared";
      break;
    }
    std::size_t in_size = in.size() - in_at;
    std::size_t out_size = out.size() - out_at;
    rc = LZ4F_decompress(ctx, out.data() + out_at, &out_size, in.data() + in_at, &in_size, nullptr);
    if (LZ4F_isError(rc)) {
      error = LZ4F_getErrorName(rc);
      break;
    }
    in_at += in_size;
    out_at += out_size;
    // Room left for output but nothing more came: the input ran out (or the decoder is stuck).
    if (rc != 0 && out_at < out.size() && (in_at == in.size() || (in_size == 0 && out_size == 0))) {
      error = "the frame is cut off";
      break;
    }
  }
  LZ4F_freeDecompressionContext(ctx);
  out.resize(out_at);
  return error;
}

std::uint32_t le32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}

std::uint64_t le64(const std::uint8_t* p) {
  return static_cast<std::uint64_t>(le32(p)) | (static_cast<std::uint64_t>(le32(p + 4)) << 32);
}

// The fields of a record header (or of a connection header): name=value pairs, each prefixed by
// its uint32 length. Values are binary.
class Fields {
 public:
  Fields(std::span<const std::uint8_t> bytes, std::string where) : where_(std::move(where)) {
    std::size_t at = 0;
    while (at < bytes.size()) {
      if (bytes.size() - at < 4) fail("a field length is cut off at byte " + std::to_string(at));
      const std::uint32_t len = le32(bytes.data() + at);
      at += 4;
      if (len > bytes.size() - at) {
        fail("field at byte " + std::to_string(at - 4) + " claims " + std::to_string(len) +
             " bytes, " + std::to_string(bytes.size() - at) + " left");
      }
      const auto* begin = reinterpret_cast<const char*>(bytes.data() + at);
      const std::string_view field(begin, len);
      const auto eq = field.find('=');
      if (eq == std::string_view::npos) {
        fail("field at byte " + std::to_string(at - 4) + " has no '='");
      }
      fields_.emplace_back(std::string(field.substr(0, eq)), std::string(field.substr(eq + 1)));
      at += len;
    }
  }

  [[nodiscard]] const std::string* find(std::string_view name) const {
    for (const auto& [key, value] : fields_) {
      if (key == name) return &value;
    }
    return nullptr;
  }
  [[nodiscard]] const std::string& get(std::string_view name, std::size_t size = 0) const {
    const std::string* v = find(name);
    if (v == nullptr) fail("has no '" + std::string(name) + "' field");
    if (size != 0 && v->size() != size) {
      fail("field '" + std::string(name) + "' has " + std::to_string(v->size()) +
           " bytes, expected " + std::to_string(size));
    }
    return *v;
  }
  [[nodiscard]] std::uint8_t u8(std::string_view name) const {
    return static_cast<std::uint8_t>(get(name, 1)[0]);
  }
  [[nodiscard]] std::uint32_t u32(std::string_view name) const {
    return le32(reinterpret_cast<const std::uint8_t*>(get(name, 4).data()));
  }
  [[nodiscard]] std::uint64_t u64(std::string_view name) const {
    return le64(reinterpret_cast<const std::uint8_t*>(get(name, 8).data()));
  }
  // ROS time: uint32 seconds, uint32 nanoseconds.
  [[nodiscard]] std::int64_t time_ns(std::string_view name) const {
    const auto* p = reinterpret_cast<const std::uint8_t*>(get(name, 8).data());
    return static_cast<std::int64_t>(le32(p)) * 1'000'000'000 + le32(p + 4);
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw core::InputError(where_ + " " + what);
  }

 private:
  std::string where_;
  std::vector<std::pair<std::string, std::string>> fields_;
};

std::string list_topics(const std::vector<RosbagTopicInfo>& topics) {
  std::string s;
  for (const auto& t : topics) s += (s.empty() ? "" : ", ") + t.name + " (" + t.type + ")";
  return s.empty() ? "none" : s;
}

std::string hex_byte(std::uint8_t b) {
  static constexpr char kHex[] = "0123456789abcdef";
  return std::string("0x") + kHex[b >> 4] + kHex[b & 0xF];
}

}  // namespace

struct Rosbag1Reader::Record {
  std::uint64_t offset{0};       // of the record's header length
  std::optional<Fields> fields;  // the header
  std::uint8_t op{0};
  std::uint64_t data_offset{0};  // file offset of its data
  std::uint32_t data_bytes{0};
};

void Rosbag1Reader::FileCloser::operator()(std::FILE* f) const {
  std::fclose(f);
}

Rosbag1Reader::Rosbag1Reader(const fs::path& path) : path_(path) {
  const std::string name = path.string();
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw core::InputError(name + ": no such ROS 1 bag file");
  file_size_ = fs::file_size(path, ec);
  file_.reset(std::fopen(name.c_str(), "rb"));
  if (!file_ || ec) throw core::InputError(name + ": cannot open for reading");
  check_magic();
  offset_ = kMagic.size();
  Record header;
  if (!read_record(header) || header.op != static_cast<std::uint8_t>(Rosbag1Op::kBagHeader)) {
    throw core::InputError(name + ": expected the bag header record at offset " +
                           std::to_string(kMagic.size()));
  }
  index_pos_ = header.fields->u64("index_pos");
  const std::uint32_t conn_count = header.fields->u32("conn_count");
  const std::uint32_t chunk_count = header.fields->u32("chunk_count");
  first_record_ = offset_;
  indexed_ = index_pos_ != 0;
  if (indexed_) {
    read_index(conn_count, chunk_count);
  } else {
    scan_for_connections();
  }
  collect_topics();
  offset_ = first_record_;
}

void Rosbag1Reader::check_magic() {
  const std::string name = path_.string();
  std::vector<std::uint8_t> magic;
  if (file_size_ < kMagic.size()) {
    throw core::InputError(name + ": not a ROS 1 bag (shorter than the '#ROSBAG V2.0' line)");
  }
  read_bytes(0, kMagic.size(), magic);
  const std::string_view got(reinterpret_cast<const char*>(magic.data()), magic.size());
  if (got != kMagic) {
    if (got.rfind("#ROSBAG V", 0) == 0) {
      const auto end = got.find('\n');
      throw core::InputError(name + ": bag format " + std::string(got.substr(9, end - 9)) +
                             " is not supported, expected 2.0 (migrate with `rosbag fix`)");
    }
    throw core::InputError(name + ": not a ROS 1 bag (expected '#ROSBAG V2.0' at offset 0)");
  }
}

void Rosbag1Reader::read_index(std::uint32_t conn_count, std::uint32_t chunk_count) {
  const std::string name = path_.string();
  if (index_pos_ < first_record_ || index_pos_ > file_size_) {
    throw core::InputError(name + ": bag header: index_pos " + std::to_string(index_pos_) +
                           " lies outside the file (" + std::to_string(file_size_) + " bytes)");
  }
  // The index section: every connection record, then one chunk info record per chunk.
  offset_ = index_pos_;
  Record r;
  std::vector<std::uint8_t> data;
  std::uint32_t chunk_infos = 0;
  while (read_record(r)) {
    if (r.op == static_cast<std::uint8_t>(Rosbag1Op::kConnection)) {
      read_bytes(r.data_offset, r.data_bytes, data);
      add_connection(r, data);
    } else if (r.op == static_cast<std::uint8_t>(Rosbag1Op::kChunkInfo)) {
      ++chunk_infos;
      read_bytes(r.data_offset, r.data_bytes, data);
      const std::uint32_t count = r.fields->u32("count");
      if (data.size() != 8ull * count) {
        throw core::InputError(name + ": chunk info record at offset " + std::to_string(r.offset) +
                               " holds " + std::to_string(data.size()) + " bytes, expected " +
                               std::to_string(8ull * count));
      }
      for (std::uint32_t i = 0; i < count; ++i) {
        const std::uint8_t* entry = data.data() + 8 * std::size_t{i};
        const auto it = connections_.find(le32(entry));
        if (it != connections_.end()) it->second.messages += le32(entry + 4);
      }
    } else {
      ++stats_.unknown_records;
    }
  }
  if (connections_.size() != conn_count || chunk_infos != chunk_count) {
    throw core::InputError(name + ": the index lists " + std::to_string(connections_.size()) +
                           " connections and " + std::to_string(chunk_infos) +
                           " chunks, the bag header says " + std::to_string(conn_count) + " and " +
                           std::to_string(chunk_count) + " (truncated or corrupt)");
  }
}

void Rosbag1Reader::collect_topics() {
  for (const auto& entry : connections_) {
    const auto& c = entry.second;  // a plain reference: clang 14 cannot capture structured bindings
    auto it = std::find_if(topics_.begin(), topics_.end(),
                           [&](const RosbagTopicInfo& t) { return t.name == c.topic; });
    if (it == topics_.end()) {
      topics_.push_back({c.topic, c.type, 0});
      it = topics_.end() - 1;
    } else if (it->type != c.type) {
      throw core::InputError(path_.string() + ": topic " + c.topic + " has connections of types " +
                             it->type + " and " + c.type);
    }
    it->messages += c.messages;
  }
}

Rosbag1Reader::~Rosbag1Reader() = default;

void Rosbag1Reader::read_bytes(std::uint64_t offset, std::size_t n,
                               std::vector<std::uint8_t>& out) {
  // Checked before resizing: a size read from the file costs nothing until the file holds it.
  if (offset > file_size_ || n > file_size_ - offset) {
    throw core::InputError(path_.string() + ": truncated: needs " + std::to_string(n) +
                           " bytes at offset " + std::to_string(offset) + ", the file has " +
                           std::to_string(file_size_));
  }
  out.resize(n);
  if (n == 0) return;
  if (fseeko(file_.get(), static_cast<off_t>(offset), SEEK_SET) != 0 ||
      std::fread(out.data(), 1, n, file_.get()) != n) {
    throw core::InputError(path_.string() + ": read error at offset " + std::to_string(offset));
  }
}

// Reads the record header at offset_ and moves offset_ past the record; false at the end of the
// file. The data is left in the file (read_bytes fetches it when wanted).
bool Rosbag1Reader::read_record(Record& record, bool tail_ok) {
  if (offset_ >= file_size_) return false;
  const auto cut_off = [&] {
    if (!tail_ok) return false;
    stats_.truncated_at = offset_;
    offset_ = file_size_;
    return true;
  };
  const std::string where = path_.string() + ": record at offset " + std::to_string(offset_);
  std::vector<std::uint8_t> buf;
  if (file_size_ - offset_ < 4) {
    if (cut_off()) return false;
    throw core::InputError(where + ": truncated (the header length is cut off)");
  }
  read_bytes(offset_, 4, buf);
  const std::uint32_t header_bytes = le32(buf.data());
  if (header_bytes > kMaxHeaderBytes || header_bytes + 8ull > file_size_ - offset_) {
    if (cut_off()) return false;
    throw core::InputError(where + ": header length " + std::to_string(header_bytes) +
                           " runs past the end of the file (" + std::to_string(file_size_) +
                           " bytes): truncated or corrupt");
  }
  record.offset = offset_;
  read_bytes(offset_ + 4, header_bytes, buf);
  record.fields.emplace(buf, where);
  record.op = record.fields->u8("op");
  std::vector<std::uint8_t> len;
  read_bytes(offset_ + 4 + header_bytes, 4, len);
  record.data_bytes = le32(len.data());
  record.data_offset = offset_ + 8 + header_bytes;
  if (record.data_bytes > file_size_ - record.data_offset) {
    if (cut_off()) return false;
    throw core::InputError(where + ": data length " + std::to_string(record.data_bytes) +
                           " runs past the end of the file (" + std::to_string(file_size_) +
                           " bytes): truncated or corrupt");
  }
  offset_ = record.data_offset + record.data_bytes;
  return true;
}

void Rosbag1Reader::add_connection(const Record& record, std::span<const std::uint8_t> data) {
  const std::uint32_t id = record.fields->u32("conn");
  if (connections_.count(id) != 0) return;  // chunks repeat the index's connection records
  const std::string where = path_.string() + ": connection " + std::to_string(id) + " (offset " +
                            std::to_string(record.offset) + ")";
  const Fields header(data, where);
  Rosbag1Connection c;
  c.id = id;
  c.topic = record.fields->get("topic");
  c.type = header.get("type");
  if (const std::string* md5 = header.find("md5sum")) c.md5sum = *md5;
  connections_.emplace(id, std::move(c));
}

void Rosbag1Reader::load_chunk(const Record& record) {
  const std::string where = path_.string() + ": chunk at offset " + std::to_string(record.offset);
  const std::string& compression = record.fields->get("compression");
  const std::uint32_t size = record.fields->u32("size");
  if (size > kMaxChunkBytes) {
    throw core::InputError(where + " claims " + std::to_string(size) +
                           " uncompressed bytes (more than " + std::to_string(kMaxChunkBytes) +
                           "): corrupt");
  }
  ++stats_.chunks;
  stats_.uncompressed_bytes += size;
  if (compression == "none") {
    if (record.data_bytes != size) {
      throw core::InputError(where + ": uncompressed chunk of " +
                             std::to_string(record.data_bytes) + " bytes declares size " +
                             std::to_string(size));
    }
    read_bytes(record.data_offset, record.data_bytes, chunk_);
  } else if (compression == "bz2" || compression == "lz4") {
    read_bytes(record.data_offset, record.data_bytes, raw_);
    const std::string error = compression == "bz2" ? decompress_bz2(raw_, size, chunk_)
                                                   : decompress_lz4(raw_, size, chunk_);
    if (!error.empty() || chunk_.size() != size) {
      throw core::InputError(
          where + ": corrupt " + compression + " data (" +
          (error.empty() ? std::to_string(chunk_.size()) + " of " + std::to_string(size) + " bytes"
                         : error) +
          ")");
    }
  } else {
    throw core::InputError(where + ": compression '" + compression +
                           "' is not supported (expected none, bz2 or lz4)");
  }
  chunk_offset_ = record.offset;
  chunk_at_ = 0;
  in_chunk_ = true;
}

// The records inside the current chunk: connections and message data. Returns the next message
// of the selected topic (or, while scanning, counts every message).
bool Rosbag1Reader::next_in_chunk(RosbagMessage& out) {
  while (chunk_at_ < chunk_.size()) {
    const std::string where = path_.string() + ": chunk at offset " +
                              std::to_string(chunk_offset_) + ", record at byte " +
                              std::to_string(chunk_at_);
    const std::size_t left = chunk_.size() - chunk_at_;
    if (left < 4) throw core::InputError(where + ": truncated (header length cut off)");
    const std::uint32_t header_bytes = le32(chunk_.data() + chunk_at_);
    if (header_bytes > left - 4 || left - 4 - header_bytes < 4) {
      throw core::InputError(where + ": header length " + std::to_string(header_bytes) +
                             " runs past the chunk's end");
    }
    const std::span<const std::uint8_t> header(chunk_.data() + chunk_at_ + 4, header_bytes);
    const std::uint32_t data_bytes = le32(chunk_.data() + chunk_at_ + 4 + header_bytes);
    const std::size_t data_at = chunk_at_ + 8 + header_bytes;
    if (data_bytes > chunk_.size() - data_at) {
      throw core::InputError(where + ": data length " + std::to_string(data_bytes) +
                             " runs past the chunk's end");
    }
    const std::span<const std::uint8_t> data(chunk_.data() + data_at, data_bytes);
    chunk_at_ = data_at + data_bytes;
    Record record;
    record.offset = chunk_offset_;
    record.fields.emplace(header, where);
    record.op = record.fields->u8("op");
    if (record.op == static_cast<std::uint8_t>(Rosbag1Op::kConnection)) {
      add_connection(record, data);
    } else if (record.op == static_cast<std::uint8_t>(Rosbag1Op::kMessageData)) {
      const std::uint32_t conn = record.fields->u32("conn");
      const auto it = connections_.find(conn);
      if (it == connections_.end()) {
        throw core::InputError(where + ": message of unknown connection " + std::to_string(conn));
      }
      if (!started_) {  // scanning an unindexed bag
        ++it->second.messages;
        continue;
      }
      if (it->second.topic != selected_) {
        ++other_;
        continue;
      }
      out.stamp_ns = record.fields->time_ns("time");
      out.data = data;
      out.index = ++index_;
      return true;
    } else {
      ++stats_.unknown_records;
    }
  }
  in_chunk_ = false;
  return false;
}

void Rosbag1Reader::scan_for_connections() {
  offset_ = first_record_;
  Record r;
  RosbagMessage unused;
  std::vector<std::uint8_t> data;
  while (read_record(r, true)) {
    if (r.op == static_cast<std::uint8_t>(Rosbag1Op::kChunk)) {
      load_chunk(r);
      next_in_chunk(unused);
    } else if (r.op == static_cast<std::uint8_t>(Rosbag1Op::kConnection)) {
      read_bytes(r.data_offset, r.data_bytes, data);
      add_connection(r, data);
    }
  }
  // An interrupted recording ends inside its last record: the data ends before it.
  index_pos_ = stats_.truncated_at != 0 ? stats_.truncated_at : file_size_;
  stats_ = {};
  stats_.truncated_at = index_pos_ != file_size_ ? index_pos_ : 0;
}

void Rosbag1Reader::select_topic(const std::string& name) {
  if (started_) throw core::Error(path_.string() + ": select_topic after reading began");
  const auto it = std::find_if(topics_.begin(), topics_.end(),
                               [&](const RosbagTopicInfo& t) { return t.name == name; });
  if (it == topics_.end()) {
    throw core::ConfigError(path_.string() + ": no topic '" + name + "'; the bag has " +
                            list_topics(topics_));
  }
  selected_ = name;
}

bool Rosbag1Reader::next(RosbagMessage& out) {
  if (selected_.empty()) throw core::Error(path_.string() + ": no topic selected");
  started_ = true;
  while (true) {
    if (in_chunk_ && next_in_chunk(out)) return true;
    if (offset_ >= index_pos_) return false;
    Record r;
    if (!read_record(r)) return false;
    if (r.offset < index_pos_ && r.data_offset + r.data_bytes > index_pos_) {
      throw core::InputError(path_.string() + ": record at offset " + std::to_string(r.offset) +
                             " overlaps the index at " + std::to_string(index_pos_));
    }
    switch (static_cast<Rosbag1Op>(r.op)) {
      case Rosbag1Op::kChunk:
        load_chunk(r);
        break;
      case Rosbag1Op::kMessageData: {  // not inside a chunk: unusual, but valid
        const std::uint32_t conn = r.fields->u32("conn");
        const auto it = connections_.find(conn);
        if (it == connections_.end()) {
          throw core::InputError(path_.string() + ": message at offset " +
                                 std::to_string(r.offset) + " of unknown connection " +
                                 std::to_string(conn));
        }
        if (it->second.topic != selected_) {
          ++other_;
          break;
        }
        read_bytes(r.data_offset, r.data_bytes, message_);
        out.stamp_ns = r.fields->time_ns("time");
        out.data = message_;
        out.index = ++index_;
        return true;
      }
      case Rosbag1Op::kIndexData:
      case Rosbag1Op::kConnection:
      case Rosbag1Op::kChunkInfo:
      case Rosbag1Op::kBagHeader:
        break;
      default:
        throw core::InputError(path_.string() + ": record at offset " + std::to_string(r.offset) +
                               " has unknown op " + hex_byte(r.op) + " (expected 0x02..0x07)");
    }
  }
}

}  // namespace ringtrack::io
